"""Swept contact of a ball against a rotating flipper (a kinematic tapered capsule).

A flipper is the convex hull of a base circle (radius ``rb``) around its pivot and a tip circle
(radius ``rt``) at distance ``length`` along its angle. In the flipper's own frame (pivot at the
origin, tip at (length, 0)) it is static, and the ball follows a curve: its straight path seen
from the rotating frame. We cut the pass into slices short enough that the curve stays within
``tol`` of its chord (the chord error of a path with acceleration at most M over a slice of
length s is M s^2 / 8), and sweep the chord exactly against the capsule grown by ``tol``. A slice
that shows no contact therefore proves the true path free, so the ball cannot pass through a
swinging flipper at any speed or step size; a contact is found within ``2 tol`` of the surface.
A flipper at rest against a stop is a single slice: the exact static sweep. This is root finding
on the distance function in the rotating frame (as Visual Pinball does), made conservative.

Acceleration bound of the ball seen in the frame rotating at ``w`` about the pivot, for a ball
moving at constant velocity v at distance at most rho from the pivot:
|q''| = |-2 w J R v - w^2 R (c - P)| <= 2 |w| |v| + w^2 rho.
"""

import math

from numba import njit

from pinball_env.physics.sweep import INF, norm, segment_offset, sweep_point, sweep_segment

# Most slices one flipper sweep may take. A ball at 10 m/s next to a flipper at full swing needs
# about 30 per substep and one at 1 km/s about 300; the cap bounds the work at any speed.
MAX_FLIPPER_SLICES = 1024


@njit(cache=True)
def capsule_face_normal(length, rb, rt):
    """Outward normal of the capsule's upper tangent face in its own frame, ``(nx, ny)``; the
    lower face's is ``(nx, -ny)``. It leans back by the taper: ``nx = (rb - rt) / length``."""
    nx = (rb - rt) / length
    return nx, math.sqrt(1.0 - nx * nx)


@njit(cache=True)
def flipper_reach(length, rb, rt):
    """Radius of the disc around the pivot that holds the flipper at any angle [m]."""
    return max(rb, length + rt)


@njit(cache=True)
def capsule_distance(u, v, length, rb, rt):
    """Signed distance from (u, v) to the tapered capsule in its own frame, and the outward normal.

    Returns ``(distance, nx, ny)``; the distance is negative inside (exact outside, a usable
    approximation inside: the normal always points the way out of the nearest feature).
    """
    face_nx, face_ny = capsule_face_normal(length, rb, rt)
    w = abs(v)
    sign = 1.0 if v >= 0.0 else -1.0
    along = u * face_ny - w * face_nx  # position along the face, from the base tangent point
    if along < 0.0:
        d = norm(u, w)
        if d == 0.0:
            return -rb, face_nx, sign * face_ny
        return d - rb, u / d, sign * w / d
    if along > length * face_ny:
        d = norm(u - length, w)
        if d == 0.0:
            return -rt, 1.0, 0.0
        return d - rt, (u - length) / d, sign * w / d
    return u * face_nx + w * face_ny - rb, face_nx, sign * face_ny


@njit(cache=True)
def sweep_capsule(qx, qy, dx, dy, reach, length, rb, rt):
    """A point moving from q by d against the static tapered capsule grown by ``reach``.

    Returns ``(t, nx, ny)`` like the other sweeps (capsule frame). The grown capsule is again a
    tapered capsule (radii rb + reach and rt + reach, same axis, same face directions), so the
    sweep is a ray against its two circles and its two faces, the earliest winning.
    """
    gap, nx, ny = capsule_distance(qx, qy, length, rb, rt)
    if gap <= reach:
        if dx * nx + dy * ny < 0.0:
            return 0.0, nx, ny
        return INF, 0.0, 0.0
    face_nx, face_ny = capsule_face_normal(length, rb, rt)
    ax = (rb + reach) * face_nx  # tangent points of the grown faces (upper; lower mirrored)
    ay = (rb + reach) * face_ny
    bx = length + (rt + reach) * face_nx
    by = (rt + reach) * face_ny
    best_t, best_nx, best_ny = sweep_point(qx, qy, dx, dy, rb + reach, 0.0, 0.0)
    t, nx, ny = sweep_point(qx, qy, dx, dy, rt + reach, length, 0.0)
    if t < best_t:
        best_t, best_nx, best_ny = t, nx, ny
    # One-sided faces, ordered so that their normal rot+90(P1 - P0) points outwards.
    t, nx, ny = sweep_segment(qx, qy, dx, dy, 0.0, ax, ay, bx, by, True)
    if t < best_t:
        best_t, best_nx, best_ny = t, nx, ny
    t, nx, ny = sweep_segment(qx, qy, dx, dy, 0.0, bx, -by, ax, -ay, True)
    if t < best_t:
        best_t, best_nx, best_ny = t, nx, ny
    return best_t, best_nx, best_ny


@njit(cache=True)
def to_flipper_frame(x, y, px, py, angle):
    """World point (x, y) in the frame of a flipper with pivot (px, py) at ``angle``."""
    c = math.cos(angle)
    s = math.sin(angle)
    rx = x - px
    ry = y - py
    return c * rx + s * ry, -s * rx + c * ry


@njit(cache=True)
def flipper_distance(x, y, px, py, length, rb, rt, angle):
    """Signed distance from a world point to a flipper at ``angle``, with the world normal."""
    u, v = to_flipper_frame(x, y, px, py, angle)
    d, nu, nv = capsule_distance(u, v, length, rb, rt)
    c = math.cos(angle)
    s = math.sin(angle)
    return d, c * nu - s * nv, s * nu + c * nv


@njit(cache=True)
def sweep_flipper(cx, cy, vx, vy, duration, r, px, py, length, rb, rt, angle0, omega, t_stop, tol):
    """First contact of a ball moving at constant velocity with a rotating flipper.

    The ball starts at (cx, cy) with velocity (vx, vy) and moves for ``duration`` seconds. The
    flipper starts at ``angle0`` and turns at ``omega`` [rad/s] until ``t_stop`` (when it
    reaches its stop), then rests. Returns ``(tau, nx, ny, svx, svy)``: the contact time in
    seconds from the start (``inf`` for none), the world normal towards the ball, and the
    velocity of the flipper surface at the contact point. The work is bounded: after
    MAX_FLIPPER_SLICES slices it returns a *cut*, ``tau`` the time up to which the path is
    proved free and a zero normal; the caller stops the ball there for the rest of its step.
    """
    speed = norm(vx, vy)
    dist = norm(cx - px, cy - py)
    clear = flipper_reach(length, rb, rt) + r + 2.0 * tol
    if dist - speed * duration > clear:
        return INF, 0.0, 0.0, 0.0, 0.0
    # A path that passes the pivot farther than that (and a rounding margin) misses a resting
    # flipper at any angle. (Not a turning one: its slices could run out, a cut, wherever the
    # path is.)
    if omega == 0.0 or t_stop <= 0.0:
        gx, gy = segment_offset(px, py, cx, cy, cx + vx * duration, cy + vy * duration)
        if gx * gx + gy * gy > (clear + 1e-9) * (clear + 1e-9):
            return INF, 0.0, 0.0, 0.0, 0.0
    rho = dist + speed * duration
    tau_a = 0.0
    for _ in range(MAX_FLIPPER_SLICES):
        if not tau_a < duration:
            return INF, 0.0, 0.0, 0.0, 0.0
        moving = omega != 0.0 and tau_a < t_stop
        if moving:
            bound = 2.0 * abs(omega) * speed + omega * omega * rho
            step = math.sqrt(8.0 * tol / bound) if bound > 0.0 else duration
            tau_b = min(duration, t_stop, tau_a + step)
            chord_error = bound * (tau_b - tau_a) ** 2 / 8.0
        else:
            tau_b = duration
            chord_error = 0.0
        angle_a = angle0 + omega * min(tau_a, t_stop)
        angle_b = angle0 + omega * min(tau_b, t_stop)
        ua, va = to_flipper_frame(cx + vx * tau_a, cy + vy * tau_a, px, py, angle_a)
        ub, vb = to_flipper_frame(cx + vx * tau_b, cy + vy * tau_b, px, py, angle_b)
        t, _, _ = sweep_capsule(ua, va, ub - ua, vb - va, r + chord_error, length, rb, rt)
        if t < INF:
            tau = tau_a + t * (tau_b - tau_a)
            # The normal from the closest point of the true pose (the chord's is off by up to
            # chord_error / r in angle).
            angle = angle0 + omega * min(tau, t_stop)
            _, nx, ny = flipper_distance(
                cx + vx * tau, cy + vy * tau, px, py, length, rb, rt, angle
            )
            w = omega if (moving and tau < t_stop) else 0.0
            # Surface velocity w x (contact - pivot), the contact point being r below the ball.
            qx = cx + vx * tau - r * nx - px
            qy = cy + vy * tau - r * ny - py
            return tau, nx, ny, -w * qy, w * qx
        tau_a = tau_b
    # Out of slices with time left (an absurd speed): a cut. The slices so far prove the path
    # free up to tau_a, and no further.
    return tau_a, 0.0, 0.0, 0.0, 0.0
