"""Generated tables' names: ``"procgen:SEED"`` (easy) and ``"procgen-hard:SEED"``, with
``+targets`` before the colon for the tables with a drop bank and a spinner
(``"procgen+targets:SEED"``, ``"procgen-hard+targets:SEED"``), and the difficulties and seeds
they take."""

from __future__ import annotations

import re

from pinball_env.table import TableError

DIFFICULTIES = ("easy", "hard")
PREFIXES = {"easy": "procgen", "hard": "procgen-hard"}
# Added to a prefix for the tables with targets.
TARGETS_SUFFIX = "+targets"
NAME_PATTERN = re.compile(r"(procgen|procgen-hard)(\+targets)?:(.*)")
MAX_SEED = 2**63 - 1
# Seeds an unlimited set of layouts (``num_layouts=0``) draws from: [start, start + this).
UNLIMITED_LAYOUTS = 2**31


def check_difficulty(difficulty: str) -> str:
    """``difficulty``, if it is one of :data:`DIFFICULTIES` (a ``ValueError`` if not)."""
    if difficulty not in DIFFICULTIES:
        allowed = ", ".join(map(repr, DIFFICULTIES))
        raise ValueError(f"difficulty must be one of {allowed}, got {difficulty!r}")
    return difficulty


def layout_seeds(count: int, start: int) -> range:
    """The seeds of the layouts ``[start, start + count)`` (``count`` 0: unlimited, that is
    :data:`UNLIMITED_LAYOUTS` of them), if they are seeds (a ``ValueError`` if not); ``count``
    and ``start`` are integers >= 0 (the options ``num_layouts`` and ``start_layout``)."""
    seeds = range(start, start + (count or UNLIMITED_LAYOUTS))
    if seeds[-1] > MAX_SEED:
        raise ValueError(f"layouts beyond seed {MAX_SEED}: lower start_layout")
    return seeds


def name_prefix(difficulty: str = "easy", targets: bool = False) -> str:
    """The prefix of the generated tables' names of ``difficulty``, with or without targets."""
    return PREFIXES[check_difficulty(difficulty)] + (TARGETS_SUFFIX if targets else "")


def table_name(seed: int, difficulty: str = "easy", targets: bool = False) -> str:
    """The name of a generated table: ``"procgen:SEED"`` or ``"procgen-hard:SEED"``, with
    targets ``"procgen+targets:SEED"`` or ``"procgen-hard+targets:SEED"``."""
    return f"{name_prefix(difficulty, targets)}:{seed}"


def parse_name(name: str) -> tuple[int, str, bool] | None:
    """``(seed, difficulty, targets)`` for a generated table's name, None for any other name;
    a ``procgen`` name with a bad seed is a ``TableError``."""
    match = NAME_PATTERN.fullmatch(name)
    if match is None:
        return None
    prefix, targets, seed = match.groups()
    if not re.fullmatch(r"\d{1,19}", seed) or int(seed) > MAX_SEED:
        raise TableError(
            f"{name!r}: the seed of a generated table is an integer from 0 to {MAX_SEED}, "
            f"got {seed!r}"
        )
    difficulty = next(d for d, p in PREFIXES.items() if p == prefix)
    return int(seed), difficulty, targets is not None
