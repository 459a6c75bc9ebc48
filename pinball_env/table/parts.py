"""The parts of a table: frozen dataclasses for its elements (walls, posts, flippers, sensors,
targets, the multiball's saucers and locks) and its sections (materials, the ball, the plunger,
the cabinet and tilt, the trough, the simulation's settings), and the polygon helpers.

:class:`~pinball_env.table.model.Table` holds them; :mod:`pinball_env.table.kinds` declares,
per element kind, its key, its fields, its element ids and its drawing. Lengths are in metres,
times in seconds; only the slope and the flipper angles are in degrees, as written in the files.
The table frame has its origin at the bottom-left corner, x to the right and y up the table.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass

from pinball_env.physics import flipper_distance

# The flipper buttons, in the order of the columns of a buttons array (and of the bits of a
# discrete action, see ``pinball_env.game``).
BUTTONS = ("left", "right")


@dataclass(frozen=True)
class Material:
    """Surface properties shared by walls, posts and flippers."""

    name: str
    restitution: float  # coefficient of restitution of the normal velocity [-]
    friction: float  # Coulomb friction coefficient ball/surface [-]


@dataclass(frozen=True)
class Wall:
    """A polyline of straight segments."""

    name: str
    points: tuple[tuple[float, float], ...]
    material: str
    closed: bool = False  # adds the segment last point -> first point
    one_sided: bool = False  # only stops a ball coming from the left of P0 -> P1
    kick: float = 0.0  # speed added along the normal on every impact [m/s] (slingshots)
    score: int = 0  # points per hit [-]

    def segments(self) -> tuple[tuple[float, float, float, float], ...]:
        """Segments (x0, y0, x1, y1) in order, the closing one last."""
        ends = self.points + self.points[:1] if self.closed else self.points
        return tuple((*p, *q) for p, q in itertools.pairwise(ends))


@dataclass(frozen=True)
class Post:
    """A fixed circle: post or pop bumper."""

    name: str
    center: tuple[float, float]
    radius: float
    material: str
    kick: float = 0.0  # speed added along the normal on every impact [m/s] (pop bumpers)
    score: int = 0  # points per hit [-]


@dataclass(frozen=True)
class Flipper:
    """A flipper: a tapered capsule turning about its pivot between two stops.

    The base circle (``base_radius``) is centred on the pivot, the tip circle (``tip_radius``)
    ``length`` away along the flipper's angle; their common tangents join them. Angles are kept in
    degrees as written in the file, counter-clockwise from +x.
    """

    name: str
    pivot: tuple[float, float]  # centre of rotation and of the base circle [m]
    length: float  # pivot to tip-circle centre [m]
    base_radius: float  # radius of the circle around the pivot [m]
    tip_radius: float  # radius of the circle at the tip [m]
    rest_angle: float  # direction pivot -> tip when released [deg]
    up_angle: float  # direction pivot -> tip when energised [deg]
    stroke_time: float  # time to swing from rest to up [s]
    return_time: float  # time to swing from up back to rest [s]
    material: str  # name of a material [-]
    button: str  # action bit that energises it: "left" or "right" [-]
    score: int = 0  # points per hit [-]

    @property
    def button_index(self) -> int:
        """Column of the flipper's button in a buttons array (see :data:`BUTTONS`)."""
        return BUTTONS.index(self.button)

    def distance(self, point: tuple[float, float], angle_deg: float) -> float:
        """Signed distance from ``point`` to the flipper's surface, turned to ``angle_deg``
        (negative inside), by the kernel's own ``flipper_distance``."""
        distance, _, _ = flipper_distance(
            point[0], point[1], *self.pivot, self.length, self.base_radius, self.tip_radius,
            math.radians(angle_deg),
        )  # fmt: skip
        return float(distance)

    @property
    def swing(self) -> float:
        """Angle swept between the two stops [rad]."""
        return math.radians(abs(self.up_angle - self.rest_angle))

    @property
    def up_speed(self) -> float:
        """Angular speed of the upstroke [rad/s]."""
        return self.swing / self.stroke_time

    @property
    def down_speed(self) -> float:
        """Angular speed of the return [rad/s]."""
        return self.swing / self.return_time


class _Line:
    """An element on a straight line between two ``points`` (sensors, targets, spinners,
    kickbacks)."""

    points: tuple[tuple[float, float], tuple[float, float]]

    @property
    def segment(self) -> tuple[float, float, float, float]:
        """The line as (x0, y0, x1, y1) [m]."""
        return (*self.points[0], *self.points[1])


@dataclass(frozen=True)
class Sensor(_Line):
    """A line the ball rolls over (rollover, drain); a crossing of the ball's centre is an event."""

    name: str
    points: tuple[tuple[float, float], tuple[float, float]]  # the two ends [m]
    drain: bool = False  # a crossing takes the ball out of play [-]
    score: int = 0  # points per crossing [-]


@dataclass(frozen=True)
class StandupTarget(_Line):
    """A scoring face that stays: a two-sided segment that counts every hit."""

    name: str
    points: tuple[tuple[float, float], tuple[float, float]]  # its two ends [m]
    material: str
    score: int = 0  # points per hit [-]

    def as_wall(self) -> Wall:
        return Wall(self.name, self.points, self.material)


@dataclass(frozen=True)
class DropTarget(_Line):
    """One target of a bank: a two-sided segment that stops the ball while up and drops when
    hit (see ``physics.targets``)."""

    name: str
    points: tuple[tuple[float, float], tuple[float, float]]  # its two ends [m]
    score: int = 0  # points per hit (the hit that drops it) [-]


@dataclass(frozen=True)
class DropBank:
    """A bank of drop targets: once all are down it rises again ``reset_time`` later (never
    onto the ball: it waits for the ball to leave)."""

    name: str
    material: str  # of its targets' faces [-]
    targets: tuple[DropTarget, ...]
    reset_time: float = 1.0  # [s] after the last target fell

    def walls(self) -> tuple[Wall, ...]:
        """Its targets as walls (all standing), for the checks of a table's geometry."""
        return tuple(Wall(t.name, t.points, self.material) for t in self.targets)


@dataclass(frozen=True)
class Spinner(_Line):
    """A flap across a lane that the ball passes through, spinning it (``physics.targets``);
    each revolution is a hit."""

    name: str
    points: tuple[tuple[float, float], tuple[float, float]]  # the flap's line across the lane [m]
    radius: float = 0.015  # flap radius [m]: a ball at normal speed v spins it at v / radius
    damping: float = 0.5  # viscous decay of the spin [1/s]
    friction: float = 20.0  # the bearing's constant deceleration [rad/s^2]
    score: int = 0  # points per revolution [-]


@dataclass(frozen=True)
class Kickback(_Line):
    """A kicker at the bottom of an outlane: a ball crossing its line against ``kick`` is a hit,
    and while the kickback is lit (the rules light it) the ball leaves at ``kick`` and the
    kickback goes dark."""

    name: str
    points: tuple[tuple[float, float], tuple[float, float]]  # its line across the outlane [m]
    kick: tuple[float, float]  # the velocity it gives the ball [m/s]
    lit: bool = False  # lit at the start of a game [-]
    score: int = 0  # points per hit [-]

    @property
    def lamp(self) -> tuple[float, float]:
        """Where its lamp is drawn: the middle of its line [m]."""
        (x0, y0), (x1, y1) = self.points
        return (0.5 * (x0 + x1), 0.5 * (y0 + y1))


@dataclass(frozen=True)
class Saucer:
    """A kickout hole: a ball whose centre comes within ``radius`` of ``center`` slower than
    ``capture_speed`` is captured (held at ``center``, immovable), scores, and after
    ``hold_time`` leaves at ``kick``. Played by ``sim.World`` (an element id after the
    kickbacks; :meth:`Table.pack` leaves it out)."""

    name: str
    center: tuple[float, float]  # where a captured ball rests [m]
    kick: tuple[float, float]  # the velocity the ball leaves with [m/s]
    radius: float = 0.02  # capture radius about the centre [m]
    capture_speed: float = 0.5  # a slower ball within the radius is captured [m/s]
    hold_time: float = 1.0  # how long it holds the ball [s]
    score: int = 0  # points per capture [-]


@dataclass(frozen=True)
class Lock:
    """A ball lock: a ball whose centre comes within ``radius`` of the next free slot slower
    than ``capture_speed`` is held there (immovable) until a rule releases the lock's balls,
    which leave their slots at ``kick``. Played by ``sim.World`` (an element id after the
    saucers; :meth:`Table.pack` leaves it out)."""

    name: str
    slots: tuple[tuple[float, float], ...]  # where held balls rest, in fill order [m]
    kick: tuple[float, float]  # the velocity a released ball leaves with [m/s]
    radius: float | None = None  # capture radius about the next free slot; None: the ball's [m]
    capture_speed: float = 1.0  # a slower ball within the radius is held [m/s]
    score: int = 0  # points per ball locked [-]

    def capture_radius(self, ball_radius: float) -> float:
        """The capture radius [m]: ``radius``, or the ball's where none is set."""
        return ball_radius if self.radius is None else self.radius


@dataclass(frozen=True)
class AutoPlunger:
    """The machine's plunger that launches the extra balls of a multiball from the plunger's
    position, straight up the table."""

    speed: tuple[float, float]  # launch speed range (min, max) [m/s]


@dataclass(frozen=True)
class Trough:
    """The balls the machine holds (those not in play wait in the trough and are fed to the
    shooter lane), and the auto-plunger that launches extra balls in a multiball. ``sim.World``
    holds ``balls`` ball slots per env; ``game.multiball`` serves them (a ball drains back to
    the trough; the auto-plunger launches ``add_balls``)."""

    balls: int = 1  # balls in the machine [-]
    auto_plunger: AutoPlunger | None = None


@dataclass(frozen=True)
class BallSave:
    """A ball that drains within ``time`` of leaving the plunger is served again, once per
    ball, without losing it."""

    time: float  # [s]


@dataclass(frozen=True)
class SkillShot:
    """A rollover lit when the player's plunger fires the ball: crossed while lit, it scores a
    bonus (a well-judged pull reaches it, a harder or softer one does not)."""

    sensor: str  # name of the rollover sensor [-]
    bonus: int  # points for crossing it while lit [-]
    time: float  # how long it stays lit after the plunger fires [s]


@dataclass(frozen=True)
class Plunger:
    """How a ball is put into play from the shooter lane.

    Without ``stroke`` (an automatic plunger) the machine fires every ball at a speed drawn from
    ``speed``. With ``stroke``, ``pull_time`` and ``pull_speed`` (the player's plunger, which
    comes with a :class:`Cabinet`) each ball waits on the plunger until the player pulls it back
    and lets go; ``speed`` is then the range of the ball search's launch of a ball left waiting.
    """

    position: tuple[float, float]  # ball centre at rest on the plunger [m]
    speed: tuple[float, float]  # launch speed range (min, max), straight up the table [m/s]
    stroke: float | None = None  # how far the plunger pulls back [m]
    pull_time: float | None = None  # time a steady pull takes over the whole stroke [s]
    # Launch speed at the shortest pull and at the whole stroke (linear between) [m/s].
    pull_speed: tuple[float, float] | None = None
    # A real plunger never fires twice alike (VPX's "scatter velocity"): the player's launch
    # speed varies by up to this much either way, drawn from the env's random stream [m/s].
    scatter: float = 0.0
    skill_shot: SkillShot | None = None

    @property
    def manual(self) -> bool:
        """Whether the player launches the balls (else the machine does)."""
        return self.stroke is not None

    def launch_speed(self, pull: float) -> float:
        """Launch speed [m/s] of the player's plunger let go at ``pull`` (0 < pull <= stroke)."""
        assert self.pull_speed is not None and self.stroke is not None  # (the player's plunger)
        low, high = self.pull_speed
        return low + (high - low) * pull / self.stroke


@dataclass(frozen=True)
class Cabinet:
    """The cabinet on its legs, a mass-spring-damper that a nudge shoves (see
    ``physics.cabinet``), and the shove a nudge gives it."""

    mass: float  # [kg]
    stiffness: float  # of the legs and floor [N/m]
    damping: float  # [N s/m]
    nudge_impulse: float  # impulse of one shove [N s]
    nudge_interval: float  # shortest time between two shoves [s]

    @property
    def natural_frequency(self) -> float:
        """Undamped natural frequency sqrt(k / M) [rad/s]."""
        return math.sqrt(self.stiffness / self.mass)

    @property
    def damping_ratio(self) -> float:
        """c / (2 sqrt(k M)) [-]."""
        return self.damping / (2.0 * math.sqrt(self.stiffness * self.mass))


@dataclass(frozen=True)
class Tilt:
    """The plumb bob, the ring around it and the tilt rules (see ``physics.cabinet``)."""

    bob_length: float  # pendulum length [m]
    bob_damping: float  # angular damping rate [1/s]
    ring_angle: float  # the bob's angle from vertical where it touches the ring [deg]
    ring_restitution: float  # of the bob's bounce off the ring [-]
    warnings: int  # touches of the ring that warn; the next one tilts [-]
    warning_time: float  # a warning is forgotten after this long without another touch [s]
    # Touches within this long of a warning are that warning (the bob still swinging from the
    # same shove: a game debounces its tilt switch); 0 counts every touch [s].
    settle_time: float = 0.0


@dataclass(frozen=True)
class Ball:
    """The ball and its initial state."""

    radius: float
    mass: float
    start: tuple[float, float]
    velocity: tuple[float, float] = (0.0, 0.0)
    # Of a ball's contact with another ball (needed where the trough holds several); None: a
    # table of one ball in play has no ball-ball contact [-].
    material: str | None = None


@dataclass(frozen=True)
class Simulation:
    """Time stepping and contact resolution settings."""

    frame_rate: float = 60.0  # control frames per second
    substeps: int = 10  # physics substeps per frame
    max_passes: int = 16  # contact passes per substep
    skin: float = 1e-6  # distance the ball is left off a surface after a contact [m]
    resting_speed: float = 0.02  # below this normal approach speed a contact is inelastic [m/s]


# --- polygons -------------------------------------------------------------------------------------


def enclosure(walls: tuple[Wall, ...]) -> Wall | None:
    """The closed wall enclosing the largest area (the table's outline), or None."""
    closed = [wall for wall in walls if wall.closed]
    return max(closed, key=lambda wall: abs(polygon_area(wall.points)), default=None)


def polygon_area(points: tuple[tuple[float, float], ...]) -> float:
    """Signed area of a closed polygon (shoelace formula)."""
    return 0.5 * sum(
        x0 * y1 - x1 * y0
        for (x0, y0), (x1, y1) in zip(points, points[1:] + points[:1], strict=True)
    )


def inside(point: tuple[float, float], polygon: tuple[tuple[float, float], ...]) -> bool:
    """Even-odd test: is ``point`` inside the closed ``polygon``?"""
    x, y = point
    result = False
    for (x0, y0), (x1, y1) in zip(polygon, polygon[1:] + polygon[:1], strict=True):
        if (y0 > y) != (y1 > y) and x < x0 + (y - y0) * (x1 - x0) / (y1 - y0):
            result = not result
    return result
