"""The compiled painters (numba; no display, no pygame): lines, discs and flippers rasterised
into uint8 images, through the kernel's own ``segment_offset`` and ``flipper_distance``; the
player's plunger, and the static layer moved by whole pixels for the cabinet's shake.

Image row 0 is the top of the table (y = ``table_height``) and x grows to the right; the centre of
pixel (row i, column j) is the world point ((j + 0.5) / sx, table_height - (i + 0.5) / sy), with
``sx`` and ``sy`` the pixels per metre. Shapes are sized in pixels so that they stay visible at
any resolution, including a stretched 84x84 observation: a line covers every pixel centre within
``max(MIN_LINE_HALF_WIDTH, its half-width)`` of it, and a disc or flipper every pixel centre
inside it or within ``OUTLINE_BAND`` of its outline.
"""

import math

from numba import njit

from pinball_env.physics.flipper import flipper_distance
from pinball_env.physics.sweep import segment_offset

MIN_LINE_HALF_WIDTH = 0.6  # [px]: a line is never thinner than about one pixel
OUTLINE_BAND = 0.5  # [px]: discs and flippers also cover pixels this close to their outline


@njit(cache=True)
def _pixel_box(x0, y0, x1, y1, margin, sx, sy, table_height, width, height):
    """Rows r0:r1 and columns c0:c1 of the pixels around the world box [x0, x1] x [y0, y1],
    widened by ``margin`` pixels; an empty range if that misses the image."""
    if not math.isfinite(x0 + y0 + x1 + y1):
        return 0, 0, 0, 0
    c0 = max(0, math.floor(x0 * sx) - margin)
    c1 = min(width, math.ceil(x1 * sx) + margin)
    r0 = max(0, math.floor((table_height - y1) * sy) - margin)
    r1 = min(height, math.ceil((table_height - y0) * sy) + margin)
    if c0 >= c1 or r0 >= r1:
        return 0, 0, 0, 0
    return r0, r1, c0, c1


@njit(cache=True)
def paint_line(image, x0, y0, x1, y1, half_width, colour, sx, sy, table_height):
    """Paint the pixels whose centre lies within ``half_width`` px of the segment, measured in
    pixel coordinates so that a line keeps its width in a stretched image (the kernel's own
    ``segment_offset``)."""
    half_width = max(MIN_LINE_HALF_WIDTH, half_width)
    height, width = image.shape[0], image.shape[1]
    margin = math.ceil(half_width)
    r0, r1, c0, c1 = _pixel_box(
        min(x0, x1), min(y0, y1), max(x0, x1), max(y0, y1), margin, sx, sy, table_height,
        width, height,
    )  # fmt: skip
    # Segment ends in pixel coordinates (column, row).
    ax, ay = x0 * sx, (table_height - y0) * sy
    bx, by = x1 * sx, (table_height - y1) * sy
    for row in range(r0, r1):
        for col in range(c0, c1):
            gx, gy = segment_offset(col + 0.5, row + 0.5, ax, ay, bx, by)
            if gx * gx + gy * gy <= half_width * half_width:
                image[row, col, :] = colour


@njit(cache=True)
def paint_disc(image, cx, cy, radius, colour, sx, sy, table_height):
    """Paint a world disc (an ellipse in a stretched image) plus its 0.5 px outline band."""
    height, width = image.shape[0], image.shape[1]
    r0, r1, c0, c1 = _pixel_box(
        cx - radius, cy - radius, cx + radius, cy + radius, 1, sx, sy, table_height, width,
        height,
    )  # fmt: skip
    for row in range(r0, r1):
        dy = table_height - (row + 0.5) / sy - cy
        dy2 = dy * dy
        for col in range(c0, c1):
            dx = (col + 0.5) / sx - cx
            dx2 = dx * dx
            distance = math.sqrt(dx2 + dy2)
            # Outside, the pixel distance to the outline is to first order the world distance
            # d = |q| - r over the size of its gradient in pixel coordinates, |(nx/sx, ny/sy)|
            # with n = q / |q| (exact when sx = sy). Both sides times |q| to avoid dividing.
            gradient = math.sqrt(dx2 / (sx * sx) + dy2 / (sy * sy))
            if (distance - radius) * distance <= OUTLINE_BAND * gradient:
                image[row, col, :] = colour


@njit(cache=True)
def paint_flipper(image, px, py, length, rb, rt, angle, colour, sx, sy, table_height):
    """Paint a flipper turned to ``angle`` about its pivot (px, py), plus its 0.5 px outline
    band (the kernel's own ``flipper_distance``)."""
    height, width = image.shape[0], image.shape[1]
    tx, ty = px + length * math.cos(angle), py + length * math.sin(angle)
    r0, r1, c0, c1 = _pixel_box(
        min(px - rb, tx - rt), min(py - rb, ty - rt), max(px + rb, tx + rt),
        max(py + rb, ty + rt), 1, sx, sy, table_height, width, height,
    )  # fmt: skip
    for row in range(r0, r1):
        y = table_height - (row + 0.5) / sy
        for col in range(c0, c1):
            d, nx, ny = flipper_distance((col + 0.5) / sx, y, px, py, length, rb, rt, angle)
            # The outline band in pixels: the distance's gradient (the unit normal) in pixels.
            if d <= OUTLINE_BAND * math.hypot(nx / sx, ny / sy):
                image[row, col, :] = colour


@njit(cache=True)
def _copy_shifted(image, static, rows, cols, background):
    """``image`` = ``static`` moved down ``rows`` and right ``cols`` pixels, the uncovered band
    ``background`` (a cabinet's shake moves the whole playfield)."""
    if rows == 0 and cols == 0:
        image[...] = static
        return
    height, width = static.shape[0], static.shape[1]
    image[...] = background
    r0, r1 = max(0, rows), min(height, height + rows)
    c0, c1 = max(0, cols), min(width, width + cols)
    if r0 < r1 and c0 < c1:
        image[r0:r1, c0:c1] = static[r0 - rows : r1 - rows, c0 - cols : c1 - cols]


@njit(cache=True)
def paint_plunger(image, x, tip, plunger, colour, sx, sy, table_height):
    """The player's plunger at ``x`` [m], its tip (a bar across the shooter lane) with its top
    edge at height ``tip`` [m]; ``plunger`` holds (x at rest [m], the rod's half-width [px], the
    tip's half-length [m], its half-width [px]). The rod runs down from the tip out of the
    bottom of the picture, as a real one leaves the cabinet through its front."""
    rod, reach, bar = plunger[1], plunger[2], plunger[3]
    # The bar's top edge at the tip, where the ball sits, raised by the ball's 0.5 px outline
    # band so that the two touch on screen.
    bar_y = tip - (bar - OUTLINE_BAND) / sy
    # The rod's round end kept under the bar's top edge.
    rod_top = bar_y - max(0.0, rod - bar) / sy
    paint_line(image, x, rod_top, x, -2.0 / sy, rod, colour, sx, sy, table_height)
    paint_line(image, x - reach, bar_y, x + reach, bar_y, bar, colour, sx, sy, table_height)


@njit(cache=True)
def _draw_env(images, env, static, balls, visible, angles, flippers, radius, flipper_colour,
              ball_colour, sx, sy, table_height, shifts, tips, plunger, plunger_colour,
              background):  # fmt: skip
    """One env's frame: the static layer (shifted by ``shifts[env]`` (rows, columns)), its
    flippers, its plunger (where ``tips[env]`` is finite) and its ball where visible, the
    moving parts moved with the static layer."""
    rows, cols = shifts[env, 0], shifts[env, 1]
    _copy_shifted(images[env], static, rows, cols, background)
    # The pixel shift in world units (0.0 without a shake: every coordinate as it was).
    dx, dy = cols / sx, -rows / sy
    for j in range(flippers.shape[0]):
        f = flippers[j]
        paint_flipper(
            images[env], f[0] + dx, f[1] + dy, f[2], f[3], f[4], angles[env, j], flipper_colour,
            sx, sy, table_height,
        )  # fmt: skip
    if math.isfinite(tips[env]):
        paint_plunger(
            images[env], plunger[0] + dx, tips[env] + dy, plunger, plunger_colour, sx, sy,
            table_height,
        )  # fmt: skip
    if visible[env]:
        paint_disc(
            images[env], balls[env, 0] + dx, balls[env, 1] + dy, radius, ball_colour, sx, sy,
            table_height,
        )  # fmt: skip


@njit(cache=True, nogil=True)
def draw_moving_parts(images, static, balls, visible, angles, flippers, radius, flipper_colour,
                       ball_colour, sx, sy, table_height, shifts, tips, plunger, plunger_colour,
                       background, start, stop):  # fmt: skip
    """The frames of envs ``start`` to ``stop`` (see :func:`_draw_env`). The GIL is released,
    so threads can draw disjoint ranges at once."""
    for env in range(start, stop):
        _draw_env(
            images, env, static, balls, visible, angles, flippers, radius, flipper_colour,
            ball_colour, sx, sy, table_height, shifts, tips, plunger, plunger_colour,
            background,
        )  # fmt: skip
