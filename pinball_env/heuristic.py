"""A scripted policy: time each flip from the ball's predicted flight, catch and aim.

It reads the ball's position and velocity from the env's ``info``, so it plays with any
observation type, and answers in the env's action space. It is the bar a learned agent has to
beat, so it plays as well as a simple rule can.
"""

import math
from collections.abc import Mapping
from typing import Any

import numpy as np

from pinball_env.game import discrete_action
from pinball_env.table import BUTTONS, Flipper, Table


class FlipperFace:
    """A flipper's upper face at one angle, for a ball of radius ``radius``.

    ``u`` runs from the pivot towards the tip, ``w`` away from the face on the side the flipper
    swings to; ``gap`` is how far the ball is from touching the face; ``gu``, ``gw`` are the
    table's gravity in these axes.
    """

    def __init__(
        self, flipper: Flipper, angle_deg: float, radius: float, gravity: tuple[float, float]
    ) -> None:
        angle = math.radians(angle_deg)
        side = 1.0 if flipper.up_angle > flipper.rest_angle else -1.0
        self.px, self.py = flipper.pivot
        self.ux, self.uy = math.cos(angle), math.sin(angle)
        self.wx, self.wy = -side * math.sin(angle), side * math.cos(angle)
        self.length = flipper.length
        self.base = flipper.base_radius + radius
        self.taper = (flipper.tip_radius - flipper.base_radius) / flipper.length
        self.end = flipper.length + flipper.tip_radius + radius  # the last u a ball can touch
        self.gu, self.gw = self.turn(*gravity)  # the table's gravity [m/s^2]

    def local(self, x: float, y: float) -> tuple[float, float]:
        """(u, w) of the table point (x, y) [m]."""
        dx, dy = x - self.px, y - self.py
        return self.ux * dx + self.uy * dy, self.wx * dx + self.wy * dy

    def turn(self, vx: float, vy: float) -> tuple[float, float]:
        """(u, w) components of the table vector (vx, vy)."""
        return self.ux * vx + self.uy * vy, self.wx * vx + self.wy * vy

    def gap(self, u: float, w: float) -> float:
        """Distance [m] between a ball centred at (u, w) and the face (about: the face as the
        flipper's centre line grown by its local half-thickness)."""
        return w - self.base - self.taper * min(max(u, 0.0), self.length)

    def over(self, u: float) -> bool:
        """Whether a ball at ``u`` is over the face (from the base circle to the tip)."""
        return -self.base < u <= self.end

    def time_to_touch(self, gap: float, vw: float) -> float:
        """When [s] a ball ``gap`` from the face, moving at ``vw`` towards it (negative), first
        touches it under the table's gravity (inf for never): the first root t of
        gap + vw t + gw t^2 / 2 = 0, written so that it holds for gw = 0 too."""
        root = vw * vw - 2.0 * self.gw * gap
        if root < 0.0 or math.sqrt(root) <= vw:
            return math.inf
        return 2.0 * gap / (math.sqrt(root) - vw)


class HeuristicPolicy:
    """Flip each flipper just before the ball reaches it; catch a falling ball and aim it.

    For each flipper, in the frame of its resting face: a ball predicted (ballistically, under
    the table's gravity) to touch the face within ``lead`` seconds, or falling within ``reach``
    metres of it (a slow ball: the flipper meets it higher up), is flipped at once, so that the
    stroke meets it; a ball rolling down the face is flipped when it reaches ``aim`` (a fraction
    of the flipper's length from the pivot), which sets where the shot goes. With ``catch``, a
    flipper stays up while a ball lands on its raised face, so that the ball rolls into the
    cradle; once it has settled the flipper drops, the ball rolls down it and is shot from the
    aim point. Otherwise a flip is held ``hold_frames`` frames (the stroke, 22 ms on the classic
    table, spans two frames) and released, so that the flipper is down and ready for the next
    ball.

    The defaults were tuned on the classic table (seeds 0-255 of Pinball-v0).

    Works for any table with flippers (mirrored ones, other gravity): each flipper's geometry
    and button are taken from the table.
    """

    def __init__(
        self,
        table: Table,
        action_type: str = "discrete",
        lead: float = 0.02,
        reach: float = 0.02,
        aim: float = 0.5,
        hold_frames: int = 2,
        catch: bool = True,
        settle_speed: float = 0.05,
    ) -> None:
        self.table = table
        self.action_type = action_type
        self.lead = lead
        self.reach = reach
        self.aim = aim
        self.hold_frames = hold_frames
        self.catch = catch
        self.settle_speed = settle_speed
        radius = table.ball.radius
        gravity = table.gravity_vector
        self._rest = [FlipperFace(f, f.rest_angle, radius, gravity) for f in table.flippers]
        self._up = [FlipperFace(f, f.up_angle, radius, gravity) for f in table.flippers]
        self._buttons = [f.button_index for f in table.flippers]
        # A ball within this of a face is touching it (rolling on it, or cradled).
        self._touch = 0.25 * radius
        # Holding a caught ball longer than this [frames] is not a catch but a stall.
        self._max_hold = round(3.0 * table.simulation.frame_rate)
        self._held = [0] * len(table.flippers)  # frames each flipper's button has been held

    def reset(self) -> None:
        """Forget the last game: every flipper down."""
        self._held = [0] * len(self._held)

    def _flip(self, j: int, x: float, y: float, vx: float, vy: float) -> bool:
        """Whether a resting flipper ``j`` should flip now at the ball (x, y), (vx, vy)."""
        face = self._rest[j]
        u, w = face.local(x, y)
        vu, vw = face.turn(vx, vy)
        gu = face.gu
        if not face.over(u) or w < 0.0:
            return False
        gap = face.gap(u, w)
        if gap <= self._touch and abs(vw) < 0.1:
            # Rolling down the face: shoot from the aim point, or before it runs off the tip.
            return u >= self.aim * face.length or u + vu * self.lead >= face.end - face.base
        # Falling onto it: flip if it is already close, or lands within the lead time.
        if vw < 0.0 and gap <= self.reach:
            return True
        t = face.time_to_touch(gap, vw)
        return t <= self.lead and face.over(u + vu * t + 0.5 * gu * t * t)

    def _keep(self, j: int, x: float, y: float, vx: float, vy: float) -> bool:
        """Whether raised flipper ``j`` should stay up: the ball is landing or rolling on its
        raised face and has not settled in the cradle."""
        face = self._up[j]
        u, w = face.local(x, y)
        if not face.over(u) or w < 0.0 or face.gap(u, w) > 4.0 * self._touch:
            return False
        return math.hypot(vx, vy) > self.settle_speed

    def buttons(self, position: np.ndarray, velocity: np.ndarray) -> np.ndarray:
        """The buttons (one per entry of ``BUTTONS``) for a ball at ``position`` [m] moving at
        ``velocity`` [m/s]."""
        x, y = float(position[0]), float(position[1])
        vx, vy = float(velocity[0]), float(velocity[1])
        pressed = np.zeros(len(BUTTONS), dtype=bool)
        for j, held in enumerate(self._held):
            if held == 0:
                up = self._flip(j, x, y, vx, vy)
            elif held < self.hold_frames:
                up = True
            else:
                up = self.catch and held < self._max_hold and self._keep(j, x, y, vx, vy)
            self._held[j] = held + 1 if up else 0
            pressed[self._buttons[j]] |= up
        return pressed

    def __call__(self, info: Mapping[str, Any]) -> int | np.ndarray:
        """The action for the env state described by ``info`` (from reset or step)."""
        pressed = self.buttons(info["ball_position"], info["ball_velocity"])
        if self.action_type == "multibinary":
            return pressed.astype(np.int8)
        return discrete_action(pressed)
