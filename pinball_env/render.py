"""Pixel pictures of a table and its moving parts, for observations and for watching.

:class:`Renderer` rasterises with compiled painters (numba; no display, no pygame; lines and
flippers through the kernel's own ``segment_offset`` and ``flipper_distance``): the static layer
(playfield, sensors, walls, posts) once, then per frame a copy of it with the flippers and the
ball painted over their pixel bounding boxes, for one env or a batch of envs in one call.
:class:`FrameRenderer` draws any table into frames of one fixed size (fitted, letterboxed), so
that an env whose tables differ renders frames of one size. :class:`Window` is a thin pygame window
for ``render_mode="human"``.

Image row 0 is the top of the table (y = height) and x grows to the right; the centre of pixel
(row i, column j) is the world point ((j + 0.5) * width / W, height - (i + 0.5) * height / H).
Shapes are sized in pixels so that they stay visible at any resolution, including a stretched
84x84 observation: a line covers every pixel centre within ``max(0.6 px, its half-width)`` of it,
and a disc or flipper every pixel centre inside it or within 0.5 px of its outline.
"""

import math
import os
from collections.abc import Sequence
from types import ModuleType

import numpy as np
from numba import njit

from pinball_env.extras import require
from pinball_env.parallel import EnvThreads
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


# Scale of rendered frames (render()), as opposed to observations, which have a size in pixels.
PIXELS_PER_METRE = 600.0


def render_size(table: Table, pixels_per_metre: float = PIXELS_PER_METRE) -> tuple[int, int]:
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
    __init__; each frame copies it and draws the flippers and the ball, for one env
    (:meth:`frame`, :meth:`grayscale`) or a batch of envs in one compiled call (:meth:`frames`).
    """

    def __init__(self, table: Table, width: int, height: int) -> None:
        if width < 1 or height < 1:
            raise ValueError(f"image size must be at least 1x1, got {width}x{height}")
        self.table = table
        self.width = int(width)
        self.height = int(height)
        # Pixels per metre, and the table height: the pixel centre (row i, column j) is the world
        # point ((j + 0.5) / sx, table_height - (i + 0.5) / sy).
        self._view = (self.width / table.width, self.height / table.height, table.height)
        # Anisotropic images: a world length maps to pixels at the geometric mean scale.
        scale = math.sqrt(self._view[0] * self._view[1])
        self._flippers = np.array(
            [(*f.pivot, f.length, f.base_radius, f.tip_radius) for f in table.flippers],
            dtype=np.float64,
        ).reshape(-1, 5)

        rgb = np.empty((self.height, self.width, 3), dtype=np.uint8)
        rgb[...] = BACKGROUND
        for sensor in table.sensors:
            colour = DRAIN if sensor.drain else SENSOR
            _paint_line(rgb, *sensor.segment, SENSOR_HALF_WIDTH * scale, _rgb(colour), *self._view)
        for wall in table.walls:
            colour = ONE_SIDED if wall.one_sided else KICKER if wall.kick > 0 else WALL
            for segment in wall.segments():
                _paint_line(rgb, *segment, WALL_HALF_WIDTH * scale, _rgb(colour), *self._view)
        for post in table.posts:
            colour = _rgb(KICKER if post.kick > 0 else POST)
            _paint_disc(rgb, *post.center, post.radius, colour, *self._view)
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
        return self._one(ball_position, flipper_angles, grayscale=False)

    def grayscale(
        self, ball_position: tuple[float, float] | None, flipper_angles: Sequence[float]
    ) -> np.ndarray:
        """:meth:`frame` as (height, width, 1) uint8 luma (:data:`LUMA_WEIGHTS`)."""
        return self._one(ball_position, flipper_angles, grayscale=True)

    def frames(
        self,
        balls: np.ndarray,
        visible: np.ndarray,
        flipper_angles: np.ndarray,
        grayscale: bool = False,
        out: np.ndarray | None = None,
        threads: EnvThreads | None = None,
    ) -> np.ndarray:
        """Frames of a batch of envs: ball centres ``balls`` (N, >= 2) [m], drawn where
        ``visible`` (N,) bool, flippers at ``flipper_angles`` (N, F) [rad]. Returns (N, height,
        width, 3) uint8, or (N, height, width, 1) luma with ``grayscale``, written into ``out``
        when given; ``threads`` share the envs."""
        flipper_angles = np.asarray(flipper_angles, dtype=np.float64)
        if flipper_angles.ndim != 2 or flipper_angles.shape[1] != len(self._flippers):
            raise ValueError(
                f"expected (N, {len(self._flippers)}) flipper angles, got {flipper_angles.shape}"
            )
        static = self._static_gray if grayscale else self._static_rgb
        if out is None:
            out = np.empty((flipper_angles.shape[0], *static.shape), dtype=np.uint8)
        colours = (_FLIPPER_LUMA, _BALL_LUMA) if grayscale else (_rgb(FLIPPER), _rgb(BALL))
        args = (
            out, static, np.ascontiguousarray(balls, dtype=np.float64),
            np.ascontiguousarray(visible, dtype=np.bool_), flipper_angles, self._flippers,
            self.table.ball.radius, *colours, *self._view,
        )  # fmt: skip
        if threads is None:
            _draw_moving_parts(*args, 0, len(out))
        else:
            threads.run(_draw_moving_parts, len(out), *args)
        return out

    def _one(
        self,
        ball_position: tuple[float, float] | None,
        flipper_angles: Sequence[float],
        grayscale: bool,
    ) -> np.ndarray:
        if len(flipper_angles) != len(self._flippers):
            raise ValueError(
                f"expected {len(self._flippers)} flipper angles, got {len(flipper_angles)}"
            )
        visible = ball_position is not None
        ball = np.array([ball_position if visible else (0.0, 0.0)], dtype=np.float64)
        angles = np.array([flipper_angles], dtype=np.float64).reshape(1, -1)
        return self.frames(ball, np.array([visible]), angles, grayscale)[0]


def fit_size(table: Table, width: int, height: int) -> tuple[int, int]:
    """(width, height) in pixels of the largest aspect-correct picture of the table that fits in
    ``width`` x ``height``."""
    scale = min(width / table.width, height / table.height)
    return (
        min(width, max(1, round(table.width * scale))),
        min(height, max(1, round(table.height * scale))),
    )


class FrameRenderer(Renderer):
    """A :class:`Renderer` whose images are ``width`` x ``height`` whatever the table: the table
    drawn as large as fits with its aspect kept (:func:`fit_size`), centred, the margins the
    background colour. An env whose tables differ in size renders frames of one size with it
    (video recorders and windows need one size)."""

    def __init__(self, table: Table, width: int, height: int) -> None:
        if width < 1 or height < 1:
            raise ValueError(f"image size must be at least 1x1, got {width}x{height}")
        inner_width, inner_height = fit_size(table, width, height)
        super().__init__(table, inner_width, inner_height)  # the table's picture
        self.width, self.height = int(width), int(height)  # the images'
        # The picture's place in them: rows from top, columns from left.
        self.top = (self.height - inner_height) // 2
        self.left = (self.width - inner_width) // 2

    def frames(
        self,
        balls: np.ndarray,
        visible: np.ndarray,
        flipper_angles: np.ndarray,
        grayscale: bool = False,
        out: np.ndarray | None = None,
        threads: EnvThreads | None = None,
    ) -> np.ndarray:
        """:meth:`Renderer.frames`, each image (N, height, width, C) with the table centred."""
        tables = super().frames(balls, visible, flipper_angles, grayscale, threads=threads)
        n, rows, columns, channels = tables.shape
        if out is None:
            out = np.empty((n, self.height, self.width, channels), dtype=np.uint8)
        out[...] = luminance(BACKGROUND) if grayscale else BACKGROUND
        out[:, self.top : self.top + rows, self.left : self.left + columns] = tables
        return out


def _rgb(colour: Colour) -> np.ndarray:
    return np.asarray(colour, dtype=np.uint8)


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
def _paint_line(image, x0, y0, x1, y1, half_width, colour, sx, sy, table_height):
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
def _paint_disc(image, cx, cy, radius, colour, sx, sy, table_height):
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
def _paint_flipper(image, px, py, length, rb, rt, angle, colour, sx, sy, table_height):
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
def _draw_env(images, env, static, balls, visible, angles, flippers, radius, flipper_colour,
              ball_colour, sx, sy, table_height):  # fmt: skip
    """One env's frame: the static layer, its flippers, and its ball where visible."""
    images[env] = static
    for j in range(flippers.shape[0]):
        f = flippers[j]
        _paint_flipper(
            images[env], f[0], f[1], f[2], f[3], f[4], angles[env, j], flipper_colour, sx, sy,
            table_height,
        )  # fmt: skip
    if visible[env]:
        _paint_disc(
            images[env], balls[env, 0], balls[env, 1], radius, ball_colour, sx, sy, table_height
        )


@njit(cache=True, nogil=True)
def _draw_moving_parts(images, static, balls, visible, angles, flippers, radius, flipper_colour,
                       ball_colour, sx, sy, table_height, start, stop):  # fmt: skip
    """The frames of envs ``start`` to ``stop`` (see :func:`_draw_env`). The GIL is released,
    so threads can draw disjoint ranges at once."""
    for env in range(start, stop):
        _draw_env(
            images, env, static, balls, visible, angles, flippers, radius, flipper_colour,
            ball_colour, sx, sy, table_height,
        )  # fmt: skip


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

    @staticmethod
    def import_pygame() -> ModuleType:
        """pygame, or ``MissingDependency`` (Gymnasium's DependencyNotInstalled) with a one-line
        install hint that fits an installed package and a checkout (the ``render`` extra)."""
        os.environ.setdefault("PYGAME_HIDE_SUPPORT_PROMPT", "1")
        pygame = require("pygame")
        return pygame

    def __init__(self, size: tuple[int, int], fps: float, title: str = "Pinball") -> None:
        pygame = self._pygame = self.import_pygame()
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

    def quit_requested(self) -> bool:
        """Whether the window was asked to close (a QUIT event waits in the queue)."""
        return bool(self._pygame.event.peek(self._pygame.QUIT))

    def close(self) -> None:
        """Close the window (safe to call twice)."""
        if self._open:
            self._pygame.display.quit()
            self._open = False
