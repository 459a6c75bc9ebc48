"""Pixel pictures of a table and its moving parts, for observations and for watching.

:class:`Renderer` rasterises with numpy (no display, no pygame; flippers through the kernel's
compiled ``flipper_distance``): the static layer (playfield, sensors, walls, posts) once, then
per frame a copy of it with the flippers and the ball painted over their pixel bounding boxes.
:class:`Window` is a thin pygame window for ``render_mode="human"``.

Image row 0 is the top of the table (y = height) and x grows to the right; the centre of pixel
(row i, column j) is the world point ((j + 0.5) * width / W, height - (i + 0.5) * height / H).
Shapes are sized in pixels so that they stay visible at any resolution, including a stretched
84x84 observation: a line covers every pixel centre within ``max(0.6 px, its half-width)`` of it,
and a disc or flipper every pixel centre inside it or within 0.5 px of its outline.
"""

import math
import os
from collections.abc import Sequence

import numpy as np
from numba import njit

from pinball_env.physics.flipper import flipper_distance
from pinball_env.physics.sweep import segment_offset
from pinball_env.table import Table

Colour = Sequence[int] | np.ndarray  # (R, G, B), or (luma,) for the grayscale layer

# Colours (R, G, B). Chosen so that in grayscale the ball is the brightest thing and the flippers
# stand well clear of the background.
BACKGROUND = (16, 20, 32)
WALL = (165, 180, 205)
ONE_SIDED = (240, 135, 45)
KICKER = (225, 55, 65)
POST = (40, 155, 140)
SENSOR = (62, 72, 92)
DRAIN = (92, 52, 62)
FLIPPER = (250, 195, 60)
BALL = (248, 248, 252)

# ITU-R BT.601 luma weights (as PIL's "L" mode and OpenCV use), in thousandths so that the
# grayscale image is computed in exact integer arithmetic.
LUMA_WEIGHTS = (299, 587, 114)

WALL_HALF_WIDTH = 0.002  # [m]: walls are drawn 4 mm wide (more where a pixel is coarser)
SENSOR_HALF_WIDTH = 0.001  # [m]
MIN_LINE_HALF_WIDTH = 0.6  # [px]: a line is never thinner than about one pixel
OUTLINE_BAND = 0.5  # [px]: discs and flippers also cover pixels this close to their outline


def luminance(colour: Colour) -> np.ndarray:
    """BT.601 luma of uint8 RGB values (last axis), rounded, as uint8 with that axis kept as 1."""
    rgb = np.asarray(colour, dtype=np.uint32)
    luma = (rgb * np.array(LUMA_WEIGHTS, dtype=np.uint32)).sum(axis=-1, keepdims=True)
    return ((luma + 500) // 1000).astype(np.uint8)


_FLIPPER_LUMA = luminance(FLIPPER)
_BALL_LUMA = luminance(BALL)


def render_size(table: Table, pixels_per_metre: float = 600.0) -> tuple[int, int]:
    """(width, height) in pixels for an aspect-correct picture of the table."""
    if not pixels_per_metre > 0.0:
        raise ValueError(f"pixels_per_metre must be positive, got {pixels_per_metre!r}")
    return (
        max(1, round(table.width * pixels_per_metre)),
        max(1, round(table.height * pixels_per_metre)),
    )


class Renderer:
    """Draws a table into (height, width, 3) uint8 frames; the table fills the image (stretched if
    the aspect differs). The static layer (playfield, walls, posts, sensors) is rasterised once in
    __init__; each frame copies it and draws the flippers and the ball."""

    def __init__(self, table: Table, width: int, height: int) -> None:
        if width < 1 or height < 1:
            raise ValueError(f"image size must be at least 1x1, got {width}x{height}")
        self.table = table
        self.width = int(width)
        self.height = int(height)
        self._sx = self.width / table.width  # [px/m]
        self._sy = self.height / table.height
        # World coordinates of the pixel centres, by column and by row.
        self._xs = (np.arange(self.width) + 0.5) / self._sx
        self._ys = table.height - (np.arange(self.height) + 0.5) / self._sy
        # Anisotropic images: a world length maps to pixels at the geometric mean scale.
        scale = math.sqrt(self._sx * self._sy)
        self._flippers = [
            (f.pivot[0], f.pivot[1], f.length, f.base_radius, f.tip_radius) for f in table.flippers
        ]

        rgb = np.empty((self.height, self.width, 3), dtype=np.uint8)
        rgb[...] = BACKGROUND
        for sensor in table.sensors:
            colour = DRAIN if sensor.drain else SENSOR
            self._line(rgb, sensor.segment, SENSOR_HALF_WIDTH * scale, colour)
        for wall in table.walls:
            colour = ONE_SIDED if wall.one_sided else KICKER if wall.kick > 0 else WALL
            for segment in wall.segments():
                self._line(rgb, segment, WALL_HALF_WIDTH * scale, colour)
        for post in table.posts:
            self._disc(rgb, *post.center, post.radius, KICKER if post.kick > 0 else POST)
        rgb.flags.writeable = False  # frames copy it; nothing may paint on it
        self._static_rgb = rgb
        # Every colour is painted solid, so the grayscale image is the same drawing in luma:
        # keeping a gray static layer saves converting whole frames.
        self._static_gray = luminance(rgb)
        self._static_gray.flags.writeable = False

    def frame(
        self, ball_position: tuple[float, float] | None, flipper_angles: Sequence[float]
    ) -> np.ndarray:
        """The table with the flippers at ``flipper_angles`` [rad] (one per ``table.flippers``
        entry, in order) and the ball at ``ball_position`` [m] (None: out of play, not drawn),
        as a new (height, width, 3) uint8 array."""
        return self._draw(self._static_rgb, ball_position, flipper_angles, FLIPPER, BALL)

    def grayscale(
        self, ball_position: tuple[float, float] | None, flipper_angles: Sequence[float]
    ) -> np.ndarray:
        """:meth:`frame` as (height, width, 1) uint8 luma (:data:`LUMA_WEIGHTS`)."""
        return self._draw(
            self._static_gray, ball_position, flipper_angles, _FLIPPER_LUMA, _BALL_LUMA
        )

    def _draw(
        self,
        static: np.ndarray,
        ball_position: tuple[float, float] | None,
        flipper_angles: Sequence[float],
        flipper_colour: Colour,
        ball_colour: Colour,
    ) -> np.ndarray:
        if len(flipper_angles) != len(self._flippers):
            raise ValueError(
                f"expected {len(self._flippers)} flipper angles, got {len(flipper_angles)}"
            )
        image = static.copy()
        for flipper, angle in zip(self._flippers, flipper_angles, strict=True):
            self._capsule(image, *flipper, float(angle), flipper_colour)
        if ball_position is not None:
            x, y = ball_position
            self._disc(image, float(x), float(y), self.table.ball.radius, ball_colour)
        return image

    def _box(
        self, x0: float, y0: float, x1: float, y1: float, margin: int
    ) -> tuple[slice, slice] | None:
        """Rows and columns of the pixels around the world box [x0, x1] x [y0, y1], widened by
        ``margin`` pixels; None if that misses the image."""
        if not math.isfinite(x0 + y0 + x1 + y1):
            return None
        c0 = max(0, math.floor(x0 * self._sx) - margin)
        c1 = min(self.width, math.ceil(x1 * self._sx) + margin)
        r0 = max(0, math.floor((self.table.height - y1) * self._sy) - margin)
        r1 = min(self.height, math.ceil((self.table.height - y0) * self._sy) + margin)
        if c0 >= c1 or r0 >= r1:
            return None
        return slice(r0, r1), slice(c0, c1)

    def _line(
        self,
        image: np.ndarray,
        segment: tuple[float, float, float, float],
        half_width: float,
        colour: Colour,
    ) -> None:
        """Paint pixels whose centre lies within ``half_width`` px of the segment, measured in
        pixel coordinates so that a line keeps its width in a stretched image."""
        half_width = max(MIN_LINE_HALF_WIDTH, half_width)
        x0, y0, x1, y1 = segment
        box = self._box(min(x0, x1), min(y0, y1), max(x0, x1), max(y0, y1), math.ceil(half_width))
        if box is None:
            return
        rows, cols = box
        # Segment ends and pixel centres in pixel coordinates (column, row).
        ax, ay = x0 * self._sx, (self.table.height - y0) * self._sy
        bx, by = x1 * self._sx, (self.table.height - y1) * self._sy
        columns = np.arange(cols.start, cols.stop) + 0.5
        pixel_rows = np.arange(rows.start, rows.stop) + 0.5
        distance2 = _segment_field(columns, pixel_rows, ax, ay, bx, by)
        image[rows, cols][distance2 <= half_width * half_width] = colour

    def _disc(self, image: np.ndarray, cx: float, cy: float, radius: float, colour: Colour) -> None:
        """Paint a world disc (an ellipse in a stretched image) plus its 0.5 px outline band."""
        box = self._box(cx - radius, cy - radius, cx + radius, cy + radius, 1)
        if box is None:
            return
        rows, cols = box
        dx = self._xs[cols][None, :] - cx
        dy = self._ys[rows][:, None] - cy
        dx2, dy2 = dx * dx, dy * dy
        distance = np.sqrt(dx2 + dy2)
        # Outside, the pixel distance to the outline is to first order the world distance
        # d = |q| - r over the size of its gradient in pixel coordinates, |(nx / sx, ny / sy)|
        # with n = q / |q| (exact when sx = sy). Both sides multiplied by |q| to avoid dividing.
        gradient = np.sqrt(dx2 / self._sx**2 + dy2 / self._sy**2)
        mask = (distance - radius) * distance <= OUTLINE_BAND * gradient
        image[rows, cols][mask] = colour

    def _capsule(
        self,
        image: np.ndarray,
        px: float,
        py: float,
        length: float,
        rb: float,
        rt: float,
        angle: float,
        colour: Colour,
    ) -> None:
        """Paint a flipper turned to ``angle`` about its pivot (px, py), plus its 0.5 px outline
        band."""
        c, s = math.cos(angle), math.sin(angle)
        tx, ty = px + length * c, py + length * s
        box = self._box(
            min(px - rb, tx - rt),
            min(py - rb, ty - rt),
            max(px + rb, tx + rt),
            max(py + rb, ty + rt),
            1,
        )
        if box is None:
            return
        rows, cols = box
        distance, nx, ny = _flipper_field(
            self._xs[cols], self._ys[rows], px, py, length, rb, rt, angle
        )
        # The outline band in pixels: the distance's gradient (the unit normal) in pixel units.
        gradient = np.hypot(nx / self._sx, ny / self._sy)
        mask = distance <= OUTLINE_BAND * gradient
        image[rows, cols][mask] = colour


@njit(cache=True)
def _segment_field(xs, ys, x0, y0, x1, y1):
    """Squared distance from every point (xs[j], ys[i]) to segment P0-P1 (the kernel's own
    ``segment_offset``), an array of shape (len(ys), len(xs))."""
    distance2 = np.empty((ys.shape[0], xs.shape[0]))
    for i in range(ys.shape[0]):
        for j in range(xs.shape[0]):
            gx, gy = segment_offset(xs[j], ys[i], x0, y0, x1, y1)
            distance2[i, j] = gx * gx + gy * gy
    return distance2


@njit(cache=True)
def _flipper_field(xs, ys, px, py, length, rb, rt, angle):
    """Signed distance and outward normal of a flipper at every pixel centre of a box (the
    kernel's own ``flipper_distance``), arrays of shape (len(ys), len(xs))."""
    distance = np.empty((ys.shape[0], xs.shape[0]))
    nx = np.empty_like(distance)
    ny = np.empty_like(distance)
    for i in range(ys.shape[0]):
        for j in range(xs.shape[0]):
            distance[i, j], nx[i, j], ny[i, j] = flipper_distance(
                xs[j], ys[i], px, py, length, rb, rt, angle
            )
    return distance, nx, ny


# The scoreboard beside rendered frames: a 3x5 pixel font (rows top to bottom, bits left to right)
# for the characters it shows, drawn in solid blocks.
SCOREBOARD_WIDTH = 110  # [px]
SCOREBOARD_TEXT = (250, 195, 60)
_FONT = {
    "0": (7, 5, 5, 5, 7), "1": (2, 6, 2, 2, 7), "2": (7, 1, 7, 4, 7), "3": (7, 1, 7, 1, 7),
    "4": (5, 5, 7, 1, 1), "5": (7, 4, 7, 1, 7), "6": (7, 4, 7, 5, 7), "7": (7, 1, 1, 1, 1),
    "8": (7, 5, 7, 5, 7), "9": (7, 5, 7, 1, 7), "A": (2, 5, 7, 5, 5), "B": (6, 5, 6, 5, 6),
    "C": (7, 4, 4, 4, 7), "E": (7, 4, 7, 4, 7), "L": (4, 4, 4, 4, 7), "O": (7, 5, 5, 5, 7),
    "R": (6, 5, 6, 5, 5), "S": (7, 4, 7, 1, 7), " ": (0, 0, 0, 0, 0),
}  # fmt: skip


def text_mask(text: str, scale: int) -> np.ndarray:
    """(5 scale, 4 scale len(text)) bool pixels of ``text`` in the scoreboard font (digits and
    the letters of SCORE and BALLS), each font pixel a ``scale`` x ``scale`` block."""
    rows = []
    for row in range(5):
        bits = []
        for char in text:
            code = _FONT[char][row]
            bits.extend([bool(code & 4), bool(code & 2), bool(code & 1), False])
        rows.append(bits)
    return np.kron(np.array(rows, dtype=np.uint8), np.ones((scale, scale), np.uint8)) > 0


def scoreboard(
    height: int, score: int, balls_left: int, width: int = SCOREBOARD_WIDTH
) -> np.ndarray:
    """A (height, width, 3) uint8 strip showing the score and the balls left, as a machine's
    display does beside the playfield."""
    strip = np.empty((height, width, 3), dtype=np.uint8)
    strip[...] = BACKGROUND
    top = 10
    for label, value in (("SCORE", score), ("BALLS", balls_left)):
        for text, most in ((label, 4), (str(int(value)), 4)):
            scale = max(1, min(most, (width - 10) // (4 * len(text))))
            mask = text_mask(text, scale)
            rows, cols = min(mask.shape[0], max(height - top, 0)), min(mask.shape[1], width - 5)
            strip[top : top + rows, 5 : 5 + cols][mask[:rows, :cols]] = SCOREBOARD_TEXT
            top += mask.shape[0] + 2 * scale
        top += 12
    return strip


class Window:
    """A pygame window showing frames at a fixed rate (render_mode="human")."""

    def __init__(self, size: tuple[int, int], fps: float, title: str = "Pinball") -> None:
        os.environ.setdefault("PYGAME_HIDE_SUPPORT_PROMPT", "1")
        try:
            import pygame
        except ImportError as error:
            from gymnasium.error import DependencyNotInstalled

            raise DependencyNotInstalled(
                'pygame is not installed: pip install -e ".[render]"'
            ) from error
        self._pygame = pygame
        self.size = (int(size[0]), int(size[1]))
        self.fps = float(fps)
        pygame.display.init()
        pygame.display.set_caption(title)
        self._screen = pygame.display.set_mode(self.size)
        self._clock = pygame.time.Clock()
        self._open = True

    def show(self, frame: np.ndarray) -> None:
        """Blit an (H, W, 3) uint8 frame (scaled to the window if needed), pump the event queue
        so the window stays responsive, and wait to hold ``fps``."""
        pygame = self._pygame
        surface = pygame.surfarray.make_surface(np.ascontiguousarray(frame.swapaxes(0, 1)))
        if surface.get_size() != self.size:
            surface = pygame.transform.scale(surface, self.size)
        self._screen.blit(surface, (0, 0))
        pygame.event.pump()
        pygame.display.flip()
        self._clock.tick(self.fps)

    def close(self) -> None:
        """Close the window (safe to call twice)."""
        if self._open:
            self._pygame.display.quit()
            self._open = False
