"""The multiball elements of a table description: saucers, locks, the trough and
the ball-ball material; their fields, ranges, placement checks and round trip, and the built-in
tables they leave as they were. (Each documented range is refused just outside it by
``test_reference``, which loads this table too.)"""

import dataclasses
import hashlib
import json
import re
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml

from pinball_env.table import (
    Ball,
    Table,
    TableError,
    available_tables,
    builtin_tables_dir,
    dump_table,
    load_table,
    table_from_dict,
    table_to_dict,
)
from pinball_env.table.elements import (
    MAX_BALLS,
    MAX_EJECT_SPEED,
    MAX_LOCK_SLOTS,
    MAX_LOCKS,
    MAX_SAUCERS,
)
from pinball_env.table.parts import AutoPlunger, Lock, Saucer, Trough
from pinball_env.table.reference import schema_fields, schema_limits
from tests.table.multiball import multiball_dict

SOURCE = "multiball.yaml"


def load(data: dict[str, Any]) -> Table:
    return table_from_dict(data, SOURCE)


def refused(change: Callable[[dict[str, Any]], Any], message: str) -> str:
    """The error of the multiball table changed by ``change``, which must match ``message``."""
    data = multiball_dict()
    change(data)
    with pytest.raises(TableError, match=message) as error:
        load(data)
    return str(error.value)


# --- loading and the round trip -------------------------------------------------------------


def test_the_multiball_table_loads() -> None:
    table = load(multiball_dict())
    assert table.saucers == (
        Saucer("right_saucer", (0.40, 0.45), (-1.0, 1.5), 0.02, 0.5, 1.5, 500),
    )
    assert table.locks == (
        Lock("left_lock", ((0.10, 0.45), (0.10, 0.48)), (0.5, -0.5), None, 1.0, 1000),
    )
    assert table.locks[0].capture_radius(table.ball.radius) == table.ball.radius
    assert table.trough == Trough(balls=3, auto_plunger=AutoPlunger(speed=(2.5, 3.0)))
    assert table.ball.material == "steel"
    assert isinstance(table.trough.balls, int)


def test_the_defaults_come_from_the_dataclasses() -> None:
    data = multiball_dict()
    data["saucers"] = [{"name": "s", "center": [0.40, 0.45], "kick": [0.0, 1.0]}]
    data["locks"][0] = {"name": "l", "slots": [[0.10, 0.45]], "kick": [0.0, 1.0]}
    data["trough"] = {}
    del data["ball"]["material"]
    table = load(data)
    assert table.saucers[0] == Saucer("s", (0.40, 0.45), (0.0, 1.0))
    assert (table.saucers[0].radius, table.saucers[0].capture_speed) == (0.02, 0.5)
    assert (table.saucers[0].hold_time, table.saucers[0].score) == (1.0, 0)
    assert table.locks[0] == Lock("l", ((0.10, 0.45),), (0.0, 1.0))
    assert (table.locks[0].radius, table.locks[0].capture_speed) == (None, 1.0)
    assert table.locks[0].capture_radius(0.0135) == 0.0135
    assert dataclasses.replace(table.locks[0], radius=0.02).capture_radius(0.0135) == 0.02
    assert table.trough == Trough(balls=1, auto_plunger=None)
    assert table.ball.material is None


def test_a_table_without_them_has_none() -> None:
    table = load_table("classic_v1")
    assert (table.saucers, table.locks, table.trough, table.ball.material) == ((), (), None, None)
    # Code that builds a Table or a Ball without them keeps working.
    assert Ball(0.0135, 0.08, (0.1, 0.1)).material is None
    assert dataclasses.replace(table, source="x").trough is None


def test_the_round_trip_keeps_them(tmp_path: Path) -> None:
    table = load(multiball_dict())
    data = table_to_dict(table)
    assert table_from_dict(data, SOURCE) == table
    assert data["ball"]["material"] == "steel"
    assert "radius" not in data["locks"][0]  # absent stays absent: the ball's radius
    assert data["trough"] == {"balls": 3, "auto_plunger": {"speed": [2.5, 3.0]}}
    path = dump_table(table, tmp_path / "multiball.yaml")
    assert dataclasses.replace(load_table(path), source=SOURCE) == table
    # A lock's radius where set, and a trough without an auto-plunger, round-trip too.
    raw = multiball_dict()
    raw["locks"][0]["radius"] = 0.02
    raw["trough"] = {"balls": 2}
    table = load(raw)
    assert table_to_dict(table)["locks"][0]["radius"] == 0.02
    assert table_to_dict(table)["trough"] == {"balls": 2}
    assert (
        table_from_dict(
            yaml.safe_load(yaml.safe_dump(table_to_dict(table), sort_keys=False)), SOURCE
        )
        == table
    )


def test_they_are_not_packed_for_the_kernel() -> None:
    """The kernel's arrays and settings are classic_v1's (``sim.World`` plays the multiball
    data); the saucers and locks have element ids after all of classic_v1's."""
    table, classic = load(multiball_dict()), load_table("classic_v1")
    packed, expected = table.pack(), classic.pack()
    assert packed._fields == expected._fields
    for name in expected._fields:
        np.testing.assert_array_equal(getattr(packed, name), getattr(expected, name), err_msg=name)
    assert table.pack_settings() == classic.pack_settings()
    n = len(classic.element_names)
    assert table.element_names == (*classic.element_names, "right_saucer", "left_lock")
    np.testing.assert_array_equal(table.element_scores[:n], classic.element_scores)
    assert table.element_scores[n:].tolist() == [500, 1000]
    assert table.n_balls == 3 and classic.n_balls == 1
    assert table.pack_ball_pair()[:2].tolist() == [0.95, 0.1]
    assert classic.pack_ball_pair()[:2].tolist() == [1.0, 0.0]


# Digests of the built-in tables' descriptions (table_to_dict, as JSON in its key order), taken
# with the loader before the multiball keys: the tables, and what they write, are as they were.
BUILTIN_DIGESTS = {
    "box": "f9dadb76944aa05d83b158750ef915424faa2b9caef25706e26e1b2096ae05f8",
    "classic": "1cefb17a7ee6e664d958808628dc30ba3eb050479c8f5a43079055a1e12b03f0",
    "classic_v1": "aa931bf3ad855ded1e3db9d9db66870e7a7724528b2f1571f13e8744a56d82ef",
    "classic_v2": "1cbb412d18b6d9e5c33b7bb75ee7397e1400e12347baa42a544818f0d6a11201",
}


@pytest.mark.parametrize("name", sorted(BUILTIN_DIGESTS))
def test_the_builtin_tables_write_as_they_did(name: str) -> None:
    # Every built-in table but classic_v3 (Pinball-v3's, the multiball one, newer than the keys).
    assert available_tables("all") == sorted([*BUILTIN_DIGESTS, "classic_v3"])
    table = load_table(name)
    data = table_to_dict(table)
    assert hashlib.sha256(json.dumps(data).encode()).hexdigest() == BUILTIN_DIGESTS[name]
    assert not {"saucers", "locks", "trough"} & set(data) and "material" not in data["ball"]
    assert load_table(builtin_tables_dir() / f"{name}.yaml") == table


# --- the reference --------------------------------------------------------------------------


def test_the_reference_lists_every_new_key() -> None:
    docs = {doc.path: (doc.kind, doc.default) for doc in schema_fields()}
    velocity = f"velocity [vx, vy] in m/s, its speed in (0, {MAX_EJECT_SPEED:g}] m/s"
    assert docs["ball.material"] == ("name", "absent")
    assert docs["saucers"] == (f"list of up to {MAX_SAUCERS} mappings", "[]")
    assert docs["saucers[].name"] == ("name", None)
    assert docs["saucers[].center"] == ("point in the playfield [m]", None)
    assert docs["saucers[].radius"] == ("number in [0.01, 0.1] m", "0.02")
    assert docs["saucers[].capture_speed"] == ("number in [0.05, 5] m/s", "0.5")
    assert docs["saucers[].hold_time"] == ("number in [0.05, 10] s", "1")
    assert docs["saucers[].kick"] == (velocity, None)
    assert docs["saucers[].score"] == ("points 0-1000000", "0")
    assert docs["locks"] == (f"list of up to {MAX_LOCKS} mappings", "[]")
    assert docs["locks[].slots"] == (
        f"list of 1-{MAX_LOCK_SLOTS} points in the playfield [m]",
        None,
    )
    assert docs["locks[].radius"] == ("number in [0.002, 0.1] m", "absent")
    assert docs["locks[].capture_speed"] == ("number in [0.05, 5] m/s", "1")
    assert docs["locks[].kick"] == (velocity, None)
    assert docs["locks[].score"] == ("points 0-1000000", "0")
    assert docs["trough"] == ("mapping", "absent")
    assert docs["trough.balls"] == (f"integer in [1, {MAX_BALLS}]", "1")
    assert docs["trough.auto_plunger"] == ("mapping", "absent")
    assert docs["trough.auto_plunger.speed"] == (
        "pair [min, max], each a number in (0, 20] m/s",
        None,
    )
    limits = "\n".join(schema_limits())
    assert "lock slot" in limits and "ball.material" in limits


# --- ranges and counts ----------------------------------------------------------------------


def test_errors_name_the_element() -> None:
    error = refused(lambda d: d["saucers"][0].update(radius=0.2), "out of range")
    assert error.startswith(f"{SOURCE}: saucers[0] 'right_saucer'.radius: 0.2 is out of range")


@pytest.mark.parametrize("key", ["saucers", "locks"])
@pytest.mark.parametrize("speed", [0.0, MAX_EJECT_SPEED * 1.000001])
def test_a_kick_is_refused_outside_its_speeds(key: str, speed: float) -> None:
    error = refused(lambda d: d[key][0].update(kick=[0.0, speed]), r"\.kick: kick speed")
    assert f"must be in (0, {MAX_EJECT_SPEED:g}]" in error
    data = multiball_dict()
    data[key][0]["kick"] = [0.6 * MAX_EJECT_SPEED, -0.8 * MAX_EJECT_SPEED]  # at the limit
    load(data)


def test_the_counts_are_bounded() -> None:
    def saucers(d: dict[str, Any]) -> None:
        d["saucers"] = [
            {"name": f"s{i}", "center": [0.40, 0.45], "kick": [0.0, 1.0]}
            for i in range(MAX_SAUCERS + 1)
        ]

    refused(saucers, rf"saucers: expected at most {MAX_SAUCERS} items")

    def locks(d: dict[str, Any]) -> None:
        d["locks"] = [dict(d["locks"][0], name=f"l{i}") for i in range(MAX_LOCKS + 1)]

    refused(locks, rf"locks: expected at most {MAX_LOCKS} items")
    slots = [[0.10 + 0.03 * i, 0.45] for i in range(MAX_LOCK_SLOTS + 1)]
    refused(lambda d: d["locks"][0].update(slots=slots), r"slots: expected at most 6 items")
    refused(lambda d: d["locks"][0].update(slots=[]), r"slots: expected at least 1 items")
    # Six slots a little over a ball's diameter apart are fine.
    data = multiball_dict()
    data["locks"][0]["slots"] = slots[:MAX_LOCK_SLOTS]
    assert len(load(data).locks[0].slots) == MAX_LOCK_SLOTS


def test_names_are_unique_across_all_elements() -> None:
    refused(
        lambda d: d["saucers"][0].update(name="bumper_left"),
        r"saucers\[0\] 'bumper_left': duplicate element name 'bumper_left' \(also posts\[0\]",
    )
    refused(
        lambda d: d["locks"][0].update(name="right_saucer"),
        r"locks\[0\] 'right_saucer': duplicate element name .* \(also saucers\[0\]",
    )


def test_unknown_keys_are_refused() -> None:
    refused(lambda d: d["saucers"][0].update(colour=1), r"saucers\[0\] 'right_saucer': unknown key")
    refused(lambda d: d["trough"].update(speed=1), r"trough: unknown key 'speed'")


# --- placement ------------------------------------------------------------------------------


def test_a_saucer_in_a_wall_is_refused() -> None:
    refused(
        lambda d: d["saucers"][0].update(center=[0.468, 0.5]),
        r"saucers\[0\] 'right_saucer'\.center: ball overlaps wall 'lane_wall'",
    )


def test_a_saucer_on_a_post_is_refused() -> None:
    refused(
        lambda d: d["saucers"][0].update(center=[0.16, 0.76]),
        r"saucers\[0\] 'right_saucer'\.center: ball overlaps post 'bumper_left'",
    )


def test_a_lock_slot_outside_the_outline_is_refused() -> None:
    refused(
        lambda d: d["locks"][0]["slots"].append([0.01, 1.06]),
        r"locks\[0\] 'left_lock'\.slots\[2\]: \(0\.01, 1\.06\) is outside the table's outline",
    )


def test_overlapping_slots_are_refused() -> None:
    error = refused(
        lambda d: d["locks"][0].update(slots=[[0.10, 0.45], [0.10, 0.47]]),
        r"locks\[0\] 'left_lock'\.slots\[1\]: a ball held at \(0\.1, 0\.47\) overlaps one at "
        r"locks\[0\] 'left_lock'\.slots\[0\]",
    )
    assert "< the ball's diameter 0.027" in error
    # Just over a diameter apart, the balls do not touch.
    data = multiball_dict()
    data["locks"][0]["slots"] = [[0.10, 0.45], [0.10, 0.4775]]
    load(data)


def test_a_saucer_on_a_lock_slot_is_refused() -> None:
    refused(
        lambda d: d["saucers"][0].update(center=[0.11, 0.47]),
        r"locks\[0\] 'left_lock'\.slots\[0\]: .* overlaps one at saucers\[0\] 'right_saucer'",
    )


def test_a_held_ball_on_the_plunger_is_refused() -> None:
    refused(
        lambda d: d["saucers"][0].update(center=[0.4865, 0.065]),
        r"saucers\[0\] 'right_saucer'\.center: .* overlaps one at plunger\.position",
    )


def test_a_held_ball_in_a_flipper_swing_is_refused() -> None:
    # Clear of the left flipper at rest (-25 deg) but in its way up (to 25 deg).
    refused(
        lambda d: d["locks"][0]["slots"].append([0.2024, 0.1405]),
        r"locks\[0\] 'left_lock'\.slots\[2\]: a ball held here lies in flipper "
        r"'left_flipper''s swing",
    )


# --- the trough and the ball-ball material --------------------------------------------------


def test_several_balls_need_the_ball_material() -> None:
    error = refused(lambda d: d["ball"].pop("material"), r"ball\.material: a trough of 3 balls")
    assert error.startswith(f"{SOURCE}: ball.material: a trough of 3 balls needs the ball-ball")
    # One ball needs none.
    data = multiball_dict()
    del data["ball"]["material"]
    data["trough"]["balls"] = 1
    assert load(data).ball.material is None


def test_the_ball_material_is_a_known_one() -> None:
    refused(
        lambda d: d["ball"].update(material="glass"),
        r"ball\.material: unknown material 'glass' \(known: bumper, flipper",
    )


def test_several_balls_need_a_plunger() -> None:
    data = yaml.safe_load((builtin_tables_dir() / "box.yaml").read_text(encoding="utf-8"))
    data["materials"]["steel"] = {"restitution": 0.95, "friction": 0.1}
    data["ball"]["material"] = "steel"
    data["trough"] = {"balls": 2}
    with pytest.raises(TableError, match=r"trough\.balls: 2 balls need a plunger"):
        table_from_dict(data)
    data["trough"] = {"balls": 1, "auto_plunger": {"speed": [2.0, 3.0]}}
    with pytest.raises(
        TableError, match=r"trough\.auto_plunger: an auto-plunger .* needs a plunger"
    ):
        table_from_dict(data)
    data["trough"] = {"balls": 1}
    assert table_from_dict(data).trough == Trough(1)


def test_the_auto_plunger_speed_is_a_range() -> None:
    refused(
        lambda d: d["trough"]["auto_plunger"].update(speed=[3.0, 2.5]),
        re.escape("trough.auto_plunger.speed: expected [min, max] with min <= max, got [3, 2.5]"),
    )
    refused(
        lambda d: d["trough"]["auto_plunger"].update(speed=[0.0, 2.5]),
        r"trough\.auto_plunger\.speed\[0\]: 0.0 is out of range \(must be \(0, 20\]\)",
    )
    refused(lambda d: d["trough"].update(balls=2.0), r"trough\.balls: expected an integer")
