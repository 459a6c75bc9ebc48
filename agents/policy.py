"""Trained agents outside ``agents.evaluate``: load any saved agent and the env it was trained on.

    from agents.policy import load_policy

    policy = load_policy("runs/Pinball-v0_ppo_seed0_20261128-011611")
    env = policy.make_env()  # gym.make("Pinball-v0", ...) as trained: frame stack, statistics
    obs, info = env.reset(seed=100_000)
    terminated = truncated = False
    while not (terminated or truncated):
        obs, reward, terminated, truncated, info = env.step(policy.act(obs))
    print(info["score"])
    policy.reset()  # before the next game (a recurrent agent's memory; nothing for the others)

:func:`load_policy` takes a stable-baselines3 run folder (its ``model.zip``, or its newest
checkpoint when training stopped before one was written), a model zip or checkpoint zip, or a
Ray RLlib run folder or checkpoint folder. A :class:`Policy` holds the env id and options it was
trained with (``env_kwargs``), and builds the env chain it plays through: ``make_env()`` (one
game) and ``make_vec(num_envs)`` (the native vector env), each ``gym.make``'s env with the
config's frame stack (stable-baselines3's layout: the last ``k`` observations concatenated,
oldest first, images channels first) and the observation statistics frozen as they were
saved. ``act(obs)`` takes one observation of that chain or a batch of them and returns the
greedy action(s).

The agents that ship with the project load by name, their method's:
``load_policy("pretrained:ppo-gentle-v1")`` (:data:`PRETRAINED`; each a model zip in
``agents/pretrained/`` with a card, ``NAME.json``: its config, the commit it was trained at, its
frames and minutes of training and its scores under the benchmark protocol; the names they
shipped under before, such as ``ppo-v1``, load too: :data:`PRETRAINED_ALIASES`).
``pretrained:NAME`` goes wherever a model path goes
(``python -m agents.evaluate --model pretrained:ppo-gentle-v1 --watch``).

A model zip saved by ``agents.train`` carries its config and its observation statistics (the
entry ``pinball/agent.json``), so it loads copied alone; an older zip needs the run's
``config.yaml`` beside it or one folder up (and ``NAME_vecnormalize.pkl`` beside it when the
config normalises), and the error says which file is missing. Models and checkpoints hold
pickles: load only files you trust.
"""

import dataclasses
import json
import os
import pickle
import zipfile
from collections.abc import Callable
from functools import partial
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium import spaces

import pinball_env  # noqa: F401  (registers the env ids)
from agents.config import (
    AnyConfig,
    ConfigError,
    RllibConfig,
    algorithm_class,
    config_from_dict,
    load_config,
)
from agents.runs import (
    AGENT_ENTRY,
    CONFIG_FILE,
    FILTER_PATH,
    MODEL_FILE,
    MODULE_PATH,
    STATS_FILE,
    is_rllib_checkpoint,
    latest_checkpoint,
    rllib_checkpoint,
    stats_for,
)

# The agents that ship with the project: agents/pretrained/NAME.zip (NAME: the method's name),
# loadable as "pretrained:NAME".
PRETRAINED_PREFIX = "pretrained:"
PRETRAINED_DIR = Path(__file__).resolve().parent / "pretrained"
# The names agents shipped under before they were named after their method, alias -> name:
# pretrained:ppo-v1 was the method ppo-gentle-v1's run (the method ppo-v1 is another recipe).
PRETRAINED_ALIASES = {"ppo-v1": "ppo-gentle-v1"}
# Every name that loads as "pretrained:NAME": the shipped agents' and their aliases.
PRETRAINED = tuple(
    sorted({path.stem for path in PRETRAINED_DIR.glob("*.zip")} | set(PRETRAINED_ALIASES))
)


def resolve_model_path(path: str | os.PathLike[str]) -> Path:
    """``path``, or for ``"pretrained:NAME"`` the shipped model zip of that name (or of the
    agent an alias names)."""
    text = os.fspath(path)
    if not text.startswith(PRETRAINED_PREFIX):
        return Path(path)
    name = text.removeprefix(PRETRAINED_PREFIX)
    if name not in PRETRAINED:
        raise ConfigError(
            f"{text}: no such pretrained agent (shipped: "
            f"{', '.join(PRETRAINED_PREFIX + known for known in PRETRAINED) or 'none'})"
        )
    return PRETRAINED_DIR / f"{PRETRAINED_ALIASES.get(name, name)}.zip"


def pretrained_card(name: str) -> dict[str, Any]:
    """The card of the pretrained agent ``name`` (``agents/pretrained/NAME.json``; an alias:
    its agent's)."""
    model = resolve_model_path(PRETRAINED_PREFIX + name)  # (the error for an unknown name)
    return json.loads(model.with_suffix(".json").read_text())


@dataclasses.dataclass(frozen=True)
class ObsNormalization:
    """Frozen observation statistics: ``clip((obs - offset) / scale)`` as float32, the very
    arithmetic of stable-baselines3's ``VecNormalize`` (offset the mean, scale
    ``sqrt(var + epsilon)``) and of RLlib's ``MeanStdFilter`` (scale ``std + SMALL_NUMBER``)."""

    offset: np.ndarray
    scale: np.ndarray
    clip: float | None

    @classmethod
    def from_moments(cls, mean: Any, var: Any, epsilon: float, clip: float) -> "ObsNormalization":
        """stable-baselines3's ``VecNormalize`` statistics."""
        var = np.asarray(var, dtype=np.float64)
        return cls(np.asarray(mean, dtype=np.float64), np.sqrt(var + epsilon), float(clip))

    def __call__(self, obs: np.ndarray) -> np.ndarray:
        scaled = (obs - self.offset) / self.scale
        if self.clip is not None:
            scaled = np.clip(scaled, -self.clip, self.clip)
        return scaled.astype(np.float32)

    def space(self, shape: tuple[int, ...]) -> spaces.Box:
        bound = np.inf if self.clip is None else self.clip
        return spaces.Box(-bound, bound, shape, dtype=np.float32)


class NormalizeObservation(gym.ObservationWrapper):
    """Observations normalised by frozen statistics (:class:`ObsNormalization`)."""

    def __init__(self, env: gym.Env, normalization: ObsNormalization) -> None:
        super().__init__(env)
        self.normalization = normalization
        self.observation_space = normalization.space(env.observation_space.shape)

    def observation(self, observation: np.ndarray) -> np.ndarray:
        return self.normalization(observation)


class StackedObservation(gym.ObservationWrapper):
    """stable-baselines3's frame-stack layout over Gymnasium's ``FrameStackObservation``
    (zero-padded): a state observation's ``k`` copies concatenated, oldest first; images
    channels first, ``k * channels`` of them. ``k = 1`` only moves image channels first
    (``VecTransposeImage``)."""

    def __init__(self, env: gym.Env, k: int) -> None:
        inner = gym.wrappers.FrameStackObservation(env, k, padding_type="zero") if k > 1 else env
        super().__init__(inner)
        self.k = k
        single = env.observation_space
        self.image = len(single.shape) == 3
        low, high = (
            self._layout(inner.observation_space.low),
            self._layout(inner.observation_space.high),
        )
        self.observation_space = spaces.Box(low, high, dtype=single.dtype)

    def _layout(self, observation: np.ndarray) -> np.ndarray:
        if self.k == 1:
            return np.transpose(observation, (2, 0, 1)) if self.image else observation
        if self.image:  # (k, H, W, C) -> (k * C, H, W)
            k, height, width, channels = observation.shape
            return np.transpose(observation, (0, 3, 1, 2)).reshape(k * channels, height, width)
        return observation.reshape(-1)

    def observation(self, observation: np.ndarray) -> np.ndarray:
        return np.ascontiguousarray(self._layout(np.asarray(observation)))


class NormalizeVectorObservation(gym.vector.VectorObservationWrapper):
    """:class:`NormalizeObservation` over the envs of a vector env, images channels first."""

    def __init__(self, env: gym.vector.VectorEnv, normalization: ObsNormalization | None) -> None:
        super().__init__(env)
        self.normalization = normalization
        single = env.single_observation_space
        self.image = len(single.shape) == 3
        if self.image:
            self.single_observation_space = spaces.Box(
                np.transpose(single.low, (2, 0, 1)), np.transpose(single.high, (2, 0, 1)),
                dtype=single.dtype,
            )  # fmt: skip
        if normalization is not None:
            self.single_observation_space = normalization.space(single.shape)
        self.observation_space = gym.vector.utils.batch_space(
            self.single_observation_space, env.num_envs
        )

    def observations(self, observations: np.ndarray) -> np.ndarray:
        if self.image:
            return np.ascontiguousarray(np.transpose(observations, (0, 3, 1, 2)))
        return observations if self.normalization is None else self.normalization(observations)


class Policy:
    """A trained agent (see the module's docstring): ``act``, ``env_kwargs``, ``make_env``,
    ``make_vec``; ``config`` is its training config, ``source`` the file or folder loaded."""

    def __init__(
        self,
        act: Callable[[np.ndarray, bool], np.ndarray],
        observation_space: spaces.Space,
        config: AnyConfig,
        source: Path,
        normalization: ObsNormalization | None,
        model: Any = None,
    ) -> None:
        self._act = act
        self.model = model  # stable-baselines3's model, when it is one
        self.observation_space = observation_space
        self.config = config
        self.source = source
        self.normalization = normalization

    @property
    def env_id(self) -> str:
        return self.config.env.id

    @property
    def env_kwargs(self) -> dict[str, Any]:
        """The options of ``gym.make(env_id, ...)`` it was trained with (the time limit in
        frames included)."""
        kwargs = dict(self.config.env.make_kwargs)
        if kwargs.get("max_episode_steps") is None:
            kwargs.pop("max_episode_steps", None)  # gym.make's own: the registered one
        return kwargs

    @property
    def frame_stack(self) -> int:
        return self.config.env.frame_stack

    def reset(self) -> None:
        """A new game (or games) starts: a recurrent agent forgets what it remembers (its LSTM
        state; nothing for the others). :meth:`act` carries that state from call to call."""
        reset = getattr(self._act, "reset", None)
        if reset is not None:
            reset()

    def act(self, obs: np.ndarray, deterministic: bool = True) -> Any:
        """The action for one observation of the env chain (an int for discrete actions), or
        the actions for a batch of them; greedy unless ``deterministic`` is false. A recurrent
        agent's carries its memory from call to call: :meth:`reset` it at a new game."""
        obs = np.asarray(obs)
        single = obs.shape == self.observation_space.shape
        actions = self._act(obs[None] if single else obs, deterministic)
        if not single:
            return actions
        action = np.asarray(actions)[0]
        return int(action) if action.ndim == 0 else action

    def make_env(self, **overrides: Any) -> gym.Env:
        """``gym.make(env_id, **env_kwargs, **overrides)`` with the frame stack and the frozen
        observation statistics it was trained with (``render_mode="human"`` to watch it)."""
        env = gym.make(self.env_id, **{**self.env_kwargs, **overrides})
        if self.frame_stack > 1 or len(env.observation_space.shape) == 3:
            env = StackedObservation(env, self.frame_stack)
        if self.normalization is not None:
            env = NormalizeObservation(env, self.normalization)
        self._check_space(env.observation_space, overrides)
        return env

    def make_vec(self, num_envs: int, **overrides: Any) -> gym.vector.VectorEnv:
        """``num_envs`` games of the chain: the native vector env (``PinballVectorEnv``; a
        ``SyncVectorEnv`` of :meth:`make_env` games when frames are stacked)."""
        if self.frame_stack > 1:
            return gym.vector.SyncVectorEnv([partial(self.make_env, **overrides)] * num_envs)
        kwargs = {**self.config.env.make_kwargs, **overrides}
        venv = gym.make_vec(self.env_id, num_envs, vectorization_mode="vector_entry_point",
                            **kwargs)  # fmt: skip
        venv = NormalizeVectorObservation(venv, self.normalization)
        self._check_space(venv.single_observation_space, overrides)
        return venv

    def _check_space(self, space: spaces.Space, overrides: dict[str, Any]) -> None:
        if space.shape != self.observation_space.shape:
            raise ValueError(
                f"{self.source}: the env's observations {space.shape} are not the policy's "
                f"{self.observation_space.shape} (overrides {overrides})"
            )


def load_policy(path: str | os.PathLike[str]) -> Policy:
    """The agent saved at ``path`` (see the module's docstring): a run folder (its final model,
    or its newest checkpoint while it has none), a model or checkpoint zip, an RLlib
    checkpoint folder, or ``"pretrained:NAME"``. Every loading of a saved agent in ``agents``
    goes through here."""
    path = resolve_model_path(path)
    if not path.exists():
        raise ConfigError(f"{path}: no such file or folder")
    if path.is_dir() and not is_rllib_checkpoint(path):
        model_path = path / MODEL_FILE
        if not model_path.is_file():
            newest = latest_checkpoint(path)
            if newest is None:
                raise ConfigError(f"{path}: no {MODEL_FILE} and no checkpoint in this folder")
            model_path = newest[1]
        path = model_path
    return _rllib_policy(path) if is_rllib_checkpoint(path) else _sb3_policy(path)


def read_agent_entry(model_path: Path) -> dict[str, Any] | None:
    """The config and statistics a model zip carries (``AGENT_ENTRY``), or None (an older zip)."""
    try:
        with zipfile.ZipFile(model_path) as archive:
            if AGENT_ENTRY not in archive.namelist():
                return None
            return json.loads(archive.read(AGENT_ENTRY))
    except (zipfile.BadZipFile, json.JSONDecodeError, OSError) as error:
        raise ConfigError(f"{model_path}: not a readable model zip: {error}") from None


def _sb3_policy(model_path: Path) -> Policy:
    entry = read_agent_entry(model_path)
    if entry is not None:
        config = config_from_dict(entry["config"], f"{model_path}:{AGENT_ENTRY}")
    else:
        run = next((p for p in (model_path.parent, model_path.parent.parent)
                    if (p / CONFIG_FILE).is_file()), None)  # fmt: skip
        if run is None:
            raise ConfigError(
                f"{model_path}: the model carries no config and no {CONFIG_FILE} is beside it "
                "or one folder up: copy the run's config.yaml next to it"
            )
        config = load_config(run / CONFIG_FILE)
    normalization = None
    if config.env.normalize and config.env.kwargs.get("obs_type", "state") == "state":
        normalization = _sb3_statistics(model_path, entry)
    model = algorithm_class(config.algo).load(model_path, device=config.device)
    return Policy(Predictor(model), model.observation_space, config, model_path, normalization,
                  model)  # fmt: skip


class Predictor:
    """A stable-baselines3 model's actions for a batch of observations, ``(obs, deterministic)
    -> actions``. A recurrent model's (sb3-contrib's RecurrentPPO) carry its LSTM state from
    call to call, each env's own, from a fresh state at the first call and after
    :meth:`reset` (or when the batch changes size): call it once per step of the same envs,
    and reset it where a new game starts in all of them."""

    def __init__(self, model: Any) -> None:
        self.model = model
        self.recurrent = hasattr(model.policy, "lstm_actor")
        self.reset()

    def reset(self) -> None:
        """Forget the recurrent state: the next call starts every env afresh."""
        self._state: Any = None
        self._batch = -1

    def __call__(self, obs: np.ndarray, deterministic: bool = True) -> np.ndarray:
        if not self.recurrent:
            return self.model.predict(obs, deterministic=deterministic)[0]
        starts = np.full(len(obs), len(obs) != self._batch)
        actions, self._state = self.model.predict(
            obs, state=None if starts[0] else self._state, episode_start=starts,
            deterministic=deterministic,
        )  # fmt: skip
        self._batch = len(obs)
        return actions


def _sb3_statistics(model_path: Path, entry: dict[str, Any] | None) -> ObsNormalization:
    """The observation statistics of a model: those its zip carries, or the ``VecNormalize``
    saved beside it."""
    stats = None if entry is None else entry.get("obs_normalization")
    if stats is not None:
        return ObsNormalization.from_moments(
            stats["mean"], stats["var"], stats["epsilon"], stats["clip_obs"]
        )
    pickled = stats_for(model_path)
    if pickled is None:
        raise ConfigError(
            f"{model_path}: its VecNormalize statistics are missing: the zip carries none and "
            f"{model_path.stem}_{STATS_FILE} is not beside it"
        )
    with open(pickled, "rb") as file:
        venv = pickle.load(file)
    rms = venv.obs_rms
    return ObsNormalization.from_moments(rms.mean, rms.var, venv.epsilon, venv.clip_obs)


def _rllib_policy(path: Path) -> Policy:
    """An RLlib checkpoint's RL module and its frozen ``MeanStdFilter``, in this process."""
    import torch
    from ray.rllib.core.columns import Columns
    from ray.rllib.core.rl_module.rl_module import RLModule

    checkpoint, config = rllib_checkpoint(path)
    torch.set_num_threads(config.torch_threads)
    module = RLModule.from_checkpoint(str(checkpoint.joinpath(*MODULE_PATH).resolve()))
    module.eval()
    if not isinstance(module.action_space, spaces.Discrete):
        raise ConfigError(f"{path}: RLlib policies load for discrete actions only")
    normalization = _rllib_filter(checkpoint, module, config)

    def act(obs: np.ndarray, deterministic: bool) -> np.ndarray:
        with torch.no_grad():
            out = module.forward_inference({Columns.OBS: torch.as_tensor(obs, dtype=torch.float32)})
        logits = out[Columns.ACTION_DIST_INPUTS]
        if deterministic:
            return logits.argmax(dim=-1).numpy()
        return torch.distributions.Categorical(logits=logits).sample().numpy()

    return Policy(act, module.observation_space, config, checkpoint, normalization)


def _rllib_filter(checkpoint: Path, module: Any, config: RllibConfig) -> ObsNormalization | None:
    """The running mean and std a checkpoint's env runners normalised with, frozen."""
    filter_path = checkpoint.joinpath(*FILTER_PATH)
    if not filter_path.is_dir():
        if config.env.normalize:
            raise ConfigError(f"{checkpoint}: its observation filter (MeanStdFilter) is missing")
        return None
    from ray.rllib.connectors.env_to_module import MeanStdFilter
    from ray.rllib.utils.filter import RunningStat
    from ray.rllib.utils.numpy import SMALL_NUMBER

    trained = MeanStdFilter()  # as the env runners made it; then their spaces
    trained.input_action_space = module.action_space
    trained.input_observation_space = module.observation_space
    trained.restore_from_path(str(filter_path.resolve()))
    state = trained.get_state()[None]
    stat = RunningStat.from_state(state["running_stats"][0])
    shape = np.shape(stat.mean)
    offset = stat.mean if state["de_mean_to_zero"] else np.zeros(shape)
    scale = stat.std + SMALL_NUMBER if state["de_std_to_one"] else np.ones(shape)
    clip = state["clip_by_value"]
    return ObsNormalization(np.asarray(offset, np.float64), np.asarray(scale, np.float64),
                            float(clip) if clip else None)  # fmt: skip
