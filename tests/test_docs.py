"""The documentation: its generated parts up to date, every Python example in the README and the
docs run, the README short and its links alive."""

import importlib.util
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
# A fenced Python block, and the comment before it that says why it is not run, if any.
BLOCK = re.compile(r"(?:<!-- not run: (?P<why>[^>]+?) -->\n)?```python\n(?P<code>.*?)```", re.S)


def load_generator():
    spec = importlib.util.spec_from_file_location("docs_generate", ROOT / "docs" / "generate.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_the_generated_parts_are_up_to_date():
    generator = load_generator()
    for page in generator.PAGES:
        text = page.read_text()
        assert generator.regenerate(text) == text, f"{page.name}: run python docs/generate.py"


def test_every_generated_part_has_a_generator_and_an_end():
    generator = load_generator()
    for page in PAGES:
        text = page.read_text()
        opened = re.findall(r"^<!-- generated: ([\w:.-]+) -->$", text, re.M)
        closed = [m["name"] for m in generator.MARKER.finditer(text)]
        assert opened == closed, f"{page.name}: a generated part without its end marker"
        for name in closed:
            assert name.partition(":")[0] in generator.GENERATORS, (page.name, name)


def examples(page: Path) -> list[tuple[str | None, str]]:
    return [(m["why"], m["code"]) for m in BLOCK.finditer(page.read_text())]


@pytest.mark.parametrize("page", [p for p in PAGES if examples(p)], ids=lambda p: p.name)
def test_the_examples_run(page, tmp_path, monkeypatch):
    # A page's examples run in order in one namespace, as a reader would type them, in an empty
    # folder (some write files).
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("SDL_VIDEODRIVER", "dummy")
    namespace: dict = {"__name__": "__docs__"}
    ran = 0
    for why, code in examples(page):
        if why is None:
            exec(compile(code, f"{page.name} example", "exec"), namespace)
            ran += 1
        else:
            compile(code, f"{page.name} example", "exec")  # not run, but valid Python
    assert ran or all(why for why, _ in examples(page))


def test_the_readme_fits_on_a_screen_and_its_links_are_alive():
    text = (ROOT / "README.md").read_text()
    assert len(text.splitlines()) <= 200
    for target in re.findall(r"\]\(([^)#\s]+)(?:#[^)]*)?\)|src=\"([^\"]+)\"", text):
        target = next(t for t in target if t) if isinstance(target, tuple) else target
        if not re.match(r"https?://", target):
            assert (ROOT / target).exists(), f"README links to a missing {target}"


def test_the_site_builds_strict(tmp_path):
    pytest.importorskip("mkdocs", reason="the docs extra (in dev) builds the site")

    result = subprocess.run(
        [sys.executable, "-m", "mkdocs", "build", "--strict", "--site-dir", str(tmp_path)],
        cwd=ROOT, capture_output=True, text=True, env={**os.environ, "NO_MKDOCS_2_WARNING": "1"},
    )  # fmt: skip
    assert result.returncode == 0, result.stderr[-3000:]


def layout_sections() -> dict[str, str]:
    """The house page's layout of ``pinball_env/``, by top-level entry (``name.py`` or ``name/``):
    the lines each entry spans, its subfolders and modules among them."""
    block = (ROOT / "docs" / "development.md").read_text(encoding="utf-8").split("## Layout", 1)[1]
    lines = block.split("```", 2)[1].splitlines()
    start = next(i for i, line in enumerate(lines) if line.startswith("pinball_env/"))
    end = next(i for i, line in enumerate(lines) if i > start and not line.startswith(" "))
    sections: dict[str, list[str]] = {}
    entry = ""
    for line in lines[start + 1 : end]:
        if not line.startswith("   "):  # an entry at the package's top (two spaces in)
            entry = line.split()[0]
        sections.setdefault(entry, []).append(line)
    return {entry: "\n".join(lines) for entry, lines in sections.items()}


def test_the_house_page_names_every_module_and_only_those():
    """docs/development.md's layout names each module of the package in its top-level entry
    (each subpackage as ``name/``), and names no module that does not exist there."""
    root = ROOT / "pinball_env"
    sections = layout_sections()
    missing = []
    for path in sorted(root.rglob("*.py")):
        rel = path.relative_to(root)
        if path.name == "__init__.py" and len(rel.parts) <= 2:
            continue  # the package itself, or a top-level package: its entry
        entry = rel.parts[0] if len(rel.parts) == 1 else f"{rel.parts[0]}/"
        name = f"{rel.parts[-2]}/" if path.name == "__init__.py" else path.name
        if not re.search(rf"(?<![\w.]){re.escape(name)}(?![\w])", sections.get(entry, "")):
            missing.append(str(rel))
    assert not missing, f"docs/development.md's layout does not name: {missing}"
    ghosts = [
        (entry, name)
        for entry, text in sections.items()
        for name in re.findall(r"(?<![\w/.])(\w+\.py)\b", text)
        if not list((root / entry if entry.endswith("/") else root).rglob(name))
    ]
    assert not ghosts, f"docs/development.md's layout names modules that do not exist: {ghosts}"
