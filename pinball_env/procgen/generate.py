"""Generated tables from a seed: a layout drawn, validated and checked, redrawn until it plays.

The same seed gives the same table on any machine (NumPy's ``SeedSequence`` and ``PCG64`` are
specified, and every length is rounded to 0.01 mm). A layout that fails ``load_table``'s
validation or :func:`~pinball_env.procgen.playability.playability` is redrawn from the next
derived seed (``SeedSequence([seed, difficulty, draw])``); :func:`generate` says how many draws it
took and why each was rejected. With ``targets`` a drop bank and a spinner are drawn onto each
layout from a stream of their own (``SeedSequence([seed, difficulty, draw, 1])``), so that tables
without them are what they were before targets existed (published scores depend on that).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from pinball_env.procgen.layout import LayoutError, draw_layout
from pinball_env.procgen.names import (
    DIFFICULTIES,
    MAX_SEED,
    check_difficulty,
    parse_name,
    table_name,
)
from pinball_env.procgen.playability import playability
from pinball_env.procgen.ranges import RANGES
from pinball_env.table import Table, TableError, table_from_dict
from pinball_env.table.fields import is_flag, is_int

# Draws tried before giving up on a seed (none has needed more than a handful).
MAX_DRAWS = 100


@dataclass(frozen=True)
class Generated:
    """A generated table and how it was found."""

    table: Table
    seed: int
    difficulty: str
    targets: bool  # a drop bank and a spinner drawn onto the layout
    draws: int  # layouts drawn, the kept one included
    rejected: tuple[str, ...]  # why each earlier draw was rejected


def generate_table(seed: int, difficulty: str = "easy", targets: bool = False) -> Table:
    """The playable table drawn from ``seed`` (see :mod:`pinball_env.procgen`); with
    ``targets``, with a drop bank and a spinner."""
    return generate(seed, difficulty, targets).table


def generate(seed: int, difficulty: str = "easy", targets: bool = False) -> Generated:
    """:func:`generate_table`, with the number of draws it took and the rejections."""
    check_difficulty(difficulty)
    if not is_flag(targets):
        raise TypeError(f"targets must be True or False, got {targets!r}")
    targets = bool(targets)
    if not is_int(seed):
        raise TypeError(f"seed must be an integer, got {type(seed).__name__}")
    if not 0 <= seed <= MAX_SEED:
        raise ValueError(f"seed must be from 0 to {MAX_SEED}, got {seed}")
    seed = int(seed)
    name = table_name(seed, difficulty, targets)
    rejected: list[str] = []
    for draw in range(MAX_DRAWS):
        stream = [seed, DIFFICULTIES.index(difficulty), draw]
        rng = np.random.default_rng(stream)
        targets_rng = np.random.default_rng([*stream, 1]) if targets else None
        try:
            layout = draw_layout(rng, RANGES[difficulty], name, targets_rng)
            table = table_from_dict(layout, f"<{name}>")
        except (TableError, LayoutError) as exc:
            rejected.append(f"draw {draw}: {exc}")
            continue
        problem = playability(table, rng)
        if problem is None:
            return Generated(table, seed, difficulty, targets, draw + 1, tuple(rejected))
        rejected.append(f"draw {draw}: {problem}")
    raise RuntimeError(f"{name}: no playable layout in {MAX_DRAWS} draws: {rejected[-3:]}")


def table_by_name(name: str) -> Table:
    """The generated table named ``name`` (``"procgen:SEED"``, ``"procgen-hard:SEED"``, either
    with ``+targets`` before the colon): what ``pinball_env.table.load_any_table`` calls for
    those names."""
    parsed = parse_name(name)
    if parsed is None:
        raise TableError(
            f"{name!r} is not a generated table's name (procgen[-hard][+targets]:SEED)"
        )
    return generate_table(*parsed)
