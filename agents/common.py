"""What training and evaluation share: the env chain a config describes, run folders, and
atomic writes."""

import importlib
import json
import os
import platform
import re
import tempfile
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np

import pinball_env  # noqa: F401  (registers Pinball-v0)
from agents.config import AnyConfig, ConfigError, TrainConfig, save_config
from pinball_env.heuristic import HeuristicPolicy
from pinball_env.wrappers import SB3VecEnv

CONFIG_FILE = "config.yaml"
MODEL_FILE = "model.zip"
STATS_FILE = "vecnormalize.pkl"
CHECKPOINTS = "checkpoints"
CHECKPOINT_NAME = re.compile(r"step_(\d+)\.zip$")
BASELINES = ("random", "heuristic")

# A policy over a VecEnv: (observations, infos) -> actions.
Policy = Callable[[np.ndarray, list[dict[str, Any]]], np.ndarray]


def make_env(
    config: TrainConfig,
    num_envs: int | None = None,
    seed: int | None = None,
    stats: Path | None = None,
    render: bool = False,
) -> Any:
    """The stable-baselines3 VecEnv a config trains on: the native vector env (``num_envs``
    games, env i first reset with ``seed + i``), frame stacking, and ``VecNormalize``.

    With ``stats`` (a saved ``VecNormalize``), its statistics are loaded and frozen, and rewards
    are left raw: the evaluation's view of the same env.
    """
    from stable_baselines3.common.vec_env import VecFrameStack, VecNormalize, VecTransposeImage

    kwargs = config.env.make_kwargs
    venv = SB3VecEnv(
        gym.make_vec(
            config.env.id, num_envs=num_envs or config.env.num_envs,
            vectorization_mode="vector_entry_point", num_threads=config.env_threads,
            render_mode="rgb_array" if render else None, **kwargs,
        )
    )  # fmt: skip
    venv.seed(config.seed if seed is None else seed)
    image = kwargs.get("obs_type", "state") != "state"
    if config.env.frame_stack > 1:
        venv = VecFrameStack(venv, config.env.frame_stack)
    if image:
        venv = VecTransposeImage(venv)  # channels first, as SB3's CNN wants
    if config.env.normalize:
        if stats is not None:
            venv = VecNormalize.load(str(stats), venv)
            venv.training = False
            venv.norm_reward = False
        else:
            venv = VecNormalize(
                venv, norm_obs=not image, gamma=config.hyperparams.get("gamma", 0.99)
            )
    return venv


class FrameCounter:
    """The frames played by all envs of a VecEnv, counted from each step's infos (a step's
    frames vary with the frame skip, ``skip_above`` and the end of a game)."""

    def __init__(self, num_envs: int, frames: int = 0) -> None:
        self.frames = frames
        self.game_frames = np.zeros(num_envs, dtype=np.int64)  # of each env's game, last step

    def update(self, dones: np.ndarray, infos: list[dict[str, Any]]) -> None:
        for env, (done, info) in enumerate(zip(dones, infos, strict=True)):
            self.frames += int(info["frames"] - self.game_frames[env])
            self.game_frames[env] = 0 if done else info["frames"]


def baseline_policy(name: str, venv: Any, seed: int) -> Policy:
    """``random`` or ``heuristic`` as a function of (observations, infos) -> actions."""
    n = venv.num_envs
    if name == "random":
        rng = np.random.default_rng(seed)
        space = venv.action_space
        return lambda obs, infos: rng.integers(0, space.n, size=n)
    world = venv.get_attr("game")[0].world
    players: dict[int, tuple[Any, HeuristicPolicy]] = {}  # env -> (its table, its player)

    def heuristic(obs: np.ndarray, infos: list[dict[str, Any]]) -> np.ndarray:
        actions = np.empty(n, dtype=np.int64)
        for env, info in enumerate(infos):
            table = world.table_of(env)  # generated tables change from game to game
            if env not in players or players[env][0] is not table:
                players[env] = (table, HeuristicPolicy(table))
            actions[env] = players[env][1](info)
        return actions

    return heuristic


def run_name(config: AnyConfig, when: str) -> str:
    """A run folder's name: env, algorithm (``rllib-ppo`` for RLlib), seed and start time."""
    env = config.env.id.replace("/", "-")
    return f"{env}_{config.label}_seed{config.seed}_{when}"


def start_run(config: AnyConfig, runs: Path, command: list[str], libraries: list[str]) -> Path:
    """Create a run folder (named by ``run_name``) with the exact config and ``meta.json``: the
    versions of pinball_env, gymnasium, torch and ``libraries``, the command, the start time."""
    run = runs / run_name(config, time.strftime("%Y%m%d-%H%M%S"))
    if run.exists():
        raise ConfigError(f"run folder {run} exists already")
    (run / CHECKPOINTS).mkdir(parents=True)
    save_config(config, run / CONFIG_FILE)
    versions = {
        name: importlib.import_module(name).__version__
        for name in ("pinball_env", "gymnasium", "torch", *libraries)
    }
    meta = {
        **versions,
        "python": platform.python_version(),
        "command": command,
        "started": time.strftime("%Y-%m-%dT%H:%M:%S"),
    }
    (run / "meta.json").write_text(json.dumps(meta, indent=1))
    return run


def atomic_write(path: Path, write: Callable[[Any], None]) -> None:
    """Write ``path`` through ``write(file)`` into a temporary file beside it, then rename it
    into place: a run killed mid-write leaves the old file (or none), never half a file."""
    path.parent.mkdir(parents=True, exist_ok=True)
    handle, temporary = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    try:
        with os.fdopen(handle, "wb") as file:
            write(file)
            file.flush()
            os.fsync(file.fileno())
        os.chmod(temporary, 0o644)  # mkstemp's 0600 is for secrets, not models
        os.replace(temporary, path)
    except BaseException:
        Path(temporary).unlink(missing_ok=True)
        raise


def save_model(model: Any, folder: Path, name: str) -> None:
    """Save ``model`` as ``folder/name.zip`` and, when it trains on a ``VecNormalize``, its
    statistics as ``folder/name_vecnormalize.pkl`` (first, so a model never lacks them)."""
    import pickle

    venv = model.get_env()
    if hasattr(venv, "obs_rms"):  # a VecNormalize: it pickles its statistics, not its envs
        atomic_write(folder / f"{name}_{STATS_FILE}", lambda file: pickle.dump(venv, file))
    atomic_write(folder / f"{name}.zip", model.save)


def latest_checkpoint(run: Path) -> tuple[int, Path] | None:
    """``(steps, path)`` of the newest complete checkpoint of a run, or None."""
    found = []
    for path in (run / CHECKPOINTS).glob("step_*.zip"):
        match = CHECKPOINT_NAME.search(path.name)
        if match:
            found.append((int(match.group(1)), path))
    return max(found) if found else None


def stats_for(model_path: Path) -> Path | None:
    """The VecNormalize statistics saved beside a model, if any."""
    stats = model_path.with_name(f"{model_path.stem}_{STATS_FILE}")
    return stats if stats.exists() else None
