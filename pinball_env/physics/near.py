"""The broad phase: each ball's candidate set, the elements it can reach soon.

A ball's set is gathered around a point, its *zone*'s centre: every wall, post, flipper (at
any angle), drop target (standing or not) and sensor whose surface lies within the zone's
radius of it. Before each sweep the kernel checks that the ball's path (a segment of its
centre) lies in the zone shrunk by the ball's radius and a margin (:func:`path_in_zone`); then
an element outside the set is farther from every point of the path than the ball's radius and
the margin, where no sweep finds a contact nor a sensor a crossing. So only the set is swept,
in id order as before, and the contacts are bitwise those of sweeping everything. (A turning
flipper is swept whether in the set or not: its sweep can end in a cut wherever the path is,
see ``flipper.sweep_flipper``.) A path that leaves the zone (a ball sped up by a kick or a
flipper, a ball placed elsewhere, a frame later) gathers a new set where the ball is, reaching
as far as the ball goes in NEAR_TIME at its speed under gravity (or along its whole path, if
longer), and one ball radius more.

The set lives in the env's rows of ``Scratch`` (``near``, ``near_ends``, ``near_zone``) and
carries over from frame to frame; ``World`` clears the zone when an env's table changes. A zone
of infinite radius holds every element for good: what :func:`gather_near` with
``reach = inf`` gathers, the tests' brute force.
"""

import math

from numba import njit

from pinball_env.physics.columns import (
    FLIPPER_BASE_RADIUS,
    FLIPPER_LENGTH,
    FLIPPER_PIVOT_X,
    FLIPPER_PIVOT_Y,
    FLIPPER_TIP_RADIUS,
)
from pinball_env.physics.flipper import flipper_reach
from pinball_env.physics.sweep import norm, segment_offset

# How far ahead a new set reaches: the ball's travel in this time [s] (about a frame at 60 Hz:
# fewer gathers, each over every element, against more candidates in every sweep; measured).
NEAR_TIME = 0.02
# The sweeps find contacts within the ball's radius of a surface, flipper contacts within half
# the skin more (step.FLIPPER_CONTACT_TOLERANCE twice): twice the skin, and a nanometre for
# rounding, covers both [m].
NEAR_SKINS = 2.0
NEAR_ROUNDING = 1e-9
# Groups of a set, in order, each ending at its entry of ``Scratch.near_ends``.
NEAR_SOLIDS, NEAR_FLIPPERS, NEAR_DROP_TARGETS, NEAR_SENSORS = range(4)


@njit(cache=True, inline="always")
def near_reach(vx, vy, duration, r, gravity, skin):
    """The radius of a new zone for a ball about to move at (vx, vy) [m/s] for ``duration``
    [s] under ``gravity`` [m/s^2]: its travel in that time or NEAR_TIME, whichever is longer,
    and its radius, the margin and one radius more [m]. The zone holds the path it is
    gathered for, with a radius to spare."""
    time = max(duration, NEAR_TIME)
    travel = norm(vx, vy) * time + 0.5 * gravity * NEAR_TIME * NEAR_TIME
    return travel + 2.0 * r + NEAR_SKINS * skin + NEAR_ROUNDING


@njit(cache=True, inline="always")
def path_in_zone(x, y, dx, dy, zone, r, skin):
    """Whether the ball's centre path from (x, y) by (dx, dy) lies within the zone's radius,
    less the ball's radius ``r`` and the margin, of its centre (a disc holds a segment when it
    holds both ends). False for a NaN path; an infinite zone holds any other."""
    limit = zone[2] - r - NEAR_SKINS * skin - NEAR_ROUNDING
    ax = x - zone[0]
    ay = y - zone[1]
    bx = ax + dx
    by = ay + dy
    return (
        limit >= 0.0 and ax * ax + ay * ay <= limit * limit and bx * bx + by * by <= limit * limit
    )


@njit(cache=True, inline="always")
def gather_segments(x, y, reach, every, segments, near, count):
    """Append to ``near`` (from ``count`` on) the index of each of ``segments`` ((n, 4): x0,
    y0, x1, y1) that passes within ``reach`` of (x, y) (each, with ``every``); returns the new
    count."""
    for j in range(segments.shape[0]):
        s = segments[j]
        gx, gy = segment_offset(x, y, s[0], s[1], s[2], s[3])
        if every or gx * gx + gy * gy <= reach * reach:
            near[count] = j
            count += 1
    return count


@njit(cache=True)
def gather_near(x, y, reach, geometry, near, ends, zone):
    """Gather the set of a zone of radius ``reach`` around (x, y) into ``near`` and ``ends``
    (an env's rows of ``Scratch.near`` and ``Scratch.near_ends``) and record the zone in
    ``zone``: walls and posts by element id, then flippers, drop targets and sensors by their
    index.
    A non-finite point or reach (or an infinite one) takes every element."""
    every = not math.isfinite(x + y) or not reach < math.inf  # (NaN too)
    segments = geometry.segments
    count = gather_segments(x, y, reach, every, segments, near, 0)
    circles = geometry.circles
    for j in range(circles.shape[0]):
        c = circles[j]
        if every or norm(x - c[0], y - c[1]) - c[2] <= reach:
            near[count] = segments.shape[0] + j
            count += 1
    ends[NEAR_SOLIDS] = count
    flippers = geometry.flippers
    for j in range(flippers.shape[0]):
        f = flippers[j]
        extent = flipper_reach(f[FLIPPER_LENGTH], f[FLIPPER_BASE_RADIUS], f[FLIPPER_TIP_RADIUS])
        if every or norm(x - f[FLIPPER_PIVOT_X], y - f[FLIPPER_PIVOT_Y]) - extent <= reach:
            near[count] = j
            count += 1
    ends[NEAR_FLIPPERS] = count
    count = gather_segments(x, y, reach, every, geometry.drop_targets, near, count)
    ends[NEAR_DROP_TARGETS] = count
    count = gather_segments(x, y, reach, every, geometry.sensors, near, count)
    ends[NEAR_SENSORS] = count
    zone[0] = x
    zone[1] = y
    zone[2] = reach
