"""A batch of balls on one table: the kernel's arrays and the call into the world step.

``World`` owns the preallocated arrays the kernel writes in place (built by
:func:`~pinball_env.physics.make_state` and :func:`~pinball_env.physics.make_scratch` from the
packed table). The single env is a World of one; a vector env is a World of N calling the same
kernel, :func:`~pinball_env.physics.step_world`. Physics backends swap :meth:`World._advance`.
"""

import math
from collections.abc import Callable
from dataclasses import dataclass

import numba
import numpy as np

from pinball_env.parallel import EnvThreads
from pinball_env.physics import CONTACT_CAPACITY, make_scratch, make_state, step_world
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


class World:
    """``n_envs`` independent balls and flipper sets on the same table, stepped together.

    Attributes:
        table: the validated table.
        geometry, settings: the table as the kernel sees it (``table.pack()``,
            ``table.pack_settings()``).
        state: the kernel's per-env arrays (``physics.State``): balls, active, flipper angles
            and angular velocities, flipper commands, the contact log and the hit counts.
        scratch: the kernel's per-env work arrays.
        num_threads: threads that share the envs of a frame (the kernel releases the GIL; the
            results are bitwise the same for any count).
    """

    def __init__(self, table: Table, n_envs: int = 1, num_threads: int = 1) -> None:
        self.threads = EnvThreads(num_threads)
        self._entry: Callable[..., int] | None = None
        self.table = table
        self.geometry = table.pack()
        self.settings = table.pack_settings()
        self.state = make_state(self.geometry, n_envs)
        self.scratch = make_scratch(self.geometry, self.settings, n_envs)
        # Column of the buttons array that drives each flipper.
        self._flipper_buttons = np.array(table.flipper_buttons, dtype=np.int64)
        for env in range(n_envs):
            self.rest_flippers(env)
            self.place_ball(env, table.ball.start, table.ball.velocity)

    @property
    def n_envs(self) -> int:
        return self.state.balls.shape[0]

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
        plunger = self.table.plunger
        if plunger is None:
            raise ValueError(f"table {self.table.name!r} has no plunger")
        self.place_ball(env, plunger.position, (0.0, speed))

    def rest_flippers(self, env: int) -> None:
        """Put env ``env``'s flippers at rest against their lower stops, released."""
        self.state.flipper_angle[env] = self.geometry.flippers[:, FLIPPER_REST_ANGLE]
        self.state.flipper_omega[env] = 0.0
        self.state.flipper_command[env] = False

    def step(self, buttons: np.ndarray | None = None) -> None:
        """Advance every env by one frame.

        Args:
            buttons: (n_envs, len(BUTTONS)) bool, the flipper buttons (left, right) held during
                the frame; None keeps the previous commands.
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
            self.state.flipper_command[:] = pressed[:, self._flipper_buttons]
        if self._advance():
            bad = np.flatnonzero(~np.isfinite(self.state.balls).all(axis=1)).tolist()
            raise FloatingPointError(f"the ball state of env(s) {bad} is no longer finite")

    def _advance(self) -> int:
        """One frame of physics on the state arrays: the swept-collision kernel. Returns the
        number of envs whose ball state is no longer finite."""
        args = (self.geometry, self.settings, self.state, self.scratch)
        kernel = self._kernel(args)
        if self.threads.num_threads == 1:
            return kernel(*args, 0, self.n_envs)
        return sum(self.threads.run(kernel, self.n_envs, *args))

    def _kernel(self, args: tuple) -> Callable[..., int]:
        """``step_world``'s compiled entry for these arrays' types. Calling it skips numba's
        dispatch, which infers the types of the 26 arrays on every call (about 3.5 us, as long
        as the kernel takes for a ball)."""
        if self._entry is None:
            step_world(*args, 0, 0)  # compiles (or loads) the kernel for these types; no env
            overloads = getattr(step_world, "overloads", None)  # None: NUMBA_DISABLE_JIT
            if overloads is None:
                self._entry = step_world
            else:
                signature = tuple(numba.typeof(a) for a in (*args, 0, 0))
                self._entry = overloads[signature].entry_point
        return self._entry

    def __getstate__(self) -> dict:
        state = self.__dict__.copy()
        state["_entry"] = None  # a compiled function cannot be pickled; a copy finds its own
        return state

    def frame_points(self) -> np.ndarray:
        """Points scored by each env in the last frame, (n_envs,) int64."""
        return self.state.hits @ self.table.element_scores

    def frame_contacts(self, env: int = 0) -> list[Contact]:
        """The logged contacts and sensor crossings of env ``env`` in the last frame."""
        count = min(int(self.state.contact_count[env]), CONTACT_CAPACITY)
        names = self.table.element_names
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
