"""The cross-check against pymunk: agreement at low speed, and where pymunk is wrong."""

import json

import gymnasium as gym
import numpy as np
import pytest

from pinball_env.game.actions import discrete_action
from pinball_env.tools.crosscheck import scenarios as cc
from pinball_env.tools.crosscheck.cli import main


@pytest.mark.parametrize("engine", cc.ENGINES)
def test_low_speed_wall_bounces_agree_with_the_analytic_answer(engine):
    rows = cc.wall_bounces([0.5, 1.0, 2.0, 4.0], [15.0, 30.0, 45.0, 60.0, 75.0, 90.0])
    for row in rows:
        assert cc.agrees(row, engine, row["speed"]), row
    if engine == "swept":  # ours is exact, not just within the tolerance
        assert max(abs(row["swept"]["contact_time_error"]) for row in rows) < 1e-9
        assert max(row["swept"]["velocity_error"] for row in rows) < 1e-9


@pytest.mark.parametrize("engine", cc.ENGINES)
def test_corner_post_and_bumper_hits_agree_with_the_analytic_answer(engine):
    bumper_hits = cc.post_hits([0.0, 0.5, 0.9], restitution=0.9, kick=1.5)
    for row in cc.corner_hits([0.2, 0.5, 0.9]) + cc.post_hits([0.0, 0.5, 0.9]) + bumper_hits:
        assert cc.agrees(row, engine, row["speed"]), row


def test_flipper_scenarios_agree_within_the_flipper_tolerance():
    for row in cc.flipper_drop([0.01, 0.05]):
        assert 0.0 <= row["time_difference"] <= cc.DROP_TIME_TOLERANCE + 1e-9
        assert row["relative_speed_difference"] <= cc.FLIPPER_SPEED_TOLERANCE
    for row in cc.flipper_swing([0.035, 0.05]):
        assert row["relative_difference"] <= cc.FLIPPER_SPEED_TOLERANCE


def test_ours_never_passes_through_and_pymunk_does_at_speed():
    speeds = [1.0, 10.0, 30.0, 100.0, 1000.0]
    result = cc.tunnelling(speeds, trials=30)
    for target in ("wall", "resting flipper", "swinging flipper"):
        assert result[target]["swept"] == [0.0] * len(speeds)
        assert result[target]["pymunk"][0] == 0.0  # slow balls: pymunk is right too
        assert result[target]["pymunk"][-1] > 0.5  # fast balls: mostly through


def test_free_run_is_identical_up_to_the_integration_order_until_the_first_contact():
    run = cc.free_run(10)
    g_h = 9.81 * 0.11320321376790671 / 600  # g sin(6.5 deg) times the substep
    for frame, distance in enumerate(run["divergence"]):
        assert distance == pytest.approx(g_h * (frame + 1) / 60, rel=1e-6)


def test_report_is_written(tmp_path):
    report = main(["--out", str(tmp_path), "--trials", "3", "--frames", "60"])
    saved = json.loads((tmp_path / "crosscheck.json").read_text())
    # The file holds every scenario's rows, as asked, and the tolerances they were judged by.
    assert set(saved) == set(report)
    assert saved["tolerances"]["flipper_relative"] == cc.FLIPPER_SPEED_TOLERANCE
    assert len(saved["wall_bounces"]) == 7 * 6 and saved["tunnelling"]["trials"] == 3
    assert saved["free_run"]["frames"] == 60
    # Every finding is a verdict computed from the rows, and none is a disagreement.
    findings = saved["summary"]["findings"]
    assert len(findings) == 13 and not any("DISAGREE" in finding for finding in findings)
    assert len(saved["ball_ball"]) == 12 and "two_balls_cradled" in saved
    assert (tmp_path / "crosscheck.png").stat().st_size > 10_000


def test_tilted_bumpers_do_not_kick_on_either_engine():
    for row in cc.post_hits([0.0, 0.5, 0.9], restitution=0.9, kick=1.5, tilted=True):
        for engine in cc.ENGINES:
            assert cc.agrees(row, engine, row["speed"]), row


def test_a_nudge_changes_a_free_balls_velocity_by_the_cabinets_change_opposite():
    for row in cc.nudge_free_flight(frames=12):
        for engine in cc.ENGINES:
            assert row[engine]["contacts"] == 0, row["nudge"]
            assert row[engine]["max_velocity_error"] <= cc.ROUNDING, (row["nudge"], engine)


def test_a_nudge_on_a_ball_in_contact_is_what_each_engines_contact_rules_predict():
    rows = cc.nudge_contact()
    assert {row["situation"] for row in rows} == set(cc.NUDGE_SITUATIONS)
    for row in rows:
        assert cc.nudge_agrees(row), row
    # Along the wall: the same friction. Into it: ours bounces, e (J/M + g h) = 0.15 m/s.
    along = [row for row in rows if row.get("expected_difference") == 0.0]
    into = [row for row in rows if row.get("expected_difference", 0.0) > 0.0]
    assert len(along) == 4 and len(into) == 2
    for row in into:
        assert row["expected_difference"] == pytest.approx(0.5 * (0.3 + 1.1105 / 600), rel=1e-3)


def test_plunger_launches_agree_with_the_analytic_flight():
    rows = cc.plunger_launches([0.1, 0.25, 0.5, 1.0])
    assert [row["apex"] is None for row in rows] == [False, False, True, True]
    for row in rows:
        for engine in cc.ENGINES:
            assert cc.plunger_agrees(row, engine), (row, engine)
        if row["apex"] is not None:  # the integration order: exactly v h apart
            apart = row["pymunk"]["apex"] - row["swept"]["apex"]
            assert apart == pytest.approx(row["speed"] * cc.SUBSTEP, rel=1e-6)
        else:
            assert abs(row["pymunk"]["gate_time"] - row["swept"]["gate_time"]) <= cc.SUBSTEP


def test_pinball_v1_on_pymunk_moves_the_cabinet_as_the_kernel_does():
    """Plunge, then shake the cabinet until it tilts: the cabinet (which only the nudges move)
    stays bitwise the same on both engines, frame after frame."""
    envs = {physics: gym.make("Pinball-v1", physics=physics) for physics in cc.ENGINES}
    for env in envs.values():
        env.reset(seed=3)
    plunge = [discrete_action([False, False, True, False, False, False])] * 40 + [0] * 30
    shake = [
        discrete_action([True, True, False, i // 15 % 2 == 0, i // 15 % 2 == 1, False])
        for i in range(120)
    ]
    tilted = dict.fromkeys(cc.ENGINES, False)
    for action in plunge + shake:
        for physics, env in envs.items():
            info = env.step(action)[4]
            tilted[physics] |= bool(info["tilted"])
        swept, pymunk = (envs[p].unwrapped.game.world.state.cabinet for p in cc.ENGINES)
        assert np.array_equal(swept, pymunk)
    assert tilted == {"swept": True, "pymunk": True}


def test_drop_targets_and_spinners_agree_with_pymunk():
    """A drop target bounces a ball as a wall does (analytic), falls, and lets the next through,
    on both engines; a spinner counts the same revolutions on both."""
    drops = cc.target_hits([0.5, 2.0])
    for row in drops:
        for engine in cc.ENGINES:
            assert cc.agrees(row, engine, row["speed"]), (row, engine)
            assert row[engine]["fell"] and row[engine]["passed_when_down"]
    turns = cc.spinner_turns([1.0, 4.0])
    assert turns[0]["swept"] < turns[1]["swept"]
    for row in turns:
        assert abs(row["swept"] - row["pymunk"]) <= 1


def test_ball_ball_shots_agree_with_the_analytic_answer():
    """Head-on, onto a resting ball and oblique, restitution 1 and 0.5: ours exact (momentum,
    and energy at e = 1, to rounding), pymunk within the stated tolerances."""
    rows = cc.ball_ball_hits()
    assert {row["shot"] for row in rows} == set(cc.PAIR_SHOTS) and len(rows) == 12
    for row in rows:
        for engine in cc.ENGINES:
            assert cc.pair_agrees(row, engine), (row, engine)
        assert row["swept"]["velocity_error"] < 1e-9
        assert row["swept"]["momentum_error"] < 1e-12
        assert abs(row["swept"]["contact_time_error"]) < 1e-5  # the skin, at the speed apart
        if row["restitution"] == 1.0:
            before = (
                row["relative_speed"] ** 2 if row["shot"] != "head-on" else 2 * row["speed"] ** 2
            )
            after = np.square(row["swept"]["velocities"]).sum()
            assert after == pytest.approx(before, abs=1e-12)
        if row["angle"] == 0.0:  # head-on: pymunk's impulse is the same, only late
            assert row["pymunk"]["velocity_error"] < 1e-9


def test_two_balls_rest_together_on_a_raised_flipper_without_overlap():
    result = cc.two_balls_cradled()
    g_h = 9.81 * 0.11320321376790671 * cc.SUBSTEP
    for engine in cc.ENGINES:
        assert all(result[engine]["in_play"]) and max(result[engine]["speeds"]) < g_h
    assert result["swept"]["least_gap"] >= 0.0 and result["swept"]["gap"] <= 2e-6
    assert result["pymunk"]["least_gap"] >= -1e-4  # pymunk's collision slop
    assert result["apart"] < 1e-4
