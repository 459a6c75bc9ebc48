"""The parts of a contact pass, shared by the kernels (``step.step_ball`` for one ball,
``multiball.step_balls`` for several): the element properties and distances, the flipper
schedule, the contact search of a pass (:func:`earliest_contact`), the response
(:func:`respond`) and the wedge rules (:func:`unwedge`, :func:`release_wedge`,
:func:`deepest_overlap`, :func:`settle`).

Contact response (per unit mass, relative to the velocity of the surface, zero except on a
swinging flipper): the normal velocity is reflected with restitution ``e`` (``e = 0`` below
``resting_speed``, so a ball lying or rolling on a surface stays on it without jitter); friction
is a Coulomb impulse, at most ``mu`` times the normal impulse, that drives the slip of the
contact point towards zero, the ball being a solid sphere (I = 2/5 m r^2) whose spin about the
playfield normal is part of its state; kicking elements (bumpers, slingshots) then add ``kick``
along the normal. After a contact the ball is put ``skin`` off the surface (the separation,
measured by :func:`surface_distance`).
"""

import math

from numba import njit

from pinball_env.physics.columns import (
    FLIPPER_BASE_RADIUS,
    FLIPPER_DOWN_SPEED,
    FLIPPER_LENGTH,
    FLIPPER_PIVOT_X,
    FLIPPER_PIVOT_Y,
    FLIPPER_REST_ANGLE,
    FLIPPER_TIP_RADIUS,
    FLIPPER_UP_ANGLE,
    FLIPPER_UP_SPEED,
)
from pinball_env.physics.data import (
    first_circle,
    first_drop_target,
    first_flipper,
    first_sensor,
)
from pinball_env.physics.flipper import flipper_distance, flipper_reach, sweep_flipper
from pinball_env.physics.near import (
    NEAR_DROP_TARGETS,
    NEAR_FLIPPERS,
    NEAR_SOLIDS,
    gather_near,
    near_reach,
    path_in_zone,
)
from pinball_env.physics.sweep import (
    INF,
    norm,
    segment_contact,
    segment_offset,
    sweep_circle,
)
from pinball_env.physics.targets import (
    sweep_drop_targets,
)

# For a solid sphere, the share of the contact-point slip one friction impulse can remove:
# 1 / (1 + m r^2 / I) with I = 2/5 m r^2. The remaining 5/7 goes into spin.
ROLLING_SHARE = 2.0 / 7.0
# Contacts that use less than this fraction of a substep make no progress ...
MIN_PROGRESS = 1e-9
# ... and after this many in a row the ball is wedged: the rest of the substep is dropped.
MAX_STALLED_PASSES = 4
# Flipper contacts are found within this fraction of the skin from the surface.
FLIPPER_CONTACT_TOLERANCE = 0.25
# Rounds of pushing a wedged ball out of the surfaces around it (see settle).
SETTLE_ROUNDS = 8
# The ball is moved without a sweep (out of a wedge) by at most this fraction of its radius, so
# that it cannot pass through a wall that it overlaps by less.
MAX_NUDGE = 0.25


# --- contact response and the rules of a contact -------------------------------------------------


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
def is_hit(speed, kick, resting_speed):
    """Whether a contact is a hit (a scoring event): the ball strikes the surface, rather than
    lying or rolling on it, or the surface kicks."""
    return speed >= resting_speed or kick > 0.0


# --- the elements ---------------------------------------------------------------------------------


@njit(cache=True, inline="always")
def element_props(element, geometry):
    """Surface properties row of a solid element (drop targets included)."""
    j = element - first_circle(geometry)
    if j < 0:
        return geometry.segment_props[element]
    if j < geometry.circles.shape[0]:
        return geometry.circle_props[j]
    if element < first_sensor(geometry):
        return geometry.flipper_props[element - first_flipper(geometry)]
    return geometry.drop_target_props[element - first_drop_target(geometry)]


@njit(cache=True, inline="always")
def separation(x, y, element, geometry, angles):
    """Distance from the point (x, y) to the surface of a solid element (negative inside) and
    the unit normal from the surface towards the point (zero where it is undefined), the
    flippers at ``angles`` (a drop target as if it stood)."""
    j = element - first_circle(geometry)
    if j < 0:
        s = geometry.segments[element]
        gx, gy = segment_offset(x, y, s[0], s[1], s[2], s[3])
        d = norm(gx, gy)
        return (d, gx / d, gy / d) if d > 0.0 else (d, 0.0, 0.0)
    if j < geometry.circles.shape[0]:
        c = geometry.circles[j]
        gx, gy = x - c[0], y - c[1]
        d = norm(gx, gy)
        return (d - c[2], gx / d, gy / d) if d > 0.0 else (d - c[2], 0.0, 0.0)
    if element >= first_sensor(geometry):  # a drop target
        s = geometry.drop_targets[element - first_drop_target(geometry)]
        gx, gy = segment_offset(x, y, s[0], s[1], s[2], s[3])
        d = norm(gx, gy)
        return (d, gx / d, gy / d) if d > 0.0 else (d, 0.0, 0.0)
    j = element - first_flipper(geometry)
    f = geometry.flippers[j]
    return flipper_distance(
        x, y, f[FLIPPER_PIVOT_X], f[FLIPPER_PIVOT_Y], f[FLIPPER_LENGTH],
        f[FLIPPER_BASE_RADIUS], f[FLIPPER_TIP_RADIUS], angles[j],
    )  # fmt: skip


@njit(cache=True, inline="always")
def surface_distance(x, y, element, geometry, angles):
    """Distance from the point (x, y) to the surface of a solid element (negative inside), the
    flippers at ``angles``: :func:`separation` without the normal."""
    d, _, _ = separation(x, y, element, geometry, angles)
    return d


@njit(cache=True)
def within_reach(x, y, r, flipper):
    """Whether a flipper (a row of ``Geometry.flippers``) can touch a ball of radius ``r`` at
    (x, y) at some angle."""
    reach = flipper_reach(
        flipper[FLIPPER_LENGTH], flipper[FLIPPER_BASE_RADIUS], flipper[FLIPPER_TIP_RADIUS]
    )
    return norm(x - flipper[FLIPPER_PIVOT_X], y - flipper[FLIPPER_PIVOT_Y]) <= reach + r


# --- the flipper schedule ------------------------------------------------------------------------


@njit(cache=True)
def flipper_motion(flipper, angle, energised):
    """Angular velocity and time to reach the commanded stop, for a flipper at ``angle``.

    Returns ``(target, omega, stop)``: the stop's angle [rad], the angular velocity on the way
    [rad/s] and the time at which it gets there [s] (0 when it is there already).
    """
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
def flipper_angle_at(start, omega, stop, time):
    """Angle of a flipper ``time`` seconds into a substep that it started at ``start``, turning
    at ``omega`` until ``stop``."""
    return start + omega * min(time, stop)


@njit(cache=True)
def flipper_end(start, target, omega, stop, held, held_time, h):
    """A flipper's angle and angular velocity at the end of a substep of ``h`` seconds, from its
    motion (:func:`flipper_motion`); a held flipper stops where it was ``held_time`` in."""
    if held:
        return flipper_angle_at(start, omega, stop, held_time), 0.0
    if stop <= h:
        return target, 0.0
    return start + omega * h, omega


# --- sweeping: the earliest contact --------------------------------------------------------------


@njit(cache=True)
def earliest_static_contact(x, y, dx, dy, r, segments, segment_bounds, segment_one_sided, circles):
    """Earliest contact of a ball sweeping from (x, y) by (dx, dy) with the walls and posts.

    Returns ``(t, nx, ny, element)``; ``element = -1`` (and ``t = inf``) when the path is free.
    On equal times the lowest id wins. A segment whose bounding circle is out of the sweep's
    reach is skipped without the full test.
    """
    best_t = INF
    best_nx = 0.0
    best_ny = 0.0
    best = -1
    travel = math.sqrt(dx * dx + dy * dy)
    for j in range(segments.shape[0]):
        t, nx, ny = segment_contact(
            x, y, dx, dy, r, travel, segments[j], segment_bounds[j], segment_one_sided[j]
        )
        if t < best_t:
            best_t, best_nx, best_ny, best = t, nx, ny, j
    offset = segments.shape[0]  # first_circle: the circles' ids follow the segments'
    for j in range(circles.shape[0]):
        t, nx, ny = sweep_circle(x, y, dx, dy, r, circles[j, 0], circles[j, 1], circles[j, 2])
        if t < best_t:
            best_t, best_nx, best_ny, best = t, nx, ny, offset + j
    return best_t, best_nx, best_ny, best


@njit(cache=True, inline="always")
def near_static_contact(x, y, dx, dy, r, segments, bounds, one_sided, circles, near, count):
    """:func:`earliest_static_contact` over the walls and posts of a candidate set: the first
    ``count`` entries of ``near``, element ids in increasing order (see ``physics.near``). The
    contacts are bitwise those of testing every element: each test is the same computation,
    in the same order."""
    best_t = INF
    best_nx = 0.0
    best_ny = 0.0
    best = -1
    travel = math.sqrt(dx * dx + dy * dy)
    n_segments = segments.shape[0]
    for k in range(count):
        e = near[k]
        if e < n_segments:
            t, nx, ny = segment_contact(
                x, y, dx, dy, r, travel, segments[e], bounds[e], one_sided[e]
            )
        else:
            c = e - n_segments
            t, nx, ny = sweep_circle(x, y, dx, dy, r, circles[c, 0], circles[c, 1], circles[c, 2])
        if t < best_t:
            best_t, best_nx, best_ny, best = t, nx, ny, e
    return best_t, best_nx, best_ny, best


@njit(cache=True, inline="always")
def earliest_flipper_contact(
    x, y, vx, vy, duration, r, flippers, angles, omegas, stops, tol, near, first, last
):  # fmt: skip
    """Earliest contact of a ball moving at (vx, vy) for ``duration`` seconds with a flipper
    of a candidate set (those whose indexes are ``near[first:last]``, in increasing order) or
    turning (a turning flipper's sweep can end in a cut wherever the path is).

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
    k = first
    for j in range(flippers.shape[0]):
        listed = k < last and near[k] == j
        if listed:
            k += 1
        elif omegas[j] == 0.0 or stops[j] <= 0.0:
            continue
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


@njit(cache=True, inline="always")
def earliest_contact(
    state, env, geometry, x, y, vx, vy, remaining, r, skin, gravity, tol, angles, omegas,
    pass_stops, near, near_ends, zone, flipper_id,
):  # fmt: skip
    """A pass's contact search, the one of every kernel: the earliest contact of a ball at
    (x, y) moving at (vx, vy) for the ``remaining`` seconds of its substep with the walls and
    posts, the flippers (at ``angles`` now, turning at ``omegas`` until ``pass_stops``) and
    env ``env``'s standing drop targets of its candidate set (``near``, ``near_ends``, gathered
    anew where the path leaves its ``zone``: ``physics.near``). Returns
    ``(t, nx, ny, svx, svy, element, cut)``: ``t`` the fraction of the move (>= 1: none, then
    ``element`` -1), the normal, the surface's velocity, the element id (``flipper_id`` the
    first flipper's) and whether a flipper sweep ran out of slices (``cut``: the ball's substep
    ends there). Ties go to the lower id. Inlined: with numba's reference counting off in the
    kernels' entries (``_nrt=False``), its arrays cost nothing more than written out."""
    dx, dy = vx * remaining, vy * remaining
    if not path_in_zone(x, y, dx, dy, zone, r, skin):
        reach = near_reach(vx, vy, remaining, r, gravity, skin)
        gather_near(x, y, reach, geometry, near, near_ends, zone)
    t, nx, ny, element = near_static_contact(
        x, y, dx, dy, r, geometry.segments, geometry.segment_bounds, geometry.segment_one_sided,
        geometry.circles, near, near_ends[NEAR_SOLIDS],
    )  # fmt: skip
    svx = svy = 0.0
    cut = False
    if geometry.flippers.shape[0] > 0:
        tau, fnx, fny, fsvx, fsvy, flipper = earliest_flipper_contact(
            x, y, vx, vy, remaining, r, geometry.flippers, angles, omegas, pass_stops, tol,
            near, near_ends[NEAR_SOLIDS], near_ends[NEAR_FLIPPERS],
        )  # fmt: skip
        if tau < t * remaining:  # a tie goes to the wall or post (lower id)
            t, nx, ny, svx, svy = tau / remaining, fnx, fny, fsvx, fsvy
            element = flipper_id + flipper
            cut = fnx == 0.0 and fny == 0.0  # the sweep ran out of slices
    if geometry.drop_targets.shape[0] > 0:
        t, nx, ny, svx, svy, element, cut = sweep_drop_targets(
            state, env, geometry, x, y, dx, dy, r, t, nx, ny, svx, svy, element, cut, near,
            near_ends[NEAR_FLIPPERS], near_ends[NEAR_DROP_TARGETS],
        )  # fmt: skip
    return t, nx, ny, svx, svy, element, cut


# --- one ball ------------------------------------------------------------------------------------


@njit(cache=True)
def unwedge(x, y, a, ax, ay, b, bx, by, geometry, angles, r, skin):
    """The ball centre moved the least so that it lies at least ``skin`` off both elements
    ``a`` and ``b`` (normals (ax, ay), (bx, by) at the contacts), the flippers at ``angles``.
    Separating from one at a time, as the passes do, leaves a ball wedged in a narrow V pushed
    into whichever it left last."""
    pa = r + skin - surface_distance(x, y, a, geometry, angles)
    pb = r + skin - surface_distance(x, y, b, geometry, angles)
    if pa <= 0.0 and pb <= 0.0:
        return x, y
    if pa > 0.0 and pa * (ax * bx + ay * by) >= pb:  # a push off a alone clears b too
        return x + ax * pa, y + ay * pa
    if pb > 0.0 and pb * (ax * bx + ay * by) >= pa:  # a push off b alone clears a too
        return x + bx * pb, y + by * pb
    det = ax * by - ay * bx
    if abs(det) < 1e-6:  # (nearly) facing surfaces closer than a ball: no room to be found
        return x, y
    mx, my = (pa * by - ay * pb) / det, (ax * pb - bx * pa) / det
    if norm(mx, my) > MAX_NUDGE * r:  # no room near here (and a long move could cross a wall)
        return x, y
    return x + mx, y + my


@njit(cache=True)
def release_wedge(x, y, r, flippers, omegas, stops, held_time, pushers, held):
    """A wedged ball (time left in its substep after the pass cap or the progress rule) has
    the rest of the substep dropped; so has every flipper that is still moving ``held_time``
    into it and could reach the ball, or it would sweep through the ball unchecked. Marks
    those in ``held``; returns whether the ball is pinched: a flipper that pushed into it in
    this substep (bit j of ``pushers``) is held, stalled against it as a real coil would be."""
    pinched = False
    for j in range(flippers.shape[0]):
        held[j] = within_reach(x, y, r, flippers[j]) and omegas[j] != 0.0 and stops[j] > held_time
        pinched = pinched or (held[j] and (pushers >> j) & 1 == 1)
    return pinched


@njit(cache=True)
def deepest_overlap(x, y, geometry, angles, up, r):
    """How deep a ball of radius ``r`` at (x, y) lies in the two-sided wall, post, flipper (at
    ``angles``) or standing drop target (``up``: the env's row of ``State.targets_up``) it
    overlaps most [m]; 0 or less when it overlaps none."""
    deepest = -INF
    for element in range(first_sensor(geometry)):  # the solids
        if element < geometry.segments.shape[0] and geometry.segment_one_sided[element]:
            continue  # a ball may lie partly through a gate
        d, _, _ = separation(x, y, element, geometry, angles)
        deepest = max(deepest, r - d)
    target_id = first_drop_target(geometry)
    for j in range(geometry.drop_targets.shape[0]):
        if up[j]:
            d, _, _ = separation(x, y, target_id + j, geometry, angles)
            deepest = max(deepest, r - d)
    return deepest


@njit(cache=True)
def settle(x, y, geometry, angles, up, r, skin):
    """Push the ball out of every two-sided wall, post, flipper (at ``angles``) and standing
    drop target (``up``) that it overlaps, in rounds until it overlaps none by more than half
    the skin or SETTLE_ROUNDS have passed (projected Gauss-Seidel): a wedged ball among three
    or more surfaces, which :func:`unwedge` (two at a time) cannot clear. Where the surfaces
    leave no room for the ball near where it is, it stays inside one of them (the caller then
    undoes the substep)."""
    target = r + skin
    x0, y0 = x, y
    for _ in range(SETTLE_ROUNDS):
        moved = False
        target_id = first_drop_target(geometry)
        for element in range(target_id + geometry.drop_targets.shape[0]):  # the solids
            if element < geometry.segments.shape[0] and geometry.segment_one_sided[element]:
                continue
            if element >= first_sensor(geometry) and (
                element < target_id or not up[element - target_id]
            ):
                continue  # a sensor, or a target that has dropped
            d, nx, ny = separation(x, y, element, geometry, angles)
            if d < target - 0.5 * skin and (nx != 0.0 or ny != 0.0):
                x += nx * (target - d)
                y += ny * (target - d)
                moved = True
        if not moved:
            break
    if norm(x - x0, y - y0) > MAX_NUDGE * r:  # no room near here (a long move could cross a wall)
        return x0, y0
    return x, y


# The one function here over 60 lines, by design: the hot loop of every ball-frame. numba counts
# a reference for each array a helper receives, so helpers over arrays here would cost more than
# the physics (4-5x per ball-frame, measured); the docstring says which helpers it does call.
