"""Generated tables' names: ``"procgen:SEED"`` (easy) and ``"procgen-hard:SEED"``, and the
difficulties and seeds they take."""

from __future__ import annotations

import re

from pinball_env.table import TableError

DIFFICULTIES = ("easy", "hard")
PREFIXES = {"easy": "procgen", "hard": "procgen-hard"}
NAME_PATTERN = re.compile(r"(procgen|procgen-hard):(.*)")
MAX_SEED = 2**63 - 1


def check_difficulty(difficulty: str) -> str:
    """``difficulty``, if it is one of :data:`DIFFICULTIES` (a ``ValueError`` if not)."""
    if difficulty not in DIFFICULTIES:
        raise ValueError(f"difficulty must be one of {DIFFICULTIES}, got {difficulty!r}")
    return difficulty


def table_name(seed: int, difficulty: str = "easy") -> str:
    """The name of a generated table: ``"procgen:SEED"`` or ``"procgen-hard:SEED"``."""
    return f"{PREFIXES[check_difficulty(difficulty)]}:{seed}"


def parse_name(name: str) -> tuple[int, str] | None:
    """``(seed, difficulty)`` for a generated table's name, None for any other name; a
    ``procgen`` name with a bad seed is a ``TableError``."""
    match = NAME_PATTERN.fullmatch(name)
    if match is None:
        return None
    prefix, seed = match.groups()
    if not re.fullmatch(r"\d{1,19}", seed) or int(seed) > MAX_SEED:
        raise TableError(
            f"{name!r}: the seed of a generated table is an integer from 0 to {MAX_SEED}, "
            f"got {seed!r}"
        )
    difficulty = next(d for d, p in PREFIXES.items() if p == prefix)
    return int(seed), difficulty
