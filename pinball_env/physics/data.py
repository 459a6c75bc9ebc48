"""The kernel's data: the static table (``Geometry``), the simulation scalars (``Settings``), the
per-env state (``State``) and the per-env work arrays (``Scratch``), with the constructors that fix
their shapes and dtypes (as MuJoCo MJX's ``make_data`` does).

Every per-env array has the env as its first axis, so a single env is a batch of one and a vector
env steps N with the same kernel. Column meanings are in :mod:`pinball_env.physics.columns`.

Element ids are global and ordered: segments first, then circles, flippers, sensors, drop
targets, spinners and kickbacks, as
``Table.pack`` lays the arrays out and ``Table.element_names`` names them. The ``first_*``
functions give the offsets from the arrays; the kernel and the backends use them.
They are inlined into their callers (``inline="always"``): a compiled call that receives the
geometry tuple counts a reference to each of its arrays, which per contact costs more than the
arithmetic.
"""

import math
from typing import NamedTuple

import numpy as np
from numba import njit

from pinball_env.physics.columns import (
    BALL_STATE_SIZE,
    CABINET_STATE_SIZE,
    CONTACT_SIZE,
    SPIN_STATE_SIZE,
)

# Contacts logged per env and frame; more are counted but not logged. A frame of a ball rattling
# in a corner makes a few dozen; the cap bounds memory, not physics.
CONTACT_CAPACITY = 64
# Tables with fewer segments and circles than this skip the broad phase: on the 48 elements of
# the classic table the bounding-circle test of each is cheaper than walking a grid (measured).
MIN_GRID_ELEMENTS = 96


class Geometry(NamedTuple):
    """The static table as read-only arrays (see ``columns`` for the columns)."""

    segments: np.ndarray  # (S, 4) float64: x0, y0, x1, y1 [m]
    segment_bounds: np.ndarray  # (S, 3): bounding circles, from segment_bounds(segments)
    segment_props: np.ndarray  # (S, PROP_SIZE) float64
    segment_one_sided: np.ndarray  # (S,) bool
    circles: np.ndarray  # (C, 3) float64: x, y, radius [m]
    circle_props: np.ndarray  # (C, PROP_SIZE) float64
    flippers: np.ndarray  # (F, FLIPPER_SIZE) float64
    flipper_props: np.ndarray  # (F, PROP_SIZE) float64 (kick 0)
    sensors: np.ndarray  # (K, 4) float64: x0, y0, x1, y1 [m]
    sensor_drain: np.ndarray  # (K,) bool
    # The broad phase (see build_grid): for each grid cell the segments and circles whose
    # bounding box overlaps it, packed as [cell starts (cells + 1) | ids | first and last column
    # and row of each element (S + C, 4)], int64. The cell size and count are in Settings.
    grid: np.ndarray
    # The cabinet's constants, (1, CABINET_SIZE) float64 (see ``physics.cabinet``), or
    # (0, CABINET_SIZE) for a table without a cabinet: then nothing moves it, and the ball feels
    # gravity alone.
    cabinet: np.ndarray
    # Targets and their kin (see ``physics.targets``), each with 0 rows on a table without.
    drop_targets: np.ndarray  # (T, 4) float64: x0, y0, x1, y1 [m], two-sided while up
    drop_target_bounds: np.ndarray  # (T, 3): bounding circles (segment_bounds)
    drop_target_props: np.ndarray  # (T, PROP_SIZE) float64 (kick 0)
    drop_target_bank: np.ndarray  # (T,) int64: the bank each belongs to
    bank_reset: np.ndarray  # (B,) float64: a bank rises this long after its last target fell [s]
    spinners: np.ndarray  # (P, SPINNER_SIZE) float64
    kickbacks: np.ndarray  # (K, KICKBACK_SIZE) float64


class Settings(NamedTuple):
    """Scalars of the simulation."""

    gravity_x: float  # [m/s^2], in the playfield plane
    gravity_y: float
    radius: float  # ball radius [m]
    dt: float  # frame length [s]
    substeps: int  # fixed substeps per frame
    max_passes: int  # contact passes per substep
    skin: float  # distance left between ball and surface after a contact [m]
    resting_speed: float  # normal speed below which a contact is inelastic [m/s]
    grid_cell: float  # broad-phase cell size [m]
    grid_columns: int  # broad-phase cells across and up the playfield (1 x 1: no broad phase)
    grid_rows: int


class State(NamedTuple):
    """Per-env state, updated in place by ``step_world``; the first axis is the env."""

    balls: np.ndarray  # (N, BALL_STATE_SIZE) float64
    active: np.ndarray  # (N,) bool: the ball is in play; cleared when it drains
    flipper_angle: np.ndarray  # (N, F) float64 [rad]
    flipper_omega: np.ndarray  # (N, F) float64 [rad/s], at the end of the frame
    flipper_command: np.ndarray  # (N, F) bool, input: energised
    contacts: np.ndarray  # (N, capacity, CONTACT_SIZE) float64: log of the frame's contacts
    contact_count: np.ndarray  # (N,) int64: contacts of the frame (may exceed the capacity)
    hits: np.ndarray  # (N, E) int64: hits of the frame per element id (scoring events)
    cabinet: np.ndarray  # (N, CABINET_STATE_SIZE) float64: the cabinet and its plumb bob
    tilted: np.ndarray  # (N,) bool, input: the machine is tilted (kickers dead)
    targets_up: np.ndarray  # (N, T) bool: the drop target stands (and stops the ball)
    bank_clock: np.ndarray  # (N, B) float64: time since the bank's last target fell [s]
    spinners: np.ndarray  # (N, P, SPIN_STATE_SIZE) float64: each spinner's angle and spin
    kickback_lit: np.ndarray  # (N, K) bool: the kickback fires at the next ball over it


class Scratch(NamedTuple):
    """Work arrays of the world step, one row per env so that envs can be stepped in parallel."""

    targets: np.ndarray  # (N, F) float64: the stop each flipper moves to in this substep [rad]
    omegas: np.ndarray  # (N, F) float64: its angular velocity on the way [rad/s]
    stops: np.ndarray  # (N, F) float64: when it reaches the stop [s into the substep]
    angles: np.ndarray  # (N, F) float64: angles at the current pass [rad]
    pass_stops: np.ndarray  # (N, F) float64: stops counted from the current pass [s]
    held: np.ndarray  # (N, F) bool: flippers stopped for the rest of a substep (a wedged ball)
    crossings: np.ndarray  # (N, K) float64: sensor crossings of one move [fraction]
    hit_elements: np.ndarray  # (N, max_passes) int64: hits of one substep, committed at its end
    cabinet_dv: np.ndarray  # (N, substeps, 2) float64: the cabinet's velocity change per substep


@njit(cache=True, inline="always")
def first_circle(geometry):
    """Element id of the first circle (the segments come first)."""
    return geometry.segments.shape[0]


@njit(cache=True, inline="always")
def first_flipper(geometry):
    """Element id of the first flipper."""
    return geometry.segments.shape[0] + geometry.circles.shape[0]


@njit(cache=True, inline="always")
def first_sensor(geometry):
    """Element id of the first sensor: the solid elements (that the ball collides with) are the
    ids below it."""
    return first_flipper(geometry) + geometry.flippers.shape[0]


@njit(cache=True, inline="always")
def first_drop_target(geometry):
    """Element id of the first drop target (after the sensors)."""
    return first_sensor(geometry) + geometry.sensors.shape[0]


@njit(cache=True, inline="always")
def first_spinner(geometry):
    """Element id of the first spinner."""
    return first_drop_target(geometry) + geometry.drop_targets.shape[0]


@njit(cache=True, inline="always")
def first_kickback(geometry):
    """Element id of the first kickback."""
    return first_spinner(geometry) + geometry.spinners.shape[0]


@njit(cache=True, inline="always")
def element_count(geometry):
    """Number of elements of every kind."""
    return first_kickback(geometry) + geometry.kickbacks.shape[0]


def grid_layout(n_elements: int, width: float, height: float, radius: float) -> tuple:
    """``(cell, columns, rows)`` of the broad-phase grid of a table: cells about two balls wide,
    at least 16 across the narrower side; one cell (no broad phase) for fewer than
    MIN_GRID_ELEMENTS segments and circles."""
    if n_elements < MIN_GRID_ELEMENTS:
        return max(width, height), 1, 1
    cell = max(min(width, height) / 16.0, 2.0 * radius)
    return cell, max(1, math.ceil(width / cell)), max(1, math.ceil(height / cell))


def build_grid(
    segments: np.ndarray, circles: np.ndarray, cell: float, columns: int, rows: int
) -> np.ndarray:
    """The packed broad-phase grid (see :class:`Geometry`): each segment and circle is listed,
    in id order, in every cell its bounding box overlaps."""
    segments = np.asarray(segments, dtype=np.float64).reshape(-1, 4)
    circles = np.asarray(circles, dtype=np.float64).reshape(-1, 3)
    low = np.concatenate(
        [np.minimum(segments[:, :2], segments[:, 2:]), circles[:, :2] - circles[:, 2:]]
    )
    high = np.concatenate(
        [np.maximum(segments[:, :2], segments[:, 2:]), circles[:, :2] + circles[:, 2:]]
    )
    spans = np.empty((len(low), 4), dtype=np.int64)
    spans[:, 0] = np.clip(np.floor(low[:, 0] / cell), 0, columns - 1)
    spans[:, 1] = np.clip(np.floor(high[:, 0] / cell), 0, columns - 1)
    spans[:, 2] = np.clip(np.floor(low[:, 1] / cell), 0, rows - 1)
    spans[:, 3] = np.clip(np.floor(high[:, 1] / cell), 0, rows - 1)
    members: list[list[int]] = [[] for _ in range(columns * rows)]
    for element, (c0, c1, r0, r1) in enumerate(spans):
        for row in range(r0, r1 + 1):
            for column in range(c0, c1 + 1):
                members[row * columns + column].append(element)
    starts = np.cumsum([0] + [len(m) for m in members])
    items = [e for m in members for e in m]
    return np.concatenate([starts, np.array(items, dtype=np.int64), spans.ravel()]).astype(np.int64)


def segment_bounds(segments: np.ndarray) -> np.ndarray:
    """Bounding circle of every segment, (S, 3): centre x, y and radius (half the length)."""
    segments = np.asarray(segments, dtype=np.float64).reshape(-1, 4)
    bounds = np.empty((segments.shape[0], 3))
    bounds[:, 0] = 0.5 * (segments[:, 0] + segments[:, 2])
    bounds[:, 1] = 0.5 * (segments[:, 1] + segments[:, 3])
    bounds[:, 2] = 0.5 * np.hypot(segments[:, 2] - segments[:, 0], segments[:, 3] - segments[:, 1])
    return bounds


def make_state(geometry: Geometry, n_envs: int, contact_capacity: int = CONTACT_CAPACITY) -> State:
    """A zeroed :class:`State` for ``n_envs`` envs on ``geometry``: no ball in play, flippers at
    angle 0 and released (``World`` then puts them at rest), drop targets up, spinners still,
    kickbacks dark."""
    if n_envs < 1:
        raise ValueError(f"n_envs must be >= 1, got {n_envs}")
    n_flippers = geometry.flippers.shape[0]
    return State(
        balls=np.zeros((n_envs, BALL_STATE_SIZE)),
        active=np.zeros(n_envs, dtype=np.bool_),
        flipper_angle=np.zeros((n_envs, n_flippers)),
        flipper_omega=np.zeros((n_envs, n_flippers)),
        flipper_command=np.zeros((n_envs, n_flippers), dtype=np.bool_),
        contacts=np.zeros((n_envs, contact_capacity, CONTACT_SIZE)),
        contact_count=np.zeros(n_envs, dtype=np.int64),
        hits=np.zeros((n_envs, element_count(geometry)), dtype=np.int64),
        cabinet=np.zeros((n_envs, CABINET_STATE_SIZE)),
        tilted=np.zeros(n_envs, dtype=np.bool_),
        targets_up=np.ones((n_envs, geometry.drop_targets.shape[0]), dtype=np.bool_),
        bank_clock=np.zeros((n_envs, geometry.bank_reset.shape[0])),
        spinners=np.zeros((n_envs, geometry.spinners.shape[0], SPIN_STATE_SIZE)),
        kickback_lit=np.zeros((n_envs, geometry.kickbacks.shape[0]), dtype=np.bool_),
    )


def make_scratch(geometry: Geometry, settings: Settings, n_envs: int) -> Scratch:
    """The work arrays of ``step_world`` for ``n_envs`` envs."""
    flippers = (n_envs, geometry.flippers.shape[0])
    return Scratch(
        targets=np.zeros(flippers),
        omegas=np.zeros(flippers),
        stops=np.zeros(flippers),
        angles=np.zeros(flippers),
        pass_stops=np.zeros(flippers),
        held=np.zeros(flippers, dtype=np.bool_),
        crossings=np.zeros((n_envs, geometry.sensors.shape[0])),
        hit_elements=np.zeros((n_envs, settings.max_passes), dtype=np.int64),
        cabinet_dv=np.zeros((n_envs, settings.substeps, 2)),
    )
