"""Training configs: YAML files in ``configs/agents/``, checked into frozen dataclasses.

A config names everything a run depends on; a key that is not known, a value of the wrong kind
or an option the algorithm or the env does not take is an error that names it, raised before
anything is built. ``key=value`` overrides (dotted keys into the sections, YAML values) apply
on top of the file::

    python -m agents.train --config configs/agents/ppo.yaml total_timesteps=200000 env.num_envs=8

:class:`TrainConfig` is a stable-baselines3 run (``agents.train``), :class:`RllibConfig` a Ray
RLlib run (``agents.rllib``); both share :class:`EnvConfig` and the checks of the env.
"""

import copy
import dataclasses
import functools
import inspect
import math
import os
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import gymnasium as gym
import yaml

from pinball_env.checks import is_finite, is_flag, is_int, is_real
from pinball_env.extras import missing_message
from pinball_env.game import check_playable
from pinball_env.options import GAME_FRAMES, PinballOptions
from pinball_env.protocol import EVAL_SEEDS, protocol_options
from pinball_env.table import Table, load_any_table

# stable-baselines3's algorithms and sb3-contrib's (RecurrentPPO: an LSTM policy; QRDQN: DQN
# with a distribution of returns, quantile regression).
ALGORITHMS = ("ppo", "a2c", "dqn", "recurrent_ppo", "qrdqn")
POLICIES = ("MlpPolicy", "CnnPolicy", "MlpLstmPolicy")
# The recurrent algorithm and its policy, which no other algorithm takes.
RECURRENT = ("recurrent_ppo", "MlpLstmPolicy")
# The options of gym.make_vec("Pinball-v0", ...) that are not PinballEnv's own, and those a
# training config must not set (rendering, and the thread count, which `torch_threads` sets).
VECTOR_ONLY_KWARGS = ("max_episode_steps",)
FORBIDDEN_ENV_KWARGS = ("render_mode", "num_threads", "autoreset_mode")
# The agents train on the native vector env of the pinball envs: ids registered with this entry
# point (Pinball-v0, PinballProcgen-v0, or another id registered with it).
PINBALL_ENTRY_POINT = "pinball_env.envs:PinballEnv"
# Keys renamed since configs were written, old name -> new: the old loads as the new (the
# config.yaml of older runs, the models that carry it, YAML files written before).
RENAMED_KEYS = {"anchor_coef": "kl_anchor_coef"}  # ("anchor" is a ball-search spot in the env)


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
        return {"max_episode_steps": None, "max_frames": GAME_FRAMES, **self.kwargs}


@dataclass(frozen=True)
class _RunConfig:
    """What both kinds of run config share: the budget, the seeds, the threads, the env and the
    bookkeeping (each kind adds its own keys)."""

    algo: str = "ppo"
    """The algorithm: one of ALGORITHMS (stable-baselines3's) or, for RLlib, its PPO."""
    total_timesteps: int = 1_000_000
    """Env steps to train for, summed over all envs (frames = steps x frame_skip)."""
    max_minutes: float = 0.0
    """Wall-clock limit of a training session [min] (0: none): stable-baselines3 stops at the
    first env step past it (the unfinished rollout is not learned from), RLlib after the
    training iteration past it, however few of ``total_timesteps`` are done, and the model is
    saved."""
    seed: int = 0
    """Seed of the algorithm and of the training games: stable-baselines3's env i starts from
    seed + i; RLlib's env i of env runner k (0: the driver's) from seed + k * num_envs + i."""
    torch_threads: int = 1
    """torch's thread count (of the learner; its default, one per core, was seen to slow SB3
    15-20x on 2 cores)."""
    env_threads: int = 1
    """Threads that step the envs' physics (of each RLlib env runner)."""
    hyperparams: dict[str, Any] = field(default_factory=dict)
    """Keyword arguments of the algorithm: stable-baselines3's constructor (``policy_kwargs``
    included) or RLlib's ``PPOConfig.training`` (lr, gamma, lambda_, num_epochs,
    train_batch_size_per_learner, minibatch_size, entropy_coeff...)."""
    env: EnvConfig = field(default_factory=EnvConfig)
    """The environment (for RLlib: ``num_envs`` games per env runner, and ``normalize`` runs
    its ``MeanStdFilter`` over the observations)."""
    checkpoint_every: int = 500_000
    """Write a checkpoint every this many env steps (0: only the final model)."""
    eval_seed: int = EVAL_SEEDS.start
    """First seed of evaluation games (the protocol's held-out games, ``EVAL_SEEDS``); training
    never uses seeds from here on."""
    notes: str = ""
    """Free text: what this config is for, what shaping it uses and why."""

    def to_dict(self) -> dict[str, Any]:
        """The config as plain data (what ``config.yaml`` holds)."""
        return dataclasses.asdict(self)


@dataclass(frozen=True)
class TrainConfig(_RunConfig):
    """A stable-baselines3 training run (``agents.train``): over the shared keys, the policy,
    the frame budget, the device, the warm start and its KL anchor, and the validation games."""

    policy: str = "MlpPolicy"
    """``MlpPolicy`` for state observations, ``CnnPolicy`` for images."""
    total_frames: int = 0
    """A budget in frames (0: none), summed over the envs, the warm start's games included:
    learning stops at the first env step at or past it, as at ``max_minutes``. The benchmark
    protocol's budget (``pinball_env.protocol.TRAINING_FRAMES``): frames, not steps, so that
    frame skips and ``skip_above`` cost what they play."""
    device: str = "cpu"
    """torch device."""
    imitation_steps: int = 0
    """A warm start (0: none; PPO and A2C on state observations and discrete actions): env
    steps, summed over the envs, of the heuristic playing the training games, whose actions the
    policy and whose returns the value are fitted to before learning (``agents.imitation``).
    They count in ``max_minutes``, not in ``total_timesteps``."""
    imitation_epochs: int = 5
    """Passes over the heuristic's steps in the warm start."""
    imitation_learning_rate: float | None = None
    """The warm start's learning rate (None: the algorithm's first learning rate), so that a
    gentle fine-tuning rate does not also weaken the fit."""
    kl_anchor_coef: float = 0.0
    """With a warm start: the weight of the pull back towards it after each update, a pass over
    the update's states lowering KL(warm start || policy) (``agents.imitation.KLAnchor``; 0:
    none). A resume takes the warm start from the run's ``checkpoints/step_0.zip``. Its old
    name ``anchor_coef`` still loads (``RENAMED_KEYS``)."""
    validate_every: int = 0
    """Every this many env steps, and at the end (0: never), the model plays
    ``validate_episodes`` whole games from ``validate_seed`` on, deterministically; the best of
    these validations becomes the run's ``model.zip`` (``agents.train``). They count in
    ``max_minutes``."""
    validate_episodes: int = 100
    """Games of each validation (the same games every time)."""
    validate_seed: int = 300_000
    """First seed of the validation games: neither a training game nor an evaluation game."""

    @property
    def label(self) -> str:
        """The algorithm as run folders name it."""
        return self.algo

    @property
    def training_seeds(self) -> int:
        """How many seeds from ``seed`` on the training games start from."""
        return self.env.num_envs

    @property
    def validation_seeds(self) -> range:
        """The seeds of the validation games (none without validation)."""
        first = self.validate_seed
        return range(first, first + self.validate_episodes if self.validate_every else first)


@dataclass(frozen=True)
class RllibConfig(_RunConfig):
    """A Ray RLlib run (``agents.rllib``): PPO on RLlib's current API stack, its env runners
    stepping the native vector env."""

    env_runners: int = 2
    """Remote env runner actors (``num_env_runners``; 0: sample in the driver)."""
    cpus_per_env_runner: float = 1.0
    """CPUs Ray reserves for each env runner (``num_cpus_per_env_runner``)."""
    model: dict[str, Any] = field(default_factory=dict)
    """Fields of RLlib's ``DefaultModelConfig`` (fcnet_hiddens, fcnet_activation...)."""

    @property
    def label(self) -> str:
        return f"rllib-{self.algo}"

    @property
    def training_seeds(self) -> int:
        """How many seeds from ``seed`` on the training games start from."""
        return (self.env_runners + 1) * self.env.num_envs


AnyConfig = TrainConfig | RllibConfig


def load_config(
    path: str | os.PathLike[str],
    overrides: list[str] = (),
    kind: type = TrainConfig,
    check: bool = True,
) -> AnyConfig:
    """The config (a ``kind``) in the YAML file ``path`` over its ``base`` config if it names
    one, with ``key=value`` overrides applied, checked (``check=False``: its keys only, for
    reading what it says where its libraries are not installed: the docs' table of configs)."""
    path = Path(path)
    data = read_config_data(path)
    for item in overrides:
        apply_override(data, item, path)
    return config_from_dict(data, str(path), kind, check)


def read_config_data(path: Path, inside: tuple[Path, ...] = ()) -> dict[str, Any]:
    """The mapping in the YAML file ``path`` laid over the config its ``base`` key names (a path
    from ``path``'s folder), and so on down: a mapping merges key by key, any other value
    replaces the base's. ``inside``: the files that named this one as their base."""
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
    if "base" not in data:
        return data
    base = data.pop("base")
    if not isinstance(base, str) or not base:
        raise ConfigError(f"{path}: base: must be the path of a config file, got {base!r}")
    chain = (*inside, path.resolve())
    base_path = path.parent / base
    if base_path.resolve() in chain:
        files = " -> ".join(str(file) for file in (*chain, base_path.resolve()))
        raise ConfigError(f"{path}: base: {base} makes a cycle ({files})")
    return _merged(read_config_data(base_path, chain), data)


def _merged(base: dict[str, Any], over: dict[str, Any]) -> dict[str, Any]:
    """``base`` with ``over``'s keys: mappings in both merged in turn, other values replaced."""
    merged = dict(base)
    for key, value in over.items():
        both = isinstance(value, dict) and isinstance(merged.get(key), dict)
        merged[key] = _merged(merged[key], value) if both else value
    return merged


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


def load_run_config(run: Path) -> AnyConfig:
    """The config a run folder was trained with: an RLlib run's (it has ``env_runners``) or a
    stable-baselines3 run's."""
    path = run / "config.yaml"
    try:
        data = yaml.safe_load(path.read_text())
    except (OSError, yaml.YAMLError) as error:
        raise ConfigError(f"{path}: cannot read the run's config: {error}") from None
    kind = RllibConfig if isinstance(data, dict) and "env_runners" in data else TrainConfig
    return load_config(path, kind=kind)


def config_from_dict(
    data: dict[str, Any], source: str = "<config>", kind: type = TrainConfig, check: bool = True
) -> AnyConfig:
    """A checked config (:class:`TrainConfig` or :class:`RllibConfig`) from plain data
    (``check=False``: only its keys checked, see :func:`load_config`)."""
    data = dict(data)
    env_data = data.pop("env", {}) or {}
    if not isinstance(env_data, dict):
        raise ConfigError(f"{source}: env: must be a mapping")
    if kind is TrainConfig and "env_runners" in data:
        raise ConfigError(f"{source}: an RLlib config (it has env_runners): train it with "
                          "python -m agents.rllib")  # fmt: skip
    if kind is RllibConfig and "policy" in data:
        raise ConfigError(f"{source}: a stable-baselines3 config (it has a policy): train it "
                          "with python -m agents.train")  # fmt: skip
    _rename_keys(data, source)
    check_keys(data, kind, source, "")
    check_keys(env_data, EnvConfig, source, "env.")
    config = kind(**data, env=EnvConfig(**env_data))
    if check:
        check_config(config, source)
    return config


def _rename_keys(data: dict[str, Any], source: str) -> None:
    """Give the keys of ``RENAMED_KEYS`` in ``data`` their new names (in place); ConfigError
    where both names are given."""
    for old, new in RENAMED_KEYS.items():
        if old in data:
            if new in data:
                raise ConfigError(f"{source}: {old} is the old name of {new}: give {new} alone")
            data[new] = data.pop(old)


def check_keys(data: dict[str, Any], cls: type, source: str, prefix: str) -> None:
    known = {f.name for f in dataclasses.fields(cls)} - {"env"}
    for key in data:
        if key not in known:
            raise ConfigError(
                f"{source}: unknown key '{prefix}{key}' (known: {', '.join(sorted(known))})"
            )


def check_config(config: AnyConfig, source: str = "<config>") -> None:
    """Raise ConfigError naming the first key whose value cannot be used."""

    def fail(key: str, problem: str) -> None:
        raise ConfigError(f"{source}: {key}: {problem}")

    def integer(key: str, value: Any, low: int) -> None:
        _check_integer(fail, key, value, low)

    integer("total_timesteps", config.total_timesteps, 1)
    integer("seed", config.seed, 0)
    minutes = config.max_minutes
    if not is_real(minutes) or not 0 <= minutes < 1e6:
        fail("max_minutes", f"must be a number of minutes >= 0, got {minutes!r}")
    if isinstance(config, TrainConfig):
        integer("total_frames", config.total_frames, 0)
    integer("torch_threads", config.torch_threads, 1)
    integer("env_threads", config.env_threads, 1)
    integer("checkpoint_every", config.checkpoint_every, 0)
    integer("eval_seed", config.eval_seed, 0)
    integer("env.num_envs", config.env.num_envs, 1)
    integer("env.frame_stack", config.env.frame_stack, 1)
    if not is_flag(config.env.normalize):
        fail("env.normalize", f"must be true or false, got {config.env.normalize!r}")
    if not isinstance(config.notes, str):
        fail("notes", "must be text")
    if not isinstance(config.hyperparams, dict):
        fail("hyperparams", "must be a mapping of the algorithm's keyword arguments")
    if isinstance(config, RllibConfig):
        integer("env_runners", config.env_runners, 0)
        _check_rllib(config, fail)
    else:
        _check_sb3(config, fail)
    seeds = config.training_seeds
    if config.eval_seed < config.seed + seeds:
        fail("eval_seed", f"{config.eval_seed} overlaps the training seeds {config.seed}.."
                          f"{config.seed + seeds - 1}")  # fmt: skip
    _check_env(config.env, fail)


def protocol_config(config: AnyConfig) -> AnyConfig:
    """``config`` playing the benchmark protocol's game (``pinball_env.protocol``): its env
    options (how the agent sees and acts) on the protocol's table, balls and time, with sticky
    actions; ConfigError if its env is not a protocol env or its options change the game."""
    try:
        kwargs = protocol_options(config.env.id, config.env.kwargs)
    except ValueError as error:
        raise ConfigError(str(error)) from None
    return dataclasses.replace(config, env=dataclasses.replace(config.env, kwargs=kwargs))


def _check_integer(fail: Callable[[str, str], None], key: str, value: Any, low: int) -> None:
    if not is_int(value) or value < low:
        fail(key, f"must be an integer >= {low}, got {value!r}")


def _check_validation(config: TrainConfig, fail: Callable[[str, str], None]) -> None:
    """Validation games: counts, and seeds apart from the training and evaluation games."""
    for key, low in (("validate_every", 0), ("validate_episodes", 1), ("validate_seed", 0)):
        _check_integer(fail, key, getattr(config, key), low)
    games = config.validation_seeds
    if not games:
        return
    if games.start < config.seed + config.training_seeds:
        fail("validate_seed", f"{games.start} overlaps the training seeds {config.seed}.."
                              f"{config.seed + config.training_seeds - 1}")  # fmt: skip
    if config.eval_seed in games:
        fail("validate_seed", f"the validation games {games.start}..{games.stop - 1} hold "
                              f"eval_seed {config.eval_seed}")  # fmt: skip


def check_evaluation_seeds(config: AnyConfig, first: int, episodes: int) -> None:
    """Raise ConfigError if the games ``first..first + episodes - 1`` include a training game
    of ``config``'s model or a validation game that chose it."""
    games = range(first, first + episodes)
    for name, seeds in (
        ("training", range(config.seed, config.seed + config.training_seeds)),
        ("validation", getattr(config, "validation_seeds", range(0))),
    ):
        if seeds and games.start < seeds.stop and seeds.start < games.stop:
            raise ConfigError(
                f"seeds {games.start}..{games.stop - 1} overlap the {name} seeds "
                f"{seeds.start}..{seeds.stop - 1}"
            )


def _check_sb3(config: TrainConfig, fail: Callable[[str, str], None]) -> None:
    """The stable-baselines3 parts: algorithm, policy, its options, the torch device."""
    if config.algo not in ALGORITHMS:
        fail("algo", f"unknown algorithm {config.algo!r} (known: {', '.join(ALGORITHMS)})")
    if config.policy not in POLICIES:
        fail("policy", f"unknown policy {config.policy!r} (known: {', '.join(POLICIES)})")
    try:
        import torch

        torch.device(config.device)
    except (RuntimeError, TypeError):
        fail("device", f"not a torch device: {config.device!r}")
    taken = set(inspect.signature(algorithm_class(config.algo).__init__).parameters)
    taken -= {"self", "policy", "env", "seed", "device", "tensorboard_log", "verbose"}
    _check_options("hyperparams", config.hyperparams, taken, config.algo.upper(), fail)
    for key, value in config.hyperparams.items():
        if isinstance(value, str) and key in SCHEDULES and schedule(value) is None:
            fail(f"hyperparams.{key}", f"a schedule is lin_X or cos_X with X > 0, got {value!r}")
    if (config.algo == RECURRENT[0]) != (config.policy == RECURRENT[1]):
        fail("policy", f"{RECURRENT[0]} takes {RECURRENT[1]}, and only it does "
                       f"(algo {config.algo}, policy {config.policy})")  # fmt: skip
    image = config.env.kwargs.get("obs_type", "state") != "state"
    if image != (config.policy == "CnnPolicy"):
        obs_type = config.env.kwargs.get("obs_type", "state")
        fail("policy", f"{config.policy} does not fit obs_type {obs_type!r}")
    _check_imitation(config, fail)
    _check_validation(config, fail)


def _check_imitation(config: TrainConfig, fail: Callable[[str, str], None]) -> None:
    """The warm start: a count of steps and epochs and a learning rate, for an actor-critic on
    state observations with discrete actions (the heuristic's)."""
    for key, low in (("imitation_steps", 0), ("imitation_epochs", 1)):
        _check_integer(fail, key, getattr(config, key), low)
    rate = config.imitation_learning_rate
    if rate is not None and not _positive(rate):
        fail("imitation_learning_rate", f"must be a positive number or null, not {rate!r}")
    kl_anchor = config.kl_anchor_coef
    if kl_anchor != 0 and not _positive(kl_anchor):
        fail("kl_anchor_coef", f"must be a number >= 0, not {kl_anchor!r}")
    if kl_anchor and not config.imitation_steps:
        fail("kl_anchor_coef", "pulls towards a warm start: set imitation_steps too")
    if not config.imitation_steps:
        return
    if config.algo not in ("ppo", "a2c"):
        fail("imitation_steps", f"a warm start needs an actor-critic (ppo, a2c), not {config.algo}")
    kwargs = config.env.kwargs
    if config.policy != "MlpPolicy" or config.env.frame_stack != 1:
        fail("imitation_steps", "a warm start needs state observations (MlpPolicy, no frame stack)")
    if kwargs.get("action_type", "discrete") != "discrete":
        fail("imitation_steps", "a warm start needs discrete actions (the heuristic's)")


# PPOConfig.training options that are code, not settings, or belong to other keys (model).
RLLIB_NOT_HYPERPARAMS = {
    "self", "kwargs", "model", "optimizer", "learner_class", "learner_connector",
    "add_default_connectors_to_learner_pipeline", "learner_config_dict", "lr_schedule",
    "vf_share_layers",
}  # fmt: skip


def _check_rllib(config: RllibConfig, fail: Callable[[str, str], None]) -> None:
    """The RLlib parts: PPO, its training options and model fields, state observations."""
    if config.algo != "ppo":
        fail("algo", f"unknown algorithm {config.algo!r} (RLlib runs ship PPO only)")
    cpus = config.cpus_per_env_runner
    if not is_real(cpus) or not 0 < cpus <= 1024:
        fail("cpus_per_env_runner", f"must be a number of CPUs > 0, got {cpus!r}")
    try:
        from ray.rllib.algorithms.algorithm_config import AlgorithmConfig
        from ray.rllib.algorithms.ppo import PPOConfig
        from ray.rllib.core.rl_module.default_model_config import DefaultModelConfig
    except ImportError:
        fail("algo", f"Ray RLlib: {missing_message('ray')}")
    taken = set(inspect.signature(PPOConfig.training).parameters)
    taken |= set(inspect.signature(AlgorithmConfig.training).parameters)
    _check_options("hyperparams", config.hyperparams, taken - RLLIB_NOT_HYPERPARAMS, "PPO", fail)
    if not isinstance(config.model, dict):
        fail("model", "must be a mapping of DefaultModelConfig fields")
    fields = {f.name for f in dataclasses.fields(DefaultModelConfig)}
    _check_options("model", config.model, fields, "DefaultModelConfig", fail)
    if config.env.kwargs.get("obs_type", "state") != "state":
        fail("env.kwargs.obs_type", "RLlib runs train on state observations")
    if config.env.frame_stack != 1:
        fail("env.frame_stack", "RLlib runs do not stack frames")


def _check_options(
    key: str, options: dict[str, Any], taken: set[str], owner: str,
    fail: Callable[[str, str], None],
) -> None:  # fmt: skip
    for name, value in options.items():
        if name not in taken:
            fail(f"{key}.{name}", f"not an option of {owner}")
        if is_real(value) and not is_finite(value):
            fail(f"{key}.{name}", f"must be finite, got {value!r}")


def _check_env(env: EnvConfig, fail: Callable[[str, str], None]) -> None:
    """The env id and its options (each one the env takes, its checks passed, the table
    loadable and playable), checked without building an env."""
    try:
        spec = gym.spec(env.id) if isinstance(env.id, str) else None
    except gym.error.Error:
        spec = None
    if spec is None or spec.entry_point != PINBALL_ENTRY_POINT:
        fail("env.id", f"{env.id!r} is not a registered pinball environment")
    if not isinstance(env.kwargs, dict):
        fail("env.kwargs", f"must be a mapping of {env.id}'s options")
    options = set(PinballOptions.names()) - set(spec.kwargs)  # the id's own are fixed
    for key in env.kwargs:
        if key in FORBIDDEN_ENV_KWARGS or key not in options | set(VECTOR_ONLY_KWARGS):
            fail(f"env.kwargs.{key}", f"not a training option of {env.id}")
    steps = env.kwargs.get("max_episode_steps", 1)
    _check_integer(fail, "env.kwargs.max_episode_steps", steps, 1)
    kwargs = {k: v for k, v in env.kwargs.items() if k not in VECTOR_ONLY_KWARGS}
    try:
        game = PinballOptions(**{**spec.kwargs, **kwargs})
        if not game.generated and not isinstance(game.table, Table):
            check_playable(load_any_table(game.table))
    except (ValueError, TypeError) as error:  # TableError is a ValueError
        fail("env.kwargs", str(error))


# Options that take a schedule, X decayed to 0 over the run's total_timesteps: "lin_X" (rl-zoo3's
# notation) linearly, "cos_X" along a half cosine (PufferLib's). stable-baselines3 takes a schedule
# of the learning rate and the clip range itself; the entropy coefficient of PPO and A2C is set
# before each update by ``callbacks.EntropySchedule`` (stable-baselines3 has no schedule of it).
SCHEDULES = ("learning_rate", "clip_range", "ent_coef")
SCHEDULE_SHAPES: dict[str, Callable[[float, float], float]] = {
    "lin_": lambda start, left: left * start,
    "cos_": lambda start, left: start * 0.5 * (1.0 - math.cos(math.pi * left)),
}


def schedule(text: str) -> Callable[[float], float] | None:
    """The schedule ``"lin_X"`` or ``"cos_X"`` (X a positive finite number) as a function of
    the progress left (1 at the start of the run, 0 at total_timesteps), or None."""
    for prefix, shape in SCHEDULE_SHAPES.items():
        if text.startswith(prefix):
            try:
                start = float(text.removeprefix(prefix))
            except ValueError:
                return None
            return functools.partial(shape, start) if _positive(start) else None
    return None


def _positive(value: Any) -> bool:
    """A finite number > 0 (a bool is not a number here)."""
    return is_finite(value) and value > 0


def sb3_hyperparams(config: TrainConfig) -> dict[str, Any]:
    """The algorithm's keyword arguments, schedules made functions of the progress left (the
    entropy coefficient's start: ``callbacks.EntropySchedule`` sets it on)."""
    kwargs = {}
    for key, value in config.hyperparams.items():
        function = schedule(value) if key in SCHEDULES and isinstance(value, str) else None
        if function is None:  # copies: an algorithm may fill in its kwargs (A2C's optimizer)
            kwargs[key] = copy.deepcopy(value)
        else:
            kwargs[key] = function(1.0) if key == "ent_coef" else function
    return kwargs


def entropy_schedule(config: TrainConfig) -> Callable[[float], float] | None:
    """The schedule of the entropy coefficient (``hyperparams.ent_coef`` a schedule), or None."""
    value = config.hyperparams.get("ent_coef")
    return schedule(value) if isinstance(value, str) else None


def algorithm_class(name: str) -> type:
    """stable-baselines3's (or sb3-contrib's) class for an algorithm name (imported only now)."""
    import sb3_contrib
    import stable_baselines3

    return {"ppo": stable_baselines3.PPO, "a2c": stable_baselines3.A2C,
            "dqn": stable_baselines3.DQN, "recurrent_ppo": sb3_contrib.RecurrentPPO,
            "qrdqn": sb3_contrib.QRDQN}[name]  # fmt: skip


def save_config(config: AnyConfig, path: Path) -> None:
    path.write_text(yaml.safe_dump(config.to_dict(), sort_keys=False))
