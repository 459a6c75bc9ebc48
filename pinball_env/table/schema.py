"""The table schema: every key of a table description, its type and its range, and the checks
that tie elements together (unique names, known materials, nothing overlapping the ball's start,
a plunger shot that a gate lets through, ...).

:func:`table_from_dict` validates a description (as read from YAML) into a frozen
:class:`~pinball_env.table.model.Table`; :func:`table_to_dict` writes one back. Every mistake
(unknown or missing key, wrong type, non-finite or out-of-range number, bad geometry) raises
:class:`TableError` with the source, the path of the element and the problem; nothing is
silently defaulted. :func:`check_ball_state` validates a ball state given at run time (reset
options) the same way.
"""

from __future__ import annotations

import dataclasses
import math
import numbers
import reprlib
from collections.abc import Callable, Iterable, Mapping
from dataclasses import MISSING, dataclass, fields
from functools import partial
from typing import Any, NoReturn

import numpy as np
from numba import njit

from pinball_env.physics import flipper_distance, flipper_reach, point_segment_distance
from pinball_env.table.model import (
    BUTTONS,
    Ball,
    BallSave,
    Cabinet,
    DropBank,
    DropTarget,
    Flipper,
    Kickback,
    Material,
    Plunger,
    Post,
    Sensor,
    Simulation,
    SkillShot,
    Spinner,
    StandupTarget,
    Table,
    Tilt,
    Wall,
    enclosure,
    inside,
)
from pinball_env.table.reachable import cell_of
from pinball_env.table.rules import (
    EFFECTS,
    FLIPPER_BUTTONS,
    TRIGGERS,
    Effect,
    Light,
    Rule,
    RuleSet,
    Timer,
    Trigger,
    find_cycle,
)

# Fastest ball a table or a reset may set [m/s]: a real one rarely passes 10 m/s, and the flipper
# contact's work grows with the speed.
MAX_BALL_SPEED = 100.0
# How many of each element a table may have. They bound the work of a frame (every pass sweeps
# the ball against every segment, post and flipper) and of loading a file.
MAX_SEGMENTS = 2048  # over all walls
MAX_POINTS = 1024  # per wall
MAX_POSTS = 256
MAX_FLIPPERS = 8
MAX_SENSORS = 256
MAX_SCORE = 1_000_000  # points per hit
# A wall or post must keep this far from the area a flipper sweeps [m]. The check samples the
# swing and each segment at most SWING_SAMPLES times, so on a large flipper it keeps a wall a
# few sample steps away (about 1/100 of the swing's arc) rather than do unbounded work.
SWING_CLEARANCE = 3e-4
SWING_SAMPLES = 200

_short = reprlib.Repr()
_short.maxstring = _short.maxother = 60
_short.maxlist = _short.maxtuple = _short.maxdict = _short.maxset = 4
_short.maxlevel = 2
_short.maxlong = 40


class TableError(ValueError):
    """A table description is invalid or cannot be read."""


# --- validation helpers, shared by every field ---------------------------------------------------


@dataclass(frozen=True)
class _Loc:
    """Where a value sits: the source file and the element path, for error messages."""

    source: str
    path: str = ""

    def key(self, key: str) -> _Loc:
        key = key if len(key) <= 60 else _short.repr(key)
        return _Loc(self.source, f"{self.path}.{key}" if self.path else key)

    def index(self, i: int, name: object = None) -> _Loc:
        label = f"{self.path}[{i}]" + (f" {_short.repr(name)}" if isinstance(name, str) else "")
        return _Loc(self.source, label)

    def fail(self, problem: str) -> NoReturn:
        raise TableError(f"{self.source}: {self.path or 'top level'}: {problem}")


Parser = Callable[[Any, _Loc], Any]


def _describe(value: object) -> str:
    """The type and a shortened repr of a value from a file: aliases in YAML can make a small
    file hold a value whose full repr is gigabytes."""
    return f"{type(value).__name__} {_short.repr(value)}"


def _listing(names: Iterable[str], most: int = 12) -> str:
    """Names for a message, sorted, each shortened, at most ``most`` of them."""
    names = sorted(names)
    shown = [name if len(name) <= 40 else _short.repr(name) for name in names[:most]]
    return ", ".join(shown) + (f", ... ({len(names)} in all)" if len(names) > most else "")


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
            loc.fail(f"unknown key {_short.repr(key)} (allowed: {', '.join(allowed)})")
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
    try:
        finite = math.isfinite(value)
    except OverflowError:  # an integer too large for a float
        loc.fail(f"{_short.repr(value)} is out of range (too large)")
    if not finite:
        loc.fail(f"expected a finite number, got {value!r}")
    too_low = low is not None and (value <= low if open_low else value < low)
    too_high = high is not None and (value >= high if open_high else value > high)
    if too_low or too_high:
        if high is None:
            interval = f"{'>' if open_low else '>='} {low:g}"
        else:
            interval = f"{'(' if open_low else '['}{low:g}, {high:g}{')' if open_high else ']'}"
        loc.fail(f"{_short.repr(value)} is out of range (must be {interval})")
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
            f"speed {math.hypot(vx, vy):.10g} m/s is above {MAX_BALL_SPEED:g} m/s "
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


# Physically sensible ranges. A value outside them is a typo (or an attack): it would make the
# ball, the table or the work of a frame absurd.
_positive = partial(_number, low=0.0, open_low=True)
_non_negative = partial(_number, low=0.0)
_score = partial(_number, low=0, high=MAX_SCORE, integer=True)
_playfield_size = partial(_number, low=0.05, high=5.0)  # [m]: a real playfield is ~0.5 x 1 m
_ball_radius = partial(_number, low=0.002, high=0.1)  # [m]: a real ball is 13.5 mm
_ball_mass = partial(_number, low=0.001, high=10.0)  # [kg]: a real ball is 80 g
_post_radius = partial(_number, low=0.001, high=1.0)  # [m]
_flipper_length = partial(_number, low=0.01, high=1.0)  # [m]: a real flipper is ~70 mm
_flipper_radius = partial(_number, low=0.001, high=0.1)  # [m]
_kick = partial(_number, low=0.0, high=10.0)  # [m/s]: a real pop bumper adds ~1.5 m/s
_gravity = partial(_number, low=0.0, high=100.0, open_low=True)  # [m/s^2]: Earth's 9.81

# --- building a table -----------------------------------------------------------------------------


def table_from_dict(data: Mapping[str, Any], source: str = "<dict>") -> Table:
    """Validate a table description (as read from YAML) into a :class:`Table`."""
    source = source if len(source) <= 200 else _short.repr(source)
    top = _Loc(source)
    raw = _mapping(data, top, ["name", "playfield", "ball", "materials"], _TOP_KEYS)
    playfield = _mapping(raw["playfield"], top.key("playfield"), ["width", "height"])
    width = _playfield_size(playfield["width"], top.key("playfield").key("width"))
    height = _playfield_size(playfield["height"], top.key("playfield").key("height"))
    point = partial(_point, width=width, height=height)
    materials = _materials(raw["materials"], top.key("materials"))
    elements = _elements(raw, top, point, materials)
    ball_loc = top.key("ball")
    ball_parsers = {
        "radius": _ball_radius,
        "mass": _ball_mass,
        "start": point,
        "velocity": _velocity,
    }
    ball = _record(Ball, raw["ball"], ball_loc, ball_parsers)
    _check_placed(ball.start, ball.radius, elements, ball_loc.key("start"))
    return Table(
        name=_string(raw["name"], top.key("name")),
        width=width,
        height=height,
        ball=ball,
        materials=materials,
        source=source,
        **elements,
        **_options(raw, top, point, ball, elements),
    )


def _elements(
    raw: Mapping[str, Any], top: _Loc, point: Parser, materials: tuple[Material, ...]
) -> dict[str, tuple[Any, ...]]:
    """The walls, posts, flippers and sensors, by group name (the Table's fields), checked
    together: unique names, known materials, no flipper pivot in a wall."""
    post_parsers = {
        "name": _string,
        "center": point,
        "radius": _post_radius,
        "material": _string,
        "kick": _kick,
        "score": _score,
    }
    post = partial(_record, Post, parsers=post_parsers)
    elements = {
        "walls": _group(raw, top, "walls", partial(_wall, point=point), MAX_SEGMENTS),
        "posts": _group(raw, top, "posts", post, MAX_POSTS),
        "flippers": _group(raw, top, "flippers", partial(_flipper, point=point), MAX_FLIPPERS),
        "sensors": _group(raw, top, "sensors", partial(_sensor, point=point), MAX_SENSORS),
    }
    elements.update(_target_groups(raw, top, point))
    n_segments = sum(len(wall.segments()) for wall in elements["walls"])
    n_segments += len(elements["standup_targets"])
    if n_segments > MAX_SEGMENTS:
        top.key("walls").fail(f"{n_segments} segments in all, at most {MAX_SEGMENTS} allowed")
    targets = [t for bank in elements["drop_targets"] for t in bank.targets]
    _check_elements({**elements, "drop_targets.targets": tuple(targets)}, materials, top)
    _check_kickers(elements, materials, top)
    _check_outline(elements["walls"], top)
    solid = {**elements, "walls": _solid_walls(elements)}
    _check_pivots(elements["flippers"], solid["walls"], top)
    _check_swings(solid, top)
    return elements


def _options(
    raw: Mapping[str, Any],
    top: _Loc,
    point: Parser,
    ball: Ball,
    elements: Mapping[str, tuple[Any, ...]],
) -> dict[str, Any]:
    """The optional top-level keys that are given, parsed and checked (the rest default)."""
    options: dict[str, Any] = {}
    if "plunger" in raw:
        options["plunger"] = plunger = _plunger(raw["plunger"], top.key("plunger"), point)
        position_loc = top.key("plunger").key("position")
        _check_placed(plunger.position, ball.radius, elements, position_loc)
        _check_launch_path(plunger, elements["walls"], top)
    if "slope_deg" in raw:
        options["slope_deg"] = _number(
            raw["slope_deg"], top.key("slope_deg"), 0.0, 90.0, open_high=True
        )
    if "gravity" in raw:
        options["gravity"] = _gravity(raw["gravity"], top.key("gravity"))
    if "simulation" in raw:
        simulation_parsers = {
            "frame_rate": partial(_number, low=1.0, high=1000.0),
            "substeps": partial(_number, low=1, high=100, integer=True),
            "max_passes": partial(_number, low=1, high=100, integer=True),
            "skin": partial(_number, low=1e-8, high=1e-4),  # [m]
            "resting_speed": partial(_number, low=0.0, high=1.0),  # [m/s]
        }
        options["simulation"] = _record(
            Simulation, raw["simulation"], top.key("simulation"), simulation_parsers
        )
    substep = 1.0 / (
        options.get("simulation", Simulation()).frame_rate
        * options.get("simulation", Simulation()).substeps
    )
    if "cabinet" in raw:
        options["cabinet"] = _cabinet(raw["cabinet"], top.key("cabinet"), substep)
    if "tilt" in raw:
        gravity = options.get("gravity", Table.gravity)
        options["tilt"] = _tilt(raw["tilt"], top.key("tilt"), substep, gravity)
    _check_whole_cabinet(options, elements["sensors"], top)
    if "ball_save" in raw:
        options["ball_save"] = _ball_save(raw["ball_save"], top.key("ball_save"))
    if "rules" in raw:
        options["rules"] = _rules(raw["rules"], top.key("rules"), point, rule_names(elements))
    return options


def table_to_dict(table: Table) -> dict[str, Any]:
    """The description that :func:`table_from_dict` reads back as ``table`` (plain lists and
    dicts, ready for ``yaml.safe_dump``)."""

    def plain(element: Any, drop: tuple[str, ...] = ()) -> dict[str, Any]:
        return {k: v for k, v in _plain(dataclasses.asdict(element)).items() if k not in drop}

    data: dict[str, Any] = {
        "name": table.name,
        "playfield": {"width": table.width, "height": table.height},
        "slope_deg": table.slope_deg,
        "gravity": table.gravity,
        "ball": plain(table.ball),
        "materials": {m.name: plain(m, drop=("name",)) for m in table.materials},
    }
    for group in ("walls", "posts", "flippers", "sensors"):
        data[group] = [plain(element) for element in getattr(table, group)]
    # Targets and rules only where the table has them (older tables write as they did).
    for group in ("standup_targets", "drop_targets", "spinners", "kickbacks"):
        if getattr(table, group):
            data[group] = [plain(element) for element in getattr(table, group)]
    if table.ball_save is not None:
        data["ball_save"] = plain(table.ball_save)
    if table.rules is not None:
        data["rules"] = _rules_to_dict(table.rules)
    if table.plunger is not None:
        # The player's plunger's fields only where set: a machine's plunger writes as it always
        # did (digests of tables, such as a recording's, stay the same).
        defaults = {f.name: f.default for f in fields(Plunger)}
        data["plunger"] = {
            key: value for key, value in plain(table.plunger).items()
            if _plain(defaults[key]) != value
        }  # fmt: skip
    if table.cabinet is not None:
        data["cabinet"] = plain(table.cabinet)
    if table.tilt is not None:
        # settle_time only where set: a tilt without one writes as it always did.
        data["tilt"] = plain(table.tilt, drop=() if table.tilt.settle_time else ("settle_time",))
    data["simulation"] = plain(table.simulation)
    return data


def _plain(value: Any) -> Any:
    """``value`` with tuples turned into lists, in nested dicts and lists too."""
    if isinstance(value, dict):
        return {k: _plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    return value


def _check_placed(
    center: tuple[float, float],
    radius: float,
    elements: Mapping[str, tuple[Any, ...]],
    loc: _Loc,
) -> None:
    """A ball of ``radius`` at ``center`` is clear of every element and inside the outline."""
    walls = _solid_walls(elements)
    _check_clear(center, radius, walls, elements["posts"], elements["flippers"], loc)
    _check_enclosed(center, elements["walls"], loc)


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
    "cabinet",
    "tilt",
    "standup_targets",
    "drop_targets",
    "spinners",
    "kickbacks",
    "ball_save",
    "rules",
    "simulation",
)


def _name_of(item: object) -> object:
    return item.get("name") if isinstance(item, Mapping) else None


def _group(
    raw: Mapping[str, Any], top: _Loc, key: str, parse: Parser, max_len: int
) -> tuple[Any, ...]:
    """The optional list ``raw[key]`` of at most ``max_len`` elements, each parsed at its path
    ``key[i] 'name'``."""
    items = _list(raw.get(key, []), top.key(key), max_len=max_len)
    return tuple(parse(item, top.key(key).index(i, _name_of(item))) for i, item in enumerate(items))


def _materials(value: object, loc: _Loc) -> tuple[Material, ...]:
    if not isinstance(value, Mapping) or not value:
        loc.fail(f"expected a mapping of at least one material, got {_describe(value)}")
    if len(value) > MAX_POSTS:
        loc.fail(f"{len(value)} materials, at most {MAX_POSTS} allowed")
    parsers = {
        # At most 1: a bounce never adds energy (kicks do, see _check_kickers).
        "restitution": partial(_number, low=0.0, high=1.0),
        "friction": partial(_number, low=0.0, high=2.0),
    }
    return tuple(
        _record(Material, item, loc.key(_string(name, loc)), parsers, name=name)
        for name, item in value.items()
    )


def _wall(value: object, loc: _Loc, point: Parser) -> Wall:
    parsers = {
        "closed": _flag,
        "material": _string,
        "one_sided": _flag,
        "kick": _kick,
        "score": _score,
    }
    wall = _line(Wall, value, loc, point, MAX_POINTS, parsers)
    if wall.closed and len(wall.points) < 3:
        loc.fail(f"a closed polyline needs at least 3 points, got {len(wall.points)}")
    _check_lengths(wall.segments(), loc)
    return wall


def _line(
    cls: type, value: object, loc: _Loc, point: Parser, max_points: int, parsers: dict[str, Parser]
) -> Any:
    """A wall or a sensor: ``cls`` with a name, 2 to ``max_points`` points and ``parsers``' keys."""
    points = partial(_points, point=point, min_len=2, max_len=max_points)
    return _record(cls, value, loc, {"name": _string, "points": points, **parsers})


def _flipper(value: object, loc: _Loc, point: Parser) -> Flipper:
    angle = partial(_number, low=-360.0, high=360.0)
    flipper = _record(
        Flipper,
        value,
        loc,
        {
            "name": _string,
            "pivot": point,
            "length": _flipper_length,
            "base_radius": _flipper_radius,
            "tip_radius": _flipper_radius,
            "rest_angle": angle,
            "up_angle": angle,
            "stroke_time": partial(_number, low=0.005, high=0.2),
            "return_time": partial(_number, low=0.005, high=0.5),
            "material": _string,
            "button": partial(_choice, options=BUTTONS),
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
    sensor = _line(Sensor, value, loc, point, 2, {"drain": _flag, "score": _score})
    _check_lengths([sensor.segment], loc)
    return sensor


def _plunger(value: object, loc: _Loc, point: Parser) -> Plunger:
    speed = partial(_pair, item=partial(_number, low=0.0, high=20.0, open_low=True))
    parsers = {
        "position": point,
        "speed": speed,
        "stroke": partial(_number, low=0.005, high=0.2),  # [m]: a real one pulls ~5 cm
        "pull_time": partial(_number, low=0.05, high=5.0),  # [s]
        "pull_speed": speed,
        "scatter": partial(_number, low=0.0, high=1.0),  # [m/s]
        "skill_shot": _skill_shot,
    }
    plunger = _record(Plunger, value, loc, parsers)
    for key in ("speed", "pull_speed"):
        if getattr(plunger, key) is not None:
            low, high = getattr(plunger, key)
            if low > high:
                loc.key(key).fail(f"expected [min, max] with min <= max, got [{low:g}, {high:g}]")
    manual = [key for key in ("stroke", "pull_time", "pull_speed") if getattr(plunger, key) is None]
    if len(manual) not in (0, 3):
        loc.fail(
            "a player's plunger needs stroke, pull_time and pull_speed together; missing "
            + ", ".join(manual)
        )
    for key in ("skill_shot", "scatter"):
        if getattr(plunger, key) and not plunger.manual:
            loc.key(key).fail(f"a {key.replace('_', ' ')} needs the player's plunger (stroke, ...)")
    if plunger.manual and plunger.scatter >= plunger.pull_speed[0]:
        loc.key("scatter").fail(
            f"a scatter of {plunger.scatter:g} m/s could stop the shortest pull's "
            f"{plunger.pull_speed[0]:g} m/s launch (it must be smaller)"
        )
    return plunger


def _skill_shot(value: object, loc: _Loc) -> SkillShot:
    parsers = {
        "sensor": _string,
        "bonus": _score,
        "time": partial(_number, low=0.1, high=60.0),  # [s]
    }
    return _record(SkillShot, value, loc, parsers)


# The cabinet's ranges. A real machine weighs 100-140 kg, a shove moves it a few millimetres; the
# semi-implicit Euler of the substeps needs the spring and damper slow against a substep.
MAX_CABINET_SPEED = 1.0  # fastest a shove may set the cabinet moving [m/s]
MAX_RATE_PER_SUBSTEP = 0.5  # most of sqrt(k/M), c/M, sqrt(g/L), bob damping times a substep


def _cabinet(value: object, loc: _Loc, substep: float) -> Cabinet:
    parsers = {
        "mass": partial(_number, low=10.0, high=1000.0),  # [kg]
        "stiffness": partial(_number, low=1.0, high=1e7),  # [N/m]
        "damping": partial(_number, low=0.0, high=1e6),  # [N s/m]
        "nudge_impulse": partial(_number, low=0.0, high=500.0, open_low=True),  # [N s]
        "nudge_interval": partial(_number, low=0.05, high=10.0),  # [s]
    }
    cabinet = _record(Cabinet, value, loc, parsers)
    if cabinet.nudge_impulse / cabinet.mass > MAX_CABINET_SPEED:
        loc.key("nudge_impulse").fail(
            f"a shove of {cabinet.nudge_impulse:g} N s sets the {cabinet.mass:g} kg cabinet "
            f"moving at {cabinet.nudge_impulse / cabinet.mass:g} m/s, above "
            f"{MAX_CABINET_SPEED:g} m/s (a shove moves a real cabinet a few millimetres)"
        )
    _check_rates(
        loc, substep, stiffness=cabinet.natural_frequency, damping=cabinet.damping / cabinet.mass
    )
    return cabinet


def _tilt(value: object, loc: _Loc, substep: float, gravity: float) -> Tilt:
    parsers = {
        "bob_length": partial(_number, low=0.02, high=1.0),  # [m]: VPX's bob is 0.1 m
        "bob_damping": partial(_number, low=0.0, high=100.0),  # [1/s]
        "ring_angle": partial(_number, low=0.0, high=30.0, open_low=True),  # [deg], small angles
        "ring_restitution": partial(_number, low=0.0, high=1.0),
        "warnings": partial(_number, low=0, high=10, integer=True),
        "warning_time": partial(_number, low=0.5, high=600.0),  # [s]
        "settle_time": partial(_number, low=0.0, high=60.0),  # [s]
    }
    tilt = _record(Tilt, value, loc, parsers)
    if tilt.settle_time >= tilt.warning_time:
        loc.key("settle_time").fail(
            f"{tilt.settle_time:g} s is not shorter than warning_time ({tilt.warning_time:g} s): "
            "a warning would be forgotten while its own swing still counts as it"
        )
    _check_rates(
        loc, substep, bob_length=math.sqrt(gravity / tilt.bob_length), bob_damping=tilt.bob_damping
    )
    return tilt


def _check_rates(loc: _Loc, substep: float, **rates: float) -> None:
    """Each rate [1/s] times a substep is at most MAX_RATE_PER_SUBSTEP, for a stable integration."""
    for key, rate in rates.items():
        if rate * substep > MAX_RATE_PER_SUBSTEP:
            loc.key(key).fail(
                f"too fast for the substeps: a rate of {rate:g}/s over a substep of "
                f"{substep:g} s is {rate * substep:g}, at most {MAX_RATE_PER_SUBSTEP:g} "
                "(raise simulation.substeps, or soften it)"
            )


def _check_whole_cabinet(
    options: Mapping[str, Any], sensors: tuple[Sensor, ...], top: _Loc
) -> None:
    """The player's plunger, the cabinet and the tilt come together; a skill shot names a
    rollover of the table."""
    plunger = options.get("plunger")
    parts = {
        "a player's plunger (plunger: stroke, pull_time, pull_speed)": plunger is not None
        and plunger.manual,
        "cabinet": "cabinet" in options,
        "tilt": "tilt" in options,
    }
    if any(parts.values()) and not all(parts.values()):
        have = [name for name, present in parts.items() if present]
        lack = [name for name, present in parts.items() if not present]
        top.fail(
            f"the cabinet is a whole: {', '.join(have)} without {', '.join(lack)} (a table has "
            "the player's plunger, the cabinet and the tilt, or none of them)"
        )
    skill = plunger.skill_shot if plunger is not None else None
    if skill is not None:
        rollovers = [sensor.name for sensor in sensors if not sensor.drain]
        if skill.sensor not in rollovers:
            top.key("plunger").key("skill_shot").key("sensor").fail(
                f"no rollover sensor {skill.sensor!r} (rollovers: {_listing(rollovers)})"
            )


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
                name = _short.repr(element.name)
                loc.fail(f"duplicate element name {name} (also {seen[element.name]})")
            seen[element.name] = loc.path
            material = getattr(element, "material", None)  # sensors have none
            if material is not None and material not in known:
                loc.key("material").fail(
                    f"unknown material {_short.repr(material)} (known: {_listing(known)})"
                )


def _check_kickers(
    groups: Mapping[str, tuple[Any, ...]], materials: tuple[Material, ...], top: _Loc
) -> None:
    """A kicking wall or post bounces with restitution below 1: a kick adds speed at every hit,
    and only a lossy bounce keeps that bounded (at kick / (1 - restitution))."""
    restitution = {m.name: m.restitution for m in materials}
    for group in ("walls", "posts"):
        for i, element in enumerate(groups[group]):
            if element.kick > 0.0 and restitution[element.material] >= 1.0:
                top.key(group).index(i, element.name).fail(
                    f"a kicker needs a material with restitution < 1, got "
                    f"{_short.repr(element.material)} with {restitution[element.material]:g} "
                    "(the ball would gain speed at every hit, without bound)"
                )


def _check_outline(walls: tuple[Wall, ...], top: _Loc) -> None:
    """The outline (the closed wall enclosing the largest area) is two-sided: a one-sided one
    lets the ball through one way, out of the table."""
    outline = enclosure(walls)
    if outline is not None and outline.one_sided:
        i = walls.index(outline)
        top.key("walls").index(i, outline.name).key("one_sided").fail(
            "the table's outline (its largest closed wall) must be two-sided, or the ball "
            "leaves the table through it"
        )


def _check_swings(groups: Mapping[str, tuple[Any, ...]], top: _Loc) -> None:
    """No wall or post lies across the area a flipper sweeps between its stops (or within
    SWING_CLEARANCE of it): a rising flipper would hit a ball through it."""
    walls, posts = groups["walls"], groups["posts"]
    segments = np.array([s for _, _, s in _wall_segments(walls)], dtype=np.float64).reshape(-1, 4)
    circles = np.array([(*p.center, p.radius) for p in posts], dtype=np.float64).reshape(-1, 3)
    owners = [f"wall {_short.repr(w.name)} segment {j}" for w, j, _ in _wall_segments(walls)]
    owners += [f"post {_short.repr(p.name)}" for p in posts]
    for i, flipper in enumerate(groups["flippers"]):
        gap, element = _swing_clearance(
            *flipper.pivot, flipper.length, flipper.base_radius, flipper.tip_radius,
            math.radians(flipper.rest_angle), math.radians(flipper.up_angle), segments,
            circles, SWING_CLEARANCE / 2.0, SWING_SAMPLES,
        )  # fmt: skip
        if gap < SWING_CLEARANCE:
            top.key("flippers").index(i, flipper.name).fail(
                f"{owners[element]} lies in the flipper's swing (or too close to be sure it "
                "does not): a rising flipper would hit a ball through it"
            )


@njit(cache=True)
def _swing_clearance(px, py, length, rb, rt, a0, a1, segments, circles, step, most):
    """A lower bound of the distance between a flipper swinging from angle a0 to a1 and each
    segment and circle, the smallest of them: ``(distance, element)``, segments first then
    circles (``inf, -1`` when none is in reach). The swing is sampled at angles ``step`` of arc
    apart at the flipper's reach and the segments at points ``step`` apart, at most ``most``
    of each (so the work is bounded), and each sampled distance is lowered by twice the
    sampling step used: no point of the swing or the segment is farther from a sample."""
    reach = flipper_reach(length, rb, rt)
    arc = abs(a1 - a0) * reach
    n_angles = min(int(arc / step) + 2, most)
    angle_step = arc / (n_angles - 1)
    best = math.inf
    best_element = -1
    for k in range(segments.shape[0]):
        x0, y0, x1, y1 = segments[k, 0], segments[k, 1], segments[k, 2], segments[k, 3]
        if point_segment_distance(px, py, x0, y0, x1, y1) > reach + step:
            continue
        span = math.hypot(x1 - x0, y1 - y0)
        n_points = min(int(span / step) + 2, most)
        margin = 2.0 * max(angle_step, span / (n_points - 1))
        for i in range(n_points):
            s = i / (n_points - 1)
            x = x0 + s * (x1 - x0)
            y = y0 + s * (y1 - y0)
            if math.hypot(x - px, y - py) > reach + margin:
                continue
            for n in range(n_angles):
                angle = a0 + (a1 - a0) * n / (n_angles - 1)
                d, _, _ = flipper_distance(x, y, px, py, length, rb, rt, angle)
                if d - margin < best:
                    best, best_element = d - margin, k
    for k in range(circles.shape[0]):
        for n in range(n_angles):
            angle = a0 + (a1 - a0) * n / (n_angles - 1)
            d, _, _ = flipper_distance(circles[k, 0], circles[k, 1], px, py, length, rb, rt, angle)
            d -= circles[k, 2] + 2.0 * angle_step
            if d < best:
                best, best_element = d, segments.shape[0] + k
    return best, best_element


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
        gap = flipper.distance(center, flipper.rest_angle)
        if gap < radius:
            loc.fail(
                f"ball overlaps flipper {flipper.name!r} at its rest angle "
                f"(distance to its surface {gap:g} < ball radius {radius:g})"
            )


def _check_enclosed(point: tuple[float, float], walls: tuple[Wall, ...], loc: _Loc) -> None:
    """A ball centre lies inside the table's outline (when it has one)."""
    outline = enclosure(walls)
    if outline is not None and not inside(point, outline.points):
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
    elements = {"walls": table.solid_walls, "posts": table.posts, "flippers": table.flippers}
    _check_placed(point, table.ball.radius, elements, where.key("ball_position"))
    if not table.free_space[cell_of(point, table.free_space.shape)]:
        where.key("ball_position").fail(
            f"({point[0]:g}, {point[1]:g}) cannot be reached in play from the plunger: it is "
            "walled off (inside a slingshot, say) or on the far side of a drain (or within a "
            "millimetre of it)"
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


def _segment_distance(p: tuple[float, float], segment: tuple[float, float, float, float]) -> float:
    return float(point_segment_distance(p[0], p[1], *segment))


# --- targets and rules ---------------------------------------------------------------------------

MAX_DROP_TARGETS = 64  # over all banks
MAX_SPINNERS = 16
MAX_KICKBACKS = 8
MAX_RULES = 256  # and as many lights, counters, timers
MAX_MULTIPLIER = 100


def _two_points(value: object, loc: _Loc, point: Parser) -> tuple[tuple[float, float], ...]:
    points = _points(value, loc, point, 2, 2)
    _check_lengths([(*points[0], *points[1])], loc)
    return points


def _standup(value: object, loc: _Loc, point: Parser) -> StandupTarget:
    parsers = {
        "name": _string,
        "points": partial(_two_points, point=point),
        "material": _string,
        "score": _score,
    }
    return _record(StandupTarget, value, loc, parsers)


def _drop_bank(value: object, loc: _Loc, point: Parser) -> DropBank:
    target_parsers = {"name": _string, "points": partial(_two_points, point=point), "score": _score}

    def targets(items: object, where: _Loc) -> tuple[DropTarget, ...]:
        items = _list(items, where, 1, MAX_DROP_TARGETS)
        return tuple(
            _record(DropTarget, item, where.index(i, _name_of(item)), target_parsers)
            for i, item in enumerate(items)
        )

    parsers = {
        "name": _string,
        "material": _string,
        "targets": targets,
        # [s]: at least a few frames, so that the rules see the bank down before it rises
        "reset_time": partial(_number, low=0.1, high=60.0),
    }
    return _record(DropBank, value, loc, parsers)


def _spinner(value: object, loc: _Loc, point: Parser) -> Spinner:
    parsers = {
        "name": _string,
        "points": partial(_two_points, point=point),
        "radius": partial(_number, low=0.002, high=0.1),  # [m]: a real flap is ~15 mm
        "damping": partial(_number, low=0.0, high=50.0),  # [1/s]
        "friction": partial(_number, low=0.0, high=1000.0),  # [rad/s^2]
        "score": _score,
    }
    return _record(Spinner, value, loc, parsers)


def _kickback(value: object, loc: _Loc, point: Parser) -> Kickback:
    parsers = {
        "name": _string,
        "points": partial(_two_points, point=point),
        "kick": _velocity,
        "lit": _flag,
        "score": _score,
    }
    kickback = _record(Kickback, value, loc, parsers)
    if not 0.0 < math.hypot(*kickback.kick) <= 10.0:
        loc.key("kick").fail(
            f"kick speed {math.hypot(*kickback.kick):g} m/s must be in (0, 10] (a real kickback "
            "fires the ball at a few m/s)"
        )
    return kickback


def _target_groups(raw: Mapping[str, Any], top: _Loc, point: Parser) -> dict[str, tuple[Any, ...]]:
    """The stand-up targets, drop banks, spinners and kickbacks, by group name."""
    groups = {
        "standup_targets": _group(
            raw, top, "standup_targets", partial(_standup, point=point), MAX_SEGMENTS
        ),
        "drop_targets": _group(
            raw, top, "drop_targets", partial(_drop_bank, point=point), MAX_DROP_TARGETS
        ),
        "spinners": _group(raw, top, "spinners", partial(_spinner, point=point), MAX_SPINNERS),
        "kickbacks": _group(raw, top, "kickbacks", partial(_kickback, point=point), MAX_KICKBACKS),
    }
    n_targets = sum(len(bank.targets) for bank in groups["drop_targets"])
    if n_targets > MAX_DROP_TARGETS:
        top.key("drop_targets").fail(f"{n_targets} targets in all, at most {MAX_DROP_TARGETS}")
    return groups


def _solid_walls(elements: Mapping[str, tuple[Any, ...]]) -> tuple[Wall, ...]:
    """The walls with the stand-up and drop targets (standing) as walls, for the checks."""
    targets = tuple(t.as_wall() for t in elements.get("standup_targets", ()))
    banks = tuple(w for bank in elements.get("drop_targets", ()) for w in bank.walls())
    return elements["walls"] + targets + banks


def _ball_save(value: object, loc: _Loc) -> BallSave:
    return _record(
        BallSave, value, loc, {"time": partial(_number, low=0.0, high=60.0, open_low=True)}
    )


def _names(
    value: object, loc: _Loc, known: Iterable[str], what: str, min_len: int = 1
) -> tuple[str, ...]:
    """A name or a list of names, each one of ``known`` (a ``what``)."""
    items = [value] if isinstance(value, str) else _list(value, loc, min_len, MAX_RULES)
    known = list(known)
    for i, name in enumerate(items):
        where = loc if isinstance(value, str) else loc.index(i)
        _string(name, where)
        if name not in known:
            where.fail(f"unknown {what} {_short.repr(name)} (known: {_listing(known) or 'none'})")
    if len(set(items)) != len(items):
        loc.fail(f"a {what} is named twice")
    return tuple(items)


def _rules(
    value: object, loc: _Loc, point: Parser, names: Mapping[str, tuple[str, ...]]
) -> RuleSet:
    """The ``rules`` section; ``names`` lists the table's names of each kind (elements, banks,
    kickbacks) that rules may refer to."""
    raw = _mapping(value, loc, [], ["lights", "counters", "timers", "max_multiplier", "rules"])
    light_parsers = {"name": _string, "at": point, "lit": _flag}
    lights = tuple(
        _record(Light, item, loc.key("lights").index(i, _name_of(item)), light_parsers)
        for i, item in enumerate(_list(raw.get("lights", []), loc.key("lights"), 0, MAX_RULES))
    )
    counters = tuple(
        _string(item, loc.key("counters").index(i))
        for i, item in enumerate(_list(raw.get("counters", []), loc.key("counters"), 0, MAX_RULES))
    )
    timer_parsers = {
        "name": _string,
        "time": partial(_number, low=0.0, high=600.0, open_low=True),  # [s]
        "factor": partial(_number, low=1, high=MAX_MULTIPLIER, integer=True),
        "elements": partial(_names, known=names["elements"], what="element", min_len=0),
    }
    timers = tuple(
        _record(Timer, item, loc.key("timers").index(i, _name_of(item)), timer_parsers)
        for i, item in enumerate(_list(raw.get("timers", []), loc.key("timers"), 0, MAX_RULES))
    )
    for key, items in (("lights", [x.name for x in lights]), ("counters", list(counters)),
                       ("timers", [x.name for x in timers])):  # fmt: skip
        if len(set(items)) != len(items):
            duplicate = next(name for name in items if items.count(name) > 1)
            loc.key(key).fail(f"{_short.repr(duplicate)} is named twice")
    known = {
        **names,
        "lights": tuple(x.name for x in lights),
        "counters": counters,
        "timers": tuple(x.name for x in timers),
    }
    max_multiplier = _number(
        raw.get("max_multiplier", 1), loc.key("max_multiplier"), 1, MAX_MULTIPLIER, integer=True
    )
    items = _list(raw.get("rules", []), loc.key("rules"), 0, MAX_RULES)
    rules = tuple(
        _rule(item, loc.key("rules").index(i, _name_of(item)), known)
        for i, item in enumerate(items)
    )
    rule_names = [rule.name for rule in rules]
    if len(set(rule_names)) != len(rule_names):
        duplicate = next(name for name in rule_names if rule_names.count(name) > 1)
        loc.key("rules").fail(f"two rules are named {_short.repr(duplicate)}")
    rule_set = RuleSet(lights, counters, timers, max_multiplier, rules)
    cycle = find_cycle(rule_set)
    if cycle:
        ring = " -> ".join(repr(rules[i].name) for i in cycle)
        loc.key("rules").fail(
            f"rules {ring} trigger one another in a ring: they could fire for ever in one frame"
        )
    return rule_set


def _rule(value: object, loc: _Loc, known: Mapping[str, tuple[str, ...]]) -> Rule:
    raw = _mapping(value, loc, ["name", "when", "do"])
    name = _string(raw["name"], loc.key("name"))
    when = _trigger(raw["when"], loc.key("when"), known)
    effects = _list(raw["do"], loc.key("do"), 1, MAX_RULES)
    do = tuple(_effect(item, loc.key("do").index(i), known) for i, item in enumerate(effects))
    return Rule(name, when, do)


# What each trigger and effect names: the kind of name (a key of the known names) and whether a
# list is allowed; None: a number.
_TRIGGER_NAMES = {
    "hit": ("elements", True),
    "bank": ("banks", False),
    "lights_on": ("lights", True),
    "flipper": ("buttons", False),
    "counter": ("counters", False),
    "timer_ends": ("timers", False),
}
_EFFECT_NAMES = {
    "light": ("lights", True),
    "unlight": ("lights", True),
    "rotate": ("lights", True),
    "count": ("counters", False),
    "start_timer": ("timers", False),
    "light_kickback": ("kickbacks", False),
    "score": None,
    "bonus": None,
    "multiplier": None,
    "extra_ball": None,
}
_KIND_WORDS = {"elements": "element", "banks": "drop bank", "lights": "light",
               "buttons": "flipper button", "counters": "counter", "timers": "timer",
               "kickbacks": "kickback"}  # fmt: skip


def _one_key(value: object, loc: _Loc, kinds: tuple[str, ...], extra: tuple[str, ...]) -> str:
    """The one key of ``kinds`` in mapping ``value`` (which may hold ``extra`` keys too)."""
    raw = _mapping(value, loc, [], (*kinds, *extra))
    given = [key for key in raw if key in kinds]
    if len(given) != 1:
        loc.fail(f"expected exactly one of {', '.join(kinds)}, got {', '.join(given) or 'none'}")
    return given[0]


def _named(
    value: object, loc: _Loc, spec: tuple[str, bool], known: Mapping[str, Any]
) -> tuple[str, ...]:
    kind, many = spec
    if not many and not isinstance(value, str):
        loc.fail(f"expected the name of a {_KIND_WORDS[kind]}, got {_describe(value)}")
    return _names(value, loc, known[kind], _KIND_WORDS[kind])


def _trigger(value: object, loc: _Loc, known: Mapping[str, Any]) -> Trigger:
    kind = _one_key(value, loc, TRIGGERS, ("at",))
    names = _named(value[kind], loc.key(kind), _TRIGGER_NAMES[kind], known)
    if ("at" in value) != (kind == "counter"):
        loc.fail("'at' goes with a counter trigger, and a counter trigger needs it")
    at = _number(value["at"], loc.key("at"), 1, 10**6, integer=True) if kind == "counter" else 0
    return Trigger(kind, names, at)


def _effect(value: object, loc: _Loc, known: Mapping[str, Any]) -> Effect:
    kind = _one_key(value, loc, EFFECTS, ("by",))
    if "by" in value and kind != "count":
        loc.fail("'by' goes with a count effect only")
    spec = _EFFECT_NAMES[kind]
    if spec is None:
        high = {"score": MAX_SCORE, "bonus": MAX_SCORE, "multiplier": MAX_MULTIPLIER,
                "extra_ball": 10}[kind]  # fmt: skip
        return Effect(kind, (), _number(value[kind], loc.key(kind), 1, high, integer=True))
    names = _named(value[kind], loc.key(kind), spec, known)
    if kind == "rotate" and len(names) < 2:
        loc.key(kind).fail("rotate needs at least two lights")
    by = _number(value.get("by", 1), loc.key("by"), 1, 10**6, integer=True)
    return Effect(kind, names, by if kind == "count" else 0)


def _rules_to_dict(rules: RuleSet) -> dict[str, Any]:
    """The ``rules`` section as :func:`_rules` reads it."""

    def names(spec: tuple[str, bool] | None, values: tuple[str, ...]) -> Any:
        return list(values) if spec[1] else values[0]

    def trigger(when: Trigger) -> dict[str, Any]:
        out = {when.kind: names(_TRIGGER_NAMES[when.kind], when.names)}
        return {**out, "at": when.at} if when.kind == "counter" else out

    def effect(do: Effect) -> dict[str, Any]:
        spec = _EFFECT_NAMES[do.kind]
        if spec is None:
            return {do.kind: do.value}
        out = {do.kind: names(spec, do.names)}
        return {**out, "by": do.value} if do.kind == "count" else out

    return {
        "lights": [{"name": x.name, "at": list(x.at), "lit": x.lit} for x in rules.lights],
        "counters": list(rules.counters),
        "timers": [
            {"name": x.name, "time": x.time, "factor": x.factor, "elements": list(x.elements)}
            for x in rules.timers
        ],
        "max_multiplier": rules.max_multiplier,
        "rules": [
            {"name": r.name, "when": trigger(r.when), "do": [effect(e) for e in r.do]}
            for r in rules.rules
        ],
    }


_NAMED_GROUPS = (
    "walls",
    "standup_targets",
    "posts",
    "flippers",
    "sensors",
    "spinners",
    "kickbacks",
)


def rule_names(table_elements: Mapping[str, tuple[Any, ...]]) -> dict[str, tuple[str, ...]]:
    """What the rules of a table with these element groups may name."""
    groups = table_elements
    elements = [e.name for group in _NAMED_GROUPS for e in groups.get(group, ())]
    elements += [t.name for bank in groups.get("drop_targets", ()) for t in bank.targets]
    return {
        "elements": tuple(elements),
        "banks": tuple(bank.name for bank in groups.get("drop_targets", ())),
        "kickbacks": tuple(k.name for k in groups.get("kickbacks", ())),
        "buttons": FLIPPER_BUTTONS,
    }
