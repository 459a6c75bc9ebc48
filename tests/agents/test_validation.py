"""Validation during training (agents.validation): the best model kept, and the report's games
refused before training."""

import csv

import numpy as np
import pytest

from agents import evaluate, train
from agents.envs import make_env_chain
from agents.policy import load_policy
from pinball_env import protocol
from tests.agents.tiny_runs import ROOT, tiny_run


def test_validation_keeps_the_best_model_and_goes_on_after_a_resume(tmp_path, capsys):
    from stable_baselines3 import PPO

    games = ["validate_every=128", "validate_episodes=3"]
    run = tiny_run(ROOT / "configs/agents/ppo.yaml", tmp_path / "runs", *games)
    with open(run / "validation.csv") as file:
        rows = list(csv.DictReader(file))
    assert [int(row["steps"]) for row in rows] == [128, 256]  # the last one: the final model
    best = max(rows, key=lambda row: float(row["score_mean"]))
    assert (run / "model.zip").read_bytes() == (run / "best_model.zip").read_bytes()
    assert PPO.load(run / "model.zip").num_timesteps == int(best["steps"])
    out = capsys.readouterr().out
    assert f"at {best['steps']} steps" in out
    # Each validation says it has begun before its games, then what they scored.
    said = [line.split(":")[0] for line in out.splitlines() if " at " in line and "steps" in line]
    assert said[:4] == ["validating at 128 steps", "validation at 128 steps",
                        "validating at 256 steps", "validation at 256 steps"]  # fmt: skip
    # The model replays its validation games through its saved chain, to the same scores.
    trained = load_policy(run)
    venv = make_env_chain(trained.config, num_envs=3, seed=300_000, frozen=trained.normalization)
    replayed = evaluate.rollouts(
        venv, evaluate.model_policy(trained.model), [300_000, 300_001, 300_002]
    )
    assert np.mean([row["score"] for row in replayed]) == pytest.approx(
        float(best["score_mean"]), abs=0.01
    )
    assert protocol.iqm([row["score"] for row in replayed]) == pytest.approx(
        float(best["score_iqm"]), abs=0.01
    )
    # Those games chose the model: they are not evaluation games.
    with pytest.raises(SystemExit):
        evaluate.main(["--model", str(run), "--episodes", "5", "--seed", "299998"])
    assert "overlap the validation seeds 300000..300002" in capsys.readouterr().err
    # Killed after the first checkpoint and validation: the resume validates on.
    for path in [*run.glob("model*"), *(run / "checkpoints").glob("step_256*")]:
        path.unlink()
    (run / "validation.csv").write_text("".join((run / "validation.csv").open().readlines()[:2]))
    train.main(["--resume", str(run), "--no-progress"])
    with open(run / "validation.csv") as file:
        assert [row["steps"] for row in csv.DictReader(file)] == ["128", "256"]
    assert (run / "model.zip").is_file()


def test_report_games_that_validated_the_model_are_refused_before_training(tmp_path, capsys):
    runs = tmp_path / "runs"
    argv = [
        "--config",
        str(ROOT / "configs/agents/ppo.yaml"),
        "validate_every=128",
        "validate_seed=100100",
        "validate_episodes=100",
        "--runs",
        str(runs),
        "--report",
        "--episodes",
        "101",
    ]
    with pytest.raises(SystemExit):
        train.main(argv)  # fmt: skip
    assert "seeds 100000..100100 overlap the validation seeds 100100..100199" in (
        capsys.readouterr().err
    )
    assert not runs.exists()
