"""The runnable modules: benchmark and table drawing (smoke runs with tiny budgets)."""

import importlib.util
import json

from pinball_env.tools import benchmark, plot


def test_benchmark_prints_and_writes_its_figures(tmp_path, capsys):
    out = tmp_path / "bench.json"
    result = benchmark.main(
        ["--envs", "4", "--frames", "5", "--env-steps", "20", "--json", str(out)]
    )
    saved = json.loads(out.read_text())
    for key in ("ns_per_ball_element_test", "ball_frames_per_second", "env_rgb_steps_per_second"):
        assert saved[key] == result[key] > 0
    assert "ns_per_ball_element_test" in capsys.readouterr().out


def test_draw_renders_tables_and_traces(tmp_path):
    for table in ("classic", "box"):
        out = plot.main([table, "--out", str(tmp_path / f"{table}.png"), "--trace", "30"])
        assert out.stat().st_size > 10_000


def test_the_tools_run_as_modules_of_pinball_env_tools():
    for name in ("demo", "plot", "crosscheck", "benchmark"):
        assert importlib.util.find_spec(f"pinball_env.tools.{name}") is not None, name
