"""Rules as data: the ``rules`` section's schema, its round trip and its errors, and each trigger
and effect played on a scripted ball (classic_v1's rules, and rigs made from them)."""

import copy

import numpy as np
import pytest

from pinball_env.game import Game
from pinball_env.game.rulebook import compile_rules
from pinball_env.table import TableError, load_table, table_from_dict, table_to_dict
from pinball_env.table.rules import BALL_SAVED, BONUS_SCORED, find_cycle

NO_BUTTONS = 0
LEFT = 1  # Pinball-v1's discrete action 1: the left flipper


@pytest.fixture(scope="module")
def classic():
    return load_table("classic_v1")


def with_rules(table, **changes):
    """classic_v1 with its rules section changed (keys replaced)."""
    data = table_to_dict(table)
    data["rules"] = {**data["rules"], **changes}
    return table_from_dict(data, "<rules rig>")


class Scripted:
    """A one-env game on ``table`` whose ball is put where a test wants it."""

    def __init__(self, table):
        self.game = Game(table, 1)
        self.rng = np.random.default_rng(0)
        self.game.new_game(0, self.rng)
        self.info = self.game.info(0)

    def ball(self, position, velocity):
        self.game.world.place_ball(0, position, velocity)
        self.game.state.on_plunger[0] = False

    def step(self, action=NO_BUTTONS, frames=1):
        """Play ``frames`` steps; returns the rule events of all of them."""
        events = {}
        for _ in range(frames):
            self.game.step(np.array([action]), [self.rng])
            self.info = self.game.info(0)
            for name, count in self.info["rule_events"].items():
                events[name] = events.get(name, 0) + count
        return events

    def lights(self):
        return self.game.state.lights[0].tolist()


# --- schema -----------------------------------------------------------------------------------


def test_classic_v1_rules_round_trip(classic):
    again = table_from_dict(copy.deepcopy(table_to_dict(classic)), classic.source)
    assert again == classic
    assert table_to_dict(again) == table_to_dict(classic)


def test_the_rules_run_event_rules_first_then_each_after_what_triggers_it(classic):
    rules = classic.rules
    names = [rules.rules[i].name for i in rules.order()]
    assert names.index("lanes complete") > names.index("lane 3")
    assert names.index("third bank") > names.index("bank down")
    assert not find_cycle(rules)


def bad_rules(classic, rules, match):
    with pytest.raises(TableError, match=match):
        with_rules(classic, rules=rules)


@pytest.mark.parametrize(
    ("rule", "match"),
    [
        ({"name": "r", "when": {"hitt": "lane_1"}, "do": [{"score": 1}]},
         r"rules\.rules\[0\] 'r'\.when: unknown key 'hitt'"),
        ({"name": "r", "when": {"hit": "lane_9"}, "do": [{"score": 1}]},
         r"rules\[0\] 'r'\.when\.hit: unknown element 'lane_9'"),
        ({"name": "r", "when": {"hit": "lane_1"}, "do": [{"light": "nowhere"}]},
         r"rules\[0\] 'r'\.do\[0\]\.light: unknown light 'nowhere'"),
        ({"name": "r", "when": {"hit": "lane_1"}, "do": [{"shout": 1}]},
         r"'r'\.do\[0\]: unknown key 'shout'"),
        ({"name": "r", "when": {"bank": "left_bank"}, "do": [{"score": 1}]},
         r"unknown drop bank 'left_bank'"),
        ({"name": "r", "when": {"counter": "banks_down"}, "do": [{"score": 1}]},
         r"'at' goes with a counter trigger"),
        ({"name": "r", "when": {"hit": "lane_1"}, "do": [{"score": 1, "by": 2}]},
         r"'by' goes with a count effect only"),
        ({"name": "r", "when": {"hit": "lane_1"}, "do": [{"rotate": ["lane_1_lit"]}]},
         r"rotate needs at least two lights"),
        ({"name": "r", "when": {"flipper": "middle"}, "do": [{"score": 1}]},
         r"unknown flipper button 'middle'"),
        ({"name": "r", "when": {"hit": "lane_1", "bank": "right_bank"}, "do": [{"score": 1}]},
         r"expected exactly one of"),
        ({"name": "r", "when": {"hit": "lane_1"}, "do": []}, r"'r'\.do: expected at least 1"),
        ({"name": "r", "when": {"hit": "lane_1"}, "do": [{"score": 0}]}, r"out of range"),
        ({"name": "r", "when": {"timer_ends": "frenzy"}, "do": [{"score": 1}]},
         r"unknown timer 'frenzy'"),
    ],
)  # fmt: skip
def test_bad_rules_are_refused_naming_the_rule(classic, rule, match):
    bad_rules(classic, [rule], match)


def test_rules_that_trigger_each_other_in_a_ring_are_refused(classic):
    ring = [
        {"name": "a", "when": {"lights_on": ["lane_1_lit"]}, "do": [{"count": "banks_down"}]},
        {"name": "b", "when": {"counter": "banks_down", "at": 1}, "do": [{"light": "lane_1_lit"}]},
    ]
    bad_rules(classic, ring, r"rules 'a' -> 'b' -> 'a' trigger one another in a ring")
    selfish = [{"name": "c", "when": {"counter": "banks_down", "at": 2},
                "do": [{"count": "banks_down", "by": 2}]}]  # fmt: skip
    bad_rules(classic, selfish, r"rules 'c' -> 'c' trigger one another")


def test_duplicate_names_are_refused(classic):
    rule = {"name": "r", "when": {"hit": "lane_1"}, "do": [{"score": 1}]}
    bad_rules(classic, [rule, rule], r"two rules are named 'r'")
    with pytest.raises(TableError, match=r"rules\.counters: 'x' is named twice"):
        with_rules(classic, counters=["x", "x"])


def test_bad_targets_are_refused(classic):
    data = table_to_dict(classic)
    data["spinners"][0]["radius"] = 0.5
    with pytest.raises(TableError, match=r"spinners\[0\] 'left_spinner'\.radius: 0\.5 is out of"):
        table_from_dict(data)
    data = table_to_dict(classic)
    data["kickbacks"][0]["kick"] = [0.0, 0.0]
    with pytest.raises(TableError, match=r"kickbacks\[0\] 'left_kickback'\.kick: kick speed 0"):
        table_from_dict(data)
    data = table_to_dict(classic)
    data["drop_targets"][0]["targets"][1]["name"] = "drop_1"
    with pytest.raises(TableError, match=r"duplicate element name 'drop_1'"):
        table_from_dict(data)
    data = table_to_dict(classic)
    data["drop_targets"][0]["reset_time"] = 0.0
    with pytest.raises(TableError, match=r"reset_time: 0\.0 is out of range"):
        table_from_dict(data)
    data = table_to_dict(classic)
    data["standup_targets"][0]["points"] = [[0.0065, 0.64], [0.0065, 0.64]]
    with pytest.raises(TableError, match=r"standup_targets\[0\] 'left_standup'\.points: segment"):
        table_from_dict(data)
    data = table_to_dict(classic)
    data["ball_save"] = {"time": -1.0}
    with pytest.raises(TableError, match=r"ball_save\.time"):
        table_from_dict(data)


# --- triggers and effects on a scripted ball --------------------------------------------------


def test_a_rollover_lights_its_lane_and_adds_to_the_bonus(classic):
    play = Scripted(classic)
    play.ball((0.1855, 0.87), (0.0, 1.0))
    events = play.step(frames=5)
    assert events == {"lane 1": 1}
    assert play.lights() == [True, False, False]
    assert play.info["bonus"] == 100


def test_a_flipper_press_rotates_the_lanes(classic):
    play = Scripted(classic)
    play.game.state.lights[0] = [True, False, False]
    assert play.step(LEFT) == {"lane change": 1}
    assert play.lights() == [False, True, False]
    assert play.step(LEFT) == {}  # held: no new press
    play.step(NO_BUTTONS)
    play.step(LEFT)
    assert play.lights() == [False, False, True]
    play.step(NO_BUTTONS)
    play.step(LEFT)
    assert play.lights() == [True, False, False]


def test_all_lanes_lit_raise_the_multiplier_up_to_its_top(classic):
    play = Scripted(classic)
    for multiplier in (2, 3, 4, 5, 5):
        play.game.state.lights[0] = [True, True, False]
        play.ball((0.2875, 0.87), (0.0, 1.0))
        score = play.info["score"]
        events = play.step(frames=5)
        assert events["lanes complete"] == 1
        assert play.lights() == [False, False, False]
        assert play.info["bonus_multiplier"] == multiplier
        assert play.info["score"] - score == 10 + 500  # the rollover, the award


def knock_down_bank(play):
    """The right bank with two targets already down: a shot at the last."""
    play.game.world.state.targets_up[0] = [False, False, True]
    play.ball((0.40, 0.665), (2.0, 0.0))
    return play.step(frames=10)


def test_the_bank_starts_the_frenzy_lights_the_kickback_and_counts(classic):
    play = Scripted(classic)
    assert not play.game.world.state.kickback_lit[0, 0]
    events = knock_down_bank(play)
    assert events["bank down"] == 1 and events["drop target"] == 1
    assert play.game.world.state.kickback_lit[0, 0]
    assert play.game.state.counters[0, 0] == 1
    assert play.game.state.timers[0, 0] > 0
    # The frenzy doubles the bumpers: a hit of one scores 200.
    play.ball((0.2365, 0.55), (0.0, 1.0))
    points = 0
    for _ in range(10):
        play.step()
        points += play.info["points"]
        if play.info["events"].get("bumper_bottom"):
            break
    assert play.info["events"] == {"bumper_bottom": 1}
    assert points == 200


def test_the_third_bank_is_an_extra_ball(classic):
    play = Scripted(classic)
    play.game.state.counters[0, 0] = 2
    balls = play.info["balls_left"]
    events = knock_down_bank(play)
    assert events["third bank"] == 1
    assert play.info["balls_left"] == balls + 1
    assert play.game.state.counters[0, 0] == 0  # it counts again from 0


def test_a_timer_ends_and_its_mode_with_it(classic):
    rules = [
        {"name": "start", "when": {"hit": "lane_1"}, "do": [{"start_timer": "bumper_frenzy"}]},
        {"name": "over", "when": {"timer_ends": "bumper_frenzy"}, "do": [{"score": 7}]},
    ]
    play = Scripted(with_rules(classic, rules=rules))
    play.ball((0.1855, 0.87), (0.0, 1.0))
    events = play.step(frames=5)
    assert events == {"start": 1}
    frames = play.game.state.timers[0, 0]
    assert 0 < frames <= 20 * 60
    play.game.state.timers[0, 0] = 3
    events = play.step(frames=3)
    assert events == {"over": 1}
    assert play.game.state.timers[0, 0] == 0


def test_the_end_of_ball_bonus_is_multiplied_and_lost_on_a_tilt(classic):
    play = Scripted(classic)
    play.game.state.save_frames[0] = 0  # no ball save
    play.game.state.bonus[0] = 1000
    play.game.state.multiplier[0] = 3
    play.ball((0.2365, 0.08), (0.0, -2.0))
    events = play.step(frames=3)
    assert events == {BONUS_SCORED: 1}
    assert play.info["score"] == 3000
    assert play.info["rule_score"] == 3000
    assert (play.info["bonus"], play.info["bonus_multiplier"]) == (0, 1)
    play.game.state.bonus[0] = 1000
    play.game.world.state.tilted[0] = True
    play.game.state.save_frames[0] = 0
    play.ball((0.2365, 0.08), (0.0, -2.0))
    play.step(frames=3)
    assert play.info["score"] == 3000
    assert play.info["bonus"] == 0


def test_the_ball_save_serves_a_quick_drain_again_once(classic):
    play = Scripted(classic)
    balls = play.info["balls_left"]
    assert play.game.state.save_frames[0] == -1  # it starts at the launch
    play.game.launch(0, play.rng)  # the machine's launch
    assert play.game.state.save_frames[0] == round(6.0 * 60)
    play.ball((0.2365, 0.08), (0.0, -2.0))
    events = play.step(frames=3)
    assert events == {BALL_SAVED: 1}
    assert play.info["balls_left"] == balls
    assert play.info["ball_on_plunger"]  # served again, onto the plunger
    play.game.launch(0, play.rng)
    assert play.game.state.save_frames[0] == 0  # used up for this ball
    play.ball((0.2365, 0.08), (0.0, -2.0))
    play.step(frames=3)
    assert play.info["balls_left"] == balls - 1


def test_a_lit_kickback_saves_an_outlane_ball_once(classic):
    play = Scripted(classic)
    play.game.state.save_frames[0] = 0
    play.game.world.state.kickback_lit[0, 0] = True
    play.ball((0.022, 0.25), (0.0, -1.0))
    for _ in range(20):
        play.step()
        if play.info["events"].get("left_kickback"):
            break
    assert play.info["ball_velocity"][1] > 2.0
    assert not play.game.world.state.kickback_lit[0, 0]
    balls = play.info["balls_left"]
    play.ball((0.022, 0.25), (0.0, -1.0))
    play.step(frames=60)
    assert play.info["balls_left"] == balls - 1  # dark, it lets the next one drain


def test_a_tilted_machine_plays_no_rules(classic):
    play = Scripted(classic)
    play.game.world.state.tilted[0] = True
    play.ball((0.1855, 0.87), (0.0, 1.0))
    assert play.step(frames=5) == {}
    assert play.lights() == [False, False, False]


def test_compile_rules_resolves_names_to_ids(classic):
    book = compile_rules(classic)
    names = classic.element_names
    hit_lane_1 = next(i for i, r in enumerate(classic.rules.rules) if r.name == "lane 1")
    assert [names[i] for i in book.trigger_ids[hit_lane_1] if i >= 0] == ["lane_1"]
    frenzy = [names[i] for i in book.timer_ids[0] if i >= 0]
    assert frenzy == ["bumper_left", "bumper_right", "bumper_bottom"]
    assert book.save_frames == 360 and book.max_multiplier == 5
    assert names[book.first_target] == "drop_1"


def test_bonus_shaping_pays_the_bonus_as_earned_and_sums_to_the_score():
    """With bonus_shaping 1 (and no other shaping) a game's rewards add up to its score times
    reward_scale, as without; the bonus's reward comes where it is earned, not at the drain."""
    import gymnasium as gym

    totals = {}
    for shaping in (0.0, 1.0):
        env = gym.make("Pinball-v1", bonus_shaping=shaping, max_episode_steps=None)
        env.reset(seed=5)
        rng = np.random.default_rng(5)
        total, at_drains, done = 0.0, 0.0, False
        while not done:
            _, reward, terminated, truncated, info = env.step(int(rng.integers(0, 8)))
            total += reward
            if info["rule_events"].get(BONUS_SCORED):
                at_drains += reward
            done = terminated or truncated
        assert total == pytest.approx(info["score"] * 0.01, abs=1e-6)
        totals[shaping] = (info["score"], at_drains)
    assert totals[0.0][0] == totals[1.0][0]  # the same game: shaping changes rewards only
    assert totals[1.0][1] < totals[0.0][1]  # the bonus was paid before the drains


def test_every_env_of_a_game_plays_the_same_rules(classic):
    game = Game(classic, n_envs=2)
    other = with_rules(classic, max_multiplier=3)
    with pytest.raises(ValueError, match="other rules or ball save"):
        game.set_table(1, other)
