"""The table reference (pinball_env.table.reference) against the loader and the built-in tables:
every key of a built-in file is documented, every documented range is the one the loader
enforces, and the rule keys are exactly the triggers and effects the parser accepts."""

import copy
import re
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

from pinball_env.table import TableError, table_description, table_from_dict
from pinball_env.table.fields import MAX_SCORE
from pinball_env.table.reference import (
    FieldDoc,
    RuleKey,
    rule_keys,
    schema_fields,
    schema_limits,
)
from tests.table.multiball import multiball_dict

TABLES = sorted((Path(__file__).parents[2] / "pinball_env" / "table" / "tables").glob("*.yaml"))
TRIGGERS = {k.key for k in rule_keys() if k.kind == "trigger"}
EFFECTS = {k.key for k in rule_keys() if k.kind == "effect"}
DOCS = {doc.path: doc for doc in schema_fields()}


def load(name: str) -> dict[str, Any]:
    """A built-in table's data (its base resolved), or ("multiball") classic_v1's with every
    multiball key."""
    if name == "multiball":
        return multiball_dict()
    return table_description(name)


def file_keys(value: Any, path: str = "") -> Iterator[str]:
    """The normalised path of every key in a table file's data: list items as ``[]``, material
    names as ``NAME``, a rule's trigger and effects as ``TRIGGER`` and ``EFFECT``."""
    if isinstance(value, dict):
        for key, item in value.items():
            if path == "materials":
                key = "NAME"
            elif path == "rules.rules[].when" and key in TRIGGERS:
                key = "TRIGGER"
            elif path == "rules.rules[].do[]" and key in EFFECTS:
                key = "EFFECT"
            inner = f"{path}.{key}" if path else key
            yield inner
            if key not in ("TRIGGER", "EFFECT"):  # their names or numbers hold no keys
                yield from file_keys(item, inner)
    elif isinstance(value, list):
        for item in value:
            yield from file_keys(item, path + "[]")


def test_the_docs_are_well_formed() -> None:
    docs = schema_fields()
    assert len({doc.path for doc in docs}) == len(docs)
    assert all(isinstance(doc, FieldDoc) and doc.kind for doc in docs)
    keys = rule_keys()
    assert all(isinstance(key, RuleKey) and key.meaning for key in keys)
    assert {key.kind for key in keys} == {"trigger", "effect"}
    assert all(isinstance(limit, str) for limit in schema_limits())
    # Required keys have no default; the record defaults show as text.
    assert DOCS["flippers[].stroke_time"] == FieldDoc(
        "flippers[].stroke_time", "number in [0.005, 0.2] s", None
    )
    assert DOCS["walls[].closed"].default == "false"
    assert DOCS["slope_deg"].default == "6.5"
    assert DOCS["walls[].points"].kind == "list of 2-1024 points in the playfield [m]"
    assert DOCS["flippers[].button"].kind == "one of left, right"
    assert DOCS["posts[].score"].kind == f"points 0-{MAX_SCORE}"


@pytest.mark.parametrize("path", [*TABLES, "multiball"], ids=lambda p: getattr(p, "stem", p))
def test_every_key_of_a_builtin_table_is_documented(path: Path | str) -> None:
    data = load("multiball") if path == "multiball" else table_description(path)
    missing = {
        key
        for key in file_keys(data)
        if key not in DOCS and not key.endswith((".TRIGGER", ".EFFECT"))
    }
    assert not missing


def test_the_documented_top_level_is_the_loaders() -> None:
    data = load("classic")
    with pytest.raises(TableError, match=r"allowed: ([a-z_, ]+)\)") as error:
        table_from_dict({**data, "no_such_key": 1})
    allowed = re.search(r"allowed: ([a-z_, ]+)\)", str(error.value)).group(1).split(", ")
    assert sorted(allowed) == sorted(path for path in DOCS if "." not in path and "[" not in path)


# --- ranges -----------------------------------------------------------------------------------

_RANGE = re.compile(r"^(number|integer) in ([\[(])(\S+), (\S+?)([\])])")


def ranged() -> list[tuple[str, bool, float, float, bool, bool]]:
    """(path, integer, low, high, open_low, open_high) of every documented numeric range."""
    out = []
    for doc in DOCS.values():
        if doc.kind.startswith("points 0-"):
            out.append((doc.path, True, 0, int(doc.kind.split("-")[1]), False, False))
        elif match := _RANGE.match(doc.kind):
            kind, open_low, low, high, open_high = match.groups()
            integer = kind == "integer"
            cast = int if integer else float
            out.append(
                (doc.path, integer, cast(low), cast(high), open_low == "(", open_high == ")")
            )
    return out


# Keys that only go with another: a counter trigger's ``at``, a count effect's ``by``.
COMPANIONS = {"at": "counter", "by": "count"}


def parent_of(data: dict[str, Any], path: str) -> tuple[dict[str, Any], str] | None:
    """The mapping in ``data`` that holds ``path``'s key (one that has the key or its companion,
    else the first of the list items and materials), and the key; None when the file has no
    such mapping."""
    *parents, key = path.split(".")
    nodes = list(holders(data, parents))
    wanted = [n for n in nodes if key in n or COMPANIONS.get(key) in n]
    node = (wanted or nodes or [None])[0]
    return None if node is None else (node, key)


def holders(node: Any, parents: list[str]) -> Iterator[dict[str, Any]]:
    """Every mapping at the path ``parents`` under ``node`` (each item of a list, each material)."""
    if not parents:
        if isinstance(node, dict):
            yield node
        return
    part, rest = parents[0], parents[1:]
    name = part.removesuffix("[]")
    if not isinstance(node, dict):
        return
    children = list(node.values()) if name == "NAME" else [node.get(name)]
    if part.endswith("[]"):
        children = [item for child in children if isinstance(child, list) for item in child]
    for child in children:
        yield from holders(child, rest)


def cases(name: str) -> list[tuple[str, str, bool, float, float, bool, bool]]:
    data = load(name)
    return [(name, *spec) for spec in ranged() if parent_of(data, spec[0]) is not None]


# classic.yaml's fields, then those that only classic_v1.yaml has (the cabinet, targets, rules),
# then the multiball keys that no built-in table has yet (saucers, locks, trough).
RANGES = cases("classic")
RANGES += [case for case in cases("classic_v1") if case[1] not in {c[1] for c in RANGES}]
RANGES += [case for case in cases("multiball") if case[1] not in {c[1] for c in RANGES}]


def with_value(name: str, path: str, value: float) -> dict[str, Any]:
    data = copy.deepcopy(load(name))
    node, key = parent_of(data, path)
    node[key] = value
    return data


def outside(low: float, high: float, open_low: bool, open_high: bool, integer: bool) -> list:
    step = 1 if integer else 1e-6
    return [low if open_low else low - step * max(1, abs(low)), high if open_high else high + step]


@pytest.mark.parametrize(("table", "path", "integer", "low", "high", "open_low", "open_high"),
                         RANGES, ids=[f"{c[0]}:{c[1]}" for c in RANGES])  # fmt: skip
def test_a_documented_range_is_the_loaders(
    table: str, path: str, integer: bool, low: float, high: float, open_low: bool, open_high: bool
) -> None:
    """Just outside the documented range the loader refuses the value as out of range; at the
    range's ends (just inside an open end) it refuses it for no range of its own (another check,
    such as the substeps' stability, may still object to an extreme value)."""
    key = path.rsplit(".", 1)[-1]
    for value in outside(low, high, open_low, open_high, integer):
        with pytest.raises(TableError, match=rf"\b{key}: \S+ is out of range \(must be"):
            table_from_dict(with_value(table, path, value))
    step = 1e-6 * max(1.0, abs(high))
    for value in (low + step if open_low else low, high - step if open_high else high):
        try:
            table_from_dict(with_value(table, path, value))
        except TableError as error:
            assert not re.search(rf"\b{key}: \S+ is out of range", str(error)), error


# Values inside the documented ranges that classic.yaml takes as they are (nothing else objects).
INSIDE = [
    ("slope_deg", 0.0),
    ("gravity", 100.0),
    ("ball.mass", 10.0),
    ("materials.NAME.friction", 2.0),
    ("walls[].kick", 10.0),
    ("posts[].score", MAX_SCORE),
    ("flippers[].stroke_time", 0.005),
    ("flippers[].return_time", 0.5),
    ("simulation.substeps", 100),
    ("simulation.skin", 1e-8),
]


@pytest.mark.parametrize(("path", "value"), INSIDE)
def test_a_value_inside_a_documented_range_is_accepted(path: str, value: float) -> None:
    spec = next(spec for spec in ranged() if spec[0] == path)
    _, _, low, high, open_low, open_high = spec
    assert (low < value if open_low else low <= value) and (
        value < high if open_high else value <= high
    )
    table_from_dict(with_value("classic", path, value))


# --- rule keys ------------------------------------------------------------------------------


def accepted_keys(where: str) -> set[str]:
    """The triggers (``where`` "when") or effects ("do") that the parser allows, from its error
    for an unknown one, less the keys that go with them (documented as fields)."""
    data = load("classic_v1")
    rule = {"name": "probe", "when": {"hit": data["flippers"][0]["name"]}, "do": [{"score": 1}]}
    rule["when" if where == "when" else "do"] = (
        {"no_such_trigger": 1} if where == "when" else [{"no_such_effect": 1}]
    )
    data["rules"]["rules"] = [*data["rules"]["rules"], rule]
    with pytest.raises(TableError, match=r"unknown key") as error:
        table_from_dict(data)
    allowed = set(re.search(r"allowed: ([a-z_, ]+)\)", str(error.value)).group(1).split(", "))
    extra = {path.rsplit(".", 1)[-1] for path in DOCS if path.startswith(f"rules.rules[].{where}")}
    return allowed - extra


def test_the_rule_keys_are_the_parsers() -> None:
    assert accepted_keys("when") == TRIGGERS
    assert accepted_keys("do") == EFFECTS
    assert len(rule_keys()) == len(TRIGGERS) + len(EFFECTS)
