"""The world step: advance a batch of balls (one per env) through the table by swept collision.

Every array has a leading env axis, so the single env is a batch of one and the vector env
calls the very same kernel. Each frame of length ``dt`` is cut into fixed substeps; inside a
substep gravity updates the velocity (semi-implicit Euler), then the ball sweeps along its
straight path and stops at the earliest contact over all elements (ties go to the lowest element
id), responds, and sweeps the remaining time again. A pass cap and a minimum-progress rule end the
loop for a ball wedged between surfaces: the rest of that substep is dropped, never skipped over,
so the ball can stall for an instant but cannot tunnel.

Contact response (per unit mass, relative to the surface velocity, which is zero for static
elements): the normal velocity is reflected with restitution ``e`` (``e = 0`` below
``resting_speed``, so a ball lying or rolling on a surface stays on it without jitter); friction
is a Coulomb impulse at most ``mu`` times the normal impulse that drives the slip of the contact
point towards zero, the ball being a solid sphere (I = 2/5 m r^2) whose spin about the playfield
normal is part of its state; kicking elements (bumpers, slingshots) then add ``kick`` along the
normal. After a contact the ball is put ``skin`` off the surface.
"""

import math

from numba import njit

from pinball_env.physics.layout import (
    BALL_SPIN,
    BALL_VX,
    BALL_VY,
    BALL_X,
    BALL_Y,
    CONTACT_ELEMENT,
    CONTACT_SPEED,
    CONTACT_TIME,
    PROP_FRICTION,
    PROP_KICK,
    PROP_RESTITUTION,
)
from pinball_env.physics.sweep import INF, sweep_circle, sweep_segment

# For a solid sphere, the share of the contact-point slip one friction impulse can remove:
# 1 / (1 + m r^2 / I) with I = 2/5 m r^2. The remaining 5/7 goes into spin.
ROLLING_SHARE = 2.0 / 7.0
# Contacts that use less than this fraction of a substep make no progress ...
MIN_PROGRESS = 1e-9
# ... and after this many in a row the ball is wedged: the rest of the substep is dropped.
MAX_STALLED_PASSES = 4


@njit(cache=True)
def earliest_contact(x, y, dx, dy, r, segments, segment_one_sided, circles):
    """Earliest contact of a ball sweeping from (x, y) by (dx, dy) over all static elements.

    Returns ``(t, nx, ny, element)``; ``element = -1`` (and ``t = inf``) when the path is free.
    Element ids are global: segments first, then circles. On equal times the lowest id wins.
    """
    best_t = INF
    best_nx = 0.0
    best_ny = 0.0
    best = -1
    for j in range(segments.shape[0]):
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
def surface_distance(x, y, element, segments, circles):
    """Distance from the point (x, y) to the surface of a static element (negative inside)."""
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
        return math.hypot(x - x0 - s * ex, y - y0 - s * ey)
    j = element - n_segments
    return math.hypot(x - circles[j, 0], y - circles[j, 1]) - circles[j, 2]


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


@njit(cache=True)
def step_balls(
    balls,
    active,
    segments,
    segment_props,
    segment_one_sided,
    circles,
    circle_props,
    gravity,
    radius,
    dt,
    substeps,
    max_passes,
    skin,
    resting_speed,
    contacts,
    contact_count,
):
    """Advance every active ball by one frame ``dt`` in place and log its contacts.

    Args:
        balls: (n_envs, BALL_STATE_SIZE) float64 ball states, updated in place.
        active: (n_envs,) bool; inactive balls (drained, not in play) are left untouched.
        segments, segment_props, segment_one_sided: static segments, see ``layout``.
        circles, circle_props: static circles (posts, bumpers), see ``layout``.
        gravity: (2,) float64 acceleration in the playfield plane [m/s^2].
        radius: ball radius [m].
        dt: frame length [s]; substeps: fixed substeps per frame; max_passes: contact passes
            per substep; skin: distance left between ball and surface after a contact [m];
            resting_speed: normal speed below which a contact is inelastic [m/s].
        contacts: (n_envs, capacity, CONTACT_SIZE) float64 contact log, written from row 0.
        contact_count: (n_envs,) int64, set to the number of contacts of the frame (it may
            exceed the capacity, then only the first ``capacity`` were logged).
    """
    h = dt / substeps
    capacity = contacts.shape[1]
    n_segments = segments.shape[0]
    for i in range(balls.shape[0]):
        contact_count[i] = 0
        if not active[i]:
            continue
        x = balls[i, BALL_X]
        y = balls[i, BALL_Y]
        vx = balls[i, BALL_VX]
        vy = balls[i, BALL_VY]
        spin = balls[i, BALL_SPIN]
        logged = 0
        for k in range(substeps):
            vx += gravity[0] * h
            vy += gravity[1] * h
            remaining = h
            stalled = 0
            for _ in range(max_passes):
                dx = vx * remaining
                dy = vy * remaining
                t, nx, ny, element = earliest_contact(
                    x, y, dx, dy, radius, segments, segment_one_sided, circles
                )
                if element < 0:
                    x += dx
                    y += dy
                    remaining = 0.0
                    break
                x += dx * t
                y += dy * t
                used = remaining * t
                remaining -= used
                if element < n_segments:
                    props = segment_props[element]
                else:
                    props = circle_props[element - n_segments]
                vx, vy, spin, speed = respond(
                    vx, vy, spin, nx, ny, 0.0, 0.0, radius,
                    props[PROP_RESTITUTION], props[PROP_FRICTION], props[PROP_KICK],
                    resting_speed,
                )  # fmt: skip
                # Leave the ball exactly skin off the surface it touched.
                gap = surface_distance(x, y, element, segments, circles)
                push = radius + skin - gap
                x += nx * push
                y += ny * push
                if logged < capacity:
                    contacts[i, logged, CONTACT_ELEMENT] = element
                    contacts[i, logged, CONTACT_TIME] = k * h + (h - remaining)
                    contacts[i, logged, CONTACT_SPEED] = speed
                logged += 1
                if used <= MIN_PROGRESS * h:
                    stalled += 1
                    if stalled >= MAX_STALLED_PASSES:
                        break
                else:
                    stalled = 0
        balls[i, BALL_X] = x
        balls[i, BALL_Y] = y
        balls[i, BALL_VX] = vx
        balls[i, BALL_VY] = vy
        balls[i, BALL_SPIN] = spin
        contact_count[i] = logged
