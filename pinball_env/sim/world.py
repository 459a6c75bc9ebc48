"""A batch of balls on a table: the kernel's arrays and the call into the world step.

``World`` owns the preallocated arrays the kernel writes in place (built by
:func:`~pinball_env.physics.make_state` and :func:`~pinball_env.physics.make_scratch` from the
packed table). The single env is a World of one; a vector env is a World of N calling the same
kernel, :func:`~pinball_env.physics.step_world`. :meth:`World.set_table` gives an env a table of
its own (generated layouts): the World then steps every env on its own table in one call of
:func:`~pinball_env.physics.step_tables`. Physics backends swap :meth:`World._advance`.

Ball slots. Every env has ``n_balls`` ball slots (the table's trough; 1 on a table of one
ball): ``balls`` (N, M, 5), ``active`` and ``held`` (N, M), the kernel's own arrays
(``physics.State``); ``place_ball``/``launch`` take ``ball=``, and ``hold_ball``,
``release_ball`` and ``release_lock`` hold and free them. Which kernel steps the slots is
decided once, here, when the World is built: a table of several balls, or with saucers or
locks, is stepped by :func:`~pinball_env.physics.multiball.step_multiworld` (ball-ball contact,
held balls), every other table by ``step_world`` (its slot 0).

Saucers and locks are played at the end of each frame (after the physics, for either
backend; every env in one compiled pass): ``sim.holders``.
"""

import math
import sys
import threading
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass
from typing import Any, ClassVar

import numba
import numpy as np

from pinball_env.physics import (
    CONTACT_CAPACITY,
    make_scratch,
    make_state,
    step_tables,
    step_world,
)
from pinball_env.physics.columns import (
    BALL_VX,
    BALL_VY,
    BALL_X,
    BALL_Y,
    CONTACT_ELEMENT,
    CONTACT_SPEED,
    CONTACT_TIME,
    FLIPPER_REST_ANGLE,
)
from pinball_env.physics.multiball import step_multiworld
from pinball_env.sim.holders import holder_arrays, play_holders
from pinball_env.sim.parallel import EnvThreads
from pinball_env.sim.tables import EnvTables
from pinball_env.table import BUTTONS, Table

# Fastest ball World.place_ball accepts [m/s]: far beyond any table (tables and resets allow
# 100 m/s; the property tests fire balls at up to 1 km/s), well inside exact arithmetic.
MAX_PLACE_SPEED = 1e4


@dataclass(frozen=True)
class Contact:
    """One contact (or sensor crossing) of a ball during a frame."""

    element: int  # global element id: segments, circles, flippers, sensors
    name: str  # element name from the table, e.g. "outline[2]" or "bumper_top"
    time: float  # seconds since the start of the frame
    speed: float  # normal approach speed before the response [m/s] (0 for sensors)


COMPILE_NOTICE = (
    "pinball_env: compiling the simulation's step loop for this kind of game and this Python, "
    "once: one to three minutes on 2 cores (numba caches it beside the package; later runs "
    "load it in seconds)"
)


@contextmanager
def notice_if_slow(message: str, after: float = 5.0) -> Iterator[None]:
    """Print ``message`` on standard error if the block still runs ``after`` seconds in: a
    first compile's silent minutes said aloud (a load from numba's cache takes less, and says
    nothing)."""
    timer = threading.Timer(after, print, (message,), {"file": sys.stderr, "flush": True})
    timer.daemon = True
    timer.start()
    try:
        yield
    finally:
        timer.cancel()


def compiled_entry(function: Callable[..., Any], args: tuple) -> Callable[..., Any]:
    """The compiled entry of numba function ``function`` for the types of ``args``, compiled
    (or loaded from the cache) by calling it with them: a call of the entry skips numba's
    dispatch, which infers the type of every array on every call (about 3.5 us for the
    kernel's 26, as long as the kernel takes for a ball). ``args`` must be a call that changes
    nothing (no env). ``function`` itself with ``NUMBA_DISABLE_JIT``. A compile that takes
    long says so (:data:`COMPILE_NOTICE`)."""
    with notice_if_slow(COMPILE_NOTICE):
        function(*args)
    overloads = getattr(function, "overloads", None)
    if overloads is None:
        return function
    return overloads[tuple(numba.typeof(arg) for arg in args)].entry_point


def several_balls(table: Table) -> bool:
    """Whether ``table`` needs the several-ball kernel: a trough of several balls, saucers or
    locks (balls held in place, fixed circles to the others)."""
    return table.n_balls > 1 or bool(table.saucers) or bool(table.locks)


class World:
    """``n_envs`` independent balls and flipper sets, on the same table unless
    :meth:`set_table` gives some env another, stepped together.

    Attributes:
        tables: the static per-env record (:class:`~pinball_env.sim.tables.EnvTables`): every
            env's table, packed, with the numbers the rules and observations read of it.
        table: the table the World was made with, every env's until :meth:`set_table` gives
            one another (:meth:`table_of` is any env's); its ball and simulation settings are
            every env's.
        geometry, settings: ``table`` as the kernel sees it (``table.pack()``,
            ``table.pack_settings()``).
        state: the kernel's per-env arrays (``physics.State``): balls, active, flipper angles
            and angular velocities, flipper commands, the contact log and the hit counts.
        scratch: the kernel's per-env work arrays.
        num_threads: threads that share the envs of a frame (the kernel releases the GIL; the
            results are bitwise the same for any count).
        n_balls: ball slots per env (``table.n_balls``: the trough's balls, else 1).
        several: the table has several balls, saucers or locks: the several-ball kernel
            steps it.
        pair: the ball-ball material row (``table.pack_ball_pair()``).
    """

    # Whether the physics is the swept kernels' (``step_world``'s ``step_ball``, or with
    # ``several`` ``step_multiworld``'s ``step_balls`` then ``sim.holders``), which compiled loops
    # over frames (the game's step) may run themselves; a backend that swaps :meth:`_advance`
    # says no.
    swept_kernel: ClassVar[bool] = True

    def __init__(self, table: Table, n_envs: int = 1, num_threads: int = 1) -> None:
        self.threads = EnvThreads(num_threads)
        self._entry: Callable[..., int] | None = None
        self.tables = EnvTables(table, n_envs)
        self.n_balls = table.n_balls
        self.state = make_state(self.geometry, n_envs, self.n_balls)
        self.scratch = make_scratch(self.geometry, self.settings, n_envs, self.n_balls)
        # Column of the buttons array that drives each flipper.
        self.flipper_buttons = np.array(table.flipper_buttons, dtype=np.int64)
        self._everyone = np.ones(n_envs, dtype=bool)  # the kernel's mask that steps every env
        self.pair = table.pack_ball_pair()
        self.several = several_balls(table)
        if self.several:
            hits = np.zeros((n_envs, len(table.element_scores)), dtype=np.int64)
            self.state = self.state._replace(hits=hits)  # the saucers' and locks' ids too
        # Saucers and locks, by element id (after every packed element); per ball: the element
        # holding it (-1: none), its slot in a lock, how long it has been held [s], and the
        # element it was last released from (not captured by it again until it is out of
        # reach; -1: none).
        self.saucer_ids, self.lock_ids = (
            np.array(table.element_ids(kind), dtype=np.int64) for kind in ("saucers", "locks")
        )
        self.holders = holder_arrays(table, self.saucer_ids, self.lock_ids)
        shape = (n_envs, self.n_balls)
        self.holder = np.full(shape, -1, dtype=np.int64)
        self.slot = np.full(shape, -1, dtype=np.int64)
        self.held_time = np.zeros(shape)
        self.released_from = np.full(shape, -1, dtype=np.int64)
        for env in range(n_envs):
            self.reset_targets(env)
            self.rest_flippers(env)
            self.place_ball(env, table.ball.start, table.ball.velocity)

    @property
    def n_envs(self) -> int:
        return self.state.balls.shape[0]

    @property
    def table(self) -> Table:
        return self.tables.first

    @property
    def geometry(self) -> Any:
        return self.tables.geometry

    @property
    def settings(self) -> Any:
        return self.tables.settings

    @settings.setter
    def settings(self, settings: Any) -> None:  # for tests that change the first table's
        self.tables.settings = settings

    @property
    def scores(self) -> np.ndarray:
        """(n_envs, elements) int64: points per element id, per env."""
        return self.tables.scores

    # Shorthands for the ball slots' arrays (the kernel's, ``state``).
    @property
    def balls(self) -> np.ndarray:
        """(n_envs, n_balls, 5) every ball slot's state (columns ``BALL_*``), writable."""
        return self.state.balls

    @property
    def active(self) -> np.ndarray:
        """(n_envs, n_balls) bool: the ball is in play (cleared when it drains); writable."""
        return self.state.active

    @property
    def held(self) -> np.ndarray:
        """(n_envs, n_balls) bool: the ball is held (a saucer, a lock, :meth:`hold_ball`): it
        does not move and is a fixed circle to the others. Read-only by convention: use
        :meth:`hold_ball` and :meth:`release_ball`."""
        return self.state.held

    def _check_ball(self, ball: int) -> int:
        if not 0 <= ball < self.n_balls:
            raise ValueError(f"ball must be in [0, {self.n_balls}), got {ball}")
        return int(ball)

    def _free(self, env: int, ball: int) -> None:
        """Ball ``ball`` of env ``env`` is no longer held by anything."""
        self.holder[env, ball] = self.slot[env, ball] = -1
        self.held_time[env, ball] = 0.0
        self.state.held[env, ball] = False

    def place_ball(
        self,
        env: int,
        position: tuple[float, float],
        velocity: tuple[float, float] = (0.0, 0.0),
        ball: int = 0,
    ) -> None:
        """Put env ``env``'s ball ``ball`` (a slot, 0 by default) in play, free, at
        ``position`` [m] with ``velocity`` [m/s], no spin.

        Raises ValueError for a non-finite position or velocity, or a speed above
        MAX_PLACE_SPEED. (This is the physics API: tables and resets check more, see
        ``table.check_ball_state``. A ball placed inside a wall, post or flipper is pushed out
        as it can be; the step keeps a sound state sound, see ``deepest_overlap``.)
        """
        (x, y), (vx, vy) = position, velocity
        if not all(math.isfinite(value) for value in (x, y, vx, vy)):
            raise ValueError(
                f"ball state must be finite, got position {position}, velocity {velocity}"
            )
        if math.hypot(vx, vy) > MAX_PLACE_SPEED:
            raise ValueError(
                f"ball speed {math.hypot(vx, vy):g} m/s is above {MAX_PLACE_SPEED:g} m/s"
            )
        ball = self._check_ball(ball)
        row = self.state.balls[env, ball]
        row[:] = 0.0
        row[BALL_X], row[BALL_Y] = position
        row[BALL_VX], row[BALL_VY] = velocity
        self.state.active[env, ball] = True
        self._free(env, ball)
        self.released_from[env, ball] = -1

    def launch(self, env: int, speed: float, ball: int = 0) -> None:
        """Put env ``env``'s ball ``ball`` (0 by default) on the plunger and fire it up the
        shooter lane at ``speed``."""
        if ball != 0:
            table = self.table_of(env)
            if table.plunger is None:
                raise ValueError(f"table {table.name!r} has no plunger")
            self._check_speeds(np.array([speed], dtype=np.float64))
            self.place_ball(env, table.plunger.position, (0.0, float(speed)), ball)
            return
        self.launch_balls([env], [speed])

    def hold_ball(self, env: int, ball: int, position: tuple[float, float]) -> None:
        """Hold env ``env``'s ball ``ball`` at ``position`` [m], at rest and immovable (a fixed
        circle to the other balls) until :meth:`release_ball`; it is in play. Needs the
        several-ball kernel (a table with a trough of several balls, saucers or locks) or the
        pymunk backend."""
        ball = self._check_ball(ball)
        if not self.several:
            raise ValueError(
                f"table {self.table.name!r} has one ball and no saucer or lock: nothing holds "
                "a ball"
            )
        self.place_ball(env, position, (0.0, 0.0), ball)
        self.state.held[env, ball] = True

    def release_ball(self, env: int, ball: int, velocity: tuple[float, float]) -> None:
        """Let env ``env``'s held ball ``ball`` go, where it is, at ``velocity`` [m/s]."""
        ball = self._check_ball(ball)
        row = self.state.balls[env, ball]
        self.place_ball(env, (row[BALL_X], row[BALL_Y]), velocity, ball)
        self.released_from[env, ball] = -1

    def release_lock(self, env: int, lock: int) -> int:
        """Let every ball that env ``env``'s lock ``lock`` (an index into ``table.locks``)
        holds go at the lock's ``kick``; returns how many."""
        element = int(self.lock_ids[lock])
        kick = self.table_of(env).locks[lock].kick
        balls = np.flatnonzero(self.holder[env] == element)
        for ball in balls:
            self.release_ball(env, int(ball), kick)
            self.released_from[env, ball] = element
        return len(balls)

    def _play_holders(self, envs: np.ndarray | None) -> None:
        """The saucers and locks at the end of a frame (module docstring), every env in one
        compiled pass (:func:`play_holders`)."""
        stepped = self._everyone if envs is None else np.ascontiguousarray(envs, dtype=np.bool_)
        state = self.state
        play_holders(state.balls, state.active, state.held, self.holder, self.slot,
                     self.held_time, self.released_from, self.state, stepped, self.holders,
                     self.settings.dt)  # fmt: skip

    def launch_balls(
        self, envs: Sequence[int] | np.ndarray, speeds: Sequence[float] | np.ndarray
    ) -> None:
        """:meth:`launch` for each of ``envs`` at its entry of ``speeds`` [m/s], at once."""
        envs = np.asarray(envs, dtype=np.intp)
        positions = []
        for env in envs:
            table = self.table_of(env)
            if table.plunger is None:
                raise ValueError(f"table {table.name!r} has no plunger")
            positions.append(table.plunger.position)
        speeds = np.asarray(speeds, dtype=np.float64)
        self._check_speeds(speeds)
        balls = self.state.balls
        balls[envs, 0] = 0.0
        balls[envs, 0, BALL_X] = [x for x, _ in positions]
        balls[envs, 0, BALL_Y] = [y for _, y in positions]
        balls[envs, 0, BALL_VY] = speeds
        self.state.active[envs, 0] = True
        for env in envs:
            self._free(int(env), 0)
            self.released_from[env, 0] = -1

    @staticmethod
    def _check_speeds(speeds: np.ndarray) -> None:
        if not np.isfinite(speeds).all() or (np.abs(speeds) > MAX_PLACE_SPEED).any():
            raise ValueError(f"launch speeds must be finite and at most {MAX_PLACE_SPEED:g} m/s, "
                             f"got {speeds.tolist()}")  # fmt: skip

    def rest_flippers(self, env: int) -> None:
        """Put env ``env``'s flippers at rest against their lower stops, released."""
        geometry = self.tables.geometry_of(env)
        self.state.flipper_angle[env] = geometry.flippers[:, FLIPPER_REST_ANGLE]
        self.state.flipper_omega[env] = 0.0
        self.state.flipper_command[env] = False

    def reset_targets(self, env: int) -> None:
        """Env ``env``'s targets as a game starts: drop targets up, spinners still, kickbacks lit
        as the table says."""
        state, table = self.state, self.table_of(env)
        state.targets_up[env] = True
        state.bank_clock[env] = 0.0
        state.spinners[env] = 0.0
        state.kickback_lit[env] = False
        state.kickback_lit[env, : len(table.kickbacks)] = [k.lit for k in table.kickbacks]

    # --- a table per env ----------------------------------------------------------------------

    def table_of(self, env: int) -> Table:
        """The table env ``env`` plays."""
        return self.tables.table(env)

    def set_table(self, env: int, table: Table) -> None:
        """Make env ``env`` play ``table`` from now on: its flippers at rest, its ball at the
        table's start. The table needs the flippers of the World's table, driven by the same
        buttons (its other elements may differ in number and kind). Tables of several balls,
        saucers or locks play alone (a ValueError: the several-ball kernel takes one table)."""
        for which in (self.table, table):
            if several_balls(which):
                raise ValueError(
                    f"table {which.name!r} has several balls, saucers or locks: a World of it "
                    "plays one table in every env"
                )
        if table.flipper_buttons != self.table.flipper_buttons:
            raise ValueError(
                f"table {table.name!r} has flippers on buttons {table.flipper_buttons}, the "
                f"world's tables on {self.table.flipper_buttons}: every env needs the same"
            )
        if not self.tables.varied:
            self._entry = None  # the kernel now takes a table per env
        self._fit(*self.tables.set(env, table))
        self.scratch.near_zone[env] = -1.0  # the candidate set was the old table's
        self.reset_targets(env)
        self.rest_flippers(env)
        self.place_ball(env, table.ball.start, table.ball.velocity)

    def _fit(self, n_elements: int, n_sensors: int, max_passes: int, targets: tuple) -> None:
        """Widen the per-element rows of the state and scratch arrays (zero-padded) to hold a
        table of ``n_elements`` elements, ``n_sensors`` sensors, ``max_passes`` passes and
        ``targets`` (drop targets, banks, spinners, kickbacks). The arrays are replaced, so
        holders of ``state`` must take the new one (``Game`` does)."""

        def widen(array: np.ndarray, width: int) -> np.ndarray:
            if array.shape[1] >= width:
                return array
            wider = np.zeros((array.shape[0], width, *array.shape[2:]), dtype=array.dtype)
            wider[:, : array.shape[1]] = array
            return wider

        n_targets, n_banks, n_spinners, n_kickbacks = targets
        n_near = n_elements - n_spinners - n_kickbacks  # physics.data.near_size
        self.state = self.state._replace(
            hits=widen(self.state.hits, n_elements),
            targets_up=widen(self.state.targets_up, n_targets),
            bank_clock=widen(self.state.bank_clock, n_banks),
            spinners=widen(self.state.spinners, n_spinners),
            kickback_lit=widen(self.state.kickback_lit, n_kickbacks),
        )
        self.scratch = self.scratch._replace(
            crossings=widen(self.scratch.crossings, n_sensors),
            hit_elements=widen(self.scratch.hit_elements, max_passes),
            near=widen(self.scratch.near, n_near),
        )

    def step(self, buttons: np.ndarray | None = None, envs: np.ndarray | None = None) -> None:
        """Advance every env (or those in ``envs``) by one frame.

        Args:
            buttons: (n_envs, len(BUTTONS)) bool, the flipper buttons (left, right) held during
                the frame; None keeps the previous commands.
            envs: (n_envs,) bool, the envs to advance; the others are left exactly as they are
                (None: all).
        """
        if buttons is not None:
            pressed = np.asarray(buttons)
            shape = (self.n_envs, len(BUTTONS))
            if pressed.shape != shape:
                raise ValueError(
                    f"buttons must have shape {shape} ({', '.join(BUTTONS)} per env), "
                    f"got shape {pressed.shape}"
                )
            if pressed.dtype != np.bool_ and not np.all((pressed == 0) | (pressed == 1)):
                raise ValueError(f"buttons must be booleans or 0/1, got dtype {pressed.dtype}")
            commands = pressed[:, self.flipper_buttons]
            if envs is None:
                self.state.flipper_command[:] = commands
            else:
                self.state.flipper_command[envs] = commands[envs]
        if self._advance(envs):
            bad = np.flatnonzero(~np.isfinite(self.state.balls).all(axis=(1, 2))).tolist()
            raise FloatingPointError(f"the ball state of env(s) {bad} is no longer finite")
        if self.table.saucers or self.table.locks:
            self._play_holders(envs)

    def _advance(self, envs: np.ndarray | None = None) -> int:
        """One frame of physics on the state arrays of ``envs`` (a bool mask; None: all): the
        swept-collision kernel. Returns the number of envs whose ball state is no longer
        finite."""
        moving = self._everyone if envs is None else np.ascontiguousarray(envs, dtype=np.bool_)
        if moving.shape != (self.n_envs,):
            raise ValueError(f"envs must have shape ({self.n_envs},), got {moving.shape}")
        args: tuple[Any, ...]  # the kernel's arguments
        if self.several:
            args = (self.geometry, self.settings, self.state, self.scratch, self.pair, moving)
        elif self.tables.varied:
            geometries, settings = self.tables.kernel_arrays()
            args = (geometries, settings, self.state, self.scratch, moving)
        else:
            args = (self.geometry, self.settings, self.state, self.scratch, moving)
        return sum(self.threads.run(self._kernel(args), self.n_envs, *args))

    def _kernel(self, args: tuple) -> Callable[..., int]:
        """``step_world``'s (or ``step_tables``', ``step_multiworld``'s) compiled entry for these
        arrays' types."""
        if self._entry is None:
            step = step_tables if self.tables.varied else step_world
            if self.several:
                step = step_multiworld
            self._entry = compiled_entry(step, (*args, 0, 0))
        return self._entry

    def __getstate__(self) -> dict:
        state = self.__dict__.copy()
        state["_entry"] = None  # a compiled function cannot be pickled; a copy finds its own
        return state

    def frame_points(self) -> np.ndarray:
        """Points scored by each env in the last frame, (n_envs,) int64."""
        return (self.state.hits * self.tables.scores).sum(axis=1)

    def frame_contacts(self, env: int = 0) -> list[Contact]:
        """The logged contacts and sensor crossings of env ``env`` in the last frame."""
        count = min(int(self.state.contact_count[env]), CONTACT_CAPACITY)
        names = self.table_of(env).element_names
        return [
            Contact(
                element=int(row[CONTACT_ELEMENT]),
                name=names[int(row[CONTACT_ELEMENT])],
                time=float(row[CONTACT_TIME]),
                speed=float(row[CONTACT_SPEED]),
            )
            for row in self.state.contacts[env, :count]
        ]

    def trace(self, n_frames: int, env: int = 0, buttons: np.ndarray | None = None) -> np.ndarray:
        """Step ``n_frames`` frames and return env ``env``'s ball 0's centre after each,
        (n, 2)."""
        path = np.empty((n_frames, 2))
        for frame in range(n_frames):
            self.step(buttons)
            path[frame] = self.state.balls[env, 0, [BALL_X, BALL_Y]]
        return path


__all__ = ["CONTACT_CAPACITY", "Contact", "World"]
