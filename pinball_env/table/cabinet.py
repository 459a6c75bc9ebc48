"""The cabinet in a description: the cabinet (a mass-spring-damper that a nudge shoves) and the
tilt (its plumb bob), their ranges, the stability of their integration over a substep, and the
whole they make with the player's plunger."""

from __future__ import annotations

import math
from collections.abc import Mapping
from functools import partial
from typing import Any

from pinball_env.table.fields import Where, listing, number, record
from pinball_env.table.parts import Cabinet, Sensor, Tilt

# The cabinet's ranges. A real machine weighs 100-140 kg, a shove moves it a few millimetres; the
# semi-implicit Euler of the substeps needs the spring and damper slow against a substep.
MAX_SHOVE_SPEED = 1.0  # fastest a shove may set the cabinet moving [m/s]
MAX_RATE_PER_SUBSTEP = 0.5  # most of sqrt(k/M), c/M, sqrt(g/L), bob damping times a substep

CABINET_FIELDS = {
    "mass": partial(number, low=10.0, high=1000.0, unit="kg"),
    "stiffness": partial(number, low=1.0, high=1e7, unit="N/m"),
    "damping": partial(number, low=0.0, high=1e6, unit="N s/m"),
    "nudge_impulse": partial(number, low=0.0, high=500.0, open_low=True, unit="N s"),
    "nudge_interval": partial(number, low=0.05, high=10.0, unit="s"),
}
TILT_FIELDS = {
    "bob_length": partial(number, low=0.02, high=1.0, unit="m"),  # VPX's bob is 0.1 m
    "bob_damping": partial(number, low=0.0, high=100.0, unit="1/s"),
    # Small angles: the bob's swing is integrated as a pendulum's.
    "ring_angle": partial(number, low=0.0, high=30.0, open_low=True, unit="deg"),
    "ring_restitution": partial(number, low=0.0, high=1.0),
    "warnings": partial(number, low=0, high=10, integer=True),
    "warning_time": partial(number, low=0.5, high=600.0, unit="s"),
    "settle_time": partial(number, low=0.0, high=60.0, unit="s"),
}


def parse_cabinet(value: object, loc: Where, substep: float) -> Cabinet:
    """The ``cabinet`` section: a shove no faster than MAX_SHOVE_SPEED, rates stable over a
    ``substep`` [s]."""
    cabinet = record(Cabinet, value, loc, CABINET_FIELDS)
    if cabinet.nudge_impulse / cabinet.mass > MAX_SHOVE_SPEED:
        loc.key("nudge_impulse").fail(
            f"a shove of {cabinet.nudge_impulse:g} N s sets the {cabinet.mass:g} kg cabinet "
            f"moving at {cabinet.nudge_impulse / cabinet.mass:g} m/s, above "
            f"{MAX_SHOVE_SPEED:g} m/s (a shove moves a real cabinet a few millimetres)"
        )
    _check_rates(
        loc, substep, stiffness=cabinet.natural_frequency, damping=cabinet.damping / cabinet.mass
    )
    return cabinet


def parse_tilt(value: object, loc: Where, substep: float, gravity: float) -> Tilt:
    """The ``tilt`` section: the bob's rates stable over a ``substep`` [s] under ``gravity``."""
    tilt = record(Tilt, value, loc, TILT_FIELDS)
    if tilt.settle_time >= tilt.warning_time:
        loc.key("settle_time").fail(
            f"{tilt.settle_time:g} s is not shorter than warning_time ({tilt.warning_time:g} s): "
            "a warning would be forgotten while its own swing still counts as it"
        )
    _check_rates(
        loc, substep, bob_length=math.sqrt(gravity / tilt.bob_length), bob_damping=tilt.bob_damping
    )
    return tilt


def _check_rates(loc: Where, substep: float, **rates: float) -> None:
    """Each rate [1/s] times a substep is at most MAX_RATE_PER_SUBSTEP, for a stable integration."""
    for key, rate in rates.items():
        if rate * substep > MAX_RATE_PER_SUBSTEP:
            loc.key(key).fail(
                f"too fast for the substeps: a rate of {rate:g}/s over a substep of "
                f"{substep:g} s is {rate * substep:g}, at most {MAX_RATE_PER_SUBSTEP:g} "
                "(raise simulation.substeps, or soften it)"
            )


def check_whole_cabinet(
    options: Mapping[str, Any], sensors: tuple[Sensor, ...], top: Where
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
                f"no rollover sensor {skill.sensor!r} (rollovers: {listing(rollovers)})"
            )
