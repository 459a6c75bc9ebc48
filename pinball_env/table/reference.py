"""The reference of the table files, read from the schema's own declarations so that it cannot
drift from the loader: every key a file may hold (:func:`schema_fields`), every trigger and effect
of the rules (:func:`rule_keys`) and the checks that tie several keys together
(:func:`schema_limits`). The documentation's "Tables" page is generated from them.

A field's kind is read from its parser: a ``partial`` of :func:`~pinball_env.table.fields.number`
from its keywords (range, ``integer``, ``unit``), a ``choice`` from its options, the common
parsers from :data:`_KNOWN`, and any other function from its docstring's first line.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from functools import partial
from typing import Any

from pinball_env.table import cabinet, elements
from pinball_env.table.fields import (
    MAX_BALL_SPEED,
    MAX_SCORE,
    POINT,
    choice,
    flag,
    name_list,
    number,
    pair,
    point_list,
    record,
    records,
    score,
    string,
    velocity_pair,
)
from pinball_env.table.model import Table
from pinball_env.table.rules import EFFECT_KEYS, TRIGGER_KEYS, Keyword
from pinball_env.table.rules_schema import (
    DO_DEFAULTS,
    DO_FIELDS,
    EFFECT_NUMBERS,
    MAX_RULES,
    RULE_FIELDS,
    TRIGGER_FLAGS,
    WHEN_FIELDS,
    known_names,
)
from pinball_env.table.schema import TABLE_FIELDS


@dataclass(frozen=True)
class FieldDoc:
    """A key of a table file: its ``path`` (``flippers[].stroke_time``: ``[]`` for any item of a
    list, ``NAME`` for any material name), its ``kind`` (with its range and unit) and its
    ``default`` as text (None: the key is required)."""

    path: str
    kind: str
    default: str | None


@dataclass(frozen=True)
class RuleKey:
    """A trigger (``kind`` "trigger", the key of a rule's ``when``) or an effect ("effect", the
    key of an item of its ``do``) and what it means."""

    kind: str
    key: str
    meaning: str


# Parsers described by a fixed phrase (score is a partial of number, but reads better so).
_KNOWN: dict[Any, str] = {
    string: "name",
    flag: "true/false",
    POINT: "point in the playfield [m]",
    pair: "pair [x, y]",
    velocity_pair: f"velocity [vx, vy] in m/s, at most {MAX_BALL_SPEED:g} m/s",
    score: f"points 0-{MAX_SCORE}",
}
# Functions whose partials are described from their keywords (a partial of record or records
# is also walked into: its keys follow it).
_BY_KEYWORDS: dict[Callable[..., Any], Callable[[dict[str, Any]], str]] = {
    point_list: lambda kw: f"list of {_count(kw)} points in the playfield [m]",
    name_list: lambda kw: f"list of {_count(kw)} names",
    records: lambda kw: f"list of {_count(kw)} mappings",
    record: lambda kw: "mapping",
    choice: lambda kw: f"one of {', '.join(kw['options'])}",
    number: lambda kw: _number(**kw),
    pair: lambda kw: f"pair [min, max], each a {_kind(kw['item'])}",
    known_names: lambda kw: f"{kw['what']} name, or a list of up to {MAX_RULES} {kw['what']} names",
}
# The mappings that the code of the rules parses key by key: their kind (or that of a list of
# them, where they sit in one) and their defaults.
_RULE_MAPPINGS: dict[int, tuple[str, Mapping[str, Any]]] = {
    id(RULE_FIELDS): (
        f"list of up to {MAX_RULES} rules, each a mapping (`if_lit`: the name of a light; the "
        "rule fires only while it is lit)",
        {"if_lit": None},
    ),
    id(WHEN_FIELDS): ("mapping of one trigger (see the rule keys), with `at` for a counter", {}),
    id(DO_FIELDS): (
        f"list of 1-{MAX_RULES} effects, each a mapping of one effect (see the rule keys), "
        "with `by` for a count",
        DO_DEFAULTS,
    ),
}


def schema_fields() -> list[FieldDoc]:
    """Every key a table file may hold, in file order (a mapping's or list's keys after it)."""
    docs: list[FieldDoc] = []
    _walk(TABLE_FIELDS, _defaults(Table), "", docs)
    return docs


def rule_keys() -> list[RuleKey]:
    """Every trigger, then every effect, in the order of their declarations, with what each
    names or the number it takes."""
    return [
        *(RuleKey("trigger", key, _meaning(key, word)) for key, word in TRIGGER_KEYS.items()),
        *(RuleKey("effect", key, _meaning(key, word)) for key, word in EFFECT_KEYS.items()),
    ]


def schema_limits() -> list[str]:
    """The checks that tie several keys (or elements) together, beyond each key's own range."""
    e, c = elements, cabinet
    return [
        f"at most {e.MAX_SEGMENTS} wall segments in all (stand-up targets count as one each)",
        f"at most {e.MAX_DROP_TARGETS} drop targets in all, over all banks",
        f"at least one material, at most {e.MAX_POSTS}",
        "element names are unique over all groups; every material named is declared",
        "a closed wall has at least 3 points; no segment has zero length",
        "a kicking wall or post has a material with restitution < 1",
        f"a flipper's swing |up_angle - rest_angle| is in (0, {e.MAX_SWING:g}] deg",
        "a flipper's |base_radius - tip_radius| < length",
        f"a kickback's kick speed is in (0, {e.MAX_KICKBACK_SPEED:g}] m/s",
        "a saucer's centre and every lock slot (where balls are held) are inside the outline, "
        "clear of every element by the ball's radius, out of every flipper's swing, and at least "
        "a ball's diameter from one another and from the plunger's position",
        "a lock's radius, where absent, is the ball's radius",
        "a trough of more than one ball needs a plunger and ball.material (the ball-ball "
        "material, one of the materials); an auto_plunger needs a plunger, its speed is "
        "[min, max] with min <= max",
        "a plunger's speed and pull_speed are [min, max] with min <= max",
        "a player's plunger has stroke, pull_time and pull_speed together; scatter and "
        "skill_shot need it, and scatter < pull_speed's min",
        "the player's plunger, cabinet and tilt come together, or none of them",
        f"a shove (cabinet.nudge_impulse / mass) is at most {c.MAX_SHOVE_SPEED:g} m/s",
        f"the cabinet's and the bob's rates times a substep are at most {c.MAX_RATE_PER_SUBSTEP:g}",
        "tilt.settle_time < tilt.warning_time",
        "a skill shot's sensor is a rollover (not a drain) of the table",
        "the ball's start and the plunger's position are clear of every element",
        f"at most {MAX_RULES} rules, lights, counters and timers each; names given once",
        "a counter trigger has `at`, no other trigger has; only a count effect has `by`",
        "rotate names at least two lights; rules never trigger one another in a ring",
    ]


def _walk(
    fields: Mapping[str, Any], defaults: Mapping[str, Any], prefix: str, docs: list[FieldDoc]
) -> None:
    """Append the docs of ``fields`` (a record's or mapping's keys) and of the keys under them."""
    for key, decl in fields.items():
        path = f"{prefix}.{key}" if prefix else key
        default = defaults.get(key, dataclasses.MISSING)
        docs.append(FieldDoc(path, _kind(decl), None if _required(default) else _text(default)))
        if isinstance(decl, partial) and decl.func in (record, records):
            inner = path + ("[]" if decl.func is records else "")
            _walk(decl.keywords["parsers"], _defaults(decl.args[0]), inner, docs)
        elif isinstance(decl, (Mapping, list)):  # a list of one mapping: a list of such ones
            nested, path = (decl, path) if isinstance(decl, Mapping) else (decl[0], path + "[]")
            _walk(nested, _RULE_MAPPINGS.get(id(nested), ("", {}))[1], path, docs)


def _kind(decl: Any) -> str:
    """The kind of a declaration: a parser, a mapping or a list of one mapping."""
    if isinstance(decl, list):
        return _RULE_MAPPINGS[id(decl[0])][0]
    if isinstance(decl, Mapping):
        if "NAME" in decl:  # materials
            return f"mapping of 1-{elements.MAX_POSTS} names, each a mapping"
        return _RULE_MAPPINGS.get(id(decl), ("mapping",))[0]
    if decl in _KNOWN:
        return _KNOWN[decl]
    if isinstance(decl, partial) and decl.func in _BY_KEYWORDS:
        return _BY_KEYWORDS[decl.func](dict(decl.keywords))
    func = decl.func if isinstance(decl, partial) else decl
    if not func.__doc__:
        raise ValueError(f"no description for the parser {func!r}")
    return func.__doc__.strip().splitlines()[0]


def _number(
    low: float | None = None,
    high: float | None = None,
    open_low: bool = False,
    open_high: bool = False,
    integer: bool = False,
    unit: str = "",
) -> str:
    """A number parser's kind, phrased as :func:`~pinball_env.table.fields.number`'s messages."""

    def text(x: float) -> str:
        return str(x) if integer else f"{x:g}"

    assert low is not None  # (every number field of a table has its lower bound)
    if high is None:
        interval = f"{'>' if open_low else '>='} {text(low)}"
    else:
        interval = f"{'(' if open_low else '['}{text(low)}, {text(high)}{')' if open_high else ']'}"
    return f"{'integer' if integer else 'number'} in {interval}" + (f" {unit}" if unit else "")


def _count(keywords: Mapping[str, Any]) -> str:
    low, high = keywords.get("min_len", 0), keywords.get("max_len")
    if low == high:
        return str(low)
    return f"up to {high}" if low == 0 else f"{low}-{high}"


def _meaning(key: str, word: Keyword) -> str:
    if word.names is None and key in TRIGGER_FLAGS:
        takes = "true"
    elif word.names is None:
        takes = _kind(EFFECT_NUMBERS[key])
    else:
        kind, many = word.names
        takes = f"{kind}: a name or a list of names" if many else f"{kind}: a name"
    return f"{word.meaning} ({takes})"


def _defaults(cls: type) -> dict[str, Any]:
    return {f.name: f.default for f in dataclasses.fields(cls)}


def _required(default: Any) -> bool:
    return default is dataclasses.MISSING


def _text(value: Any) -> str:
    """A default as it would be written in a file (absent: the key's section is left out)."""
    if value is None:
        return "absent"
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float):
        return f"{value:g}"
    if isinstance(value, tuple):
        return "[" + ", ".join(map(_text, value)) + "]"
    if dataclasses.is_dataclass(value):
        return "{}"  # a section whose keys all default
    return str(value)
