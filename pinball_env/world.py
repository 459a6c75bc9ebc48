"""A batch of balls on one table: the state arrays and the call into the world-step kernel.

``World`` owns the preallocated arrays the kernel writes in place. The single env is a World of
one, the vector env a World of N; both call :func:`pinball_env.physics.step_balls`.
"""

from dataclasses import dataclass

import numpy as np

from pinball_env.physics import step_balls
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
)
from pinball_env.table import Table

# Contacts logged per env and frame; more are counted but not logged. A frame of a ball
# rattling in a corner makes a few dozen; the cap bounds memory, not physics.
CONTACT_CAPACITY = 64


@dataclass(frozen=True)
class Contact:
    """One contact of a ball during a frame."""

    element: int  # global element id (segments, then circles)
    name: str  # element name from the table, e.g. "outline[2]" or "post1"
    time: float  # seconds since the start of the frame
    speed: float  # normal approach speed before the response [m/s]


class World:
    """``n_envs`` independent balls on the same table, stepped together.

    Attributes:
        balls: (n_envs, BALL_STATE_SIZE) float64 ball states (see ``physics.layout``).
        active: (n_envs,) bool, which balls are in play.
        contacts, contact_count: the contact log of the last frame.
    """

    def __init__(self, table: Table, n_envs: int = 1) -> None:
        if n_envs < 1:
            raise ValueError(f"n_envs must be >= 1, got {n_envs}")
        self.table = table
        self.packed = table.pack()
        self.n_envs = n_envs
        self.dt = 1.0 / table.simulation.frame_rate
        self.balls = np.zeros((n_envs, BALL_STATE_SIZE))
        self.active = np.zeros(n_envs, dtype=bool)
        self.contacts = np.zeros((n_envs, CONTACT_CAPACITY, CONTACT_SIZE))
        self.contact_count = np.zeros(n_envs, dtype=np.int64)
        for env in range(n_envs):
            self.place_ball(env, table.ball.start, table.ball.velocity)

    def place_ball(
        self, env: int, position: tuple[float, float], velocity: tuple[float, float] = (0.0, 0.0)
    ) -> None:
        """Put env ``env``'s ball in play at ``position`` [m] with ``velocity`` [m/s], no spin."""
        state = self.balls[env]
        state[:] = 0.0
        state[BALL_X], state[BALL_Y] = position
        state[BALL_VX], state[BALL_VY] = velocity
        self.active[env] = True

    def step(self) -> None:
        """Advance every active ball by one frame."""
        sim = self.table.simulation
        p = self.packed
        step_balls(
            self.balls,
            self.active,
            p.segments,
            p.segment_props,
            p.segment_one_sided,
            p.circles,
            p.circle_props,
            p.gravity,
            self.table.ball.radius,
            self.dt,
            sim.substeps,
            sim.max_passes,
            sim.skin,
            sim.resting_speed,
            self.contacts,
            self.contact_count,
        )

    def frame_contacts(self, env: int = 0) -> list[Contact]:
        """The logged contacts of env ``env`` in the last frame, in time order."""
        count = min(int(self.contact_count[env]), CONTACT_CAPACITY)
        rows = self.contacts[env, :count]
        return [
            Contact(
                element=int(row[CONTACT_ELEMENT]),
                name=self.packed.element_names[int(row[CONTACT_ELEMENT])],
                time=float(row[CONTACT_TIME]),
                speed=float(row[CONTACT_SPEED]),
            )
            for row in rows
        ]

    def trace(self, n_frames: int, env: int = 0) -> np.ndarray:
        """Step ``n_frames`` frames and return env ``env``'s ball centre after each, (n, 2)."""
        path = np.empty((n_frames, 2))
        for frame in range(n_frames):
            self.step()
            path[frame] = self.balls[env, [BALL_X, BALL_Y]]
        return path
