"""``PinballEnv``: the Gymnasium shell around the game rules and the swept-collision physics."""

import itertools
import os
from collections.abc import Mapping
from typing import Any, ClassVar

import gymnasium as gym
import numpy as np
from gymnasium import spaces
from gymnasium.error import ResetNeeded
from gymnasium.spaces import Box, Space

from pinball_env.game import DISCRETE_BUTTONS, Game, InvalidActions, check_choice
from pinball_env.procgen import load_any_table
from pinball_env.render import Renderer, Window, render_size, scoreboard
from pinball_env.table import BUTTONS, Table

OBS_TYPES = ("state", "rgb", "grayscale")


class PinballEnv(gym.Env):
    """A real flipper-and-ball pinball table; the agent works the two flipper buttons.

    ## Description

    A 27 mm steel ball on a 0.51 m x 1.07 m playfield inclined at 6.5 degrees (the default
    ``classic`` table: top arch, shooter lane and gate, three pop bumpers, two slingshots, in- and
    outlanes, two flippers, a drain). The ball moves by swept (continuous) collision in fixed
    substeps, so it never passes through a wall or a flipper; flippers swing up in 22 ms while
    their button is held and fall back in 40 ms when it is released. Balls are put into play from
    the plunger at a random speed; a game is ``balls`` balls.

    ## Action Space

    ``action_type="discrete"`` (default): ``Discrete(4)``

    | Num | Action                  |
    |-----|-------------------------|
    | 0   | no button               |
    | 1   | left flipper button     |
    | 2   | right flipper button    |
    | 3   | both buttons            |

    ``action_type="multibinary"``: ``MultiBinary(2)``, (left button, right button).
    A button acts for the whole step (one frame, 1/60 s, or ``frame_skip`` frames): held, the
    flipper swings up to its stop and stays there; released, it falls back to rest.

    On the keyboard (``get_keys_to_action``, for ``gymnasium.utils.play.play`` and
    ``python -m pinball_env.tools.play``): left flipper Left Shift, Z or the left arrow; right
    flipper Right Shift, M or the right arrow.

    ## Observation Space

    ``obs_type="state"`` (default): a ``Box`` of float32, table coordinates (x to the right,
    y up the table, origin at the bottom-left corner), for a table with two flippers:

    | Index | Observation                                   | Min   | Max   | Unit  |
    |-------|-----------------------------------------------|-------|-------|-------|
    | 0     | ball x                                        | 0     | 0.51  | m     |
    | 1     | ball y                                        | 0     | 1.07  | m     |
    | 2     | ball vx (clipped to +-20)                     | -20   | 20    | m/s   |
    | 3     | ball vy (clipped to +-20)                     | -20   | 20    | m/s   |
    | 4     | left flipper angle above rest                 | 0     | 0.873 | rad   |
    | 5     | right flipper angle above rest                | 0     | 0.873 | rad   |
    | 6     | left flipper angular velocity, + going up     | -39.7 | 39.7  | rad/s |
    | 7     | right flipper angular velocity, + going up    | -39.7 | 39.7  | rad/s |
    | 8     | ball in play (1) or game over (0)             | 0     | 1     | -     |
    | 9     | balls left, the one in play included          | 0     | balls | -     |

    The bounds come from the table (playfield size, flipper swing and speeds): for another table
    the flipper rows repeat once per flipper in the table's order. A drained ball is replaced at
    once by the next one on the plunger; after the last one the ball stays where it crossed the
    drain.

    ``obs_type="rgb"``: a ``Box(0, 255, (84, 84, 3), uint8)`` picture of the whole table (stretched
    to the image), drawn without a display; ``obs_type="grayscale"``: the same as
    ``(84, 84, 1)`` luminance. ``image_size`` changes the size.

    ## Rewards

    The points of the step's scoring events times ``reward_scale`` (default 0.01): a pop bumper
    is 100 points (reward 1), a slingshot or a rollover 10 (0.1). Optional shaping, off by
    default: ``height_shaping`` times the rise of the ball during the step in table heights (a
    potential, so it sums to ``height_shaping`` times the net rise of each ball, from its launch
    to where it drains); ``drain_penalty`` taken off for each ball that drains.

    ## Starting State

    Flippers at rest, score 0, ``balls`` balls to play; the first ball is fired up the shooter
    lane at a speed drawn uniformly from the table's plunger range (2.2-3.2 m/s on ``classic``).
    ``reset(options={"ball_position": [x, y], "ball_velocity": [vx, vy]})`` (metres, metres per
    second; either key alone is allowed) puts the ball in play at that state instead, for tests
    and curricula. The state is checked as a table file is: inside the outline, clear of every
    element, somewhere a ball in play can get to from the plunger (not inside a slingshot, not
    below the drain), at most 100 m/s.

    ## Episode End

    Termination: the last ball drains (the game is over). Truncation: only by the ``TimeLimit``
    wrapper, ``max_episode_steps=7200`` (two minutes of play) for ``Pinball-v0``; it counts
    steps, so with ``frame_skip=k`` pass ``max_episode_steps=7200 // k`` for the same two
    minutes. Every game can
    end: a ball in play that has not moved a ball radius in 10 s (resting in the shooter lane,
    or held in a flipper's cradle) is served again from the plunger, as a real machine's ball
    search would, without losing a ball. Stepping before the first ``reset`` raises Gymnasium's
    ``ResetNeeded``.

    ``info`` (reset and step): ``ball_position``, ``ball_velocity`` (float64 arrays, m and m/s),
    ``score`` (points this game), ``balls_left``, ``events`` (scoring element name -> hits this
    step), ``points`` (this step), ``drained`` (a ball drained this step) and ``frames``
    (frames played in this game).

    ## Arguments

    ```python
    gym.make("Pinball-v0", table="classic", obs_type="state", action_type="discrete", balls=3,
             reward_scale=0.01, height_shaping=0.0, drain_penalty=0.0, frame_skip=1,
             skip_above=0.0, max_frames=None, image_size=(84, 84), physics="swept",
             render_mode=None)
    ```

    - ``table``: a built-in table name (``"classic"``; the built-in tables are package data in
      ``pinball_env/table/tables``), a path to a table YAML file, or a ``Table``. A game needs a
      plunger, flippers, a closed outline and a drain (``"box"`` is a physics test box without
      them).
    - ``obs_type``: ``"state"``, ``"rgb"`` or ``"grayscale"``.
    - ``action_type``: ``"discrete"`` or ``"multibinary"``.
    - ``balls``: balls per game (>= 1).
    - ``reward_scale``: reward per point.
    - ``height_shaping``: weight of the optional height shaping term (0 = off).
    - ``drain_penalty``: reward taken off for each ball that drains (0 = off).
    - ``frame_skip``: frames per step (1-60), the action held on each; rewards, ``points`` and
      ``drained`` are summed over them, and a game that ends stops there.
    - ``skip_above``: a training aid, 0 (off) or a height in table heights (0-1): after the
      step's frames, while the ball is in play above that height, the buttons are released and
      the step runs on (up to 60 more frames), so that the agent is asked only while the ball
      is low, near the flippers.
    - ``max_frames``: None, or the frames a game lasts: the step that reaches it stops there
      and returns ``truncated`` (a time limit in frames, whatever the frame skip; the
      ``TimeLimit`` wrapper's ``max_episode_steps`` counts steps).
    - ``image_size``: (height, width) of image observations, in pixels, or one int for a square.
    - ``physics``: ``"swept"`` (ours, continuous collision) or ``"pymunk"`` (the same table in
      pymunk, for cross-checks; needs the ``crosscheck`` extra).
    - ``render_mode``: ``"human"`` (a pygame window at real speed, frame rate over
      ``frame_skip`` steps per second, needs the ``render`` extra; ``metadata["render_fps"]`` is
      that rate rounded to an int, at least 1) or ``"rgb_array"`` (an aspect-correct uint8
      HxWx3 frame, no display needed). A frame shows the playfield (the ball where it drained
      once the game is over) and beside it a scoreboard with the score and the balls left.

    ## Version History

    - v0: first release: swept collision against walls, posts and rotating flippers.
    """

    metadata: ClassVar[dict[str, Any]] = {"render_modes": ["human", "rgb_array"], "render_fps": 60}
    # The keyboard's flipper buttons (pygame key names), by button: get_keys_to_action's map,
    # which gymnasium.utils.play and python -m pinball_env.tools.play both use.
    FLIPPER_KEYS: ClassVar[dict[str, tuple[str, ...]]] = {
        "left": ("K_LSHIFT", "K_z", "K_LEFT"),
        "right": ("K_RSHIFT", "K_m", "K_RIGHT"),
    }

    def __init__(
        self,
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
    ) -> None:
        check_choice("obs_type", obs_type, OBS_TYPES)
        check_choice("render_mode", render_mode, (None, *self.metadata["render_modes"]))
        self.image_size = _image_size(image_size)
        self.table = table if isinstance(table, Table) else load_any_table(table)
        self.game = Game(
            self.table, n_envs=1, balls_per_game=balls, action_type=action_type,
            reward_scale=reward_scale, height_shaping=height_shaping,
            drain_penalty=drain_penalty, frame_skip=frame_skip, skip_above=skip_above,
            max_frames=max_frames, physics=physics,
        )  # fmt: skip
        self.obs_type = obs_type
        self.action_type = action_type
        self.render_mode = render_mode
        # Steps per second at real speed; the metadata holds it rounded, as an int, which
        # gymnasium.utils.play requires; windows (ours, the play tool's) keep the exact rate.
        self.steps_per_second = self.table.simulation.frame_rate / self.game.frame_skip
        self.metadata = {**self.metadata, "render_fps": max(1, round(self.steps_per_second))}

        self.action_space, self.observation_space = make_spaces(
            self.game, obs_type, self.image_size
        )
        self._obs_renderer = obs_renderer(self.table, obs_type, self.image_size)
        self._reset_done = False
        self._frame_renderer: Renderer | None = None
        self._window: Window | None = None

    # --- Gymnasium API ----------------------------------------------------------------------

    def reset(
        self, *, seed: int | None = None, options: Mapping[str, Any] | None = None
    ) -> tuple[np.ndarray, dict[str, Any]]:
        super().reset(seed=seed)
        self._new_game(options)
        self._reset_done = True
        if self.render_mode == "human":
            self.render()
        return self._observe(), self._info()

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
        return self._observe(), float(reward[0]), bool(game_over[0]), out_of_time, self._info()

    def render(self) -> np.ndarray | None:
        if self.render_mode is None:
            gym.logger.warn(
                "render() called without a render_mode; pass render_mode='rgb_array' or "
                "'human' to gym.make"
            )
            return None
        if self._frame_renderer is None:
            self._frame_renderer = Renderer(self.table, *render_size(self.table))
        frame = render_frame(self._frame_renderer, self.game, 0)
        if self.render_mode == "rgb_array":
            return frame
        if self._window is None:
            self._window = Window((frame.shape[1], frame.shape[0]), self.steps_per_second)
        self._window.show(frame)
        return None

    def close(self) -> None:
        if self._window is not None:
            self._window.close()
            self._window = None

    def __getstate__(self) -> dict[str, Any]:
        # A pygame window cannot be pickled; a copy opens its own when it first renders.
        state = self.__dict__.copy()
        state["_window"] = None
        return state

    def get_keys_to_action(self) -> dict[tuple[int, ...], int | np.ndarray]:
        """The keyboard map of ``gymnasium.utils.play.play``: every non-empty set of the
        :attr:`FLIPPER_KEYS` (a sorted tuple of pygame key codes) -> the action pressing the
        buttons of its keys. Actions are ints for ``action_type="discrete"`` and int8 (left,
        right) arrays for ``"multibinary"`` (then pass ``noop=np.array([0, 0])`` to ``play``,
        whose default noop, 0, is not a MultiBinary action). Needs pygame for the key codes."""
        pygame = Window.import_pygame()
        keys = [
            (getattr(pygame, name), button)
            for button, names in enumerate(self.FLIPPER_KEYS[b] for b in BUTTONS)
            for name in names
        ]
        # play looks up exactly the set of keys held, so every combination needs an entry.
        mapping: dict[tuple[int, ...], int | np.ndarray] = {}
        for count in range(1, len(keys) + 1):
            for combination in itertools.combinations(keys, count):
                pressed = np.zeros(len(BUTTONS), dtype=bool)
                pressed[[button for _, button in combination]] = True
                codes = tuple(sorted(code for code, _ in combination))
                if self.action_type == "discrete":
                    # The action whose row of DISCRETE_BUTTONS is the pressed buttons.
                    mapping[codes] = int(np.flatnonzero((pressed == DISCRETE_BUTTONS).all(1))[0])
                else:
                    mapping[codes] = pressed.astype(np.int8)
        return mapping

    @property
    def reward_scale(self) -> float:
        """Reward per point (the game's)."""
        return self.game.reward_scale

    @property
    def height_shaping(self) -> float:
        """Weight of the height shaping term (the game's)."""
        return self.game.height_shaping

    # --- helpers ----------------------------------------------------------------------------

    def _new_game(self, options: Mapping[str, Any] | None) -> None:
        self.game.new_game(0, self.np_random, options)

    def _info(self) -> dict[str, Any]:
        return self.game.info(0)

    def _moving_parts(self) -> tuple[tuple[float, float] | None, np.ndarray]:
        world = self.game.world
        ball = tuple(world.balls[0, :2]) if world.active[0] else None
        return ball, world.state.flipper_angle[0]

    def _observe(self) -> np.ndarray:
        if self._obs_renderer is None:
            return self.game.observe()[0]
        if self.obs_type == "rgb":
            return self._obs_renderer.frame(*self._moving_parts())
        return self._obs_renderer.grayscale(*self._moving_parts())


def _image_size(size: object) -> tuple[int, int]:
    """(height, width) from an int (a square) or a pair of ints, each >= 16."""
    pair = (size, size) if isinstance(size, (int, np.integer)) else size
    valid = (
        isinstance(pair, (tuple, list))
        and len(pair) == 2
        and all(isinstance(n, (int, np.integer)) and not isinstance(n, bool) for n in pair)
        and min(pair) >= 16
    )
    if not valid:
        raise ValueError(
            f"image_size must be an int or (height, width) ints, each >= 16, got {size!r}"
        )
    return int(pair[0]), int(pair[1])


def make_spaces(game: Game, obs_type: str, image_size: tuple[int, int]) -> tuple[Space, Box]:
    """The action and observation spaces of one env of ``game`` (see PinballEnv)."""
    if game.action_type == "discrete":
        action_space: Space = spaces.Discrete(len(DISCRETE_BUTTONS))
    else:
        action_space = spaces.MultiBinary(len(BUTTONS))
    if obs_type == "state":
        low, high = game.observation_bounds()
        return action_space, spaces.Box(low, high, dtype=np.float32)
    channels = 3 if obs_type == "rgb" else 1
    return action_space, spaces.Box(0, 255, (*image_size, channels), dtype=np.uint8)


def obs_renderer(table: Table, obs_type: str, image_size: tuple[int, int]) -> Renderer | None:
    """The renderer of image observations (None for state observations)."""
    if obs_type == "state":
        return None
    height, width = image_size
    return Renderer(table, width, height)


def render_frame(renderer: Renderer, game: Game, env: int) -> np.ndarray:
    """The frame ``render()`` shows for env ``env``: the playfield, with the ball where it
    drained once the game is over, and a scoreboard beside it."""
    world = game.world
    playfield = renderer.frame(tuple(world.balls[env, :2]), world.state.flipper_angle[env])
    board = scoreboard(playfield.shape[0], game.score[env], game.balls_left[env])
    return np.concatenate([playfield, board], axis=1)
