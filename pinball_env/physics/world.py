"""The world step: advance a batch of balls (one per env) through the table by swept collision.

Every state array has a leading env axis, so the single env is a batch of one and a vector env
(to come) calls the very same kernel. Each frame of length ``dt`` is cut into fixed substeps. In
a substep the flippers follow their commands (kinematic: a constant angular speed towards the
stop the command selects), gravity updates the ball's velocity (semi-implicit Euler), then the
ball sweeps along its straight path and stops at the earliest contact over all walls, posts and
flippers (ties go to the lowest element id), responds, and sweeps the remaining time again. A
pass cap and a minimum-progress rule end the loop for a wedged ball: the rest of that substep is
dropped, never skipped over, so the ball can stall for an instant but cannot tunnel; a flipper
pushing a wedged ball stalls too, as a real coil does. Sensors (rollovers, the drain) are
crossed, not collided with: a crossing of the ball's centre is an event, and a drain crossing
takes the ball out of play.

Contact response (per unit mass, relative to the velocity of the surface, zero except on a
swinging flipper): the normal velocity is reflected with restitution ``e`` (``e = 0`` below
``resting_speed``, so a ball lying or rolling on a surface stays on it without jitter); friction
is a Coulomb impulse, at most ``mu`` times the normal impulse, that drives the slip of the
contact point towards zero, the ball being a solid sphere (I = 2/5 m r^2) whose spin about the
playfield normal is part of its state; kicking elements (bumpers, slingshots) then add ``kick``
along the normal. After a contact the ball is put ``skin`` off the surface.
"""

import math
from typing import NamedTuple

import numpy as np
from numba import njit

from pinball_env.physics.flipper import flipper_distance, sweep_flipper
from pinball_env.physics.layout import (
    BALL_SPIN,
    BALL_VX,
    BALL_VY,
    BALL_X,
    BALL_Y,
    CONTACT_ELEMENT,
    CONTACT_SPEED,
    CONTACT_TIME,
    FLIPPER_BASE_RADIUS,
    FLIPPER_DOWN_SPEED,
    FLIPPER_LENGTH,
    FLIPPER_PIVOT_X,
    FLIPPER_PIVOT_Y,
    FLIPPER_REST_ANGLE,
    FLIPPER_TIP_RADIUS,
    FLIPPER_UP_ANGLE,
    FLIPPER_UP_SPEED,
    PROP_FRICTION,
    PROP_KICK,
    PROP_RESTITUTION,
)
from pinball_env.physics.sweep import INF, norm, sweep_circle, sweep_segment

# For a solid sphere, the share of the contact-point slip one friction impulse can remove:
# 1 / (1 + m r^2 / I) with I = 2/5 m r^2. The remaining 5/7 goes into spin.
ROLLING_SHARE = 2.0 / 7.0
# Contacts that use less than this fraction of a substep make no progress ...
MIN_PROGRESS = 1e-9
# ... and after this many in a row the ball is wedged: the rest of the substep is dropped.
MAX_STALLED_PASSES = 4
# Flipper contacts are found within this fraction of the skin from the surface.
FLIPPER_TOLERANCE = 0.25


class Geometry(NamedTuple):
    """The static table as arrays (see ``layout`` for the columns)."""

    segments: np.ndarray  # (S, 4)
    segment_bounds: np.ndarray  # (S, 3): bounding circles, from segment_bounds(segments)
    segment_props: np.ndarray  # (S, PROP_SIZE)
    segment_one_sided: np.ndarray  # (S,) bool
    circles: np.ndarray  # (C, 3)
    circle_props: np.ndarray  # (C, PROP_SIZE)
    flippers: np.ndarray  # (F, FLIPPER_SIZE)
    flipper_props: np.ndarray  # (F, PROP_SIZE)
    sensors: np.ndarray  # (K, 4)
    sensor_drain: np.ndarray  # (K,) bool


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
    """Per-env state, updated in place by :func:`step_world`; the first axis is the env."""

    balls: np.ndarray  # (N, BALL_STATE_SIZE) float64
    active: np.ndarray  # (N,) bool: the ball is in play; cleared when it drains
    flipper_angle: np.ndarray  # (N, F) float64 [rad]
    flipper_omega: np.ndarray  # (N, F) float64 [rad/s], at the end of the frame
    flipper_command: np.ndarray  # (N, F) bool, input: energised
    contacts: np.ndarray  # (N, capacity, CONTACT_SIZE) float64: log of the frame's contacts
    contact_count: np.ndarray  # (N,) int64: contacts of the frame (may exceed the capacity)
    hits: np.ndarray  # (N, E) int64: hits of the frame per element id (scoring events)


@njit(cache=True)
def respond(vx, vy, spin, nx, ny, svx, svy, r, restitution, friction, kick, resting_speed):
    """Velocity and spin of the ball after a contact with normal n on a surface moving at sv.

    Returns ``(vx, vy, spin, approach_speed)``, the last being the normal speed towards the
    surface before the response (0 when the ball was not approaching it).
    """
    rvx = vx - svx
    rvy = vy - svy
    vn = rvx * nx + rvy * ny
    if vn >= 0.0:
        return vx, vy, spin, 0.0
    e = restitution if -vn >= resting_speed else 0.0
    jn = -(1.0 + e) * vn  # normal impulse per unit mass
    vx += jn * nx
    vy += jn * ny
    # Slip of the contact point (at -r n from the centre) along the tangent t = rot+90(n).
    tx = -ny
    ty = nx
    slip = rvx * tx + rvy * ty - r * spin
    jt = min(ROLLING_SHARE * abs(slip), friction * jn)
    if slip < 0.0:
        jt = -jt
    vx -= jt * tx
    vy -= jt * ty
    spin += 2.5 * jt / r  # torque of the friction impulse, I = 2/5 m r^2
    if kick > 0.0:
        vx += kick * nx
        vy += kick * ny
    return vx, vy, spin, -vn


def segment_bounds(segments: np.ndarray) -> np.ndarray:
    """Bounding circle of every segment, (S, 3): centre x, y and radius (half the length)."""
    segments = np.asarray(segments, dtype=np.float64).reshape(-1, 4)
    bounds = np.empty((segments.shape[0], 3))
    bounds[:, 0] = 0.5 * (segments[:, 0] + segments[:, 2])
    bounds[:, 1] = 0.5 * (segments[:, 1] + segments[:, 3])
    bounds[:, 2] = 0.5 * np.hypot(segments[:, 2] - segments[:, 0], segments[:, 3] - segments[:, 1])
    return bounds


@njit(cache=True)
def earliest_static_contact(x, y, dx, dy, r, segments, segment_bounds, segment_one_sided, circles):
    """Earliest contact of a ball sweeping from (x, y) by (dx, dy) with the walls and posts.

    Returns ``(t, nx, ny, element)``; ``element = -1`` (and ``t = inf``) when the path is free.
    Element ids: segments first, then circles. On equal times the lowest id wins. A segment
    whose bounding circle is out of the sweep's reach is skipped without the full test.
    """
    best_t = INF
    best_nx = 0.0
    best_ny = 0.0
    best = -1
    travel = math.sqrt(dx * dx + dy * dy)
    for j in range(segments.shape[0]):
        mx = x - segment_bounds[j, 0]
        my = y - segment_bounds[j, 1]
        reach = r + travel + segment_bounds[j, 2]
        if mx * mx + my * my > reach * reach * (1.0 + 1e-12):
            continue  # cannot touch: the margin covers rounding in this test
        t, nx, ny = sweep_segment(
            x, y, dx, dy, r,
            segments[j, 0], segments[j, 1], segments[j, 2], segments[j, 3],
            segment_one_sided[j],
        )  # fmt: skip
        if t < best_t:
            best_t, best_nx, best_ny, best = t, nx, ny, j
    offset = segments.shape[0]
    for j in range(circles.shape[0]):
        t, nx, ny = sweep_circle(x, y, dx, dy, r, circles[j, 0], circles[j, 1], circles[j, 2])
        if t < best_t:
            best_t, best_nx, best_ny, best = t, nx, ny, offset + j
    return best_t, best_nx, best_ny, best


@njit(cache=True)
def earliest_flipper_contact(x, y, vx, vy, duration, r, flippers, angles, omegas, stops, tol):
    """Earliest contact of a ball moving at (vx, vy) for ``duration`` seconds with a flipper.

    ``angles``, ``omegas`` and ``stops`` give each flipper's angle now, its angular velocity and
    when it reaches its stop. Returns ``(tau, nx, ny, svx, svy, flipper)`` with ``tau`` in
    seconds and sv the surface velocity; ``flipper = -1`` (and ``tau = inf``) for none.
    """
    best_tau = INF
    best_nx = 0.0
    best_ny = 0.0
    best_svx = 0.0
    best_svy = 0.0
    best = -1
    for j in range(flippers.shape[0]):
        f = flippers[j]
        tau, nx, ny, svx, svy = sweep_flipper(
            x, y, vx, vy, duration, r,
            f[FLIPPER_PIVOT_X], f[FLIPPER_PIVOT_Y], f[FLIPPER_LENGTH],
            f[FLIPPER_BASE_RADIUS], f[FLIPPER_TIP_RADIUS],
            angles[j], omegas[j], stops[j], tol,
        )  # fmt: skip
        if tau < best_tau:
            best_tau, best_nx, best_ny, best_svx, best_svy, best = tau, nx, ny, svx, svy, j
    return best_tau, best_nx, best_ny, best_svx, best_svy, best


@njit(cache=True)
def surface_distance(x, y, element, geometry, angles):
    """Distance from the point (x, y) to the surface of a solid element (negative inside)."""
    segments = geometry.segments
    n_segments = segments.shape[0]
    if element < n_segments:
        x0 = segments[element, 0]
        y0 = segments[element, 1]
        ex = segments[element, 2] - x0
        ey = segments[element, 3] - y0
        length2 = ex * ex + ey * ey
        s = 0.0
        if length2 > 0.0:
            s = min(max(((x - x0) * ex + (y - y0) * ey) / length2, 0.0), 1.0)
        return norm(x - x0 - s * ex, y - y0 - s * ey)
    j = element - n_segments
    circles = geometry.circles
    if j < circles.shape[0]:
        return norm(x - circles[j, 0], y - circles[j, 1]) - circles[j, 2]
    j -= circles.shape[0]
    f = geometry.flippers[j]
    d, _, _ = flipper_distance(
        x, y, f[FLIPPER_PIVOT_X], f[FLIPPER_PIVOT_Y], f[FLIPPER_LENGTH],
        f[FLIPPER_BASE_RADIUS], f[FLIPPER_TIP_RADIUS], angles[j],
    )  # fmt: skip
    return d


@njit(cache=True)
def element_props(element, geometry):
    """Surface properties row of a solid element."""
    n_segments = geometry.segments.shape[0]
    if element < n_segments:
        return geometry.segment_props[element]
    j = element - n_segments
    if j < geometry.circles.shape[0]:
        return geometry.circle_props[j]
    return geometry.flipper_props[j - geometry.circles.shape[0]]


@njit(cache=True)
def sensor_crossing(x, y, dx, dy, sensor):
    """Fraction of the move (x, y) -> (x + dx, y + dy) at which the centre crosses a sensor.

    Half-open: a point exactly on the sensor line counts as behind it (the side opposite its
    normal), so a path that ends on the line and goes on is counted once. ``inf`` for none.
    """
    x0 = sensor[0]
    y0 = sensor[1]
    ex = sensor[2] - x0
    ey = sensor[3] - y0
    side0 = ex * (y - y0) - ey * (x - x0)
    side1 = ex * (y + dy - y0) - ey * (x + dx - x0)
    if (side0 > 0.0) == (side1 > 0.0):
        return INF
    u = side0 / (side0 - side1)
    along = ((x + dx * u - x0) * ex + (y + dy * u - y0) * ey) / (ex * ex + ey * ey)
    if along < 0.0 or along >= 1.0:  # half-open too: sensors meeting end to end count once
        return INF
    return u


@njit(cache=True)
def cross_sensors(x, y, dx, dy, sensors, sensor_drain, crossings):
    """Fractions of the move (x, y) -> (x + dx, y + dy) at which the centre crosses each sensor,
    written to ``crossings`` (inf for none). Returns the earliest drain crossing (inf for none):
    the ball leaves play there, so only crossings up to it happen."""
    drain = INF
    for j in range(sensors.shape[0]):
        crossings[j] = sensor_crossing(x, y, dx, dy, sensors[j])
        if sensor_drain[j] and crossings[j] < drain:
            drain = crossings[j]
    return drain


@njit(cache=True)
def log_contact(state, env, element, time, speed):
    """Append a contact to env's log (counting it even when the log is full)."""
    row = state.contact_count[env]
    if row < state.contacts.shape[1]:
        state.contacts[env, row, CONTACT_ELEMENT] = element
        state.contacts[env, row, CONTACT_TIME] = time
        state.contacts[env, row, CONTACT_SPEED] = speed
    state.contact_count[env] = row + 1


@njit(cache=True)
def flipper_motion(flipper, angle, energised):
    """Angular velocity and time to reach the commanded stop, for a flipper at ``angle``."""
    if energised:
        target = flipper[FLIPPER_UP_ANGLE]
        speed = flipper[FLIPPER_UP_SPEED]
    else:
        target = flipper[FLIPPER_REST_ANGLE]
        speed = flipper[FLIPPER_DOWN_SPEED]
    if angle == target:
        return target, 0.0, 0.0
    omega = speed if target > angle else -speed
    return target, omega, abs(target - angle) / speed


@njit(cache=True)
def step_world(geometry, settings, state):
    """Advance every env by one frame ``settings.dt`` in place, logging contacts and hits."""
    h = settings.dt / settings.substeps
    r = settings.radius
    tol = FLIPPER_TOLERANCE * settings.skin
    segments = geometry.segments  # unpacked once: the hot loop then sees plain arrays
    bounds = geometry.segment_bounds
    segment_one_sided = geometry.segment_one_sided
    circles = geometry.circles
    n_segments = segments.shape[0]
    n_circles = circles.shape[0]
    n_flippers = geometry.flippers.shape[0]
    first_sensor = n_segments + n_circles + n_flippers
    targets = np.empty(n_flippers)
    omegas = np.empty(n_flippers)
    stops = np.empty(n_flippers)
    angles = np.empty(n_flippers)
    pass_stops = np.empty(n_flippers)
    n_sensors = geometry.sensors.shape[0]
    crossings = np.empty(n_sensors)
    held = np.zeros(n_flippers, dtype=np.bool_)  # flippers stopped for the rest of a substep
    hit_elements = np.empty(settings.max_passes, dtype=np.int64)  # hits of one substep
    balls = state.balls
    for i in range(balls.shape[0]):
        state.contact_count[i] = 0
        state.hits[i, :] = 0
        x = balls[i, BALL_X]
        y = balls[i, BALL_Y]
        vx = balls[i, BALL_VX]
        vy = balls[i, BALL_VY]
        spin = balls[i, BALL_SPIN]
        for k in range(settings.substeps):
            start_angles = state.flipper_angle[i]
            for j in range(n_flippers):
                targets[j], omegas[j], stops[j] = flipper_motion(
                    geometry.flippers[j], start_angles[j], state.flipper_command[i, j]
                )
            held[:] = False
            held_time = h
            if state.active[i]:
                vx += settings.gravity_x * h
                vy += settings.gravity_y * h
                remaining = h
                stalled = 0
                pusher = -1  # the last flipper that pushed into the ball in this substep
                n_hits = 0
                for _ in range(settings.max_passes):
                    if remaining <= 0.0:
                        break
                    elapsed = h - remaining
                    for j in range(n_flippers):
                        angles[j] = start_angles[j] + omegas[j] * min(elapsed, stops[j])
                        pass_stops[j] = max(stops[j] - elapsed, 0.0)
                    t, nx, ny, element = earliest_static_contact(
                        x, y, vx * remaining, vy * remaining, r,
                        segments, bounds, segment_one_sided, circles,
                    )  # fmt: skip
                    svx = svy = 0.0
                    if n_flippers > 0:
                        tau, fnx, fny, fsvx, fsvy, flipper = earliest_flipper_contact(
                            x, y, vx, vy, remaining, r, geometry.flippers,
                            angles, omegas, pass_stops, tol,
                        )  # fmt: skip
                        if tau < t * remaining:  # a tie goes to the wall or post (lower id)
                            t, nx, ny, svx, svy = tau / remaining, fnx, fny, fsvx, fsvy
                            element = n_segments + n_circles + flipper
                    move = min(t, 1.0)
                    # Sensors crossed on the way to the contact (or to the end of the substep).
                    used = remaining * move
                    crossed = False  # the common case, checked first: no sensor crossed
                    for j in range(n_sensors):
                        if sensor_crossing(x, y, vx * used, vy * used, geometry.sensors[j]) < INF:
                            crossed = True
                            break
                    if crossed:
                        drain = cross_sensors(
                            x, y, vx * used, vy * used, geometry.sensors, geometry.sensor_drain,
                            crossings,
                        )  # fmt: skip
                        for j in range(n_sensors):
                            if crossings[j] <= drain and crossings[j] < INF:
                                state.hits[i, first_sensor + j] += 1
                                time = k * h + elapsed + used * crossings[j]
                                log_contact(state, i, first_sensor + j, time, 0.0)
                        if drain < INF:
                            x += vx * used * drain
                            y += vy * used * drain
                            state.active[i] = False
                            break
                    x += vx * used
                    y += vy * used
                    remaining -= used
                    if element < 0:
                        break
                    props = element_props(element, geometry)
                    vx, vy, spin, speed = respond(
                        vx, vy, spin, nx, ny, svx, svy, r,
                        props[PROP_RESTITUTION], props[PROP_FRICTION], props[PROP_KICK],
                        settings.resting_speed,
                    )  # fmt: skip
                    # Leave the ball exactly skin off the surface it touched.
                    for j in range(n_flippers):
                        angles[j] = start_angles[j] + omegas[j] * min(h - remaining, stops[j])
                    gap = surface_distance(x, y, element, geometry, angles)
                    push = r + settings.skin - gap
                    x += nx * push
                    y += ny * push
                    log_contact(state, i, element, k * h + h - remaining, speed)
                    if speed >= settings.resting_speed or props[PROP_KICK] > 0.0:
                        hit_elements[n_hits] = element
                        n_hits += 1
                    if element >= n_segments + n_circles and svx * nx + svy * ny > 0.0:
                        pusher = element - n_segments - n_circles
                    if used <= MIN_PROGRESS * h:
                        stalled += 1
                        if stalled >= MAX_STALLED_PASSES:
                            break
                    else:
                        stalled = 0
                pinched = False
                if remaining > 0.0 and state.active[i]:
                    # Wedged (time left after the pass cap or the progress rule): the rest of
                    # the substep is dropped for the ball, and so for every moving flipper that
                    # could reach it, which would otherwise sweep through it unchecked. A
                    # flipper pushing a wedged ball thus stalls against it, as a real coil does;
                    # the pinched ball is at rest, and its pinch is no hit.
                    held_time = h - remaining
                    for j in range(n_flippers):
                        f = geometry.flippers[j]
                        reach = max(
                            f[FLIPPER_BASE_RADIUS], f[FLIPPER_LENGTH] + f[FLIPPER_TIP_RADIUS]
                        )
                        near = norm(x - f[FLIPPER_PIVOT_X], y - f[FLIPPER_PIVOT_Y]) <= reach + r
                        held[j] = near and omegas[j] != 0.0 and stops[j] > held_time
                    if pusher >= 0 and held[pusher]:
                        pinched = True
                        vx = 0.0
                        vy = 0.0
                if not pinched:
                    for n in range(n_hits):
                        state.hits[i, hit_elements[n]] += 1
            for j in range(n_flippers):
                if held[j]:
                    state.flipper_angle[i, j] = start_angles[j] + omegas[j] * min(
                        held_time, stops[j]
                    )
                    state.flipper_omega[i, j] = 0.0
                elif stops[j] <= h:
                    state.flipper_angle[i, j] = targets[j]
                    state.flipper_omega[i, j] = 0.0
                else:
                    state.flipper_angle[i, j] = start_angles[j] + omegas[j] * h
                    state.flipper_omega[i, j] = omegas[j]
        balls[i, BALL_X] = x
        balls[i, BALL_Y] = y
        balls[i, BALL_VX] = vx
        balls[i, BALL_VY] = vy
        balls[i, BALL_SPIN] = spin
