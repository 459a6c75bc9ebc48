"""Pixel pictures of a table and its moving parts, for observations and for watching.

- ``colours.py``: the colours, and their grayscale (BT.601 luma in exact integers);
- ``painters.py``: the compiled painters (numba): lines, discs, flippers, a batch of frames;
- ``raster.py``: :class:`Renderer` (one table, one or N envs' frames) and :class:`FrameRenderer`
  (frames of one fixed size whatever the table), :func:`render_size`, :func:`fit_size`;
- ``scoreboard.py``: the score and balls left beside rendered frames (and the cabinet's tilt
  warnings and TILT);
- ``window.py``: :class:`Window`, a thin pygame window for ``render_mode="human"``.

No module imports pygame until a :class:`Window` opens.
"""

from pinball_env.render.colours import (
    BACKGROUND,
    BALL,
    DRAIN,
    FLIPPER,
    KICKER,
    LUMA_WEIGHTS,
    ONE_SIDED,
    PLUNGER,
    POST,
    SCOREBOARD_ALERT,
    SCOREBOARD_TEXT,
    SENSOR,
    WALL,
    Colour,
    luminance,
)
from pinball_env.render.painters import MIN_LINE_HALF_WIDTH, OUTLINE_BAND
from pinball_env.render.raster import (
    PIXELS_PER_METRE,
    PLUNGER_TIP_FLOOR,
    SENSOR_HALF_WIDTH,
    SHAKE_EXAGGERATION,
    WALL_HALF_WIDTH,
    FrameRenderer,
    Renderer,
    TargetsView,
    fit_size,
    render_size,
)
from pinball_env.render.scoreboard import SCOREBOARD_WIDTH, scoreboard, text_mask
from pinball_env.render.window import Window

__all__ = [
    "BACKGROUND",
    "BALL",
    "DRAIN",
    "FLIPPER",
    "KICKER",
    "LUMA_WEIGHTS",
    "MIN_LINE_HALF_WIDTH",
    "ONE_SIDED",
    "OUTLINE_BAND",
    "PIXELS_PER_METRE",
    "PLUNGER",
    "PLUNGER_TIP_FLOOR",
    "POST",
    "SCOREBOARD_ALERT",
    "SCOREBOARD_TEXT",
    "SCOREBOARD_WIDTH",
    "SENSOR",
    "SENSOR_HALF_WIDTH",
    "SHAKE_EXAGGERATION",
    "WALL",
    "WALL_HALF_WIDTH",
    "Colour",
    "FrameRenderer",
    "Renderer",
    "TargetsView",
    "Window",
    "fit_size",
    "luminance",
    "render_size",
    "scoreboard",
    "text_mask",
]
