"""Lengths rounded for table files, and the elements placed so far, for the clearance of the
next one."""

from __future__ import annotations

import itertools
import math

from pinball_env.physics import point_segment_distance


def mm(value: float) -> float:
    """A length rounded to 0.01 mm, so that files are short and the same on every machine."""
    return round(float(value), 5)


def point(x: float, y: float) -> list[float]:
    """A point of a table file, its coordinates rounded by :func:`mm`."""
    return [mm(x), mm(y)]


class Obstacles:
    """The segments and circles placed so far, for the clearance of the next element."""

    def __init__(self) -> None:
        self.segments: list[tuple[float, float, float, float]] = []
        self.circles: list[tuple[float, float, float]] = []

    def add_wall(self, points: list[list[float]], closed: bool = False) -> None:
        ends = points + points[:1] if closed else points
        for (x0, y0), (x1, y1) in itertools.pairwise(ends):
            self.segments.append((x0, y0, x1, y1))

    def add_circle(self, center: list[float], radius: float) -> None:
        self.circles.append((*center, radius))

    def circle_gap(self, x: float, y: float, radius: float) -> float:
        """The smallest gap between a circle and everything placed."""
        gaps = [point_segment_distance(x, y, *s) - radius for s in self.segments]
        gaps += [math.hypot(x - cx, y - cy) - radius - r for cx, cy, r in self.circles]
        return min(gaps, default=math.inf)

    def segment_gap(self, segment: tuple[float, float, float, float]) -> float:
        """The smallest gap between a segment and everything placed."""
        gaps = [segment_distance(segment, s) for s in self.segments]
        gaps += [point_segment_distance(cx, cy, *segment) - r for cx, cy, r in self.circles]
        return min(gaps, default=math.inf)


def segment_distance(a: tuple[float, ...], b: tuple[float, ...]) -> float:
    """Distance between two segments (0 if they cross)."""
    ax0, ay0, ax1, ay1 = a
    bx0, by0, bx1, by1 = b

    def side(px: float, py: float, qx: float, qy: float, rx: float, ry: float) -> float:
        return (qx - px) * (ry - py) - (qy - py) * (rx - px)

    d1, d2 = side(ax0, ay0, ax1, ay1, bx0, by0), side(ax0, ay0, ax1, ay1, bx1, by1)
    d3, d4 = side(bx0, by0, bx1, by1, ax0, ay0), side(bx0, by0, bx1, by1, ax1, ay1)
    if d1 * d2 < 0.0 and d3 * d4 < 0.0:
        return 0.0
    return min(
        point_segment_distance(ax0, ay0, *b), point_segment_distance(ax1, ay1, *b),
        point_segment_distance(bx0, by0, *a), point_segment_distance(bx1, by1, *a),
    )  # fmt: skip
