"""The ``rules`` section of a table description: lights, counters, timers and the rules that
name them, parsed into a :class:`~pinball_env.table.rules.RuleSet` (the rules' data model) with
every name checked against what the table declares, and a ring of rules that could fire for ever
in one frame refused.

The section's keys are declared at module level (``RULES_FIELDS`` and the records' maps under
it; the triggers and effects in :mod:`pinball_env.table.rules`), which
:mod:`pinball_env.table.reference` documents."""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from functools import partial
from typing import Any

from pinball_env.table.fields import (
    MAX_SCORE,
    POINT,
    Parser,
    Where,
    bound,
    describe,
    flag,
    list_of,
    listing,
    mapping,
    name_list,
    name_of,
    number,
    records,
    short,
    string,
)
from pinball_env.table.kinds import KINDS
from pinball_env.table.rules import (
    EFFECT_NAMES,
    EFFECTS,
    FLIPPER_BUTTONS,
    TRIGGER_NAMES,
    TRIGGERS,
    Effect,
    Light,
    Rule,
    RuleSet,
    Timer,
    Trigger,
    find_cycle,
)

MAX_RULES = 256  # and as many lights, counters, timers
MAX_MULTIPLIER = 100
MAX_COUNT = 10**6  # a counter's ``at`` and a count's ``by``


def known_names(
    value: object, loc: Where, known: Iterable[str], what: str, min_len: int = 1
) -> tuple[str, ...]:
    """A name or a list of names, each one of ``known`` (a ``what``)."""
    items = [value] if isinstance(value, str) else list_of(value, loc, min_len, MAX_RULES)
    known = list(known)
    for i, name in enumerate(items):
        where = loc if isinstance(value, str) else loc.index(i)
        string(name, where)
        if name not in known:
            where.fail(f"unknown {what} {short(name)} (known: {listing(known) or 'none'})")
    if len(set(items)) != len(items):
        loc.fail(f"a {what} is named twice")
    return tuple(items)


# The keys of the section and of its records, in file order, and their parsers. A timer's
# ``known`` elements are the table's, given at parse time.
LIGHT_FIELDS: dict[str, Parser] = {"name": string, "at": POINT, "lit": flag}
TIMER_FIELDS: dict[str, Any] = {
    "name": string,
    "time": partial(number, low=0.0, high=600.0, open_low=True, unit="s"),
    "factor": partial(number, low=1, high=MAX_MULTIPLIER, integer=True),
    "elements": partial(known_names, known=(), what="element", min_len=0),
}
# A rule's ``when`` holds one trigger (rules.TRIGGER_KEYS) and these keys; each effect of its
# ``do`` holds one effect (rules.EFFECT_KEYS) and these. A mapping declares a mapping's keys
# (each parsed by the code below), a list of one mapping a list of such mappings.
WHEN_FIELDS: dict[str, Parser] = {"at": partial(number, low=1, high=MAX_COUNT, integer=True)}
DO_FIELDS: dict[str, Parser] = {"by": partial(number, low=1, high=MAX_COUNT, integer=True)}
DO_DEFAULTS = {"by": 1}
# The number that each effect without names (rules.EFFECT_KEYS) takes.
EFFECT_NUMBERS: dict[str, Parser] = {
    "score": partial(number, low=1, high=MAX_SCORE, integer=True),
    "bonus": partial(number, low=1, high=MAX_SCORE, integer=True),
    "multiplier": partial(number, low=1, high=MAX_MULTIPLIER, integer=True),
    "extra_ball": partial(number, low=1, high=10, integer=True),
    "add_balls": partial(number, low=1, high=10, integer=True),
    "ball_save": partial(number, low=0.0, high=600.0, open_low=True, unit="s"),
}
# The triggers without names (rules.TRIGGER_KEYS): each takes ``true``.
TRIGGER_FLAGS = ("multiball_starts", "multiball_ends")
RULE_FIELDS: dict[str, Any] = {
    "name": string,
    "when": WHEN_FIELDS,
    "do": [DO_FIELDS],
    "if_lit": string,
}
RULE_OPTIONAL = ("if_lit",)
RULES_FIELDS: dict[str, Any] = {
    "lights": partial(records, Light, parsers=LIGHT_FIELDS, max_len=MAX_RULES),
    "counters": partial(name_list, max_len=MAX_RULES),
    "timers": partial(records, Timer, parsers=TIMER_FIELDS, max_len=MAX_RULES),
    "max_multiplier": partial(number, low=1, high=MAX_MULTIPLIER, integer=True),
    "rules": [RULE_FIELDS],
}


def parse_rules(
    value: object, loc: Where, point: Parser, names: Mapping[str, tuple[str, ...]]
) -> RuleSet:
    """The ``rules`` section; ``names`` lists the table's names of each kind (elements, banks,
    kickbacks) that rules may refer to."""
    raw = mapping(value, loc, [], RULES_FIELDS)
    lights, counters, timers = _declarations(raw, loc, point, names["elements"])
    known = {
        **names,
        "lights": tuple(x.name for x in lights),
        "counters": counters,
        "timers": tuple(x.name for x in timers),
    }
    max_multiplier = RULES_FIELDS["max_multiplier"](
        raw.get("max_multiplier", RuleSet.max_multiplier), loc.key("max_multiplier")
    )
    items = list_of(raw.get("rules", []), loc.key("rules"), 0, MAX_RULES)
    rules = tuple(
        _rule(item, loc.key("rules").index(i, name_of(item)), known) for i, item in enumerate(items)
    )
    named = [rule.name for rule in rules]
    if len(set(named)) != len(named):
        duplicate = next(name for name in named if named.count(name) > 1)
        loc.key("rules").fail(f"two rules are named {short(duplicate)}")
    rule_set = RuleSet(lights, counters, timers, max_multiplier, rules)
    _check_no_ring(rule_set, loc.key("rules"))
    return rule_set


def _declarations(
    raw: Mapping[str, Any], loc: Where, point: Parser, elements: tuple[str, ...]
) -> tuple[tuple[Light, ...], tuple[str, ...], tuple[Timer, ...]]:
    """The lights, counters and timers that the rules name, each name given once; a timer's
    ``elements`` are among the table's ``elements``."""
    fields: dict[str, Any] = bound(RULES_FIELDS, point)  # (timers' takes its parsers too)
    lights = fields["lights"](raw.get("lights", []), loc.key("lights"))
    counters = fields["counters"](raw.get("counters", []), loc.key("counters"))
    timer_fields = {**TIMER_FIELDS, "elements": partial(TIMER_FIELDS["elements"], known=elements)}
    timers = fields["timers"](raw.get("timers", []), loc.key("timers"), parsers=timer_fields)
    for key, items in (("lights", [x.name for x in lights]), ("counters", list(counters)),
                       ("timers", [x.name for x in timers])):  # fmt: skip
        if len(set(items)) != len(items):
            duplicate = next(name for name in items if items.count(name) > 1)
            loc.key(key).fail(f"{short(duplicate)} is named twice")
    return lights, counters, timers


def _check_no_ring(rule_set: RuleSet, loc: Where) -> None:
    """No rules trigger one another in a ring (they could fire for ever in one frame)."""
    cycle = find_cycle(rule_set)
    if cycle:
        ring = " -> ".join(repr(rule_set.rules[i].name) for i in cycle)
        loc.fail(
            f"rules {ring} trigger one another in a ring: they could fire for ever in one frame"
        )


def _rule(value: object, loc: Where, known: Mapping[str, tuple[str, ...]]) -> Rule:
    required = [key for key in RULE_FIELDS if key not in RULE_OPTIONAL]
    raw = mapping(value, loc, required, RULE_OPTIONAL)
    name = string(raw["name"], loc.key("name"))
    when = _trigger(raw["when"], loc.key("when"), known)
    effects = list_of(raw["do"], loc.key("do"), 1, MAX_RULES)
    do = tuple(_effect(item, loc.key("do").index(i), known) for i, item in enumerate(effects))
    if_lit = None
    if "if_lit" in raw:
        if_lit = known_names(raw["if_lit"], loc.key("if_lit"), known["lights"], "light")[0]
        if not isinstance(raw["if_lit"], str):
            loc.key("if_lit").fail(f"expected the name of a light, got {describe(raw['if_lit'])}")
    return Rule(name, when, do, if_lit)


# What each trigger and effect names: the kind of name (a key of the known names) and whether a
# list is allowed; None: a number.

_KIND_WORDS = {"elements": "element", "banks": "drop bank", "lights": "light",
               "buttons": "flipper button", "counters": "counter", "timers": "timer",
               "kickbacks": "kickback", "locks": "lock"}  # fmt: skip


def _one_key(value: object, loc: Where, kinds: tuple[str, ...], extra: tuple[str, ...]) -> str:
    """The one key of ``kinds`` in mapping ``value`` (which may hold ``extra`` keys too)."""
    raw = mapping(value, loc, [], (*kinds, *extra))
    given = [key for key in raw if key in kinds]
    if len(given) != 1:
        loc.fail(f"expected exactly one of {', '.join(kinds)}, got {', '.join(given) or 'none'}")
    return given[0]


def _named(
    value: object, loc: Where, spec: tuple[str, bool], known: Mapping[str, Any]
) -> tuple[str, ...]:
    kind, many = spec
    if not many and not isinstance(value, str):
        loc.fail(f"expected the name of a {_KIND_WORDS[kind]}, got {describe(value)}")
    return known_names(value, loc, known[kind], _KIND_WORDS[kind])


def _trigger(value: object, loc: Where, known: Mapping[str, Any]) -> Trigger:
    kind = _one_key(value, loc, TRIGGERS, tuple(WHEN_FIELDS))
    assert isinstance(value, Mapping)  # (_one_key's)
    spec = TRIGGER_NAMES[kind]
    if spec is None:  # TRIGGER_FLAGS
        if value[kind] is not True:
            loc.key(kind).fail(f"expected true, got {describe(value[kind])}")
        names: tuple[str, ...] = ()
    else:
        names = _named(value[kind], loc.key(kind), spec, known)
    if ("at" in value) != (kind == "counter"):
        loc.fail("'at' goes with a counter trigger, and a counter trigger needs it")
    at = WHEN_FIELDS["at"](value["at"], loc.key("at")) if kind == "counter" else 0
    return Trigger(kind, names, at)


def _effect(value: object, loc: Where, known: Mapping[str, Any]) -> Effect:
    kind = _one_key(value, loc, EFFECTS, tuple(DO_FIELDS))
    assert isinstance(value, Mapping)  # (_one_key's)
    if "by" in value and kind != "count":
        loc.fail("'by' goes with a count effect only")
    spec = EFFECT_NAMES[kind]
    if spec is None:
        return Effect(kind, (), EFFECT_NUMBERS[kind](value[kind], loc.key(kind)))
    names = _named(value[kind], loc.key(kind), spec, known)
    if kind == "rotate" and len(names) < 2:
        loc.key(kind).fail("rotate needs at least two lights")
    by = DO_FIELDS["by"](value.get("by", DO_DEFAULTS["by"]), loc.key("by"))
    return Effect(kind, names, by if kind == "count" else 0)


def rule_names(table_elements: Mapping[str, tuple[Any, ...]]) -> dict[str, tuple[str, ...]]:
    """What the rules of a table with these element groups may name."""
    groups = table_elements
    # Every element kind's (a drop bank's targets, not the bank: banks are named apart).
    elements = [
        member.name
        for kind in KINDS
        for element in groups.get(kind.key, ())
        for member in kind.members(element)
    ]
    return {
        "elements": tuple(elements),
        "banks": tuple(bank.name for bank in groups.get("drop_targets", ())),
        "kickbacks": tuple(k.name for k in groups.get("kickbacks", ())),
        "locks": tuple(lock.name for lock in groups.get("locks", ())),
        "buttons": FLIPPER_BUTTONS,
    }
