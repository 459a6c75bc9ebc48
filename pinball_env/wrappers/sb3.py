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
from typing import Any, TypeGuard

import numba
import numpy as np
from gymnasium.vector import AutoresetMode

from pinball_env.envs import PinballVectorEnv
from pinball_env.extras import require

require("stable_baselines3")
from stable_baselines3.common.running_mean_std import RunningMeanStd  # noqa: E402
from stable_baselines3.common.vec_env import VecEnv, VecNormalize  # noqa: E402


class SB3VecEnv(VecEnv):
    """A stable-baselines3 ``VecEnv`` over a :class:`PinballVectorEnv`.

    The vector env is switched to ``SAME_STEP`` autoreset (before its first step). Give it the
    bare vector env: Gymnasium vector wrappers would be bypassed (use SB3's ``VecEnv`` wrappers,
    such as ``VecNormalize``, around this one). Infos are a dict per env, as SB3 wants them,
    filled only where SB3 reads them: an env whose episode ended in the step has the vector
    env's info keys of its last step, ``terminal_observation``, ``TimeLimit.truncated`` and
    ``episode`` (``r``, ``l``, ``t``, as SB3's ``Monitor`` writes them); the others' dicts are
    empty, so that a step does no per-env Python work for them. With ``step_infos`` every env's
    dict has its info keys and ``TimeLimit.truncated`` every step (a scripted player reads
    them; a callback can switch it at any time). ``frames`` counts the frames every env has
    played since the adapter was made, from the vector env's arrays. ``seed(s)`` seeds env i
    with ``s + i`` at the next reset. ``get_attr``, ``set_attr`` and ``env_method`` act on each
    env of ``indices`` (default: all) as the vector env's ``env_attr``, ``set_env_attr`` and
    ``call_env`` do (see ``PinballVectorEnv``): per-env attributes such as ``table``,
    ``layout`` (procgen) or ``np_random`` are each env's own, the vector env's attributes are
    shared (``set_attr`` of one of them needs every env), and other names are the user's, per
    env.
    """

    def __init__(self, venv: PinballVectorEnv, step_infos: bool = False) -> None:
        if not isinstance(venv, PinballVectorEnv):
            raise TypeError(
                f"SB3VecEnv wraps a bare PinballVectorEnv (gym.make_vec('Pinball-v0', ...)), got "
                f"{type(venv).__name__}: a wrapper around it would be bypassed"
            )
        venv.autoreset_mode = AutoresetMode.SAME_STEP
        venv.metadata = {**venv.metadata, "autoreset_mode": AutoresetMode.SAME_STEP}
        self.venv = venv
        self.step_infos = step_infos
        self.frames = 0  # frames played by all envs since the adapter was made
        self._game_frames = np.zeros(venv.num_envs, dtype=np.int64)  # each game's, last step
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
        self._game_frames[:] = infos["frames"]
        return obs

    def step_async(self, actions: np.ndarray) -> None:
        self._actions = actions

    def step_wait(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, list[dict[str, Any]]]:
        obs, rewards, terminated, truncated, infos = self.venv.step(self._actions)
        dones = terminated | truncated
        ended = np.flatnonzero(dones)
        frames = infos["frames"]
        if ended.size:
            frames = frames.copy()
            frames[ended] = infos["final_info"]["frames"][ended]  # the games that ended
        self.frames += int((frames - self._game_frames).sum())
        self._game_frames[:] = frames
        self._game_frames[ended] = 0
        if self.step_infos:
            per_env = _per_env(infos, self.num_envs)
            for info, cut in zip(per_env, (truncated & ~terminated).tolist(), strict=True):
                info["TimeLimit.truncated"] = cut
        else:
            per_env = [{} for _ in range(self.num_envs)]
        final = infos.get("final_info", {})  # the last step of the episodes that ended
        for env in ended:
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
        return [self.venv.env_attr(env, attr_name) for env in self._indices(indices)]

    def set_attr(self, attr_name: str, value: Any, indices: Any = None) -> None:
        envs = self._indices(indices)
        if self._every_env(envs):  # then a shared attribute too
            self.venv.set_attr(attr_name, [value] * self.num_envs)
            return
        for env in envs:
            self.venv.set_env_attr(env, attr_name, value)

    def env_method(
        self, method_name: str, *method_args: Any, indices: Any = None, **method_kwargs: Any
    ) -> list[Any]:
        envs = self._indices(indices)
        if self._every_env(envs):  # then a method of the vector env too, called once
            return list(self.venv.call(method_name, *method_args, **method_kwargs))
        return [self.venv.call_env(env, method_name, *method_args, **method_kwargs) for env in envs]

    def env_is_wrapped(self, wrapper_class: type, indices: Any = None) -> list[bool]:
        return [False] * len(self._indices(indices))

    def _every_env(self, envs: list[int]) -> bool:
        return sorted(envs) == list(range(self.num_envs))

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


class SB3VecNormalize(VecNormalize):
    """stable-baselines3's ``VecNormalize``, bitwise, at the env's speed: a step normalises the
    terminal observations of the envs whose game ended, found with ``np.flatnonzero``, rather
    than testing every env's ``done`` in Python, and an array observation's batch moments and
    normalisation are each one compiled pass (:func:`batch_moments`, :func:`normalized`) doing
    numpy's float operations in numpy's order, rather than a dozen numpy temporaries. Saved and
    loaded as ``VecNormalize`` is (``VecNormalize.load`` returns this class for what it saved)."""

    def step_wait(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, list[dict[str, Any]]]:
        obs, rewards, dones, infos = self.venv.step_wait()
        assert isinstance(obs, (np.ndarray, dict))  # (as VecNormalize's: not a tuple)
        self.old_obs = obs
        self.old_reward = rewards
        if self.training and self.norm_obs:
            rms = self.obs_rms  # one RunningMeanStd for an array, one per key for a dict
            if _compiled(obs) and isinstance(rms, RunningMeanStd) and rms.mean.size > 1:
                shape = rms.mean.shape
                mean, var = batch_moments(np.ascontiguousarray(obs).reshape(len(obs), -1))
                rms.update_from_moments(mean.reshape(shape), var.reshape(shape), len(obs))
            elif isinstance(obs, dict) and isinstance(rms, dict):
                for key in rms:
                    rms[key].update(obs[key])
            else:
                assert isinstance(rms, RunningMeanStd)
                rms.update(obs)
        obs = self.normalize_obs(obs)
        if self.training:
            self._update_reward(rewards)
        rewards = self.normalize_reward(rewards)
        for env in np.flatnonzero(dones):
            if "terminal_observation" in infos[env]:
                infos[env]["terminal_observation"] = self.normalize_obs(
                    infos[env]["terminal_observation"]
                )
        self.returns[dones] = 0
        return obs, rewards, dones, infos

    def normalize_obs(self, obs: np.ndarray | dict[str, np.ndarray]) -> Any:
        rms = self.obs_rms
        if not (self.norm_obs and _compiled(obs) and isinstance(rms, RunningMeanStd)):
            return super().normalize_obs(obs)
        std = np.sqrt(rms.var + self.epsilon).reshape(-1)
        rows = np.ascontiguousarray(obs).reshape(-1, std.size)  # one row per observation
        return normalized(rows, rms.mean.reshape(-1), std, float(self.clip_obs)).reshape(
            np.shape(obs)
        )


def _compiled(obs: Any) -> TypeGuard[np.ndarray]:
    """Whether the compiled passes take ``obs``: a float array (numpy sums integers in float64)."""
    return isinstance(obs, np.ndarray) and obs.dtype in (np.float32, np.float64)


@numba.njit(cache=True)
def batch_moments(rows: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``np.mean(rows, axis=0)`` and ``np.var(rows, axis=0)``, bitwise for rows of two or more
    columns: numpy then reduces axis 0 of a C-contiguous array row after row in the array's own
    dtype, as this does (a single column it sums pairwise)."""
    n, width = rows.shape
    total = np.zeros(width, rows.dtype)
    for i in range(n):
        for j in range(width):
            total[j] += rows[i, j]
    mean = (total / n).astype(rows.dtype)  # as numpy divides: exact, then rounded once
    squares = np.zeros(width, rows.dtype)
    for i in range(n):
        for j in range(width):
            x = rows[i, j] - mean[j]
            squares[j] += x * x
    return mean, (squares / n).astype(rows.dtype)


@numba.njit(cache=True)
def normalized(rows: np.ndarray, mean: np.ndarray, std: np.ndarray, clip: float) -> np.ndarray:
    """``np.clip((rows - mean) / std, -clip, clip).astype(np.float32)``, bitwise, in one pass."""
    out = np.empty(rows.shape, np.float32)
    for i in range(rows.shape[0]):
        for j in range(rows.shape[1]):
            x = (rows[i, j] - mean[j]) / std[j]
            if x < -clip:
                x = -clip
            elif x > clip:
                x = clip
            out[i, j] = x
    return out
