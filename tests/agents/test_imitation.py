"""The warm start and the anchor (agents.imitation): discounted returns, the fit of the heuristic,
the KL pull back to it, and runs that resume in and after it."""

import csv
import itertools
import json

import numpy as np
import pytest

from agents import train
from agents.config import ConfigError, load_config, sb3_hyperparams
from agents.envs import make_env_chain
from agents.imitation import discounted_returns, imitate, teacher_games
from agents.runs import latest_checkpoint
from tests.agents.tiny_runs import ROOT, tiny_run


def test_discounted_returns_restart_at_each_game_end():
    rewards = np.array([[1.0, 0.0], [2.0, 1.0], [4.0, 0.0]])
    dones = np.array([[False, True], [True, False], [False, False]])
    returns = discounted_returns(rewards, dones, gamma=0.5)
    assert returns[:, 0].tolist() == [2.0, 2.0, 4.0]  # 1 + 0.5 * 2, then a new game: 4
    assert returns[:, 1].tolist() == [0.0, 1.0, 0.0]


def test_the_warm_start_fits_the_heuristic_and_counts_in_the_budget(tmp_path):
    from stable_baselines3 import PPO

    config = load_config(ROOT / "configs/agents/ppo.yaml",
                         ["env.num_envs=8", "env.kwargs.frame_skip=1"])  # fmt: skip
    venv = make_env_chain(config)
    model = PPO("MlpPolicy", venv, seed=0, device="cpu", **sb3_hyperparams(config))
    fit = imitate(model, venv, steps=8000, epochs=5, seed=0)
    games = teacher_games(make_env_chain(config), 1000)
    majority = np.bincount(games["actions"].ravel()).max() / games["actions"].size
    assert fit["steps"] == 8000 and fit["frames"] > fit["steps"]  # skip_above runs frames on
    assert fit["accuracy"] > majority + 0.03  # more than always pressing the usual buttons
    assert venv.obs_rms.count > 8000  # VecNormalize learned from the heuristic's games
    # Through the command line: the fit is logged, and the learning goes on within the budget.
    run = tiny_run(ROOT / "configs/agents/ppo.yaml", tmp_path / "runs", "imitation_steps=512")
    with open(run / "progress.csv") as file:
        row = next(csv.DictReader(file))
    assert float(row["imitation/steps"]) == 512 and float(row["imitation/accuracy"]) > 0.5
    assert int(float(row["time/frames"])) > int(float(row["imitation/frames"]))


def test_the_warm_start_fits_at_its_own_learning_rate():
    from stable_baselines3 import PPO

    config = load_config(ROOT / "configs/agents/ppo.yaml", ["env.num_envs=4"])  # (512 a batch)
    moves = []
    for learning_rate in (None, 1e-30):  # the algorithm's 3e-4, and a rate that moves nothing
        venv = make_env_chain(config)
        model = PPO("MlpPolicy", venv, seed=0, device="cpu", **sb3_hyperparams(config))
        before = [p.detach().clone() for p in model.policy.parameters()]
        imitate(model, venv, steps=256, epochs=1, seed=0, learning_rate=learning_rate)
        after = [p.detach() for p in model.policy.parameters()]
        moves.append(max(float((p - q).abs().max()) for p, q in zip(after, before, strict=True)))
        assert model.policy.optimizer.param_groups[0]["lr"] == pytest.approx(3e-4)  # restored
    assert moves[0] > 1e-4 and moves[1] < 1e-20


def test_the_anchor_pulls_a_drifted_policy_back_to_its_warm_start():
    """KLAnchor: KL(warm start || policy) is 0 at the start, and each pull over a rollout's
    states lowers it; the warm start it keeps is a frozen copy."""
    import torch
    from stable_baselines3 import PPO

    from agents.imitation import KLAnchor

    config = load_config(ROOT / "configs/agents/ppo.yaml", ["env.num_envs=4"])
    venv = make_env_chain(config)
    model = PPO("MlpPolicy", venv, seed=0, device="cpu", **sb3_hyperparams(config))
    anchor = KLAnchor(model.policy, coef=1.0, batch_size=64, seed=0)
    frozen = [p.detach().clone() for p in anchor.reference.parameters()]
    venv.reset()
    actions = [np.array([venv.action_space.sample()] * 4) for _ in range(64)]
    rollout = np.stack([venv.step(action)[0] for action in actions])  # (steps, envs, features)
    anchor.remember(rollout)
    assert anchor.divergence(model.policy) == pytest.approx(0.0, abs=1e-6)
    with torch.no_grad():  # the drift: the action head's weights pushed at random
        for parameter in model.policy.action_net.parameters():
            parameter.add_(torch.randn_like(parameter))
    divergences = [anchor.divergence(model.policy)]
    for _ in range(5):
        anchor.remember(rollout)
        assert anchor.pull(model.policy) == pytest.approx(divergences[-1], rel=1e-5)
        divergences.append(anchor.divergence(model.policy, rollout.reshape(-1, rollout.shape[2])))
    assert divergences[0] > 0.05
    assert all(later < earlier for earlier, later in itertools.pairwise(divergences))
    assert divergences[-1] < divergences[0] / 2
    assert anchor.pull(model.policy) is None  # (the states are forgotten once pulled on)
    kept = zip(anchor.reference.parameters(), frozen, strict=True)
    assert all(torch.equal(now, before) for now, before in kept)


def test_a_warm_start_is_checkpointed_and_an_anchored_run_resumes_from_it(tmp_path, monkeypatch):
    """A finished warm start is checkpoint step_0 with its frames: a run killed after it goes on
    from there without fitting again, its frames counted on; with kl_anchor_coef, the pull's KL is
    logged and a resume takes the warm start from that checkpoint."""
    config = ROOT / "configs/agents/ppo.yaml"
    run = tiny_run(config, tmp_path / "runs", "imitation_steps=64", "kl_anchor_coef=1.0")
    assert (run / "checkpoints/step_0.zip").is_file()
    with open(run / "progress.csv") as file:
        rows = list(csv.DictReader(file))
    warm_frames = int(float(rows[0]["imitation/frames"]))
    kls = [float(row["anchor/kl"]) for row in rows if row.get("anchor/kl")]
    assert kls and all(np.isfinite(kl) and kl >= 0 for kl in kls)
    # The run as a kill right after its warm start leaves it: step_0 and the frames it played.
    for path in [*run.glob("model*"), *run.glob("progress*.csv"), run / "validation.csv"]:
        path.unlink(missing_ok=True)
    for path in (run / "checkpoints").glob("step_*"):
        if not path.name.startswith("step_0.") and not path.name.startswith("step_0_"):
            path.unlink()
    meta = json.loads((run / "meta.json").read_text())
    meta["trained"] = {"steps": 0, "frames": warm_frames}
    (run / "meta.json").write_text(json.dumps(meta))

    def no_second_fit(*args, **kwargs):
        raise AssertionError("the warm start was fitted again")

    monkeypatch.setattr("agents.train.imitate", no_second_fit)
    train.main(["--resume", str(run), "--no-progress"])
    assert latest_checkpoint(run)[0] >= 256
    with open(run / "progress.csv") as file:
        frames = [int(float(row["time/frames"])) for row in csv.DictReader(file)]
    assert frames[0] > warm_frames  # counted on from the warm start's
    # A resume past step 0 takes the warm start from its checkpoint, and needs it.
    train.main(["--resume", str(run), "total_timesteps=512", "--no-progress"])
    assert latest_checkpoint(run)[0] >= 512  # (model.zip is the best validated)
    for path in (run / "checkpoints").glob("step_0*"):
        path.unlink()
    with pytest.raises(ConfigError, match="kl_anchor_coef needs the warm start's checkpoint"):
        train.train(load_config(run / "config.yaml", ["total_timesteps=1024"]), run, resume=True)


def test_a_run_stopped_in_its_warm_start_is_trained_again(tmp_path, monkeypatch, capsys):
    """A stop in the warm start saves no checkpoint (one would skip the rest of the warm start
    for good); the resume trains the run from the start: the run never stopped, bit for bit."""
    import pickle
    import signal

    import torch
    from stable_baselines3 import PPO

    from agents import imitation

    config, overrides = ROOT / "configs/agents/ppo.yaml", ["imitation_steps=64"]
    whole = tiny_run(config, tmp_path / "whole", *overrides)
    fits = []

    def stopped_in_the_fit(*args, **kwargs):
        fits.append(imitation.imitate(*args, **kwargs))
        if len(fits) == 1:
            signal.raise_signal(signal.SIGINT)  # (StopRequest's: the stop turns true)
        return fits[-1]

    monkeypatch.setattr("agents.train.imitate", stopped_in_the_fit)
    with pytest.raises(SystemExit) as exit_:
        tiny_run(config, tmp_path / "runs", *overrides)
    assert exit_.value.code == 128 + signal.SIGINT
    # ... and a KeyboardInterrupt, which pytest re-raises: Ctrl-C stops a test session too.
    assert isinstance(exit_.value, KeyboardInterrupt)
    (run,) = (tmp_path / "runs").iterdir()
    assert latest_checkpoint(run) is None and not (run / "model.zip").exists()
    assert "stopped in the warm start, before learning: nothing saved" in capsys.readouterr().err
    train.main(["--resume", str(run), "--no-progress"])
    assert len(fits) == 2 and "training it again from the start" in capsys.readouterr().out
    trained, again = (PPO.load(path / "model.zip").policy.state_dict() for path in (whole, run))
    assert all(torch.equal(trained[key], again[key]) for key in trained)
    trained, again = (pickle.loads((path / "model_vecnormalize.pkl").read_bytes())
                      for path in (whole, run))  # fmt: skip
    for rms in ("obs_rms", "ret_rms"):
        for moment in ("mean", "var"):
            assert np.array_equal(getattr(getattr(trained, rms), moment),
                                  getattr(getattr(again, rms), moment))  # fmt: skip


def test_ctrl_c_in_a_tests_training_stops_the_test_session(tmp_path):
    """A training run inside a pytest session keeps Ctrl-C only to save its checkpoint: then
    the session stops (pytest's KeyboardInterrupt), and the tests after it do not run."""
    import subprocess
    import sys

    inner = tmp_path / "test_inner.py"
    inner.write_text(
        f"""import signal

from agents import train
from tests.agents.tiny_runs import tiny_run


def test_training(monkeypatch, tmp_path):
    def signalled(*args, **kwargs):  # Ctrl-C, in the warm start
        signal.raise_signal(signal.SIGINT)
        return fitted(*args, **kwargs)

    fitted = train.imitate
    monkeypatch.setattr("agents.train.imitate", signalled)
    tiny_run({str(ROOT / "configs/agents/ppo.yaml")!r}, tmp_path / "runs", "imitation_steps=64")


def test_after():
    open({str(tmp_path / "ran")!r}, "w").close()
"""
    )
    done = subprocess.run(
        [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", "-p", "no:xdist",
         "--rootdir", str(ROOT), str(inner)],
        cwd=ROOT, capture_output=True, text=True, timeout=300,
    )  # fmt: skip
    assert done.returncode == pytest.ExitCode.INTERRUPTED, done.stdout + done.stderr
    assert "CommandInterrupted: 130" in done.stdout and not (tmp_path / "ran").exists()
