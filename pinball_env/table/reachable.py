"""Where a ball can get to: the free space connected to the plunger, on a 1 mm grid.

A position can be clear of every wall and inside the outline and still be a place no ball can
reach: inside a slingshot's triangle, say, where a ball put by hand would bounce off the kicking
face for ever. ``free_space`` marks the grid cells a ball centre can occupy (farther than about
a radius from every two-sided wall, post and resting flipper; one-sided walls let a ball through
one way, so they do not separate regions) and keeps the region connected to the start by a flood
fill. The blocking radius is a cell and a half less than the ball's, so that a channel just wider
than the ball stays open on the grid: the test separates enclosed pockets, and leaves exact
clearance to the table's own overlap checks. Drains close the region too: a ball below the
drain line is out of play, and one put there would never cross it.
"""

import math

import numpy as np
from numba import njit

from pinball_env.physics.columns import (
    FLIPPER_BASE_RADIUS,
    FLIPPER_LENGTH,
    FLIPPER_PIVOT_X,
    FLIPPER_PIVOT_Y,
    FLIPPER_REST_ANGLE,
    FLIPPER_TIP_RADIUS,
)
from pinball_env.physics.flipper import flipper_distance, flipper_reach
from pinball_env.physics.sweep import segment_offset

CELL = 0.001  # [m] grid spacing


@njit(cache=True)
def _cells_near(x0, y0, x1, y1, reach, cell, n_rows, n_cols):
    """Rows r0:r1 and columns c0:c1 of the cells around segment P0-P1 grown by ``reach``."""
    c0 = max(int((min(x0, x1) - reach) / cell), 0)
    c1 = min(int((max(x0, x1) + reach) / cell) + 1, n_cols)
    r0 = max(int((min(y0, y1) - reach) / cell), 0)
    r1 = min(int((max(y0, y1) + reach) / cell) + 1, n_rows)
    return r0, r1, c0, c1


@njit(cache=True)
def _mark_near_segments(marked, segments, reach, cell, closed):
    """Mark the cells whose centre is closer than ``reach`` to a segment (or at ``reach`` too,
    when ``closed``)."""
    n_rows, n_cols = marked.shape
    for k in range(segments.shape[0]):
        x0, y0, x1, y1 = segments[k, 0], segments[k, 1], segments[k, 2], segments[k, 3]
        r0, r1, c0, c1 = _cells_near(x0, y0, x1, y1, reach, cell, n_rows, n_cols)
        for row in range(r0, r1):
            y = (row + 0.5) * cell
            for col in range(c0, c1):
                dx, dy = segment_offset((col + 0.5) * cell, y, x0, y0, x1, y1)
                distance2 = dx * dx + dy * dy
                if distance2 < reach * reach or (closed and distance2 == reach * reach):
                    marked[row, col] = True


@njit(cache=True)
def _block_discs(blocked, centres, radii, reach, cell):
    """Mark the cells whose centre is within ``reach`` of a disc."""
    n_rows, n_cols = blocked.shape
    for k in range(centres.shape[0]):
        cx, cy, outer = centres[k, 0], centres[k, 1], radii[k] + reach
        for row in range(
            max(int((cy - outer) / cell), 0), min(int((cy + outer) / cell) + 1, n_rows)
        ):
            for col in range(
                max(int((cx - outer) / cell), 0), min(int((cx + outer) / cell) + 1, n_cols)
            ):
                if math.hypot((col + 0.5) * cell - cx, (row + 0.5) * cell - cy) < outer:
                    blocked[row, col] = True


@njit(cache=True)
def _block_flippers(blocked, flippers, reach, cell):
    """Mark the cells whose centre is within ``reach`` of a flipper at rest."""
    n_rows, n_cols = blocked.shape
    for k in range(flippers.shape[0]):
        f = flippers[k]
        px, py = f[FLIPPER_PIVOT_X], f[FLIPPER_PIVOT_Y]
        extent = flipper_reach(f[FLIPPER_LENGTH], f[FLIPPER_BASE_RADIUS], f[FLIPPER_TIP_RADIUS])
        extent += reach
        for row in range(
            max(int((py - extent) / cell), 0), min(int((py + extent) / cell) + 1, n_rows)
        ):
            for col in range(
                max(int((px - extent) / cell), 0), min(int((px + extent) / cell) + 1, n_cols)
            ):
                d, _, _ = flipper_distance(
                    (col + 0.5) * cell, (row + 0.5) * cell, px, py, f[FLIPPER_LENGTH],
                    f[FLIPPER_BASE_RADIUS], f[FLIPPER_TIP_RADIUS], f[FLIPPER_REST_ANGLE],
                )  # fmt: skip
                if d < reach:
                    blocked[row, col] = True


@njit(cache=True)
def _flood(blocked, start_row, start_col):
    """Cells 4-connected to the start through unblocked cells."""
    n_rows, n_cols = blocked.shape
    reached = np.zeros_like(blocked)
    queue = np.empty((n_rows * n_cols, 2), dtype=np.int64)
    if blocked[start_row, start_col]:
        return reached
    reached[start_row, start_col] = True
    queue[0, 0], queue[0, 1] = start_row, start_col
    head, tail = 0, 1
    while head < tail:
        row, col = queue[head, 0], queue[head, 1]
        head += 1
        for dr, dc in ((1, 0), (-1, 0), (0, 1), (0, -1)):
            r, c = row + dr, col + dc
            if 0 <= r < n_rows and 0 <= c < n_cols and not blocked[r, c] and not reached[r, c]:
                reached[r, c] = True
                queue[tail, 0], queue[tail, 1] = r, c
                tail += 1
    return reached


def free_space(
    width: float,
    height: float,
    radius: float,
    two_sided_segments: np.ndarray,
    circles: np.ndarray,
    flippers: np.ndarray,
    start: tuple[float, float],
    drains: np.ndarray | None = None,
) -> np.ndarray:
    """(rows, cols) bool grid of the CELL-sized cells a ball centre can reach from ``start``
    while in play: ``drains`` (segments, (n, 4)) are lines its centre does not cross, since
    the ball leaves play there.

    Row i, column j is the cell centred on ((j + 0.5) CELL, (i + 0.5) CELL).
    """
    blocked = np.zeros((math.ceil(height / CELL), math.ceil(width / CELL)), dtype=np.bool_)
    reach = radius - 1.5 * CELL
    _mark_near_segments(
        blocked, np.ascontiguousarray(two_sided_segments, dtype=np.float64), reach, CELL, False
    )
    _block_discs(
        blocked,
        np.ascontiguousarray(circles[:, :2], dtype=np.float64),
        np.ascontiguousarray(circles[:, 2], dtype=np.float64),
        reach,
        CELL,
    )
    _block_flippers(blocked, np.ascontiguousarray(flippers, dtype=np.float64), reach, CELL)
    if drains is not None:  # a line the centre cannot cross: thick enough to close the grid
        _mark_near_segments(
            blocked, np.ascontiguousarray(drains, dtype=np.float64), CELL, CELL, False
        )
    return _flood(blocked, *cell_of(start, blocked.shape))


def touches(reached, segments, reach, cell):
    """Whether a reached cell lies within ``reach`` of one of the segments."""
    near = np.zeros_like(reached)
    _mark_near_segments(near, segments, reach, cell, True)
    return bool((near & reached).any())


def cell_of(point: tuple[float, float], shape: tuple[int, int]) -> tuple[int, int]:
    """(row, col) of the grid cell holding ``point``, clipped to the grid."""
    row = min(max(int(point[1] / CELL), 0), shape[0] - 1)
    col = min(max(int(point[0] / CELL), 0), shape[1] - 1)
    return row, col
