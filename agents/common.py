"""What training and evaluation share: the env chain a config describes, run folders, and
atomic writes."""

import importlib
import io
import json
import os
import platform
import re
import signal
import sys
import tempfile
import threading
import time
import zipfile
from collections.abc import Callable
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np

import pinball_env  # noqa: F401  (registers Pinball-v0)
from agents.config import AnyConfig, ConfigError, RllibConfig, TrainConfig, load_config, save_config
from pinball_env.heuristic import HeuristicPolicy
from pinball_env.wrappers import SB3VecEnv

CONFIG_FILE = "config.yaml"
MODEL_FILE = "model.zip"
STATS_FILE = "vecnormalize.pkl"
CHECKPOINTS = "checkpoints"
CHECKPOINT_NAME = re.compile(r"step_(\d+)\.zip$")
# The entry of a model zip that carries its config and observation statistics (agents.policy).
AGENT_ENTRY = "pinball/agent.json"
BASELINES = ("random", "heuristic")

# A policy over a VecEnv: (observations, infos) -> actions.
Policy = Callable[[np.ndarray, list[dict[str, Any]]], np.ndarray]


def make_env(
    config: TrainConfig,
    num_envs: int | None = None,
    seed: int | None = None,
    stats: Path | None = None,
    render: bool = False,
    frozen: Callable[[np.ndarray], np.ndarray] | None = None,
) -> Any:
    """The stable-baselines3 VecEnv a config trains on: the native vector env (``num_envs``
    games, env i first reset with ``seed + i``), frame stacking, and ``VecNormalize``.

    With ``stats`` (a saved ``VecNormalize``), its statistics are loaded and frozen, and rewards
    are left raw; with ``frozen`` (a policy's ``ObsNormalization``), observations are
    normalised by it instead: either is the evaluation's view of the same env.
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
    if frozen is not None:
        venv = frozen_observations(venv, frozen)
    elif config.env.normalize:
        if stats is not None:
            venv = VecNormalize.load(str(stats), venv)
            venv.training = False
            venv.norm_reward = False
        else:
            venv = VecNormalize(
                venv, norm_obs=not image, gamma=config.hyperparams.get("gamma", 0.99)
            )
    return venv


def frozen_observations(venv: Any, normalise: Callable[[np.ndarray], np.ndarray]) -> Any:
    """``venv`` with its observations (and terminal observations) passed through
    ``normalise``: a saved policy's frozen statistics, rewards left raw."""
    from stable_baselines3.common.vec_env import VecEnvWrapper

    class Frozen(VecEnvWrapper):
        def reset(self) -> np.ndarray:
            return normalise(self.venv.reset())

        def step_wait(self) -> Any:
            obs, rewards, dones, infos = self.venv.step_wait()
            for info in infos:
                if "terminal_observation" in info:
                    info["terminal_observation"] = normalise(info["terminal_observation"])
            return normalise(obs), rewards, dones, infos

    return Frozen(venv)


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


class StopRequest:
    """SIGINT (Ctrl-C) and SIGTERM, while a training runs inside ``with StopRequest() as
    stop:``, ask it to stop: ``stop`` turns true (``stop.signal`` names the signal) and the
    training saves a checkpoint at its next step and says how to resume. A second SIGINT
    stops at once (KeyboardInterrupt). Outside the main thread it installs nothing."""

    SIGNALS = (signal.SIGINT, signal.SIGTERM)

    def __init__(self) -> None:
        self.signal: signal.Signals | None = None
        self._previous: dict[int, Any] = {}

    def __enter__(self) -> "StopRequest":
        if threading.current_thread() is threading.main_thread():
            self._previous = {sig: signal.signal(sig, self._handle) for sig in self.SIGNALS}
        return self

    def __exit__(self, *exc: object) -> None:
        for sig, handler in self._previous.items():
            signal.signal(sig, handler)
        self._previous = {}

    def __bool__(self) -> bool:
        return self.signal is not None

    def _handle(self, signum: int, frame: Any) -> None:
        if self.signal is not None and signum == signal.SIGINT:
            raise KeyboardInterrupt
        self.signal = signal.Signals(signum)
        print(
            f"\n{self.signal.name}: saving a checkpoint, then stopping "
            "(Ctrl-C again stops at once, saving nothing)", file=sys.stderr, flush=True,
        )  # fmt: skip


class ProgressBar:
    """A tqdm bar of the env steps to ``total_timesteps`` whose remaining time honours
    ``max_minutes``: while the deadline would come first, the bar's end is the step it will
    reach by then at the session's rate so far (shown as ``stops at max_minutes``)."""

    def __init__(self, config: AnyConfig, steps: int, deadline: float, show: bool) -> None:
        self.total, self.first, self.deadline = config.total_timesteps, steps, deadline
        self.limited = bool(config.max_minutes)
        self.began = time.monotonic()
        self.shown = 0.0
        self.bar = None
        if show:
            from tqdm import tqdm

            self.bar = tqdm(total=self.total, initial=steps, unit="step", dynamic_ncols=True)

    def update(self, steps: int, force: bool = False) -> None:
        """Show ``steps`` done (at most twice a second, unless ``force``)."""
        now = time.monotonic()
        if self.bar is None or (now - self.shown < 0.5 and not force):
            return
        self.shown = now
        if self.limited and steps > self.first and now > self.began:
            rate = (steps - self.first) / (now - self.began)
            reachable = steps + rate * max(0.0, self.deadline - now)
            end = int(min(self.total, max(steps, reachable)))
            if end != self.bar.total:
                self.bar.total = end
                self.bar.set_description("stops at max_minutes" if end < self.total else "")
        self.bar.update(steps - self.bar.n)

    def score(self, score: float) -> None:
        if self.bar is not None:
            self.bar.set_postfix(score=f"{score:.0f}", refresh=False)

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()


class TrainingInterrupted(Exception):
    """A training stopped by a signal, after saving ``checkpoint``; the message says how to
    resume it."""

    def __init__(self, run: Path, checkpoint: Path, steps: int, stop: StopRequest, module: str):
        self.run, self.checkpoint, self.steps = run, checkpoint, steps
        self.exit_code = 128 + int(stop.signal or signal.SIGINT)
        super().__init__(
            f"{(stop.signal or signal.SIGINT).name}: stopped at {steps:,} steps; checkpoint "
            f"{checkpoint}\nresume with: python -m {module} --resume {run}"
        )


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


# What ``--resume RUN key=value`` may change: how long and how often, not what is learned.
RESUME_KEYS = {
    TrainConfig: ("total_timesteps", "max_minutes", "checkpoint_every", "validate_every",
                  "validate_episodes", "validate_seed"),
    RllibConfig: ("total_timesteps", "max_minutes", "checkpoint_every"),
}  # fmt: skip


def extend_run(run: Path, overrides: list[str], kind: type, command: list[str]) -> AnyConfig:
    """The config of run folder ``run`` for a resume, ``overrides`` (``key=value``, only
    ``RESUME_KEYS``) applied and saved into its ``config.yaml``; ``meta.json`` records the
    resume."""
    if not (run / CONFIG_FILE).is_file():
        raise ConfigError(f"{run}: not a run folder (no {CONFIG_FILE})")
    allowed = RESUME_KEYS[kind]
    for item in overrides:
        key = item.partition("=")[0]
        if key not in allowed:
            raise ConfigError(
                f"--resume: {key!r} would change what the run learned; a resume may change "
                f"only {', '.join(allowed)}"
            )
    config = load_config(run / CONFIG_FILE, overrides, kind=kind)
    if overrides:
        save_config(config, run / CONFIG_FILE)
    meta_path = run / "meta.json"
    meta = json.loads(meta_path.read_text()) if meta_path.is_file() else {}
    meta.setdefault("resumes", []).append(
        {"command": command, "overrides": list(overrides),
         "started": time.strftime("%Y-%m-%dT%H:%M:%S")}
    )  # fmt: skip
    meta_path.write_text(json.dumps(meta, indent=1))
    return config


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


def save_model(model: Any, folder: Path, name: str, config: AnyConfig) -> None:
    """Save ``model`` as ``folder/name.zip`` and, when it trains on a ``VecNormalize``, its
    statistics as ``folder/name_vecnormalize.pkl`` (first, so a model never lacks them; a
    resume reads them). The zip also carries ``config`` and the observation statistics
    (``AGENT_ENTRY``), so that it loads copied alone (``agents.policy``)."""
    import pickle

    venv = model.get_env()
    normalization = None
    if hasattr(venv, "obs_rms"):  # a VecNormalize: it pickles its statistics, not its envs
        atomic_write(folder / f"{name}_{STATS_FILE}", lambda file: pickle.dump(venv, file))
        if venv.norm_obs:
            normalization = {
                "mean": venv.obs_rms.mean.tolist(), "var": venv.obs_rms.var.tolist(),
                "epsilon": venv.epsilon, "clip_obs": venv.clip_obs,
            }  # fmt: skip
    buffer = io.BytesIO()
    model.save(buffer)
    entry = {"format": 1, "config": config.to_dict(), "obs_normalization": normalization}
    with zipfile.ZipFile(buffer, "a") as archive:  # stable-baselines3 reads only its entries
        archive.writestr(AGENT_ENTRY, json.dumps(entry, indent=1))
    atomic_write(folder / f"{name}.zip", lambda file: file.write(buffer.getvalue()))


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
