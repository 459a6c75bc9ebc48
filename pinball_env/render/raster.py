"""Pixel pictures of a table and its moving parts, for observations and for watching.

:class:`Renderer` rasterises with the compiled painters (``painters.py``): the static layer
(playfield, sensors, walls, posts) once, then per frame a copy of it with the flippers and the
ball painted over their pixel bounding boxes, for one env or a batch of envs in one call.
:class:`FrameRenderer` draws any table into frames of one fixed size (fitted, letterboxed), so
that an env whose tables differ renders frames of one size.

Image row 0 is the top of the table (y = height) and x grows to the right; the centre of pixel
(row i, column j) is the world point ((j + 0.5) * width / W, height - (i + 0.5) * height / H).
"""

import math
from collections.abc import Sequence

import numpy as np

from pinball_env.render.colours import (
    BACKGROUND,
    BALL,
    DRAIN,
    FLIPPER,
    KICKER,
    ONE_SIDED,
    POST,
    SENSOR,
    WALL,
    luminance,
    rgb,
)
from pinball_env.render.painters import draw_moving_parts, paint_disc, paint_line
from pinball_env.sim.parallel import EnvThreads
from pinball_env.table import Table

WALL_HALF_WIDTH = 0.002  # [m]: walls are drawn 4 mm wide (more where a pixel is coarser)
SENSOR_HALF_WIDTH = 0.001  # [m]

# Scale of rendered frames (render()), as opposed to observations, which have a size in pixels.
PIXELS_PER_METRE = 600.0

_FLIPPER_LUMA = luminance(FLIPPER)
_BALL_LUMA = luminance(BALL)


def render_size(table: Table, pixels_per_metre: float = PIXELS_PER_METRE) -> tuple[int, int]:
    """(width, height) in pixels for an aspect-correct picture of the table."""
    if not pixels_per_metre > 0.0:
        raise ValueError(f"pixels_per_metre must be positive, got {pixels_per_metre!r}")
    return (
        max(1, round(table.width * pixels_per_metre)),
        max(1, round(table.height * pixels_per_metre)),
    )


def fit_size(table: Table, width: int, height: int) -> tuple[int, int]:
    """(width, height) in pixels of the largest aspect-correct picture of the table that fits in
    ``width`` x ``height``."""
    scale = min(width / table.width, height / table.height)
    return (
        min(width, max(1, round(table.width * scale))),
        min(height, max(1, round(table.height * scale))),
    )


def _check_size(width: int, height: int) -> None:
    if width < 1 or height < 1:
        raise ValueError(f"image size must be at least 1x1, got {width}x{height}")


class Renderer:
    """Draws a table into (height, width, 3) uint8 frames; the table fills the image (stretched if
    the aspect differs). The static layer (playfield, walls, posts, sensors) is rasterised once in
    __init__; each frame copies it and draws the flippers and the ball, for one env
    (:meth:`frame`, :meth:`grayscale`) or a batch of envs in one compiled call (:meth:`frames`).
    """

    def __init__(self, table: Table, width: int, height: int) -> None:
        _check_size(width, height)
        self.table = table
        self.width = int(width)
        self.height = int(height)
        # The table's picture in the images: rows from top, columns from left (a FrameRenderer
        # letterboxes it; here it fills them).
        self.top = self.left = 0
        # Pixels per metre, and the table height: the pixel centre (row i, column j) is the world
        # point ((j + 0.5) / sx, table_height - (i + 0.5) / sy).
        self._view = (self.width / table.width, self.height / table.height, table.height)
        self._flippers = np.array(
            [(*f.pivot, f.length, f.base_radius, f.tip_radius) for f in table.flippers],
            dtype=np.float64,
        ).reshape(-1, 5)
        self._static_rgb = self._static_layer()
        # Every colour is painted solid, so the grayscale image is the same drawing in luma:
        # keeping a gray static layer saves converting whole frames.
        self._static_gray = luminance(self._static_rgb)
        self._static_gray.flags.writeable = False

    def _static_layer(self) -> np.ndarray:
        """The playfield, sensors, walls and posts, read-only (frames copy it)."""
        table, view = self.table, self._view
        # Anisotropic images: a world length maps to pixels at the geometric mean scale.
        scale = math.sqrt(view[0] * view[1])
        image = np.empty((self.height, self.width, 3), dtype=np.uint8)
        image[...] = BACKGROUND
        for sensor in table.sensors:
            colour = DRAIN if sensor.drain else SENSOR
            paint_line(image, *sensor.segment, SENSOR_HALF_WIDTH * scale, rgb(colour), *view)
        for wall in table.walls:
            colour = ONE_SIDED if wall.one_sided else KICKER if wall.kick > 0 else WALL
            for segment in wall.segments():
                paint_line(image, *segment, WALL_HALF_WIDTH * scale, rgb(colour), *view)
        for post in table.posts:
            colour = rgb(KICKER if post.kick > 0 else POST)
            paint_disc(image, *post.center, post.radius, colour, *view)
        image.flags.writeable = False  # frames copy it; nothing may paint on it
        return image

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
        width, 3) uint8, or (N, height, width, 1) luma with ``grayscale``, the table's picture at
        (:attr:`top`, :attr:`left`), written into ``out`` when given; ``threads`` share the
        envs."""
        flipper_angles = np.asarray(flipper_angles, dtype=np.float64)
        if flipper_angles.ndim != 2 or flipper_angles.shape[1] != len(self._flippers):
            raise ValueError(
                f"expected (N, {len(self._flippers)}) flipper angles, got {flipper_angles.shape}"
            )
        static = self._static_gray if grayscale else self._static_rgb
        n, (rows, columns, channels) = flipper_angles.shape[0], static.shape
        if out is None:
            out = np.empty((n, self.height, self.width, channels), dtype=np.uint8)
        fills = (rows, columns) == (self.height, self.width)
        pictures = out if fills else np.empty((n, *static.shape), dtype=np.uint8)
        colours = (_FLIPPER_LUMA, _BALL_LUMA) if grayscale else (rgb(FLIPPER), rgb(BALL))
        args = (
            pictures, static, np.ascontiguousarray(balls, dtype=np.float64),
            np.ascontiguousarray(visible, dtype=np.bool_), flipper_angles, self._flippers,
            self.table.ball.radius, *colours, *self._view,
        )  # fmt: skip
        if threads is None:
            draw_moving_parts(*args, 0, n)
        else:
            threads.run(draw_moving_parts, n, *args)
        if not fills:
            out[...] = luminance(BACKGROUND) if grayscale else BACKGROUND
            out[:, self.top : self.top + rows, self.left : self.left + columns] = pictures
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


class FrameRenderer(Renderer):
    """A :class:`Renderer` whose images are ``width`` x ``height`` whatever the table: the table
    drawn as large as fits with its aspect kept (:func:`fit_size`), centred, the margins the
    background colour. An env whose tables differ in size renders frames of one size with it
    (video recorders and windows need one size)."""

    def __init__(self, table: Table, width: int, height: int) -> None:
        _check_size(width, height)
        inner_width, inner_height = fit_size(table, width, height)
        super().__init__(table, inner_width, inner_height)  # the table's picture
        self.width, self.height = int(width), int(height)  # the images'
        self.top = (self.height - inner_height) // 2
        self.left = (self.width - inner_width) // 2
