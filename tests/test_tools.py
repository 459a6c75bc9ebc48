"""The runnable modules: the speed benchmark and table drawing (smoke runs with tiny budgets)."""

import importlib.util
import json

import pytest

from benchmarks import speed
from pinball_env.tools import plot, tilt


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


def test_the_tilt_tool_and_picture(tmp_path):
    result = tilt.main(
        ["--envs", "Pinball-v2", "--seconds", "3", "--json", str(tmp_path / "t.json")]
    )
    rows = result["Pinball-v2"]["patterns"]
    assert len(rows) == len(tilt.PATTERNS) * len(tilt.EVERY)
    assert all(row["tilt"] is not None and row["tilt"] <= 3.0 for row in rows)
    assert json.loads((tmp_path / "t.json").read_text()) == result
    out = plot.main(["--tilt", "classic_v1", "classic_v2", "--out", str(tmp_path / "tilt.png")])
    assert out.read_bytes()[:4] == b"\x89PNG" and out.stat().st_size > 20_000
    with pytest.raises(ValueError, match="has no cabinet"):
        plot.main(["--tilt", "classic", "--out", str(tmp_path / "none.png")])


def test_draw_renders_tables_and_traces(tmp_path):
    for table in ("classic", "box"):
        out = plot.main([table, "--out", str(tmp_path / f"{table}.png"), "--trace", "30"])
        assert out.stat().st_size > 10_000


def test_draw_shows_the_cabinet_at_work(tmp_path):
    out = plot.main(["classic_v1", "--cabinet", "--out", str(tmp_path / "cabinet.png")])
    assert out.read_bytes()[:4] == b"\x89PNG" and out.stat().st_size > 20_000
    with pytest.raises(ValueError, match="has no cabinet"):
        plot.main(["classic", "--cabinet", "--out", str(tmp_path / "none.png")])


def test_the_tools_run_as_modules_of_pinball_env_tools():
    for name in ("demo", "plot", "crosscheck", "play", "tilt"):
        assert importlib.util.find_spec(f"pinball_env.tools.{name}") is not None, name
    # The speed benchmark is a developer's tool of the checkout, not a module of the package.
    assert importlib.util.find_spec("pinball_env.tools.benchmark") is None
    assert importlib.util.find_spec("benchmarks.speed") is not None
