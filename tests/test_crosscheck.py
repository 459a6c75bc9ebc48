"""The cross-check against pymunk: agreement at low speed, and where pymunk is wrong."""

import json

import pytest

from pinball_env.tools import crosscheck as cc


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
        assert row["relative_speed_difference"] <= cc.FLIPPER_TOLERANCE
    for row in cc.flipper_swing([0.035, 0.05]):
        assert row["relative_difference"] <= cc.FLIPPER_TOLERANCE


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
    report = cc.main(["--out", str(tmp_path), "--trials", "3", "--frames", "60"])
    saved = json.loads((tmp_path / "crosscheck.json").read_text())
    assert saved["summary"]["findings"] == report["summary"]["findings"]
    assert (tmp_path / "crosscheck.png").stat().st_size > 10_000
