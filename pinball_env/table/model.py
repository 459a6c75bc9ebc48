"""The table model: :class:`Table`, the validated table, and the table packed for the kernels.

A :class:`Table` is validated data (see :mod:`pinball_env.table.schema`, which builds it, and
:mod:`pinball_env.table.files`, which reads it from YAML) made of the frozen dataclasses of
:mod:`pinball_env.table.parts`. Lengths are in metres, times in seconds; only the slope and the
flipper angles are in degrees, as written in the files. The table frame has its origin at the
bottom-left corner, x to the right and y up the table.

:meth:`Table.pack` turns it into the kernel's :class:`~pinball_env.physics.Geometry`, and
:meth:`Table.pack_settings` into its :class:`~pinball_env.physics.Settings`. Element ids follow
the order of :mod:`pinball_env.table.kinds` (the kernel's: segments, circles, flippers, sensors,
drop targets, spinners, kickbacks): :attr:`Table.element_names` and :attr:`Table.element_scores`
are indexed by them, and :meth:`Table.element_ids` gives a kind's.

The multiball elements (:class:`Saucer`, :class:`Lock`, :class:`Trough`, and the ball-ball
``Ball.material``) are not in :meth:`Table.pack`: ``sim.World`` plays them (the trough's number
of balls, saucers and locks capture balls at the end of a frame), with the ball-ball material
packed by :meth:`Table.pack_ball_pair`. Saucers, then locks, have element ids after every
packed element (after the kickbacks), so no id of a table without them moves.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from typing import Any, Generic, TypeVar

import numpy as np

from pinball_env.physics import (
    Geometry,
    Settings,
    columns,
    segment_bounds,
)
from pinball_env.table.kinds import ID_ORDER, element_ids
from pinball_env.table.parts import (
    Ball,
    BallSave,
    Cabinet,
    DropBank,
    DropTarget,
    Flipper,
    Kickback,
    Lock,
    Material,
    Plunger,
    Post,
    Saucer,
    Sensor,
    Simulation,
    Spinner,
    StandupTarget,
    Tilt,
    Trough,
    Wall,
    enclosure,
)
from pinball_env.table.reachable import CELL, free_space, touches
from pinball_env.table.rules import RuleSet

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
        """Name of every element by global id, in the kinds' id order
        (:data:`~pinball_env.table.kinds.ID_ORDER`): the walls' segments (``"wall[i]"``), the
        stand-up targets, posts, flippers, sensors, drop targets, spinners and kickbacks, then
        the saucers and locks (not packed: ``sim.World`` counts their captures)."""
        return tuple(name for name, _ in self._ids)

    @cached
    def element_scores(self) -> np.ndarray:
        """Points per hit of every element by global id, (E,) int64, read-only."""
        return _frozen_array([points for _, points in self._ids], np.int64, (-1,))

    @property
    def _ids(self) -> Iterator[tuple[str, int]]:
        """(name, points per hit) of every element id, in order."""
        for kind in ID_ORDER:
            for element in getattr(self, kind.key):
                yield from kind.ids(element)

    def element_ids(self, key: str) -> range:
        """The element ids of the kind ``key`` (its ``Table`` field: ``"saucers"``, ...), a run
        of consecutive ids."""
        return self._id_ranges[key]

    @cached
    def _id_ranges(self) -> dict[str, range]:
        return element_ids({kind.key: getattr(self, kind.key) for kind in ID_ORDER})

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
