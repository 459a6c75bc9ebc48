"""The speed benchmark's --compare (the same figures for a git revision, alternating) and its
table generation figure, on tiny budgets: shapes and plumbing, never timings."""

import json
import subprocess
from pathlib import Path

import pytest

from benchmarks import compare, speed

ROOT = Path(speed.__file__).resolve().parents[1]


def in_git_checkout() -> bool:
    try:
        compare.git(ROOT, "rev-parse", "HEAD")
    except (OSError, subprocess.CalledProcessError):
        return False
    return True


needs_git = pytest.mark.skipif(not in_git_checkout(), reason="needs the git checkout")


def test_the_command_line():
    args = speed.parser().parse_args(["--quick", "--compare", "b18d650", "--repeats", "3"])
    assert (args.quick, args.compare, args.repeats, args.seed) == (True, "b18d650", 3, 0)
    args = speed.parser().parse_args([])
    assert (args.quick, args.compare, args.repeats, args.json) == (False, None, 1, None)
    with pytest.raises(SystemExit):
        speed.main(["--compare", "HEAD", "--repeats", "0"])
    with pytest.raises(SystemExit):
        speed.main(["--worker", "kernel"])  # without --json-out


def fake_groups(quick, seed):
    def measure():
        pytest.fail("the parent process measures nothing itself")

    return [(name, measure) for name in ("native1024_2thread", "kernel", "sync8_pymunk")]


def test_compare_alternates_and_reports_both_trees_and_the_ratios(monkeypatch, tmp_path, capsys):
    calls = []

    def fake_worker(script, tree, name, quick, seed):
        side = "checkout" if tree == ROOT else "rev"
        calls.append((name, side))
        assert script.read_text() == Path(speed.__file__).read_text()
        if name == "kernel" and side == "checkout":  # a figure the checkout cannot measure
            return {}, "\x1b[1mImportError: no kernel\x1b[0m\nmore"
        if name == "kernel":
            return {"kernel_us_per_ball_frame": 5.0}, None
        value = {"native1024_2thread": 400.0, "sync8_pymunk": 10.0}[name]
        return {f"{name}_steps_per_second": value * (2 if side == "checkout" else 1)}, None

    monkeypatch.setattr(speed, "groups", fake_groups)
    monkeypatch.setattr(compare, "run_worker", fake_worker)
    monkeypatch.setattr(compare, "unpack_revision", lambda repo, rev: ("f" * 40, tmp_path))
    out = tmp_path / "bench.json"
    result = speed.main(["--quick", "--compare", "old", "--repeats", "2", "--json", str(out)])
    saved = json.loads(out.read_text())
    assert saved == json.loads(json.dumps(result))
    # Measurement by measurement, each tree once per repeat, which goes first alternating.
    assert calls == [
        ("native1024_2thread", "checkout"), ("native1024_2thread", "rev"),
        ("kernel", "rev"), ("kernel", "checkout"),
        ("sync8_pymunk", "checkout"), ("sync8_pymunk", "rev"),
        ("native1024_2thread", "rev"), ("native1024_2thread", "checkout"),
        ("kernel", "checkout"), ("kernel", "rev"),
        ("sync8_pymunk", "rev"), ("sync8_pymunk", "checkout"),
    ]  # fmt: skip
    assert list(saved)[:3] == [  # the measurements' order, whichever tree measured them
        "native1024_2thread_steps_per_second",
        "kernel_us_per_ball_frame",
        "sync8_pymunk_steps_per_second",
    ]
    assert saved["native1024_2thread_steps_per_second"] == 800.0
    assert saved["kernel_us_per_ball_frame"] is None
    assert saved["ratio_native1024_2thread_to_sync8_pymunk"] == 40.0
    assert saved["ratio_native1024_2thread_to_cartpole_vec1024"] is None  # not measured
    assert saved["quick"] is True and "cores" in saved["machine"]
    other = saved["compare"]
    assert set(other) == {"rev", "sha", "repeats", "figures", "ratios", "errors"}
    assert (other["rev"], other["sha"], other["repeats"]) == ("old", "f" * 40, 2)
    assert other["figures"]["native1024_2thread_steps_per_second"] == 400.0
    assert other["figures"]["kernel_us_per_ball_frame"] == 5.0
    assert "machine" not in other["figures"] and set(other["ratios"]) == set(other["figures"])
    assert other["ratios"]["native1024_2thread_steps_per_second"] == 2.0
    assert other["ratios"]["ratio_native1024_2thread_to_sync8_pymunk"] == 1.0
    assert other["ratios"]["kernel_us_per_ball_frame"] is None
    assert other["errors"] == {"checkout": {"kernel": "ImportError: no kernel\nmore"}, "rev": {}}
    lines = capsys.readouterr().out.splitlines()
    assert lines[0].split() == ["figure", "checkout", "old", "(fffffff)", "ratio"]
    assert lines[1].split() == ["native1024_2thread_steps_per_second", "800", "400", "2"]
    assert "kernel failed on checkout: ImportError: no kernel" in lines
    assert json.loads(lines[-1]) == saved


@needs_git
def test_a_revision_is_unpacked_once_and_its_workers_import_its_package(monkeypatch, tmp_path):
    monkeypatch.setenv(compare.CACHE_ENV, str(tmp_path / "cache"))
    sha, tree = compare.unpack_revision(ROOT, "HEAD")
    assert tree == tmp_path / "cache" / sha and len(sha) == 40
    assert {path.name for path in tree.iterdir()} == {"pinball_env", "agents", "configs"}
    assert compare.unpack_revision(ROOT, "HEAD") == (sha, tree)  # reused
    with pytest.raises(compare.RevisionError, match="not a revision"):
        compare.unpack_revision(ROOT, "no-such-revision")
    script = tmp_path / "pinball_benchmark.py"
    script.write_text(Path(speed.__file__).read_text())
    # run_worker checks that the worker imported the tree's pinball_env, not the checkout's.
    figures, error = compare.run_worker(script, tree, "cartpole_single", True, 0)
    assert error is None and figures["cartpole_single_steps_per_second"] > 0
    figures, error = compare.run_worker(script, ROOT, "no_such_figure", True, 0)
    assert figures == {} and "KeyError" in error


def test_table_generation_is_timed():
    figures = speed.measure_tablegen(count=1, seed=0)
    assert set(figures) == set(speed.TABLEGEN_FIGURES)
    assert all(isinstance(value, float) and value > 0 for value in figures.values()), figures
