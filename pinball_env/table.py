"""Pinball tables: load a YAML description, validate it strictly, pack it for the kernels.

A table file describes the playfield in SI units (metres, seconds; only the slope is in degrees)
in the table frame: origin at the bottom-left corner, x to the right, y up the table. See
``configs/tables/box.yaml`` for an annotated example. Every mistake in a file (unknown or missing
key, wrong type, non-finite or out-of-range number, bad geometry) raises :class:`TableError` with
the file name, the path of the element and the problem; nothing is silently defaulted.
"""

from __future__ import annotations

import itertools
import math
import numbers
import os
from collections.abc import Callable, Iterable, Mapping
from dataclasses import MISSING, dataclass, fields
from functools import partial
from pathlib import Path
from typing import Any, NoReturn

import numpy as np
import yaml

from pinball_env.physics import layout

TABLES_DIR = Path(__file__).resolve().parent.parent / "configs" / "tables"
_SUFFIXES = (".yaml", ".yml")


class TableError(ValueError):
    """A table description is invalid or cannot be read."""


# --------------------------------------------------------------------------------------------
# Table model
# --------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class Material:
    """Surface properties shared by walls and posts."""

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
    element_names: tuple[str, ...]  # global element id -> name: segments, then circles
    gravity: np.ndarray  # (2,) float64 [m/s^2], in the playfield plane


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
    slope_deg: float = 6.5  # inclination of the playfield [deg]
    gravity: float = 9.81  # [m/s^2]
    simulation: Simulation = Simulation()  # frozen, so sharing it is safe
    source: str = "<dict>"  # file the table was read from

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

        segments, segment_props, one_sided, names = [], [], [], []
        for wall in self.walls:
            for i, segment in enumerate(wall.segments()):
                segments.append(segment)
                segment_props.append(props(wall.material, wall.kick))
                one_sided.append(wall.one_sided)
                names.append(f"{wall.name}[{i}]")
        circles = [(*post.center, post.radius) for post in self.posts]
        circle_props = [props(post.material, post.kick) for post in self.posts]
        names.extend(post.name for post in self.posts)
        return PackedTable(
            segments=_frozen_array(segments, np.float64, (-1, 4)),
            segment_props=_frozen_array(segment_props, np.float64, (-1, layout.PROP_SIZE)),
            segment_one_sided=_frozen_array(one_sided, np.bool_, (-1,)),
            circles=_frozen_array(circles, np.float64, (-1, 3)),
            circle_props=_frozen_array(circle_props, np.float64, (-1, layout.PROP_SIZE)),
            element_names=tuple(names),
            gravity=_frozen_array(self.gravity_vector, np.float64, (2,)),
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


def _list(value: object, loc: _Loc, min_len: int = 0) -> list[Any]:
    if not isinstance(value, (list, tuple)):
        loc.fail(f"expected a list, got {_describe(value)}")
    if len(value) < min_len:
        loc.fail(f"expected at least {min_len} items, got {len(value)}")
    return list(value)


def _string(value: object, loc: _Loc) -> str:
    if not isinstance(value, str) or not value:
        loc.fail(f"expected a non-empty string, got {_describe(value)}")
    return value


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


def _pair(value: object, loc: _Loc) -> tuple[float, float]:
    """An [x, y] pair of finite numbers."""
    if not isinstance(value, (list, tuple)) or len(value) != 2:
        loc.fail(f"expected a pair [x, y], got {_describe(value)}")
    return (_number(value[0], loc.index(0)), _number(value[1], loc.index(1)))


def _point(value: object, loc: _Loc, width: float, height: float) -> tuple[float, float]:
    """An [x, y] pair inside the playfield (bounds included)."""
    x, y = _pair(value, loc)
    if not (0.0 <= x <= width and 0.0 <= y <= height):
        loc.fail(f"point ({x:g}, {y:g}) is outside the playfield [0, {width:g}] x [0, {height:g}]")
    return (x, y)


def _record(
    cls: type, value: object, loc: _Loc, parsers: Mapping[str, Parser], **extra: Any
) -> Any:
    """Build dataclass ``cls`` from a mapping: one parser per key, defaults from ``cls``."""
    required = [f.name for f in fields(cls) if f.name in parsers and f.default is MISSING]
    raw = _mapping(value, loc, required, parsers)
    return cls(**{key: parsers[key](raw[key], loc.key(key)) for key in raw}, **extra)


_positive = partial(_number, low=0.0, open_low=True)
_non_negative = partial(_number, low=0.0)


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
    walls = tuple(
        _wall(item, top.key("walls").index(i, _name_of(item)), point)
        for i, item in enumerate(_list(raw.get("walls", []), top.key("walls")))
    )
    posts = tuple(
        _record(
            Post,
            item,
            top.key("posts").index(i, _name_of(item)),
            {
                "name": _string,
                "center": point,
                "radius": _positive,
                "material": _string,
                "kick": _non_negative,
            },
        )
        for i, item in enumerate(_list(raw.get("posts", []), top.key("posts")))
    )
    _check_elements(walls, posts, materials, top)

    ball_loc = top.key("ball")
    ball_parsers = {"radius": _positive, "mass": _positive, "start": point, "velocity": _pair}
    ball = _record(Ball, raw["ball"], ball_loc, ball_parsers)
    _check_ball_clear(ball, walls, posts, ball_loc.key("start"))

    options: dict[str, Any] = {}
    if "slope_deg" in raw:
        options["slope_deg"] = _number(
            raw["slope_deg"], top.key("slope_deg"), 0.0, 90.0, open_high=True
        )
    if "gravity" in raw:
        options["gravity"] = _positive(raw["gravity"], top.key("gravity"))
    if "simulation" in raw:
        simulation_parsers = {
            "frame_rate": _positive,
            "substeps": partial(_number, low=1, integer=True),
            "max_passes": partial(_number, low=1, integer=True),
            "skin": partial(_number, low=0.0, high=1e-3, open_low=True),
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
    "simulation",
)


def _name_of(item: object) -> object:
    return item.get("name") if isinstance(item, Mapping) else None


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
    def points(items: object, points_loc: _Loc) -> tuple[tuple[float, float], ...]:
        items = _list(items, points_loc, min_len=2)
        return tuple(point(p, points_loc.index(i)) for i, p in enumerate(items))

    wall = _record(
        Wall,
        value,
        loc,
        {
            "name": _string,
            "points": points,
            "closed": _flag,
            "material": _string,
            "one_sided": _flag,
            "kick": _non_negative,
        },
    )
    if wall.closed and len(wall.points) < 3:
        loc.fail(f"a closed polyline needs at least 3 points, got {len(wall.points)}")
    for i, (x0, y0, x1, y1) in enumerate(wall.segments()):
        if x0 == x1 and y0 == y1:
            loc.fail(f"segment {i} has zero length (both ends at ({x0:g}, {y0:g}))")
    return wall


def _check_elements(
    walls: tuple[Wall, ...], posts: tuple[Post, ...], materials: tuple[Material, ...], top: _Loc
) -> None:
    """Element names are unique and every material reference resolves."""
    known = [m.name for m in materials]
    seen: dict[str, str] = {}
    for group, elements in (("walls", walls), ("posts", posts)):
        for i, element in enumerate(elements):
            loc = top.key(group).index(i, element.name)
            if element.name in seen:
                loc.fail(f"duplicate element name {element.name!r} (also {seen[element.name]})")
            seen[element.name] = loc.path
            if element.material not in known:
                loc.key("material").fail(
                    f"unknown material {element.material!r} (known: {', '.join(sorted(known))})"
                )


def _check_ball_clear(
    ball: Ball, walls: tuple[Wall, ...], posts: tuple[Post, ...], loc: _Loc
) -> None:
    """The ball at its start position touches no wall segment and no post."""
    for wall in walls:
        for i, segment in enumerate(wall.segments()):
            distance = _segment_distance(ball.start, segment)
            if distance < ball.radius:
                loc.fail(
                    f"ball overlaps wall {wall.name!r} segment {i} "
                    f"(distance {distance:g} < ball radius {ball.radius:g})"
                )
    for post in posts:
        gap = math.dist(ball.start, post.center) - post.radius
        if gap < ball.radius:
            loc.fail(
                f"ball overlaps post {post.name!r} "
                f"(distance to its surface {gap:g} < ball radius {ball.radius:g})"
            )


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
