"""Ray casts from a point against a table's walls, posts and flippers (the state observation's
"rays": what a state policy sees of the layout); on a table of several balls they also see
the other balls and the standing drop targets (:func:`cast_all_rays`).

The ray tests are those of a point sweep (``sweep.py``: a ray against a segment, against a
circle from outside), written for a unit direction and an unbounded length, which the
observation's published values depend on bitwise; ``sweep_point``'s arithmetic (a ray scaled
to one sweep) rounds differently. A flipper is seen as its capsule at the given angle: the base
and tip circles and the two sides between them.
"""

import math

import numpy as np
from numba import njit

from pinball_env.physics.columns import (
    BALL_X,
    BALL_Y,
    BOUND_RADIUS,
    BOUND_X,
    BOUND_Y,
    FLIPPER_BASE_RADIUS,
    FLIPPER_LENGTH,
    FLIPPER_PIVOT_X,
    FLIPPER_PIVOT_Y,
    FLIPPER_TIP_RADIUS,
)
from pinball_env.physics.flipper import flipper_reach
from pinball_env.physics.sweep import norm, segment_offset

# Rays see this far [m]; a ray that meets nothing reads 1.
RAY_RANGE = 0.5


# Rounding margin of the distance bounds by which cast_rays skips elements [relative].
_MARGIN = 1e-9


@njit(cache=True, inline="always")
def nearest_first(x, y, geometry, bounds, order):
    """The walls, posts and flippers (element ids in ``order``) that a ray from (x, y) may meet
    within RAY_RANGE, nearest first by a lower bound of their distance (in ``bounds``); returns
    how many. A NaN point keeps every element, its bound -inf."""
    segments, circles, flippers = geometry.segments, geometry.circles, geometry.flippers
    n_segments, n_circles = segments.shape[0], circles.shape[0]
    limit = RAY_RANGE * (1.0 + _MARGIN)
    n = 0
    for e in range(n_segments + n_circles + flippers.shape[0]):
        if e < n_segments:
            s = segments[e]
            gx, gy = segment_offset(x, y, s[0], s[1], s[2], s[3])
            bound = norm(gx, gy)
        elif e < n_segments + n_circles:
            c = circles[e - n_segments]
            bound = norm(x - c[0], y - c[1]) - c[2]
        else:
            f = flippers[e - n_segments - n_circles]
            reach = flipper_reach(f[FLIPPER_LENGTH], f[FLIPPER_BASE_RADIUS], f[FLIPPER_TIP_RADIUS])
            bound = norm(x - f[FLIPPER_PIVOT_X], y - f[FLIPPER_PIVOT_Y]) - reach
        if bound <= limit:  # (a NaN point keeps every element, below)
            bound = bound * (1.0 - _MARGIN) - 1e-12
            i = n  # insertion sort, nearest first
            while i > 0 and bounds[i - 1] > bound:
                bounds[i], order[i] = bounds[i - 1], order[i - 1]
                i -= 1
            bounds[i], order[i] = bound, e
            n += 1
        elif not bound > limit:
            bounds[n], order[n] = -math.inf, e
            n += 1
    return n


@njit(cache=True)
def cast_rays(x, y, directions, geometry, flipper_angles, out, bounds, order, sides):
    """Distances from (x, y) along ``directions`` (:func:`ray_directions`) to the first wall,
    post or flipper (its capsule at ``flipper_angles``: base and tip circles and the two
    sides), in RAY_RANGE (1: nothing within it), written to ``out``.

    Each ray's distance is the least over the elements, as tested one by one; the elements are
    taken nearest first (by a lower bound of their distance from the point: ``bounds`` and
    ``order``, work arrays as long as the table has walls, posts and flippers), and a ray stops
    at the first whose bound is beyond what it has found, so the distances are bitwise those of
    testing every element. ``sides``: a work array, (flippers, 2)."""
    segments, circles, flippers = geometry.segments, geometry.circles, geometry.flippers
    segment_bounds = geometry.segment_bounds
    n_segments, n_circles = segments.shape[0], circles.shape[0]
    n = nearest_first(x, y, geometry, bounds, order)
    for j in range(flippers.shape[0]):  # each flipper's direction, for every ray
        sides[j, 0], sides[j, 1] = math.cos(flipper_angles[j]), math.sin(flipper_angles[j])
    for k in range(directions.shape[0]):
        dx, dy = directions[k, 0], directions[k, 1]
        best = RAY_RANGE
        for i in range(n):
            if bounds[i] > best:
                break
            e = order[i]
            if e < n_segments:
                # A ray clear of the segment's bounding circle misses it.
                bx, by = segment_bounds[e, BOUND_X] - x, segment_bounds[e, BOUND_Y] - y
                miss = segment_bounds[e, BOUND_RADIUS] * (1.0 + _MARGIN) + 1e-12
                if abs(bx * dy - by * dx) > miss or bx * dx + by * dy < -miss:
                    continue
                x0, y0, x1, y1 = segments[e, 0], segments[e, 1], segments[e, 2], segments[e, 3]
                best = min(best, ray_segment(x, y, dx, dy, x0, y0, x1, y1))
            elif e < n_segments + n_circles:
                j = e - n_segments
                best = min(best, ray_circle(x, y, dx, dy, circles[j, 0], circles[j, 1],
                                             circles[j, 2]))  # fmt: skip
            else:
                j = e - n_segments - n_circles
                best = min(best, ray_flipper(x, y, dx, dy, flippers[j], sides[j, 0], sides[j, 1]))
        out[k] = best / RAY_RANGE


@njit(cache=True, inline="always")
def ray_flipper(x, y, dx, dy, flipper, ux, uy):
    """Distance along the ray to a flipper (a row of ``Geometry.flippers``) pointing along
    (ux, uy) (the cosine and sine of its angle): its base and tip circles and the two sides
    between them (inf: none)."""
    px, py = flipper[FLIPPER_PIVOT_X], flipper[FLIPPER_PIVOT_Y]
    length = flipper[FLIPPER_LENGTH]
    rb, rt = flipper[FLIPPER_BASE_RADIUS], flipper[FLIPPER_TIP_RADIUS]
    tx, ty = px + length * ux, py + length * uy
    best = min(ray_circle(x, y, dx, dy, px, py, rb), ray_circle(x, y, dx, dy, tx, ty, rt))
    for side in (-1.0, 1.0):  # the sides, as lines between the circles' edges
        nx, ny = -side * uy, side * ux
        side_hit = ray_segment(x, y, dx, dy, px + nx * rb, py + ny * rb, tx + nx * rt, ty + ny * rt)
        best = min(best, side_hit)
    return best


@njit(cache=True, inline="always")
def ray_segment(x, y, dx, dy, x0, y0, x1, y1):
    """Distance along the ray (x, y) + t (dx, dy), unit direction, to the segment (inf: none)."""
    ex, ey = x1 - x0, y1 - y0
    denominator = dx * ey - dy * ex
    if denominator == 0.0:
        return math.inf
    t = ((x0 - x) * ey - (y0 - y) * ex) / denominator
    s = ((x0 - x) * dy - (y0 - y) * dx) / denominator
    return t if t >= 0.0 and 0.0 <= s <= 1.0 else math.inf


@njit(cache=True, inline="always")
def ray_circle(x, y, dx, dy, cx, cy, r):
    """Distance along the ray to the circle (0 from inside it, inf: none)."""
    fx, fy = x - cx, y - cy
    c = fx * fx + fy * fy - r * r
    if c <= 0.0:
        return 0.0
    b = fx * dx + fy * dy
    disc = b * b - c
    if b > 0.0 or disc < 0.0:
        return math.inf
    return -b - math.sqrt(disc)


@njit(cache=True)
def ray_directions(n_rays):
    """(n_rays, 2): the unit directions of ``n_rays`` rays, 0 = +x, evenly round the circle."""
    directions = np.empty((n_rays, 2))
    for k in range(n_rays):
        a = 2.0 * math.pi * k / n_rays
        directions[k, 0], directions[k, 1] = math.cos(a), math.sin(a)
    return directions


@njit(cache=True, inline="always")
def ray_balls_and_targets(x, y, dx, dy, balls, active, radius, targets, up):
    """Distance along the ray to the nearest other ball (a circle of ``radius`` at the centre of
    each ball of ``balls`` (M, 5) that ``active`` (M,) marks, in play or held; a ball centred on
    (x, y), the ball the ray starts from, is not seen) or standing drop target (each of the
    first ``len(up)`` rows of ``targets`` (T, 4) that ``up`` marks, a segment) (inf: none)."""
    best = math.inf
    for b in range(balls.shape[0]):
        bx, by = balls[b, BALL_X], balls[b, BALL_Y]
        if active[b] and not (bx == x and by == y):
            best = min(best, ray_circle(x, y, dx, dy, bx, by, radius))
    for t in range(up.shape[0]):
        if up[t]:
            s = targets[t]
            best = min(best, ray_segment(x, y, dx, dy, s[0], s[1], s[2], s[3]))
    return best


@njit(cache=True, nogil=True)
def cast_all_rays(
    origins, geometries, angles, n_rays, size, out, balls, active, radius, targets_up, start,
    stop,
):  # fmt: skip
    """:func:`cast_rays` from ``origins[i]`` (a ball row) for envs ``start`` to ``stop``, env i on
    ``geometries[i]``; ``size``: at least the walls, posts and flippers of any of them (the width
    of ``State.hits`` will do). The rays also see env i's balls ``balls[i]`` (M, 5) where
    ``active[i]`` (in play or held; of ``radius``) and its drop targets where ``targets_up[i]``:
    each ray reads the nearer of :func:`cast_rays`'s distance and
    :func:`ray_balls_and_targets`'s (dividing by RAY_RANGE keeps the order, so the walls'
    readings are bitwise those of the walls alone). What the rays see besides the walls is
    the caller's choice, made once: the observation of a table of several balls passes its
    ball slots and targets, that of a table of one ball no columns (M = T = 0: the walls,
    posts and flippers alone)."""
    bounds, order = np.empty(size), np.empty(size, dtype=np.int64)
    directions, sides = ray_directions(n_rays), np.empty((angles.shape[1], 2))
    for env in range(start, stop):
        x, y = origins[env, BALL_X], origins[env, BALL_Y]
        geometry = geometries[env]
        cast_rays(x, y, directions, geometry, angles[env], out[env], bounds, order, sides)
        if balls.shape[1] == 0 and targets_up.shape[1] == 0:
            continue
        targets = geometry.drop_targets
        up = targets_up[env]
        for k in range(n_rays):
            d = ray_balls_and_targets(x, y, directions[k, 0], directions[k, 1], balls[env],
                                      active[env], radius, targets, up)  # fmt: skip
            out[env, k] = min(out[env, k], d / RAY_RANGE)
