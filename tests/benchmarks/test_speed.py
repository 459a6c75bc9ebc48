"""The speed benchmark (benchmarks.speed): its figures printed and written, and only those asked
(smoke runs with tiny budgets)."""

import json

import pytest

from benchmarks import speed


def test_benchmark_prints_and_writes_its_figures(tmp_path, capsys):
    out = tmp_path / "bench.json"
    result = speed.main(["--quick", "--json", str(out)])
    saved = json.loads(out.read_text())
    for key in (
        "single_swept_steps_per_second",
        "sync8_pymunk_steps_per_second",
        "native1024_2thread_steps_per_second",
        "native256_grayscale_2thread_steps_per_second",
        "training128_1thread_steps_per_second",
        "cartpole_vec1024_steps_per_second",
        "kernel_ns_per_ball_element_test",
        "startup_warm_seconds",
        "ratio_native1024_2thread_to_sync8_pymunk",
        "v1_native1024_2thread_steps_per_second",
        "ratio_v1_native1024_2thread_to_native1024_2thread",
        "v3_native1024_2thread_steps_per_second",
        "ratio_v3_native1024_2thread_to_v2_native1024_2thread",
        *speed.MULTIBALL_FIGURES.values(),
        "ratio_kernel_3balls_to_1ball",
        "tablegen_ms_per_table",
        "tablegen_targets_ms_per_table",
        "sb3_ppo_env_steps_per_second",
        "sb3_ppo_env_share",
        "sb3_ppo_learner_share",
        *(f"{prefix}_env_steps_per_second" for prefix in speed.SB3_CONFIGS),
        "v1_sb3chain1024_2thread_steps_per_second",
        "ratio_v1_sb3chain1024_2thread_to_v1_native1024_2thread",
    ):
        assert saved[key] == result[key] > 0, key
    for prefix in speed.SB3_CONFIGS:
        shares = saved[f"{prefix}_env_share"] + saved[f"{prefix}_learner_share"]
        assert shares == pytest.approx(1.0)
    assert "compare" not in saved
    assert "native4096_1thread_steps_per_second" in capsys.readouterr().out


def test_benchmark_measures_only_what_it_is_asked(capsys):
    result = speed.main(["--quick", "--only", "kernel", "v1_sb3chain1024_2thread"])
    measured = {key for key, value in result.items() if value is not None}
    assert "kernel_ns_per_ball_element_test" in measured
    assert "v1_sb3chain1024_2thread_steps_per_second" in measured
    assert "single_swept_steps_per_second" not in result
    with pytest.raises(SystemExit):
        speed.main(["--quick", "--only", "no_such_measurement"])
    assert "no measurement no_such_measurement (there are: " in capsys.readouterr().err


def test_multiball_kernel_figure_keeps_its_balls_in_play(monkeypatch):
    from pinball_env.physics import multiball

    step, in_play = multiball.step_multiworld, []

    def counted(*args):
        faults = step(*args)
        in_play.append(int(args[2].active.sum()))  # the State: its ball slots
        return faults

    monkeypatch.setattr(multiball, "step_multiworld", counted)
    figures = speed.measure_multiball(3, 8, 20, 0)
    assert figures[speed.MULTIBALL_FIGURES[3]] > 0
    assert len(in_play) == 120  # 100 untimed frames, then 20
    assert min(in_play[-20:]) >= 8 * 3 - 2  # a drained ball is launched again at once
