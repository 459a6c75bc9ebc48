"""The table schema: the top level of a table description (its keys, the playfield, the ball, the
optional sections), parsed part by part into a frozen :class:`~pinball_env.table.model.Table`.

:func:`table_from_dict` validates a description (as read from YAML); every mistake (unknown or
missing key, wrong type, non-finite or out-of-range number, bad geometry) raises
:class:`~pinball_env.table.fields.TableError` with the source, the path of the element and the
problem; nothing is silently defaulted. The parts have modules of their own: ``fields`` (the
kinds of value), ``elements``, ``cabinet``, ``rules_schema`` (the ``rules`` section) and
``geometry`` (the checks that tie places together); ``serialise`` writes a table back.
"""

from __future__ import annotations

from collections.abc import Mapping
from functools import partial
from typing import Any

from pinball_env.table.cabinet import check_whole_cabinet, parse_cabinet, parse_tilt
from pinball_env.table.elements import parse_elements, parse_materials, parse_plunger
from pinball_env.table.fields import (
    Parser,
    Where,
    in_playfield,
    mapping,
    number,
    record,
    short,
    string,
    velocity_pair,
)
from pinball_env.table.geometry import check_launch_path, check_placed
from pinball_env.table.model import Ball, BallSave, Simulation, Table
from pinball_env.table.rules_schema import parse_rules, rule_names

# Physically sensible ranges of the top level's numbers.
_playfield_size = partial(number, low=0.05, high=5.0)  # [m]: a real playfield is ~0.5 x 1 m
_ball_radius = partial(number, low=0.002, high=0.1)  # [m]: a real ball is 13.5 mm
_ball_mass = partial(number, low=0.001, high=10.0)  # [kg]: a real ball is 80 g
_gravity = partial(number, low=0.0, high=100.0, open_low=True)  # [m/s^2]: Earth's 9.81


def table_from_dict(data: Mapping[str, Any], source: str = "<dict>") -> Table:
    """Validate a table description (as read from YAML) into a :class:`Table`."""
    source = source if len(source) <= 200 else short(source)
    top = Where(source)
    raw = mapping(data, top, ["name", "playfield", "ball", "materials"], _TOP_KEYS)
    playfield = mapping(raw["playfield"], top.key("playfield"), ["width", "height"])
    width = _playfield_size(playfield["width"], top.key("playfield").key("width"))
    height = _playfield_size(playfield["height"], top.key("playfield").key("height"))
    point = partial(in_playfield, width=width, height=height)
    materials = parse_materials(raw["materials"], top.key("materials"))
    elements = parse_elements(raw, top, point, materials)
    ball_loc = top.key("ball")
    ball_parsers = {
        "radius": _ball_radius,
        "mass": _ball_mass,
        "start": point,
        "velocity": velocity_pair,
    }
    ball = record(Ball, raw["ball"], ball_loc, ball_parsers)
    check_placed(ball.start, ball.radius, elements, ball_loc.key("start"))
    return Table(
        name=string(raw["name"], top.key("name")),
        width=width,
        height=height,
        ball=ball,
        materials=materials,
        source=source,
        **elements,
        **_sections(raw, top, point, ball, elements),
    )


def _sections(
    raw: Mapping[str, Any],
    top: Where,
    point: Parser,
    ball: Ball,
    elements: Mapping[str, tuple[Any, ...]],
) -> dict[str, Any]:
    """The optional top-level keys that are given, parsed and checked (the rest default)."""
    sections: dict[str, Any] = {}
    if "plunger" in raw:
        sections["plunger"] = plunger = parse_plunger(raw["plunger"], top.key("plunger"), point)
        position_loc = top.key("plunger").key("position")
        check_placed(plunger.position, ball.radius, elements, position_loc)
        check_launch_path(plunger, elements["walls"], top)
    if "slope_deg" in raw:
        sections["slope_deg"] = number(
            raw["slope_deg"], top.key("slope_deg"), 0.0, 90.0, open_high=True
        )
    if "gravity" in raw:
        sections["gravity"] = _gravity(raw["gravity"], top.key("gravity"))
    if "simulation" in raw:
        simulation_parsers = {
            "frame_rate": partial(number, low=1.0, high=1000.0),
            "substeps": partial(number, low=1, high=100, integer=True),
            "max_passes": partial(number, low=1, high=100, integer=True),
            "skin": partial(number, low=1e-8, high=1e-4),  # [m]
            "resting_speed": partial(number, low=0.0, high=1.0),  # [m/s]
        }
        sections["simulation"] = record(
            Simulation, raw["simulation"], top.key("simulation"), simulation_parsers
        )
    substep = 1.0 / (
        sections.get("simulation", Simulation()).frame_rate
        * sections.get("simulation", Simulation()).substeps
    )
    if "cabinet" in raw:
        sections["cabinet"] = parse_cabinet(raw["cabinet"], top.key("cabinet"), substep)
    if "tilt" in raw:
        gravity = sections.get("gravity", Table.gravity)
        sections["tilt"] = parse_tilt(raw["tilt"], top.key("tilt"), substep, gravity)
    check_whole_cabinet(sections, elements["sensors"], top)
    if "ball_save" in raw:
        sections["ball_save"] = _ball_save(raw["ball_save"], top.key("ball_save"))
    if "rules" in raw:
        sections["rules"] = parse_rules(raw["rules"], top.key("rules"), point, rule_names(elements))
    return sections


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


def _ball_save(value: object, loc: Where) -> BallSave:
    return record(
        BallSave, value, loc, {"time": partial(number, low=0.0, high=60.0, open_low=True)}
    )
