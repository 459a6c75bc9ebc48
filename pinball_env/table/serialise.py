"""A table written back as a description: :func:`table_to_dict` gives the plain lists and dicts
that :func:`~pinball_env.table.schema.table_from_dict` reads back as the same table (the YAML
files are ``files.dump_table``'s). The element kinds are written as their registry
(:mod:`~pinball_env.table.kinds`) says. Optional sections (targets, rules, the multiball
saucers, locks, trough and ``ball.material``) are written only where a table has them, so that
an older table writes, and digests, as it always did."""

from __future__ import annotations

import dataclasses
import hashlib
import json
from dataclasses import fields
from typing import Any

from pinball_env.table.kinds import KINDS
from pinball_env.table.model import Table
from pinball_env.table.parts import Plunger
from pinball_env.table.rules import EFFECT_NAMES, TRIGGER_NAMES, Effect, RuleSet, Trigger


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
        # The ball-ball material only where set (a table of one ball writes as it did).
        "ball": plain(table.ball, drop=() if table.ball.material else ("material",)),
        "materials": {m.name: plain(m, drop=("name",)) for m in table.materials},
    }
    for kind in KINDS:
        elements = getattr(table, kind.key)
        if elements or kind.written_when_none:
            # A field left unset (None: a lock's radius, the ball's) is left out of the file.
            data[kind.key] = [
                {key: value for key, value in plain(element).items() if value is not None}
                for element in elements
            ]
    if table.trough is not None:
        auto = table.trough.auto_plunger is None
        data["trough"] = plain(table.trough, drop=("auto_plunger",) * auto)
    if table.ball_save is not None:
        data["ball_save"] = plain(table.ball_save)
    if table.rules is not None:
        data["rules"] = rules_to_dict(table.rules)
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


def rules_to_dict(rules: RuleSet) -> dict[str, Any]:
    """The ``rules`` section as :func:`parse_rules` reads it."""

    def names(spec: tuple[str, bool], values: tuple[str, ...]) -> Any:
        return list(values) if spec[1] else values[0]

    def trigger(when: Trigger) -> dict[str, Any]:
        spec = TRIGGER_NAMES[when.kind]
        out = {when.kind: True if spec is None else names(spec, when.names)}
        return {**out, "at": when.at} if when.kind == "counter" else out

    def effect(do: Effect) -> dict[str, Any]:
        spec = EFFECT_NAMES[do.kind]
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
            {
                "name": r.name,
                "when": trigger(r.when),
                "do": [effect(e) for e in r.do],
                **({} if r.if_lit is None else {"if_lit": r.if_lit}),
            }
            for r in rules.rules
        ],
    }


# Digests of the tables last digested, by identity (a table is immutable): a saved game's check
# digests its env's table each time (envs.states), and a vector env's envs share one table.
_DIGESTS: dict[int, tuple[Table, str]] = {}
_DIGESTS_KEPT = 64


def table_sha256(table: Table) -> str:
    """A digest of everything a table file describes (its canonical JSON)."""
    kept = _DIGESTS.get(id(table))
    if kept is not None and kept[0] is table:
        return kept[1]
    text = json.dumps(table_to_dict(table), sort_keys=True)
    digest = hashlib.sha256(text.encode("utf-8")).hexdigest()
    if len(_DIGESTS) >= _DIGESTS_KEPT:
        _DIGESTS.clear()
    _DIGESTS[id(table)] = (table, digest)
    return digest
