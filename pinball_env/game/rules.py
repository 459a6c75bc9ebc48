"""The rules of pinball over a batch of envs: actions to buttons, balls per game, launches, drains,
score, reward and the per-step info.

Everything works over the env axis, so the single env (a Game of one) and a vector env (a Game
of N) run the same code. A step's frames run in one compiled loop (``game.play.play_frames``);
only launches (random draws) come back to Python. Everything that changes during play is in
one record, :class:`GameState`, so that a game can be snapshotted and restored as one object;
what does not change (every env's table) is the World's ``tables`` record.
"""

import reprlib
from collections.abc import Callable, Mapping, Sequence
from typing import Any, NamedTuple

import numpy as np

from pinball_env.game.actions import (
    CABINET_BUTTONS,
    button_names,
    discrete_buttons,
)
from pinball_env.game.play import (
    AFTER_PHYSICS,
    NEW_STEP,
    PHYSICS,
    STEP_DONE,
    Rules,
    new_progress,
    play_frames,
    play_frames_per_env,
)
from pinball_env.game.rulebook import RuleBook, compile_rules
from pinball_env.options import PinballOptions
from pinball_env.physics import State
from pinball_env.physics.columns import BALL_VX, BALL_VY, BALL_X, BALL_Y, CABINET_X, CABINET_Y
from pinball_env.sim.backends import make_world
from pinball_env.sim.world import compiled_entry
from pinball_env.table import BUTTONS, TEST_TABLES, Table, check_ball_state
from pinball_env.table.rules import RuleSet

# A discrete action of a table without a cabinet is the flipper buttons held as bits: bit i is
# button BUTTONS[i] (0 none, 1 left, 2 right, 3 both). Row a of DISCRETE_BUTTONS is action a's
# buttons (``game.actions`` has the cabinet's too).
DISCRETE_BUTTONS = discrete_buttons(cabinet=False)
RESET_OPTIONS = ("ball_position", "ball_velocity")
# Ball search: a ball in play that has not moved a ball radius in this long [s] (resting in the
# shooter lane, say, or held in a flipper's cradle) is served again from the plunger, as a real
# machine's ball search and auto-plunger would; no ball is lost. So every game can end.
BALL_SEARCH_TIME = 10.0
# Most frames one step runs on with the buttons released while the ball is high (skip_above),
# after its frame_skip frames: then the agent is asked again, wherever the ball is.
MAX_RUN_ON_FRAMES = 60


class InvalidActions(ValueError):
    """Actions that are not in the game's action space (raised before anything changes)."""


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
    # The cabinet (tables with one): the tilt itself is the kernel's (world.tilted).
    plunger_pull: np.ndarray  # (N,) float64: how far the plunger is pulled back [m]
    on_plunger: np.ndarray  # (N,) bool: the ball in play waits on the plunger
    nudge_wait: np.ndarray  # (N,) int64: frames until the next nudge can shove the cabinet
    tilt_warnings: np.ndarray  # (N,) int64: warnings standing
    warning_age: np.ndarray  # (N,) int64: frames since the last warning
    skill_left: np.ndarray  # (N,) int64: frames the skill shot stays lit (0: dark)
    lane_frames: np.ndarray  # (N,) int64: frames the ball has stayed in the shooter lane
    # The rules (tables with them, see ``game.rulebook``; the targets' state is the kernel's).
    lights: np.ndarray  # (N, L) bool
    counters: np.ndarray  # (N, C) int64
    timers: np.ndarray  # (N, Tm) int64: frames each timer still runs (0: stopped)
    bonus: np.ndarray  # (N,) int64: the end-of-ball bonus so far [points]
    multiplier: np.ndarray  # (N,) int64: the bonus multiplier (1 to max_multiplier)
    save_frames: np.ndarray  # (N,) int64: frames the ball save lasts (-1: from the launch, 0: off)
    rule_points: np.ndarray  # (N,) int64: points the rules scored in this game
    rule_events: np.ndarray  # (N, R + 2) int64: rules fired in the last step (RuleSet.event_names)
    lights_were_on: np.ndarray  # (N, R) bool: a lights_on rule's lights were all lit
    flippers_before: np.ndarray  # (N, F) bool: the flipper commands of the last frame
    # The flipper commands and cabinet buttons the last frame pressed (with sticky actions,
    # repeat_action_probability, the next frame may press them again).
    pressed: np.ndarray  # (N, F + 4) bool


class Game:
    """``n_envs`` games on one table (until :meth:`set_table` gives an env another), each of
    ``options.balls`` balls.

    Args:
        table: a validated table with a plunger, flippers, an outline and a drain.
        n_envs: games played side by side.
        options: the game's options (``PinballOptions``: balls, action_type, reward_scale,
            height_shaping, drain_penalty, frame_skip, skip_above, repeat_action_probability,
            max_frames, physics; the
            others are the envs'), or None for the defaults; ``**kwargs`` replace any of them.
            ``skip_above`` runs a step on, buttons released, for at most MAX_RUN_ON_FRAMES
            frames while the ball is above it; ``max_frames`` ends a game's time
            (:meth:`out_of_time`).
        num_threads: threads that share the envs of a frame (the swept kernel).

    Attributes:
        world: the physics of every env (and, in ``world.tables``, every env's table).
        state: the :class:`GameState` (``state.world`` is ``world.state``).
        table: the table the game was made with; its ball and simulation are every env's.
    """

    def __init__(
        self,
        table: Table,
        n_envs: int = 1,
        options: PinballOptions | None = None,
        num_threads: int = 1,
        **kwargs: Any,
    ) -> None:
        check_playable(table)
        options = options or PinballOptions()
        if kwargs:
            options = PinballOptions.from_kwargs("Game", {**options.to_kwargs(), **kwargs})
        self.options = options
        self.table = table
        self.balls_per_game = options.balls
        self.action_type = options.action_type
        self.reward_scale = options.reward_scale
        self.height_shaping = options.height_shaping
        self.drain_penalty = options.drain_penalty
        self.bonus_shaping = options.bonus_shaping
        self.frame_skip = options.frame_skip
        self.skip_above = options.skip_above
        self.max_frames = options.max_frames
        self.world = make_world(table, n_envs, options.physics, num_threads)
        self.book: RuleBook = compile_rules(table)
        self.rule_set = table.rules
        rule_set = table.rules or RuleSet()
        self.event_names = rule_set.event_names
        n_rules, n_flippers = len(self.book.trigger_kind), len(table.flippers)
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
            plunger_pull=np.zeros(n_envs),
            on_plunger=np.zeros(n_envs, dtype=bool),
            nudge_wait=np.zeros(n_envs, dtype=np.int64),
            tilt_warnings=np.zeros(n_envs, dtype=np.int64),
            warning_age=np.zeros(n_envs, dtype=np.int64),
            skill_left=np.zeros(n_envs, dtype=np.int64),
            lane_frames=np.zeros(n_envs, dtype=np.int64),
            lights=np.zeros((n_envs, len(rule_set.lights)), dtype=bool),
            counters=np.zeros((n_envs, len(rule_set.counters)), dtype=np.int64),
            timers=np.zeros((n_envs, len(self.book.timer_frames)), dtype=np.int64),
            bonus=np.zeros(n_envs, dtype=np.int64),
            multiplier=np.ones(n_envs, dtype=np.int64),
            save_frames=np.zeros(n_envs, dtype=np.int64),
            rule_points=np.zeros(n_envs, dtype=np.int64),
            rule_events=np.zeros((n_envs, n_rules + 2), dtype=np.int64),
            lights_were_on=np.zeros((n_envs, n_rules), dtype=bool),
            flippers_before=np.zeros((n_envs, n_flippers), dtype=bool),
            pressed=np.zeros(
                (n_envs, self.world.state.flipper_command.shape[1] + len(CABINET_BUTTONS)),
                dtype=bool,
            ),
        )
        # The buttons: the flippers', and the cabinet's on a table that has one.
        self.cabinet = table.has_cabinet
        self.button_names = button_names(self.cabinet)
        if not (self.cabinet or options.nudge_actions):
            raise ValueError(
                f"nudge_actions=False: an option of tables with the cabinet, not of {table.name!r}"
            )
        self.discrete_buttons = discrete_buttons(self.cabinet, options.nudge_actions)
        self._no_cabinet_buttons = np.zeros((n_envs, len(CABINET_BUTTONS)), dtype=bool)
        self._everyone = np.ones(n_envs, dtype=bool)
        self._rules: Rules | None = None  # the step loop's numbers (see _rules_now)
        self._play: dict[type, Any] = {}  # play_frames's compiled entries (compiled_entry)
        # Called after each frame's physics, when set: to record the frames a step runs on.
        self.on_frame: Callable[[], None] | None = None
        self.repeat_action_probability = options.repeat_action_probability
        # One draw per frame a step may play, from each env's stream (none without sticky).
        frames = self.frame_skip + (MAX_RUN_ON_FRAMES if self.skip_above else 0)
        self._progress = new_progress(n_envs, frames if self.repeat_action_probability else 0)
        self.ball_search_frames = round(BALL_SEARCH_TIME * table.simulation.frame_rate)

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
        # The step loop reads the cabinet's numbers, the player's plunger's among them, once.
        cabinet = (table.cabinet, table.tilt, table.plunger if table.has_cabinet else None)
        if cabinet != (self.table.cabinet, self.table.tilt, self.table.plunger if self.cabinet
                       else None):  # fmt: skip
            raise ValueError(
                f"table {table.name!r} has another cabinet, tilt or player's plunger than "
                f"{self.table.name!r}: every env of a game needs the same"
            )
        # The rules are compiled once per game, on element ids.
        if (table.rules, table.ball_save) != (self.table.rules, self.table.ball_save) or (
            table.rules is not None and table.element_names != self.table.element_names
        ):
            raise ValueError(
                f"table {table.name!r} has other rules or ball save than {self.table.name!r}: "
                "every env of a game needs the same"
            )
        self.world.set_table(env, table)
        self.state = self.state._replace(world=self.world.state)  # it may have grown
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
        state.pressed[env] = False
        self.world.reset_targets(env)
        if self.book.active:
            rules = self.rule_set
            state.lights[env] = [light.lit for light in rules.lights] if rules else []
            for array in (state.counters, state.timers, state.bonus, state.rule_points,
                          state.rule_events, state.lights_were_on):  # fmt: skip
                array[env] = 0
            state.multiplier[env] = 1
            state.save_frames[env] = -1
            state.flippers_before[env] = False
        if self.cabinet:
            self.world.state.cabinet[env] = 0.0
            self.world.state.tilted[env] = False
            for array in (state.nudge_wait, state.tilt_warnings, state.warning_age,
                          state.skill_left, state.lane_frames):  # fmt: skip
                array[env] = 0
            self.serve(env)
        else:
            self.launch(env, rng)
        if options:
            self.world.place_ball(env, position, velocity)
            self.state.on_plunger[env] = False
            self._moved(env)

    def launch(self, env: int, rng: np.random.Generator) -> None:
        """Fire env ``env``'s ball off the plunger: the player's plunge at the speed of its pull
        and a scatter drawn from ``rng``; else the machine's launch, at a speed drawn from the
        table's range (the next ball, or with the player's plunger the ball search's launch of
        a ball left in the shooter lane)."""
        self.launch_balls([env], {env: rng})

    def launch_balls(self, envs: Sequence[int], rngs: Sequence[np.random.Generator] | dict) -> None:
        """:meth:`launch` for each of ``envs`` (env ``i`` drawing from ``rngs[i]``), the draws
        made env by env, in the order given, and the balls put in play at once."""
        progress, state = self._progress, self.state
        speeds = []
        for env in envs:
            plunger = self.world.table_of(env).plunger
            if progress.plunge[env]:
                scatter = float(rngs[env].uniform(-plunger.scatter, plunger.scatter))
                speeds.append(plunger.launch_speed(state.plunger_pull[env]) + scatter)
            else:
                low, high = plunger.speed
                speeds.append(float(rngs[env].uniform(low, high)))
        envs = np.asarray(envs, dtype=np.intp)
        self.world.launch_balls(envs, speeds)
        plunged = envs[progress.plunge[envs]]
        progress.plunge[envs] = False
        if len(plunged):
            state.skill_left[plunged] = self._rules_now().skill_frames
        first = envs[state.save_frames[envs] < 0]  # the ball save runs from the first launch
        state.save_frames[first] = self.book.save_frames
        state.on_plunger[envs] = False
        state.plunger_pull[envs] = 0.0
        self._moved(envs)

    def serve(self, env: int) -> None:
        """Put env ``env``'s ball on the player's plunger, at rest, to wait for the player."""
        self.world.launch(env, 0.0)
        self.world.state.active[env] = False
        self.state.on_plunger[env] = True
        self.state.plunger_pull[env] = 0.0
        self._moved(env)

    @property
    def in_play(self) -> np.ndarray:
        """(n_envs,) bool: a ball is in play (moving, or waiting on the player's plunger)."""
        return self.world.state.active | self.state.on_plunger

    def _moved(self, envs: int | np.ndarray) -> None:
        """Restart the ball-search clock of env ``envs`` (or of each of them) where its ball is
        now."""
        self.state.anchor[envs] = self.world.balls[envs][..., [BALL_X, BALL_Y]]
        self.state.still_frames[envs] = 0

    def buttons(self, actions: Any) -> np.ndarray:
        """The (n_envs, buttons) bool buttons (:attr:`button_names`) held by ``actions``:
        (n_envs,) integers for ``"discrete"`` (rows of :attr:`discrete_buttons`), (n_envs,
        buttons) zeros and ones for ``"multibinary"``."""
        actions = np.asarray(actions)
        if self.action_type == "discrete":
            n_actions = len(self.discrete_buttons)
            valid = (
                actions.shape == (self.n_envs,)
                and actions.dtype.kind in "biu"  # Gymnasium's Discrete takes True as 1
                and actions.min() >= 0
                and actions.max() < n_actions
            )
            if valid:  # (as integers: a bool array would index as a mask)
                return self.discrete_buttons[actions.astype(np.intp)]
            expected = f"({self.n_envs},) integers in [0, {n_actions})"
        else:
            shape = (self.n_envs, len(self.button_names))
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

        Each env's frames run in one compiled loop (``play_frames``), which comes back
        here only for launches (they draw from the env's random stream), and, with a physics
        backend other than the swept kernel or with :attr:`on_frame` set, for each frame's
        physics; ``on_frame()`` is then called after it (the frame's points not yet counted).

        Returns ``(reward, game_over)``, (n_envs,) float64 and bool, the reward summed over the
        frames. The step's points and drains (summed) are in :attr:`state`.
        """
        buttons = self.buttons(actions)
        commands = buttons[:, self.world.flipper_buttons]
        cabinet = buttons[:, len(BUTTONS) :] if self.cabinet else self._no_cabinet_buttons
        progress = self._progress
        playing = self._everyone if frozen is None else ~frozen
        if frozen is None:
            progress.stage[:] = NEW_STEP
        else:
            progress.stage[:] = np.where(playing, NEW_STEP, STEP_DONE)
        if self.repeat_action_probability:
            draws = progress.repeat_draws
            for env in np.flatnonzero(playing):
                draws[env] = rngs[env].random(draws.shape[1])
        rules = self._rules_now()
        geometries, settings = self.world.tables.kernel_arrays()
        # With on_frame the loop hands each frame's physics to Python (the same kernel), and the
        # hook sees the frame.
        swept = self.world.swept_kernel and self.on_frame is None
        args = (geometries, settings, self.state, self.world.scratch, progress, rules, commands,
                np.ascontiguousarray(cabinet), swept)  # fmt: skip
        play = self._play.get(type(geometries))  # one table (tuples) or one per env (lists)
        if play is None:
            loop = play_frames if isinstance(geometries, tuple) else play_frames_per_env
            play = self._play[type(geometries)] = compiled_entry(loop, (*args, 0, 0))
        while True:
            self.world.threads.run(play, self.n_envs, *args)
            if not progress.finite.all():
                bad = np.flatnonzero(~progress.finite).tolist()
                raise FloatingPointError(f"the ball state of env(s) {bad} is no longer finite")
            # Launches first: the player's plunge hands back before its frame's physics.
            launches = np.flatnonzero(progress.launch)
            if len(launches):
                self.launch_balls(launches, rngs)
            progress.launch[:] = False
            # (Not swept) the backend's frame is due.
            physics = None if swept else progress.stage == PHYSICS
            if physics is not None and physics.any():
                self.world.step(None, physics)
                progress.stage[physics] = AFTER_PHYSICS
                if self.on_frame is not None:
                    self.on_frame()
            elif len(launches) == 0:
                break
        if frozen is None:
            self.state.points[:] = progress.points
            self.state.drained[:] = progress.drained
            return progress.reward.copy(), self.state.balls_left == 0
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
            bonus_shaping=self.bonus_shaping if self.book.active else 0.0,
            heights=self.world.tables.height,
            skip_heights=self.skip_above * self.world.tables.height,
            frame_skip=self.frame_skip,
            skip_frames=MAX_RUN_ON_FRAMES if self.skip_above else 0,
            repeat_probability=self.repeat_action_probability,
            max_frames=-1 if self.max_frames is None else self.max_frames,
            search_frames=self.ball_search_frames,
            radius=self.table.ball.radius,
            scores=self.world.tables.scores,
            **self._cabinet_rules(),
            book=self.book,
        )

    def _cabinet_rules(self) -> dict[str, Any]:
        """The cabinet's numbers of the step loop (all zero for a table without a cabinet)."""
        table, rate = self.table, self.table.simulation.frame_rate
        plunger, cabinet, tilt = table.plunger, table.cabinet, table.tilt
        skill_sensors = np.full(self.n_envs, -1, dtype=np.int64)
        if not self.cabinet:
            return dict(cabinet=False, plunger_x=0.0, plunger_y=0.0, stroke=0.0, pull_step=0.0,
                        nudge_impulse=0.0, nudge_frames=0, warnings=0, warning_frames=0,
                        settle_frames=0, skill_sensors=skill_sensors, skill_bonus=0,
                        skill_frames=0)  # fmt: skip
        skill = plunger.skill_shot
        for env in range(self.n_envs):
            names = self.world.table_of(env).element_names
            if skill is not None and skill.sensor in names:
                skill_sensors[env] = names.index(skill.sensor)
        return dict(
            cabinet=True,
            plunger_x=float(plunger.position[0]),
            plunger_y=float(plunger.position[1]),
            stroke=plunger.stroke,
            pull_step=plunger.stroke / (plunger.pull_time * rate),
            nudge_impulse=cabinet.nudge_impulse,
            nudge_frames=max(1, round(cabinet.nudge_interval * rate)),
            warnings=tilt.warnings,
            warning_frames=max(1, round(tilt.warning_time * rate)),
            settle_frames=round(tilt.settle_time * rate),
            skill_sensors=skill_sensors,
            skill_bonus=0 if skill is None else skill.bonus,
            skill_frames=0 if skill is None else max(1, round(skill.time * rate)),
        )

    # --- what the envs report -----------------------------------------------------------------

    def events(self, env: int) -> dict[str, int]:
        """The scoring elements env ``env`` hit in the last step: name -> hits."""
        hits = self.world.state.hits[env]
        names = self.world.table_of(env).element_names
        return {names[i]: int(hits[i]) for i in self.world.tables.scoring[env] if hits[i]}

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
            **self._cabinet_infos(slice(None)),
            **self._rule_infos(slice(None)),
        }

    def _rule_infos(self, envs: int | slice) -> dict[str, Any]:
        """The rules' entries of the infos (none for a table without rules or ball save):
        ``rule_events`` (the step's rules fired, ball saves and bonuses, counts in the order of
        :attr:`event_names`), ``bonus``, ``bonus_multiplier`` and ``rule_score`` (points the rules
        scored in this game: modes, awards and end-of-ball bonuses)."""
        if not self.book.active:
            return {}
        state = self.state
        return {
            "rule_events": state.rule_events[envs].copy(),
            "bonus": state.bonus[envs].copy(),
            "bonus_multiplier": state.multiplier[envs].copy(),
            "rule_score": state.rule_points[envs].copy(),
        }

    def _cabinet_infos(self, envs: int | slice) -> dict[str, Any]:
        """The cabinet's entries of the infos (none for a table without a cabinet)."""
        if not self.cabinet:
            return {}
        state, world = self.state, self.world.state
        return {
            "tilt_warnings": state.tilt_warnings[envs].copy(),
            "tilted": world.tilted[envs] | self._progress.tilt[envs],
            "ball_on_plunger": state.on_plunger[envs].copy(),
            "plunger_pull": state.plunger_pull[envs].copy(),
            "cabinet_offset": world.cabinet[envs, CABINET_X : CABINET_Y + 1].copy(),
            "skill_shot": self._progress.skill_shot[envs].copy(),
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
            **{
                key: value if isinstance(value, np.ndarray) else value.item()
                for key, value in self._cabinet_infos(env).items()
            },
            **self._rule_info(env),
        }

    def _rule_info(self, env: int) -> dict[str, Any]:
        """:meth:`_rule_infos` of one env, ``rule_events`` as name -> times this step."""
        info = {key: value.item() for key, value in self._rule_infos(env).items()
                if key != "rule_events"}  # fmt: skip
        if info:
            counts = self.state.rule_events[env]
            info["rule_events"] = {
                name: int(n) for name, n in zip(self.event_names, counts, strict=False) if n
            }
        return info


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
