"""Command-line tools, each run as ``python -m pinball_env.tools.NAME``:

- ``demo``: the scripted heuristic plays (a window, or headless with a PNG of the last frame);
- ``plot``: matplotlib pictures of a table and a ball's path on it;
- ``crosscheck``: the swept physics against pymunk, scenario by scenario, with a report;
- ``play``: the keyboard in a window, recordings and their replays;
- ``tilt``: what nudging patterns trip Pinball-v1's and -v2's tilt;
- ``serve``: the game in a browser (play, watch, replay), for machines without a screen; the
  page and what it is sent are ``tools/web/``.

The speed benchmark is a developer's tool of the checkout: ``python -m benchmarks.speed``.
"""

import argparse
import re
from typing import Any


def command_parser(module: str, doc: str | None, **kwargs: Any) -> argparse.ArgumentParser:
    """The argument parser of ``python -m MODULE``: its usage names that command, and its
    description is the first line of the module's docstring in plain text (the docstring's
    reStructuredText double backquotes dropped)."""
    first = (doc or "").strip().splitlines()[0] if (doc or "").strip() else ""
    return argparse.ArgumentParser(
        prog=f"python -m {module}", description=re.sub(r"``([^`]*)``", r"\1", first), **kwargs
    )
