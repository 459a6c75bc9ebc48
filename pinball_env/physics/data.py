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

from typing import NamedTuple

import numpy as np
from numba import njit

from pinball_env.physics.columns import (
    BALL_STATE_SIZE,
    BOUND_NX,
    BOUND_NY,
    BOUND_OFFSET,
    BOUND_RADIUS,
    BOUND_SIZE,
    BOUND_X,
    BOUND_Y,
    CABINET_STATE_SIZE,
    CONTACT_ELEMENT,
    CONTACT_SIZE,
    CONTACT_SPEED,
    CONTACT_TIME,
    EVENT_SIZE,
    SPIN_STATE_SIZE,
    WORK_SIZE,
)

# Contacts logged per env and frame; more are counted but not logged. A frame of a ball rattling
# in a corner makes a few dozen; the cap bounds memory, not physics.
CONTACT_CAPACITY = 64


class Geometry(NamedTuple):
    """The static table as read-only arrays (see ``columns`` for the columns)."""

    segments: np.ndarray  # (S, 4) float64: x0, y0, x1, y1 [m]
    segment_bounds: np.ndarray  # (S, BOUND_SIZE): from segment_bounds(segments)
    segment_props: np.ndarray  # (S, PROP_SIZE) float64
    segment_one_sided: np.ndarray  # (S,) bool
    circles: np.ndarray  # (C, 3) float64: x, y, radius [m]
    circle_props: np.ndarray  # (C, PROP_SIZE) float64
    flippers: np.ndarray  # (F, FLIPPER_SIZE) float64
    flipper_props: np.ndarray  # (F, PROP_SIZE) float64 (kick 0)
    sensors: np.ndarray  # (K, 4) float64: x0, y0, x1, y1 [m]
    sensor_drain: np.ndarray  # (K,) bool
    # The cabinet's constants, (1, CABINET_SIZE) float64 (see ``physics.cabinet``), or
    # (0, CABINET_SIZE) for a table without a cabinet: then nothing moves it, and the ball feels
    # gravity alone.
    cabinet: np.ndarray
    # Targets and their kin (see ``physics.targets``), each with 0 rows on a table without.
    drop_targets: np.ndarray  # (T, 4) float64: x0, y0, x1, y1 [m], two-sided while up
    drop_target_bounds: np.ndarray  # (T, BOUND_SIZE): segment_bounds(drop_targets)
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


class State(NamedTuple):
    """Per-env state, updated in place by the world step; the first axis is the env.

    The balls are slots: M per env (M = 1 on a table of one ball), the second axis of
    ``balls``, ``active`` and ``held``. A slot keeps its row when its ball drains (out of play)."""

    balls: np.ndarray  # (N, M, BALL_STATE_SIZE) float64
    active: np.ndarray  # (N, M) bool: the ball is in play; cleared when it drains
    held: np.ndarray  # (N, M) bool, input: held in a lock or saucer (fixed, of infinite mass)
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
    # The candidate set of each ball slot (see ``physics.near``): the elements it can reach soon.
    near: np.ndarray  # (N, M, S) int64: walls', posts' ids; flippers', targets', sensors' indexes
    near_ends: np.ndarray  # (N, M, 4) int64: where each of those groups ends in the row of near
    near_zone: np.ndarray  # (N, M, 3) float64: the zone's centre and radius [m] (radius < 0: none)
    # The several-ball kernel's (``physics.multiball``): per ball slot, its cached earliest
    # element contact and its bookkeeping over a substep (columns ``EV_*`` and ``W_*``).
    events: np.ndarray  # (N, M, EVENT_SIZE) float64
    work: np.ndarray  # (N, M, WORK_SIZE) float64
    dropped: np.ndarray  # (N, T) bool: drop targets hit in this substep (they drop at its end)
    passes: np.ndarray  # (N,) int64: the event passes of the env's last frame (for the tests)


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


@njit(cache=True, inline="always")
def log_contact(state, env, element, time, speed):
    """Append a contact to env's log (counting it even when the log is full)."""
    row = state.contact_count[env]
    if row < state.contacts.shape[1]:
        state.contacts[env, row, CONTACT_ELEMENT] = element
        state.contacts[env, row, CONTACT_TIME] = time
        state.contacts[env, row, CONTACT_SPEED] = speed
    state.contact_count[env] = row + 1


def segment_bounds(segments: np.ndarray) -> np.ndarray:
    """Bounds of every segment, (S, BOUND_SIZE): its bounding circle (centre and half its
    length) and its line (unit normal rot+90(P1 - P0) and offset; zero for a point)."""
    segments = np.asarray(segments, dtype=np.float64).reshape(-1, 4)
    bounds = np.zeros((segments.shape[0], BOUND_SIZE))
    ex, ey = segments[:, 2] - segments[:, 0], segments[:, 3] - segments[:, 1]
    length = np.hypot(ex, ey)
    bounds[:, BOUND_X] = 0.5 * (segments[:, 0] + segments[:, 2])
    bounds[:, BOUND_Y] = 0.5 * (segments[:, 1] + segments[:, 3])
    bounds[:, BOUND_RADIUS] = 0.5 * length
    safe = np.where(length > 0.0, length, 1.0)
    bounds[:, BOUND_NX] = np.where(length > 0.0, -ey / safe, 0.0)
    bounds[:, BOUND_NY] = np.where(length > 0.0, ex / safe, 0.0)
    bounds[:, BOUND_OFFSET] = (
        bounds[:, BOUND_NX] * segments[:, 0] + bounds[:, BOUND_NY] * segments[:, 1]
    )
    return bounds


def make_state(
    geometry: Geometry, n_envs: int, n_balls: int = 1, contact_capacity: int = CONTACT_CAPACITY
) -> State:
    """A zeroed :class:`State` for ``n_envs`` envs of ``n_balls`` ball slots on ``geometry``: no
    ball in play, none held, flippers at angle 0 and released (``World`` then puts them at
    rest), drop targets up, spinners still, kickbacks dark."""
    if n_envs < 1 or n_balls < 1:
        raise ValueError(f"n_envs and n_balls must be >= 1, got {n_envs}, {n_balls}")
    n_flippers = geometry.flippers.shape[0]
    return State(
        balls=np.zeros((n_envs, n_balls, BALL_STATE_SIZE)),
        active=np.zeros((n_envs, n_balls), dtype=np.bool_),
        held=np.zeros((n_envs, n_balls), dtype=np.bool_),
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


def make_scratch(geometry: Geometry, settings: Settings, n_envs: int, n_balls: int = 1) -> Scratch:
    """The work arrays of the world step for ``n_envs`` envs of ``n_balls`` ball slots."""
    flippers = (n_envs, geometry.flippers.shape[0])
    slots = (n_envs, n_balls)
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
        near=np.zeros((*slots, near_size(geometry)), dtype=np.int64),
        near_ends=np.zeros((*slots, 4), dtype=np.int64),
        near_zone=np.full((*slots, 3), -1.0),
        events=np.zeros((*slots, EVENT_SIZE)),
        work=np.zeros((*slots, WORK_SIZE)),
        dropped=np.zeros((n_envs, geometry.drop_targets.shape[0]), dtype=np.bool_),
        passes=np.zeros(n_envs, dtype=np.int64),
    )


def near_size(geometry: Geometry) -> int:
    """The longest candidate set of a table: its solids, drop targets and sensors."""
    return int(first_spinner(geometry))
