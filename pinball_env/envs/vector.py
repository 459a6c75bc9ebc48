"""``PinballVectorEnv``: N pinball games stepped together, natively batched.

``gym.make_vec("Pinball-v0", num_envs=N)`` returns it. It runs the very same ``Game`` (rules)
and kernel (physics) as the single env, over N envs in one call, on ``num_threads`` threads.
"""

import functools
import os
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from gymnasium.error import ResetNeeded
from gymnasium.utils import seeding
from gymnasium.utils.env_checker import data_equivalence
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.vector.utils import batch_space

from pinball_env.checks import is_int
from pinball_env.envs.core import CoreAttributes, PinballCore
from pinball_env.envs.states import PinballState, clone_env, restore_env
from pinball_env.game import InvalidActions
from pinball_env.options import split_options
from pinball_env.table import Table

# Envs per thread below which a second thread costs more than it saves.
MIN_ENVS_PER_THREAD = 32
# Methods that call() refuses, as Gymnasium's AsyncVectorEnv does: they act on every env at once.
NOT_CALLABLE = ("reset", "step", "close")
_UNSET = object()  # a user attribute (set_attr) not set for an env


def default_threads(num_envs: int) -> int:
    """One thread per core (at most 8), as long as each has MIN_ENVS_PER_THREAD envs."""
    cores = min(os.cpu_count() or 1, 8)
    return max(1, min(cores, num_envs // MIN_ENVS_PER_THREAD))


@dataclass(frozen=True)
class EnvAttribute:
    """An attribute that each env of a vector env has its own value of: ``get(env)``, and
    ``set(env, value)`` unless it is read-only."""

    get: Callable[[int], Any]
    set: Callable[[int, Any], None] | None = None


class PinballVectorEnv(CoreAttributes, VectorEnv):
    """``num_envs`` games of any pinball env in one batch (``gym.make_vec("Pinball-v2",
    num_envs=1024)``): ``PinballEnv``'s game, spaces, rewards and options, for N envs.

    ## Arguments

    Every option of ``PinballEnv`` (:class:`~pinball_env.options.PinballOptions`) and those of
    :class:`~pinball_env.options.VectorOptions` (``num_envs``, ``max_episode_steps``,
    ``num_threads``, ``autoreset_mode``); the documentation's page "The environments" has the
    table of them, generated from those declarations. Results are bitwise the same for any
    ``num_threads``. ``autoreset_mode``: ``NEXT_STEP`` (Gymnasium's default: an env that ended
    is reset by the next ``step``, which ignores its action and returns the reset observation,
    reward 0), ``SAME_STEP`` (reset in the same step; the last observation and info of the
    episode are in ``info["final_obs"]`` and ``info["final_info"]``, masked by
    ``_final_obs``) or ``DISABLED`` (no automatic reset: reset the envs that ended with
    ``reset(options={"reset_mask": mask})`` before the next step, which raises
    ``AssertionError`` otherwise, as ``SyncVectorEnv`` does).

    With ``table="generated"`` (``PinballProcgen-v0``) each env plays its own table, all stepped
    in one kernel call; ``reset(options={"layout": L})`` plays layout ``L`` in every env reset,
    or ``{"layout": [L0, L1, ...]}`` one per env (for evaluations on chosen layouts); later
    games draw their layouts. The tables a reset needs are generated on several threads (a
    line on stderr shows the progress when that takes more than two seconds); the layouts
    drawn do not depend on it.

    ## Infos

    Arrays over the envs, each with a ``_key`` mask: ``ball_position`` (N, 2), ``ball_velocity``
    (N, 2), ``score``, ``balls_left``, ``points`` (this step), ``drained``, ``frames`` (and
    ``layout`` with generated tables); when episodes end, ``episode_return`` and
    ``episode_length`` masked by the envs that ended (the key ``episode`` is left to
    Gymnasium's ``RecordEpisodeStatistics``). In SAME_STEP mode,
    ``final_obs`` (an object array) and ``final_info`` (arrays with their own ``_key`` masks)
    hold the ended envs' last observation and info, as ``SyncVectorEnv`` does. The per-step
    ``events`` of the single env are not batched. With the cabinet, its entries (N,); with
    rules, ``bonus``, ``bonus_multiplier``, ``rule_score`` (N,) and ``rule_events`` (N, R + 2)
    counts of each rule fired this step, in the order of the attribute ``event_names`` of the
    game (``env.unwrapped.game.event_names``: the rules, then the ball save and the end-of-ball
    bonus).

    ## Seeding and resets

    ``reset(seed=s)`` seeds env i with ``s + i`` (or a list gives one seed per env, None for
    none), so env i plays exactly as ``gym.make("Pinball-v0")`` reset with that seed and given
    the same actions. ``np_random_seed`` is the tuple of every env's seed (before a seeded
    reset, the random seed its generator was drawn from), ``np_random`` the tuple of their
    generators. ``reset(options={"reset_mask": mask, ...})`` resets only the envs where the
    (num_envs,) bool array ``mask`` is True (errors as ``SyncVectorEnv``'s: TypeError for a
    mask that is not a bool array, ValueError for a wrong shape or no True); the other options
    are the single env's (``ball_position``, ``ball_velocity``). Actions that are not a batch
    (a scalar, or not numbers) are a TypeError, a batch of the wrong length or values a
    ValueError.

    ## Attributes per env: get_attr, set_attr, call

    There are no sub-env objects; ``get_attr(name)``, ``set_attr(name, values)`` and
    ``call(name, *args, **kwargs)`` act on every env's value of ``name``, a tuple of one per env
    as ``SyncVectorEnv``'s (``get_attr`` is ``call``: a method is called), of three kinds:

    - per env (:meth:`env_attributes`): ``np_random`` (settable; the env's seed is then -1, as
      Gymnasium's ``Env`` has it), ``np_random_seed``, ``table``, ``score``, ``balls_left``
      (and ``layout`` with generated tables)
      (read-only: setting them is an AttributeError), and the method ``render`` (the env's
      frame);
    - shared, the vector env's own attributes (``render_mode``, ``max_episode_steps``,
      ``game``...): the same value for every env; ``set_attr`` takes one value (or one per env,
      all equal: ValueError otherwise). Its methods act on every env at once: ``call`` refuses
      ``reset``, ``step`` and ``close`` (as ``AsyncVectorEnv`` does) and calls any other once,
      its result in every env's place;
    - any other name: a user's attribute that ``set_attr`` gives each env (one value for all, or
      one per env) and ``get_attr`` returns, as a single env keeps an attribute set on it; the
      game does not read it. Getting one that was never set is an AttributeError.

    ``env_attr(env, name)``, ``set_env_attr(env, name, value)`` and ``call_env(env, name, ...)``
    do the same for one env (what ``SB3VecEnv``'s ``get_attr``, ``set_attr`` and ``env_method``
    use): ``env_attr`` leaves methods uncalled, ``set_env_attr`` of a shared attribute and
    ``call_env`` of a method of the vector env are ValueErrors (they are not one env's).
    """

    # Gymnasium's VectorEnv declares it an instance variable (each env sets its own render_fps).
    metadata: dict[str, Any] = {  # noqa: RUF012
        "render_modes": ["rgb_array"],
        "render_fps": 60,
        "autoreset_mode": AutoresetMode.NEXT_STEP,
    }

    def __init__(self, **kwargs: Any) -> None:
        options, vector = split_options(type(self).__name__, kwargs)
        if options.render_mode not in (None, *self.metadata["render_modes"]):
            allowed = ", ".join(map(repr, (None, *self.metadata["render_modes"])))
            raise ValueError(f"render_mode must be one of {allowed}, got {options.render_mode!r}")
        self.options, self.vector_options = options, vector
        self.num_envs = vector.num_envs
        self.autoreset_mode = vector.autoreset_mode
        self.max_episode_steps = vector.max_episode_steps
        threads = vector.num_threads or default_threads(self.num_envs)
        self.core = PinballCore(options, self.num_envs, threads)
        self.num_threads = self.game.world.threads.num_threads
        self.render_mode = options.render_mode
        self.steps_per_second = self.core.steps_per_second
        self.metadata = {
            **self.metadata,
            "render_fps": self.core.render_fps,
            "autoreset_mode": self.autoreset_mode,
        }
        self.single_action_space = self.core.action_space
        self.single_observation_space = self.core.observer.space
        self.action_space = batch_space(self.single_action_space, self.num_envs)
        self.observation_space = batch_space(self.single_observation_space, self.num_envs)
        n = self.num_envs
        # Each env's generator, and the seed it was made from (seeding.np_random draws one).
        generators = [seeding.np_random() for _ in range(n)]
        self._rngs = [rng for rng, _ in generators]
        self._seeds: list[int] = [seed for _, seed in generators]
        self._user_attributes: dict[str, list[Any]] = {}  # set_attr's names of no attribute
        self._returns = np.zeros(n)
        self._lengths = np.zeros(n, dtype=np.int64)
        self._ended = np.zeros(n, dtype=bool)  # to be reset: by the next step (NEXT_STEP)
        self._reset_done = False

    # --- Gymnasium API ------------------------------------------------------------------------

    def reset(
        self,
        *,
        seed: int | list[int | None] | None = None,
        options: Mapping[str, Any] | None = None,
    ) -> tuple[np.ndarray, dict[str, Any]]:
        # No super().reset(seed): the randomness is the envs' generators (np_random), not one.
        options = dict(options or {})
        seeds = self._seeds_of(seed)
        envs = np.arange(self.num_envs)
        if "reset_mask" in options:
            envs = np.flatnonzero(self._check_mask(options.pop("reset_mask")))
        # Made first, so that a bad seed (gymnasium.error.Error) changes nothing.
        generators = {
            int(env): seeding.np_random(seeds[env]) for env in envs if seeds[env] is not None
        }
        for env, (rng, env_seed) in generators.items():
            self._rngs[env], self._seeds[env] = rng, env_seed
        if generators:
            self.core.seeded(list(generators))
        self.core.new_games(envs, self._rngs, options)
        self._returns[envs] = 0.0
        self._lengths[envs] = 0
        self._ended[envs] = False
        self._reset_done = True
        return self.core.observe(), self._infos(envs)

    def step(
        self, actions: Any
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, dict[str, Any]]:
        if not self._reset_done:
            raise ResetNeeded("call reset() before step(): no game has started")
        actions = self._check_actions(actions)  # before anything changes
        if self.autoreset_mode == AutoresetMode.DISABLED and self._ended.any():
            raise AssertionError(  # SyncVectorEnv's error (an assert there)
                f"env(s) {np.flatnonzero(self._ended).tolist()} ended: with autoreset_mode "
                "Disabled, reset them (reset(options={'reset_mask': mask})) before the next step"
            )
        restart = self._ended.copy()  # NEXT_STEP: the envs that ended last step
        if restart.any():
            self.core.new_games(np.flatnonzero(restart), self._rngs)
            self._returns[restart] = 0.0
            self._lengths[restart] = 0
        reward, game_over = self.game.step(actions, self._rngs, frozen=restart)
        lengths = self._lengths
        lengths[~restart] += 1
        self._returns += reward
        terminated = game_over & ~restart
        truncated = np.zeros(self.num_envs, dtype=bool)
        if self.max_episode_steps is not None:  # as Gymnasium's TimeLimit: even if terminated
            truncated = (lengths >= self.max_episode_steps) & ~restart
        truncated |= self.game.out_of_time() & ~restart
        ended = terminated | truncated
        obs, infos = self.core.observe(), self._infos()
        if ended.any():
            infos["episode_return"] = np.where(ended, self._returns, 0.0)
            infos["episode_length"] = np.where(ended, lengths, 0)
            infos["_episode_return"] = infos["_episode_length"] = ended.copy()
        if self.autoreset_mode == AutoresetMode.SAME_STEP and ended.any():
            obs, infos = self._reset_same_step(ended, obs, infos)
            ended[:] = False
        self._ended = ended
        return obs, reward, terminated, truncated, infos

    # --- saved games (envs.states) ------------------------------------------------------------

    def clone_state(
        self, indices: Sequence[int] | None = None, include_rng: bool = False
    ) -> list[PinballState]:
        """The games of envs ``indices`` (all by default) as they are now, saved, one
        ``PinballState`` each (the single env's ``clone_state``, with each env's episode so
        far), for :meth:`restore_state`; each env's random stream only with ``include_rng``."""
        if not self._reset_done:
            raise ResetNeeded("call reset() before clone_state(): no game has started")
        envs = self._indices(indices)
        states = []
        for env in envs:
            episode = (float(self._returns[env]), int(self._lengths[env]), bool(self._ended[env]))
            rng = self._rngs[env] if include_rng else None
            states.append(clone_env(self.core, env, self._env_id, rng, episode))
        return states

    def restore_state(
        self, states: PinballState | Sequence[PinballState], indices: Sequence[int] | None = None
    ) -> tuple[np.ndarray, dict[str, Any]]:
        """Put envs ``indices`` (all by default) back as ``states``: one state for each, or one
        state copied into every one of them (a game branched into many). Every state is checked
        first (another id, table, package version or balls: a ValueError, and nothing
        changes). Returns every env's observations and infos. A single env's state starts a
        new episode's return and length; a vector env's goes on with its own."""
        envs = self._indices(indices)
        if isinstance(states, PinballState):
            states = [states] * len(envs)
        states = list(states)
        if len(states) != len(envs):
            raise ValueError(f"{len(states)} states for {len(envs)} envs: one each, or one for all")
        restores = [restore_env(self.core, env, state, self._env_id, self._rngs[env])
                    for env, state in zip(envs, states, strict=True)]  # fmt: skip
        for env, state, restore in zip(envs, states, restores, strict=True):
            restore()
            episode = state.episode or (0.0, 0, False)
            self._returns[env], self._lengths[env], self._ended[env] = episode
        self._reset_done = True
        return self.core.observe(), self._infos()

    def _indices(self, indices: Sequence[int] | None) -> list[int]:
        if indices is None:
            return list(range(self.num_envs))
        envs = [int(env) for env in np.asarray(indices, dtype=np.int64).ravel()]
        bad = [env for env in envs if not 0 <= env < self.num_envs]
        if bad:
            raise ValueError(f"env indices {bad} are not in [0, {self.num_envs})")
        return envs

    @property
    def _env_id(self) -> str | None:
        return None if self.spec is None else self.spec.id

    # (gymnasium types render() with its RenderFrame type variable, which no env can bind)
    def render(self) -> tuple[np.ndarray, ...] | None:  # type: ignore[override, unused-ignore]
        """Every env's frame (the playfield and a scoreboard), for ``render_mode="rgb_array"``:
        each the frame of the single env."""
        if self.render_mode is None:
            return None
        return tuple(self.core.frame(env) for env in range(self.num_envs))

    def close_extras(self, **kwargs: Any) -> None:
        """Stop the threads that step the envs and generate tables (none if the constructor
        refused its options)."""
        if hasattr(self, "core"):
            self.core.close()

    # One generator, and one seed, per env (as gymnasium's SyncVectorEnv): not VectorEnv's one.
    @property  # type: ignore[misc]  # read-only: set_attr sets one env's
    def np_random(self) -> tuple[np.random.Generator, ...]:  # type: ignore[override]
        """Every env's random generator (set one with ``set_attr("np_random", ...)``)."""
        return tuple(self._rngs)

    @property
    def np_random_seed(self) -> tuple[int, ...]:  # type: ignore[override]
        """Every env's seed: its last reset's, or the random one its generator was drawn from
        before any seeded reset; -1 where a generator was set (``set_attr("np_random")``)."""
        return tuple(self._seeds)

    @property
    def first_table(self) -> Table:
        """The table the envs were made with, whose ball, simulation and cabinet every env's
        table shares (``get_attr("table")`` gives the table each env plays)."""
        return self.game.table

    @property
    def table(self) -> Table:
        """:attr:`first_table`, under the name it had (kept for code that reads it)."""
        return self.first_table

    @property
    def layout(self) -> np.ndarray | None:
        """(num_envs,) each env's layout (generated tables), else None."""
        return self.core.layout

    # --- attributes per env (see the class docstring) -----------------------------------------

    def env_attributes(self) -> dict[str, EnvAttribute]:
        """The attributes that each env has its own value of, by name."""
        game = self.game
        attributes = {
            "np_random": EnvAttribute(self._rngs.__getitem__, self._set_rng),
            "np_random_seed": EnvAttribute(self._seeds.__getitem__),
            "table": EnvAttribute(game.world.table_of),
            "score": EnvAttribute(lambda env: int(game.score[env])),
            "balls_left": EnvAttribute(lambda env: int(game.balls_left[env])),
            "render": EnvAttribute(lambda env: functools.partial(self._render_env, env)),
        }
        if self.core.layout is not None:
            layouts = self.core.layout
            attributes["layout"] = EnvAttribute(lambda env: int(layouts[env]))
        return attributes

    def get_attr(self, name: str) -> tuple[Any, ...]:
        """Every env's ``name``, a method called (as ``SyncVectorEnv.get_attr``, which is
        ``call``)."""
        return self.call(name)

    def call(self, name: str, /, *args: Any, **kwargs: Any) -> tuple[Any, ...]:
        """Every env's ``name``, called with the arguments where it is callable: a per-env
        method for each env, a method of the vector env once, its result in every env's place;
        ``reset``, ``step`` and ``close`` are refused (ValueError, as ``AsyncVectorEnv``)."""
        if self._kind(name) == "shared" and callable(method := getattr(self, name)):
            if name in NOT_CALLABLE:
                raise ValueError(  # AsyncVectorEnv's message
                    f"Trying to call function `{name}` with `call`, use `{name}` directly instead."
                )
            return (method(*args, **kwargs),) * self.num_envs
        return tuple(self.call_env(env, name, *args, **kwargs) for env in range(self.num_envs))

    def set_attr(self, name: str, values: list[Any] | tuple[Any, ...] | Any) -> None:
        """Set every env's ``name``: ``values`` a list or tuple of one per env, or any other value
        for all (as ``SyncVectorEnv.set_attr``). A shared attribute takes one value."""
        if not isinstance(values, (list, tuple)):
            values = [values for _ in range(self.num_envs)]
        if len(values) != self.num_envs:
            raise ValueError(  # SyncVectorEnv's message
                "Values must be a list or tuple with length equal to the number of environments. "
                f"Got `{len(values)}` values for {self.num_envs} environments."
            )
        if self._kind(name) == "shared":
            if not all(data_equivalence(value, values[0], exact=True) for value in values):
                raise ValueError(
                    f"{name!r} is an attribute of the vector env, shared by every env: give "
                    "one value for all"
                )
            setattr(self, name, values[0])
            return
        for env, value in enumerate(values):
            self.set_env_attr(env, name, value)

    def env_attr(self, env: int, name: str) -> Any:
        """Env ``env``'s ``name`` as it is (a per-env method bound to the env, not called)."""
        self._check_env(env)
        kind = self._kind(name)
        if kind == "per env":
            return self.env_attributes()[name].get(env)
        if kind == "shared":
            return getattr(self, name)
        value = self._user_attributes.get(name, [_UNSET] * self.num_envs)[env]
        if value is _UNSET:
            raise AttributeError(
                f"{type(self).__name__} has no attribute {name!r}, shared or of env {env}"
            )
        return value

    def set_env_attr(self, env: int, name: str, value: Any) -> None:
        """Set env ``env``'s ``name`` (a per-env or user attribute; a shared one is a ValueError:
        set it for every env with :meth:`set_attr`)."""
        self._check_env(env)
        kind = self._kind(name)
        if kind == "shared":
            raise ValueError(
                f"{name!r} is an attribute of the vector env, shared by every env: set it for "
                "all of them with set_attr"
            )
        if kind == "per env":
            attribute = self.env_attributes()[name]
            if attribute.set is None:
                raise AttributeError(f"each env's {name!r} is read-only")
            attribute.set(env, value)
            return
        self._user_attributes.setdefault(name, [_UNSET] * self.num_envs)[env] = value

    def call_env(self, env: int, name: str, /, *args: Any, **kwargs: Any) -> Any:
        """Env ``env``'s ``name``, called with the arguments where it is callable; a method of
        the vector env is a ValueError (it acts on every env at once: call it directly, or
        with :meth:`call`)."""
        value = self.env_attr(env, name)
        if not callable(value):
            return value
        if self._kind(name) == "shared":
            raise ValueError(
                f"{name!r} is a method of the vector env, acting on every env at once: call it "
                "directly, or with call()"
            )
        return value(*args, **kwargs)

    # --- helpers ------------------------------------------------------------------------------

    def _kind(self, name: str) -> str:
        """``"per env"``, ``"user"`` (set_attr's) or ``"shared"`` (see the class docstring)."""
        if name in self.env_attributes():
            return "per env"
        if name in self._user_attributes or not hasattr(self, name):
            return "user"
        return "shared"

    def _check_env(self, env: object) -> None:
        if not is_int(env) or not 0 <= env < self.num_envs:
            raise IndexError(f"env must be an integer in [0, {self.num_envs}), got {env!r}")

    def _set_rng(self, env: int, rng: Any) -> None:
        if not isinstance(rng, np.random.Generator):
            raise TypeError(f"np_random must be a numpy Generator, got {type(rng).__name__}")
        self._rngs[env] = rng
        self._seeds[env] = -1  # as Gymnasium's Env: the seed of a generator set is unknown

    def _render_env(self, env: int) -> np.ndarray | None:
        """Env ``env``'s frame (None without a render mode)."""
        return None if self.render_mode is None else self.core.frame(env)

    def _check_actions(self, actions: Any) -> np.ndarray:
        """``actions`` as an array, checked: TypeError if they are not a batch of numbers,
        ValueError if their shape or values are not the action space's (as Gymnasium's vector
        envs do)."""
        try:
            array = np.asarray(actions)
        except ValueError:  # ragged
            raise ValueError(
                f"invalid actions: expected an array in {self.action_space}, got {actions!r}"
            ) from None
        if array.ndim == 0 or array.dtype.kind not in "biuf":
            raise TypeError(
                f"actions must be a batch of {self.num_envs} actions, one per env (an array in "
                f"{self.action_space}), got {type(actions).__name__} {actions!r}"
            )
        if self.game.action_type == "discrete" and array.dtype == np.bool_:
            array = array.astype(np.int64)  # the action space (MultiDiscrete) holds them, as 0/1
        try:
            self.game.buttons(array)
        except InvalidActions as error:
            raise ValueError(f"{error} (the action space is {self.action_space})") from None
        return array

    def _infos(self, envs: np.ndarray | None = None) -> dict[str, Any]:
        """The infos, masked to ``envs`` (default: all)."""
        infos = self.core.infos()
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
        self.core.new_games(np.flatnonzero(ended), self._rngs)
        self._returns[ended] = 0.0
        self._lengths[ended] = 0
        obs, infos_after = self.core.observe(), self._infos()
        infos_after.update(
            {"final_obs": final_obs, "_final_obs": ended.copy(), "final_info": final_info,
             "_final_info": ended.copy()}
        )  # fmt: skip
        for key in ("episode_return", "episode_length"):
            if key in infos:
                infos_after[key], infos_after[f"_{key}"] = infos[key], infos[f"_{key}"]
        return obs, infos_after

    def _check_mask(self, mask: Any) -> np.ndarray:
        """``options["reset_mask"]``, checked as ``SyncVectorEnv`` does (its messages)."""
        if not isinstance(mask, np.ndarray):
            raise TypeError(f"`options['reset_mask']` must be a numpy array, got {type(mask)}")
        if mask.shape != (self.num_envs,):
            raise ValueError(
                f"`options['reset_mask']` must have shape `({self.num_envs},)`, got {mask.shape}"
            )
        if mask.dtype != np.bool_:
            raise TypeError(f"`options['reset_mask']` must have `dtype=np.bool_`, got {mask.dtype}")
        if not mask.any():
            raise ValueError(
                "`options['reset_mask']` must contain a boolean array with at least one True "
                f"value, got reset_mask={mask}"
            )
        return mask

    def _seeds_of(self, seed: int | list[int | None] | None) -> list[int | None]:
        """The seed of each env's reset (None: none)."""
        if seed is None:
            return [None] * self.num_envs
        if is_int(seed):
            return [int(seed) + env for env in range(self.num_envs)]
        if not isinstance(seed, Iterable):  # a bool or a float
            raise TypeError(f"seed must be an int, a list of ints or None, got {seed!r}")
        seeds = [int(s) if is_int(s) else s for s in seed]
        if len(seeds) != self.num_envs:
            raise ValueError(  # SyncVectorEnv's message
                f"If seeds are passed as a list the length must match num_envs={self.num_envs} "
                f"but got length={len(seeds)}."
            )
        return seeds
