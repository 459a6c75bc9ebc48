"""Tests of the rasteriser (pinball_env.render.Renderer), the scoreboard, the cabinet in frames
(the player's plunger, the shake, the tilt warnings) and the pygame window."""

import hashlib
import math
import subprocess
import sys

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.error import DependencyNotInstalled

import pinball_env  # noqa: F401  (registers the envs)
from pinball_env.render import (
    BACKGROUND,
    BALL,
    FLIPPER,
    KICKER,
    ONE_SIDED,
    PIXELS_PER_METRE,
    PLUNGER,
    PLUNGER_TIP_FLOOR,
    POST,
    SCOREBOARD_ALERT,
    SHAKE_EXAGGERATION,
    WALL,
    Renderer,
    Window,
    luminance,
    render_size,
    scoreboard,
    text_mask,
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
    pygame = pytest.importorskip("pygame")
    monkeypatch.setenv("SDL_VIDEODRIVER", "dummy")
    frame = Renderer(TABLE, *SMALL).frame(OPEN_SPOT, REST)
    window = Window((168, 168), fps=1000.0, title="test")

    def shown() -> np.ndarray:  # the window's pixels, (H, W, 3) as the frames
        return pygame.surfarray.array3d(pygame.display.get_surface()).swapaxes(0, 1)

    try:
        window.show(frame)  # scaled up twice to the window: each pixel a 2x2 block
        assert np.array_equal(shown(), frame.repeat(2, axis=0).repeat(2, axis=1))
        window.show(np.zeros((168, 168, 3), dtype=np.uint8))  # the window's size: as it is
        assert not shown().any()
        assert not window.quit_requested()
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


# --- the cabinet ----------------------------------------------------------------------------

CABINET = load_table("classic_v1")
CABINET_REST = [math.radians(f.rest_angle) for f in CABINET.flippers]
PLUNGER_AT = CABINET.plunger.position
STROKE = CABINET.plunger.stroke


def ball_rows(image: np.ndarray) -> tuple[int, int]:
    """The first and last rows holding ball pixels."""
    rows = np.flatnonzero(has_colour(image, BALL).any(axis=1))
    return int(rows[0]), int(rows[-1])


def test_a_table_without_a_cabinet_renders_as_before() -> None:
    # render() frames of Pinball-v0, hashed: the same as before the cabinet (commit 601e8ae).
    env = gym.make("Pinball-v0", render_mode="rgb_array")
    env.reset(seed=5)
    rng = np.random.default_rng(5)
    digest = hashlib.sha256()
    for step in range(120):
        env.step(int(rng.integers(4)))
        if step % 20 == 0:
            digest.update(env.render().tobytes())
    assert digest.hexdigest() == (
        "d49adaeaa68b6b543052b55c98e0e01c6697201fa0c486b8dca63c3302beced9"
    )


def test_the_ball_on_the_plunger_is_drawn_pulled_back_with_it() -> None:
    renderer = Renderer(CABINET, *render_size(CABINET))
    sy = renderer.height / CABINET.height
    # The stroke (5 cm) would take the ball out of the picture: it is drawn scaled, the tip
    # coming down to PLUNGER_TIP_FLOOR at the whole stroke.
    assert 0.0 < renderer.pull_scale < 1.0
    tip_at_stroke = PLUNGER_AT[1] - CABINET.ball.radius - STROKE * renderer.pull_scale
    assert tip_at_stroke == pytest.approx(PLUNGER_TIP_FLOOR)
    rest = renderer.frame(PLUNGER_AT, CABINET_REST, plunger_pull=0.0, on_plunger=True)
    top, bottom = ball_rows(rest)
    row, col = pixel(renderer, PLUNGER_AT[0], PLUNGER_AT[1] - CABINET.ball.radius - 0.003)
    assert tuple(rest[row, col]) == PLUNGER  # the tip under the ball
    for pull in (0.25 * STROKE, 0.5 * STROKE, STROKE, 2 * STROKE):  # past the stroke: the stroke
        image = renderer.frame(PLUNGER_AT, CABINET_REST, plunger_pull=pull, on_plunger=True)
        drop = min(pull, STROKE) * renderer.pull_scale * sy
        new_top, new_bottom = ball_rows(image)
        assert abs(new_top - top - drop) <= 1 and abs(new_bottom - bottom - drop) <= 1
        assert has_colour(image, BALL).sum() == pytest.approx(has_colour(rest, BALL).sum(), 0.1)
        # The plunger fills the lane from the ball down to the picture's bottom edge.
        column = has_colour(image[:, col], PLUNGER)
        assert column[new_bottom + 2 :].all() and not column[: new_bottom - 2].any()


def test_the_plunger_is_pulled_back_without_a_ball_on_it() -> None:
    renderer = Renderer(CABINET, *render_size(CABINET))
    col = pixel(renderer, *PLUNGER_AT)[1]
    plain = renderer.frame(OPEN_SPOT, CABINET_REST)

    def tip_row(pull: float) -> int:
        image = renderer.frame(OPEN_SPOT, CABINET_REST, plunger_pull=pull)
        assert ball_rows(image) == ball_rows(plain)  # a ball in play stays where it is
        return int(np.flatnonzero(has_colour(image[:, col], PLUNGER))[0])

    assert tip_row(0.0) < tip_row(0.5 * STROKE) < tip_row(STROKE)
    # No pull given: no plunger drawn, the frame a table without a cabinet would have.
    assert not has_colour(plain, PLUNGER).any()
    assert np.array_equal(plain, renderer.frame(OPEN_SPOT, CABINET_REST, cabinet_offset=(0, 0)))


def test_the_cabinet_arguments_need_a_table_with_the_cabinet() -> None:
    with pytest.raises(ValueError, match="has no player's plunger"):
        Renderer(TABLE, *SMALL).frame(OPEN_SPOT, REST, plunger_pull=0.01)
    with pytest.raises(ValueError, match="on_plunger needs plunger_pull"):
        Renderer(CABINET, *SMALL).frame(OPEN_SPOT, CABINET_REST, on_plunger=True)
    with pytest.raises(ValueError, match=r"expected \(2, 2\) cabinet offsets"):
        Renderer(CABINET, *SMALL).frames(
            np.zeros((2, 2)), np.ones(2, bool), np.zeros((2, 2)), cabinet_offset=np.zeros(2)
        )


@pytest.mark.parametrize("offset", [(0.004, -0.003), (-0.007, 0.0), (0.0, 0.005)])
def test_the_shake_moves_the_whole_playfield(offset: tuple[float, float]) -> None:
    renderer = Renderer(CABINET, *render_size(CABINET))
    cabinet = {"plunger_pull": 0.02, "on_plunger": True}
    still = renderer.frame(PLUNGER_AT, CABINET_REST, **cabinet)
    moved = renderer.frame(PLUNGER_AT, CABINET_REST, **cabinet, cabinet_offset=offset)
    # Whole pixels: right and up the table by the offset (rows grow down the picture).
    rows = -round(offset[1] * PIXELS_PER_METRE)
    cols = round(offset[0] * PIXELS_PER_METRE)
    height, width = still.shape[:2]
    inside = moved[max(rows, 0) : height + min(rows, 0), max(cols, 0) : width + min(cols, 0)]
    source = still[max(-rows, 0) : height + min(-rows, 0), max(-cols, 0) : width + min(-cols, 0)]
    # The moving parts are painted at the moved world points: a pixel centre on an outline
    # may round the other way.
    assert np.sum(np.any(inside != source, axis=-1)) <= 4
    assert has_colour(moved, BALL).sum() == has_colour(still, BALL).sum()
    band = np.ones((height, width), bool)
    band[max(rows, 0) : height + min(rows, 0), max(cols, 0) : width + min(cols, 0)] = False
    assert band.sum() == abs(rows) * width + abs(cols) * height - abs(rows * cols)
    # The band the shift uncovers is the background (but for the rod, which runs out of the
    # picture's bottom edge).
    assert np.all(moved[band & ~has_colour(moved, PLUNGER)] == np.array(BACKGROUND, np.uint8))


@pytest.mark.parametrize("grayscale", [False, True])
def test_a_batch_draws_each_cabinet_as_one_frame_does(grayscale: bool) -> None:
    renderer = Renderer(CABINET, *SMALL)
    balls = np.array([PLUNGER_AT, OPEN_SPOT, PLUNGER_AT])
    waiting = np.array([True, False, True])
    pulls = np.array([0.0, 0.03, STROKE])
    offsets = np.array([[0.0, 0.0], [0.01, 0.02], [-0.02, -0.01]])
    angles = np.array([CABINET_REST] * 3)
    frames = renderer.frames(
        balls, np.ones(3, bool), angles, grayscale, plunger_pull=pulls, on_plunger=waiting,
        cabinet_offset=offsets,
    )  # fmt: skip
    one = renderer.grayscale if grayscale else renderer.frame
    for env in range(3):
        alone = one(
            tuple(balls[env]), CABINET_REST, plunger_pull=pulls[env], on_plunger=waiting[env],
            cabinet_offset=tuple(offsets[env]),
        )  # fmt: skip
        assert np.array_equal(frames[env], alone)
    if grayscale:  # the same drawing in luma; the ball still the brightest thing
        rgb = renderer.frames(
            balls, np.ones(3, bool), angles, plunger_pull=pulls, on_plunger=waiting,
            cabinet_offset=offsets,
        )  # fmt: skip
        assert np.array_equal(frames, luminance(rgb))
        assert luminance(PLUNGER)[0] < luminance(BALL)[0]


def test_the_scoreboard_shows_the_tilt_warnings_and_the_tilt() -> None:
    # The letters added for the cabinet differ from every other character.
    glyphs = {char: text_mask(char, 1).tobytes() for char in "0123456789ABCEGILNORSTW/"}
    for char in "GINTW/":
        assert [other for other, glyph in glyphs.items() if glyph == glyphs[char]] == [char]
    plain = scoreboard(642, 1230, 2)
    assert np.array_equal(plain, scoreboard(642, 1230, 2, tilt_warnings=0, allowed_warnings=2))
    assert not has_colour(plain, SCOREBOARD_ALERT).any()
    warned = scoreboard(642, 1230, 2, tilt_warnings=1, allowed_warnings=2)
    tilted = scoreboard(642, 1230, 2, tilt_warnings=3, allowed_warnings=2, tilted=True)
    for board, texts in ((warned, [("WARNING", 3), ("1/2", 4)]), (tilted, [("TILT", 4)])):
        alert = has_colour(board, SCOREBOARD_ALERT)
        assert alert.sum() == sum(text_mask(text, scale).sum() for text, scale in texts)
        top = np.flatnonzero(alert.any(axis=1))[0]
        assert np.array_equal(board[:top], plain[:top])  # below the score and the balls
        assert not alert[:, :5].any() and not has_colour(board[top:], (250, 195, 60)).any()
    # The first text drawn is the label, at the left margin, as SCORE and BALLS are.
    label = text_mask("TILT", 4)
    top = np.flatnonzero(has_colour(tilted, SCOREBOARD_ALERT).any(axis=1))[0]
    drawn = has_colour(tilted[top : top + label.shape[0], 5 : 5 + label.shape[1]], SCOREBOARD_ALERT)
    assert np.array_equal(drawn, label)


def test_the_env_frames_show_the_cabinet() -> None:
    env = gym.make("Pinball-v1", render_mode="rgb_array")
    env.reset(seed=0)
    core = env.unwrapped.core
    renderer = core.frame_renderers(env.unwrapped.table)
    width = renderer.width  # the playfield's; the scoreboard beside it
    first = env.render()
    assert has_colour(first[:, :width], PLUNGER).any()
    top = ball_rows(first[:, :width])[0]
    for _ in range(30):  # the plunger held for half a second: the ball goes down with it
        _, _, _, _, info = env.step(4)
    assert info["ball_on_plunger"] and info["plunger_pull"] > 0.0
    assert ball_rows(env.render()[:, :width])[0] > top
    # A nudge to the left: the playfield moves left by the offset, SHAKE_EXAGGERATION times.
    _, _, _, _, info = env.step(8)
    shift = round(SHAKE_EXAGGERATION * info["cabinet_offset"][0] * PIXELS_PER_METRE)
    assert shift < 0
    row = pixel(renderer, 0.468, 0.4)[0]
    walls = np.flatnonzero(has_colour(first[row, :width], WALL))  # the left one, the lane's...
    moved = np.flatnonzero(has_colour(env.render()[row, :width], WALL))
    assert np.array_equal(moved, (walls + shift)[walls + shift >= 0])  # the left one moved out
    # Nudges left and right in the plumb bob's rhythm: warnings, then the tilt.
    seen = set()
    for step in range(300):
        action = (8 if step // 16 % 2 == 0 else 16) if step % 16 == 0 else 0
        _, _, _, _, info = env.step(action)
        board = env.render()[:, width:]
        alert = has_colour(board, SCOREBOARD_ALERT).sum()
        if info["tilted"]:
            seen.add("tilt")
            assert alert == text_mask("TILT", 4).sum()
        elif info["tilt_warnings"]:
            seen.add("warning")
            texts = [("WARNING", 3), (f"{info['tilt_warnings']}/2", 4)]
            assert alert == sum(text_mask(text, scale).sum() for text, scale in texts)
        else:
            assert alert == 0
    assert seen == {"warning", "tilt"}


def test_the_renderer_draws_lamps_and_fallen_targets():
    import gymnasium as gym

    from pinball_env.render.colours import LIGHT_OFF, LIGHT_ON, TARGET, TARGET_DOWN

    env = gym.make("Pinball-v1", render_mode="rgb_array").unwrapped
    env.reset(seed=0)
    table = env.game.table
    renderer = env.core.frame_renderers(table)
    sx, sy = renderer.width / table.width, renderer.height / table.height

    def pixel(frame, x, y):
        row = renderer.top + int((table.height - y) * sy)
        return tuple(frame[row, renderer.left + int(x * sx)])

    light = table.rules.lights[0].at
    target = table.drop_target_list[1].segment
    middle = (0.5 * (target[0] + target[2]), 0.5 * (target[1] + target[3]))
    frame = env.render()
    assert pixel(frame, *light) == LIGHT_OFF and pixel(frame, *middle) == TARGET
    env.game.state.lights[0, 0] = True
    env.game.world.state.targets_up[0, 1] = False
    frame = env.render()
    assert pixel(frame, *light) == LIGHT_ON and pixel(frame, *middle) == TARGET_DOWN
