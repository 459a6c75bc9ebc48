"""The table's geometry checks: what ties the elements' places together (no zero-length segment,
a ball's start and the plunger clear of every element and inside the outline, a two-sided
outline, no flipper pivot in a wall, nothing in a flipper's swing, a launch path that one-sided
walls let through, the places where saucers and locks hold balls clear of all that and of one
another: :func:`check_held`), and :func:`check_ball_state`, the same checks on a ball state given
at run time.

The swing check runs on a numba kernel (:func:`_swing_clearance`), bounded in work by
``SWING_SAMPLES``.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping
from typing import TYPE_CHECKING, Any

import numpy as np
from numba import njit

from pinball_env.physics import flipper_distance, flipper_reach, point_segment_distance
from pinball_env.table.fields import Where, in_playfield, short, velocity_pair
from pinball_env.table.parts import Flipper, Plunger, Post, Wall, enclosure, inside
from pinball_env.table.reachable import cell_of

if TYPE_CHECKING:  # (the model reads the kinds, which check elements here)
    from pinball_env.table.model import Table

# A wall or post must keep this far from the area a flipper sweeps [m]. The check samples the
# swing and each segment at most SWING_SAMPLES times, so on a large flipper it keeps a wall a
# few sample steps away (about 1/100 of the swing's arc) rather than do unbounded work.
SWING_CLEARANCE = 3e-4
SWING_SAMPLES = 200


def check_lengths(segments: Iterable[tuple[float, ...]], loc: Where) -> None:
    """No segment has both ends at one point."""
    for i, (x0, y0, x1, y1) in enumerate(segments):
        if x0 == x1 and y0 == y1:
            loc.fail(f"segment {i} has zero length (both ends at ({x0:g}, {y0:g}))")


def check_placed(
    center: tuple[float, float],
    radius: float,
    elements: Mapping[str, tuple[Any, ...]],
    loc: Where,
) -> None:
    """A ball of ``radius`` at ``center`` is clear of every element and inside the outline."""
    walls = solid_walls(elements)
    _check_clear(center, radius, walls, elements["posts"], elements["flippers"], loc)
    _check_enclosed(center, elements["walls"], loc)


def check_held(
    places: Iterable[tuple[Where, tuple[float, float]]],
    radius: float,
    elements: Mapping[str, tuple[Any, ...]],
    plunger: Plunger | None,
) -> None:
    """The places where balls of ``radius`` are held (saucer centres, lock slots, each with its
    path) are each clear of every element, inside the outline and out of every flipper's swing
    (a held ball is immovable: a rising flipper would push into it), and at least a ball's
    diameter from one another and from the plunger's position (balls wait there while others
    are held)."""
    places = list(places)
    if not places:
        return
    for loc, center in places:
        check_placed(center, radius, elements, loc)
    for i, (loc, center) in enumerate(places):
        others = places[:i]
        if plunger is not None:
            others.append((Where(loc.source, "plunger.position"), plunger.position))
        for other, c in others:
            gap = math.dist(center, c)
            if gap < 2.0 * radius:
                loc.fail(
                    f"a ball held at ({center[0]:g}, {center[1]:g}) overlaps one at {other.path} "
                    f"(centres {gap:g} apart < the ball's diameter {2.0 * radius:g})"
                )
    circles = np.array([(*c, radius) for _, c in places], dtype=np.float64).reshape(-1, 3)
    for flipper in elements["flippers"]:
        px, py = flipper.pivot
        gap, k = _swing_clearance(
            px, py, flipper.length, flipper.base_radius, flipper.tip_radius,
            math.radians(flipper.rest_angle), math.radians(flipper.up_angle),
            np.zeros((0, 4)), circles, SWING_CLEARANCE / 2.0, SWING_SAMPLES,
        )  # fmt: skip
        if gap < SWING_CLEARANCE:
            places[k][0].fail(
                f"a ball held here lies in flipper {short(flipper.name)}'s swing (or too close "
                "to be sure it does not): a rising flipper would push into an immovable ball"
            )


def check_outline(walls: tuple[Wall, ...], top: Where) -> None:
    """The outline (the closed wall enclosing the largest area) is two-sided: a one-sided one
    lets the ball through one way, out of the table."""
    outline = enclosure(walls)
    if outline is not None and outline.one_sided:
        i = walls.index(outline)
        top.key("walls").index(i, outline.name).key("one_sided").fail(
            "the table's outline (its largest closed wall) must be two-sided, or the ball "
            "leaves the table through it"
        )


def check_swings(groups: Mapping[str, tuple[Any, ...]], top: Where) -> None:
    """No wall or post lies across the area a flipper sweeps between its stops (or within
    SWING_CLEARANCE of it): a rising flipper would hit a ball through it."""
    walls, posts = groups["walls"], groups["posts"]
    segments = np.array([s for _, _, s in _wall_segments(walls)], dtype=np.float64).reshape(-1, 4)
    circles = np.array([(*p.center, p.radius) for p in posts], dtype=np.float64).reshape(-1, 3)
    owners = [f"wall {short(w.name)} segment {j}" for w, j, _ in _wall_segments(walls)]
    owners += [f"post {short(p.name)}" for p in posts]
    for i, flipper in enumerate(groups["flippers"]):
        px, py = flipper.pivot
        gap, element = _swing_clearance(
            px, py, flipper.length, flipper.base_radius, flipper.tip_radius,
            math.radians(flipper.rest_angle), math.radians(flipper.up_angle), segments,
            circles, SWING_CLEARANCE / 2.0, SWING_SAMPLES,
        )  # fmt: skip
        if gap < SWING_CLEARANCE:
            top.key("flippers").index(i, flipper.name).fail(
                f"{owners[element]} lies in the flipper's swing (or too close to be sure it "
                "does not): a rising flipper would hit a ball through it"
            )


@njit(cache=True)
def _swing_clearance(px, py, length, rb, rt, a0, a1, segments, circles, step, most):
    """A lower bound of the distance between a flipper swinging from angle a0 to a1 and each
    segment and circle, the smallest of them: ``(distance, element)``, segments first then
    circles (``inf, -1`` when none is in reach). The swing is sampled at angles ``step`` of arc
    apart at the flipper's reach and the segments at points ``step`` apart, at most ``most``
    of each (so the work is bounded), and each sampled distance is lowered by twice the
    sampling step used: no point of the swing or the segment is farther from a sample."""
    reach = flipper_reach(length, rb, rt)
    arc = abs(a1 - a0) * reach
    n_angles = min(int(arc / step) + 2, most)
    angle_step = arc / (n_angles - 1)
    best = math.inf
    best_element = -1
    for k in range(segments.shape[0]):
        x0, y0, x1, y1 = segments[k, 0], segments[k, 1], segments[k, 2], segments[k, 3]
        if point_segment_distance(px, py, x0, y0, x1, y1) > reach + step:
            continue
        span = math.hypot(x1 - x0, y1 - y0)
        n_points = min(int(span / step) + 2, most)
        margin = 2.0 * max(angle_step, span / (n_points - 1))
        for i in range(n_points):
            s = i / (n_points - 1)
            x = x0 + s * (x1 - x0)
            y = y0 + s * (y1 - y0)
            if math.hypot(x - px, y - py) > reach + margin:
                continue
            for n in range(n_angles):
                angle = a0 + (a1 - a0) * n / (n_angles - 1)
                d, _, _ = flipper_distance(x, y, px, py, length, rb, rt, angle)
                if d - margin < best:
                    best, best_element = d - margin, k
    for k in range(circles.shape[0]):
        for n in range(n_angles):
            angle = a0 + (a1 - a0) * n / (n_angles - 1)
            d, _, _ = flipper_distance(circles[k, 0], circles[k, 1], px, py, length, rb, rt, angle)
            d -= circles[k, 2] + 2.0 * angle_step
            if d < best:
                best, best_element = d, segments.shape[0] + k
    return best, best_element


def _wall_segments(
    walls: tuple[Wall, ...],
) -> Iterable[tuple[Wall, int, tuple[float, float, float, float]]]:
    """(wall, index of the segment in the wall, segment) for every segment of every wall."""
    for wall in walls:
        for i, segment in enumerate(wall.segments()):
            yield wall, i, segment


def check_pivots(flippers: tuple[Flipper, ...], walls: tuple[Wall, ...], top: Where) -> None:
    """No flipper's base circle (around its pivot) overlaps a wall."""
    for i, flipper in enumerate(flippers):
        for wall, j, segment in _wall_segments(walls):
            distance = _segment_distance(flipper.pivot, segment)
            if distance < flipper.base_radius:
                x, y = flipper.pivot
                top.key("flippers").index(i, flipper.name).key("pivot").fail(
                    f"pivot ({x:g}, {y:g}) overlaps wall {wall.name!r} segment {j} "
                    f"(distance {distance:g} < base radius {flipper.base_radius:g})"
                )


def _check_clear(
    center: tuple[float, float],
    radius: float,
    walls: tuple[Wall, ...],
    posts: tuple[Post, ...],
    flippers: tuple[Flipper, ...],
    loc: Where,
) -> None:
    """A ball of ``radius`` at ``center`` touches no wall, no post and no flipper at rest."""
    for wall, i, segment in _wall_segments(walls):
        distance = _segment_distance(center, segment)
        if distance < radius:
            loc.fail(
                f"ball overlaps wall {wall.name!r} segment {i} "
                f"(distance {distance:g} < ball radius {radius:g})"
            )
    for post in posts:
        gap = math.dist(center, post.center) - post.radius
        if gap < radius:
            loc.fail(
                f"ball overlaps post {post.name!r} "
                f"(distance to its surface {gap:g} < ball radius {radius:g})"
            )
    for flipper in flippers:
        gap = flipper.distance(center, flipper.rest_angle)
        if gap < radius:
            loc.fail(
                f"ball overlaps flipper {flipper.name!r} at its rest angle "
                f"(distance to its surface {gap:g} < ball radius {radius:g})"
            )


def _check_enclosed(point: tuple[float, float], walls: tuple[Wall, ...], loc: Where) -> None:
    """A ball centre lies inside the table's outline (when it has one)."""
    outline = enclosure(walls)
    if outline is not None and not inside(point, outline.points):
        loc.fail(f"({point[0]:g}, {point[1]:g}) is outside the table's outline {outline.name!r}")


def check_ball_state(
    table: Table, position: object, velocity: object, source: str
) -> tuple[tuple[float, float], tuple[float, float]]:
    """Validate a ball state given at run time (e.g. reset options): ``position`` a finite [x, y]
    in the playfield and its outline, clear of every wall, post and resting flipper, and where a
    ball from the plunger can get to; ``velocity`` a finite pair no faster than MAX_BALL_SPEED.
    Errors name ``source``, e.g. ``reset options: ball_position: ...``."""
    where = Where(source)
    point = in_playfield(position, where.key("ball_position"), table.width, table.height)
    elements = {"walls": table.solid_walls, "posts": table.posts, "flippers": table.flippers}
    check_placed(point, table.ball.radius, elements, where.key("ball_position"))
    if not table.free_space[cell_of(point, table.free_space.shape)]:
        where.key("ball_position").fail(
            f"({point[0]:g}, {point[1]:g}) cannot be reached in play from the plunger: it is "
            "walled off (inside a slingshot, say) or on the far side of a drain (or within a "
            "millimetre of it)"
        )
    return point, velocity_pair(velocity, where.key("ball_velocity"))


def check_launch_path(plunger: Plunger, walls: tuple[Wall, ...], top: Where) -> None:
    """One-sided segments across the launch path (straight up from the plunger) let it through.

    A one-sided segment stops a ball coming from the side of its normal rot+90(P1 - P0) =
    (y0 - y1, x1 - x0). A ball launched along +y meets it from that side when the normal's y
    component x1 - x0 is negative.
    """
    px, py = plunger.position
    for i, wall in enumerate(walls):
        if not wall.one_sided:
            continue
        for j, (x0, y0, x1, y1) in enumerate(wall.segments()):
            if x0 == x1 or not min(x0, x1) <= px <= max(x0, x1):
                continue  # parallel to the path, or beside it
            crossing_y = y0 + (px - x0) * (y1 - y0) / (x1 - x0)
            if crossing_y > py and x1 < x0:
                top.key("walls").index(i, wall.name).fail(
                    f"one-sided segment {j} blocks the plunger's launch path "
                    "(its normal faces the plunger; reverse its points)"
                )


def _segment_distance(p: tuple[float, float], segment: tuple[float, float, float, float]) -> float:
    return float(point_segment_distance(p[0], p[1], *segment))


def solid_walls(elements: Mapping[str, tuple[Any, ...]]) -> tuple[Wall, ...]:
    """The walls with the stand-up and drop targets (standing) as walls, for the checks."""
    targets = tuple(t.as_wall() for t in elements.get("standup_targets", ()))
    banks = tuple(w for bank in elements.get("drop_targets", ()) for w in bank.walls())
    return elements["walls"] + targets + banks
