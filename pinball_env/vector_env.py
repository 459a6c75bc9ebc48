"""``PinballVectorEnv``: N pinball games stepped together, natively batched.

``gym.make_vec("Pinball-v0", num_envs=N)`` returns it. It runs the very same ``Game`` (rules)
and kernel (physics) as the single env, over N envs in one call, on ``num_threads`` threads.
"""

import os
from collections.abc import Mapping
from typing import Any, ClassVar

import numpy as np
from gymnasium.error import ResetNeeded
from gymnasium.utils import seeding
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.vector.utils import batch_space

from pinball_env import MAX_EPISODE_STEPS
from pinball_env.env import (
    OBS_TYPES,
    _image_size,
    make_spaces,
    obs_renderer,
    render_frame,
)
from pinball_env.game import Game, InvalidActions, check_choice
from pinball_env.procgen import load_any_table
from pinball_env.render import Renderer, render_size
from pinball_env.table import Table

# Envs per thread below which a second thread costs more than it saves.
MIN_ENVS_PER_THREAD = 32
AUTORESET_MODES = (AutoresetMode.NEXT_STEP, AutoresetMode.SAME_STEP)


def default_threads(num_envs: int) -> int:
    """One thread per core (at most 8), as long as each has MIN_ENVS_PER_THREAD envs."""
    cores = min(os.cpu_count() or 1, 8)
    return max(1, min(cores, num_envs // MIN_ENVS_PER_THREAD))


class PinballVectorEnv(VectorEnv):
    """``num_envs`` games of ``Pinball-v0`` in one batch (see ``PinballEnv`` for the game,
    its spaces, rewards and infos).

    ## Arguments

    ```python
    gym.make_vec("Pinball-v0", num_envs=1024, table="classic", obs_type="state",
                 action_type="discrete", balls=3, reward_scale=0.01, height_shaping=0.0,
                 drain_penalty=0.0, frame_skip=1, skip_above=0.0, max_frames=None,
                 image_size=(84, 84), physics="swept", render_mode=None,
                 max_episode_steps=7200, num_threads=None, autoreset_mode="NextStep")
    ```

    Every argument of ``PinballEnv``, plus:

    - ``num_envs``: games stepped together.
    - ``max_episode_steps``: truncation after this many steps of an episode (None: never);
      ``gym.make_vec`` passes the registered 7200 (with ``frame_skip=k``, pass 7200 // k for
      the same two minutes, or None and ``max_frames=7200``, which counts frames whatever the
      frame skip or ``skip_above``).
    - ``num_threads``: threads that share the envs (None: one per core while each has at least
      32 envs). Results are bitwise the same for any count.
    - ``autoreset_mode``: ``NEXT_STEP`` (Gymnasium's default: an env that ended is reset by the
      next ``step``, which ignores its action and returns the reset observation, reward 0) or
      ``SAME_STEP`` (reset in the same step; the last observation and info of the episode are
      in ``info["final_obs"]`` and ``info["final_info"]``, masked by ``_final_obs``).

    ## Infos

    Arrays over the envs, each with a ``_key`` mask: ``ball_position`` (N, 2), ``ball_velocity``
    (N, 2), ``score``, ``balls_left``, ``points`` (this step), ``drained`` and ``frames``; when
    episodes end, ``episode_return`` and ``episode_length`` masked by the envs that ended (the key
    ``episode`` is left to Gymnasium's ``RecordEpisodeStatistics``). In SAME_STEP mode,
    ``final_obs`` (an object array) and ``final_info`` (arrays with their own ``_key`` masks)
    hold the ended envs' last observation and info, as ``SyncVectorEnv`` does. The per-step
    ``events`` of the single env are not batched.

    ``reset(seed=s)`` seeds env i with ``s + i`` (or a list gives one seed per env), so env i
    plays exactly as ``gym.make("Pinball-v0")`` reset with that seed and given the same actions.
    ``reset(options={"reset_mask": mask, ...})`` resets only the masked envs; the other options
    are the single env's (``ball_position``, ``ball_velocity``).
    """

    metadata: ClassVar[dict[str, Any]] = {
        "render_modes": ["rgb_array"],
        "render_fps": 60,
        "autoreset_mode": AutoresetMode.NEXT_STEP,
    }

    def __init__(
        self,
        num_envs: int = 1,
        table: str | os.PathLike[str] | Table = "classic",
        obs_type: str = "state",
        action_type: str = "discrete",
        balls: int = 3,
        reward_scale: float = 0.01,
        height_shaping: float = 0.0,
        drain_penalty: float = 0.0,
        frame_skip: int = 1,
        skip_above: float = 0.0,
        max_frames: int | None = None,
        image_size: int | tuple[int, int] = (84, 84),
        physics: str = "swept",
        render_mode: str | None = None,
        max_episode_steps: int | None = MAX_EPISODE_STEPS,
        num_threads: int | None = None,
        autoreset_mode: AutoresetMode | str = AutoresetMode.NEXT_STEP,
    ) -> None:
        if not _is_int(num_envs) or num_envs < 1:
            raise ValueError(f"num_envs must be an integer >= 1, got {num_envs!r}")
        if max_episode_steps is not None and (
            not _is_int(max_episode_steps) or max_episode_steps < 1
        ):
            raise ValueError(
                f"max_episode_steps must be None or an integer >= 1, got {max_episode_steps!r}"
            )
        check_choice("obs_type", obs_type, OBS_TYPES)
        check_choice("render_mode", render_mode, (None, *self.metadata["render_modes"]))
        self.autoreset_mode = _autoreset_mode(autoreset_mode)
        self.num_envs = int(num_envs)
        self.image_size = _image_size(image_size)
        self.table = table if isinstance(table, Table) else load_any_table(table)
        threads = default_threads(self.num_envs) if num_threads is None else num_threads
        self.game = Game(
            self.table, n_envs=self.num_envs, balls_per_game=balls, action_type=action_type,
            reward_scale=reward_scale, height_shaping=height_shaping,
            drain_penalty=drain_penalty, frame_skip=frame_skip, skip_above=skip_above,
            max_frames=max_frames, physics=physics,
            num_threads=threads if physics == "swept" else 1,
        )  # fmt: skip
        self.num_threads = self.game.world.threads.num_threads
        self.obs_type = obs_type
        self.render_mode = render_mode
        self.max_episode_steps = max_episode_steps
        self.metadata = {
            **self.metadata,
            "render_fps": self.table.simulation.frame_rate / self.game.frame_skip,
            "autoreset_mode": self.autoreset_mode,
        }
        self.single_action_space, self.single_observation_space = make_spaces(
            self.game, obs_type, self.image_size
        )
        self.action_space = batch_space(self.single_action_space, self.num_envs)
        self.observation_space = batch_space(self.single_observation_space, self.num_envs)
        self._obs_renderer = obs_renderer(self.table, obs_type, self.image_size)
        self._frame_renderer: Renderer | None = None
        n = self.num_envs
        self._rngs = [seeding.np_random()[0] for _ in range(n)]
        self._returns = np.zeros(n)
        self._lengths = np.zeros(n, dtype=np.int64)
        self._ended = np.zeros(n, dtype=bool)  # NEXT_STEP: reset these at the next step
        self._reset_done = False

    # --- Gymnasium API ------------------------------------------------------------------------

    def reset(
        self,
        *,
        seed: int | list[int | None] | None = None,
        options: Mapping[str, Any] | None = None,
    ) -> tuple[np.ndarray, dict[str, Any]]:
        super().reset(seed=seed if isinstance(seed, int) else None)
        options = dict(options or {})
        mask = options.pop("reset_mask", None)
        envs = np.arange(self.num_envs) if mask is None else self._mask_envs(mask)
        seeds = self._seeds(seed)
        for env in envs:
            if seeds[env] is not None:
                self._rngs[env] = seeding.np_random(seeds[env])[0]
            self._new_game(int(env), options)
        self._returns[envs] = 0.0
        self._lengths[envs] = 0
        self._ended[envs] = False
        self._reset_done = True
        return self._observe(), self._infos(envs)

    def step(
        self, actions: Any
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, dict[str, Any]]:
        if not self._reset_done:
            raise ResetNeeded("call reset() before step(): no game has started")
        restart = self._ended.copy()
        for env in np.flatnonzero(restart):  # NEXT_STEP: the envs that ended last step
            self._new_game(int(env))
            self._returns[env] = 0.0
            self._lengths[env] = 0
        try:  # the game checks the actions, before it steps
            reward, game_over = self.game.step(actions, self._rngs, frozen=restart)
        except InvalidActions as error:
            raise ValueError(f"{error} (the action space is {self.action_space})") from None
        lengths = self._lengths
        lengths[~restart] += 1
        self._returns += reward
        terminated = game_over & ~restart
        truncated = np.zeros(self.num_envs, dtype=bool)
        if self.max_episode_steps is not None:  # as Gymnasium's TimeLimit: even if terminated
            truncated = (lengths >= self.max_episode_steps) & ~restart
        truncated |= self.game.out_of_time() & ~restart
        ended = terminated | truncated
        obs, infos = self._observe(), self._infos()
        if ended.any():
            infos["episode_return"] = np.where(ended, self._returns, 0.0)
            infos["episode_length"] = np.where(ended, lengths, 0)
            infos["_episode_return"] = infos["_episode_length"] = ended.copy()
        if self.autoreset_mode == AutoresetMode.SAME_STEP and ended.any():
            obs, infos = self._reset_same_step(ended, obs, infos)
            ended[:] = False
        self._ended = ended
        return obs, reward, terminated, truncated, infos

    def render(self) -> tuple[np.ndarray, ...] | None:
        """Every env's frame (the playfield and a scoreboard), for ``render_mode="rgb_array"``."""
        if self.render_mode is None:
            return None
        if self._frame_renderer is None:
            self._frame_renderer = Renderer(self.table, *render_size(self.table))
        return tuple(
            render_frame(self._frame_renderer, self.game, env) for env in range(self.num_envs)
        )

    def close_extras(self, **kwargs: Any) -> None:
        """Stop the threads that step the envs (none if the constructor refused its options)."""
        if hasattr(self, "game"):
            self.game.world.threads.close()

    # --- helpers ------------------------------------------------------------------------------

    def _new_game(self, env: int, options: Mapping[str, Any] | None = None) -> None:
        self.game.new_game(env, self._rngs[env], options)

    def _observe(self) -> np.ndarray:
        if self._obs_renderer is None:
            return self.game.observe()
        world = self.game.world
        return self._obs_renderer.frames(
            world.balls, world.active, world.state.flipper_angle,
            grayscale=self.obs_type == "grayscale", threads=world.threads,
        )  # fmt: skip

    def _infos(self, envs: np.ndarray | None = None) -> dict[str, Any]:
        """The infos, masked to ``envs`` (default: all)."""
        infos = self.game.infos()
        mask = np.ones(self.num_envs, dtype=bool)
        if envs is not None:
            mask = np.zeros(self.num_envs, dtype=bool)
            mask[envs] = True
        for key in list(infos):
            infos[f"_{key}"] = mask
        return infos

    def _reset_same_step(
        self, ended: np.ndarray, obs: np.ndarray, infos: dict[str, Any]
    ) -> tuple[np.ndarray, dict[str, Any]]:
        """SAME_STEP: reset the envs that ended, keeping their last observation and info."""
        final_obs = np.empty(self.num_envs, dtype=object)
        final_info: dict[str, np.ndarray] = {}
        for key, value in infos.items():
            if not key.startswith("_"):
                final_info[key] = np.where(ended.reshape(-1, *[1] * (value.ndim - 1)), value, 0)
                final_info[f"_{key}"] = ended.copy()
        for env in np.flatnonzero(ended):
            final_obs[env] = obs[env].copy()
        for env in np.flatnonzero(ended):
            self._new_game(int(env))
        self._returns[ended] = 0.0
        self._lengths[ended] = 0
        obs, infos_after = self._observe(), self._infos()
        infos_after.update(
            {"final_obs": final_obs, "_final_obs": ended.copy(), "final_info": final_info,
             "_final_info": ended.copy()}
        )  # fmt: skip
        for key in ("episode_return", "episode_length"):
            if key in infos:
                infos_after[key], infos_after[f"_{key}"] = infos[key], infos[f"_{key}"]
        return obs, infos_after

    def _mask_envs(self, mask: Any) -> np.ndarray:
        mask = np.asarray(mask)
        if mask.shape != (self.num_envs,) or mask.dtype != np.bool_ or not mask.any():
            raise ValueError(
                f"options['reset_mask'] must be ({self.num_envs},) booleans, at least one true, "
                f"got shape {mask.shape} dtype {mask.dtype}"
            )
        return np.flatnonzero(mask)

    def _seeds(self, seed: int | list[int | None] | None) -> list[int | None]:
        if seed is None:
            return [None] * self.num_envs
        if _is_int(seed):
            return [int(seed) + env for env in range(self.num_envs)]
        seeds = list(seed)
        if len(seeds) != self.num_envs:
            raise ValueError(f"expected {self.num_envs} seeds, got {len(seeds)}")
        return seeds


def _is_int(value: object) -> bool:
    return isinstance(value, (int, np.integer)) and not isinstance(value, (bool, np.bool_))


def _autoreset_mode(mode: AutoresetMode | str) -> AutoresetMode:
    try:
        parsed = AutoresetMode(mode)
    except ValueError:
        parsed = None
    if parsed not in AUTORESET_MODES:
        allowed = ", ".join(repr(m.value) for m in AUTORESET_MODES)
        raise ValueError(f"autoreset_mode must be one of {allowed}, got {mode!r}")
    return parsed
