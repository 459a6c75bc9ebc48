"""Tiny training runs of the shipped configs, shared by the agents' tests."""

import subprocess
import sys
from pathlib import Path

from agents import train
from agents.config import load_config
from agents.policy import load_policy

ROOT = Path(__file__).resolve().parents[2]
CONFIGS_DIR = ROOT / "configs" / "agents"
# The stable-baselines3 configs (rllib_*.yaml are RLlib's: tests/agents/test_rllib.py).
CONFIGS = sorted(p for p in (ROOT / "configs" / "agents").glob("*.yaml") if "rllib" not in p.name)
# Tiny budgets: a few hundred steps, a couple of envs.
TINY = {
    "ppo": ["hyperparams.n_steps=64", "hyperparams.batch_size=64"],
    "a2c": ["hyperparams.n_steps=8"],
    "dqn": ["hyperparams.learning_starts=64", "hyperparams.buffer_size=1000"],
    "recurrent_ppo": ["hyperparams.n_steps=64", "hyperparams.batch_size=64"],
    "qrdqn": ["hyperparams.learning_starts=64", "hyperparams.buffer_size=1000"],
}


def tiny_overrides(config: Path) -> list[str]:
    loaded = load_config(config)  # (over its base, if it has one)
    warm = ["imitation_steps=64"] if loaded.imitation_steps else []
    validation = ["validate_episodes=2"] if loaded.validate_every else []
    return ["total_timesteps=256", "env.num_envs=2", "checkpoint_every=128", *TINY[loaded.algo],
            *warm, *validation]  # fmt: skip


def tiny_run(config: Path, runs: Path, *extra: str) -> Path:
    overrides = [*tiny_overrides(config), *extra]
    train.main(["--config", str(config), *overrides, "--runs", str(runs), "--no-progress"])
    (run,) = runs.iterdir()
    return run


def strip_agent_entry(model: Path) -> None:
    """Rewrite a model zip without the config and statistics it carries (an older zip)."""
    import zipfile

    from agents.runs import AGENT_ENTRY

    with zipfile.ZipFile(model) as archive:
        entries = {name: archive.read(name) for name in archive.namelist() if name != AGENT_ENTRY}
    with zipfile.ZipFile(model, "w") as archive:
        for name, data in entries.items():
            archive.writestr(name, data)


def start_training(
    runs: Path,
    *overrides: str,
    module: str = "agents.train",
    config: Path = CONFIGS_DIR / "ppo.yaml",
) -> subprocess.Popen:
    """``python -m MODULE --config CONFIG`` with a budget it will not reach, in a process of its
    own (stdout and stderr piped)."""
    command = [sys.executable, "-m", module, "--config", str(config), *overrides,
               "--runs", str(runs), "--no-progress"]  # fmt: skip
    return subprocess.Popen(command, cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True)  # fmt: skip


def wait_for(condition, process: subprocess.Popen, seconds: float = 240.0) -> None:
    import time

    deadline = time.monotonic() + seconds
    while not condition():
        if process.poll() is not None:
            raise AssertionError(f"training ended early: {process.communicate()}")
        if time.monotonic() > deadline:
            process.kill()
            raise AssertionError("timed out waiting for the training")
        time.sleep(0.2)


def logged_rows(runs: Path) -> int:
    files = list(runs.glob("*/progress.csv"))
    return len(files[0].read_text().splitlines()) if files else -1


def readme_example(path: Path, seed: int) -> int:
    """The docs' load_policy example (getting started, agents), as a user would write it."""
    policy = load_policy(path)
    env = policy.make_env()
    obs, info = env.reset(seed=seed)
    terminated = truncated = False
    while not (terminated or truncated):
        obs, _, terminated, truncated, info = env.step(policy.act(obs))
    return info["score"]
