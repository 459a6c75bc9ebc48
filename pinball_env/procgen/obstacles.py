"""Lengths rounded for table files, and the elements placed so far, for the clearance of the
next one."""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence

import numpy as np
from numba import njit

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
        # The lists as arrays, for the compiled gaps, kept until they grow.
        self._rows = (np.empty((0, 4)), np.empty((0, 3)))

    def add_wall(self, points: list[list[float]], closed: bool = False) -> None:
        ends = points + points[:1] if closed else points
        for (x0, y0), (x1, y1) in itertools.pairwise(ends):
            self.segments.append((x0, y0, x1, y1))

    def add_circle(self, center: list[float], radius: float) -> None:
        x, y = center
        self.circles.append((x, y, radius))

    def circle_gap(self, x: float, y: float, radius: float) -> float:
        """The smallest gap between a circle and everything placed."""
        gaps = [point_segment_distance(x, y, *s) - radius for s in self.segments]
        gaps += [math.hypot(x - cx, y - cy) - radius - r for cx, cy, r in self.circles]
        return min(gaps, default=math.inf)

    def segment_gap(self, segment: Sequence[float]) -> float:
        """The smallest gap between a segment and everything placed."""
        segments, circles = self._rows
        if len(segments) != len(self.segments) or len(circles) != len(self.circles):
            segments = np.array(self.segments, dtype=np.float64).reshape(-1, 4)
            circles = np.array(self.circles, dtype=np.float64).reshape(-1, 3)
            self._rows = segments, circles
        return _segment_gap(np.array(segment, dtype=np.float64), segments, circles)


@njit(cache=True)
def _segment_gap(segment: np.ndarray, segments: np.ndarray, circles: np.ndarray) -> float:
    """:meth:`Obstacles.segment_gap` of ``segment`` (4,) with ``segments`` (n, 4) and
    ``circles`` (m, 3) placed, compiled: layouts try many places against many elements."""
    x0, y0, x1, y1 = segment[0], segment[1], segment[2], segment[3]
    gap = math.inf
    for s in segments:
        gap = min(gap, segment_distance((x0, y0, x1, y1), (s[0], s[1], s[2], s[3])))
    for cx, cy, r in circles:
        gap = min(gap, point_segment_distance(cx, cy, x0, y0, x1, y1) - r)
    return gap


@njit(cache=True)
def _side(px: float, py: float, qx: float, qy: float, rx: float, ry: float) -> float:
    """Which side of the line P-Q the point R is on (the sign), twice the triangle's area."""
    return (qx - px) * (ry - py) - (qy - py) * (rx - px)


@njit(cache=True)
def segment_distance(a: tuple[float, ...], b: tuple[float, ...]) -> float:
    """Distance between two segments (0 if they cross)."""
    ax0, ay0, ax1, ay1 = a
    bx0, by0, bx1, by1 = b
    d1, d2 = _side(ax0, ay0, ax1, ay1, bx0, by0), _side(ax0, ay0, ax1, ay1, bx1, by1)
    d3, d4 = _side(bx0, by0, bx1, by1, ax0, ay0), _side(bx0, by0, bx1, by1, ax1, ay1)
    if d1 * d2 < 0.0 and d3 * d4 < 0.0:
        return 0.0
    return min(
        point_segment_distance(ax0, ay0, bx0, by0, bx1, by1),
        point_segment_distance(ax1, ay1, bx0, by0, bx1, by1),
        point_segment_distance(bx0, by0, ax0, ay0, ax1, ay1),
        point_segment_distance(bx1, by1, ax0, ay0, ax1, ay1),
    )
