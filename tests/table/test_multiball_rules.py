"""The multiball's rules as data: the triggers ``locked``, ``multiball_starts`` and
``multiball_ends``, the effects ``release_lock``, ``add_balls`` and ``ball_save``, the ``if_lit``
guard; their errors named as every rule's; classic_v3 round trips and compiles."""

import copy

import numpy as np
import pytest

from pinball_env.game.rulebook import ADD_BALLS, BALL_SAVE, LOCKED, RELEASE_LOCK, compile_rules
from pinball_env.table import TableError, load_table, table_from_dict, table_to_dict


@pytest.fixture(scope="module")
def v3():
    return load_table("classic_v3")


def with_rules(table, rules):
    data = table_to_dict(table)
    data["rules"] = {**data["rules"], "rules": rules}
    return table_from_dict(data, "<rules rig>")


def test_classic_v3_round_trips_and_compiles(v3):
    again = table_from_dict(copy.deepcopy(table_to_dict(v3)), v3.source)
    assert again == v3
    book = compile_rules(v3)
    names = [rule.name for rule in v3.rules.rules]
    lights = [light.name for light in v3.rules.lights]
    assert book.guard[names.index("jackpot")] == lights.index("jackpot_lit")
    assert book.guard[names.index("lock 2")] == lights.index("lock_1_lit")
    assert book.guard[names.index("lock 1")] == -1
    lock_id = v3.element_names.index("upper_lock")
    assert book.trigger_kind[names.index("lock 1")] == LOCKED
    assert lock_id in book.trigger_ids[names.index("lock 1")]
    multiball = names.index("multiball")
    kinds = book.effect_kind[book.effect_start[multiball] : book.effect_start[multiball + 1]]
    assert {RELEASE_LOCK, ADD_BALLS, BALL_SAVE} <= set(kinds.tolist())
    save = book.effect_start[multiball] + kinds.tolist().index(BALL_SAVE)
    assert book.effect_value[save] == 600  # 10 s at 60 frames a second


@pytest.mark.parametrize(
    ("rule", "match"),
    [
        ({"name": "r", "when": {"locked": "lower_lock"}, "do": [{"score": 1}]},
         r"rules\.rules\[0\] 'r'\.when\.locked: unknown lock 'lower_lock'"),
        ({"name": "r", "when": {"multiball_starts": 1}, "do": [{"score": 1}]},
         r"rules\[0\] 'r'\.when\.multiball_starts: expected true"),
        ({"name": "r", "when": {"multiball_ends": True}, "do": [{"release_lock": "x"}]},
         r"rules\[0\] 'r'\.do\[0\]\.release_lock: unknown lock 'x'"),
        ({"name": "r", "when": {"hit": "lane_1"}, "do": [{"add_balls": 0}]},
         r"rules\[0\] 'r'\.do\[0\]\.add_balls: .*out of range"),
        ({"name": "r", "when": {"hit": "lane_1"}, "do": [{"ball_save": -1}]},
         r"rules\[0\] 'r'\.do\[0\]\.ball_save: .*out of range"),
        ({"name": "r", "when": {"hit": "lane_1"}, "if_lit": "nowhere", "do": [{"score": 1}]},
         r"rules\[0\] 'r'\.if_lit: unknown light 'nowhere'"),
        ({"name": "r", "when": {"hit": "lane_1"}, "if_lit": ["jackpot_lit"], "do": [{"score": 1}]},
         r"rules\[0\] 'r'\.if_lit: expected the name of a light"),
        ({"name": "r", "when": {"hit": "lane_1"}, "iff": "jackpot_lit", "do": [{"score": 1}]},
         r"rules\[0\] 'r': unknown key 'iff'"),
    ],
)  # fmt: skip
def test_bad_multiball_rules_are_refused_naming_the_rule(v3, rule, match):
    with pytest.raises(TableError, match=match):
        with_rules(v3, [rule])


@pytest.mark.parametrize("effect", [{"add_balls": 1}, {"ball_save": 5.0}])
def test_the_balls_effects_need_a_trough_with_an_auto_plunger(effect):
    v1 = load_table("classic_v1")
    rule = {"name": "more", "when": {"hit": "lane_1"}, "do": [effect]}
    key = next(iter(effect))
    with pytest.raises(TableError, match=rf"rules\[0\] 'more'\.do\[0\]\.{key}: needs a trough"):
        with_rules(v1, [rule])


def test_if_lit_and_the_flags_round_trip(v3):
    data = table_to_dict(v3)
    rules = {r["name"]: r for r in data["rules"]["rules"]}
    assert rules["jackpot"]["if_lit"] == "jackpot_lit"
    assert rules["jackpot lit"]["when"] == {"multiball_starts": True}
    assert "if_lit" not in rules["lock 1"]
    assert np.isclose(
        next(e for e in rules["multiball"]["do"] if "ball_save" in e)["ball_save"], 10.0
    )
