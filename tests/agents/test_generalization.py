"""The generalization benchmark: a smoke run end to end, the normalisation, and its errors."""

import csv
import json
from pathlib import Path

import numpy as np
import pytest

from agents import generalization
from agents.generalization import TEST_START, normalised

ROOT = Path(__file__).resolve().parents[2]
CONFIG = ROOT / "configs" / "agents" / "procgen_ppo.yaml"
TINY = ["hyperparams.n_steps=16", "hyperparams.batch_size=32", "env.num_envs=2",
        "total_timesteps=96"]  # fmt: skip


def test_the_benchmark_trains_and_tests_each_layout_count(tmp_path):
    out = tmp_path / "bench"
    results = generalization.main(["--config", str(CONFIG), *TINY, "--layouts", "1", "0",
                                   "--test-layouts", "3", "--out", str(out)])  # fmt: skip
    assert [row["layouts"] for row in results] == [1, 0]
    assert [row["train_steps"] for row in results] == [96, 96]
    for row in results:
        for name in ("train", "test"):
            assert set(row[name]) == {"normalised", "ci95", "model", "random", "heuristic"}
        run = out / f"layouts_{row['layouts']}" / row["run"]
        config = (run / "config.yaml").read_text()
        assert f"num_layouts: {row['layouts']}" in config and "start_layout: 0" in config
        assert (run / "model.zip").is_file()
    # The test games are the same for every count: the baselines' scores are shared.
    assert results[0]["test"]["heuristic"] == results[1]["test"]["heuristic"]
    summary = json.loads((out / "generalization.json").read_text())
    assert summary["test_start"] == TEST_START and summary["test_layouts"] == 3
    with open(out / "generalization.csv") as file:
        rows = list(csv.DictReader(file))
    assert [(r["layouts"], r["set"]) for r in rows] == [
        ("1", "train"), ("1", "test"), ("unlimited", "train"), ("unlimited", "test"),
    ]  # fmt: skip
    assert (out / "generalization.png").stat().st_size > 10_000


def test_the_held_out_layouts_are_beyond_every_training_draw():
    from pinball_env.envs.layouts import UNLIMITED_LAYOUTS

    assert TEST_START > UNLIMITED_LAYOUTS


def test_the_score_is_normalised_by_the_baselines_on_the_same_games():
    random = np.array([1000.0, 3000.0, 2000.0, 2000.0])
    heuristic = random + 2000.0
    assert normalised(random, random, heuristic)[0] == 0.0
    assert normalised(heuristic, random, heuristic)[0] == 1.0
    score, (low, high) = normalised(random + 3000.0, random, heuristic)
    assert score == 1.5 and low <= score <= high
    noisy = normalised(np.array([4000.0, 500.0, 6000.0, 100.0]), random, heuristic)
    assert noisy[1][0] < noisy[0] < noisy[1][1]  # a real interval around the estimate


def test_the_benchmark_needs_the_procgen_env(tmp_path, capsys):
    with pytest.raises(SystemExit) as exit_:
        generalization.main(["--config", str(ROOT / "configs/agents/ppo.yaml"),
                             "--out", str(tmp_path)])  # fmt: skip
    assert exit_.value.code == 2
    assert "PinballProcgen-v0" in capsys.readouterr().err
    with pytest.raises(SystemExit):
        generalization.main(["--config", str(CONFIG), "--layouts", "-1"])


def test_no_normalised_score_where_the_heuristic_does_not_beat_random(capsys):
    from agents.generalization import score_set

    random = np.array([5000.0, 4000.0])
    below = score_set(np.array([100.0, 300.0]), random, random - 500.0, "test")
    assert below["normalised"] is None and below["ci95"] is None
    assert (below["model"], below["random"], below["heuristic"]) == (200.0, 4500.0, 4000.0)
    assert "does not beat random" in capsys.readouterr().out
    above = score_set(random + 1000.0, random, random + 1000.0, "test")
    assert above["normalised"] == 1.0
