"""``SB3VecEnv``: the native vector env as a stable-baselines3 ``VecEnv``.

stable-baselines3 takes its own ``VecEnv`` class, not Gymnasium's vector envs, and resets an
env in the step that ends its episode, keeping the last observation in
``info["terminal_observation"]``: this adapter runs the native vector env in Gymnasium's
``SAME_STEP`` autoreset mode, which does exactly that::

    env = SB3VecEnv(gym.make_vec("Pinball-v0", num_envs=16))
    PPO("MlpPolicy", env).learn(100_000)
"""

import time
from collections.abc import Iterable, Sequence
from typing import Any

import numpy as np
from gymnasium.vector import AutoresetMode

from pinball_env.vector_env import PinballVectorEnv

try:
    from stable_baselines3.common.vec_env import VecEnv
except ImportError as error:  # pragma: no cover - depends on the install
    from gymnasium.error import DependencyNotInstalled

    raise DependencyNotInstalled(
        'SB3VecEnv needs stable-baselines3: pip install -e ".[train]"'
    ) from error


class SB3VecEnv(VecEnv):
    """A stable-baselines3 ``VecEnv`` over a :class:`PinballVectorEnv`.

    The vector env is switched to ``SAME_STEP`` autoreset (before its first step). Give it the
    bare vector env: Gymnasium vector wrappers would be bypassed (use SB3's ``VecEnv`` wrappers,
    such as ``VecNormalize``, around this one). Infos are a dict per env: the vector env's info
    keys, ``TimeLimit.truncated`` every step, and ``terminal_observation`` and ``episode``
    (``r``, ``l``, ``t``, as SB3's ``Monitor`` writes them) when its episode ends. ``seed(s)``
    seeds env i with ``s + i`` at the next reset. ``get_attr``, ``set_attr`` and
    ``env_method`` act on the one vector env, whose attributes every env shares.
    """

    def __init__(self, venv: PinballVectorEnv) -> None:
        if not isinstance(venv, PinballVectorEnv):
            raise TypeError(
                f"SB3VecEnv wraps a bare PinballVectorEnv (gym.make_vec('Pinball-v0', ...)), got "
                f"{type(venv).__name__}: a wrapper around it would be bypassed"
            )
        venv.autoreset_mode = AutoresetMode.SAME_STEP
        venv.metadata = {**venv.metadata, "autoreset_mode": AutoresetMode.SAME_STEP}
        self.venv = venv
        self._actions: np.ndarray | None = None
        self._start = time.perf_counter()
        super().__init__(venv.num_envs, venv.single_observation_space, venv.single_action_space)

    def reset(self) -> np.ndarray:
        seeds = None if all(seed is None for seed in self._seeds) else list(self._seeds)
        options = self._options[0] if self._options and self._options[0] else None
        obs, infos = self.venv.reset(seed=seeds, options=options)
        self._reset_seeds()
        self._reset_options()
        self.reset_infos = _per_env(infos, self.num_envs)
        return obs

    def step_async(self, actions: np.ndarray) -> None:
        self._actions = actions

    def step_wait(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, list[dict[str, Any]]]:
        obs, rewards, terminated, truncated, infos = self.venv.step(self._actions)
        dones = terminated | truncated
        per_env = _per_env(infos, self.num_envs)
        for env in range(self.num_envs):
            per_env[env]["TimeLimit.truncated"] = bool(truncated[env] and not terminated[env])
        for env in np.flatnonzero(dones):
            # The last step of the episode (the env has been reset since).
            final = infos["final_info"]
            info = per_env[env] = {
                key: value[env] for key, value in final.items()
                if isinstance(value, np.ndarray) and not key.startswith("_")
            }  # fmt: skip
            info["terminal_observation"] = infos["final_obs"][env]
            info["TimeLimit.truncated"] = bool(truncated[env] and not terminated[env])
            info["episode"] = {
                "r": round(float(infos["episode_return"][env]), 6),
                "l": int(infos["episode_length"][env]),
                "t": round(time.perf_counter() - self._start, 6),
            }
        return obs, rewards.astype(np.float32), dones, per_env

    def close(self) -> None:
        self.venv.close()

    def get_images(self) -> Sequence[np.ndarray | None]:
        frames = self.venv.render()
        return [None] * self.num_envs if frames is None else list(frames)

    def get_attr(self, attr_name: str, indices: Any = None) -> list[Any]:
        return [getattr(self.venv, attr_name)] * len(self._indices(indices))

    def set_attr(self, attr_name: str, value: Any, indices: Any = None) -> None:
        if len(self._indices(indices)) != self.num_envs:
            raise ValueError("the envs share one vector env: set an attribute for all of them")
        setattr(self.venv, attr_name, value)

    def env_method(
        self, method_name: str, *method_args: Any, indices: Any = None, **method_kwargs: Any
    ) -> list[Any]:
        result = getattr(self.venv, method_name)(*method_args, **method_kwargs)
        return [result] * len(self._indices(indices))

    def env_is_wrapped(self, wrapper_class: type, indices: Any = None) -> list[bool]:
        return [False] * len(self._indices(indices))

    def _indices(self, indices: Any) -> list[int]:
        if indices is None:
            return list(range(self.num_envs))
        if isinstance(indices, int):
            return [indices]
        return list(indices) if isinstance(indices, Iterable) else [indices]


def _per_env(infos: dict[str, Any], num_envs: int) -> list[dict[str, Any]]:
    """The single env's info dicts from the vector env's arrays (without the masks)."""
    keys = [key for key, value in infos.items() if isinstance(value, np.ndarray)]
    keys = [key for key in keys if not key.startswith("_") and key != "final_obs"]
    return [{key: infos[key][env] for key in keys} for env in range(num_envs)]
