"""MkDocs hooks (mkdocs.yml's ``hooks``): the docstrings' Sphinx roles read as plain code.

The package's docstrings cross-reference with Sphinx roles (``:class:`~pinball_env.options.X```),
which mkdocstrings passes through as text; in the rendered page the role's name goes and a ``~``
keeps only the last part of the path, as Sphinx shows it.
"""

import re

ROLE = re.compile(r":(?:class|meth|func|mod|data|attr|exc|obj):<code>(~?)([^<]+)</code>")


def _code(match: re.Match[str]) -> str:
    short, path = match.groups()
    return f"<code>{path.rsplit('.', 1)[-1] if short else path}</code>"


def on_page_content(html: str, **_: object) -> str:
    return ROLE.sub(_code, html)
