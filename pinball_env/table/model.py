"""The table model: frozen dataclasses for every element, and the table packed for the kernels.

A :class:`Table` is validated data (see :mod:`pinball_env.table.schema`, which builds it, and
:mod:`pinball_env.table.files`, which reads it from YAML). Lengths are in metres, times in seconds;
only the slope and the flipper angles are in degrees, as written in the files. The table frame has
its origin at the bottom-left corner, x to the right and y up the table.

:meth:`Table.pack` turns it into the kernel's :class:`~pinball_env.physics.Geometry`, and
:meth:`Table.pack_settings` into its :class:`~pinball_env.physics.Settings`. Element ids follow
the kernel's order (segments, circles, flippers, sensors): :attr:`Table.element_names` and
:attr:`Table.element_scores` are indexed by them.

The multiball elements (:class:`Saucer`, :class:`Lock`, :class:`Trough`, and the ball-ball
``Ball.material``) are not in :meth:`Table.pack`: ``sim.World`` plays them (the trough's number
of balls, saucers and locks capture balls at the end of a frame), with the ball-ball material
packed by :meth:`Table.pack_ball_pair`. Saucers, then locks, have element ids after every
packed element (after the kickbacks), so no id of a table without them moves.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, Generic, TypeVar

import numpy as np

from pinball_env.physics import (
    Geometry,
    Settings,
    columns,
    flipper_distance,
    segment_bounds,
)
from pinball_env.table.reachable import CELL, free_space, touches
from pinball_env.table.rules import RuleSet

# The flipper buttons, in the order of the columns of a buttons array (and of the bits of a
# discrete action, see ``pinball_env.game``).
BUTTONS = ("left", "right")


Value = TypeVar("Value")


class cached(Generic[Value]):
    """``functools.cached_property`` without the lock Python 3.11 takes: one lock per property,
    shared by every table and held while the value is computed, so that a process forked while
    another thread computes one (a generated table checked in the background) waits on it for
    ever. Two threads may both compute a value; both compute the same, and one is kept."""

    def __init__(self, func: Callable[[Any], Value]) -> None:
        self.func = func
        self.__doc__ = func.__doc__
        self.name = func.__name__

    def __set_name__(self, owner: type, name: str) -> None:
        self.name = name

    def __get__(self, instance: Any, owner: type | None = None) -> Any:
        if instance is None:
            return self
        cache = instance.__dict__  # (a frozen dataclass's too: its __setattr__ is not called)
        if self.name not in cache:
            cache[self.name] = self.func(instance)
        return cache[self.name]


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


@dataclass(frozen=True)
class Table:
    """A validated table description."""

    name: str
    width: float  # playfield width [m]
    height: float  # playfield length, up the table [m]
    ball: Ball
    materials: tuple[Material, ...]
    walls: tuple[Wall, ...] = ()
    posts: tuple[Post, ...] = ()
    flippers: tuple[Flipper, ...] = ()
    sensors: tuple[Sensor, ...] = ()
    plunger: Plunger | None = None  # None: the ball is only ever placed at ball.start
    cabinet: Cabinet | None = None  # with tilt and a manual plunger: the whole cabinet
    tilt: Tilt | None = None
    # Targets and rules (see ``physics.targets`` and ``table.rules``).
    standup_targets: tuple[StandupTarget, ...] = ()
    drop_targets: tuple[DropBank, ...] = ()
    spinners: tuple[Spinner, ...] = ()
    kickbacks: tuple[Kickback, ...] = ()
    ball_save: BallSave | None = None
    rules: RuleSet | None = None
    slope_deg: float = 6.5  # inclination of the playfield [deg]
    gravity: float = 9.81  # [m/s^2]
    simulation: Simulation = Simulation()  # frozen, so sharing it is safe
    source: str = "<dict>"  # file the table was read from
    # Multiball (see ``Saucer``, ``Lock``, ``Trough``): played by ``sim.World``, not packed in
    # ``pack``. Last, so that a Table built by position keeps its meaning.
    saucers: tuple[Saucer, ...] = ()
    locks: tuple[Lock, ...] = ()
    trough: Trough | None = None  # None: one ball, as a trough of 1

    @cached
    def free_space(self) -> np.ndarray:
        """Grid of where a ball centre can get to in play from the plunger (or the ball's
        start), see :mod:`pinball_env.table.reachable`; computed on first use."""
        geometry = self.pack()
        start = self.plunger.position if self.plunger is not None else self.ball.start
        two_sided = geometry.segments[~geometry.segment_one_sided]
        drains = geometry.sensors[geometry.sensor_drain]
        return free_space(
            self.width, self.height, self.ball.radius, two_sided, geometry.circles,
            geometry.flippers, start, drains,
        )  # fmt: skip

    @cached
    def drain_reachable(self) -> bool:
        """Whether a ball in play can get to a drain (so that a game can end): some place it
        can reach (:attr:`free_space`) lies right beside a drain line."""
        geometry = self.pack()
        drains = geometry.sensors[geometry.sensor_drain]
        return bool(touches(self.free_space, drains, 2.5 * CELL, CELL))

    @property
    def solid_walls(self) -> tuple[Wall, ...]:
        """The walls, stand-up targets and drop targets (standing) as walls: everything a ball
        can meet along a segment."""
        targets = tuple(t.as_wall() for t in self.standup_targets)
        return self.walls + targets + tuple(w for bank in self.drop_targets for w in bank.walls())

    @property
    def drop_target_list(self) -> tuple[DropTarget, ...]:
        """Every bank's targets, in element-id order."""
        return tuple(t for bank in self.drop_targets for t in bank.targets)

    @property
    def has_targets(self) -> bool:
        """Whether the table has drop targets, spinners or kickbacks (per-env element state)."""
        return bool(self.drop_targets or self.spinners or self.kickbacks)

    @property
    def outline(self) -> Wall | None:
        """The closed wall enclosing the largest area, which keeps the ball in; None if none."""
        return enclosure(self.walls)

    @property
    def gravity_vector(self) -> tuple[float, float]:
        """Component of gravity in the playfield plane, pointing down the table [m/s^2]."""
        return (0.0, -self.gravity * math.sin(math.radians(self.slope_deg)))

    def material(self, name: str) -> Material:
        """The material called ``name``."""
        for material in self.materials:
            if material.name == name:
                return material
        raise KeyError(f"{self.source}: no material {name!r} in table {self.name!r}")

    @cached
    def element_names(self) -> tuple[str, ...]:
        """Name of every element by global id: segments (``"wall[i]"``, then the stand-up
        targets), circles, flippers, sensors, drop targets, spinners and kickbacks, then the
        saucers and locks (not packed: ``sim.World`` counts their captures)."""
        segments = [f"{wall.name}[{i}]" for wall in self.walls for i in range(len(wall.segments()))]
        return (*segments, *(e.name for e in self._named_elements))

    @cached
    def element_scores(self) -> np.ndarray:
        """Points per hit of every element by global id, (E,) int64, read-only."""
        segments = [wall.score for wall in self.walls for _ in wall.segments()]
        others = [e.score for e in self._named_elements]
        return _frozen_array(segments + others, np.int64, (-1,))

    @property
    def _named_elements(self) -> tuple[Any, ...]:
        """The elements after the walls' segments, in id order."""
        return (
            *self.standup_targets, *self.posts, *self.flippers, *self.sensors,
            *self.drop_target_list, *self.spinners, *self.kickbacks, *self.saucers, *self.locks,
        )  # fmt: skip

    @property
    def flipper_buttons(self) -> tuple[int, ...]:
        """The button column (see :data:`BUTTONS`) that drives each flipper."""
        return tuple(flipper.button_index for flipper in self.flippers)

    def pack(self) -> Geometry:
        """The kernel's read-only arrays for this table (see ``physics.Geometry``)."""
        segments, segment_props, one_sided = [], [], []
        for wall in self.walls:
            for segment in wall.segments():
                segments.append(segment)
                segment_props.append(self._props(wall.material, wall.kick))
                one_sided.append(wall.one_sided)
        for target in self.standup_targets:
            segments.append(target.segment)
            segment_props.append(self._props(target.material, 0.0))
            one_sided.append(False)
        segment_rows = _frozen_array(segments, np.float64, (-1, 4))
        props = (-1, columns.PROP_SIZE)
        circles = [(*post.center, post.radius) for post in self.posts]
        circle_props = [self._props(post.material, post.kick) for post in self.posts]
        flippers = [_flipper_row(flipper) for flipper in self.flippers]
        flipper_props = [self._props(flipper.material, 0.0) for flipper in self.flippers]
        return Geometry(
            segments=segment_rows,
            segment_bounds=_frozen_array(
                segment_bounds(segment_rows), np.float64, (-1, columns.BOUND_SIZE)
            ),
            segment_props=_frozen_array(segment_props, np.float64, props),
            segment_one_sided=_frozen_array(one_sided, np.bool_, (-1,)),
            circles=_frozen_array(circles, np.float64, (-1, 3)),
            circle_props=_frozen_array(circle_props, np.float64, props),
            flippers=_frozen_array(flippers, np.float64, (-1, columns.FLIPPER_SIZE)),
            flipper_props=_frozen_array(flipper_props, np.float64, props),
            sensors=_frozen_array([s.segment for s in self.sensors], np.float64, (-1, 4)),
            sensor_drain=_frozen_array([s.drain for s in self.sensors], np.bool_, (-1,)),
            cabinet=_frozen_array(self._cabinet_row(), np.float64, (-1, columns.CABINET_SIZE)),
            **self._pack_targets(),
        )

    def _pack_targets(self) -> dict[str, np.ndarray]:
        """The drop targets', spinners' and kickbacks' arrays of ``Geometry``."""
        targets = [t.segment for t in self.drop_target_list]
        props = [self._props(bank.material, 0.0) for bank in self.drop_targets
                 for _ in bank.targets]  # fmt: skip
        banks = [b for b, bank in enumerate(self.drop_targets) for _ in bank.targets]
        spinners = [
            [*s.segment, s.radius, s.damping, s.friction] for s in self.spinners
        ]  # columns SPINNER_*
        kickbacks = [[*k.segment, *k.kick] for k in self.kickbacks]  # columns KICKBACK_*
        return dict(
            drop_targets=_frozen_array(targets, np.float64, (-1, 4)),
            drop_target_bounds=_frozen_array(
                segment_bounds(targets), np.float64, (-1, columns.BOUND_SIZE)
            ),
            drop_target_props=_frozen_array(props, np.float64, (-1, columns.PROP_SIZE)),
            drop_target_bank=_frozen_array(banks, np.int64, (-1,)),
            bank_reset=_frozen_array([b.reset_time for b in self.drop_targets], np.float64, (-1,)),
            spinners=_frozen_array(spinners, np.float64, (-1, columns.SPINNER_SIZE)),
            kickbacks=_frozen_array(kickbacks, np.float64, (-1, columns.KICKBACK_SIZE)),
        )

    @property
    def has_cabinet(self) -> bool:
        """Whether the table has the whole cabinet: the player's plunger, the nudge, the tilt."""
        return self.cabinet is not None

    def _cabinet_row(self) -> list[list[float]]:
        """The cabinet's constants as the kernel's rows (columns ``CABINET_*``, ``BOB_*``)."""
        if self.cabinet is None:
            return []
        cabinet, tilt = self.cabinet, self.tilt
        assert tilt is not None  # (the whole cabinet)
        row = [0.0] * columns.CABINET_SIZE
        row[columns.CABINET_MASS] = cabinet.mass
        row[columns.CABINET_STIFFNESS] = cabinet.stiffness
        row[columns.CABINET_DAMPING] = cabinet.damping
        row[columns.BOB_LENGTH] = tilt.bob_length
        row[columns.BOB_DAMPING] = tilt.bob_damping
        row[columns.BOB_RING] = math.radians(tilt.ring_angle)
        row[columns.BOB_RESTITUTION] = tilt.ring_restitution
        row[columns.BOB_GRAVITY] = self.gravity
        return [row]

    def pack_settings(self) -> Settings:
        """The kernel's simulation scalars for this table."""
        sim = self.simulation
        gravity_x, gravity_y = self.gravity_vector
        return Settings(
            gravity_x=gravity_x,
            gravity_y=gravity_y,
            radius=self.ball.radius,
            dt=1.0 / sim.frame_rate,
            substeps=sim.substeps,
            max_passes=sim.max_passes,
            skin=sim.skin,
            resting_speed=sim.resting_speed,
        )

    @property
    def n_balls(self) -> int:
        """Ball slots per env: the trough's balls, 1 without a trough."""
        return 1 if self.trough is None else self.trough.balls

    def pack_ball_pair(self) -> np.ndarray:
        """The ball-ball material as a surface properties row (columns ``PROP_*``; the kick
        unused): ``ball.material``'s restitution and friction, 1 and 0 where it names none
        (a table of one ball has no ball-ball contact). Writable, a fresh copy."""
        row = np.zeros(columns.PROP_SIZE)
        row[columns.PROP_RESTITUTION] = 1.0
        if self.ball.material is not None:
            material = self.material(self.ball.material)
            row[columns.PROP_RESTITUTION] = material.restitution
            row[columns.PROP_FRICTION] = material.friction
        return row

    def _props(self, material: str, kick: float) -> list[float]:
        """A surface properties row (columns ``PROP_*``)."""
        row = [0.0] * columns.PROP_SIZE
        row[columns.PROP_RESTITUTION] = self.material(material).restitution
        row[columns.PROP_FRICTION] = self.material(material).friction
        row[columns.PROP_KICK] = kick
        return row


def _flipper_row(flipper: Flipper) -> list[float]:
    """A flipper as a row of the kernel's flipper array (columns ``FLIPPER_*``)."""
    row = [0.0] * columns.FLIPPER_SIZE
    row[columns.FLIPPER_PIVOT_X], row[columns.FLIPPER_PIVOT_Y] = flipper.pivot
    row[columns.FLIPPER_LENGTH] = flipper.length
    row[columns.FLIPPER_BASE_RADIUS] = flipper.base_radius
    row[columns.FLIPPER_TIP_RADIUS] = flipper.tip_radius
    row[columns.FLIPPER_REST_ANGLE] = math.radians(flipper.rest_angle)
    row[columns.FLIPPER_UP_ANGLE] = math.radians(flipper.up_angle)
    row[columns.FLIPPER_UP_SPEED] = flipper.up_speed
    row[columns.FLIPPER_DOWN_SPEED] = flipper.down_speed
    return row


def _frozen_array(rows: Any, dtype: type, shape: tuple[int, ...]) -> np.ndarray:
    array: np.ndarray = np.ascontiguousarray(np.asarray(rows, dtype=dtype).reshape(shape))
    array.flags.writeable = False
    return array


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
