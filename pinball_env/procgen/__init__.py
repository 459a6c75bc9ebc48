"""Generated tables: endless playable layouts, each drawn from a seed.

``generate_table(seed, difficulty, targets=False)`` draws a table in the proportions of real
machines (Procgen's idea, for pinball): playfield size and slope, the top arch, the shooter lane
and its gate, the flippers, outlanes and inlanes, slingshots, and a varying number and placement
of pop bumpers, rubber posts, deflector walls (some one-way), upper deflectors and top rollover
lanes; with ``targets=True`` also a drop bank (2-4 targets facing the flippers) and a spinner,
drawn from a random stream of their own, so that the tables without them stay as they were. The
same seed gives the same table on any machine (NumPy's ``SeedSequence`` and ``PCG64`` are specified,
and every length is rounded to 0.01 mm).

A drawn layout is kept only if it passes ``load_table``'s validation and :func:`playability`
(the plunger shot comes into the playfield and down to a flipper, the inlanes feed the
flippers, every ball drains with the flippers at rest: see ``playability.py``). Placed elements
keep ``CLEARANCE`` (a ball and a margin) from every other element, so nothing overlaps and every
gap lets a ball through. A layout that fails is redrawn from the next derived seed; :func:`generate`
says how many draws it took and why each was rejected. ``"easy"`` tables are forgiving (long
flippers, a narrow centre gap, narrow outlanes, upper deflectors); ``"hard"`` ones are not.

- ``names.py``: the difficulties, seeds and names (``"procgen:SEED"``, ``"procgen-hard:SEED"``,
  ``"procgen+targets:SEED"``, ``"procgen-hard+targets:SEED"``);
- ``ranges.py``: what each difficulty draws from;
- ``obstacles.py``: rounded lengths, and the clearance between placed elements;
- ``layout.py``: :func:`draw_layout`, the layout drawn element by element (and the targets);
- ``playability.py``: :func:`playability`, the check on the kernel;
- ``generate.py``: :func:`generate` and :func:`generate_table`, draws until one plays.

Importing the package registers the generated tables' names with the table package, so that
:func:`load_any_table` (``pinball_env.table.load_any_table``) takes them wherever a table name is
taken (the envs, the plot tool, training configs).
"""

from pinball_env.procgen.generate import (
    MAX_DRAWS,
    Generated,
    generate,
    generate_table,
    table_by_name,
)
from pinball_env.procgen.layout import (
    BALL_RADIUS,
    CLEARANCE,
    DRAIN_Y,
    LANE_WIDTH,
    MARGIN,
    MATERIALS,
    LayoutError,
    draw_layout,
)
from pinball_env.procgen.names import (
    DIFFICULTIES,
    MAX_SEED,
    NAME_PATTERN,
    PREFIXES,
    TARGETS_SUFFIX,
    UNLIMITED_LAYOUTS,
    check_difficulty,
    layout_seeds,
    name_prefix,
    parse_name,
    table_name,
)
from pinball_env.procgen.obstacles import Obstacles
from pinball_env.procgen.playability import (
    DRAIN_TIME,
    DROPS,
    LAUNCHES,
    MIN_FLIPPER_SHARE,
    MIN_LAUNCH_SHARE,
    REST_TIME,
    SLING_HEIGHTS,
    SLING_SPEEDS,
    playability,
)
from pinball_env.procgen.ranges import RANGES, Ranges
from pinball_env.table import load_any_table, register_generator

_Obstacles = Obstacles  # the name the tests knew

for _difficulty in DIFFICULTIES:
    for _targets in (False, True):
        register_generator(name_prefix(_difficulty, _targets), table_by_name)

__all__ = [
    "BALL_RADIUS",
    "CLEARANCE",
    "DIFFICULTIES",
    "DRAIN_TIME",
    "DRAIN_Y",
    "DROPS",
    "LANE_WIDTH",
    "LAUNCHES",
    "MARGIN",
    "MATERIALS",
    "MAX_DRAWS",
    "MAX_SEED",
    "MIN_FLIPPER_SHARE",
    "MIN_LAUNCH_SHARE",
    "NAME_PATTERN",
    "PREFIXES",
    "RANGES",
    "REST_TIME",
    "SLING_HEIGHTS",
    "SLING_SPEEDS",
    "TARGETS_SUFFIX",
    "UNLIMITED_LAYOUTS",
    "Generated",
    "LayoutError",
    "Obstacles",
    "Ranges",
    "check_difficulty",
    "draw_layout",
    "generate",
    "generate_table",
    "layout_seeds",
    "load_any_table",
    "name_prefix",
    "parse_name",
    "playability",
    "table_by_name",
    "table_name",
]
