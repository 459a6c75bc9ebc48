"""Swept (continuous) collision of a moving ball against static segments and circles.

The ball is a circle of radius ``r`` whose centre moves from ``c`` to ``c + d`` over one sweep,
``B(t) = c + d t`` with ``t`` in [0, 1] (CS230 lecture 17b). Each test returns the fraction ``t``
of the displacement at first contact and the unit contact normal pointing from the obstacle
towards the ball, or ``t = inf`` when the ball does not touch the obstacle during the sweep.

The scalar functions (``sweep_segment``, ``sweep_circle``) are what the world step calls in its hot
loop; ``sweep_circle_segment`` and ``sweep_circle_circle`` wrap them for array arguments.

Cases handled, in order:

1. Start overlap: the ball already touches or overlaps the obstacle. Moving towards it is a
   contact at t = 0 with the normal from the closest point; moving away (or along it) is none.
2. Face: the lecture's time of intersection with the line offset by D2 = +r or -r, on the side the
   ball starts on, accepted only if the contact point projects inside the segment.
3. Ends: otherwise the ball may hit an end point, a ray against a circle of radius r around each
   end; the earlier wins. Faces plus ends make a ray-capsule test (Ericson, RTCD 5.3.2, 5.5.7).
4. One-sided segments collide only with a ball that starts wholly on the side of the normal
   n = rot+90(P1 - P0); a ball from the other side, or still partly through, passes untouched.
"""

import math

import numpy as np
from numba import njit

from pinball_env.physics.columns import (
    BOUND_NX,
    BOUND_NY,
    BOUND_OFFSET,
    BOUND_RADIUS,
    BOUND_X,
    BOUND_Y,
)

INF = math.inf
# A one-sided segment stops only a ball whose centre starts at least this share of its radius in
# front of it (a resting ball, r + skin away, is well clear of the margin).
ONE_SIDED_CLEARANCE = 1.0 - 1e-6


@njit(cache=True)
def norm(x, y):
    """Length of (x, y): the square root of the sum of squares, which is fast and gives bitwise
    the same result compiled or not, with ``hypot`` only where the squares underflow."""
    squared = x * x + y * y
    if squared > 1e-290:
        return math.sqrt(squared)
    return math.hypot(x, y)


@njit(cache=True)
def segment_offset(x, y, x0, y0, x1, y1):
    """Vector from the point of segment P0-P1 closest to (x, y) to (x, y); a zero-length segment
    is its point."""
    ex = x1 - x0
    ey = y1 - y0
    length2 = ex * ex + ey * ey
    s = 0.0
    if length2 > 0.0:
        s = min(max(((x - x0) * ex + (y - y0) * ey) / length2, 0.0), 1.0)
    return x - x0 - s * ex, y - y0 - s * ey


@njit(cache=True)
def point_segment_distance(x, y, x0, y0, x1, y1):
    """Distance from the point (x, y) to segment P0-P1."""
    gx, gy = segment_offset(x, y, x0, y0, x1, y1)
    return norm(gx, gy)


@njit(cache=True)
def sweep_point(cx, cy, dx, dy, reach, px, py):
    """Ray ``c + d t`` against a circle of radius ``reach`` around ``(px, py)``.

    Returns ``(t, nx, ny)``; ``t = inf`` for no contact in [0, 1]. Includes the start-overlap
    rule: a ball already within ``reach`` is a contact at t = 0 if it moves towards the centre.
    """
    mx = cx - px
    my = cy - py
    dist2 = mx * mx + my * my
    closing = mx * dx + my * dy  # < 0 when moving towards the centre
    if dist2 <= reach * reach:
        if dist2 == 0.0:
            # Centres coincide: any motion closes in; push back against it.
            speed = norm(dx, dy)
            if speed == 0.0:
                return INF, 0.0, 0.0
            return 0.0, -dx / speed, -dy / speed
        if closing >= 0.0:
            return INF, 0.0, 0.0
        dist = norm(mx, my)
        return 0.0, mx / dist, my / dist
    if closing >= 0.0:
        return INF, 0.0, 0.0
    a = dx * dx + dy * dy
    disc = closing * closing - a * (dist2 - reach * reach)
    if disc < 0.0:
        return INF, 0.0, 0.0
    # Stable form of the smaller root (-b - sqrt(disc)) / a; b < 0 here so no cancellation.
    t = (dist2 - reach * reach) / (-closing + math.sqrt(disc))
    if t > 1.0:
        return INF, 0.0, 0.0
    hx = mx + dx * t
    hy = my + dy * t
    h = norm(hx, hy)
    return t, hx / h, hy / h


@njit(cache=True)
def sweep_segment(cx, cy, dx, dy, r, x0, y0, x1, y1, one_sided):
    """Ball of radius ``r`` moving from ``c`` by ``d`` against segment P0-P1.

    Returns ``(t, nx, ny)`` with ``t = inf`` for no contact. See the module docstring.
    """
    ex = x1 - x0
    ey = y1 - y0
    length2 = ex * ex + ey * ey
    if length2 == 0.0:
        # A zero-length segment is a point.
        return sweep_point(cx, cy, dx, dy, r, x0, y0)
    length = norm(ex, ey)
    ux = ex / length
    uy = ey / length
    # Segment normal: the direction P0->P1 rotated by +90 degrees.
    nx = -uy
    ny = ux
    d0 = nx * (cx - x0) + ny * (cy - y0)  # signed distance of the centre from the line
    if one_sided and d0 < ONE_SIDED_CLEARANCE * r:
        # Behind a one-sided segment, or still partly through it (a ball that has not fully
        # passed a one-way gate falls back through it, as past a flap): passes untouched.
        return INF, 0.0, 0.0

    # 1. Start overlap, from the closest point of the segment.
    gx, gy = segment_offset(cx, cy, x0, y0, x1, y1)
    dist2 = gx * gx + gy * gy
    if dist2 <= r * r:
        if dist2 > 0.0:
            if gx * dx + gy * dy >= 0.0:
                return INF, 0.0, 0.0  # moving away from (or along) the closest point
            dist = norm(gx, gy)
            return 0.0, gx / dist, gy / dist
        # Centre exactly on the segment: the normal faces against the motion.
        dn = nx * dx + ny * dy
        if dn < 0.0:
            return 0.0, nx, ny
        if dn > 0.0 and not one_sided:
            return 0.0, -nx, -ny
        return INF, 0.0, 0.0

    # 2. Face: the lecture's intersection with the line offset by D2 = side * r.
    along = ux * (cx - x0) + uy * (cy - y0)
    dv = nx * dx + ny * dy
    side = 1.0 if d0 > 0.0 else -1.0
    if d0 != 0.0 and side * dv < 0.0:
        t = (side * r - d0) / dv
        if 0.0 <= t <= 1.0:
            proj = along + (ux * dx + uy * dy) * t
            if 0.0 <= proj <= length:
                return t, side * nx, side * ny

    # 3. Ends: ray against a circle of radius r around each end point; the earlier wins.
    t0, n0x, n0y = sweep_point(cx, cy, dx, dy, r, x0, y0)
    t1, n1x, n1y = sweep_point(cx, cy, dx, dy, r, x1, y1)
    if t1 < t0:
        return t1, n1x, n1y
    return t0, n0x, n0y


@njit(cache=True)
def sweep_circle(cx, cy, dx, dy, r, ox, oy, radius):
    """Ball of radius ``r`` moving from ``c`` by ``d`` against a static circle (post, bumper)."""
    return sweep_point(cx, cy, dx, dy, r + radius, ox, oy)


@njit(cache=True, inline="always")
def segment_contact(x, y, dx, dy, r, travel, segment, bounds, one_sided):
    """:func:`sweep_segment` of a segment (a row of ``Geometry.segments``), after two cheap
    tests with its row of bounds (``data.segment_bounds``) that rule out most: a segment whose
    bounding circle is out of the sweep's reach (``travel`` its length), or whose line the
    path stays on one side of, farther than the ball's radius, cannot be touched (``t = inf``).
    The margins cover rounding in these tests."""
    mx = x - bounds[BOUND_X]
    my = y - bounds[BOUND_Y]
    reach = r + travel + bounds[BOUND_RADIUS]
    if mx * mx + my * my > reach * reach * (1.0 + 1e-12):
        return INF, 0.0, 0.0
    d0 = bounds[BOUND_NX] * x + bounds[BOUND_NY] * y - bounds[BOUND_OFFSET]
    d1 = d0 + bounds[BOUND_NX] * dx + bounds[BOUND_NY] * dy
    clear = r * (1.0 + 1e-9) + 1e-12
    if (d0 > clear and d1 > clear) or (d0 < -clear and d1 < -clear):
        return INF, 0.0, 0.0
    return sweep_segment(x, y, dx, dy, r, segment[0], segment[1], segment[2], segment[3], one_sided)


def _as_point(name: str, value: np.ndarray) -> tuple[float, float]:
    array = np.asarray(value, dtype=np.float64)
    if array.shape != (2,):
        raise ValueError(f"{name} must have shape (2,), got {array.shape}")
    return float(array[0]), float(array[1])


def sweep_circle_segment(
    center: np.ndarray,
    displacement: np.ndarray,
    radius: float,
    p0: np.ndarray,
    p1: np.ndarray,
    one_sided: bool = False,
) -> tuple[float, np.ndarray]:
    """First contact of a ball moving by ``displacement`` with the segment ``p0``-``p1``.

    Args:
        center: ball centre at the start, shape (2,).
        displacement: motion of the centre over the sweep, shape (2,).
        radius: ball radius (> 0).
        p0, p1: segment end points, shape (2,). Equal points behave as a single point.
        one_sided: if true the segment stops only a ball coming from the side of its normal
            ``rot+90(p1 - p0)`` (counter-clockwise); a ball from the other side, or one still
            partly through it, passes.

    Returns:
        ``(t, normal)``: ``t`` in [0, 1] is the fraction of the displacement at first contact and
        ``normal`` the unit contact normal from the segment towards the ball; ``t = math.inf``
        (normal zero) where the ball does not touch the segment during the sweep.
    """
    cx, cy = _as_point("center", center)
    dx, dy = _as_point("displacement", displacement)
    x0, y0 = _as_point("p0", p0)
    x1, y1 = _as_point("p1", p1)
    t, nx, ny = sweep_segment(cx, cy, dx, dy, float(radius), x0, y0, x1, y1, bool(one_sided))
    return t, np.array([nx, ny])


def sweep_circle_circle(
    center: np.ndarray, displacement: np.ndarray, radius: float, c: np.ndarray, R: float
) -> tuple[float, np.ndarray]:
    """First contact of a ball moving by ``displacement`` with a static circle ``(c, R)``.

    Same conventions as :func:`sweep_circle_segment`; the normal points from ``c`` to the ball.
    """
    cx, cy = _as_point("center", center)
    dx, dy = _as_point("displacement", displacement)
    ox, oy = _as_point("c", c)
    t, nx, ny = sweep_circle(cx, cy, dx, dy, float(radius), ox, oy, float(R))
    return t, np.array([nx, ny])
