"""Pinball tables: load a YAML description, validate it strictly, pack it for the kernels.

A table file describes the playfield in SI units (metres, seconds; only the slope and the flipper
angles are in degrees) in the table frame: origin at the bottom-left corner, x to the right, y up
the table. See ``configs/tables/box.yaml`` (a plain box) and ``configs/tables/classic.yaml`` (a
full table with flippers, sensors and a plunger) for annotated examples. Every mistake in a file
(unknown or missing key, wrong type, non-finite or out-of-range number, bad geometry) raises
:class:`TableError` with the file name, the path of the element and the problem; nothing is
silently defaulted.
"""

from __future__ import annotations

import itertools
import math
import numbers
import os
from collections.abc import Callable, Iterable, Mapping
from dataclasses import MISSING, dataclass, fields
from functools import cached_property, partial
from pathlib import Path
from typing import Any, NoReturn

import numpy as np
import yaml

from pinball_env.physics import layout
from pinball_env.physics.flipper import flipper_distance
from pinball_env.reachable import cell_of, free_space

TABLES_DIR = Path(__file__).resolve().parent.parent / "configs" / "tables"
# Fastest ball a table or a reset may set [m/s]: a real one rarely passes 10 m/s, and the flipper
# contact's work grows with the speed.
MAX_BALL_SPEED = 100.0
_SUFFIXES = (".yaml", ".yml")


class TableError(ValueError):
    """A table description is invalid or cannot be read."""


# --------------------------------------------------------------------------------------------
# Table model
# --------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class Material:
    """Surface properties shared by walls, posts and flippers."""

    name: str
    restitution: float  # coefficient of restitution of the normal velocity [-]
    friction: float  # Coulomb friction coefficient ball/surface [-]


@dataclass(frozen=True)
class Wall:
    """A polyline of straight segments."""

    name: str
    points: tuple[tuple[float, float], ...]
    material: str
    closed: bool = False  # adds the segment last point -> first point
    one_sided: bool = False  # only stops a ball coming from the left of P0 -> P1
    kick: float = 0.0  # speed added along the normal on every impact [m/s] (slingshots)
    score: int = 0  # points per hit [-]

    def segments(self) -> tuple[tuple[float, float, float, float], ...]:
        """Segments (x0, y0, x1, y1) in order, the closing one last."""
        ends = self.points + self.points[:1] if self.closed else self.points
        return tuple((*p, *q) for p, q in itertools.pairwise(ends))


@dataclass(frozen=True)
class Post:
    """A fixed circle: post or pop bumper."""

    name: str
    center: tuple[float, float]
    radius: float
    material: str
    kick: float = 0.0  # speed added along the normal on every impact [m/s] (pop bumpers)
    score: int = 0  # points per hit [-]


# Flipper buttons, in the order of their action bits.
_BUTTONS = ("left", "right")


@dataclass(frozen=True)
class Flipper:
    """A flipper: a tapered capsule turning about its pivot between two stops.

    The base circle (``base_radius``) is centred on the pivot, the tip circle (``tip_radius``)
    ``length`` away along the flipper's angle; their common tangents join them. Angles are kept in
    degrees as written in the file, counter-clockwise from +x.
    """

    name: str
    pivot: tuple[float, float]  # centre of rotation and of the base circle [m]
    length: float  # pivot to tip-circle centre [m]
    base_radius: float  # radius of the circle around the pivot [m]
    tip_radius: float  # radius of the circle at the tip [m]
    rest_angle: float  # direction pivot -> tip when released [deg]
    up_angle: float  # direction pivot -> tip when energised [deg]
    stroke_time: float  # time to swing from rest to up [s]
    return_time: float  # time to swing from up back to rest [s]
    material: str  # name of a material [-]
    button: str  # action bit that energises it: "left" or "right" [-]
    score: int = 0  # points per hit [-]

    @property
    def swing(self) -> float:
        """Angle swept between the two stops [rad]."""
        return math.radians(abs(self.up_angle - self.rest_angle))

    @property
    def up_speed(self) -> float:
        """Angular speed of the upstroke [rad/s]."""
        return self.swing / self.stroke_time

    @property
    def down_speed(self) -> float:
        """Angular speed of the return [rad/s]."""
        return self.swing / self.return_time


@dataclass(frozen=True)
class Sensor:
    """A line the ball rolls over (rollover, drain); a crossing of the ball's centre is an event."""

    name: str
    points: tuple[tuple[float, float], tuple[float, float]]  # the two ends [m]
    drain: bool = False  # a crossing takes the ball out of play [-]
    score: int = 0  # points per crossing [-]

    @property
    def segment(self) -> tuple[float, float, float, float]:
        """The line as (x0, y0, x1, y1) [m]."""
        return (*self.points[0], *self.points[1])


@dataclass(frozen=True)
class Plunger:
    """How a ball is put into play from the shooter lane."""

    position: tuple[float, float]  # ball centre at rest on the plunger [m]
    speed: tuple[float, float]  # launch speed range (min, max), straight up the table [m/s]


@dataclass(frozen=True)
class Ball:
    """The ball and its initial state."""

    radius: float
    mass: float
    start: tuple[float, float]
    velocity: tuple[float, float] = (0.0, 0.0)


@dataclass(frozen=True)
class Simulation:
    """Time stepping and contact resolution settings."""

    frame_rate: float = 60.0  # control frames per second
    substeps: int = 10  # physics substeps per frame
    max_passes: int = 16  # contact passes per substep
    skin: float = 1e-6  # distance the ball is left off a surface after a contact [m]
    resting_speed: float = 0.02  # below this normal approach speed a contact is inelastic [m/s]


@dataclass(frozen=True, eq=False)
class PackedTable:
    """The table as read-only, C-contiguous arrays in the layout the kernels expect."""

    segments: np.ndarray  # (S, 4) float64: x0, y0, x1, y1
    segment_props: np.ndarray  # (S, layout.PROP_SIZE) float64
    segment_one_sided: np.ndarray  # (S,) bool
    circles: np.ndarray  # (C, 3) float64: x, y, radius
    circle_props: np.ndarray  # (C, layout.PROP_SIZE) float64
    # global element id -> name: segments ("wall[i]"), then circles, flippers and sensors
    element_names: tuple[str, ...]
    gravity: np.ndarray  # (2,) float64 [m/s^2], in the playfield plane
    flippers: np.ndarray  # (F, layout.FLIPPER_SIZE) float64, columns layout.FLIPPER_*
    flipper_props: np.ndarray  # (F, layout.PROP_SIZE) float64 (kick 0)
    flipper_buttons: tuple[int, ...]  # (F,) action bit per flipper: 0 "left", 1 "right"
    sensors: np.ndarray  # (K, 4) float64: x0, y0, x1, y1
    sensor_drain: np.ndarray  # (K,) bool
    element_scores: np.ndarray  # (S + C + F + K,) int64 points per hit, by global element id


@dataclass(frozen=True)
class Table:
    """A validated table description."""

    name: str
    width: float
    height: float
    ball: Ball
    materials: tuple[Material, ...]
    walls: tuple[Wall, ...] = ()
    posts: tuple[Post, ...] = ()
    flippers: tuple[Flipper, ...] = ()
    sensors: tuple[Sensor, ...] = ()
    plunger: Plunger | None = None  # None: the ball is only ever placed at ball.start
    slope_deg: float = 6.5  # inclination of the playfield [deg]
    gravity: float = 9.81  # [m/s^2]
    simulation: Simulation = Simulation()  # frozen, so sharing it is safe
    source: str = "<dict>"  # file the table was read from

    @cached_property
    def free_space(self) -> np.ndarray:
        """Grid of where a ball centre can get to from the plunger (or the ball's start), see
        :mod:`pinball_env.reachable`; computed on first use."""
        packed = self.pack()
        start = self.plunger.position if self.plunger is not None else self.ball.start
        two_sided = packed.segments[~packed.segment_one_sided]
        return free_space(
            self.width, self.height, self.ball.radius, two_sided, packed.circles,
            packed.flippers, start,
        )  # fmt: skip

    @property
    def gravity_vector(self) -> tuple[float, float]:
        """Component of gravity in the playfield plane, pointing down the table [m/s^2]."""
        return (0.0, -self.gravity * math.sin(math.radians(self.slope_deg)))

    def material(self, name: str) -> Material:
        """The material called ``name``."""
        for material in self.materials:
            if material.name == name:
                return material
        raise KeyError(f"{self.source}: no material {name!r} in table {self.name!r}")

    def pack(self) -> PackedTable:
        """Arrays for the kernels (see :class:`PackedTable`)."""

        def props(material: str, kick: float) -> list[float]:
            row = [0.0] * layout.PROP_SIZE
            row[layout.PROP_RESTITUTION] = self.material(material).restitution
            row[layout.PROP_FRICTION] = self.material(material).friction
            row[layout.PROP_KICK] = kick
            return row

        segments, segment_props, one_sided, names, scores = [], [], [], [], []
        for wall in self.walls:
            for i, segment in enumerate(wall.segments()):
                segments.append(segment)
                segment_props.append(props(wall.material, wall.kick))
                one_sided.append(wall.one_sided)
                names.append(f"{wall.name}[{i}]")
                scores.append(wall.score)
        circles = [(*post.center, post.radius) for post in self.posts]
        circle_props = [props(post.material, post.kick) for post in self.posts]
        flippers = []
        for flipper in self.flippers:
            row = [0.0] * layout.FLIPPER_SIZE
            row[layout.FLIPPER_PIVOT_X], row[layout.FLIPPER_PIVOT_Y] = flipper.pivot
            row[layout.FLIPPER_LENGTH] = flipper.length
            row[layout.FLIPPER_BASE_RADIUS] = flipper.base_radius
            row[layout.FLIPPER_TIP_RADIUS] = flipper.tip_radius
            row[layout.FLIPPER_REST_ANGLE] = math.radians(flipper.rest_angle)
            row[layout.FLIPPER_UP_ANGLE] = math.radians(flipper.up_angle)
            row[layout.FLIPPER_UP_SPEED] = flipper.up_speed
            row[layout.FLIPPER_DOWN_SPEED] = flipper.down_speed
            flippers.append(row)
        flipper_props = [props(flipper.material, 0.0) for flipper in self.flippers]
        for elements in (self.posts, self.flippers, self.sensors):
            names.extend(element.name for element in elements)
            scores.extend(element.score for element in elements)
        return PackedTable(
            segments=_frozen_array(segments, np.float64, (-1, 4)),
            segment_props=_frozen_array(segment_props, np.float64, (-1, layout.PROP_SIZE)),
            segment_one_sided=_frozen_array(one_sided, np.bool_, (-1,)),
            circles=_frozen_array(circles, np.float64, (-1, 3)),
            circle_props=_frozen_array(circle_props, np.float64, (-1, layout.PROP_SIZE)),
            element_names=tuple(names),
            gravity=_frozen_array(self.gravity_vector, np.float64, (2,)),
            flippers=_frozen_array(flippers, np.float64, (-1, layout.FLIPPER_SIZE)),
            flipper_props=_frozen_array(flipper_props, np.float64, (-1, layout.PROP_SIZE)),
            flipper_buttons=tuple(_BUTTONS.index(flipper.button) for flipper in self.flippers),
            sensors=_frozen_array([s.segment for s in self.sensors], np.float64, (-1, 4)),
            sensor_drain=_frozen_array([s.drain for s in self.sensors], np.bool_, (-1,)),
            element_scores=_frozen_array(scores, np.int64, (-1,)),
        )


def _frozen_array(rows: Any, dtype: type, shape: tuple[int, ...]) -> np.ndarray:
    array = np.ascontiguousarray(np.asarray(rows, dtype=dtype).reshape(shape))
    array.flags.writeable = False
    return array


# --------------------------------------------------------------------------------------------
# Validation helpers, shared by every field
# --------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class _Loc:
    """Where a value sits: the source file and the element path, for error messages."""

    source: str
    path: str = ""

    def key(self, key: str) -> _Loc:
        return _Loc(self.source, f"{self.path}.{key}" if self.path else key)

    def index(self, i: int, name: object = None) -> _Loc:
        label = f"{self.path}[{i}]" + (f" {name!r}" if isinstance(name, str) else "")
        return _Loc(self.source, label)

    def fail(self, problem: str) -> NoReturn:
        raise TableError(f"{self.source}: {self.path or 'top level'}: {problem}")


Parser = Callable[[Any, _Loc], Any]


def _describe(value: object) -> str:
    return f"{type(value).__name__} {value!r}"


def _mapping(
    value: object, loc: _Loc, required: Iterable[str], optional: Iterable[str] = ()
) -> Mapping[str, Any]:
    """Check ``value`` is a mapping with all ``required`` keys and no unknown key."""
    if not isinstance(value, Mapping):
        loc.fail(f"expected a mapping, got {_describe(value)}")
    required = list(required)
    allowed = sorted({*required, *optional})
    for key in value:
        if key not in allowed:
            loc.fail(f"unknown key {key!r} (allowed: {', '.join(allowed)})")
    for key in required:
        if key not in value:
            loc.fail(f"missing required key {key!r}")
    return value


def _list(value: object, loc: _Loc, min_len: int = 0, max_len: int | None = None) -> list[Any]:
    if not isinstance(value, (list, tuple)):
        loc.fail(f"expected a list, got {_describe(value)}")
    if min_len == max_len and len(value) != min_len:
        loc.fail(f"expected exactly {min_len} items, got {len(value)}")
    if len(value) < min_len:
        loc.fail(f"expected at least {min_len} items, got {len(value)}")
    if max_len is not None and len(value) > max_len:
        loc.fail(f"expected at most {max_len} items, got {len(value)}")
    return list(value)


def _string(value: object, loc: _Loc) -> str:
    if not isinstance(value, str) or not value:
        loc.fail(f"expected a non-empty string, got {_describe(value)}")
    return value


def _choice(value: object, loc: _Loc, options: tuple[str, ...]) -> str:
    if value not in options:
        loc.fail(f"expected one of {', '.join(map(repr, options))}, got {_describe(value)}")
    return str(value)


def _flag(value: object, loc: _Loc) -> bool:
    if not isinstance(value, (bool, np.bool_)):
        loc.fail(f"expected true or false, got {_describe(value)}")
    return bool(value)


def _number(
    value: object,
    loc: _Loc,
    low: float | None = None,
    high: float | None = None,
    *,
    open_low: bool = False,
    open_high: bool = False,
    integer: bool = False,
) -> float | int:
    """A finite real (or, with ``integer``, an int) in the given interval."""
    kind = numbers.Integral if integer else numbers.Real
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, kind):
        hint = ""
        if isinstance(value, str) and _parses_as_float(value):
            hint = " (YAML reads exponents without a dot as text: write 1.0e-6, not 1e-6)"
        loc.fail(
            f"expected {'an integer' if integer else 'a number'}, got {_describe(value)}{hint}"
        )
    if not math.isfinite(value):
        loc.fail(f"expected a finite number, got {value!r}")
    too_low = low is not None and (value <= low if open_low else value < low)
    too_high = high is not None and (value >= high if open_high else value > high)
    if too_low or too_high:
        if high is None:
            interval = f"{'>' if open_low else '>='} {low:g}"
        else:
            interval = f"{'(' if open_low else '['}{low:g}, {high:g}{')' if open_high else ']'}"
        loc.fail(f"{value!r} is out of range (must be {interval})")
    return int(value) if integer else float(value)


def _parses_as_float(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


def _pair(value: object, loc: _Loc, item: Parser = _number) -> tuple[Any, Any]:
    """An [x, y] pair of finite numbers (or of whatever ``item`` parses); a list, a tuple or a
    1-d numpy array (such as ``info["ball_position"]``)."""
    pair_like = isinstance(value, (list, tuple)) or (
        isinstance(value, np.ndarray) and value.ndim == 1
    )
    if not pair_like or len(value) != 2:
        loc.fail(f"expected a pair [x, y], got {_describe(value)}")
    return (item(value[0], loc.index(0)), item(value[1], loc.index(1)))


def _velocity(value: object, loc: _Loc) -> tuple[float, float]:
    """A finite [vx, vy] pair no faster than MAX_BALL_SPEED."""
    vx, vy = _pair(value, loc)
    if math.hypot(vx, vy) > MAX_BALL_SPEED:
        loc.fail(
            f"speed {math.hypot(vx, vy):g} m/s is above {MAX_BALL_SPEED:g} m/s "
            "(no pinball moves that fast)"
        )
    return (vx, vy)


def _point(value: object, loc: _Loc, width: float, height: float) -> tuple[float, float]:
    """An [x, y] pair inside the playfield (bounds included)."""
    x, y = _pair(value, loc)
    if not (0.0 <= x <= width and 0.0 <= y <= height):
        loc.fail(f"point ({x:g}, {y:g}) is outside the playfield [0, {width:g}] x [0, {height:g}]")
    return (x, y)


def _points(
    value: object, loc: _Loc, point: Parser, min_len: int, max_len: int | None = None
) -> tuple[tuple[float, float], ...]:
    """A list of points inside the playfield (``point`` is :func:`_point` bound to its size)."""
    items = _list(value, loc, min_len, max_len)
    return tuple(point(p, loc.index(i)) for i, p in enumerate(items))


def _check_lengths(segments: Iterable[tuple[float, ...]], loc: _Loc) -> None:
    for i, (x0, y0, x1, y1) in enumerate(segments):
        if x0 == x1 and y0 == y1:
            loc.fail(f"segment {i} has zero length (both ends at ({x0:g}, {y0:g}))")


def _record(
    cls: type, value: object, loc: _Loc, parsers: Mapping[str, Parser], **extra: Any
) -> Any:
    """Build dataclass ``cls`` from a mapping: one parser per key, defaults from ``cls``."""
    required = [f.name for f in fields(cls) if f.name in parsers and f.default is MISSING]
    raw = _mapping(value, loc, required, parsers)
    return cls(**{key: parsers[key](raw[key], loc.key(key)) for key in raw}, **extra)


_positive = partial(_number, low=0.0, open_low=True)
_non_negative = partial(_number, low=0.0)
_score = partial(_number, low=0, integer=True)


# --------------------------------------------------------------------------------------------
# Building a table
# --------------------------------------------------------------------------------------------


def table_from_dict(data: Mapping[str, Any], source: str = "<dict>") -> Table:
    """Validate a table description (as read from YAML) into a :class:`Table`."""
    top = _Loc(source)
    raw = _mapping(data, top, ["name", "playfield", "ball", "materials"], _TOP_KEYS)

    playfield = _mapping(raw["playfield"], top.key("playfield"), ["width", "height"])
    width = _positive(playfield["width"], top.key("playfield").key("width"))
    height = _positive(playfield["height"], top.key("playfield").key("height"))
    point = partial(_point, width=width, height=height)

    materials = _materials(raw["materials"], top.key("materials"))
    walls = _group(raw, top, "walls", partial(_wall, point=point))
    post_parsers = {
        "name": _string,
        "center": point,
        "radius": _positive,
        "material": _string,
        "kick": _non_negative,
        "score": _score,
    }
    posts = _group(raw, top, "posts", partial(_record, Post, parsers=post_parsers))
    flippers = _group(raw, top, "flippers", partial(_flipper, point=point))
    sensors = _group(raw, top, "sensors", partial(_sensor, point=point))
    elements = {"walls": walls, "posts": posts, "flippers": flippers, "sensors": sensors}
    _check_elements(elements, materials, top)
    _check_pivots(flippers, walls, top)

    ball_loc = top.key("ball")
    ball_parsers = {"radius": _positive, "mass": _positive, "start": point, "velocity": _velocity}
    ball = _record(Ball, raw["ball"], ball_loc, ball_parsers)
    _check_clear(ball.start, ball.radius, walls, posts, flippers, ball_loc.key("start"))
    _check_enclosed(ball.start, walls, ball_loc.key("start"))

    options: dict[str, Any] = {}
    if "plunger" in raw:
        options["plunger"] = plunger = _plunger(raw["plunger"], top.key("plunger"), point)
        position_loc = top.key("plunger").key("position")
        _check_clear(plunger.position, ball.radius, walls, posts, flippers, position_loc)
        _check_enclosed(plunger.position, walls, position_loc)
        _check_launch_path(plunger, walls, top)
    if "slope_deg" in raw:
        options["slope_deg"] = _number(
            raw["slope_deg"], top.key("slope_deg"), 0.0, 90.0, open_high=True
        )
    if "gravity" in raw:
        options["gravity"] = _positive(raw["gravity"], top.key("gravity"))
    if "simulation" in raw:
        simulation_parsers = {
            "frame_rate": partial(_number, low=1.0, high=1000.0),
            "substeps": partial(_number, low=1, high=1000, integer=True),
            "max_passes": partial(_number, low=1, high=1000, integer=True),
            "skin": partial(_number, low=0.0, high=1e-4, open_low=True),
            "resting_speed": _non_negative,
        }
        options["simulation"] = _record(
            Simulation, raw["simulation"], top.key("simulation"), simulation_parsers
        )
    return Table(
        name=_string(raw["name"], top.key("name")),
        width=width,
        height=height,
        ball=ball,
        materials=materials,
        walls=walls,
        posts=posts,
        flippers=flippers,
        sensors=sensors,
        source=source,
        **options,
    )


# Keys of the top-level mapping; ``playfield`` holds Table.width and Table.height.
_TOP_KEYS = (
    "name",
    "playfield",
    "slope_deg",
    "gravity",
    "ball",
    "materials",
    "walls",
    "posts",
    "flippers",
    "sensors",
    "plunger",
    "simulation",
)


def _name_of(item: object) -> object:
    return item.get("name") if isinstance(item, Mapping) else None


def _group(raw: Mapping[str, Any], top: _Loc, key: str, parse: Parser) -> tuple[Any, ...]:
    """The optional list ``raw[key]`` of elements, each parsed at its path ``key[i] 'name'``."""
    items = _list(raw.get(key, []), top.key(key))
    return tuple(parse(item, top.key(key).index(i, _name_of(item))) for i, item in enumerate(items))


def _materials(value: object, loc: _Loc) -> tuple[Material, ...]:
    if not isinstance(value, Mapping) or not value:
        loc.fail(f"expected a mapping of at least one material, got {_describe(value)}")
    parsers = {
        "restitution": partial(_number, low=0.0, high=1.5),
        "friction": partial(_number, low=0.0, high=2.0),
    }
    return tuple(
        _record(Material, item, loc.key(_string(name, loc)), parsers, name=name)
        for name, item in value.items()
    )


def _wall(value: object, loc: _Loc, point: Parser) -> Wall:
    wall = _record(
        Wall,
        value,
        loc,
        {
            "name": _string,
            "points": partial(_points, point=point, min_len=2),
            "closed": _flag,
            "material": _string,
            "one_sided": _flag,
            "kick": _non_negative,
            "score": _score,
        },
    )
    if wall.closed and len(wall.points) < 3:
        loc.fail(f"a closed polyline needs at least 3 points, got {len(wall.points)}")
    _check_lengths(wall.segments(), loc)
    return wall


def _flipper(value: object, loc: _Loc, point: Parser) -> Flipper:
    angle = partial(_number, low=-360.0, high=360.0)
    flipper = _record(
        Flipper,
        value,
        loc,
        {
            "name": _string,
            "pivot": point,
            "length": _positive,
            "base_radius": _positive,
            "tip_radius": _positive,
            "rest_angle": angle,
            "up_angle": angle,
            "stroke_time": partial(_number, low=0.005, high=0.2),
            "return_time": partial(_number, low=0.005, high=0.5),
            "material": _string,
            "button": partial(_choice, options=_BUTTONS),
            "score": _score,
        },
    )
    swing = abs(flipper.up_angle - flipper.rest_angle)
    if not 0.0 < swing <= 90.0:
        loc.key("up_angle").fail(
            f"flipper swing must be in (0, 90] degrees, got {swing:g} (|up_angle - rest_angle|)"
        )
    taper = abs(flipper.base_radius - flipper.tip_radius)
    if taper >= flipper.length:
        loc.fail(
            f"|base_radius - tip_radius| = {taper:g} must be < length {flipper.length:g} "
            "(else one end circle swallows the other)"
        )
    return flipper


def _sensor(value: object, loc: _Loc, point: Parser) -> Sensor:
    sensor = _record(
        Sensor,
        value,
        loc,
        {
            "name": _string,
            "points": partial(_points, point=point, min_len=2, max_len=2),
            "drain": _flag,
            "score": _score,
        },
    )
    _check_lengths([sensor.segment], loc)
    return sensor


def _plunger(value: object, loc: _Loc, point: Parser) -> Plunger:
    speed = partial(_pair, item=partial(_number, low=0.0, high=20.0, open_low=True))
    plunger = _record(Plunger, value, loc, {"position": point, "speed": speed})
    low, high = plunger.speed
    if low > high:
        loc.key("speed").fail(f"expected [min, max] with min <= max, got [{low:g}, {high:g}]")
    return plunger


def _check_elements(
    groups: Mapping[str, tuple[Any, ...]], materials: tuple[Material, ...], top: _Loc
) -> None:
    """Element names are unique across all groups and every material reference resolves."""
    known = [m.name for m in materials]
    seen: dict[str, str] = {}
    for group, elements in groups.items():
        for i, element in enumerate(elements):
            loc = top.key(group).index(i, element.name)
            if element.name in seen:
                loc.fail(f"duplicate element name {element.name!r} (also {seen[element.name]})")
            seen[element.name] = loc.path
            material = getattr(element, "material", None)  # sensors have none
            if material is not None and material not in known:
                loc.key("material").fail(
                    f"unknown material {material!r} (known: {', '.join(sorted(known))})"
                )


def _wall_segments(
    walls: tuple[Wall, ...],
) -> Iterable[tuple[Wall, int, tuple[float, float, float, float]]]:
    """(wall, index of the segment in the wall, segment) for every segment of every wall."""
    for wall in walls:
        for i, segment in enumerate(wall.segments()):
            yield wall, i, segment


def _check_pivots(flippers: tuple[Flipper, ...], walls: tuple[Wall, ...], top: _Loc) -> None:
    """No flipper's base circle (around its pivot) overlaps a wall."""
    for i, flipper in enumerate(flippers):
        for wall, j, segment in _wall_segments(walls):
            distance = _segment_distance(flipper.pivot, segment)
            if distance < flipper.base_radius:
                x, y = flipper.pivot
                top.key("flippers").index(i, flipper.name).key("pivot").fail(
                    f"pivot ({x:g}, {y:g}) overlaps wall {wall.name!r} segment {j} "
                    f"(distance {distance:g} < base radius {flipper.base_radius:g})"
                )


def _check_clear(
    center: tuple[float, float],
    radius: float,
    walls: tuple[Wall, ...],
    posts: tuple[Post, ...],
    flippers: tuple[Flipper, ...],
    loc: _Loc,
) -> None:
    """A ball of ``radius`` at ``center`` touches no wall, no post and no flipper at rest."""
    for wall, i, segment in _wall_segments(walls):
        distance = _segment_distance(center, segment)
        if distance < radius:
            loc.fail(
                f"ball overlaps wall {wall.name!r} segment {i} "
                f"(distance {distance:g} < ball radius {radius:g})"
            )
    for post in posts:
        gap = math.dist(center, post.center) - post.radius
        if gap < radius:
            loc.fail(
                f"ball overlaps post {post.name!r} "
                f"(distance to its surface {gap:g} < ball radius {radius:g})"
            )
    for flipper in flippers:
        gap = _flipper_distance(center, flipper, flipper.rest_angle)
        if gap < radius:
            loc.fail(
                f"ball overlaps flipper {flipper.name!r} at its rest angle "
                f"(distance to its surface {gap:g} < ball radius {radius:g})"
            )


def enclosure(walls: tuple[Wall, ...]) -> Wall | None:
    """The closed wall enclosing the largest area (the table's outline), or None."""
    closed = [wall for wall in walls if wall.closed]
    return max(closed, key=lambda wall: abs(_polygon_area(wall.points)), default=None)


def _polygon_area(points: tuple[tuple[float, float], ...]) -> float:
    """Signed area of a closed polygon (shoelace formula)."""
    return 0.5 * sum(
        x0 * y1 - x1 * y0
        for (x0, y0), (x1, y1) in zip(points, points[1:] + points[:1], strict=True)
    )


def _inside(point: tuple[float, float], polygon: tuple[tuple[float, float], ...]) -> bool:
    """Even-odd test: is ``point`` inside the closed ``polygon``?"""
    x, y = point
    inside = False
    for (x0, y0), (x1, y1) in zip(polygon, polygon[1:] + polygon[:1], strict=True):
        if (y0 > y) != (y1 > y) and x < x0 + (y - y0) * (x1 - x0) / (y1 - y0):
            inside = not inside
    return inside


def _check_enclosed(point: tuple[float, float], walls: tuple[Wall, ...], loc: _Loc) -> None:
    """A ball centre lies inside the table's outline (when it has one)."""
    outline = enclosure(walls)
    if outline is not None and not _inside(point, outline.points):
        loc.fail(f"({point[0]:g}, {point[1]:g}) is outside the table's outline {outline.name!r}")


def check_ball_state(
    table: Table, position: object, velocity: object, source: str
) -> tuple[tuple[float, float], tuple[float, float]]:
    """Validate a ball state given at run time (e.g. reset options): ``position`` a finite [x, y]
    in the playfield and its outline, clear of every wall, post and resting flipper, and where a
    ball from the plunger can get to; ``velocity`` a finite pair no faster than MAX_BALL_SPEED.
    Errors name ``source``, e.g. ``reset options: ball_position: ...``."""
    where = _Loc(source)
    point = _point(position, where.key("ball_position"), table.width, table.height)
    _check_clear(
        point, table.ball.radius, table.walls, table.posts, table.flippers,
        where.key("ball_position"),
    )  # fmt: skip
    _check_enclosed(point, table.walls, where.key("ball_position"))
    if not table.free_space[cell_of(point, table.free_space.shape)]:
        where.key("ball_position").fail(
            f"({point[0]:g}, {point[1]:g}) cannot be reached from the plunger: it is walled off "
            "(inside a slingshot, say)"
        )
    return point, _velocity(velocity, where.key("ball_velocity"))


def _check_launch_path(plunger: Plunger, walls: tuple[Wall, ...], top: _Loc) -> None:
    """One-sided segments across the launch path (straight up from the plunger) let it through.

    A one-sided segment stops a ball coming from the side of its normal rot+90(P1 - P0) =
    (y0 - y1, x1 - x0). A ball launched along +y meets it from that side when the normal's y
    component x1 - x0 is negative.
    """
    px, py = plunger.position
    for i, wall in enumerate(walls):
        if not wall.one_sided:
            continue
        for j, (x0, y0, x1, y1) in enumerate(wall.segments()):
            if x0 == x1 or not min(x0, x1) <= px <= max(x0, x1):
                continue  # parallel to the path, or beside it
            crossing_y = y0 + (px - x0) * (y1 - y0) / (x1 - x0)
            if crossing_y > py and x1 < x0:
                top.key("walls").index(i, wall.name).fail(
                    f"one-sided segment {j} blocks the plunger's launch path "
                    "(its normal faces the plunger; reverse its points)"
                )


def _flipper_distance(p: tuple[float, float], flipper: Flipper, angle_deg: float) -> float:
    """Signed distance from ``p`` to the surface of ``flipper`` turned to ``angle_deg``."""
    distance, _, _ = flipper_distance(
        p[0], p[1], *flipper.pivot, flipper.length, flipper.base_radius, flipper.tip_radius,
        math.radians(angle_deg),
    )  # fmt: skip
    return float(distance)


def _segment_distance(p: tuple[float, float], segment: tuple[float, float, float, float]) -> float:
    x0, y0, x1, y1 = segment
    dx, dy = x1 - x0, y1 - y0
    t = ((p[0] - x0) * dx + (p[1] - y0) * dy) / (dx * dx + dy * dy)
    t = min(1.0, max(0.0, t))
    return math.dist(p, (x0 + t * dx, y0 + t * dy))


# --------------------------------------------------------------------------------------------
# Files
# --------------------------------------------------------------------------------------------


class _StrictLoader(yaml.SafeLoader):
    """Safe YAML loader that rejects a key repeated in one mapping (instead of keeping the last)."""

    def construct_mapping(self, node: yaml.MappingNode, deep: bool = False) -> dict[Any, Any]:
        self.flatten_mapping(node)  # resolve YAML merge keys ("<<") first
        seen: list[Any] = []
        for key_node, _ in node.value:
            key = self.construct_object(key_node, deep=deep)
            if key in seen:
                raise yaml.constructor.ConstructorError(
                    None, None, f"duplicate key {key!r}", key_node.start_mark
                )
            seen.append(key)
        return super().construct_mapping(node, deep=deep)


def available_tables() -> list[str]:
    """Names of the tables in ``configs/tables``."""
    if not TABLES_DIR.is_dir():
        return []
    return sorted(p.stem for p in TABLES_DIR.iterdir() if p.suffix in _SUFFIXES)


def load_table(name_or_path: str | os.PathLike[str]) -> Table:
    """Load a table from a .yaml/.yml path, or by bare name from ``configs/tables``."""
    path = Path(name_or_path)
    if path.suffix not in _SUFFIXES and len(path.parts) == 1:
        candidates = [TABLES_DIR / f"{path.name}{suffix}" for suffix in _SUFFIXES]
        path = next((p for p in candidates if p.is_file()), None)
        if path is None:
            available = ", ".join(available_tables()) or "none"
            raise TableError(f"unknown table {str(name_or_path)!r} (available: {available})")
    source = str(path)
    if not path.is_file():
        raise TableError(f"{source}: table file not found")
    try:
        data = yaml.load(path.read_text(encoding="utf-8"), Loader=_StrictLoader)
    except yaml.YAMLError as exc:
        raise TableError(f"{source}: invalid YAML: {exc}") from exc
    except (OSError, UnicodeDecodeError) as exc:
        raise TableError(f"{source}: cannot read the file: {exc}") from exc
    return table_from_dict(data, source)
