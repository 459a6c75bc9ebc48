"""Training from configs (agents.train): smoke runs of every shipped config, resume after a kill
or a signal, the wall-clock limit, and errors before training."""

import csv
import json
import subprocess
import sys

import pytest

from agents import evaluate, train
from agents.config import load_config
from agents.runs import latest_checkpoint
from tests.agents.tiny_runs import (
    CONFIGS,
    ROOT,
    TINY,
    logged_rows,
    start_training,
    tiny_overrides,
    tiny_run,
    wait_for,
)


@pytest.mark.parametrize("config", CONFIGS, ids=lambda path: path.stem)
def test_every_shipped_config_trains_and_evaluates(config, tmp_path):
    run = tiny_run(config, tmp_path / "runs")
    assert load_config(run / "config.yaml") == load_config(config, tiny_overrides(config))
    meta = json.loads((run / "meta.json").read_text())
    assert meta["pinball_env"] and meta["stable_baselines3"] and meta["torch"]
    assert (run / "model.zip").is_file()
    assert list(run.glob("events.out.tfevents.*")), "TensorBoard logs"
    assert latest_checkpoint(run)[0] >= 256
    summary = evaluate.main(["--model", str(run), "--episodes", "2"])
    assert summary["episodes"] == 2 and summary["seeds"] == [100_000, 100_001]
    with open(run / "eval" / "episodes.csv") as file:
        rows = list(csv.DictReader(file))
    for row in rows:  # whole games: every ball lost, or the two minutes played
        assert row["balls_lost"] == "3" or (row["truncated"] == "True" and row["length"] == "7200")


@pytest.mark.parametrize("config", ["ppo", "dqn"])
def test_a_run_killed_after_a_checkpoint_resumes_from_it(config, tmp_path):
    import pickle

    import stable_baselines3

    algorithm = getattr(stable_baselines3, config.upper())
    run = tiny_run(ROOT / f"configs/agents/{config}.yaml", tmp_path / "runs")
    # As if killed after the first checkpoint: the later ones and the model never written.
    (run / "model.zip").unlink()
    for path in (run / "checkpoints").glob("*"):
        if not path.name.startswith("step_128"):
            path.unlink()
    assert latest_checkpoint(run)[0] == 128
    logged = (run / "progress.csv").read_text()
    train.main(["--resume", str(run), "--no-progress"])
    model = algorithm.load(run / "model.zip")
    assert model.num_timesteps == 256
    assert latest_checkpoint(run)[0] == 256
    assert (run / "progress_0.csv").read_text() == logged  # the curve before the resume kept
    stats = run / "checkpoints/step_128_vecnormalize.pkl"
    if stats.exists():  # the normalisation went on from the checkpoint's statistics
        before = pickle.loads(stats.read_bytes()).obs_rms.count
        after = pickle.loads((run / "model_vecnormalize.pkl").read_bytes()).obs_rms.count
        assert after > before > 1
    if config == "dqn":  # no buffer in a checkpoint: it is refilled before learning again
        assert model.learning_starts == 128 + 64


def test_resume_needs_a_whole_checkpoint(tmp_path, capsys):
    run = tiny_run(ROOT / "configs/agents/ppo.yaml", tmp_path / "runs")
    (run / "checkpoints/step_256_vecnormalize.pkl").unlink()
    with pytest.raises(SystemExit):
        train.main(["--resume", str(run), "--no-progress"])
    assert "step_256.zip: its VecNormalize statistics are missing" in capsys.readouterr().err
    for path in (run / "checkpoints").glob("*"):
        path.unlink()
    with pytest.raises(SystemExit):
        train.main(["--resume", str(run), "--no-progress"])
    assert "no checkpoint to resume from" in capsys.readouterr().err


def test_the_command_line_fails_clearly_before_training(tmp_path, capsys):
    runs = tmp_path / "runs"
    for argv in (
        ["--resume", str(tmp_path / "nothing")],
        ["--config", str(ROOT / "configs/agents/ppo.yaml"), "hyperparams.n_steps=abc"],
        [],
    ):
        with pytest.raises(SystemExit) as exit_:
            train.main([*argv, "--runs", str(runs)])
        assert exit_.value.code == 2
    err = capsys.readouterr().err
    assert "not a run folder" in err and "PPO rejects them" in err and "give --config" in err
    assert not runs.exists() or not any(runs.iterdir())  # no run folder left behind
    with pytest.raises(SystemExit):
        evaluate.main(["--model", str(tmp_path / "nothing")])
    assert "nothing: no such file or folder" in capsys.readouterr().err


def test_rl_zoo3_trains_with_the_shipped_hyperparameters(tmp_path):
    command = [
        sys.executable, "-m", "rl_zoo3.train", "--algo", "ppo", "--env", "Pinball-v0",
        "--gym-packages", "pinball_env", "--conf-file", "configs/agents/rl_zoo3.yml",
        "-n", "256", "--log-folder", str(tmp_path), "--eval-freq", "-1", "--seed", "0",
    ]  # fmt: skip
    done = subprocess.run(command, cwd=ROOT, capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr[-2000:]
    assert "Normalization activated" in done.stdout and "frame_skip': 1" in done.stdout
    assert list(tmp_path.glob("ppo/Pinball-v0_*/Pinball-v0.zip"))


def test_training_stops_at_its_wall_clock_limit(tmp_path):
    run = tiny_run(ROOT / "configs/agents/ppo.yaml", tmp_path / "runs", "total_timesteps=10000000",
                   "max_minutes=0.0001")  # fmt: skip
    from stable_baselines3 import PPO

    steps = PPO.load(run / "model.zip").num_timesteps
    assert 0 < steps < 10_000_000  # stopped in the first rollout past the limit, and saved
    assert latest_checkpoint(run)[0] == steps  # a resume goes on from there


@pytest.mark.parametrize(("signal_name", "warm_start"), [("SIGINT", False), ("SIGTERM", True)])
def test_a_signal_saves_a_checkpoint_and_the_run_resumes_extended(
    tmp_path, signal_name, warm_start
):
    import signal
    import zipfile

    from stable_baselines3 import PPO

    from agents.runs import AGENT_ENTRY

    runs = tmp_path / "runs"
    budget = ["total_timesteps=100000000", "checkpoint_every=0", *TINY["ppo"], "env.num_envs=2"]
    warm = ["imitation_steps=100000000"] if warm_start else ["imitation_steps=0"]
    process = start_training(runs, *budget, *warm)
    # Learning has begun once a row is logged; the warm start, once the log file exists.
    wait_for(lambda: logged_rows(runs) >= (0 if warm_start else 2), process)
    process.send_signal(getattr(signal, signal_name))
    _, err = process.communicate(timeout=120)
    assert process.returncode == 128 + getattr(signal, signal_name), err
    (run,) = runs.iterdir()
    assert "Traceback" not in err
    if warm_start:  # nothing saved (test_a_run_stopped_in_its_warm_start_is_trained_again)
        assert latest_checkpoint(run) is None and "stopped in the warm start" in err
        assert f"--resume {run} (it starts the run again)" in err
        return
    steps, checkpoint = latest_checkpoint(run)
    assert steps >= 128
    assert f"checkpoint {checkpoint}" in err
    assert f"resume with: python -m agents.train --resume {run}" in err
    assert checkpoint.with_name(f"step_{steps}_vecnormalize.pkl").is_file()
    with zipfile.ZipFile(checkpoint) as archive:
        assert json.loads(archive.read(AGENT_ENTRY))["obs_normalization"]["var"]
    # The resume extends the run: a new budget, the same learning.
    train.main(["--resume", str(run), f"total_timesteps={steps + 256}", "--no-progress"])
    assert PPO.load(run / "model.zip").num_timesteps >= steps + 256
    assert load_config(run / "config.yaml").total_timesteps == steps + 256
    meta = json.loads((run / "meta.json").read_text())
    assert meta["resumes"][0]["overrides"] == [f"total_timesteps={steps + 256}"]


def test_a_resume_refuses_keys_that_would_change_what_was_learned(tmp_path, capsys):
    run = tiny_run(ROOT / "configs/agents/ppo.yaml", tmp_path / "runs")
    # A run on an older version says so once, in the project's words (ppo.yaml: Pinball-v0).
    assert capsys.readouterr().out.count("note: Pinball-v0 is an older game than Pinball-v3") == 1
    before = (run / "config.yaml").read_text()
    for key in ("hyperparams.learning_rate=0.1", "env.kwargs.frame_skip=2", "seed=3"):
        with pytest.raises(SystemExit) as exit_:
            train.main(["--resume", str(run), key, "--no-progress"])
        assert exit_.value.code == 2
        name = key.partition("=")[0]
        assert f"--resume: {name!r} would change what the run learned" in capsys.readouterr().err
    assert (run / "config.yaml").read_text() == before
    with pytest.raises(SystemExit):
        train.main(["--resume", str(run), "max_minutes=-1", "--no-progress"])
    assert "max_minutes" in capsys.readouterr().err
    assert (run / "config.yaml").read_text() == before


@pytest.mark.parametrize(("given", "expected"), [(None, "PASSIVE"), ("ACTIVE", "ACTIVE")])
def test_the_agents_make_torchs_threads_wait_passively_unless_told(given, expected):
    # (a training sharing the machine kept a third of its speed with spinning OpenMP threads)
    import os
    import subprocess
    import sys

    env = {key: value for key, value in os.environ.items() if key != "OMP_WAIT_POLICY"}
    if given is not None:
        env["OMP_WAIT_POLICY"] = given
    code = "import agents.train, os, torch; print(os.environ['OMP_WAIT_POLICY'])"
    result = subprocess.run([sys.executable, "-c", code], env=env, cwd=ROOT, check=True,
                            capture_output=True, text=True)  # fmt: skip
    assert result.stdout.strip() == expected
