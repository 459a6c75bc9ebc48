"""A scripted policy: time each flip from the ball's predicted flight, catch and aim; on a
table with the cabinet (``Pinball-v1``) also plunge for the skill shot and nudge a ball bound
for an outlane.

It reads the ball's position and velocity from the env's ``info`` (and, with the cabinet, the
plunger's and the tilt's entries), so it plays with any observation type, and answers in the
env's action space. It is the bar a learned agent has to beat, so it plays as well as a simple
rule can.
"""

import functools
import itertools
import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from pinball_env.game import button_names, discrete_action
from pinball_env.physics.cabinet import cabinet_substep
from pinball_env.physics.columns import BOB_X, CABINET_SHOVE_X, CABINET_STATE_SIZE
from pinball_env.sim.world import World
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


def plunger_pulls(table: Table) -> list[float]:
    """The plunger's pull [m] after each whole frame of holding its button (the first entry:
    one frame), up to the whole stroke, summed frame by frame as the game does."""
    plunger = table.plunger
    assert plunger is not None and plunger.stroke is not None and plunger.pull_time is not None
    stroke = plunger.stroke
    step = stroke / (plunger.pull_time * table.simulation.frame_rate)
    pulls = [min(step, stroke)]
    while pulls[-1] < stroke:
        pulls.append(min(pulls[-1] + step, stroke))
    return pulls


# Launch speeds tried per pull across the plunger's scatter, to aim where most of them go.
SCATTER_SAMPLES = 9


@functools.lru_cache(maxsize=32)
def skill_shot_frames(table: Table) -> int:
    """Frames to hold the player's plunger for the skill shot: the whole-frame pull whose
    launches, at speeds across the plunger's scatter, cross the skill-shot rollover while it is
    lit most often (found by simulating them all; of equals, the middle one); the whole stroke
    if none does (or the table has no skill shot)."""
    pulls = plunger_pulls(table)
    plunger = table.plunger
    assert plunger is not None  # (plunger_pulls: the player's)
    skill = plunger.skill_shot
    if skill is None or skill.sensor not in table.element_names:
        return len(pulls)
    offsets = np.linspace(-plunger.scatter, plunger.scatter, SCATTER_SAMPLES)
    world = World(table, len(pulls) * len(offsets))
    for env, (pull, offset) in enumerate(itertools.product(pulls, offsets)):
        world.launch(env, plunger.launch_speed(pull) + offset)
    sensor = table.element_names.index(skill.sensor)
    made = np.zeros(world.n_envs, dtype=bool)
    for _ in range(max(1, round(skill.time * table.simulation.frame_rate))):
        world.step()
        made |= world.state.hits[:, sensor] > 0
    rates = made.reshape(len(pulls), len(offsets)).mean(axis=1)
    if rates.max() == 0:
        return len(pulls)
    best = np.flatnonzero(rates == rates.max())
    return int(best[len(best) // 2]) + 1  # the index of a pull, as frames held


@functools.lru_cache(maxsize=32)
def bob_response(table: Table, seconds: float = 8.0) -> np.ndarray:
    """The plumb bob's angle [rad] along a nudge's shove, substep by substep from the shove's
    (``seconds`` long), after one nudge of a cabinet at rest: the bob is a linear system while
    it stays inside the ring, so the swing of any nudges is the sum of these, shifted."""
    constants = table.pack().cabinet[0]
    h = 1.0 / (table.simulation.frame_rate * table.simulation.substeps)
    assert table.cabinet is not None
    state = np.zeros(CABINET_STATE_SIZE)
    state[CABINET_SHOVE_X] = table.cabinet.nudge_impulse
    angles = np.empty(round(seconds / h))
    for k in range(len(angles)):
        cabinet_substep(state, constants, h)
        angles[k] = state[BOB_X]
    return angles


@dataclass(frozen=True)
class Outlane:
    """An outlane (sensor ``*_outlane``) beside its guide post (``*_guide_post``): the ball
    falls into it between the post's apex and the outer wall."""

    post_x: float  # the guide post's centre [m]
    apex_y: float  # the ball's centre resting on the post's apex [m]
    wall_x: float  # the outer wall, the sensor's end away from the post [m]
    inward: float  # +1 if the post (and the inlane) is right of the wall, else -1

    @classmethod
    def of(cls, table: Table) -> "list[Outlane]":
        """The table's outlanes that have a guide post."""
        posts = {post.name: post for post in table.posts}
        lanes = []
        for sensor in table.sensors:
            post = posts.get(sensor.name.removesuffix("_outlane") + "_guide_post")
            if not sensor.name.endswith("_outlane") or post is None:
                continue
            px, py = post.center
            wall_x = max((x for x, _ in sensor.points), key=lambda x: abs(x - px))
            inward = 1.0 if px > wall_x else -1.0
            lanes.append(cls(px, py + post.radius + table.ball.radius, wall_x, inward))
        return lanes


def fall_time(height: float, vy: float, gy: float) -> float:
    """When [s] a ball ``height`` above a level, moving at ``vy`` (negative: down), reaches it
    under gravity ``gy`` (negative; inf for never)."""
    root = vy * vy - 2.0 * gy * height
    if root < 0.0 or math.sqrt(root) <= vy:
        return math.inf
    return 2.0 * height / (math.sqrt(root) - vy)


Ball = tuple[float, float, float, float]  # x, y [m], vx, vy [m/s]


def urgent_balls(info: Mapping[str, Any], gy: float) -> list[Ball]:
    """The balls in play of a game of several balls (``info``'s ``ball_positions``,
    ``ball_velocities``, ``balls_in_play``) as (x, y, vx, vy), the most urgent first: the
    soonest to fall to the flippers' level (the lowest, where they fall as fast); the game's
    ball (``ball_position``) where none is in play. (Python floats: the heuristic asks every
    step, of a few balls, for which numpy's calls would cost more than the arithmetic.)"""
    playing = np.asarray(info["balls_in_play"]).tolist()
    if not any(playing):
        return game_ball(info)
    positions = np.asarray(info["ball_positions"]).tolist()
    velocities = np.asarray(info["ball_velocities"]).tolist()
    balls = [(*p, *v) for p, v, live in zip(positions, velocities, playing, strict=True) if live]
    return sorted(balls, key=lambda ball: fall_time(max(ball[1], 0.0), ball[3], gy))  # stable


def game_ball(info: Mapping[str, Any]) -> list[Ball]:
    """The game's ball (``info``'s ``ball_position`` and ``ball_velocity``), alone."""
    (x, y), (vx, vy) = (np.asarray(info[key]).tolist()
                        for key in ("ball_position", "ball_velocity"))  # fmt: skip
    return [(x, y, vx, vy)]


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

    On a table with the cabinet, with ``plunge``, a ball waiting on the plunger is plunged with
    the pull that makes the skill shot (:func:`skill_shot_frames`). With ``nudge``, a ball bound
    for an outlane (:class:`Outlane`) is nudged: one falling down the outer wall, ``wall_gap``
    or less from it, is nudged inwards (the wall slams it towards the inlane; a nudge only has a
    lasting effect through a contact) when it is ``wall_lead`` seconds above the guide post's
    apex; one falling onto the post's apex from the outlane's side, less than ``post_reach``
    from it, is nudged outwards (the post moves under it). A nudge is given only if the plumb
    bob, predicted from its own nudges (:func:`bob_response`), stays inside ``tilt_margin`` of
    the tilt ring, and never while a tilt warning stands: it never warns, let alone tilts. Where
    one shove from rest already swings the bob onto the ring (``Pinball-v2``'s tight bob), every
    nudge is a warning: it nudges only while none stands, so that one warning at most ever
    stands and it never tilts.
    The nudge's rules come from the kernel's answers to each nudge, or none, of the balls near
    the outlanes in Pinball-v0 games (seeds 2000-2127), its numbers from Pinball-v1 games with
    the machine's plunges (seeds 0-255).
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
        plunge: bool = True,
        nudge: bool = True,
        wall_gap: float = 0.0035,
        wall_lead: tuple[float, float] = (0.03, 0.09),
        post_reach: float = 0.02,
        post_lead: float = 0.06,
        tilt_margin: float = 0.8,
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
        self._before = list(self._held)  # (as they were before its last answer)
        # The cabinet's buttons (plunger, nudges), on a table with one.
        self.cabinet = table.has_cabinet
        self.plunge = plunge and self.cabinet
        self.nudge = nudge and self.cabinet
        self.wall_gap = wall_gap
        self.wall_lead = wall_lead
        self.post_reach = post_reach
        self.post_lead = post_lead
        self._shoves: list[tuple[int, float, float]] = []  # (frame, dx, dy) of its own nudges
        self._cabinet_buttons = len(button_names(cabinet=True)) - len(BUTTONS)
        if self.cabinet:
            self._prepare_cabinet(table, tilt_margin)

    def _prepare_cabinet(self, table: Table, tilt_margin: float) -> None:
        """What the plunge and the nudges need of a table with the cabinet: the skill shot's
        release, the outlanes, the bob's response to a shove and the tilt ring's margin."""
        assert table.tilt is not None and table.cabinet is not None
        rate = table.simulation.frame_rate
        pulls = plunger_pulls(table)
        self._release = pulls[skill_shot_frames(table) - 1] - 0.5 * pulls[0]
        self._outlanes = Outlane.of(table)
        self._bob = bob_response(table)
        ring = math.radians(table.tilt.ring_angle)
        self._ring = tilt_margin * ring
        # The kernel's bob stops at the ring: a response that reaches it is a touch.
        self._shove_warns = bool(np.abs(self._bob).max() >= ring * (1.0 - 1e-9))
        self._nudge_frames = max(1, round(table.cabinet.nudge_interval * rate))
        names = button_names(cabinet=True)
        self._nudge_buttons = {
            (-1.0, 0.0): names.index("nudge_left") - len(BUTTONS),
            (1.0, 0.0): names.index("nudge_right") - len(BUTTONS),
        }

    def reset(self) -> None:
        """Forget the last game: every flipper down, no nudges given."""
        self._held = [0] * len(self._held)
        self._before = list(self._held)
        self._shoves = []

    def fork(self) -> "HeuristicPolicy":
        """A copy that goes on from this one's state (its flippers held, its nudges given),
        apart from it (a planner's branches: ``players.search``)."""
        copy = object.__new__(HeuristicPolicy)
        copy.__dict__.update(self.__dict__)
        copy._held, copy._shoves = list(self._held), list(self._shoves)
        copy._before = list(self._before)
        return copy

    def played(self, action: int) -> None:
        """The game played the discrete ``action``, not its last answer (a learner's, whose
        states it labels: ``agents.distill``): its flippers' held counts follow the flipper
        buttons ``action`` held. (Its record of its own nudges stays its own.)"""
        for j, button in enumerate(self._buttons):
            self._held[j] = self._before[j] + 1 if int(action) >> button & 1 else 0

    def starts_flip(self, info: Mapping[str, Any]) -> bool:
        """Whether its action for ``info`` would send a resting flipper up (a flip begins),
        asked without moving its state on (a planner's moment to choose: ``players.search``)."""
        probe = self.fork()
        probe(info)
        return any(held == 0 < after for held, after in zip(self._held, probe._held, strict=True))

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
        ``velocity`` [m/s]; or, given (M, 2) arrays, for several balls, the most urgent first
        (:func:`urgent_balls`): a resting flipper flips for the first ball that calls for it, a
        raised one stays up for the first that is landing on it."""
        position, velocity = np.asarray(position, float), np.asarray(velocity, float)
        balls = [(float(p[0]), float(p[1]), float(v[0]), float(v[1]))
                 for p, v in zip(position.reshape(-1, 2), velocity.reshape(-1, 2),
                                 strict=True)]  # fmt: skip
        return np.array(self._press(balls), dtype=bool)

    def _press(self, balls: list[Ball]) -> list[bool]:
        """:meth:`buttons` of ``balls`` (x, y, vx, vy), the most urgent first."""
        pressed = [False] * len(BUTTONS)
        self._before = list(self._held)
        for j, held in enumerate(self._held):
            if held == 0:
                up = any(self._flip(j, *ball) for ball in balls)
            elif held < self.hold_frames:
                up = True
            else:
                up = (self.catch and held < self._max_hold
                      and any(self._keep(j, *ball) for ball in balls))  # fmt: skip
            self._held[j] = held + 1 if up else 0
            pressed[self._buttons[j]] |= up
        return pressed

    def cabinet_buttons(self, info: Mapping[str, Any]) -> np.ndarray:
        """The cabinet's buttons (plunger, nudge left, right, up) for the env state ``info``.

        It needs the env's cabinet entries (``ball_on_plunger``, ``plunger_pull``, ``frames``,
        ``tilt_warnings``, ``tilted``): without them it neither plunges (the machine fires a
        ball left waiting) nor nudges (it could not see a warning)."""
        return np.array(self._cabinet(info), dtype=bool)

    def _cabinet(self, info: Mapping[str, Any]) -> list[bool]:
        """:meth:`cabinet_buttons`, as a list."""
        pressed = [False] * self._cabinet_buttons
        waiting = bool(info.get("ball_on_plunger", False))
        if self.plunge and waiting:
            pressed[0] = float(info.get("plunger_pull", 0.0)) < self._release
        if not self.nudge or waiting or "frames" not in info or "tilt_warnings" not in info:
            return pressed
        frame = int(info["frames"])
        if self._shoves and frame < self._shoves[-1][0]:
            self._shoves = []  # a new game (without reset): the cabinet is at rest again
        if info["tilt_warnings"] or info.get("tilted", False):
            return pressed  # a warning stands (or its model of the bob is off): no nudge
        x, y = np.asarray(info["ball_position"]).tolist()
        vx, vy = np.asarray(info["ball_velocity"]).tolist()
        direction = self._outlane_nudge(x, y, vx, vy)
        if direction is not None and self._may_shove(frame, direction):
            self._shoves.append((frame, *direction))
            pressed[self._nudge_buttons[direction]] = True
        return pressed

    def _outlane_nudge(
        self, x: float, y: float, vx: float, vy: float
    ) -> tuple[float, float] | None:
        """The nudge's direction (table frame) that saves a ball at (x, y), (vx, vy) from an
        outlane, or None."""
        radius, gy = self.table.ball.radius, self.table.gravity_vector[1]
        for lane in self._outlanes:
            wall_gap = lane.inward * (x - lane.wall_x) - radius  # from the outer wall
            height = y - lane.apex_y
            if wall_gap < -radius or height < -radius:
                continue  # beyond the outer wall (the shooter lane), or past the post
            # When and where it falls past the apex's level (already there: now, here).
            t = fall_time(height, vy, gy) if height > 0.0 else 0.0
            offset = lane.inward * (lane.post_x - x - vx * t)  # to the outlane's side
            hugging = wall_gap < self.wall_gap and lane.inward * vx < 0.1 and vy < 0.0
            if hugging and self.wall_lead[0] <= t <= self.wall_lead[1]:
                if lane.inward * (lane.post_x - x) > 0.0:
                    return (lane.inward, 0.0)  # the wall slams it towards the inlane
            elif 0.0 < offset < self.post_reach and t <= self.post_lead:
                return (-lane.inward, 0.0)  # the post moves under it
        return None

    def _may_shove(self, frame: int, direction: tuple[float, float]) -> bool:
        """Whether a nudge now (at game frame ``frame``) shoves the cabinet and keeps the plumb
        bob inside the margin: its own nudges' swings, summed (the bob is linear inside the
        ring), over the response's length."""
        if self._shoves and frame - self._shoves[-1][0] < self._nudge_frames:
            return False  # the game would ignore it
        if self._shove_warns:
            return True  # a warning, taken only while none stands (see cabinet_buttons)
        substeps = self.table.simulation.substeps
        n = len(self._bob)
        self._shoves = [s for s in self._shoves if (frame - s[0]) * substeps < n]
        swing = np.zeros((2, n))
        for past, dx, dy in [*self._shoves, (frame, *direction)]:
            tail = self._bob[(frame - past) * substeps :]
            swing[0, : len(tail)] += dx * tail
            swing[1, : len(tail)] += dy * tail
        return bool(np.hypot(swing[0], swing[1]).max() < self._ring)

    def __call__(self, info: Mapping[str, Any]) -> int | np.ndarray:
        """The action for the env state described by ``info`` (from reset or step)."""
        if "balls_in_play" in info:  # several balls: those in play, the most urgent first
            balls = urgent_balls(info, self.table.gravity_vector[1])
        else:
            balls = game_ball(info)
        pressed = self._press(balls)
        if self.cabinet:
            pressed += self._cabinet(info)
        if self.action_type == "multibinary":
            return np.array(pressed, dtype=np.int8)
        return discrete_action(pressed)
