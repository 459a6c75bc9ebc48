"""``PinballEnv``: the Gymnasium shell around a game of one env (``PinballCore``)."""

import itertools
from collections.abc import Mapping
from typing import Any, ClassVar

import gymnasium as gym
import numpy as np
from gymnasium.error import ResetNeeded

from pinball_env.envs.core import CoreAttributes, PinballCore
from pinball_env.envs.states import PinballState, clone_env, restore_env
from pinball_env.game import InvalidActions, action_meanings, discrete_action
from pinball_env.options import PinballOptions
from pinball_env.render import Window
from pinball_env.table import BUTTONS, Table


class PinballEnv(CoreAttributes, gym.Env):
    """A real flipper-and-ball pinball machine, one game: ``gym.make("Pinball-v3")`` and the
    other ids of ``pinball_env.versions.ENV_VERSIONS``.

    ## Description

    A steel ball on an inclined playfield (the default ``classic`` table: 0.51 m x 1.07 m at
    6.5 degrees, pop bumpers, slingshots, in- and outlanes, two flippers and a drain) moved by
    swept (continuous) collision in fixed substeps, so it never passes through a wall, a target
    or a flipper. The agent works the flipper buttons, and on a table with the cabinet
    (``Pinball-v1`` to ``-v3``) the plunger and three nudges, under a plumb-bob tilt. A game is
    ``balls`` balls, or two minutes of play; the reward is the game's points times
    ``reward_scale``.

    ## Reference

    The documentation's page "The environments" (``docs/environments.md``) has the action
    spaces, the state observation's rows, the rewards, the starting state, the episode's end,
    the infos and every option. Its tables are generated from the declarations this class
    reads, which are also there to read from code: :meth:`get_action_meanings`,
    ``observation_rows`` (one :class:`~pinball_env.observation.ObservationRow` per entry of the
    state observation: meaning, bounds, unit) and :class:`~pinball_env.options.PinballOptions`
    (every option: type, default, check, meaning). ``PinballEnv(options, **changes)`` takes the
    options as one record, keywords replacing any of them.

    ## Version History

    Each version's record in ``pinball_env.versions`` (``tests/test_versions.py`` holds this
    list to them). ``gym.make`` of any but the newest ``Pinball`` version says that a newer one
    exists, as Gymnasium does for every older version; their games are bitwise unchanged.

    - Pinball-v3: v2's game with multiball (``classic_v3``: v2's table with a two-ball lock, a
      saucer, a trough of three balls and its auto-plunger, the jackpot lit only during a
      multiball); a row block per ball in the state observation, rays that see every ball and
      the standing drop targets.
    - Pinball-v2: v1's game with a tilt that any sustained nudging trips (``classic_v2``: the
      plumb bob's ring at 1 degree, ``settle_time`` 1 s): every nudge is a warning.
    - Pinball-v1: the whole cabinet on ``classic_v1`` (the classic layout): the player's
      plunger and a skill shot, the nudge, the plumb-bob tilt; 32 actions. Then rules and
      targets on ``classic_v1`` (top lanes with lane change and the bonus multiplier, a drop
      bank, a spinner, a stand-up, a kickback, ball save; the observation's rule rows, 29 in
      all), which changed v1's games and scores.
    - Pinball-v0: the first release: swept collision against walls, posts and rotating
      flippers.
    - PinballProcgen-v0: the first release: a generated table every game (``num_layouts``,
      ``start_layout``, ``difficulty``). Then the ``targets`` option, whose default leaves
      every game as it was.
    """

    # Gymnasium's Env declares it an instance variable (each env sets its own render_fps).
    metadata: dict[str, Any] = {"render_modes": ["human", "rgb_array"], "render_fps": 60}  # noqa: RUF012
    # The keyboard's flipper buttons (pygame key names), by button: get_keys_to_action's map,
    # which gymnasium.utils.play and python -m pinball_env.tools.play both use.
    FLIPPER_KEYS: ClassVar[dict[str, tuple[str, ...]]] = {
        "left": ("K_LSHIFT", "K_z", "K_LEFT"),
        "right": ("K_RSHIFT", "K_m", "K_RIGHT"),
    }
    # The cabinet's buttons (a table with one, Pinball-v1), the same way.
    CABINET_KEYS: ClassVar[dict[str, tuple[str, ...]]] = {
        "plunger": ("K_DOWN", "K_RETURN"),
        "nudge_left": ("K_x",),
        "nudge_right": ("K_n",),
        "nudge_up": ("K_UP", "K_b"),
    }
    # A cabinet table's 12 keys have 4095 sets: its map holds every set of flipper keys (as a
    # table without a cabinet) and every set of at most this many keys with a cabinet key
    # (both flippers, the plunger and a nudge at once), 800 in all.
    MAX_CABINET_KEYS: ClassVar[int] = 4

    def __init__(self, options: PinballOptions | None = None, **kwargs: Any) -> None:
        if options is None or kwargs:
            base = {} if options is None else options.to_kwargs()
            options = PinballOptions.from_kwargs(type(self).__name__, {**base, **kwargs})
        self.options = options
        self.core = PinballCore(options)
        self.render_mode = options.render_mode
        self.steps_per_second = self.core.steps_per_second
        self.metadata = {**self.metadata, "render_fps": self.core.render_fps}
        self.action_space = self.core.action_space
        self.observation_space = self.core.observer.space
        self._reset_done = False
        self._window: Window | None = None

    # --- Gymnasium API ----------------------------------------------------------------------

    def reset(
        self, *, seed: int | None = None, options: Mapping[str, Any] | None = None
    ) -> tuple[np.ndarray, dict[str, Any]]:
        super().reset(seed=seed)
        if seed is not None:
            self.core.seeded([0])
        self.core.new_games([0], [self.np_random], options)
        self._reset_done = True
        if self.render_mode == "human":
            self.render()
        return self.core.observe()[0], self.core.info(0)

    def step(self, action: Any) -> tuple[np.ndarray, float, bool, bool, dict[str, Any]]:
        if not self._reset_done:
            raise ResetNeeded("call reset() before step(): no game has started")
        try:  # the game checks the action, before anything changes
            reward, game_over = self.game.step(np.asarray(action)[None], [self.np_random])
        except InvalidActions:
            raise ValueError(
                f"invalid action {action!r}: expected an element of {self.action_space}"
            ) from None
        if self.render_mode == "human":
            self.render()
        out_of_time = bool(self.game.out_of_time()[0])
        obs, info = self.core.observe()[0], self.core.info(0)
        return obs, float(reward[0]), bool(game_over[0]), out_of_time, info

    # --- saved games (envs.states) ------------------------------------------------------------

    def clone_state(self, include_rng: bool = False) -> PinballState:
        """The game as it is now, saved (``pinball_env.envs.states.PinballState``: every ball,
        the flippers, the plunger, the cabinet and its bob, targets, lamps and rules, score,
        balls and frames; opaque and picklable), for :meth:`restore_state`. The env's random
        stream (``np_random``: sticky actions and launches draw from it) is saved only with
        ``include_rng`` (ALE's ``cloneSystemState``); without it a restored game goes on
        drawing from the stream the env has then."""
        if not self._reset_done:
            raise ResetNeeded("call reset() before clone_state(): no game has started")
        return clone_env(self.core, 0, self._env_id, self.np_random if include_rng else None)

    def restore_state(self, state: PinballState) -> tuple[np.ndarray, dict[str, Any]]:
        """Put the game back as ``state`` (:meth:`clone_state`'s, of this env or another of the
        same id, table, package version and balls: else a ValueError, and nothing changes), its
        random stream too where ``state`` has it; returns the observation and info there, as
        ``reset`` does. Stepped with the same actions (and draws), the game goes on bitwise as
        it went on from where it was cloned."""
        restore_env(self.core, 0, state, self._env_id, self.np_random)()
        self._reset_done = True
        return self.core.observe()[0], self.core.info(0)

    @property
    def _env_id(self) -> str | None:
        return None if self.spec is None else self.spec.id

    # (gymnasium types render() with its RenderFrame type variable, which no env can bind)
    def render(self) -> np.ndarray | None:  # type: ignore[override, unused-ignore]
        if self.render_mode is None:
            gym.logger.warn(
                "render() called without a render_mode; pass render_mode='rgb_array' or "
                "'human' to gym.make"
            )
            return None
        frame = self.core.frame(0)
        if self.render_mode == "rgb_array":
            return frame
        if self._window is None:
            self._window = Window((frame.shape[1], frame.shape[0]), self.steps_per_second)
        self._window.show(frame)
        return None

    def close(self) -> None:
        self.core.close()
        if self._window is not None:
            self._window.close()
            self._window = None

    def __getstate__(self) -> dict[str, Any]:
        # A pygame window cannot be pickled; a copy opens its own when it first renders.
        state = self.__dict__.copy()
        state["_window"] = None
        return state

    def get_keys_to_action(self) -> dict[tuple[int, ...], int | np.ndarray]:
        """The keyboard map of ``gymnasium.utils.play.play``: a set of keys (a sorted tuple of
        pygame key codes) -> the action pressing the buttons of its keys. Keys are the
        :attr:`FLIPPER_KEYS` and, on a table with the cabinet, the :attr:`CABINET_KEYS`; the map
        has every non-empty set of flipper keys and, with the cabinet, every set of at most
        :attr:`MAX_CABINET_KEYS` keys that holds a cabinet key (``play`` looks up the exact set
        held: a larger one is no action). Actions are ints for ``action_type="discrete"`` and
        int8 arrays of the buttons (``game.button_names``) for ``"multibinary"`` (then pass
        ``noop=np.zeros(env.action_space.n, np.int8)`` to ``play``, whose default noop, 0, is
        not a MultiBinary action). A discrete action holds one nudge: with
        several nudge keys held, the first of nudge left, right, up wins (a button array presses
        them all; left and right cancel). Needs pygame for the key codes."""
        pygame = Window.import_pygame()
        names = self.game.button_names
        declared = {**self.FLIPPER_KEYS, **self.CABINET_KEYS}
        keys = [
            (getattr(pygame, name), button)
            for button, names_of_button in enumerate(declared[b] for b in names)
            for name in names_of_button
        ]
        flippers = len(BUTTONS)  # buttons before these are the flippers'
        nudges = [i for i, name in enumerate(names) if name.startswith("nudge")]
        # play looks up exactly the set of keys held, so every combination needs an entry.
        mapping: dict[tuple[int, ...], int | np.ndarray] = {}
        for count in range(1, len(keys) + 1):
            for combination in itertools.combinations(keys, count):
                buttons = [button for _, button in combination]
                if count > self.MAX_CABINET_KEYS and max(buttons) >= flippers:
                    continue
                pressed = np.zeros(len(names), dtype=bool)
                pressed[buttons] = True
                codes = tuple(sorted(code for code, _ in combination))
                if self.action_type == "discrete":
                    held = [i for i in nudges if pressed[i]]
                    # The first nudge wins; without nudge actions, nudge keys do nothing.
                    pressed[held[1:] if self.options.nudge_actions else held] = False
                    mapping[codes] = discrete_action(pressed)
                else:
                    mapping[codes] = pressed.astype(np.int8)
        return mapping

    def get_action_meanings(self) -> list[str]:
        """The name of every discrete action, as ALE's envs have it: ``NOOP``, ``LEFT_FLIPPER``,
        ``RIGHT_FLIPPER``, ``BOTH_FLIPPERS`` and, on a table with the cabinet (``Pinball-v1``),
        their combinations with ``PLUNGER`` and one of ``NUDGE_LEFT``, ``NUDGE_RIGHT``,
        ``NUDGE_UP``, joined by ``_`` (action ``a``: flippers ``a & 3``, plunger bit 2, nudge
        ``a >> 3``). With ``action_type="multibinary"`` these are the discrete actions'
        names all the same; the buttons are ``game.button_names``."""
        return action_meanings(self.game.cabinet, self.options.nudge_actions)

    # --- what the env is playing -------------------------------------------------------------

    @property
    def table(self) -> Table:
        """The table of the game (of the game being played, with generated tables)."""
        return self.game.world.table_of(0)

    @property
    def layout(self) -> int | None:
        """The layout of the game (generated tables), else None."""
        return None if self.core.layout is None else int(self.core.layout[0])


def unwrapped_pinball(env: gym.Env) -> PinballEnv:
    """The :class:`PinballEnv` under ``env``'s wrappers (``env.unwrapped``, checked)."""
    core = env.unwrapped
    if not isinstance(core, PinballEnv):
        raise TypeError(f"expected a Pinball env, got {type(core).__name__}")
    return core
