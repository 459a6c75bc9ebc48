"""Tests of the table loader: box.yaml, classic.yaml, packing, and one case per validation rule."""

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

from pinball_env.physics import columns
from pinball_env.table import (
    Ball,
    Flipper,
    Plunger,
    Post,
    Sensor,
    Simulation,
    Table,
    TableError,
    Wall,
    available_tables,
    builtin_tables_dir,
    dump_table,
    load_table,
    table_from_dict,
    table_to_dict,
)

BOX = builtin_tables_dir() / "box.yaml"
CLASSIC = builtin_tables_dir() / "classic.yaml"


def box_dict() -> dict[str, Any]:
    with BOX.open(encoding="utf-8") as f:
        return yaml.safe_load(f)


def classic_dict() -> dict[str, Any]:
    with CLASSIC.open(encoding="utf-8") as f:
        return yaml.safe_load(f)


def _check_arrays(packed: Any, expected: dict[str, tuple[tuple[int, ...], type]]) -> None:
    """Every array named in ``expected`` has that shape and dtype, C order, read-only."""
    for field, (shape, dtype) in expected.items():
        array = getattr(packed, field)
        assert array.shape == shape, field
        assert array.dtype == dtype, field
        assert array.flags.c_contiguous, field
        assert not array.flags.writeable, field


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
    assert available_tables() == ["classic", "classic_v1", "classic_v2", "classic_v3"]
    assert available_tables("test") == ["box"]
    assert available_tables("all") == ["box", "classic", "classic_v1", "classic_v2", "classic_v3"]


def test_packed_arrays() -> None:
    table = load_table("box")
    packed = table.pack()
    n_segments = sum(len(w.segments()) for w in table.walls)
    n_circles = len(table.posts)
    expected = {
        "segments": ((n_segments, 4), np.float64),
        "segment_props": ((n_segments, columns.PROP_SIZE), np.float64),
        "segment_one_sided": ((n_segments,), np.bool_),
        "circles": ((n_circles, 3), np.float64),
        "circle_props": ((n_circles, columns.PROP_SIZE), np.float64),
        "segment_bounds": ((n_segments, columns.BOUND_SIZE), np.float64),
        # box.yaml has no flippers and no sensors: empty arrays of the right shape
        "flippers": ((0, columns.FLIPPER_SIZE), np.float64),
        "flipper_props": ((0, columns.PROP_SIZE), np.float64),
        "sensors": ((0, 4), np.float64),
        "sensor_drain": ((0,), np.bool_),
    }
    _check_arrays(packed, expected)
    _check_arrays(table, {"element_scores": ((n_segments + n_circles,), np.int64)})
    assert table.flipper_buttons == ()
    assert not table.element_scores.any()
    assert table.plunger is None
    with pytest.raises(ValueError, match="read-only"):
        packed.segments[0, 0] = 1.0
    assert len(table.element_names) == n_segments + n_circles
    assert table.element_names[:4] == ("outline[0]", "outline[1]", "outline[2]", "outline[3]")
    assert table.element_names[-2:] == ("post_left", "post_right")


def test_packed_values() -> None:
    packed = load_table("box").pack()
    # Gate: the last segment, one-sided, wall material.
    np.testing.assert_array_equal(packed.segments[-1], [0.36, 0.80, 0.46, 0.80])
    assert packed.segment_one_sided.tolist() == [False] * 6 + [True]
    assert packed.segment_props[-1, columns.PROP_RESTITUTION] == 0.3
    assert packed.segment_props[-1, columns.PROP_FRICTION] == 0.3
    assert packed.segment_props[-1, columns.PROP_KICK] == 0.0
    np.testing.assert_array_equal(packed.circles[0], [0.20, 0.60, 0.01])
    assert packed.circle_props[0, columns.PROP_RESTITUTION] == 0.85
    assert packed.circle_props[0, columns.PROP_FRICTION] == 0.5


def test_gravity_vector() -> None:
    table = load_table("box")
    expected = -9.81 * math.sin(math.radians(6.5))
    assert table.gravity_vector == pytest.approx((0.0, expected), rel=1e-15)
    settings = table.pack_settings()
    assert (settings.gravity_x, settings.gravity_y) == table.gravity_vector


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
    assert packed.segment_props[4, columns.PROP_KICK] == 1.5
    assert packed.circle_props[0, columns.PROP_KICK] == 2.5


def test_empty_table_packs_to_empty_arrays() -> None:
    data = box_dict()
    del data["walls"], data["posts"]
    table = table_from_dict(data)
    packed = table.pack()
    assert packed.segments.shape == (0, 4)
    assert packed.segment_props.shape == (0, columns.PROP_SIZE)
    assert packed.segment_one_sided.shape == (0,)
    assert packed.circles.shape == (0, 3)
    assert packed.circle_props.shape == (0, columns.PROP_SIZE)
    assert table.element_names == ()
    assert packed.flippers.shape == (0, columns.FLIPPER_SIZE)
    assert packed.sensors.shape == (0, 4)
    assert table.element_scores.shape == (0,)


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


# --- classic.yaml: flippers, sensors, plunger, scores ------------------------------------------


def test_classic_loads() -> None:
    table = load_table("classic")
    assert table.name == "classic"
    assert "classic" in available_tables()
    assert table.ball.start == (0.4865, 0.04)
    assert table.plunger == Plunger(position=(0.4865, 0.04), speed=(2.2, 3.2))
    assert [f.name for f in table.flippers] == ["left_flipper", "right_flipper"]
    assert table.flippers[0] == Flipper(
        name="left_flipper",
        pivot=(0.146, 0.12),
        length=0.07,
        base_radius=0.0116,
        tip_radius=0.007,
        rest_angle=-25.0,
        up_angle=25.0,
        stroke_time=0.022,
        return_time=0.04,
        material="flipper",
        button="left",
    )
    assert [s.name for s in table.sensors if s.drain] == ["drain"]
    assert table.sensors[0] == Sensor(
        name="left_outlane", points=((0.005, 0.28), (0.04, 0.28)), score=10
    )
    assert [w.name for w in table.walls if w.one_sided] == ["gate"]
    assert {w.name: w.score for w in table.walls if w.score} == {
        "left_slingshot": 10,
        "right_slingshot": 10,
    }
    assert [p.score for p in table.posts] == [100, 100, 100, 0, 0]
    outline = table.walls[0]
    assert outline.closed and len(outline.segments()) == 27  # 3 + 24 arch segments
    # The arch ends on the semicircle's far end, left of its centre (0.255, 0.82).
    assert outline.points[-1] == (0.005, 0.82)
    # The right half mirrors the left about x = 0.2365.
    by_name = {p.name: p for p in table.posts}
    assert by_name["bumper_right"].center[0] == pytest.approx(
        0.473 - by_name["bumper_left"].center[0]
    )
    assert table.flippers[1].pivot[0] == pytest.approx(0.473 - table.flippers[0].pivot[0])
    assert table.flippers[1].rest_angle == 180.0 - table.flippers[0].rest_angle


def test_flipper_speeds() -> None:
    flipper = load_table("classic").flippers[0]
    assert flipper.up_speed == pytest.approx(math.radians(50) / 0.022, rel=1e-15)
    assert flipper.down_speed == pytest.approx(math.radians(50) / 0.04, rel=1e-15)


def test_classic_packed_arrays() -> None:
    table = load_table("classic")
    packed = table.pack()
    n_segments = sum(len(w.segments()) for w in table.walls)
    n_elements = n_segments + 5 + 2 + 5  # segments, posts, flippers, sensors
    _check_arrays(
        packed,
        {
            "flippers": ((2, columns.FLIPPER_SIZE), np.float64),
            "flipper_props": ((2, columns.PROP_SIZE), np.float64),
            "sensors": ((5, 4), np.float64),
            "sensor_drain": ((5,), np.bool_),
        },
    )
    _check_arrays(table, {"element_scores": ((n_elements,), np.int64)})
    assert len(table.element_names) == n_elements


def test_packed_flippers() -> None:
    table = load_table("classic")
    packed = table.pack()
    up_speed = math.radians(50) / 0.022
    down_speed = math.radians(50) / 0.04
    expected = {
        columns.FLIPPER_PIVOT_X: (0.146, 0.327),
        columns.FLIPPER_PIVOT_Y: (0.12, 0.12),
        columns.FLIPPER_LENGTH: (0.07, 0.07),
        columns.FLIPPER_BASE_RADIUS: (0.0116, 0.0116),
        columns.FLIPPER_TIP_RADIUS: (0.007, 0.007),
        columns.FLIPPER_REST_ANGLE: (math.radians(-25), math.radians(205)),
        columns.FLIPPER_UP_ANGLE: (math.radians(25), math.radians(155)),
        columns.FLIPPER_UP_SPEED: (up_speed, up_speed),
        columns.FLIPPER_DOWN_SPEED: (down_speed, down_speed),
    }
    assert sorted(expected) == list(range(columns.FLIPPER_SIZE))
    for column, values in expected.items():
        np.testing.assert_allclose(packed.flippers[:, column], values, rtol=1e-15)
    assert table.flipper_buttons == (0, 1)
    np.testing.assert_array_equal(packed.flipper_props[:, columns.PROP_RESTITUTION], [0.8, 0.8])
    np.testing.assert_array_equal(packed.flipper_props[:, columns.PROP_FRICTION], [0.4, 0.4])
    np.testing.assert_array_equal(packed.flipper_props[:, columns.PROP_KICK], [0.0, 0.0])


def test_packed_sensors() -> None:
    packed = load_table("classic").pack()
    np.testing.assert_array_equal(packed.sensors[-1], [0.005, 0.03, 0.468, 0.03])
    assert packed.sensor_drain.tolist() == [False, False, False, False, True]


def test_element_ids_and_scores() -> None:
    table = load_table("classic")
    n_segments = sum(len(w.segments()) for w in table.walls)
    names = table.element_names
    # Segments, then circles, flippers and sensors, each in file order.
    assert names[0] == "outline[0]"
    assert names[n_segments - 1] == "right_slingshot[0]"
    assert names[n_segments:] == (
        "bumper_left",
        "bumper_right",
        "bumper_bottom",
        "left_guide_post",
        "right_guide_post",
        "left_flipper",
        "right_flipper",
        "left_outlane",
        "left_inlane",
        "right_inlane",
        "right_outlane",
        "drain",
    )
    scores = dict(zip(names, table.element_scores.tolist(), strict=True))
    assert {name: score for name, score in scores.items() if score} == {
        "left_slingshot[0]": 10,
        "right_slingshot[0]": 10,
        "bumper_left": 100,
        "bumper_right": 100,
        "bumper_bottom": 100,
        "left_outlane": 10,
        "left_inlane": 10,
        "right_inlane": 10,
        "right_outlane": 10,
    }


def test_scores_default_to_zero_and_every_segment_of_a_wall_scores() -> None:
    assert Wall(name="w", points=((0.0, 0.0), (1.0, 0.0)), material="m").score == 0
    assert Post(name="p", center=(0.0, 0.0), radius=0.1, material="m").score == 0
    data = box_dict()
    data["walls"][0]["score"] = 5
    assert table_from_dict(data).element_scores.tolist() == [5, 5, 5, 5, 0, 0, 0, 0, 0]


def test_flipper_buttons_follow_the_file() -> None:
    data = classic_dict()
    data["flippers"][0]["button"] = "right"
    assert table_from_dict(data).flipper_buttons == (1, 1)


def test_flipper_distance_matches_the_hull_of_its_circles() -> None:
    """The tapered capsule is the union of discs with centre and radius interpolated base -> tip."""
    flipper = load_table("classic").flippers[1]
    rng = np.random.default_rng(0)
    t = np.linspace(0.0, 1.0, 20001)
    angle = math.radians(flipper.rest_angle)
    cx = flipper.pivot[0] + t * flipper.length * math.cos(angle)
    cy = flipper.pivot[1] + t * flipper.length * math.sin(angle)
    radius = flipper.base_radius + t * (flipper.tip_radius - flipper.base_radius)
    for x, y in rng.uniform((0.20, 0.04), (0.40, 0.20), size=(200, 2)):
        brute = np.min(np.hypot(x - cx, y - cy) - radius)
        if brute > 0.0:  # outside; inside, the union's depth is not the capsule's signed distance
            assert flipper.distance((x, y), flipper.rest_angle) == pytest.approx(brute, abs=1e-7)


def test_plunger_is_optional() -> None:
    data = classic_dict()
    del data["plunger"]
    assert table_from_dict(data).plunger is None


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
    "gravity zero": (_set("gravity", value=0.0), "gravity", "out of range (must be (0, 100])"),
    "width negative": (_set("playfield", "width", value=-0.5), "playfield.width", "out of range"),
    "radius zero": (_set("ball", "radius", value=0), "ball.radius", "out of range"),
    "mass negative": (_set("ball", "mass", value=-0.08), "ball.mass", "out of range"),
    "restitution": (
        _set("materials", "wall", "restitution", value=1.6),
        "materials.wall.restitution",
        "out of range (must be [0, 1])",
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
    "skin zero": (
        _set("simulation", "skin", value=0.0),
        "simulation.skin",
        "(must be [1e-08, 0.0001])",
    ),
    "skin large": (_set("simulation", "skin", value=2e-4), "simulation.skin", "out of range"),
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


LEFT_FLIPPER = "flippers[0] 'left_flipper'"
DRAIN = "sensors[4] 'drain'"
BUMPER = "posts[0] 'bumper_left'"
GATE = "walls[2] 'gate'"

# The same, as mutations of classic.yaml's dict: flippers, sensors, plunger and scores.
BAD_CLASSIC_TABLES: dict[str, tuple[Mutation, str, str]] = {
    # run-time sanity: the ball inside the outline, no absurd speeds or step counts
    "ball start above the arch": (
        _set("ball", "start", value=[0.03, 1.05]),
        "ball.start",
        "outside the table's outline 'outline'",
    ),
    "plunger outside the outline": (
        _set("plunger", "position", value=[0.49, 1.05]),
        "plunger.position",
        "outside the table's outline",
    ),
    "ball too fast": (_set("ball", "velocity", value=[0.0, 150.0]), "ball.velocity", "above 100"),
    "frame rate too low": (
        _set("simulation", "frame_rate", value=0.5),
        "simulation.frame_rate",
        "out of range",
    ),
    "too many substeps": (
        _set("simulation", "substeps", value=5000),
        "simulation.substeps",
        "out of range",
    ),
    "too many passes": (
        _set("simulation", "max_passes", value=5000),
        "simulation.max_passes",
        "out of range",
    ),
    # unknown and missing keys
    "unknown flipper key": (
        _set("flippers", 0, "kick", value=1.0),
        LEFT_FLIPPER,
        "unknown key 'kick'",
    ),
    "unknown sensor key": (_set("sensors", 4, "material", value="wall"), DRAIN, "unknown key"),
    "unknown plunger key": (_set("plunger", "force", value=1.0), "plunger", "unknown key 'force'"),
    "missing flipper length": (
        _drop("flippers", 0, "length"),
        LEFT_FLIPPER,
        "missing required key 'length'",
    ),
    "missing flipper button": (_drop("flippers", 0, "button"), LEFT_FLIPPER, "key 'button'"),
    "missing sensor points": (_drop("sensors", 4, "points"), DRAIN, "missing required key"),
    "missing plunger speed": (_drop("plunger", "speed"), "plunger", "missing required key 'speed'"),
    "flipper not a mapping": (_set("flippers", 1, value="right"), "flippers[1]", "mapping"),
    "flippers not a list": (_set("flippers", value={}), "flippers", "expected a list"),
    "sensors not a list": (_set("sensors", value="drain"), "sensors", "expected a list"),
    "plunger not a mapping": (_set("plunger", value=[0.48, 0.04]), "plunger", "mapping"),
    # wrong types and non-finite numbers
    "flipper length nan": (
        _set("flippers", 0, "length", value=float("nan")),
        f"{LEFT_FLIPPER}.length",
        "finite",
    ),
    "rest angle string": (
        _set("flippers", 0, "rest_angle", value="-25deg"),
        f"{LEFT_FLIPPER}.rest_angle",
        "expected a number, got str",
    ),
    "button unknown": (
        _set("flippers", 0, "button", value="middle"),
        f"{LEFT_FLIPPER}.button",
        "expected one of 'left', 'right', got str 'middle'",
    ),
    "button not a string": (
        _set("flippers", 0, "button", value=0),
        f"{LEFT_FLIPPER}.button",
        "int",
    ),
    "drain not a bool": (_set("sensors", 4, "drain", value="yes"), f"{DRAIN}.drain", "true"),
    "speed not a pair": (_set("plunger", "speed", value=3.0), "plunger.speed", "expected a pair"),
    # scores
    "negative wall score": (
        _set("walls", 8, "score", value=-10),
        "walls[8] 'left_slingshot'.score",
        "out of range (must be [0, 1e+06])",
    ),
    "float post score": (
        _set("posts", 0, "score", value=100.5),
        f"{BUMPER}.score",
        "expected an integer",
    ),
    "string flipper score": (
        _set("flippers", 0, "score", value="10"),
        f"{LEFT_FLIPPER}.score",
        "expected an integer",
    ),
    "negative sensor score": (_set("sensors", 4, "score", value=-1), f"{DRAIN}.score", "range"),
    # out-of-range flipper fields
    "flipper length zero": (
        _set("flippers", 0, "length", value=0.0),
        f"{LEFT_FLIPPER}.length",
        "out of range (must be [0.01, 1])",
    ),
    "base radius negative": (
        _set("flippers", 0, "base_radius", value=-0.01),
        f"{LEFT_FLIPPER}.base_radius",
        "out of range",
    ),
    "tip radius zero": (
        _set("flippers", 0, "tip_radius", value=0),
        f"{LEFT_FLIPPER}.tip_radius",
        "out of range",
    ),
    "rest angle beyond a turn": (
        _set("flippers", 0, "rest_angle", value=400),
        f"{LEFT_FLIPPER}.rest_angle",
        "out of range (must be [-360, 360])",
    ),
    "stroke too short": (
        _set("flippers", 0, "stroke_time", value=0.001),
        f"{LEFT_FLIPPER}.stroke_time",
        "out of range (must be [0.005, 0.2])",
    ),
    "return too long": (
        _set("flippers", 0, "return_time", value=1.0),
        f"{LEFT_FLIPPER}.return_time",
        "out of range (must be [0.005, 0.5])",
    ),
    "no swing": (
        _set("flippers", 0, "up_angle", value=-25),
        f"{LEFT_FLIPPER}.up_angle",
        "flipper swing must be in (0, 90] degrees, got 0",
    ),
    "swing too wide": (
        _set("flippers", 1, "up_angle", value=110),
        "flippers[1] 'right_flipper'.up_angle",
        "flipper swing must be in (0, 90] degrees, got 95",
    ),
    "base swallows tip": (
        _set("flippers", 0, "base_radius", value=0.08),
        LEFT_FLIPPER,
        "|base_radius - tip_radius| = 0.073 must be < length 0.07",
    ),
    "tip swallows base": (
        _set("flippers", 0, "tip_radius", value=0.09),
        LEFT_FLIPPER,
        "must be < length",
    ),
    # geometry: points, pivots, overlaps
    "pivot outside": (
        _set("flippers", 0, "pivot", value=[0.146, -0.01]),
        f"{LEFT_FLIPPER}.pivot",
        "outside the playfield",
    ),
    "pivot in a wall": (
        _set("flippers", 0, "pivot", value=[0.146, 0.012]),
        f"{LEFT_FLIPPER}.pivot",
        "pivot (0.146, 0.012) overlaps wall 'outline' segment 0 (distance 0.007 < base radius",
    ),
    "pivot on a guide": (
        _set("flippers", 1, "pivot", value=[0.338, 0.15]),
        "flippers[1] 'right_flipper'.pivot",
        "overlaps wall 'right_outlane_guide' segment 1",
    ),
    "sensor with 3 points": (
        _set("sensors", 0, "points", value=[[0.005, 0.28], [0.02, 0.28], [0.04, 0.28]]),
        "sensors[0] 'left_outlane'.points",
        "expected exactly 2 items, got 3",
    ),
    "sensor with 1 point": (
        _set("sensors", 0, "points", value=[[0.005, 0.28]]),
        "sensors[0] 'left_outlane'.points",
        "expected exactly 2 items, got 1",
    ),
    "sensor of zero length": (
        _set("sensors", 4, "points", value=[[0.2, 0.03], [0.2, 0.03]]),
        DRAIN,
        "zero length",
    ),
    "sensor point outside": (
        _set("sensors", 4, "points", 1, value=[0.6, 0.03]),
        f"{DRAIN}.points[1]",
        "outside the playfield",
    ),
    "ball on a flipper": (
        _set("ball", "start", value=[0.18, 0.12]),
        "ball.start",
        "ball overlaps flipper 'left_flipper' at its rest angle",
    ),
    "plunger outside": (
        _set("plunger", "position", value=[0.52, 0.04]),
        "plunger.position",
        "outside the playfield",
    ),
    "plunger on a flipper": (
        _set("plunger", "position", value=[0.18, 0.12]),
        "plunger.position",
        "ball overlaps flipper 'left_flipper' at its rest angle (distance to its surface",
    ),
    "plunger on a wall": (
        _set("plunger", "position", value=[0.475, 0.04]),
        "plunger.position",
        "ball overlaps wall 'lane_wall' segment 0",
    ),
    "plunger on a post": (
        _set("plunger", "position", value=[0.2365, 0.6]),
        "plunger.position",
        "ball overlaps post 'bumper_bottom'",
    ),
    # plunger speeds
    "speed zero": (
        _set("plunger", "speed", value=[0.0, 3.2]),
        "plunger.speed[0]",
        "out of range (must be (0, 20])",
    ),
    "speed too high": (_set("plunger", "speed", value=[2.2, 25]), "plunger.speed[1]", "range"),
    "speed reversed": (
        _set("plunger", "speed", value=[3.2, 2.2]),
        "plunger.speed",
        "expected [min, max] with min <= max, got [3.2, 2.2]",
    ),
    # gate orientation
    "gate reversed": (
        _set("walls", 2, "points", value=[[0.505, 0.84], [0.468, 0.80]]),
        GATE,
        "one-sided segment 0 blocks the plunger's launch path "
        "(its normal faces the plunger; reverse its points)",
    ),
    # references and names across the new groups
    "unknown flipper material": (
        _set("flippers", 0, "material", value="steel"),
        f"{LEFT_FLIPPER}.material",
        "unknown material 'steel' (known: bumper, flipper, metal, rubber, wall)",
    ),
    "duplicate flipper and wall": (
        _set("flippers", 0, "name", value="gate"),
        "flippers[0] 'gate'",
        "duplicate element name 'gate' (also walls[2] 'gate')",
    ),
    "duplicate sensor and flipper": (
        _set("sensors", 4, "name", value="right_flipper"),
        "sensors[4] 'right_flipper'",
        "duplicate element name 'right_flipper' (also flippers[1]",
    ),
}

INVALID_CASES = [("box", case) for case in BAD_TABLES] + [
    ("classic", case) for case in BAD_CLASSIC_TABLES
]


def _write(tmp_path: Path, data: Any) -> Path:
    path = tmp_path / "bad.yaml"
    path.write_text(yaml.safe_dump(data, sort_keys=False), encoding="utf-8")
    return path


@pytest.mark.parametrize(
    ("base", "case"),
    INVALID_CASES,
    ids=[case if base == "box" else f"classic: {case}" for base, case in INVALID_CASES],
)
def test_invalid_table(tmp_path: Path, base: str, case: str) -> None:
    mutate, where, problem = (BAD_TABLES if base == "box" else BAD_CLASSIC_TABLES)[case]
    data = copy.deepcopy(box_dict() if base == "box" else classic_dict())
    mutate(data)
    path = _write(tmp_path, data)
    pattern = re.escape(f"bad.yaml: {where}") + ".*" + re.escape(problem)
    with pytest.raises(TableError, match=pattern):
        load_table(path)


def test_box_round_trips_through_the_writer(tmp_path: Path) -> None:
    """The writer used above yields a valid file when nothing is mutated."""
    assert load_table(_write(tmp_path, box_dict())).walls == load_table("box").walls


def test_classic_round_trips_through_the_writer(tmp_path: Path) -> None:
    written = load_table(_write(tmp_path, classic_dict()))
    assert dataclasses.replace(written, source="") == dataclasses.replace(
        load_table("classic"), source=""
    )


def test_gate_facing_the_launch_only_matters_across_the_path() -> None:
    """A reversed one-sided segment beside the launch path, or no plunger at all, is accepted."""
    data = classic_dict()
    data["walls"][2]["points"].reverse()
    del data["plunger"]
    table_from_dict(data)  # no plunger: no launch path to check
    data = classic_dict()
    data["walls"].append(
        {"name": "trap", "points": [[0.3, 0.5], [0.2, 0.5]], "material": "metal", "one_sided": True}
    )
    table_from_dict(data)  # blocks balls coming up the table, but not the plunger's path


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
    with pytest.raises(
        TableError,
        match=r"unknown table 'no_such_table' \(available: classic, classic_v1, classic_v2, "
        r"classic_v3; test rigs: box\)",
    ):
        load_table("no_such_table")


def test_missing_file(tmp_path: Path) -> None:
    path = tmp_path / "missing.yaml"
    with pytest.raises(TableError, match=r"missing\.yaml: table file not found"):
        load_table(path)


def test_free_space_reaches_every_lane_but_not_inside_a_slingshot() -> None:
    from pinball_env.table.reachable import cell_of

    table = load_table("classic")
    grid = table.free_space

    def reachable(x: float, y: float) -> bool:
        return bool(grid[cell_of((x, y), grid.shape)])

    for lane in [(0.02, 0.3), (0.06, 0.3), (0.413, 0.3), (0.45, 0.3), (0.4865, 0.5)]:
        assert reachable(*lane), lane  # outlanes, inlanes, the shooter lane
    assert reachable(0.2365, 0.06)  # below the flippers, above the drain
    assert not reachable(0.0964, 0.2585)  # inside the left slingshot's triangle
    assert not reachable(0.3766, 0.2585)  # and the right one


# --- YAML out, and the built-in tables -----------------------------------------------------------


@pytest.mark.parametrize("name", ["classic", "box"])
def test_a_dumped_table_loads_back_as_the_same_table(name: str, tmp_path: Path) -> None:
    table = load_table(name)
    path = dump_table(table, tmp_path / f"{name}.yaml")
    again = load_table(path)
    assert dataclasses.replace(again, source=table.source) == table
    assert table_from_dict(table_to_dict(table), table.source) == table


def test_built_in_tables_live_in_the_package() -> None:
    folder = builtin_tables_dir()
    assert folder.parent.name == "table" and folder.parent.parent.name == "pinball_env"
    assert sorted(p.name for p in folder.glob("*.yaml")) == [
        "box.yaml", "classic.yaml", "classic_v1.yaml", "classic_v2.yaml", "classic_v3.yaml"
    ]  # fmt: skip
    with pytest.raises(
        TableError,
        match=r"unknown table 'nope' \(available: classic, classic_v1, classic_v2, classic_v3; "
        r"test rigs: box\)",
    ):
        load_table("nope")


@pytest.mark.parametrize(
    "value", [3, np.int64(3), 2.5, np.float32(0.5), True, np.bool_(False), "3", None, 10**400]
)
def test_a_table_field_and_an_option_take_the_same_kinds_of_value(value: object) -> None:
    """One vocabulary: a table's number fields and the options' checks (pinball_env.checks)
    accept the same integers, reals and flags, each failing with its own error format."""
    from pinball_env import checks

    def accepted(parse: Callable[[], object]) -> bool:
        try:
            parse()
        except ValueError:  # TableError is one
            return False
        return True

    substeps, mass, closed = box_dict(), box_dict(), box_dict()
    substeps["simulation"]["substeps"] = value  # an integer in [1, 100]
    mass["ball"]["mass"] = value  # a number in [0.001, 10]
    closed["walls"][0]["closed"] = value
    assert accepted(lambda: table_from_dict(substeps)) == accepted(
        lambda: checks.integer("substeps", value, 1, 100)
    )
    assert accepted(lambda: table_from_dict(mass)) == accepted(lambda: checks.finite("m", value))
    assert accepted(lambda: table_from_dict(closed)) == accepted(lambda: checks.flag("c", value))


def test_a_fork_while_a_thread_computes_a_table_property_does_not_hang(monkeypatch):
    # Python 3.11's functools.cached_property held one lock per property, shared by every table,
    # while computing it: a process forked then (an AsyncVectorEnv's worker, while a generated
    # table was checked in the background) waited on it for ever.
    import multiprocessing
    import threading

    from pinball_env.table import model

    table = load_table("classic")
    other = dataclasses.replace(table)  # another table, nothing computed yet
    computing, finish = threading.Event(), threading.Event()
    free_space = model.free_space

    def slow_free_space(*args: Any) -> Any:
        computing.set()
        finish.wait(60)
        return free_space(*args)

    def child() -> None:  # the forked process computes its own table's free space
        model.free_space = free_space
        raise SystemExit(0 if other.drain_reachable else 1)

    monkeypatch.setattr(model, "free_space", slow_free_space)
    thread = threading.Thread(target=lambda: table.free_space)
    thread.start()
    try:
        assert computing.wait(30)
        process = multiprocessing.get_context("fork").Process(target=child)
        process.start()
        process.join(60)
        hung = process.exitcode is None
        if hung:
            process.kill()
        assert not hung and process.exitcode == 0
    finally:
        finish.set()
        thread.join()
