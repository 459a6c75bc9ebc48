"""The rules of pinball over a batch of envs: actions to buttons, balls per game, launches, drains,
score, reward and the per-step info.

Everything works over the env axis, so the single env (a Game of one) and a vector env (a Game
of N) run the same code. A step's frames run in one compiled loop (``game.play.play_frames``),
by the step parameters of ``game.parameters``; only launches (random draws) come back to
Python. Everything that changes during play is in one record, ``game.state.GameState``, so that
a game can be snapshotted and restored as one object; what does not change (every env's table)
is the World's ``tables`` record. The actions are decoded in ``game.actions``, the infos written
in ``game.infos``.
"""

import reprlib
from collections.abc import Callable, Mapping, Sequence
from typing import Any

import numpy as np

from pinball_env.game.actions import CABINET_BUTTONS, button_names, decode_actions, discrete_buttons
from pinball_env.game.infos import batch_infos, element_events, env_info
from pinball_env.game.multiball import Multiball
from pinball_env.game.parameters import (
    MAX_RUN_ON_FRAMES,
    StepParameters,
    ball_search_frames,
    make_step_parameters,
)
from pinball_env.game.play import (
    AFTER_PHYSICS,
    NEW_STEP,
    PHYSICS,
    STEP_DONE,
    new_progress,
    play_frames,
    play_frames_per_env,
)
from pinball_env.game.playable import check_playable, check_same_game
from pinball_env.game.rulebook import RuleBook, compile_rules
from pinball_env.game.state import (
    GameState,
    ball_holders,
    clear_game,
    copy_state,
    copy_state_into,
    make_game_state,
)
from pinball_env.options import PinballOptions
from pinball_env.physics.columns import BALL_X, BALL_Y
from pinball_env.sim.backends import make_world
from pinball_env.sim.world import compiled_entry
from pinball_env.table import BUTTONS, Table, check_ball_state
from pinball_env.table.rules import RuleSet

RESET_OPTIONS = ("ball_position", "ball_velocity")


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

    A table whose trough holds several balls is played by ``game.multiball`` (:attr:`multi`)
    around each frame's physics, which the compiled loop then hands back to Python: a ball
    that drains goes back to the trough, the ball is lost only when the last ball in play
    drains, locks hold balls out of play, the auto-plunger launches ``add_balls``. The loop
    plays the game's ball (``state.game_ball``, ``state.game_ball_active``): the first in play.

    Attributes:
        world: the physics of every env (and, in ``world.tables``, every env's table).
        multi: the several balls (``game.multiball.Multiball``), or None for one ball.
        state: the ``GameState`` (``state.world`` is ``world.state``).
        progress: where each env is in the step (``game.play.StepProgress``).
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
        # Several balls (a trough of more than one): game.multiball plays them around the
        # frames' physics, in the compiled loop's frames (game.multiball_passes).
        several = self.world.n_balls > 1
        self.state = make_game_state(self.world.state, self.book, rule_set, len(table.flippers),
                                     ball_holders(self.world), several,
                                     len(table.locks))  # fmt: skip
        self.multi = Multiball(self.world, table, self.state) if several else None
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
        self._parameters: StepParameters | None = None  # see step_parameters
        self._play: dict[type, Any] = {}  # play_frames's compiled entries (compiled_entry)
        # Called after each frame's physics, when set: to record the frames a step runs on.
        self.on_frame: Callable[[], None] | None = None
        self.repeat_action_probability = options.repeat_action_probability
        # One draw per frame a step may play, from each env's stream (none without sticky).
        frames = self.frame_skip + (MAX_RUN_ON_FRAMES if self.skip_above else 0)
        self.progress = new_progress(n_envs, frames if self.repeat_action_probability else 0)
        self.ball_search_frames = ball_search_frames(table)

    def set_table(self, env: int, table: Table) -> None:
        """Make env ``env`` play ``table`` (see ``World.set_table``); start a new game after.
        The other envs' games go on."""
        check_same_game(table, self.table)
        self.world.set_table(env, table)
        self._take_state(self.state)  # its arrays may have grown
        self._parameters = None  # heights and scores changed, and the arrays may have grown

    def __getstate__(self) -> dict[str, Any]:
        state = self.__dict__.copy()
        state["_play"] = {}  # compiled entries cannot be pickled; a copy finds its own
        state["_parameters"] = None  # a copy makes its own, over its own arrays
        state["on_frame"] = None  # a recorder's, not the game's
        return state

    def __setstate__(self, state: dict[str, Any]) -> None:
        self.__dict__.update(state)
        self._take_state(self.state)

    def _take_state(self, state: GameState) -> None:
        """Hold ``state`` with the World's arrays as its ``world`` (a pickle or a copy takes
        them apart): on a table of one ball, the game's ball is the World's slot 0 again."""
        world = self.world.state
        self.state = state._replace(world=world)
        if self.multi is None:
            self.state = self.state._replace(
                game_ball=world.balls[:, 0], game_ball_active=world.active[:, 0]
            )
        else:
            self.multi.state = self.state

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
        return copy_state(self.state)

    def restore(self, snapshot: GameState) -> None:
        """Put every env back to ``snapshot`` (from :meth:`snapshot` of a Game on the same table
        with as many envs)."""
        copy_state_into(snapshot, self.state)
        if self.multi is not None:
            self.multi.remember_all()

    def restored(self, env: int) -> None:
        """Env ``env``'s rows of :attr:`state` were put back (a saved game, ``envs.states``):
        what the game keeps beside them is taken from them again."""
        if self.multi is not None:
            self.multi.remember(env)

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
            assert table.plunger is not None  # (check_playable)
            position = options.get("ball_position", table.plunger.position)
            velocity = options.get("ball_velocity", (0.0, 0.0))
            position, velocity = check_ball_state(table, position, velocity, "reset options")
        self.world.rest_flippers(env)
        self.world.reset_targets(env)
        lights = None
        if self.book.active:
            rules = self.rule_set
            lights = [light.lit for light in rules.lights] if rules else []
        clear_game(self.state, env, self.balls_per_game, lights, self.cabinet)
        if self.multi is not None:
            self.multi.new_game(env)
        if self.cabinet:
            self.serve(env)
        else:
            self.launch(env, rng)
        if options:
            self.state.on_plunger[env] = False
            if self.multi is not None:
                self.multi.new_game(env)
                self.state.ball_slot[env] = 0
            self.world.place_ball(env, position, velocity)
            if self.multi is not None:
                self.multi.sync(env)
            self._moved(env)

    def launch(self, env: int, rng: np.random.Generator) -> None:
        """Fire env ``env``'s ball off the plunger: the player's plunge at the speed of its pull
        and a scatter drawn from ``rng``; else the machine's launch, at a speed drawn from the
        table's range (the next ball, or with the player's plunger the ball search's launch of
        a ball left in the shooter lane)."""
        self.launch_balls([env], {env: rng})

    def launch_balls(
        self, envs: Sequence[int] | np.ndarray, rngs: Sequence[np.random.Generator] | dict
    ) -> None:
        """:meth:`launch` for each of ``envs`` (env ``i`` drawing from ``rngs[i]``), the draws
        made env by env, in the order given, and the balls put in play at once."""
        progress, state = self.progress, self.state
        speeds = []
        for env in envs:
            plunger = self.world.table_of(env).plunger
            assert plunger is not None  # (check_playable)
            if progress.plunge[env]:
                scatter = float(rngs[env].uniform(-plunger.scatter, plunger.scatter))
                speeds.append(plunger.launch_speed(state.plunger_pull[env]) + scatter)
            else:
                low, high = plunger.speed
                speeds.append(float(rngs[env].uniform(low, high)))
        envs = np.asarray(envs, dtype=np.intp)
        if self.multi is None:
            self.world.launch_balls(envs, speeds)
        else:  # the game's ball where it is in play or on the plunger, else a trough ball
            for env, speed in zip(envs, speeds, strict=True):
                self.multi.place(int(env), self.multi.launch_slot(int(env)), (0.0, speed), True)
        plunged = envs[progress.plunge[envs]]
        progress.plunge[envs] = False
        if len(plunged):
            state.skill_left[plunged] = self.step_parameters().skill_frames
        first = envs[state.save_frames[envs] < 0]  # the ball save runs from the first launch
        state.save_frames[first] = self.book.save_frames
        state.on_plunger[envs] = False
        state.plunger_pull[envs] = 0.0
        if self.multi is not None:
            self.multi.sync_envs(envs)
        self._moved(envs)

    def serve(self, env: int) -> None:
        """Put env ``env``'s ball on the player's plunger, at rest, to wait for the player."""
        self.state.plunger_pull[env] = 0.0
        self.state.on_plunger[env] = True
        if self.multi is not None:
            self.multi.place(env, self.multi.launch_slot(env), (0.0, 0.0), False)
            self.multi.sync(env)
        else:
            self.world.launch(env, 0.0)
            self.world.state.active[env, 0] = False
        self._moved(env)

    @property
    def in_play(self) -> np.ndarray:
        """(n_envs,) bool: a ball is in play (moving, or waiting on the player's plunger)."""
        return self.state.game_ball_active | self.state.on_plunger

    def _moved(self, envs: int | np.ndarray) -> None:
        """Restart the ball-search clock of env ``envs`` (or of each of them) where its ball is
        now."""
        self.state.anchor[envs] = self.state.game_ball[envs][..., [BALL_X, BALL_Y]]
        self.state.still_frames[envs] = 0

    def buttons(self, actions: Any) -> np.ndarray:
        """The (n_envs, buttons) bool buttons (:attr:`button_names`) held by ``actions``:
        (n_envs,) integers for ``"discrete"`` (rows of :attr:`discrete_buttons`), (n_envs,
        buttons) zeros and ones for ``"multibinary"``."""
        return decode_actions(
            actions, self.action_type, self.discrete_buttons, self.n_envs, len(self.button_names)
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
        playing = self._everyone if frozen is None else ~frozen
        self._start_step(playing, frozen is None, rngs)
        self._play_frames(buttons, rngs)
        progress = self.progress
        if frozen is None:
            self.state.points[:] = progress.points
            self.state.drained[:] = progress.drained
            return progress.reward.copy(), self.state.balls_left == 0
        self.state.points[playing] = progress.points[playing]
        self.state.drained[playing] = progress.drained[playing]
        return np.where(playing, progress.reward, 0.0), self.state.balls_left == 0

    def _start_step(
        self, playing: np.ndarray, everyone: bool, rngs: Sequence[np.random.Generator]
    ) -> None:
        """Set the envs that ``playing`` marks (all of them where ``everyone``) at a new step,
        the others done, and draw the step's sticky-action draws from each env's stream."""
        progress = self.progress
        if everyone:
            progress.stage[:] = NEW_STEP
        else:
            progress.stage[:] = np.where(playing, NEW_STEP, STEP_DONE)
        if self.repeat_action_probability:
            draws = progress.repeat_draws
            for env in np.flatnonzero(playing):
                draws[env] = rngs[int(env)].random(draws.shape[1])

    def _play_frames(self, buttons: np.ndarray, rngs: Sequence[np.random.Generator]) -> None:
        """Run the compiled step loop with ``buttons`` held until every env's step is done,
        doing what it hands back: launches (drawn from ``rngs``) and, unless swept, the
        backend's physics of a frame (then :attr:`on_frame`)."""
        commands = buttons[:, self.world.flipper_buttons]
        cabinet = buttons[:, len(BUTTONS) :] if self.cabinet else self._no_cabinet_buttons
        progress, params = self.progress, self.step_parameters()
        geometries, settings = self.world.tables.kernel_arrays()
        # With on_frame the loop hands each frame's physics to Python (the same kernel), and the
        # hook sees the frame; so does a table of one ball with saucers or locks.
        multi = self.multi
        swept = self.world.swept_kernel and self.on_frame is None
        swept = swept and (multi is not None or not self.world.several)
        several = (multi.memory, multi.parameters) if multi is not None else (None, None)
        args = (geometries, settings, self.state, self.world.scratch, progress, params, commands,
                np.ascontiguousarray(cabinet), swept, *several)  # fmt: skip
        play = self._play.get(type(geometries))  # one table (tuples) or one per env (lists)
        if play is None:
            loop = play_frames if isinstance(geometries, tuple) else play_frames_per_env
            play = self._play[type(geometries)] = compiled_entry(loop, (*args, 0, 0))
        while True:
            self.world.threads.run(play, self.n_envs, *args)
            if not progress.finite.all():
                bad = np.flatnonzero(~progress.finite).tolist()
                raise FloatingPointError(f"the ball state of env(s) {bad} is no longer finite")
            if multi is not None:
                multi.write_back()  # the loop's writes to the game's ball, to its slot
            # Launches first: the player's plunge hands back before its frame's physics.
            launches = np.flatnonzero(progress.launch)
            if len(launches):
                self.launch_balls(launches, rngs)
            progress.launch[:] = False
            # The auto-plunger's launches the loop handed back (a draw each).
            serves = np.flatnonzero(progress.serve)
            if len(serves):
                assert multi is not None  # (only a game of several balls serves)
                multi.serve(serves, rngs)
                progress.serve[:] = False
            # (Not swept) the backend's frame is due.
            physics = None if swept else progress.stage == PHYSICS
            if physics is not None and physics.any():
                if multi is not None:
                    multi.before_frame(np.flatnonzero(physics), rngs)
                self.world.step(None, physics)
                if multi is not None:
                    multi.after_frame(physics)
                progress.stage[physics] = AFTER_PHYSICS
                if self.on_frame is not None:
                    self.on_frame()
            elif len(launches) == 0 and len(serves) == 0:
                break

    def out_of_time(self) -> np.ndarray:
        """(n_envs,) bool: the game has played ``max_frames`` frames (never, without)."""
        if self.max_frames is None:
            return np.zeros(self.n_envs, dtype=bool)
        return self.state.frames >= self.max_frames

    def step_parameters(self) -> StepParameters:
        """The numbers the compiled step loop plays by (per env where tables differ), made
        again only after :meth:`set_table`."""
        if self._parameters is None:
            self._parameters = make_step_parameters(self.options, self.table, self.world, self.book)
        return self._parameters

    # --- what the envs report -----------------------------------------------------------------

    def events(self, env: int) -> dict[str, int]:
        """The scoring elements env ``env`` hit in the last step: name -> hits."""
        return element_events(self, env)

    def infos(self) -> dict[str, np.ndarray]:
        """The per-step info of every env as arrays (``game.infos.batch_infos``)."""
        return batch_infos(self)

    def info(self, env: int) -> dict[str, Any]:
        """The per-step info of env ``env`` as Python numbers (``game.infos.env_info``)."""
        return env_info(self, env)
