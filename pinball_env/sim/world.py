"""A batch of balls on a table: the kernel's arrays and the call into the world step.

``World`` owns the preallocated arrays the kernel writes in place (built by
:func:`~pinball_env.physics.make_state` and :func:`~pinball_env.physics.make_scratch` from the
packed table). The single env is a World of one; a vector env is a World of N calling the same
kernel, :func:`~pinball_env.physics.step_world`. :meth:`World.set_table` gives an env a table of
its own (generated layouts): the World then steps every env on its own table in one call of
:func:`~pinball_env.physics.step_tables`. Physics backends swap :meth:`World._advance`.
"""

import math
from collections.abc import Callable, Sequence
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


def compiled_entry(function: Callable[..., Any], args: tuple) -> Callable[..., Any]:
    """The compiled entry of numba function ``function`` for the types of ``args``, compiled
    (or loaded from the cache) by calling it with them: a call of the entry skips numba's
    dispatch, which infers the type of every array on every call (about 3.5 us for the
    kernel's 26, as long as the kernel takes for a ball). ``args`` must be a call that changes
    nothing (no env). ``function`` itself with ``NUMBA_DISABLE_JIT``."""
    function(*args)
    overloads = getattr(function, "overloads", None)
    if overloads is None:
        return function
    return overloads[tuple(numba.typeof(arg) for arg in args)].entry_point


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
    """

    # Whether the physics is the swept kernel's ``step_ball``, which compiled loops over frames
    # (the game's step) may call directly; a backend that swaps :meth:`_advance` says no.
    swept_kernel: ClassVar[bool] = True

    def __init__(self, table: Table, n_envs: int = 1, num_threads: int = 1) -> None:
        self.threads = EnvThreads(num_threads)
        self._entry: Callable[..., int] | None = None
        self.tables = EnvTables(table, n_envs)
        self.state = make_state(self.geometry, n_envs)
        self.scratch = make_scratch(self.geometry, self.settings, n_envs)
        # Column of the buttons array that drives each flipper.
        self.flipper_buttons = np.array(table.flipper_buttons, dtype=np.int64)
        self._everyone = np.ones(n_envs, dtype=bool)  # the kernel's mask that steps every env
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

    # Shorthands for the arrays used most.
    @property
    def balls(self) -> np.ndarray:
        return self.state.balls

    @property
    def active(self) -> np.ndarray:
        return self.state.active

    def place_ball(
        self, env: int, position: tuple[float, float], velocity: tuple[float, float] = (0.0, 0.0)
    ) -> None:
        """Put env ``env``'s ball in play at ``position`` [m] with ``velocity`` [m/s], no spin.

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
        ball = self.state.balls[env]
        ball[:] = 0.0
        ball[BALL_X], ball[BALL_Y] = position
        ball[BALL_VX], ball[BALL_VY] = velocity
        self.state.active[env] = True

    def launch(self, env: int, speed: float) -> None:
        """Put env ``env``'s ball on the plunger and fire it up the shooter lane at ``speed``."""
        self.launch_balls([env], [speed])

    def launch_balls(self, envs: Sequence[int], speeds: Sequence[float]) -> None:
        """:meth:`launch` for each of ``envs`` at its entry of ``speeds`` [m/s], at once."""
        envs = np.asarray(envs, dtype=np.intp)
        positions = []
        for env in envs:
            table = self.table_of(env)
            if table.plunger is None:
                raise ValueError(f"table {table.name!r} has no plunger")
            positions.append(table.plunger.position)
        speeds = np.asarray(speeds, dtype=np.float64)
        if not np.isfinite(speeds).all() or (np.abs(speeds) > MAX_PLACE_SPEED).any():
            raise ValueError(f"launch speeds must be finite and at most {MAX_PLACE_SPEED:g} m/s, "
                             f"got {speeds.tolist()}")  # fmt: skip
        balls = self.state.balls
        balls[envs] = 0.0
        balls[envs, BALL_X] = [x for x, _ in positions]
        balls[envs, BALL_Y] = [y for _, y in positions]
        balls[envs, BALL_VY] = speeds
        self.state.active[envs] = True

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
        buttons (its other elements may differ in number and kind)."""
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
            bad = np.flatnonzero(~np.isfinite(self.state.balls).all(axis=1)).tolist()
            raise FloatingPointError(f"the ball state of env(s) {bad} is no longer finite")

    def _advance(self, envs: np.ndarray | None = None) -> int:
        """One frame of physics on the state arrays of ``envs`` (a bool mask; None: all): the
        swept-collision kernel. Returns the number of envs whose ball state is no longer
        finite."""
        moving = self._everyone if envs is None else np.ascontiguousarray(envs, dtype=np.bool_)
        if moving.shape != (self.n_envs,):
            raise ValueError(f"envs must have shape ({self.n_envs},), got {moving.shape}")
        if self.tables.varied:
            geometries, settings = self.tables.kernel_arrays()
            args = (geometries, settings, self.state, self.scratch, moving)
        else:
            args = (self.geometry, self.settings, self.state, self.scratch, moving)
        return sum(self.threads.run(self._kernel(args), self.n_envs, *args))

    def _kernel(self, args: tuple) -> Callable[..., int]:
        """``step_world``'s (or ``step_tables``') compiled entry for these arrays' types."""
        if self._entry is None:
            step = step_tables if self.tables.varied else step_world
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
        """Step ``n_frames`` frames and return env ``env``'s ball centre after each, (n, 2)."""
        path = np.empty((n_frames, 2))
        for frame in range(n_frames):
            self.step(buttons)
            path[frame] = self.state.balls[env, [BALL_X, BALL_Y]]
        return path


__all__ = ["CONTACT_CAPACITY", "Contact", "World"]
