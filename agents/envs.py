"""The env chain a config describes, as stable-baselines3 sees it: the native vector env through
``SB3VecEnv``, frame stacking, channels first for images, and ``SB3VecNormalize`` (SB3's
``VecNormalize`` without its per-env loop; or frozen statistics for an evaluation); and the
frames its games play."""

from collections.abc import Callable
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np

import pinball_env  # noqa: F401  (registers Pinball-v0)
from agents.config import TrainConfig
from pinball_env.wrappers import SB3VecEnv, SB3VecNormalize


def make_env_chain(
    config: TrainConfig,
    num_envs: int | None = None,
    seed: int | None = None,
    stats: Path | None = None,
    render: bool = False,
    frozen: Callable[[np.ndarray], np.ndarray] | None = None,
    step_infos: bool = True,
) -> Any:
    """The stable-baselines3 VecEnv a config trains on: the native vector env (``num_envs``
    games, env i first reset with ``seed + i``), frame stacking, and ``SB3VecNormalize``.

    With ``stats`` (a saved ``VecNormalize``), its statistics are loaded and frozen, and rewards
    are left raw; with ``frozen`` (a policy's ``ObsNormalization``), observations are
    normalised by it instead: either is the evaluation's view of the same env. Without
    ``step_infos`` (training's chain), a step's infos are filled only for the envs whose game
    ended (``SB3VecEnv``): a scripted player, which reads every env's info, needs them.
    """
    from stable_baselines3.common.vec_env import VecFrameStack, VecNormalize, VecTransposeImage

    kwargs = config.env.make_kwargs
    venv = SB3VecEnv(
        gym.make_vec(
            config.env.id, num_envs=num_envs or config.env.num_envs,
            vectorization_mode="vector_entry_point", num_threads=config.env_threads,
            render_mode="rgb_array" if render else None, **kwargs,
        ),
        step_infos=step_infos,
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
            venv = SB3VecNormalize(
                venv, norm_obs=not image, gamma=config.hyperparams.get("gamma", 0.99)
            )
    return venv


def native_env(venv: Any) -> Any:
    """The native vector env (``PinballVectorEnv``) at the bottom of an SB3 env chain."""
    while not hasattr(venv, "clone_state"):
        venv = venv.venv
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
    """The frames played by all envs of a VecEnv chain over ``SB3VecEnv`` (its ``frames``,
    counted from the vector env's arrays: a step's frames vary with the frame skip,
    ``skip_above`` and the end of a game), ``frames`` before it was made included."""

    def __init__(self, venv: Any, frames: int = 0) -> None:
        self.venv = venv.unwrapped
        self.offset = frames - self.venv.frames

    @property
    def frames(self) -> int:
        return self.offset + self.venv.frames
