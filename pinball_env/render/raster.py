"""Pixel pictures of a table and its moving parts, for observations and for watching.

:class:`Renderer` rasterises with the compiled painters (``painters.py``): the static layer
(playfield, sensors, walls, posts) once, then per frame a copy of it with the flippers and the
ball painted over their pixel bounding boxes, for one env or a batch of envs in one call. On a
table with the cabinet, a frame can also show the player's plunger (pulled back, the ball
waiting on it drawn with it) and the cabinet's shake (the whole playfield moved by its offset).
:class:`FrameRenderer` draws any table into frames of one fixed size (fitted, letterboxed), so
that an env whose tables differ renders frames of one size.

Image row 0 is the top of the table (y = height) and x grows to the right; the centre of pixel
(row i, column j) is the world point ((j + 0.5) * width / W, height - (i + 0.5) * height / H).
"""

import math
from collections.abc import Sequence
from typing import NamedTuple

import numpy as np

from pinball_env.render.colours import (
    BACKGROUND,
    BALL,
    DRAIN,
    FLIPPER,
    KICKER,
    LIGHT_OFF,
    LIGHT_ON,
    ONE_SIDED,
    PLUNGER,
    POST,
    SENSOR,
    SPINNER,
    TARGET,
    TARGET_DOWN,
    WALL,
    luminance,
    rgb,
)
from pinball_env.render.painters import draw_moving_parts, paint_disc, paint_line
from pinball_env.sim.parallel import EnvThreads
from pinball_env.table import Table
from pinball_env.table.kinds import Line, static_shapes

WALL_HALF_WIDTH = 0.002  # [m]: walls are drawn 4 mm wide (more where a pixel is coarser)
SENSOR_HALF_WIDTH = 0.001  # [m]
TARGET_HALF_WIDTH = 0.003  # [m]: a standing drop target, thicker than a wall
LAMP_RADIUS = 0.007  # [m]: the rules' lights, and a kickback's lamp
# The static layer's styles (``table.kinds.Line`` and ``Disc``): a line's colour and half-width,
# a disc's colour. The web page draws the same (``tools.web.stream``).
LINE_STYLES = {
    "wall": (WALL, WALL_HALF_WIDTH),
    "one_sided": (ONE_SIDED, WALL_HALF_WIDTH),
    "kicker": (KICKER, WALL_HALF_WIDTH),
    "sensor": (SENSOR, SENSOR_HALF_WIDTH),
    "drain": (DRAIN, SENSOR_HALF_WIDTH),
    "target": (TARGET, TARGET_HALF_WIDTH),
}
DISC_COLOURS = {"post": POST, "kicker": KICKER, "drain": DRAIN, "sensor": SENSOR}

# Scale of rendered frames (render()), as opposed to observations, which have a size in pixels.
PIXELS_PER_METRE = 600.0

# The player's plunger (tables with a cabinet): a rod under the ball, a bar across the lane at its
# tip. A real shooter lane runs on under the plunger; here the ball waits 4 cm above the table's
# bottom edge while the stroke is 5 cm, so a true-scale pull would draw the ball out of the picture
# (its centre 1 cm below it): the pull is drawn scaled (Renderer.pull_scale) so that the whole
# stroke brings the tip down to PLUNGER_TIP_FLOOR above the bottom edge, never lower.
PLUNGER_ROD_HALF_WIDTH = 0.003  # [m]
PLUNGER_TIP_HALF_WIDTH = 0.002  # [m]: the bar's thickness, half
PLUNGER_TIP_REACH = 0.8  # the bar's half-length, in ball radii
PLUNGER_TIP_FLOOR = 0.012  # [m]: the tip's bar clear of a bottom wall at 5 mm
# render() frames draw the cabinet's shake at twice its size: a nudge moves the cabinet about 5 mm
# (3 px at PIXELS_PER_METRE) for a few frames, a jolt hard to see; 6 px reads as one. Every part
# moves together, so the picture is true within the table; observations should pass the offset
# at 1x (an 84x84 image barely moves at either).
SHAKE_EXAGGERATION = 2.0

_FLIPPER_LUMA = luminance(FLIPPER)
_BALL_LUMA = luminance(BALL)
_PLUNGER_LUMA = luminance(PLUNGER)
_BACKGROUND_LUMA = luminance(BACKGROUND)


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


class TargetsView(NamedTuple):
    """What a picture shows of the targets and rules of a batch of envs (rows are envs; a table
    without some kind has 0 columns of it): ``State.targets_up``, the spinners' angles [rad]
    (``State.spinners[..., SPIN_ANGLE]``), ``State.kickback_lit`` and the rules' lights."""

    targets_up: np.ndarray  # (N, T) bool
    spinner_angles: np.ndarray  # (N, P) float64
    kickback_lit: np.ndarray  # (N, K) bool
    lights: np.ndarray  # (N, L) bool


class Renderer:
    """Draws a table into (height, width, 3) uint8 frames; the table fills the image (stretched if
    the aspect differs). The static layer (playfield, walls, posts, sensors) is rasterised once in
    __init__; each frame copies it and draws the flippers and the ball, for one env
    (:meth:`frame`, :meth:`grayscale`) or a batch of envs in one compiled call (:meth:`frames`).

    The cabinet (optional arguments, for a table with one): ``plunger_pull`` draws the player's
    plunger pulled back by it (scaled by :attr:`pull_scale`), ``on_plunger`` the ball waiting on
    it, drawn pulled back with it, and ``cabinet_offset`` [m] moves the whole playfield by the
    cabinet's offset (rounded to whole pixels; the band it uncovers is the background). Without
    them a frame is drawn exactly as on a table without a cabinet.
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
        self._plunger, self.pull_scale = self._plunger_layout()
        self._static_rgb = self._static_layer()
        # Every colour is painted solid, so the grayscale image is the same drawing in luma:
        # keeping a gray static layer saves converting whole frames.
        self._static_gray = luminance(self._static_rgb)
        self._static_gray.flags.writeable = False

    def _plunger_layout(self) -> tuple[np.ndarray | None, float]:
        """The player's plunger for the painters (x at rest [m], rod half-width [px], tip
        half-length [m], tip half-width [px]) and the scale of its drawn pull; (None, 1.0) for a
        table whose plunger the machine fires."""
        plunger = self.table.plunger
        if plunger is None or plunger.stroke is None:  # (not plunger.manual)
            return None, 1.0
        scale = math.sqrt(self._view[0] * self._view[1])  # as the walls' widths
        radius = self.table.ball.radius
        layout = np.array([
            plunger.position[0], PLUNGER_ROD_HALF_WIDTH * scale, PLUNGER_TIP_REACH * radius,
            PLUNGER_TIP_HALF_WIDTH * scale,
        ])  # fmt: skip
        room = plunger.position[1] - radius - PLUNGER_TIP_FLOOR
        return layout, min(1.0, max(0.0, room) / plunger.stroke)

    def _static_layer(self) -> np.ndarray:
        """The playfield and its static elements (``table.kinds.static_shapes``: sensors, walls,
        posts, stand-up targets, spinners' and kickbacks' lines, saucers, locks), read-only
        (frames copy it)."""
        table, view = self.table, self._view
        # Anisotropic images: a world length maps to pixels at the geometric mean scale.
        scale = math.sqrt(view[0] * view[1])
        image = np.empty((self.height, self.width, 3), dtype=np.uint8)
        image[...] = BACKGROUND
        for shape in static_shapes(table):
            if isinstance(shape, Line):
                colour, half_width = LINE_STYLES[shape.style]
                paint_line(image, *shape.segment, half_width * scale, rgb(colour), *view)
            else:
                paint_disc(
                    image, *shape.center, shape.radius, rgb(DISC_COLOURS[shape.style]), *view
                )
        image.flags.writeable = False  # frames copy it; nothing may paint on it
        return image

    def frame(
        self,
        ball_position: tuple[float, float] | None,
        flipper_angles: Sequence[float],
        *,
        plunger_pull: float | None = None,
        on_plunger: bool = False,
        cabinet_offset: tuple[float, float] | None = None,
        targets: TargetsView | None = None,
        other_balls: Sequence[tuple[float, float]] | None = None,
    ) -> np.ndarray:
        """The table with the flippers at ``flipper_angles`` [rad] (one per ``table.flippers``
        entry, in order) and the ball at ``ball_position`` [m] (None: out of play, not drawn),
        as a new (height, width, 3) uint8 array. The cabinet's and the targets' arguments are
        :meth:`frames`'s, for the one env (``targets`` a batch of one); ``other_balls`` are
        more balls' centres [m] (several balls), drawn too."""
        return self._one(
            ball_position, flipper_angles, False, plunger_pull, on_plunger, cabinet_offset,
            targets, other_balls,
        )  # fmt: skip

    def grayscale(
        self,
        ball_position: tuple[float, float] | None,
        flipper_angles: Sequence[float],
        *,
        plunger_pull: float | None = None,
        on_plunger: bool = False,
        cabinet_offset: tuple[float, float] | None = None,
        targets: TargetsView | None = None,
    ) -> np.ndarray:
        """:meth:`frame` as (height, width, 1) uint8 luma (:data:`LUMA_WEIGHTS`)."""
        return self._one(
            ball_position, flipper_angles, True, plunger_pull, on_plunger, cabinet_offset,
            targets,
        )  # fmt: skip

    def frames(
        self,
        balls: np.ndarray,
        visible: np.ndarray,
        flipper_angles: np.ndarray,
        grayscale: bool = False,
        out: np.ndarray | None = None,
        threads: EnvThreads | None = None,
        *,
        plunger_pull: np.ndarray | None = None,
        on_plunger: np.ndarray | None = None,
        cabinet_offset: np.ndarray | None = None,
        targets: TargetsView | None = None,
        other_balls: np.ndarray | None = None,
        other_visible: np.ndarray | None = None,
    ) -> np.ndarray:
        """Frames of a batch of envs: ball centres ``balls`` (N, >= 2) [m], drawn where
        ``visible`` (N,) bool, flippers at ``flipper_angles`` (N, F) [rad]. Returns (N, height,
        width, 3) uint8, or (N, height, width, 1) luma with ``grayscale``, the table's picture at
        (:attr:`top`, :attr:`left`), written into ``out`` when given; ``threads`` share the envs.

        The cabinet (a table with the player's plunger; ``game.state`` and the kernel's state
        hold them): ``plunger_pull`` (N,) [m] draws the plunger pulled back by it, ``on_plunger``
        (N,) bool lowers those balls with it (they wait on it, at ``table.plunger.position``),
        ``cabinet_offset`` (N, 2) [m] (x, y) moves the whole playfield (the ``CABINET_X``,
        ``CABINET_Y`` columns, times an exaggeration if wanted, see SHAKE_EXAGGERATION).

        ``targets`` (a table with targets or rules) draws the drop targets standing or fallen,
        the spinners' flaps as they turn, the kickbacks' lamps and the rules' lights.

        Several balls: ``other_balls`` (N, K, >= 2) [m] more balls' centres, drawn where
        ``other_visible`` (N, K) bool (on top of everything but the first ball)."""
        flipper_angles = self._checked_flipper_angles(flipper_angles)
        static = self._static_gray if grayscale else self._static_rgb
        n, (rows, columns, channels) = flipper_angles.shape[0], static.shape
        balls = np.ascontiguousarray(balls, dtype=np.float64)
        shifts = self._shifts(n, cabinet_offset)
        tips, drawn_pull = self._plunger_tips(n, plunger_pull)
        if on_plunger is not None:
            balls = _on_plunger(balls, on_plunger, drawn_pull, n)
        if out is None:
            out = np.empty((n, self.height, self.width, channels), dtype=np.uint8)
        fills = (rows, columns) == (self.height, self.width)
        pictures = out if fills else np.empty((n, *static.shape), dtype=np.uint8)
        self._draw_moving_parts(
            pictures, static, balls, visible, flipper_angles, shifts, tips, grayscale, threads
        )
        if targets is not None:
            self._paint_targets(pictures, targets, balls, visible, shifts, grayscale)
        if other_balls is not None and other_visible is not None:
            self._paint_other_balls(pictures, other_balls, other_visible, shifts, grayscale)
        if not fills:
            out[...] = luminance(BACKGROUND) if grayscale else BACKGROUND
            out[:, self.top : self.top + rows, self.left : self.left + columns] = pictures
        return out

    def _checked_flipper_angles(self, flipper_angles: np.ndarray) -> np.ndarray:
        """``flipper_angles`` as float64, (N, F) for this table's F flippers, or ValueError."""
        flipper_angles = np.asarray(flipper_angles, dtype=np.float64)
        if flipper_angles.ndim != 2 or flipper_angles.shape[1] != len(self._flippers):
            raise ValueError(
                f"expected (N, {len(self._flippers)}) flipper angles, got {flipper_angles.shape}"
            )
        return flipper_angles

    def _draw_moving_parts(
        self,
        pictures: np.ndarray,
        static: np.ndarray,
        balls: np.ndarray,
        visible: np.ndarray,
        flipper_angles: np.ndarray,
        shifts: np.ndarray,
        tips: np.ndarray,
        grayscale: bool,
        threads: EnvThreads | None,
    ) -> None:
        """The static layer, the flippers, the plunger and the ball of each env into
        ``pictures`` (compiled, :func:`draw_moving_parts`; ``threads`` share the envs)."""
        n = pictures.shape[0]
        colours = _moving_colours(grayscale)
        plunger = np.zeros(4) if self._plunger is None else self._plunger
        args = (
            pictures, static, balls, np.ascontiguousarray(visible, dtype=np.bool_),
            flipper_angles, self._flippers, self.table.ball.radius, colours[0], colours[1],
            *self._view, shifts, tips, plunger, colours[2], colours[3],
        )  # fmt: skip
        if threads is None:
            draw_moving_parts(*args, 0, n)
        else:
            threads.run(draw_moving_parts, n, *args)

    def _paint_other_balls(
        self,
        pictures: np.ndarray,
        other_balls: np.ndarray,
        other_visible: np.ndarray,
        shifts: np.ndarray,
        grayscale: bool,
    ) -> None:
        """The more balls of each env (several balls), moved with the cabinet, over its picture."""
        colour = luminance(BALL) if grayscale else rgb(BALL)
        radius, view = self.table.ball.radius, self._view
        for env, k in zip(*np.nonzero(other_visible), strict=True):
            dx, dy = shifts[env, 1] / view[0], -shifts[env, 0] / view[1]
            x, y = other_balls[env, k, 0] + dx, other_balls[env, k, 1] + dy
            paint_disc(pictures[env], x, y, radius, colour, *view)

    def _paint_targets(
        self,
        pictures: np.ndarray,
        targets: TargetsView,
        balls: np.ndarray,
        visible: np.ndarray,
        shifts: np.ndarray,
        grayscale: bool,
    ) -> None:
        """Paint each env's targets and lights over its picture (moved with the cabinet), then
        its ball again, on top."""
        table, view = self.table, self._view
        sx, sy, _ = view
        scale = math.sqrt(sx * sy)
        paint = luminance if grayscale else rgb
        colours = {name: paint(colour) for name, colour in (
            ("up", TARGET), ("down", TARGET_DOWN), ("flap", SPINNER), ("on", LIGHT_ON),
            ("off", LIGHT_OFF), ("ball", BALL))}  # fmt: skip
        drop_targets = table.drop_target_list
        for env in range(pictures.shape[0]):
            image = pictures[env]
            dx, dy = shifts[env, 1] / sx, -shifts[env, 0] / sy
            for j, target in enumerate(drop_targets):
                up = targets.targets_up[env, j]
                x0, y0, x1, y1 = target.segment
                half = (TARGET_HALF_WIDTH if up else SENSOR_HALF_WIDTH) * scale
                colour = colours["up" if up else "down"]
                paint_line(image, x0 + dx, y0 + dy, x1 + dx, y1 + dy, half, colour, *view)
            for j, spinner in enumerate(table.spinners):
                # The flap seen from above: edge on at angle 0, its whole width across.
                half = abs(math.sin(targets.spinner_angles[env, j])) * spinner.radius * scale
                x0, y0, x1, y1 = spinner.segment
                paint_line(image, x0 + dx, y0 + dy, x1 + dx, y1 + dy, half, colours["flap"],
                           *view)  # fmt: skip
            lamps = [(*k.lamp, targets.kickback_lit[env, j]) for j, k in enumerate(table.kickbacks)]
            if table.rules is not None:
                lamps += [(*light.at, targets.lights[env, j])
                          for j, light in enumerate(table.rules.lights)]  # fmt: skip
            for x, y, lit in lamps:
                colour = colours["on" if lit else "off"]
                paint_disc(image, x + dx, y + dy, LAMP_RADIUS, colour, *view)
            if visible[env]:
                x, y = balls[env, 0] + dx, balls[env, 1] + dy
                paint_disc(image, x, y, table.ball.radius, colours["ball"], *view)

    def _shifts(self, n: int, cabinet_offset: np.ndarray | None) -> np.ndarray:
        """(n, 2) int64 (rows down, columns right): the cabinet's offsets in whole pixels."""
        shifts = np.zeros((n, 2), dtype=np.int64)
        if cabinet_offset is None:
            return shifts
        offset = np.asarray(cabinet_offset, dtype=np.float64)
        if offset.shape != (n, 2):
            raise ValueError(f"expected ({n}, 2) cabinet offsets, got {offset.shape}")
        offset = np.where(np.isfinite(offset), offset, 0.0)
        sx, sy, _ = self._view
        # Clipped to the picture's size: a shift past it leaves only the background anyway.
        shifts[:, 0] = np.clip(np.rint(-offset[:, 1] * sy), -self.height, self.height)
        shifts[:, 1] = np.clip(np.rint(offset[:, 0] * sx), -self.width, self.width)
        return shifts

    def _plunger_tips(
        self, n: int, plunger_pull: np.ndarray | None
    ) -> tuple[np.ndarray, np.ndarray | None]:
        """(n,) height [m] of the plunger's tip (NaN: no plunger drawn), and the drawn pull
        (None without ``plunger_pull``)."""
        if plunger_pull is None:
            return np.full(n, np.nan), None
        if self._plunger is None:
            raise ValueError(
                f"table {self.table.name!r} has no player's plunger to draw pulled back"
            )
        pull = np.asarray(plunger_pull, dtype=np.float64).reshape(n)
        plunger = self.table.plunger
        assert plunger is not None  # (self._plunger: the player's)
        drawn = np.clip(np.nan_to_num(pull), 0.0, plunger.stroke) * self.pull_scale
        return plunger.position[1] - self.table.ball.radius - drawn, drawn

    def _one(
        self,
        ball_position: tuple[float, float] | None,
        flipper_angles: Sequence[float],
        grayscale: bool,
        plunger_pull: float | None = None,
        on_plunger: bool = False,
        cabinet_offset: tuple[float, float] | None = None,
        targets: TargetsView | None = None,
        other_balls: Sequence[tuple[float, float]] | None = None,
    ) -> np.ndarray:
        if len(flipper_angles) != len(self._flippers):
            raise ValueError(
                f"expected {len(self._flippers)} flipper angles, got {len(flipper_angles)}"
            )
        visible = ball_position is not None
        ball = np.array([ball_position if visible else (0.0, 0.0)], dtype=np.float64)
        angles = np.array([flipper_angles], dtype=np.float64).reshape(1, -1)
        pull = None if plunger_pull is None else np.array([plunger_pull], dtype=np.float64)
        waiting = None if pull is None and not on_plunger else np.array([on_plunger])
        offset = None if cabinet_offset is None else np.array([cabinet_offset], dtype=np.float64)
        more = visible_more = None
        if other_balls is not None:
            more = np.array(other_balls, dtype=np.float64).reshape(1, -1, 2)
            visible_more = np.ones(more.shape[:2], dtype=bool)
        return self.frames(
            ball, np.array([visible]), angles, grayscale, plunger_pull=pull,
            on_plunger=waiting, cabinet_offset=offset, targets=targets, other_balls=more,
            other_visible=visible_more,
        )[0]  # fmt: skip


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


def _on_plunger(
    balls: np.ndarray, on_plunger: np.ndarray, drawn_pull: np.ndarray | None, n: int
) -> np.ndarray:
    """``balls`` (n, >= 2) with those ``on_plunger`` (n,) bool lowered by the plunger's drawn
    pull (n,) [m], as they wait on it (a copy)."""
    if drawn_pull is None:
        raise ValueError("on_plunger needs plunger_pull: the ball waits on the plunger")
    waiting = np.asarray(on_plunger, dtype=np.bool_).reshape(n)
    balls = balls.copy()
    balls[waiting, 1] -= drawn_pull[waiting]
    return balls


def _moving_colours(grayscale: bool) -> tuple:
    """The colours of the moving parts (flipper, ball, plunger, background), as luma or RGB."""
    if grayscale:
        return (_FLIPPER_LUMA, _BALL_LUMA, _PLUNGER_LUMA, _BACKGROUND_LUMA)
    return (rgb(FLIPPER), rgb(BALL), rgb(PLUNGER), rgb(BACKGROUND))
