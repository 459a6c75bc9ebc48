"""Ray casts from a point against a table's walls, posts and flippers (the state observation's
"rays": what a state policy sees of the layout).

The ray tests are those of a point sweep (``sweep.py``: a ray against a segment, against a
circle from outside), written for a unit direction and an unbounded length, which the
observation's published values depend on bitwise; ``sweep_point``'s arithmetic (a ray scaled
to one sweep) rounds differently. A flipper is seen as its capsule at the given angle: the base
and tip circles and the two sides between them.
"""

import math

from numba import njit

from pinball_env.physics.columns import (
    BALL_X,
    BALL_Y,
    FLIPPER_BASE_RADIUS,
    FLIPPER_LENGTH,
    FLIPPER_PIVOT_X,
    FLIPPER_PIVOT_Y,
    FLIPPER_TIP_RADIUS,
)

# Rays see this far [m]; a ray that meets nothing reads 1.
RAY_RANGE = 0.5


@njit(cache=True)
def cast_rays(x, y, n_rays, geometry, flipper_angles, out):
    """Distances from (x, y) along ``n_rays`` directions (0 = +x, evenly round the circle) to
    the first wall, post or flipper (its capsule: base and tip circles and the two sides),
    in RAY_RANGE (1: nothing within it), written to ``out``."""
    segments, circles, flippers = geometry.segments, geometry.circles, geometry.flippers
    for k in range(n_rays):
        a = 2.0 * math.pi * k / n_rays
        dx, dy = math.cos(a), math.sin(a)
        best = RAY_RANGE
        for j in range(segments.shape[0]):
            x0, y0, x1, y1 = segments[j, 0], segments[j, 1], segments[j, 2], segments[j, 3]
            best = min(best, _ray_segment(x, y, dx, dy, x0, y0, x1, y1))
        for j in range(circles.shape[0]):
            best = min(best, _ray_circle(x, y, dx, dy, circles[j, 0], circles[j, 1],
                                         circles[j, 2]))  # fmt: skip
        for j in range(flippers.shape[0]):
            px, py = flippers[j, FLIPPER_PIVOT_X], flippers[j, FLIPPER_PIVOT_Y]
            length = flippers[j, FLIPPER_LENGTH]
            rb, rt = flippers[j, FLIPPER_BASE_RADIUS], flippers[j, FLIPPER_TIP_RADIUS]
            ux, uy = math.cos(flipper_angles[j]), math.sin(flipper_angles[j])
            tx, ty = px + length * ux, py + length * uy
            best = min(best, _ray_circle(x, y, dx, dy, px, py, rb))
            best = min(best, _ray_circle(x, y, dx, dy, tx, ty, rt))
            for side in (-1.0, 1.0):  # the sides, as lines between the circles' edges
                nx, ny = -side * uy, side * ux
                side_hit = _ray_segment(
                    x, y, dx, dy, px + nx * rb, py + ny * rb, tx + nx * rt, ty + ny * rt
                )
                best = min(best, side_hit)
        out[k] = best / RAY_RANGE


@njit(cache=True, inline="always")
def _ray_segment(x, y, dx, dy, x0, y0, x1, y1):
    """Distance along the ray (x, y) + t (dx, dy), unit direction, to the segment (inf: none)."""
    ex, ey = x1 - x0, y1 - y0
    denominator = dx * ey - dy * ex
    if denominator == 0.0:
        return math.inf
    t = ((x0 - x) * ey - (y0 - y) * ex) / denominator
    s = ((x0 - x) * dy - (y0 - y) * dx) / denominator
    return t if t >= 0.0 and 0.0 <= s <= 1.0 else math.inf


@njit(cache=True, inline="always")
def _ray_circle(x, y, dx, dy, cx, cy, r):
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


@njit(cache=True, nogil=True)
def cast_all_rays(balls, geometries, angles, n_rays, out, start, stop):
    """:func:`cast_rays` for envs ``start`` to ``stop``, env i on ``geometries[i]``."""
    for env in range(start, stop):
        cast_rays(balls[env, BALL_X], balls[env, BALL_Y], n_rays, geometries[env], angles[env],
                  out[env])  # fmt: skip
