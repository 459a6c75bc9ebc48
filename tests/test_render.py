"""Tests of the rasteriser (pinball_env.render.Renderer) and the pygame window."""

import math
import subprocess
import sys

import numpy as np
import pytest
from gymnasium.error import DependencyNotInstalled

from pinball_env.render import (
    BACKGROUND,
    BALL,
    FLIPPER,
    KICKER,
    ONE_SIDED,
    POST,
    WALL,
    Renderer,
    Window,
    render_size,
)
from pinball_env.table import Table, load_table

TABLE = load_table("classic")
SMALL = (84, 84)
FULL = render_size(TABLE)
REST = [math.radians(f.rest_angle) for f in TABLE.flippers]
UP = [math.radians(f.up_angle) for f in TABLE.flippers]
OPEN_SPOT = (0.25, 0.45)  # a point of the playfield clear of every element by > 5 cm


def pixel(renderer: Renderer, x: float, y: float) -> tuple[int, int]:
    """(row, column) of the pixel holding the world point (x, y)."""
    table = renderer.table
    row = int((table.height - y) / table.height * renderer.height)
    col = int(x / table.width * renderer.width)
    return row, col


def world(renderer: Renderer, rows: np.ndarray, cols: np.ndarray) -> tuple[np.ndarray, ...]:
    """World (x, y) of pixel centres."""
    table = renderer.table
    x = (cols + 0.5) * table.width / renderer.width
    y = table.height - (rows + 0.5) * table.height / renderer.height
    return x, y


def has_colour(image: np.ndarray, colour: tuple[int, int, int]) -> np.ndarray:
    """(H, W) mask of the pixels of exactly ``colour``."""
    return np.all(image == np.array(colour, dtype=np.uint8), axis=-1)


def test_render_size_keeps_the_aspect() -> None:
    assert FULL == (306, 642)  # 0.51 m x 1.07 m at 600 px/m
    width, height = render_size(TABLE, 150.0)
    assert width / height == pytest.approx(TABLE.width / TABLE.height, rel=0.02)
    with pytest.raises(ValueError, match="pixels_per_metre"):
        render_size(TABLE, 0.0)


@pytest.mark.parametrize("size", [SMALL, FULL])
def test_shapes_and_dtypes(size: tuple[int, int]) -> None:
    width, height = size
    renderer = Renderer(TABLE, width, height)
    rgb = renderer.frame(OPEN_SPOT, REST)
    gray = renderer.grayscale(OPEN_SPOT, REST)
    assert rgb.shape == (height, width, 3) and rgb.dtype == np.uint8
    assert gray.shape == (height, width, 1) and gray.dtype == np.uint8


def test_wrong_number_of_flipper_angles() -> None:
    renderer = Renderer(TABLE, *SMALL)
    with pytest.raises(ValueError, match="flipper angles"):
        renderer.frame(None, REST[:1])


def test_static_elements_in_place_and_colour() -> None:
    renderer = Renderer(TABLE, *FULL)
    image = renderer.frame(None, REST)
    assert tuple(image[pixel(renderer, 0.255, 1.0699)]) == WALL  # arch top, in row 0
    assert pixel(renderer, 0.255, 1.0699)[0] == 0
    assert tuple(image[pixel(renderer, 0.468, 0.4)]) == WALL  # shooter lane wall
    assert tuple(image[pixel(renderer, 0.4865, 0.82)]) == ONE_SIDED  # the gate
    assert tuple(image[pixel(renderer, 0.16, 0.72)]) == KICKER  # pop bumper
    assert tuple(image[pixel(renderer, 0.04, 0.336)]) == POST  # guide post
    assert tuple(image[pixel(renderer, 0.105, 0.2825)]) == KICKER  # slingshot face
    assert tuple(image[pixel(renderer, *OPEN_SPOT)]) == BACKGROUND


def test_ball_is_drawn_where_it_is() -> None:
    renderer = Renderer(TABLE, *FULL)
    without = renderer.frame(None, REST)
    assert not has_colour(without, BALL).any()  # nothing else uses the ball's colour

    row, col = pixel(renderer, *OPEN_SPOT)
    image = renderer.frame(OPEN_SPOT, REST)
    assert has_colour(image[row - 3 : row + 4, col - 3 : col + 4], BALL).all()
    # Every ball pixel lies within a radius (plus a pixel) of the centre.
    rows, cols = np.nonzero(has_colour(image, BALL))
    x, y = world(renderer, rows, cols)
    reach = TABLE.ball.radius + 1.5 / 600.0
    assert np.all(np.hypot(x - OPEN_SPOT[0], y - OPEN_SPOT[1]) <= reach)
    assert np.array_equal(image[~has_colour(image, BALL)], without[~has_colour(image, BALL)])

    moved = (OPEN_SPOT[0] + 0.05, OPEN_SPOT[1] + 0.05)
    image = renderer.frame(moved, REST)
    new_row, new_col = pixel(renderer, *moved)
    assert tuple(image[row, col]) == BACKGROUND
    assert tuple(image[new_row, new_col]) == BALL


@pytest.mark.parametrize("position", [(-1.0, -1.0), (5.0, 0.5), (math.nan, 0.3)])
def test_ball_off_the_image_draws_nothing(position: tuple[float, float]) -> None:
    renderer = Renderer(TABLE, *SMALL)
    assert np.array_equal(renderer.frame(position, REST), renderer.frame(None, REST))


@pytest.mark.parametrize("size", [SMALL, (32, 32)])  # at 32x32 only the outline band saves it
def test_ball_never_vanishes_at_small_sizes(size: tuple[int, int]) -> None:
    renderer = Renderer(TABLE, *size)
    r = TABLE.ball.radius
    # A grid finer than the pixels (6 mm x 12.7 mm at 84x84): centres at many sub-pixel spots.
    for x in np.linspace(r, TABLE.width - r, 61):
        for y in np.linspace(r, TABLE.height - r, 97):
            pixels = has_colour(renderer.frame((x, y), REST), BALL).sum()
            assert pixels >= 1, (x, y)


@pytest.mark.parametrize("size", [SMALL, FULL])
def test_flipper_moves_only_in_its_region(size: tuple[int, int]) -> None:
    renderer = Renderer(TABLE, *size)
    flipper = TABLE.flippers[0]
    raised = [UP[0], *REST[1:]]
    rest, up = renderer.frame(None, REST), renderer.frame(None, raised)
    changed = np.any(rest != up, axis=-1)
    assert changed.any()
    # Changes stay inside the disc the flipper sweeps round its pivot, plus a pixel.
    rows, cols = np.nonzero(changed)
    x, y = world(renderer, rows, cols)
    pixel_size = max(TABLE.width / size[0], TABLE.height / size[1])
    reach = flipper.length + max(flipper.base_radius, flipper.tip_radius) + 1.5 * pixel_size
    assert np.all(np.hypot(x - flipper.pivot[0], y - flipper.pivot[1]) <= reach)

    tip = (
        flipper.pivot[0] + flipper.length * math.cos(UP[0]),
        flipper.pivot[1] + flipper.length * math.sin(UP[0]),
    )
    assert tuple(up[pixel(renderer, *tip)]) == FLIPPER
    assert tuple(rest[pixel(renderer, *tip)]) == BACKGROUND


def test_static_layer_is_not_modified() -> None:
    renderer = Renderer(TABLE, *SMALL)
    first = renderer.frame(None, REST)
    assert np.array_equal(first, renderer.frame(None, REST))
    renderer.frame(OPEN_SPOT, UP)
    renderer.grayscale(OPEN_SPOT, UP)
    first[...] = 255  # frames are the caller's own arrays
    again = renderer.frame(None, REST)
    assert not has_colour(again, BALL).any()
    assert np.array_equal(again, renderer.frame(None, REST))
    assert np.array_equal(renderer.grayscale(None, REST), renderer.grayscale(None, REST))


@pytest.mark.parametrize("size", [SMALL, FULL])
def test_grayscale_is_the_luma_of_the_frame(size: tuple[int, int]) -> None:
    renderer = Renderer(TABLE, *size)
    rgb = renderer.frame(OPEN_SPOT, UP).astype(np.int64)
    gray = renderer.grayscale(OPEN_SPOT, UP)
    # ITU-R BT.601 luma 0.299 R + 0.587 G + 0.114 B, rounded half up.
    luma = (299 * rgb[..., 0] + 587 * rgb[..., 1] + 114 * rgb[..., 2] + 500) // 1000
    assert np.array_equal(gray[..., 0], luma)

    ball = has_colour(renderer.frame(OPEN_SPOT, UP), BALL)
    assert gray[ball].min() > gray[~ball].max()  # the ball is the brightest thing
    flippers = has_colour(renderer.frame(OPEN_SPOT, UP), FLIPPER)
    background = has_colour(renderer.frame(OPEN_SPOT, UP), BACKGROUND)
    assert int(gray[flippers].min()) - int(gray[background].max()) > 100


def test_renderer_does_not_import_pygame() -> None:
    code = (
        "import sys\n"
        "from pinball_env.render import Renderer\n"
        "from pinball_env.table import load_table\n"
        "Renderer(load_table('classic'), 84, 84).frame((0.2, 0.3), [0.0, 3.0])\n"
        "assert 'pygame' not in sys.modules\n"
    )
    subprocess.run([sys.executable, "-c", code], check=True)


def test_window_shows_frames_headless(monkeypatch: pytest.MonkeyPatch) -> None:
    pytest.importorskip("pygame")
    monkeypatch.setenv("SDL_VIDEODRIVER", "dummy")
    renderer = Renderer(TABLE, *SMALL)
    window = Window((168, 168), fps=1000.0, title="test")
    try:
        window.show(renderer.frame(OPEN_SPOT, REST))  # scaled up to the window
        window.show(np.zeros((168, 168, 3), dtype=np.uint8))
    finally:
        window.close()
    window.close()  # a second close is harmless


def test_window_without_pygame(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setitem(sys.modules, "pygame", None)  # makes `import pygame` fail
    with pytest.raises(DependencyNotInstalled, match=r'pip install -e "\.\[render\]"'):
        Window((84, 84), fps=30.0)


def test_any_table_renders() -> None:
    table: Table = load_table("box")
    renderer = Renderer(table, 64, 48)
    angles = [0.0] * len(table.flippers)
    assert renderer.frame(None, angles).shape == (48, 64, 3)
