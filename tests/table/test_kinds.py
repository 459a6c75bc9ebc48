"""The element kinds' registry (pinball_env.table.kinds) against its readers: the kernel's own
element-id order (physics.data's first_* chain, which cannot read the registry), sim.World's
saucer and lock ids, the schema, the writer and the drawing."""

import dataclasses
import re

import numpy as np
import pytest

from pinball_env.physics import first_circle, first_flipper, first_sensor
from pinball_env.physics.data import (
    element_count,
    first_drop_target,
    first_kickback,
    first_spinner,
)
from pinball_env.render.raster import DISC_COLOURS, LINE_STYLES
from pinball_env.sim import World
from pinball_env.table import available_tables, load_any_table, load_table, table_to_dict
from pinball_env.table.kinds import (
    DRAW_ORDER,
    ID_ORDER,
    KINDS,
    KINDS_BY_KEY,
    Disc,
    Line,
    kinds_of,
    static_shapes,
)
from pinball_env.table.model import Table
from pinball_env.table.schema import TABLE_FIELDS
from pinball_env.tools.serve import STATIC

# The kernel's first id of each packed kind (the walls' segments start at 0, the stand-up
# targets' follow them in the segments array), and where the unpacked kinds start.
KERNEL_FIRST = {
    "posts": first_circle,
    "flippers": first_flipper,
    "sensors": first_sensor,
    "drop_targets": first_drop_target,
    "spinners": first_spinner,
    "kickbacks": first_kickback,
    "saucers": element_count,
}
TABLES = [*available_tables("all"), "procgen:3", "procgen-hard+targets:11"]


@pytest.fixture(scope="module", params=TABLES)
def table(request) -> Table:
    return load_any_table(request.param)


def test_the_kernels_id_order_is_the_registrys(table):
    geometry = table.pack()
    assert table.element_ids("walls").start == 0
    assert table.element_ids("standup_targets").stop == geometry.segments.shape[0]
    for key, first in KERNEL_FIRST.items():
        assert table.element_ids(key).start == first(geometry), key
    assert table.element_ids("locks").stop == len(table.element_names)


def test_the_id_order_is_whole_and_packs_first():
    assert sorted(kind.id_rank for kind in KINDS) == list(range(len(KINDS)))
    packed = [kind.packed for kind in ID_ORDER]
    assert packed == sorted(packed, reverse=True)  # the unpacked kinds' ids after every packed
    assert {kind.key for kind in KINDS} == {
        field.name for field in dataclasses.fields(Table) if field.name in KINDS_BY_KEY
    }


def test_each_kinds_ids_name_its_elements(table):
    for kind in KINDS:
        ids = table.element_ids(kind.key)
        names = [name for e in getattr(table, kind.key) for name, _ in kind.ids(e)]
        assert list(table.element_names[ids.start : ids.stop]) == names, kind.key


def test_worlds_saucer_and_lock_ids_are_the_registrys():
    table = load_table("classic_v3")
    world = World(table, n_envs=1)
    np.testing.assert_array_equal(world.saucer_ids, np.array(table.element_ids("saucers")))
    np.testing.assert_array_equal(world.lock_ids, np.array(table.element_ids("locks")))


def test_the_schema_and_the_writer_list_the_kinds_in_file_order():
    keys = [key for key in TABLE_FIELDS if key in KINDS_BY_KEY]
    assert keys == [kind.key for kind in KINDS]
    assert {kind.group for kind in KINDS} == {"core", "targets", "multiball"}
    assert sum(len(kinds_of(group)) for group in ("core", "targets", "multiball")) == len(KINDS)
    written = [key for key in table_to_dict(load_table("classic_v3")) if key in KINDS_BY_KEY]
    assert written == [kind.key for kind in KINDS]
    # A table without targets writes the core kinds only (an older table writes as it did).
    written = [key for key in table_to_dict(load_table("box")) if key in KINDS_BY_KEY]
    assert written == [kind.key for kind in kinds_of("core")]


def test_the_static_layer_draws_the_floor_first_then_file_order():
    assert [kind.key for kind in DRAW_ORDER] == [
        "sensors", "walls", "posts", "standup_targets", "spinners", "kickbacks", "saucers",
        "locks",
    ]  # fmt: skip
    table = load_table("classic_v3")
    shapes = list(static_shapes(table))
    assert all(isinstance(shape, (Line, Disc)) for shape in shapes)
    n_lines = len(table.sensors) + sum(len(w.segments()) for w in table.walls)
    n_lines += len(table.standup_targets) + len(table.spinners) + len(table.kickbacks)
    assert sum(isinstance(shape, Line) for shape in shapes) == n_lines
    n_discs = len(table.posts) + len(table.saucers) + sum(len(k.slots) for k in table.locks)
    assert sum(isinstance(shape, Disc) for shape in shapes) == n_discs
    assert shapes[0] == Line(
        table.sensors[0].segment, "drain" if table.sensors[0].drain else "sensor"
    )


def test_the_renderer_and_the_page_know_every_style(table):
    shapes = list(static_shapes(table))
    assert {s.style for s in shapes if isinstance(s, Line)} <= set(LINE_STYLES)
    assert {s.style for s in shapes if isinstance(s, Disc)} <= set(DISC_COLOURS)
    # The page's widths of the lines' styles (its colours are the renderer's, by name).
    page = (STATIC / "app.js").read_text(encoding="utf-8")
    widths = re.search(r"const half = \{(.*?)\};", page, re.S)[1]
    assert set(re.findall(r"(\w+):", widths)) == set(LINE_STYLES)
