"""Tests of the table loader: box.yaml, packing, and one case per validation rule."""

import copy
import dataclasses
import math
import re
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml

from pinball_env.physics import layout
from pinball_env.table import (
    TABLES_DIR,
    Ball,
    Simulation,
    Table,
    TableError,
    Wall,
    available_tables,
    load_table,
    table_from_dict,
)

BOX = TABLES_DIR / "box.yaml"


def box_dict() -> dict[str, Any]:
    with BOX.open(encoding="utf-8") as f:
        return yaml.safe_load(f)


# --- box.yaml and packing ----------------------------------------------------------------------


def test_box_loads() -> None:
    table = load_table(BOX)
    assert table.name == "box"
    assert (table.width, table.height) == (0.51, 1.07)
    assert table.ball == Ball(radius=0.0135, mass=0.08, start=(0.255, 0.9))
    assert [m.name for m in table.materials] == ["wall", "rubber"]
    assert table.material("rubber").restitution == 0.85
    assert [w.name for w in table.walls] == ["outline", "inlane_left", "inlane_right", "gate"]
    assert [w.name for w in table.walls if w.one_sided] == ["gate"]
    assert len(table.posts) == 2
    assert table.simulation == Simulation()
    assert table.source == str(BOX)


def test_load_by_name() -> None:
    assert load_table("box") == load_table(BOX)
    assert "box" in available_tables()


def test_packed_arrays() -> None:
    table = load_table("box")
    packed = table.pack()
    n_segments = sum(len(w.segments()) for w in table.walls)
    n_circles = len(table.posts)
    expected = {
        "segments": ((n_segments, 4), np.float64),
        "segment_props": ((n_segments, layout.PROP_SIZE), np.float64),
        "segment_one_sided": ((n_segments,), np.bool_),
        "circles": ((n_circles, 3), np.float64),
        "circle_props": ((n_circles, layout.PROP_SIZE), np.float64),
        "gravity": ((2,), np.float64),
    }
    for field, (shape, dtype) in expected.items():
        array = getattr(packed, field)
        assert array.shape == shape, field
        assert array.dtype == dtype, field
        assert array.flags.c_contiguous, field
        assert not array.flags.writeable, field
    with pytest.raises(ValueError, match="read-only"):
        packed.segments[0, 0] = 1.0
    assert len(packed.element_names) == n_segments + n_circles
    assert packed.element_names[:4] == ("outline[0]", "outline[1]", "outline[2]", "outline[3]")
    assert packed.element_names[-2:] == ("post_left", "post_right")


def test_packed_values() -> None:
    packed = load_table("box").pack()
    # Gate: the last segment, one-sided, wall material.
    np.testing.assert_array_equal(packed.segments[-1], [0.36, 0.80, 0.46, 0.80])
    assert packed.segment_one_sided.tolist() == [False] * 6 + [True]
    assert packed.segment_props[-1, layout.PROP_RESTITUTION] == 0.3
    assert packed.segment_props[-1, layout.PROP_FRICTION] == 0.3
    assert packed.segment_props[-1, layout.PROP_KICK] == 0.0
    np.testing.assert_array_equal(packed.circles[0], [0.20, 0.60, 0.01])
    assert packed.circle_props[0, layout.PROP_RESTITUTION] == 0.85
    assert packed.circle_props[0, layout.PROP_FRICTION] == 0.5


def test_gravity_vector() -> None:
    table = load_table("box")
    expected = -9.81 * math.sin(math.radians(6.5))
    assert table.gravity_vector == pytest.approx((0.0, expected), rel=1e-15)
    np.testing.assert_allclose(table.pack().gravity, [0.0, expected], rtol=1e-15)


def test_wall_segments_closing_segment() -> None:
    points = ((0.0, 0.0), (1.0, 0.0), (1.0, 1.0))
    open_wall = Wall(name="w", points=points, material="m")
    assert open_wall.segments() == ((0.0, 0.0, 1.0, 0.0), (1.0, 0.0, 1.0, 1.0))
    closed_wall = dataclasses.replace(open_wall, closed=True)
    assert closed_wall.segments()[:2] == open_wall.segments()
    assert closed_wall.segments()[2] == (1.0, 1.0, 0.0, 0.0)


def test_kick_is_packed() -> None:
    data = box_dict()
    data["walls"][1]["kick"] = 1.5
    data["posts"][0]["kick"] = 2.5
    packed = table_from_dict(data).pack()
    assert packed.segment_props[4, layout.PROP_KICK] == 1.5
    assert packed.circle_props[0, layout.PROP_KICK] == 2.5


def test_empty_table_packs_to_empty_arrays() -> None:
    data = box_dict()
    del data["walls"], data["posts"]
    packed = table_from_dict(data).pack()
    assert packed.segments.shape == (0, 4)
    assert packed.segment_props.shape == (0, layout.PROP_SIZE)
    assert packed.segment_one_sided.shape == (0,)
    assert packed.circles.shape == (0, 3)
    assert packed.circle_props.shape == (0, layout.PROP_SIZE)
    assert packed.element_names == ()


def test_defaults_come_from_the_dataclasses() -> None:
    data = box_dict()
    for key in ("slope_deg", "gravity", "simulation"):
        del data[key]
    del data["ball"]["velocity"]
    table = table_from_dict(data)
    defaults = {f.name: f.default for f in dataclasses.fields(Table)}
    assert table.slope_deg == defaults["slope_deg"]
    assert table.gravity == defaults["gravity"]
    assert table.simulation == Simulation()
    assert table.ball.velocity == (0.0, 0.0)
    assert table.source == "<dict>"


def test_ints_accepted_for_floats() -> None:
    data = box_dict()
    data["gravity"] = 10
    data["simulation"]["frame_rate"] = 120
    table = table_from_dict(data)
    assert isinstance(table.gravity, float) and table.gravity == 10.0
    assert isinstance(table.simulation.frame_rate, float)
    assert isinstance(table.simulation.substeps, int)


def test_table_is_frozen() -> None:
    table = load_table("box")
    with pytest.raises(dataclasses.FrozenInstanceError):
        table.name = "other"  # type: ignore[misc]


# --- validation: one case per rule ---------------------------------------------------------------

Mutation = Callable[[dict[str, Any]], None]


def _set(*keys: Any, value: Any) -> Mutation:
    """Mutation setting data[k0][k1]...[kn] = value."""

    def mutate(data: dict[str, Any]) -> None:
        for key in keys[:-1]:
            data = data[key]
        data[keys[-1]] = value

    return mutate


def _drop(*keys: Any) -> Mutation:
    """Mutation deleting data[k0][k1]...[kn]."""

    def mutate(data: dict[str, Any]) -> None:
        for key in keys[:-1]:
            data = data[key]
        del data[keys[-1]]

    return mutate


OUTLINE = "walls[0] 'outline'"
INLANE = "walls[1] 'inlane_left'"
POST = "posts[0] 'post_left'"

# (mutation of box.yaml's dict, element path in the message, word of the problem)
BAD_TABLES: dict[str, tuple[Mutation, str, str]] = {
    # unknown keys, at every level
    "unknown top key": (_set("colour", value="red"), "top level", "unknown key 'colour'"),
    "unknown playfield key": (_set("playfield", "depth", value=1), "playfield", "unknown key"),
    "unknown ball key": (_set("ball", "spin", value=0.0), "ball", "unknown key 'spin'"),
    "unknown material key": (
        _set("materials", "wall", "restitucion", value=0.3),
        "materials.wall",
        "unknown key 'restitucion' (allowed: friction, restitution)",
    ),
    "unknown wall key": (_set("walls", 0, "colsed", value=True), OUTLINE, "unknown key 'colsed'"),
    "unknown post key": (_set("posts", 0, "kik", value=1.0), POST, "unknown key 'kik'"),
    "unknown simulation key": (
        _set("simulation", "substep", value=5),
        "simulation",
        "unknown key 'substep'",
    ),
    # missing required fields
    "missing name": (_drop("name"), "top level", "missing required key 'name'"),
    "missing playfield": (_drop("playfield"), "top level", "missing required key 'playfield'"),
    "missing ball": (_drop("ball"), "top level", "missing required key 'ball'"),
    "missing materials": (_drop("materials"), "top level", "missing required key 'materials'"),
    "missing width": (_drop("playfield", "width"), "playfield", "missing required key 'width'"),
    "missing radius": (_drop("ball", "radius"), "ball", "missing required key 'radius'"),
    "missing start": (_drop("ball", "start"), "ball", "missing required key 'start'"),
    "missing friction": (_drop("materials", "rubber", "friction"), "materials.rubber", "missing"),
    "missing wall name": (_drop("walls", 1, "name"), "walls[1]", "missing required key 'name'"),
    "missing wall points": (_drop("walls", 1, "points"), INLANE, "missing required key 'points'"),
    "missing material": (_drop("walls", 1, "material"), INLANE, "missing required key 'material'"),
    "missing post center": (_drop("posts", 0, "center"), POST, "missing required key 'center'"),
    # wrong types
    "string number": (_set("ball", "radius", value="big"), "ball.radius", "expected a number"),
    "bool number": (_set("gravity", value=True), "gravity", "expected a number, got bool"),
    "float substeps": (
        _set("simulation", "substeps", value=10.5),
        "simulation.substeps",
        "integer",
    ),
    "float max_passes": (
        _set("simulation", "max_passes", value=16.0),
        "simulation.max_passes",
        "expected an integer",
    ),
    "name not a string": (_set("name", value=3), "name", "expected a non-empty string"),
    "playfield not a mapping": (_set("playfield", value=[0.5, 1.0]), "playfield", "mapping"),
    "walls not a list": (_set("walls", value={"a": 1}), "walls", "expected a list"),
    "wall not a mapping": (_set("walls", 1, value=[1, 2]), "walls[1]", "expected a mapping"),
    "closed not a bool": (_set("walls", 0, "closed", value="yes"), f"{OUTLINE}.closed", "true"),
    "no materials": (_set("materials", value={}), "materials", "at least one material"),
    "exponent without dot": (_set("simulation", "skin", value="1e-6"), "simulation.skin", "1.0e-6"),
    # non-finite numbers
    "nan": (_set("gravity", value=float("nan")), "gravity", "finite"),
    "inf": (_set("ball", "mass", value=float("inf")), "ball.mass", "finite"),
    "nan in a point": (
        _set("ball", "velocity", value=[0.0, float("nan")]),
        "ball.velocity[1]",
        "finite",
    ),
    # out-of-range numbers
    "slope 90": (_set("slope_deg", value=90), "slope_deg", "out of range (must be [0, 90))"),
    "slope negative": (_set("slope_deg", value=-1.0), "slope_deg", "out of range"),
    "gravity zero": (_set("gravity", value=0.0), "gravity", "out of range (must be > 0)"),
    "width negative": (_set("playfield", "width", value=-0.5), "playfield.width", "out of range"),
    "radius zero": (_set("ball", "radius", value=0), "ball.radius", "out of range"),
    "mass negative": (_set("ball", "mass", value=-0.08), "ball.mass", "out of range"),
    "restitution": (
        _set("materials", "wall", "restitution", value=1.6),
        "materials.wall.restitution",
        "out of range (must be [0, 1.5])",
    ),
    "friction": (
        _set("materials", "wall", "friction", value=-0.1),
        "materials.wall.friction",
        "out of range (must be [0, 2])",
    ),
    "wall kick": (_set("walls", 1, "kick", value=-1.0), f"{INLANE}.kick", "out of range"),
    "post kick": (_set("posts", 0, "kick", value=-1.0), f"{POST}.kick", "out of range"),
    "post radius": (_set("posts", 0, "radius", value=0.0), f"{POST}.radius", "out of range"),
    "frame_rate": (_set("simulation", "frame_rate", value=0), "simulation.frame_rate", "range"),
    "substeps": (_set("simulation", "substeps", value=0), "simulation.substeps", "out of range"),
    "max_passes": (_set("simulation", "max_passes", value=0), "simulation.max_passes", "range"),
    "skin zero": (_set("simulation", "skin", value=0.0), "simulation.skin", "(must be (0, 0.001])"),
    "skin large": (_set("simulation", "skin", value=2e-3), "simulation.skin", "out of range"),
    "resting_speed": (
        _set("simulation", "resting_speed", value=-0.1),
        "simulation.resting_speed",
        "out of range",
    ),
    # points that are not pairs
    "point single": (_set("walls", 1, "points", 1, value=[0.2]), f"{INLANE}.points[1]", "pair"),
    "point triple": (_set("ball", "start", value=[0.2, 0.5, 0.0]), "ball.start", "pair"),
    "point string": (_set("posts", 0, "center", value="0.2, 0.6"), f"{POST}.center", "pair"),
    "one point": (_set("walls", 1, "points", value=[[0.1, 0.1]]), f"{INLANE}.points", "at least 2"),
    # points outside the playfield
    "wall point outside": (
        _set("walls", 1, "points", 0, value=[0.6, 0.4]),
        f"{INLANE}.points[0]",
        "outside the playfield",
    ),
    "post outside": (_set("posts", 0, "center", value=[0.2, 1.2]), f"{POST}.center", "outside"),
    "ball outside": (_set("ball", "start", value=[-0.1, 0.5]), "ball.start", "outside"),
    # zero-length segments
    "zero-length segment": (
        _set("walls", 1, "points", value=[[0.05, 0.4], [0.05, 0.4], [0.21, 0.2]]),
        INLANE,
        "segment 0 has zero length",
    ),
    "zero-length closing segment": (
        _set("walls", 0, "points", 3, value=[0.01, 0.01]),
        OUTLINE,
        "segment 3 has zero length",
    ),
    # references, names, closed polylines
    "unknown wall material": (
        _set("walls", 1, "material", value="steel"),
        f"{INLANE}.material",
        "unknown material 'steel' (known: rubber, wall)",
    ),
    "unknown post material": (_set("posts", 0, "material", value="x"), f"{POST}.material", "x'"),
    "duplicate wall names": (
        _set("walls", 2, "name", value="inlane_left"),
        "walls[2] 'inlane_left'",
        "duplicate element name 'inlane_left' (also walls[1]",
    ),
    "duplicate wall and post": (
        _set("posts", 1, "name", value="gate"),
        "posts[1] 'gate'",
        "duplicate element name 'gate'",
    ),
    "closed with 2 points": (_set("walls", 1, "closed", value=True), INLANE, "at least 3 points"),
    # ball start overlapping an element
    "ball on a wall": (
        _set("ball", "start", value=[0.02, 0.5]),
        "ball.start",
        "overlaps wall 'outline' segment 3",
    ),
    "ball on a post": (_set("ball", "start", value=[0.2, 0.62]), "ball.start", "post 'post_left'"),
}


def _write(tmp_path: Path, data: Any) -> Path:
    path = tmp_path / "bad.yaml"
    path.write_text(yaml.safe_dump(data, sort_keys=False), encoding="utf-8")
    return path


@pytest.mark.parametrize("case", BAD_TABLES, ids=list(BAD_TABLES))
def test_invalid_table(tmp_path: Path, case: str) -> None:
    mutate, where, problem = BAD_TABLES[case]
    data = copy.deepcopy(box_dict())
    mutate(data)
    path = _write(tmp_path, data)
    pattern = re.escape(f"bad.yaml: {where}") + ".*" + re.escape(problem)
    with pytest.raises(TableError, match=pattern):
        load_table(path)


def test_box_round_trips_through_the_writer(tmp_path: Path) -> None:
    """The writer used above yields a valid file when nothing is mutated."""
    assert load_table(_write(tmp_path, box_dict())).walls == load_table("box").walls


def test_yaml_syntax_error(tmp_path: Path) -> None:
    path = tmp_path / "broken.yaml"
    path.write_text("name: box\nplayfield: {width: 0.51\n", encoding="utf-8")
    with pytest.raises(TableError, match=r"broken\.yaml: invalid YAML"):
        load_table(path)


def test_duplicate_yaml_key(tmp_path: Path) -> None:
    path = tmp_path / "twice.yaml"
    path.write_text(BOX.read_text(encoding="utf-8") + "gravity: 1.0\n", encoding="utf-8")
    with pytest.raises(TableError, match=r"twice\.yaml: invalid YAML.*duplicate key 'gravity'"):
        load_table(path)


def test_top_level_not_a_mapping(tmp_path: Path) -> None:
    path = _write(tmp_path, [1, 2])
    with pytest.raises(TableError, match=r"bad\.yaml: top level: expected a mapping, got list"):
        load_table(path)


def test_empty_file(tmp_path: Path) -> None:
    path = tmp_path / "empty.yaml"
    path.write_text("", encoding="utf-8")
    with pytest.raises(TableError, match=r"empty\.yaml: top level: expected a mapping"):
        load_table(path)


def test_from_dict_names_dict_source() -> None:
    data = box_dict()
    data["ball"]["radius"] = "big"
    with pytest.raises(TableError, match=r"^<dict>: ball\.radius: expected a number, got str"):
        table_from_dict(data)


def test_unknown_name_lists_available_tables() -> None:
    with pytest.raises(TableError, match=r"unknown table 'no_such_table' \(available: .*box"):
        load_table("no_such_table")


def test_missing_file(tmp_path: Path) -> None:
    path = tmp_path / "missing.yaml"
    with pytest.raises(TableError, match=r"missing\.yaml: table file not found"):
        load_table(path)
