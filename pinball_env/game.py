"""The rules of pinball over a batch of envs: actions to buttons, balls per game, launches, drains,
score, reward, the state observation and the per-step info.

Everything works over the env axis, so the single env (a Game of one) and a vector env (a Game
of N) run the same code. A step's frames run in one compiled loop, :func:`_play_frames`: per
env, the frames of the step one after another, the World's kernel (``step_ball``) for the
physics and the rules written out beside it; only launches (random draws) come back to Python.
Everything that changes during play is in one record, :class:`GameState`, so that a game can be
snapshotted and restored as one object.
"""

import math
import numbers
import reprlib
from collections.abc import Callable, Mapping, Sequence
from typing import Any, NamedTuple

import numpy as np
from numba import njit

from pinball_env.backends import make_world
from pinball_env.physics import State, first_flipper
from pinball_env.physics.columns import BALL_VX, BALL_VY, BALL_X, BALL_Y
from pinball_env.physics.step import step_ball
from pinball_env.table import BUTTONS, TEST_TABLES, Table, check_ball_state
from pinball_env.world import compiled_entry

# The state observation clips ball velocities to +-MAX_OBS_SPEED [m/s] so its bounds hold; a
# real ball rarely exceeds 10 m/s on a table (a full flip at the tip gives about 5 m/s).
MAX_OBS_SPEED = 20.0

ACTION_TYPES = ("discrete", "multibinary")
# A discrete action is the buttons held as bits: bit i is button BUTTONS[i] (0 none, 1 left,
# 2 right, 3 both). Row a of DISCRETE_BUTTONS is action a's buttons.
DISCRETE_BUTTONS = (np.arange(2 ** len(BUTTONS))[:, None] >> np.arange(len(BUTTONS))) & 1 == 1
RESET_OPTIONS = ("ball_position", "ball_velocity")
# Ball search: a ball in play that has not moved a ball radius in this long [s] (resting in the
# shooter lane, say, or held in a flipper's cradle) is served again from the plunger, as a real
# machine's ball search and auto-plunger would; no ball is lost. So every game can end.
BALL_SEARCH_TIME = 10.0
# Most frames one step may hold an action for (a second at 60 Hz).
MAX_FRAME_SKIP = 60
# Most frames one step runs on with the buttons released while the ball is high (skip_above):
# then the agent is asked again, wherever the ball is.
MAX_SKIP_FRAMES = 60


class InvalidActions(ValueError):
    """Actions that are not in the game's action space (raised before anything changes)."""


def discrete_action(buttons: Sequence[bool]) -> int:
    """The discrete action that holds ``buttons`` (one bool per entry of ``BUTTONS``)."""
    return sum(int(bool(held)) << i for i, held in enumerate(buttons))


class GameState(NamedTuple):
    """Everything that changes during play, for every env (the first axis)."""

    world: State  # the kernel's arrays: balls, flippers, contacts, hits
    balls_left: np.ndarray  # (N,) int64: balls still to play, the one in play included
    score: np.ndarray  # (N,) int64: points scored in the current game
    drain_height: np.ndarray  # (N,) float64: where the last drained ball crossed the drain [m]
    points: np.ndarray  # (N,) int64: points of the last step
    drained: np.ndarray  # (N,) bool: a ball drained in the last step
    anchor: np.ndarray  # (N, 2) float64: where the ball was when it last moved a radius [m]
    still_frames: np.ndarray  # (N,) int64: frames since then (see BALL_SEARCH_TIME)
    frames: np.ndarray  # (N,) int64: frames played in the current game


class Rules(NamedTuple):
    """What the compiled step loop plays by (see :class:`Game`); arrays are per env."""

    reward_scale: float
    drain_penalty: float
    height_shaping: float
    heights: np.ndarray  # (N,) float64: table heights [m]
    skip_heights: np.ndarray  # (N,) float64: skip_above in metres
    frame_skip: int
    skip_frames: int  # most frames run on while the ball is high (0: skip_above is off)
    max_frames: int  # frames a game lasts (-1: no limit)
    search_frames: int  # still frames before a ball search
    radius: float  # the ball's [m]
    scores: np.ndarray  # (N, elements) int64: points per element id


class StepProgress(NamedTuple):
    """Where each env is in the current step: the compiled loop hands it back to Python for a
    launch and takes it up again where it stopped."""

    stage: np.ndarray  # (N,) int64: what comes next (NEW_STEP ... STEP_DONE)
    frames: np.ndarray  # (N,) int64: frames played in this step
    reward: np.ndarray  # (N,) float64: summed over the step's frames
    points: np.ndarray  # (N,) int64: summed over the step's frames
    drained: np.ndarray  # (N,) bool: a ball drained in the step
    height_before: np.ndarray  # (N,) float64: the ball's height when the frame began [m]
    frame_points: np.ndarray  # (N,) int64: points of the frame under way
    frame_drained: np.ndarray  # (N,) bool: the frame under way drained a ball
    launch: np.ndarray  # (N,) bool: waits for a ball off the plunger before it goes on
    finite: np.ndarray  # (N,) bool: the ball state stayed finite


# A step's stages, per env: its start, then per frame: the next frame chosen (or the step
# ended), its physics, its points and drains, the ball search, its reward (a launch may come
# between the last three).
NEW_STEP, NEXT_FRAME, PHYSICS, AFTER_PHYSICS, SEARCH, CLOSE_FRAME, STEP_DONE = range(7)


class Game:
    """``n_envs`` games on one table, each of ``balls_per_game`` balls.

    Args:
        table: a validated table with a plunger, flippers, an outline and a drain.
        n_envs: games played side by side.
        balls_per_game: balls per game (>= 1).
        action_type: ``"discrete"`` (0-3, the buttons as bits) or ``"multibinary"`` (a bool per
            button).
        reward_scale: reward per point.
        height_shaping: weight of the height shaping term (0 = off): the rise of the ball
            during the step, in table heights.
        drain_penalty: reward taken off for each ball that drains (0 = off).
        frame_skip: frames per step, the action repeated on each (rewards, points and drains
            summed; a game that ends stops there).
        skip_above: 0 (off), or a height in table heights (0-1): after the step's frames, while
            the ball is in play above it, the buttons are released and the step runs on (at
            most MAX_SKIP_FRAMES more frames), so that the agent acts only when the ball is
            low. A training aid: the decisions far from the flippers are left out.
        max_frames: None, or the frames a game lasts before it runs out of time
            (:meth:`out_of_time`; a step stops there).
        physics: the World backend, ``"swept"`` or ``"pymunk"``.
        num_threads: threads that share the envs of a frame (the swept kernel).

    Attributes:
        world: the physics of every env.
        state: the :class:`GameState` (``state.world`` is ``world.state``).
    """

    def __init__(
        self,
        table: Table,
        n_envs: int = 1,
        balls_per_game: int = 3,
        action_type: str = "discrete",
        reward_scale: float = 0.01,
        height_shaping: float = 0.0,
        drain_penalty: float = 0.0,
        frame_skip: int = 1,
        skip_above: float = 0.0,
        max_frames: int | None = None,
        physics: str = "swept",
        num_threads: int = 1,
    ) -> None:
        check_playable(table)
        check_choice("action_type", action_type, ACTION_TYPES)
        weights = {
            "reward_scale": reward_scale, "height_shaping": height_shaping,
            "drain_penalty": drain_penalty,
        }  # fmt: skip
        for name, value in weights.items():
            real = isinstance(value, numbers.Real) and not isinstance(value, (bool, np.bool_))
            if not real or not math.isfinite(value):
                raise ValueError(f"{name} must be a finite number, got {value!r}")
        if not _is_int(balls_per_game) or balls_per_game < 1:
            raise ValueError(f"balls must be an integer >= 1, got {balls_per_game!r}")
        if not _is_int(frame_skip) or not 1 <= frame_skip <= MAX_FRAME_SKIP:
            raise ValueError(
                f"frame_skip must be an integer from 1 to {MAX_FRAME_SKIP}, got {frame_skip!r}"
            )
        real = isinstance(skip_above, numbers.Real) and not isinstance(skip_above, bool)
        if not real or not 0.0 <= skip_above < 1.0:
            raise ValueError(f"skip_above must be a number in [0, 1), got {skip_above!r}")
        if max_frames is not None and (not _is_int(max_frames) or max_frames < 1):
            raise ValueError(f"max_frames must be None or an integer >= 1, got {max_frames!r}")
        self.table = table
        self.balls_per_game = int(balls_per_game)
        self.action_type = action_type
        self.reward_scale = float(reward_scale)
        self.height_shaping = float(height_shaping)
        self.drain_penalty = float(drain_penalty)
        self.frame_skip = int(frame_skip)
        self.skip_above = float(skip_above)
        self.max_frames = None if max_frames is None else int(max_frames)
        self.world = make_world(table, n_envs, physics, num_threads)
        self.state = GameState(
            world=self.world.state,
            balls_left=np.zeros(n_envs, dtype=np.int64),
            score=np.zeros(n_envs, dtype=np.int64),
            drain_height=np.zeros(n_envs),
            points=np.zeros(n_envs, dtype=np.int64),
            drained=np.zeros(n_envs, dtype=bool),
            anchor=np.zeros((n_envs, 2)),
            still_frames=np.zeros(n_envs, dtype=np.int64),
            frames=np.zeros(n_envs, dtype=np.int64),
        )
        self._everyone = np.ones(n_envs, dtype=bool)
        self._rules: Rules | None = None  # the step loop's numbers (see _rules_now)
        self._play: dict[type, Any] = {}  # _play_frames's compiled entries (compiled_entry)
        # Called after each frame's physics, when set: to record the frames a step runs on.
        self.on_frame: Callable[[], None] | None = None
        self._progress = StepProgress(
            stage=np.zeros(n_envs, dtype=np.int64),
            frames=np.zeros(n_envs, dtype=np.int64),
            reward=np.zeros(n_envs),
            points=np.zeros(n_envs, dtype=np.int64),
            drained=np.zeros(n_envs, dtype=bool),
            height_before=np.zeros(n_envs),
            frame_points=np.zeros(n_envs, dtype=np.int64),
            frame_drained=np.zeros(n_envs, dtype=bool),
            launch=np.zeros(n_envs, dtype=bool),
            finite=np.ones(n_envs, dtype=bool),
        )
        self.ball_search_frames = round(BALL_SEARCH_TIME * table.simulation.frame_rate)
        # Per env (rows), for set_table: the flippers' rest angles, the sign of their upstroke
        # (+1 counter-clockwise), their swings and top speeds, and the table's height.
        flippers = np.array([_flipper_numbers(table)] * n_envs).reshape(n_envs, 4, -1)
        self._rest, self._up_sign, self._swing, self._max_omega = flippers.transpose(1, 0, 2)
        self._width = np.full(n_envs, table.width)
        self._height = np.full(n_envs, table.height)
        self._scoring = [np.flatnonzero(table.element_scores)] * n_envs  # scoring element ids

    def set_table(self, env: int, table: Table) -> None:
        """Make env ``env`` play ``table`` (see ``World.set_table``); start a new game after.
        The other envs' games go on."""
        check_playable(table)
        ball, simulation = table.ball, table.simulation
        if ball.radius != self.table.ball.radius or simulation != self.table.simulation:
            raise ValueError(
                f"table {table.name!r} has another ball size or simulation settings than "
                f"{self.table.name!r}: every env of a game needs the same"
            )
        self.world.set_table(env, table)
        self.state = self.state._replace(world=self.world.state)  # it may have grown
        numbers = _flipper_numbers(table)
        for array, row in zip((self._rest, self._up_sign, self._swing, self._max_omega),
                              numbers, strict=True):  # fmt: skip
            array[env] = row
        self._width[env] = table.width
        self._height[env] = table.height
        self._scoring[env] = np.flatnonzero(table.element_scores)
        self._rules = None  # heights and scores changed, and the arrays may have grown

    def __getstate__(self) -> dict[str, Any]:
        state = self.__dict__.copy()
        state["_play"] = {}  # compiled entries cannot be pickled; a copy finds its own
        state["_rules"] = None  # a copy makes its own, over its own arrays
        state["on_frame"] = None  # a recorder's, not the game's
        return state

    @property
    def n_envs(self) -> int:
        return self.world.n_envs

    @property
    def balls_left(self) -> np.ndarray:
        return self.state.balls_left

    @property
    def score(self) -> np.ndarray:
        return self.state.score

    # --- state --------------------------------------------------------------------------------

    def snapshot(self) -> GameState:
        """A copy of the whole game state of every env."""
        return _copy(self.state)

    def restore(self, snapshot: GameState) -> None:
        """Put every env back to ``snapshot`` (from :meth:`snapshot` of a Game on the same table
        with as many envs)."""
        _copy_into(snapshot, self.state)

    # --- playing ------------------------------------------------------------------------------

    def new_game(
        self, env: int, rng: np.random.Generator, options: Mapping[str, Any] | None = None
    ) -> None:
        """Start a new game in env ``env``: flippers at rest, score 0, the first ball launched.

        ``options`` may hold ``ball_position`` [m] and ``ball_velocity`` [m/s] to put the ball
        in play at that state instead; they are checked before anything changes, so a rejected
        reset leaves the env as it was.
        """
        options = dict(options or {})
        unknown = sorted(reprlib.repr(key) for key in options if key not in RESET_OPTIONS)
        if unknown:
            raise ValueError(
                f"unknown reset option(s) {', '.join(unknown[:5])} "
                f"(allowed: {', '.join(RESET_OPTIONS)})"
            )
        if options:
            table = self.world.table_of(env)
            position = options.get("ball_position", table.plunger.position)
            velocity = options.get("ball_velocity", (0.0, 0.0))
            position, velocity = check_ball_state(table, position, velocity, "reset options")
        self.world.rest_flippers(env)
        state = self.state
        state.world.hits[env] = 0  # the reset's info shows no events of the last game
        state.world.contact_count[env] = 0
        state.balls_left[env] = self.balls_per_game
        state.score[env] = 0
        state.points[env] = 0
        state.drained[env] = False
        state.frames[env] = 0
        self.launch(env, rng)
        if options:
            self.world.place_ball(env, position, velocity)
            self._moved(env)

    def launch(self, env: int, rng: np.random.Generator) -> None:
        """Fire env ``env``'s next ball off the plunger at a speed drawn from the table's range."""
        low, high = self.world.table_of(env).plunger.speed
        self.world.launch(env, float(rng.uniform(low, high)))
        self._moved(env)

    def _moved(self, env: int) -> None:
        """Restart env ``env``'s ball-search clock where its ball is now."""
        self.state.anchor[env] = self.world.balls[env, [BALL_X, BALL_Y]]
        self.state.still_frames[env] = 0

    def buttons(self, actions: Any) -> np.ndarray:
        """The (n_envs, len(BUTTONS)) bool buttons held by ``actions``: (n_envs,) integers for
        ``"discrete"``, (n_envs, len(BUTTONS)) zeros and ones for ``"multibinary"``."""
        actions = np.asarray(actions)
        if self.action_type == "discrete":
            valid = (
                actions.shape == (self.n_envs,)
                and actions.dtype.kind in "biu"  # Gymnasium's Discrete takes True as 1
                and actions.min() >= 0
                and actions.max() < len(DISCRETE_BUTTONS)
            )
            if valid:  # (as integers: a bool array would index as a mask)
                return DISCRETE_BUTTONS[actions.astype(np.intp)]
            expected = f"({self.n_envs},) integers in [0, {len(DISCRETE_BUTTONS)})"
        else:
            shape = (self.n_envs, len(BUTTONS))
            if actions.shape == shape and np.all((actions == 0) | (actions == 1)):
                return actions.astype(bool)
            expected = f"{shape} zeros and ones"
        raise InvalidActions(
            f"invalid actions: expected {expected} for action_type={self.action_type!r}, "
            f"got shape {actions.shape} dtype {actions.dtype}"
        )

    def step(
        self,
        actions: Any,
        rngs: Sequence[np.random.Generator],
        frozen: np.ndarray | None = None,
    ) -> tuple[np.ndarray, np.ndarray]:
        """One step of every env with ``actions`` (see :meth:`buttons`): ``frame_skip`` frames,
        the actions held on each; then, with ``skip_above``, more frames with the buttons
        released while the ball is high. A drained ball is replaced by the next one off the
        plunger (drawn from the env's ``rngs`` entry); the game ends when the last ball drains.
        An env whose game ends, or runs out of time (``max_frames``), stays as it is for the
        rest of the step. Envs where ``frozen`` (n_envs,) bool is set keep their state as it is
        (a vector env's envs that have just been reset), with reward 0.

        Each env's frames run in one compiled loop (:func:`_play_frames`), which comes back
        here only for launches (they draw from the env's random stream), and, with a physics
        backend other than the swept kernel or with :attr:`on_frame` set, for each frame's
        physics; ``on_frame()`` is then called after it (the frame's points not yet counted).

        Returns ``(reward, game_over)``, (n_envs,) float64 and bool, the reward summed over the
        frames. The step's points and drains (summed) are in :attr:`state`.
        """
        commands = self.buttons(actions)[:, self.world.flipper_buttons]
        progress = self._progress
        playing = self._everyone if frozen is None else ~frozen
        progress.stage[:] = np.where(playing, NEW_STEP, STEP_DONE)
        rules = self._rules_now()
        geometries, settings = self.world.tables()
        # With on_frame the loop hands each frame's physics to Python (the same kernel), and the
        # hook sees the frame.
        swept = self.world.swept_kernel and self.on_frame is None
        args = (geometries, settings, self.state, self.world.scratch, progress, rules, commands,
                swept)  # fmt: skip
        play = self._play.get(type(geometries))  # one table (tuples) or one per env (lists)
        if play is None:
            play = self._play[type(geometries)] = compiled_entry(_play_frames, (*args, 0, 0))
        while True:
            self.world.threads.run(play, self.n_envs, *args)
            if not progress.finite.all():
                bad = np.flatnonzero(~progress.finite).tolist()
                raise FloatingPointError(f"the ball state of env(s) {bad} is no longer finite")
            physics = progress.stage == PHYSICS  # (not swept) the backend's frame is due
            if physics.any():
                self.world.step(None, physics)
                progress.stage[physics] = AFTER_PHYSICS
                if self.on_frame is not None:
                    self.on_frame()
            launches = np.flatnonzero(progress.launch)
            for env in launches:
                self.launch(env, rngs[env])
            progress.launch[:] = False
            if not physics.any() and len(launches) == 0:
                break
        self.state.points[playing] = progress.points[playing]
        self.state.drained[playing] = progress.drained[playing]
        return np.where(playing, progress.reward, 0.0), self.state.balls_left == 0

    def out_of_time(self) -> np.ndarray:
        """(n_envs,) bool: the game has played ``max_frames`` frames (never, without)."""
        if self.max_frames is None:
            return np.zeros(self.n_envs, dtype=bool)
        return self.state.frames >= self.max_frames

    def _rules_now(self) -> Rules:
        """The numbers the compiled step loop plays by (per env where tables differ), made
        again only after :meth:`set_table`."""
        if self._rules is None:
            self._rules = self._make_rules()
        return self._rules

    def _make_rules(self) -> Rules:
        return Rules(
            reward_scale=self.reward_scale,
            drain_penalty=self.drain_penalty,
            height_shaping=self.height_shaping,
            heights=self._height,
            skip_heights=self.skip_above * self._height,
            frame_skip=self.frame_skip,
            skip_frames=MAX_SKIP_FRAMES if self.skip_above else 0,
            max_frames=-1 if self.max_frames is None else self.max_frames,
            search_frames=self.ball_search_frames,
            radius=self.table.ball.radius,
            scores=self.world.scores,
        )

    # --- what the agent sees ------------------------------------------------------------------

    def observation_bounds(self, normalised: bool = False) -> tuple[np.ndarray, np.ndarray]:
        """Lower and upper bounds of :meth:`observe` (float32, one entry per feature), on the
        game's table (on any, ``normalised``)."""
        rest, _, swing, max_omega = _flipper_numbers(self.table)
        if normalised:
            n = len(rest)
            low = np.array([0.0, 0.0, -MAX_OBS_SPEED, -MAX_OBS_SPEED] + [0.0] * n + [-1.0] * n
                           + [0.0, 0.0])  # fmt: skip
            high = np.array([1.0, 1.0, MAX_OBS_SPEED, MAX_OBS_SPEED] + [1.0] * (2 * n)
                            + [1.0, float(self.balls_per_game)])  # fmt: skip
            return low.astype(np.float32), high.astype(np.float32)
        low = np.concatenate(
            [[0.0, 0.0, -MAX_OBS_SPEED, -MAX_OBS_SPEED], np.zeros(len(rest)), -max_omega,
             [0.0, 0.0]]
        )  # fmt: skip
        high = np.concatenate(
            [[self.table.width, self.table.height, MAX_OBS_SPEED, MAX_OBS_SPEED], swing,
             max_omega, [1.0, float(self.balls_per_game)]]
        )  # fmt: skip
        return low.astype(np.float32), high.astype(np.float32)

    def observe(self, normalised: bool = False) -> np.ndarray:
        """(n_envs, 4 + 2F + 2) float32: ball x, y, vx, vy; each flipper's angle above rest and
        angular velocity towards up; ball in play; balls left. See PinballEnv's docstring.
        ``normalised``: positions in table widths and heights, flipper angles in swings and
        angular velocities in top speeds (the same bounds on every table)."""
        world = self.world.state
        obs = _state_observation(
            world.balls, world.flipper_angle, world.flipper_omega, world.active,
            self.state.balls_left, self._rest, self._up_sign,
        )  # fmt: skip
        if normalised:
            n = self._swing.shape[1]
            obs[:, 0] /= self._width
            obs[:, 1] /= self._height
            obs[:, 4 : 4 + n] /= self._swing
            obs[:, 4 + n : 4 + 2 * n] /= self._max_omega
        return obs

    def events(self, env: int) -> dict[str, int]:
        """The scoring elements env ``env`` hit in the last step: name -> hits."""
        hits = self.world.state.hits[env]
        names = self.world.table_of(env).element_names
        return {names[i]: int(hits[i]) for i in self._scoring[env] if hits[i]}

    def infos(self) -> dict[str, np.ndarray]:
        """The per-step info of every env as arrays (first axis the env): ``ball_position`` [m],
        ``ball_velocity`` [m/s], ``score``, ``balls_left``, ``points`` (this step),
        ``drained`` (a ball drained this step) and ``frames`` (played in this game)."""
        state, balls = self.state, self.world.balls
        return {
            "ball_position": balls[:, [BALL_X, BALL_Y]],
            "ball_velocity": balls[:, [BALL_VX, BALL_VY]],
            "score": state.score.copy(),
            "balls_left": state.balls_left.copy(),
            "points": state.points.copy(),
            "drained": state.drained.copy(),
            "frames": state.frames.copy(),
        }

    def info(self, env: int) -> dict[str, Any]:
        """The per-step info of env ``env``: that of :meth:`infos` as Python numbers (the ball's
        position and velocity as float64 arrays), plus ``events`` (:meth:`events`)."""
        state, ball = self.state, self.world.balls[env]
        return {
            "ball_position": ball[[BALL_X, BALL_Y]],
            "ball_velocity": ball[[BALL_VX, BALL_VY]],
            "score": int(state.score[env]),
            "balls_left": int(state.balls_left[env]),
            "events": self.events(env),
            "points": int(state.points[env]),
            "drained": bool(state.drained[env]),
            "frames": int(state.frames[env]),
        }


def _flipper_numbers(table: Table) -> np.ndarray:
    """(4, F): the flippers' rest angles [rad], upstroke signs (+1 counter-clockwise), swings
    [rad] and top angular speeds [rad/s]."""
    rest = np.array([math.radians(f.rest_angle) for f in table.flippers])  # as Table.pack
    up = np.radians([f.up_angle for f in table.flippers])
    top = [max(f.up_speed, f.down_speed) for f in table.flippers]
    return np.array([rest, np.sign(up - rest), np.abs(up - rest), top])


@njit(cache=True, nogil=True)
def _play_frames(
    geometries, settings, state, scratch, progress, rules, commands, swept, start, stop
):
    """Take the step of envs ``start`` to ``stop`` on from where each is (``progress.stage``),
    each env's frames one after another, to its end (STEP_DONE), or to where it needs a launch
    (``progress.launch``; Python draws it from the env's stream), or, unless ``swept``, the
    physics of a frame (PHYSICS; Python runs the world's backend). With ``swept`` the physics
    is the swept kernel's :func:`step_ball`, on ``geometries[env]`` and ``settings[env]`` (or
    their only entries, see ``World.tables``); a ball state that is no longer finite ends the
    env's step (``progress.finite``).

    A frame: the flipper commands (the action's for the first ``frame_skip`` frames, then
    released while the ball is above ``skip_heights``), the physics, the points scored, a
    drained ball (the next one is launched), the ball search (BALL_SEARCH_TIME), the frame's
    reward. Envs are independent: threads may share the range.

    Written out in one body, as ``step_ball``: numba counts a reference for every array taken
    out of a record, and taking them out once per call instead of once per helper and frame
    makes a frame of the plain env about 1.7x faster.
    """
    world = state.world
    balls, active, hits = world.balls, world.active, world.hits
    flipper_command = world.flipper_command
    score, balls_left, drain_height = state.score, state.balls_left, state.drain_height
    anchor, still_frames, game_frames = state.anchor, state.still_frames, state.frames
    stage, frames, total = progress.stage, progress.frames, progress.reward
    points, drained = progress.points, progress.drained
    height_before = progress.height_before
    frame_points, frame_drained = progress.frame_points, progress.frame_drained
    launch, finite = progress.launch, progress.finite
    scores, heights, skip_heights = rules.scores, rules.heights, rules.skip_heights
    r2 = rules.radius * rules.radius
    per_env = len(geometries) > 1  # else every env plays the one table
    geometry, setting = geometries[0], settings[0]
    flipper_id = first_flipper(geometry)
    for env in range(start, stop):
        if per_env:
            geometry, setting = geometries[env], settings[env]
            flipper_id = first_flipper(geometry)
        while not launch[env]:
            now = stage[env]
            if now == NEW_STEP:
                frames[env] = points[env] = 0
                total[env] = 0.0
                drained[env] = False
                finite[env] = True
                stage[env] = NEXT_FRAME
            elif now == NEXT_FRAME:
                k = frames[env]
                held = k < rules.frame_skip
                high = active[env] and balls[env, BALL_Y] > skip_heights[env]
                if (
                    (rules.max_frames >= 0 and game_frames[env] >= rules.max_frames)
                    or (k > 0 and balls_left[env] == 0)  # the game ended in the step
                    or not (held or (high and k < rules.frame_skip + rules.skip_frames))
                ):
                    stage[env] = STEP_DONE
                    continue
                for j in range(flipper_command.shape[1]):
                    flipper_command[env, j] = held and commands[env, j]
                height_before[env] = balls[env, BALL_Y]
                stage[env] = PHYSICS
            elif now == PHYSICS:
                if not swept:
                    break
                if not step_ball(geometry, setting, world, scratch, env, flipper_id):
                    finite[env] = False
                    stage[env] = STEP_DONE
                else:
                    stage[env] = AFTER_PHYSICS
            elif now == AFTER_PHYSICS:  # points and drains; a launch for the next ball
                scored = 0
                for element in range(hits.shape[1]):
                    scored += hits[env, element] * scores[env, element]
                score[env] += scored
                gone = balls_left[env] > 0 and not active[env]
                if gone:
                    drain_height[env] = balls[env, BALL_Y]
                    balls_left[env] -= 1
                frame_points[env] = scored
                frame_drained[env] = gone
                launch[env] = gone and balls_left[env] > 0
                stage[env] = SEARCH
            elif now == SEARCH:  # a ball that has not moved a radius for long is served again
                dx = balls[env, BALL_X] - anchor[env, 0]
                dy = balls[env, BALL_Y] - anchor[env, 1]
                if not active[env] or dx * dx + dy * dy > r2:
                    anchor[env, 0] = balls[env, BALL_X]
                    anchor[env, 1] = balls[env, BALL_Y]
                    still_frames[env] = 0
                else:
                    still_frames[env] += 1
                    launch[env] = still_frames[env] >= rules.search_frames
                stage[env] = CLOSE_FRAME
            elif now == CLOSE_FRAME:  # the frame's reward
                gone = frame_drained[env]
                reward = frame_points[env] * rules.reward_scale
                if rules.drain_penalty:
                    reward -= rules.drain_penalty * gone
                if rules.height_shaping:
                    # A drained ball's last height is where it crossed the drain, not the next's.
                    after = drain_height[env] if gone else balls[env, BALL_Y]
                    reward += rules.height_shaping * (after - height_before[env]) / heights[env]
                game_frames[env] += 1
                frames[env] += 1
                total[env] += reward
                points[env] += frame_points[env]
                drained[env] |= gone
                stage[env] = NEXT_FRAME
            else:
                break


@njit(cache=True)
def _state_observation(balls, flipper_angle, flipper_omega, active, balls_left, rest, up_sign):
    """The state observation of every env (see :meth:`Game.observe`), float32. Compiled: the
    single env pays it every step."""
    n_envs, n_flippers = flipper_angle.shape
    obs = np.empty((n_envs, 6 + 2 * n_flippers), dtype=np.float32)
    for env in range(n_envs):
        obs[env, 0] = balls[env, BALL_X]
        obs[env, 1] = balls[env, BALL_Y]
        obs[env, 2] = min(max(balls[env, BALL_VX], -MAX_OBS_SPEED), MAX_OBS_SPEED)
        obs[env, 3] = min(max(balls[env, BALL_VY], -MAX_OBS_SPEED), MAX_OBS_SPEED)
        for j in range(n_flippers):
            # The angle above rest (the kernel stops it exactly) and the speed towards up.
            obs[env, 4 + j] = (flipper_angle[env, j] - rest[env, j]) * up_sign[env, j]
            obs[env, 4 + n_flippers + j] = flipper_omega[env, j] * up_sign[env, j]
        obs[env, 4 + 2 * n_flippers] = active[env]
        obs[env, 5 + 2 * n_flippers] = balls_left[env]
    return obs


def check_playable(table: Table) -> None:
    """A game needs a plunger to launch, flippers to play, an outline and a drain to end it: a
    ValueError names everything the table lacks."""
    lacks = [
        what
        for what, missing in (
            ("no plunger to launch the ball", table.plunger is None),
            ("no flippers to play", not table.flippers),
            ("no closed outline wall to keep the ball in", table.outline is None),
            ("no drain sensor to end a game", not any(s.drain for s in table.sensors)),
        )
        if missing
    ]
    if lacks:
        rig = " (it is a physics test rig)" if table.name in TEST_TABLES else ""
        raise ValueError(f"table {table.name!r} cannot be played{rig}: it has {', '.join(lacks)}")
    if not table.drain_reachable:
        raise ValueError(
            f"table {table.name!r}: no drain can be reached from the plunger, a game could "
            "never end"
        )


def check_choice(name: str, value: object, choices: Sequence[object]) -> None:
    """Raise a ValueError naming ``name`` unless ``value`` is one of ``choices``."""
    if value not in choices:
        raise ValueError(f"{name} must be one of {', '.join(map(repr, choices))}, got {value!r}")


def _is_int(value: object) -> bool:
    return isinstance(value, (int, np.integer)) and not isinstance(value, (bool, np.bool_))


def _copy(record: tuple) -> Any:
    """A deep copy of a record of arrays (and nested records)."""
    return type(record)(*(_copy(v) if isinstance(v, tuple) else v.copy() for v in record))


def _copy_into(source: tuple, target: tuple) -> None:
    """Copy every array of record ``source`` into the same array of record ``target``."""
    for src, dst in zip(source, target, strict=True):
        if isinstance(dst, tuple):
            _copy_into(src, dst)
        else:
            np.copyto(dst, src)


__all__ = [
    "ACTION_TYPES",
    "DISCRETE_BUTTONS",
    "MAX_FRAME_SKIP",
    "MAX_OBS_SPEED",
    "MAX_SKIP_FRAMES",
    "RESET_OPTIONS",
    "Game",
    "GameState",
    "InvalidActions",
    "check_choice",
    "check_playable",
    "discrete_action",
]
