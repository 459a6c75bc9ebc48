"""The table schema: the top level of a table description (its keys, the playfield, the ball, the
optional sections, among them the multiball ones: ``saucers``, ``locks``, ``trough`` and the
ball-ball ``ball.material``), parsed part by part into a frozen
:class:`~pinball_env.table.model.Table`.

:func:`table_from_dict` validates a description (as read from YAML); every mistake (unknown or
missing key, wrong type, non-finite or out-of-range number, bad geometry) raises
:class:`~pinball_env.table.fields.TableError` with the source, the path of the element and the
problem; nothing is silently defaulted. The parts have modules of their own: ``fields`` (the
kinds of value), ``elements`` (the elements' keys and checks, tied to each element kind by the
registry ``kinds``, which :func:`parse_elements` reads), ``cabinet``, ``rules_schema`` (the
``rules`` section) and ``geometry`` (the checks that tie places together); ``serialise`` writes
a table back.

:data:`TABLE_FIELDS` declares the top level's keys in file order (the sections' own maps come
from those modules, the element kinds' from ``kinds``); :mod:`pinball_env.table.reference`
documents the table files from it.
"""

from __future__ import annotations

from collections.abc import Mapping
from functools import partial
from typing import Any

from pinball_env.table import elements as el
from pinball_env.table.cabinet import (
    CABINET_FIELDS,
    TILT_FIELDS,
    check_whole_cabinet,
    parse_cabinet,
    parse_tilt,
)
from pinball_env.table.elements import (
    check_kickers,
    check_names_and_materials,
    parse_materials,
    parse_plunger,
    parse_trough,
)
from pinball_env.table.fields import (
    POINT,
    Parser,
    Where,
    bound,
    in_playfield,
    list_of,
    listing,
    mapping,
    name_of,
    number,
    record,
    short,
    string,
    velocity_pair,
)
from pinball_env.table.geometry import (
    check_held,
    check_launch_path,
    check_outline,
    check_pivots,
    check_placed,
    check_swings,
    solid_walls,
)
from pinball_env.table.kinds import KINDS, ElementKind, kinds_of
from pinball_env.table.model import Table
from pinball_env.table.parts import (
    Ball,
    BallSave,
    Cabinet,
    Material,
    Plunger,
    Simulation,
    Tilt,
    Trough,
)
from pinball_env.table.rules import RuleSet
from pinball_env.table.rules_schema import RULES_FIELDS, parse_rules, rule_names

# Physically sensible ranges of the top level's numbers.
_playfield_size = partial(number, low=0.05, high=5.0, unit="m")  # a real one is ~0.5 x 1 m
PLAYFIELD_FIELDS: dict[str, Parser] = {"width": _playfield_size, "height": _playfield_size}
BALL_FIELDS: dict[str, Parser] = {
    "radius": partial(number, low=0.002, high=0.1, unit="m"),  # a real ball is 13.5 mm
    "mass": partial(number, low=0.001, high=10.0, unit="kg"),  # a real ball is 80 g
    "start": POINT,
    "velocity": velocity_pair,
    "material": string,  # of ball-ball contact: needed by a trough of several balls
}
SIMULATION_FIELDS: dict[str, Parser] = {
    "frame_rate": partial(number, low=1.0, high=1000.0, unit="1/s"),
    "substeps": partial(number, low=1, high=100, integer=True),
    "max_passes": partial(number, low=1, high=100, integer=True),
    "skin": partial(number, low=1e-8, high=1e-4, unit="m"),
    "resting_speed": partial(number, low=0.0, high=1.0, unit="m/s"),
}
BALL_SAVE_FIELDS: dict[str, Parser] = {
    "time": partial(number, low=0.0, high=60.0, open_low=True, unit="s")
}


def _declared(group: str) -> dict[str, Parser]:
    """The declarations of a group of element kinds' lists (see ``kinds``), in file order."""
    return {kind.key: kind.declaration for kind in kinds_of(group)}


# The keys of the top-level mapping in file order: a parser, the declaration of a record (a
# partial of ``record`` or ``records``) or a mapping (``playfield``, whose keys are all required,
# and ``materials``, of any names). ``playfield`` holds Table.width and Table.height; the element
# kinds' lists come from their registry (``kinds``), parsed by ``parse_elements``, and the
# sections are parsed by their modules' code from the same maps.
TABLE_FIELDS: dict[str, Any] = {
    "name": string,
    "playfield": PLAYFIELD_FIELDS,
    "slope_deg": partial(number, low=0.0, high=90.0, open_high=True, unit="deg"),
    "gravity": partial(number, low=0.0, high=100.0, open_low=True, unit="m/s^2"),  # Earth's 9.81
    "ball": partial(record, Ball, parsers=BALL_FIELDS),
    "materials": {"NAME": partial(record, Material, parsers=el.MATERIAL_FIELDS)},
    **_declared("core"),
    "plunger": partial(record, Plunger, parsers=el.PLUNGER_FIELDS),
    "cabinet": partial(record, Cabinet, parsers=CABINET_FIELDS),
    "tilt": partial(record, Tilt, parsers=TILT_FIELDS),
    **_declared("targets"),
    **_declared("multiball"),
    "trough": partial(record, Trough, parsers=el.TROUGH_FIELDS),
    "ball_save": partial(record, BallSave, parsers=BALL_SAVE_FIELDS),
    "rules": partial(record, RuleSet, parsers=RULES_FIELDS),
    "simulation": partial(record, Simulation, parsers=SIMULATION_FIELDS),
}


def table_from_dict(data: Mapping[str, Any], source: str = "<dict>") -> Table:
    """Validate a table description (as read from YAML) into a :class:`Table`."""
    source = source if len(source) <= 200 else short(source)
    top = Where(source)
    raw = mapping(data, top, ["name", "playfield", "ball", "materials"], TABLE_FIELDS)
    playfield = mapping(raw["playfield"], top.key("playfield"), PLAYFIELD_FIELDS)
    width = _playfield_size(playfield["width"], top.key("playfield").key("width"))
    height = _playfield_size(playfield["height"], top.key("playfield").key("height"))
    point = partial(in_playfield, width=width, height=height)
    materials = parse_materials(raw["materials"], top.key("materials"))
    elements: dict[str, Any] = parse_elements(raw, top, point, materials)  # Table's fields
    ball_loc = top.key("ball")
    ball = record(Ball, raw["ball"], ball_loc, bound(BALL_FIELDS, point))
    check_placed(ball.start, ball.radius, elements, ball_loc.key("start"))
    known = [m.name for m in materials]
    if ball.material is not None and ball.material not in known:
        ball_loc.key("material").fail(
            f"unknown material {short(ball.material)} (known: {listing(known)})"
        )
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


def parse_elements(
    raw: Mapping[str, Any], top: Where, point: Parser, materials: tuple[Material, ...]
) -> dict[str, tuple[Any, ...]]:
    """Every element kind's list (see ``kinds``), by key, in file order, checked together:
    unique names, known materials, kickers that lose energy, the segments' total, the outline,
    no flipper pivot in a wall and nothing in a flipper's swing. (The places of held balls need
    the ball's radius: ``geometry.check_held``.)"""
    elements = {kind.key: _kind_list(raw, top, point, kind) for kind in KINDS}
    n_segments = sum(len(wall.segments()) for wall in elements["walls"])
    n_segments += len(elements["standup_targets"])
    if n_segments > el.MAX_SEGMENTS:
        top.key("walls").fail(f"{n_segments} segments in all, at most {el.MAX_SEGMENTS} allowed")
    targets = [t for bank in elements["drop_targets"] for t in bank.targets]
    check_names_and_materials({**elements, "drop_targets.targets": tuple(targets)}, materials, top)
    check_kickers(elements, materials, top)
    check_outline(elements["walls"], top)
    solid = {**elements, "walls": solid_walls(elements)}
    check_pivots(elements["flippers"], solid["walls"], top)
    check_swings(solid, top)
    return elements


def _kind_list(
    raw: Mapping[str, Any], top: Where, point: Parser, kind: ElementKind
) -> tuple[Any, ...]:
    """The optional list ``raw[kind.key]`` of at most ``kind.most`` elements, each parsed and
    checked at its path ``key[i] 'name'``, then checked as a whole."""
    loc = top.key(kind.key)
    parsers = bound(kind.fields, point)
    parsed = []
    for i, item in enumerate(list_of(raw.get(kind.key, []), loc, max_len=kind.most)):
        where = loc.index(i, name_of(item))
        parsed.append(record(kind.model, item, where, parsers))
        if kind.check is not None:
            kind.check(parsed[-1], where)
    if kind.check_all is not None:
        kind.check_all(tuple(parsed), loc)
    return tuple(parsed)


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
    if "trough" in raw:
        sections["trough"] = parse_trough(
            raw["trough"],
            top.key("trough"),
            sections.get("plunger"),
            ball.material,
            top.key("ball"),
        )
    check_held(_held_places(elements, top), ball.radius, elements, sections.get("plunger"))
    if "slope_deg" in raw:
        sections["slope_deg"] = TABLE_FIELDS["slope_deg"](raw["slope_deg"], top.key("slope_deg"))
    if "gravity" in raw:
        sections["gravity"] = TABLE_FIELDS["gravity"](raw["gravity"], top.key("gravity"))
    if "simulation" in raw:
        sections["simulation"] = TABLE_FIELDS["simulation"](
            raw["simulation"], top.key("simulation")
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
        sections["ball_save"] = TABLE_FIELDS["ball_save"](raw["ball_save"], top.key("ball_save"))
    if "rules" in raw:
        sections["rules"] = parse_rules(raw["rules"], top.key("rules"), point, rule_names(elements))
        _check_multiball_rules(sections["rules"], sections.get("trough"), top.key("rules"))
    return sections


def _check_multiball_rules(rules: Any, trough: Any, loc: Where) -> None:
    """The multiball effects need the machine's balls: ``add_balls`` and ``ball_save`` a trough
    of several balls with an auto_plunger."""
    for i, rule in enumerate(rules.rules):
        for j, effect in enumerate(rule.do):
            if effect.kind in ("add_balls", "ball_save") and (
                trough is None or trough.balls < 2 or trough.auto_plunger is None
            ):
                where = loc.key("rules").index(i, rule.name).key("do").index(j).key(effect.kind)
                where.fail("needs a trough of several balls with an auto_plunger")


def _held_places(
    elements: Mapping[str, tuple[Any, ...]], top: Where
) -> list[tuple[Where, tuple[float, float]]]:
    """Where the saucers and locks hold balls, each with its path (``saucers[0] 'x'.center``,
    ``locks[0] 'y'.slots[1]``)."""
    places = [
        (top.key("saucers").index(i, saucer.name).key("center"), saucer.center)
        for i, saucer in enumerate(elements["saucers"])
    ]
    for i, lock in enumerate(elements["locks"]):
        slots = top.key("locks").index(i, lock.name).key("slots")
        places += [(slots.index(j), slot) for j, slot in enumerate(lock.slots)]
    return places
