"""The runnable modules of pinball_env.tools: the tilt tool and table drawing (smoke runs with
tiny budgets)."""

import importlib.util
import json

import pytest

from pinball_env.tools import plot, tilt


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


def test_draw_shows_a_multiball(tmp_path):
    from pinball_env.table import load_table

    # 2500 steps (42 s): seed 0's first multiball starts at 40 s; the test stops there.
    out = plot.plot_multiball(load_table("classic_v3"), tmp_path / "mb.png", max_frames=2500,
                              tries=1)  # fmt: skip
    assert out.read_bytes()[:4] == b"\x89PNG" and out.stat().st_size > 20_000
    with pytest.raises(ValueError, match="one ball"):
        plot.main(["classic_v2", "--multiball", "--out", str(tmp_path / "none.png")])


def test_the_tools_run_as_modules_of_pinball_env_tools():
    for name in ("demo", "plot", "crosscheck", "play", "tilt", "serve"):
        assert importlib.util.find_spec(f"pinball_env.tools.{name}") is not None, name
    # The speed benchmark is a developer's tool of the checkout, not a module of the package.
    assert importlib.util.find_spec("pinball_env.tools.benchmark") is None
    assert importlib.util.find_spec("benchmarks.speed") is not None
