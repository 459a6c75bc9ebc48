"""Training configs: YAML files in ``configs/agents/``, checked into frozen dataclasses.

A config names everything a run depends on; a key that is not known, a value of the wrong kind
or an option the algorithm or the env does not take is an error that names it, raised before
anything is built. ``key=value`` overrides (dotted keys into the sections, YAML values) apply
on top of the file::

    python -m agents.train --config configs/agents/ppo.yaml total_timesteps=200000 env.num_envs=8
"""

import dataclasses
import inspect
import math
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import gymnasium as gym
import yaml

from pinball_env import MAX_EPISODE_STEPS
from pinball_env.env import PinballEnv
from pinball_env.procgen_env import PinballProcgenEnv

ALGORITHMS = ("ppo", "a2c", "dqn")
POLICIES = ("MlpPolicy", "CnnPolicy")
# The options of gym.make_vec("Pinball-v0", ...) that are not PinballEnv's own, and those a
# training config must not set (rendering, and the thread count, which `torch_threads` sets).
VECTOR_ONLY_KWARGS = ("max_episode_steps",)
FORBIDDEN_ENV_KWARGS = ("render_mode", "num_threads", "autoreset_mode")
# The agents train on the native vector env of the pinball envs registered with these entry
# points (Pinball-v0 and PinballProcgen-v0, or another id registered with one of them).
PINBALL_ENVS = {
    "pinball_env.env:PinballEnv": PinballEnv,
    "pinball_env.procgen_env:PinballProcgenEnv": PinballProcgenEnv,
}


class ConfigError(ValueError):
    """A config file, key or value that cannot be used; the message names it."""


@dataclass(frozen=True)
class EnvConfig:
    """The environment the agent trains on."""

    id: str = "Pinball-v0"
    """Registered Gymnasium id."""
    num_envs: int = 16
    """Games stepped side by side (one native vector env)."""
    kwargs: dict[str, Any] = field(default_factory=dict)
    """Options of ``gym.make("Pinball-v0", ...)`` (table, obs_type, frame_skip, shaping...).
    A game lasts two minutes of play (``max_frames`` 7200) whatever the frame skip."""
    normalize: bool = False
    """Normalise observations and rewards with stable-baselines3's ``VecNormalize``."""
    frame_stack: int = 1
    """Stack this many last observations (``VecFrameStack``; 1: none), for pixel agents."""

    @property
    def frame_skip(self) -> int:
        return int(self.kwargs.get("frame_skip", 1))

    @property
    def make_kwargs(self) -> dict[str, Any]:
        """The options for ``gym.make_vec``, the time limit filled in: 7200 frames."""
        return {"max_episode_steps": None, "max_frames": MAX_EPISODE_STEPS, **self.kwargs}


@dataclass(frozen=True)
class TrainConfig:
    """A training run: algorithm, policy, hyperparameters, env, budget and bookkeeping."""

    algo: str = "ppo"
    """One of ALGORITHMS (stable-baselines3's PPO, A2C, DQN)."""
    policy: str = "MlpPolicy"
    """``MlpPolicy`` for state observations, ``CnnPolicy`` for images."""
    total_timesteps: int = 1_000_000
    """Env steps to train for, summed over the envs (frames = steps x frame_skip)."""
    max_minutes: float = 0.0
    """Wall-clock limit of a training session [min] (0: none): learning stops at the first env
    step past it (the unfinished rollout is not learned from), however few of
    ``total_timesteps`` are done, and the model is saved."""
    seed: int = 0
    """Seed of the algorithm and of the training games (env i starts from seed + i)."""
    device: str = "cpu"
    """torch device."""
    torch_threads: int = 1
    """torch's thread count (its default, one per core, was seen to slow SB3 15-20x on 2 cores)."""
    env_threads: int = 1
    """Threads that step the envs' physics."""
    hyperparams: dict[str, Any] = field(default_factory=dict)
    """Keyword arguments of the algorithm's constructor (``policy_kwargs`` included)."""
    env: EnvConfig = field(default_factory=EnvConfig)
    """The environment."""
    checkpoint_every: int = 500_000
    """Write a checkpoint every this many env steps (0: only the final model)."""
    eval_seed: int = 100_000
    """First seed of evaluation games; training never uses seeds from here on."""
    notes: str = ""
    """Free text: what this config is for, what shaping it uses and why."""

    def to_dict(self) -> dict[str, Any]:
        return dataclasses.asdict(self)


def load_config(path: str | os.PathLike[str], overrides: list[str] = ()) -> TrainConfig:
    """The config in the YAML file ``path`` with ``key=value`` overrides applied, checked."""
    path = Path(path)
    try:
        text = path.read_text()
    except OSError as error:
        raise ConfigError(f"{path}: cannot read the config: {error.strerror or error}") from None
    try:
        data = yaml.safe_load(text)
    except yaml.YAMLError as error:
        raise ConfigError(f"{path}: not valid YAML: {error}") from None
    if not isinstance(data, dict):
        raise ConfigError(f"{path}: a config is a mapping of keys, got {type(data).__name__}")
    for item in overrides:
        apply_override(data, item, path)
    return config_from_dict(data, str(path))


def apply_override(data: dict[str, Any], item: str, source: str | Path = "override") -> None:
    """Set ``data[a][b] = value`` for ``item`` = ``"a.b=value"`` (the value read as YAML)."""
    key, sep, text = item.partition("=")
    if not sep or not key:
        raise ConfigError(f"{source}: override {item!r} is not key=value")
    try:
        value = yaml.safe_load(text)
    except yaml.YAMLError as error:
        raise ConfigError(f"{source}: override {item!r}: not a YAML value: {error}") from None
    *parents, last = key.split(".")
    node = data
    for part in parents:
        node = node.setdefault(part, {})
        if not isinstance(node, dict):
            raise ConfigError(f"{source}: override {item!r}: {part!r} is not a section")
    node[last] = value


def config_from_dict(data: dict[str, Any], source: str = "<config>") -> TrainConfig:
    """A checked :class:`TrainConfig` from plain data."""
    data = dict(data)
    env_data = data.pop("env", {}) or {}
    if not isinstance(env_data, dict):
        raise ConfigError(f"{source}: env: must be a mapping")
    _check_keys(data, TrainConfig, source, "")
    _check_keys(env_data, EnvConfig, source, "env.")
    config = TrainConfig(**data, env=EnvConfig(**env_data))
    check_config(config, source)
    return config


def _check_keys(data: dict[str, Any], cls: type, source: str, prefix: str) -> None:
    known = {f.name for f in dataclasses.fields(cls)} - {"env"}
    for key in data:
        if key not in known:
            raise ConfigError(
                f"{source}: unknown key {prefix}{key!r} (known: {', '.join(sorted(known))})"
            )


def check_config(config: TrainConfig, source: str = "<config>") -> None:
    """Raise ConfigError naming the first key whose value cannot be used."""

    def fail(key: str, problem: str) -> None:
        raise ConfigError(f"{source}: {key}: {problem}")

    def integer(key: str, value: Any, low: int) -> None:
        if not isinstance(value, int) or isinstance(value, bool) or value < low:
            fail(key, f"must be an integer >= {low}, got {value!r}")

    if config.algo not in ALGORITHMS:
        fail("algo", f"unknown algorithm {config.algo!r} (known: {', '.join(ALGORITHMS)})")
    if config.policy not in POLICIES:
        fail("policy", f"unknown policy {config.policy!r} (known: {', '.join(POLICIES)})")
    integer("total_timesteps", config.total_timesteps, 1)
    integer("seed", config.seed, 0)
    minutes = config.max_minutes
    if isinstance(minutes, bool) or not isinstance(minutes, (int, float)) or not 0 <= minutes < 1e6:
        fail("max_minutes", f"must be a number of minutes >= 0, got {minutes!r}")
    integer("torch_threads", config.torch_threads, 1)
    integer("env_threads", config.env_threads, 1)
    integer("checkpoint_every", config.checkpoint_every, 0)
    integer("eval_seed", config.eval_seed, 0)
    integer("env.num_envs", config.env.num_envs, 1)
    integer("env.frame_stack", config.env.frame_stack, 1)
    if not isinstance(config.env.normalize, bool):
        fail("env.normalize", f"must be true or false, got {config.env.normalize!r}")
    try:
        import torch

        torch.device(config.device)
    except (RuntimeError, TypeError):
        fail("device", f"not a torch device: {config.device!r}")
    if not isinstance(config.notes, str):
        fail("notes", "must be text")
    if config.eval_seed < config.seed + config.env.num_envs:
        fail(
            "eval_seed",
            f"{config.eval_seed} overlaps the training seeds {config.seed}.."
            f"{config.seed + config.env.num_envs - 1}",
        )
    if not isinstance(config.hyperparams, dict):
        fail("hyperparams", "must be a mapping of the algorithm's keyword arguments")
    taken = set(inspect.signature(algorithm_class(config.algo).__init__).parameters)
    taken -= {"self", "policy", "env", "seed", "device", "tensorboard_log", "verbose"}
    for key, value in config.hyperparams.items():
        if key not in taken:
            fail(f"hyperparams.{key}", f"not an option of {config.algo.upper()}")
        if isinstance(value, float) and not math.isfinite(value):
            fail(f"hyperparams.{key}", f"must be finite, got {value!r}")
    try:
        spec = gym.spec(config.env.id) if isinstance(config.env.id, str) else None
    except gym.error.Error:
        spec = None
    if spec is None or spec.entry_point not in PINBALL_ENVS:
        fail("env.id", f"{config.env.id!r} is not a registered pinball environment")
    env_class = PINBALL_ENVS[spec.entry_point]
    if not isinstance(config.env.kwargs, dict):
        fail("env.kwargs", f"must be a mapping of {config.env.id}'s options")
    options = set(inspect.signature(env_class.__init__).parameters) - {"self"}
    options |= set(VECTOR_ONLY_KWARGS)
    for key in config.env.kwargs:
        if key in FORBIDDEN_ENV_KWARGS or key not in options:
            fail(f"env.kwargs.{key}", f"not a training option of {config.env.id}")
    steps = config.env.kwargs.get("max_episode_steps", 1)
    if not isinstance(steps, int) or isinstance(steps, bool) or steps < 1:
        fail("env.kwargs.max_episode_steps", f"must be an integer >= 1, got {steps!r}")
    try:  # the env's own checks of its options (a table that cannot be loaded, say)
        env_class(**{k: v for k, v in config.env.kwargs.items() if k not in VECTOR_ONLY_KWARGS})
    except (ValueError, TypeError) as error:  # TableError is a ValueError
        fail("env.kwargs", str(error))
    image = config.env.kwargs.get("obs_type", "state") != "state"
    if image != (config.policy == "CnnPolicy"):
        obs_type = config.env.kwargs.get("obs_type", "state")
        fail("policy", f"{config.policy} does not fit obs_type {obs_type!r}")


def algorithm_class(name: str) -> type:
    """stable-baselines3's class for an algorithm name (imported only now)."""
    import stable_baselines3

    return {
        "ppo": stable_baselines3.PPO,
        "a2c": stable_baselines3.A2C,
        "dqn": stable_baselines3.DQN,
    }[name]


def save_config(config: TrainConfig, path: Path) -> None:
    path.write_text(yaml.safe_dump(config.to_dict(), sort_keys=False))
