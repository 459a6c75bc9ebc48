"""A scripted policy: flip a flipper when the ball is falling within its reach, above it.

It reads the ball's position and velocity from the env's ``info``, so it plays with any
observation type, and answers in the env's action space.
"""

import math
from collections.abc import Mapping
from typing import Any

import numpy as np

from pinball_env.game import discrete_action
from pinball_env.table import BUTTONS, Table


class HeuristicPolicy:
    """Flip when the ball is within ``reach`` metres above a flipper's face and falling.

    A flip is held for ``hold_frames`` frames (the stroke takes 22 ms, under two frames at 60 Hz;
    holding longer keeps the flipper up while the ball leaves), then released so the flipper
    is ready again. Works for any table with flippers; each flipper's button is taken from the
    table.
    """

    def __init__(
        self,
        table: Table,
        action_type: str = "discrete",
        reach: float = 0.02,
        hold_frames: int = 4,
    ) -> None:
        self.table = table
        self.action_type = action_type
        self.reach = reach
        self.hold_frames = hold_frames
        self._hold = np.zeros(len(table.flippers), dtype=np.int64)

    def reset(self) -> None:
        self._hold[:] = 0

    def buttons(self, position: np.ndarray, velocity: np.ndarray) -> np.ndarray:
        """The buttons (one per entry of ``BUTTONS``) for a ball at ``position`` [m] moving at
        ``velocity`` [m/s]."""
        pressed = np.zeros(len(BUTTONS), dtype=bool)
        r = self.table.ball.radius
        for j, flipper in enumerate(self.table.flippers):
            rest = math.radians(flipper.rest_angle)
            up_side = 1.0 if flipper.up_angle > flipper.rest_angle else -1.0
            dx, dy = position[0] - flipper.pivot[0], position[1] - flipper.pivot[1]
            along = math.cos(rest) * dx + math.sin(rest) * dy
            above = (-math.sin(rest) * dx + math.cos(rest) * dy) * up_side
            within = 0.0 <= along <= flipper.length + flipper.tip_radius + r
            close = 0.0 < above <= flipper.base_radius + r + self.reach
            if within and close and velocity[1] < 0.0:
                self._hold[j] = self.hold_frames
            if self._hold[j] > 0:
                self._hold[j] -= 1
                pressed[flipper.button_index] = True
        return pressed

    def __call__(self, info: Mapping[str, Any]) -> int | np.ndarray:
        """The action for the env state described by ``info`` (from reset or step)."""
        pressed = self.buttons(info["ball_position"], info["ball_velocity"])
        if self.action_type == "multibinary":
            return pressed.astype(np.int8)
        return discrete_action(pressed)
