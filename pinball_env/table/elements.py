"""The table's elements in a description: materials, walls, posts, flippers, sensors, the
plunger (and its skill shot), stand-up targets, drop banks, spinners and kickbacks, the multiball
elements (saucers, locks and the trough with its auto-plunger), each with its keys and its
physically sensible ranges, and the checks that tie them together (unique names, known
materials, kickers that lose energy; the geometry checks are
:mod:`~pinball_env.table.geometry`'s).

A value outside a range is a typo (or an attack): it would make the ball, the table or the work
of a frame absurd.

Each record's keys are declared once, at module level (``WALL_FIELDS``, ``FLIPPER_FIELDS``, ...),
with :data:`~pinball_env.table.fields.POINT` where the table's point parser goes; an element's
checks beyond its keys' ranges are ``check_wall``, ``check_flipper``, ... The element kinds'
registry (:mod:`pinball_env.table.kinds`) ties each kind to its keys, its limit and its checks;
``schema.parse_elements`` parses them by it, and :mod:`pinball_env.table.reference` documents the
table files from the same declarations.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from functools import partial
from typing import Any

from pinball_env.table.fields import (
    POINT,
    Parser,
    Where,
    bound,
    choice,
    describe,
    flag,
    listing,
    number,
    pair,
    point_list,
    record,
    records,
    score,
    short,
    string,
    velocity_pair,
)
from pinball_env.table.geometry import check_lengths
from pinball_env.table.parts import (
    BUTTONS,
    AutoPlunger,
    DropBank,
    DropTarget,
    Flipper,
    Kickback,
    Material,
    Plunger,
    Sensor,
    SkillShot,
    Trough,
    Wall,
)

# How many of each element a table may have. They bound the work of a frame (every pass sweeps
# the ball against every segment, post and flipper) and of loading a file.
MAX_SEGMENTS = 2048  # over all walls
MAX_POINTS = 1024  # per wall
MAX_POSTS = 256
MAX_FLIPPERS = 8
MAX_SENSORS = 256
MAX_DROP_TARGETS = 64  # over all banks
MAX_SPINNERS = 16
MAX_KICKBACKS = 8
MAX_SWING = 90.0  # a flipper's |up_angle - rest_angle| [deg]
MAX_KICKBACK_SPEED = 10.0  # a real kickback fires the ball at a few m/s [m/s]
# Multiball: every held ball (in a saucer or a lock's slot) is one more immovable circle, and
# every ball in the machine one more moving one, for the kernel to sweep.
MAX_SAUCERS = 8
MAX_LOCKS = 4
MAX_LOCK_SLOTS = 6  # per lock
MAX_BALLS = 6  # in the machine (the trough's balls)
MAX_EJECT_SPEED = 10.0  # a saucer's kick and a lock's release, like a kickback's [m/s]

_flipper_radius = partial(number, low=0.001, high=0.1, unit="m")
_kick = partial(number, low=0.0, high=10.0, unit="m/s")  # a real pop bumper adds ~1.5 m/s
_angle = partial(number, low=-360.0, high=360.0, unit="deg")


def _two_points(value: object, loc: Where, point: Parser) -> tuple[tuple[float, float], ...]:
    """list of 2 points in the playfield [m], apart"""
    points = point_list(value, loc, point, 2, 2)
    check_lengths([(*points[0], *points[1])], loc)
    return points


# The keys of each record, in file order, and their parsers.
MATERIAL_FIELDS: dict[str, Parser] = {
    # At most 1: a bounce never adds energy (kicks do, see _check_kickers).
    "restitution": partial(number, low=0.0, high=1.0),
    "friction": partial(number, low=0.0, high=2.0),
}
WALL_FIELDS: dict[str, Parser] = {
    "name": string,
    "points": partial(point_list, point=POINT, min_len=2, max_len=MAX_POINTS),
    "closed": flag,
    "material": string,
    "one_sided": flag,
    "kick": _kick,
    "score": score,
}
POST_FIELDS: dict[str, Parser] = {
    "name": string,
    "center": POINT,
    "radius": partial(number, low=0.001, high=1.0, unit="m"),
    "material": string,
    "kick": _kick,
    "score": score,
}
FLIPPER_FIELDS: dict[str, Parser] = {
    "name": string,
    "pivot": POINT,
    "length": partial(number, low=0.01, high=1.0, unit="m"),  # a real flipper is ~70 mm
    "base_radius": _flipper_radius,
    "tip_radius": _flipper_radius,
    "rest_angle": _angle,
    "up_angle": _angle,
    "stroke_time": partial(number, low=0.005, high=0.2, unit="s"),
    "return_time": partial(number, low=0.005, high=0.5, unit="s"),
    "material": string,
    "button": partial(choice, options=BUTTONS),
    "score": score,
}
SENSOR_FIELDS: dict[str, Parser] = {
    "name": string,
    "points": partial(point_list, point=POINT, min_len=2, max_len=2),
    "drain": flag,
    "score": score,
}
SKILL_SHOT_FIELDS: dict[str, Parser] = {
    "sensor": string,
    "bonus": score,
    "time": partial(number, low=0.1, high=60.0, unit="s"),
}
_speed = partial(pair, item=partial(number, low=0.0, high=20.0, open_low=True, unit="m/s"))
PLUNGER_FIELDS: dict[str, Parser] = {
    "position": POINT,
    "speed": _speed,
    "stroke": partial(number, low=0.005, high=0.2, unit="m"),  # a real one pulls ~5 cm
    "pull_time": partial(number, low=0.05, high=5.0, unit="s"),
    "pull_speed": _speed,
    "scatter": partial(number, low=0.0, high=1.0, unit="m/s"),
    "skill_shot": partial(record, SkillShot, parsers=SKILL_SHOT_FIELDS),
}
STANDUP_FIELDS: dict[str, Parser] = {
    "name": string,
    "points": partial(_two_points, point=POINT),
    "material": string,
    "score": score,
}
DROP_TARGET_FIELDS: dict[str, Parser] = {
    "name": string,
    "points": partial(_two_points, point=POINT),
    "score": score,
}
DROP_BANK_FIELDS: dict[str, Parser] = {
    "name": string,
    "material": string,
    "targets": partial(
        records, DropTarget, parsers=DROP_TARGET_FIELDS, min_len=1, max_len=MAX_DROP_TARGETS
    ),
    # At least a few frames, so that the rules see the bank down before it rises.
    "reset_time": partial(number, low=0.1, high=60.0, unit="s"),
}
SPINNER_FIELDS: dict[str, Parser] = {
    "name": string,
    "points": partial(_two_points, point=POINT),
    "radius": partial(number, low=0.002, high=0.1, unit="m"),  # a real flap is ~15 mm
    "damping": partial(number, low=0.0, high=50.0, unit="1/s"),
    "friction": partial(number, low=0.0, high=1000.0, unit="rad/s^2"),
    "score": score,
}
KICKBACK_FIELDS: dict[str, Parser] = {
    "name": string,
    "points": partial(_two_points, point=POINT),
    "kick": velocity_pair,
    "lit": flag,
    "score": score,
}


def _eject_velocity(value: object, loc: Where) -> tuple[float, float]:
    """velocity [vx, vy] in m/s, its speed in (0, 10] m/s"""  # 10: MAX_EJECT_SPEED
    kick = velocity_pair(value, loc)
    _check_kick(kick, loc, MAX_EJECT_SPEED, "a real saucer or lock kicks the ball out")
    return kick


# Multiball.
_capture_radius = partial(number, low=0.01, high=0.1, unit="m")
_capture_speed = partial(number, low=0.05, high=5.0, unit="m/s")
SAUCER_FIELDS: dict[str, Parser] = {
    "name": string,
    "center": POINT,
    "radius": _capture_radius,
    "capture_speed": _capture_speed,
    "hold_time": partial(number, low=0.05, high=10.0, unit="s"),
    "kick": _eject_velocity,
    "score": score,
}
LOCK_FIELDS: dict[str, Parser] = {
    "name": string,
    "slots": partial(point_list, point=POINT, min_len=1, max_len=MAX_LOCK_SLOTS),
    # Absent: the ball's radius (a real lock's slot is a ball-sized pocket).
    "radius": partial(number, low=0.002, high=0.1, unit="m"),
    "capture_speed": _capture_speed,
    "kick": _eject_velocity,
    "score": score,
}
AUTO_PLUNGER_FIELDS: dict[str, Parser] = {"speed": _speed}
TROUGH_FIELDS: dict[str, Parser] = {
    "balls": partial(number, low=1, high=MAX_BALLS, integer=True),
    "auto_plunger": partial(record, AutoPlunger, parsers=AUTO_PLUNGER_FIELDS),
}


def parse_materials(value: object, loc: Where) -> tuple[Material, ...]:
    """The ``materials`` mapping (name -> restitution, friction), at least one."""
    if not isinstance(value, Mapping) or not value:
        loc.fail(f"expected a mapping of at least one material, got {describe(value)}")
    if len(value) > MAX_POSTS:
        loc.fail(f"{len(value)} materials, at most {MAX_POSTS} allowed")
    return tuple(
        record(Material, item, loc.key(string(name, loc)), MATERIAL_FIELDS, name=name)
        for name, item in value.items()
    )


def check_wall(wall: Wall, loc: Where) -> None:
    """A closed wall has 3 points or more, and no segment has zero length."""
    if wall.closed and len(wall.points) < 3:
        loc.fail(f"a closed polyline needs at least 3 points, got {len(wall.points)}")
    check_lengths(wall.segments(), loc)


def check_flipper(flipper: Flipper, loc: Where) -> None:
    """A flipper swings by at most MAX_SWING, and neither end circle swallows the other."""
    swing = abs(flipper.up_angle - flipper.rest_angle)
    if not 0.0 < swing <= MAX_SWING:
        loc.key("up_angle").fail(
            f"flipper swing must be in (0, {MAX_SWING:g}] degrees, got {swing:g} "
            "(|up_angle - rest_angle|)"
        )
    taper = abs(flipper.base_radius - flipper.tip_radius)
    if taper >= flipper.length:
        loc.fail(
            f"|base_radius - tip_radius| = {taper:g} must be < length {flipper.length:g} "
            "(else one end circle swallows the other)"
        )


def check_sensor(sensor: Sensor, loc: Where) -> None:
    """A sensor's line has a length."""
    check_lengths([sensor.segment], loc)


def parse_plunger(value: object, loc: Where, point: Parser) -> Plunger:
    """The ``plunger``: a machine's (a launch speed range) or the player's (stroke, pull_time
    and pull_speed together, and then a scatter and a skill shot if any)."""
    plunger = record(Plunger, value, loc, bound(PLUNGER_FIELDS, point))
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


def check_names_and_materials(
    groups: Mapping[str, tuple[Any, ...]], materials: tuple[Material, ...], top: Where
) -> None:
    """Element names are unique across all groups and every material reference resolves."""
    known = [m.name for m in materials]
    seen: dict[str, str] = {}
    for group, elements in groups.items():
        for i, element in enumerate(elements):
            loc = top.key(group).index(i, element.name)
            if element.name in seen:
                name = short(element.name)
                loc.fail(f"duplicate element name {name} (also {seen[element.name]})")
            seen[element.name] = loc.path
            material = getattr(element, "material", None)  # sensors have none
            if material is not None and material not in known:
                loc.key("material").fail(
                    f"unknown material {short(material)} (known: {listing(known)})"
                )


def check_kickers(
    groups: Mapping[str, tuple[Any, ...]], materials: tuple[Material, ...], top: Where
) -> None:
    """A kicking wall or post bounces with restitution below 1: a kick adds speed at every hit,
    and only a lossy bounce keeps that bounded (at kick / (1 - restitution))."""
    restitution = {m.name: m.restitution for m in materials}
    for group in ("walls", "posts"):
        for i, element in enumerate(groups[group]):
            if element.kick > 0.0 and restitution[element.material] >= 1.0:
                top.key(group).index(i, element.name).fail(
                    f"a kicker needs a material with restitution < 1, got "
                    f"{short(element.material)} with {restitution[element.material]:g} "
                    "(the ball would gain speed at every hit, without bound)"
                )


# --- targets and rules ---------------------------------------------------------------------------


def check_kickback(kickback: Kickback, loc: Where) -> None:
    """A kickback fires the ball at a real kickback's speed."""
    _check_kick(
        kickback.kick, loc.key("kick"), MAX_KICKBACK_SPEED, "a real kickback fires the ball"
    )


def _check_kick(kick: tuple[float, float], loc: Where, most: float, real: str) -> None:
    """A kick's speed is in (0, ``most``] (``real``: how a real one kicks, for the message)."""
    if not 0.0 < math.hypot(*kick) <= most:
        loc.fail(
            f"kick speed {math.hypot(*kick):g} m/s must be in (0, {most:g}] ({real} at a few m/s)"
        )


def check_drop_target_count(banks: tuple[DropBank, ...], loc: Where) -> None:
    """At most MAX_DROP_TARGETS drop targets over all the banks."""
    n_targets = sum(len(bank.targets) for bank in banks)
    if n_targets > MAX_DROP_TARGETS:
        loc.fail(f"{n_targets} targets in all, at most {MAX_DROP_TARGETS}")


# --- multiball -----------------------------------------------------------------------------------


def parse_trough(
    value: object,
    loc: Where,
    plunger: Plunger | None,
    ball_material: str | None,
    ball_loc: Where,
) -> Trough:
    """The ``trough``: several balls need a plunger to serve them and a ball-ball material
    (``ball.material``); the auto-plunger launches from the plunger's position."""
    trough = record(Trough, value, loc, TROUGH_FIELDS)
    auto = trough.auto_plunger
    if auto is not None and auto.speed[0] > auto.speed[1]:
        low, high = auto.speed
        loc.key("auto_plunger").key("speed").fail(
            f"expected [min, max] with min <= max, got [{low:g}, {high:g}]"
        )
    if auto is not None and plunger is None:
        loc.key("auto_plunger").fail(
            "an auto-plunger launches from the plunger's position: the table needs a plunger"
        )
    if trough.balls > 1 and plunger is None:
        loc.key("balls").fail(
            f"{trough.balls} balls need a plunger (the player's or the machine's) to serve them "
            "from the shooter lane: the table has none"
        )
    if trough.balls > 1 and ball_material is None:
        ball_loc.key("material").fail(
            f"a trough of {trough.balls} balls needs the ball-ball material (ball.material, "
            "one of the materials): balls in play together hit one another"
        )
    return trough
