"""A batch of balls on one table: the state arrays and the call into the world-step kernel.

``World`` owns the preallocated arrays the kernel writes in place. The single env is a World of
one; a vector env (to come) is a World of N calling the same kernel,
:func:`~pinball_env.physics.step_world`.
"""

from dataclasses import dataclass

import numpy as np

from pinball_env.physics import Geometry, Settings, State, step_world
from pinball_env.physics.layout import (
    BALL_STATE_SIZE,
    BALL_VX,
    BALL_VY,
    BALL_X,
    BALL_Y,
    CONTACT_ELEMENT,
    CONTACT_SIZE,
    CONTACT_SPEED,
    CONTACT_TIME,
    FLIPPER_REST_ANGLE,
)
from pinball_env.physics.world import segment_bounds
from pinball_env.table import Table

# Contacts logged per env and frame; more are counted but not logged. A frame of a ball
# rattling in a corner makes a few dozen; the cap bounds memory, not physics.
CONTACT_CAPACITY = 64
# Flipper buttons, the columns of the ``buttons`` argument of :meth:`World.step`.
LEFT, RIGHT = 0, 1


@dataclass(frozen=True)
class Contact:
    """One contact (or sensor crossing) of a ball during a frame."""

    element: int  # global element id: segments, circles, flippers, sensors
    name: str  # element name from the table, e.g. "outline[2]" or "bumper_top"
    time: float  # seconds since the start of the frame
    speed: float  # normal approach speed before the response [m/s] (0 for sensors)


class World:
    """``n_envs`` independent games on the same table, stepped together.

    Attributes:
        state: the kernel's per-env arrays (``physics.State``): balls, active, flipper angles
            and angular velocities, flipper commands, the contact log and the hit counts.
        geometry, settings: the table as the kernel sees it.
    """

    def __init__(self, table: Table, n_envs: int = 1) -> None:
        if n_envs < 1:
            raise ValueError(f"n_envs must be >= 1, got {n_envs}")
        self.table = table
        self.packed = packed = table.pack()
        self.n_envs = n_envs
        self.geometry = Geometry(
            segments=packed.segments,
            segment_bounds=segment_bounds(packed.segments),
            segment_props=packed.segment_props,
            segment_one_sided=packed.segment_one_sided,
            circles=packed.circles,
            circle_props=packed.circle_props,
            flippers=packed.flippers,
            flipper_props=packed.flipper_props,
            sensors=packed.sensors,
            sensor_drain=packed.sensor_drain,
        )
        sim = table.simulation
        gravity_x, gravity_y = packed.gravity
        self.settings = Settings(
            gravity_x=gravity_x,
            gravity_y=gravity_y,
            radius=table.ball.radius,
            dt=1.0 / sim.frame_rate,
            substeps=sim.substeps,
            max_passes=sim.max_passes,
            skin=sim.skin,
            resting_speed=sim.resting_speed,
        )
        n_flippers = packed.flippers.shape[0]
        self.state = State(
            balls=np.zeros((n_envs, BALL_STATE_SIZE)),
            active=np.zeros(n_envs, dtype=bool),
            flipper_angle=np.zeros((n_envs, n_flippers)),
            flipper_omega=np.zeros((n_envs, n_flippers)),
            flipper_command=np.zeros((n_envs, n_flippers), dtype=bool),
            contacts=np.zeros((n_envs, CONTACT_CAPACITY, CONTACT_SIZE)),
            contact_count=np.zeros(n_envs, dtype=np.int64),
            hits=np.zeros((n_envs, len(packed.element_names)), dtype=np.int64),
        )
        # Column of the buttons array that drives each flipper.
        self._flipper_buttons = np.array(packed.flipper_buttons, dtype=np.int64)
        for env in range(n_envs):
            self.rest_flippers(env)
            self.place_ball(env, table.ball.start, table.ball.velocity)

    # Shorthands for the arrays used most.
    @property
    def balls(self) -> np.ndarray:
        return self.state.balls

    @property
    def active(self) -> np.ndarray:
        return self.state.active

    @property
    def dt(self) -> float:
        return self.settings.dt

    def place_ball(
        self, env: int, position: tuple[float, float], velocity: tuple[float, float] = (0.0, 0.0)
    ) -> None:
        """Put env ``env``'s ball in play at ``position`` [m] with ``velocity`` [m/s], no spin."""
        state = self.state.balls[env]
        state[:] = 0.0
        state[BALL_X], state[BALL_Y] = position
        state[BALL_VX], state[BALL_VY] = velocity
        self.state.active[env] = True

    def launch(self, env: int, speed: float) -> None:
        """Put env ``env``'s ball on the plunger and fire it up the shooter lane at ``speed``."""
        plunger = self.table.plunger
        if plunger is None:
            raise ValueError(f"table {self.table.name!r} has no plunger")
        self.place_ball(env, plunger.position, (0.0, speed))

    def rest_flippers(self, env: int) -> None:
        """Put env ``env``'s flippers at rest against their lower stops, released."""
        self.state.flipper_angle[env] = self.packed.flippers[:, FLIPPER_REST_ANGLE]
        self.state.flipper_omega[env] = 0.0
        self.state.flipper_command[env] = False

    def step(self, buttons: np.ndarray | None = None) -> None:
        """Advance every env by one frame.

        Args:
            buttons: (n_envs, 2) bool, the left and right flipper buttons held during the frame;
                None keeps the previous commands.
        """
        if buttons is not None:
            pressed = np.asarray(buttons)
            binary = pressed.dtype == np.bool_ or np.all((pressed == 0) | (pressed == 1))
            if pressed.shape != (self.n_envs, 2) or not binary:
                raise ValueError(
                    f"buttons must be ({self.n_envs}, 2) booleans (left, right per env), "
                    f"got {pressed.tolist()!r}"
                )
            self.state.flipper_command[:] = pressed[:, self._flipper_buttons]
        self._advance()

    def _advance(self) -> None:
        """One frame of physics on the state arrays: the swept-collision kernel."""
        step_world(self.geometry, self.settings, self.state)

    def frame_points(self) -> np.ndarray:
        """Points scored by each env in the last frame, (n_envs,) int64."""
        return self.state.hits @ self.packed.element_scores

    def frame_contacts(self, env: int = 0) -> list[Contact]:
        """The logged contacts and sensor crossings of env ``env`` in the last frame."""
        count = min(int(self.state.contact_count[env]), CONTACT_CAPACITY)
        return [
            Contact(
                element=int(row[CONTACT_ELEMENT]),
                name=self.packed.element_names[int(row[CONTACT_ELEMENT])],
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
