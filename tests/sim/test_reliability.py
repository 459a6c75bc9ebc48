"""No accepted table, reset or action can hang, blow up or leak the ball.

For any table that ``load_table`` accepts, any reset options it accepts and any valid actions,
every step returns within a bounded time, the state stays finite, the ball stays inside the
outline and never ends a frame overlapping a wall, post or flipper by more than the skin, and
every game can end. These tests cover each defect found when this promise was first tried.
"""

import copy
import math
import subprocess
import sys
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest
import yaml
from gymnasium.error import ResetNeeded
from hypothesis import given, reject, settings
from hypothesis import strategies as st
from numpy.testing import assert_array_equal

import pinball_env  # noqa: F401  (registers Pinball-v0)
from pinball_env.game import BALL_SEARCH_TIME, Game
from pinball_env.physics import deepest_overlap
from pinball_env.physics.columns import (
    BALL_SPIN,
    BALL_VX,
    BALL_VY,
    FLIPPER_REST_ANGLE,
    FLIPPER_UP_ANGLE,
)
from pinball_env.render import SCOREBOARD_WIDTH, render_size, text_mask
from pinball_env.sim.world import World
from pinball_env.table import TableError, builtin_tables_dir, load_table, table_from_dict
from tests.sim.soundness import assert_sound

ROOT = Path(__file__).resolve().parents[2]


def classic_dict() -> dict:
    return yaml.safe_load((builtin_tables_dir() / "classic.yaml").read_text())


def box_dict() -> dict:
    return yaml.safe_load((builtin_tables_dir() / "box.yaml").read_text())


# --- 1. energy and work are bounded ----------------------------------------------------------


@pytest.mark.parametrize(
    ("path", "value", "message"),
    [
        (("materials", "wall", "restitution"), 1.5, "restitution: 1.5 is out of range"),
        (("posts", 0, "kick"), 1.0e300, "kick: 1e+300 is out of range"),
        (("simulation", "skin"), 1.0e-300, "skin: 1e-300 is out of range"),
        (("gravity",), 1.0e300, "gravity: 1e+300 is out of range"),
        (("ball", "radius"), 1.0e-300, "radius: 1e-300 is out of range"),
        (("playfield", "width"), 1.0e300, "width: 1e+300 is out of range"),
        (("flippers", 0, "length"), 1.0e300, "length: 1e+300 is out of range"),
        (("simulation", "resting_speed"), 1.0e300, "resting_speed: 1e+300 is out of range"),
        (("walls", 8, "score"), 2**63, "score: 9223372036854775808 is out of range"),
    ],
)
def test_absurd_numbers_are_rejected(path, value, message):
    data = classic_dict()
    if path == ("simulation", "skin") or path == ("simulation", "resting_speed"):
        data["simulation"] = {}
    target = data
    for key in path[:-1]:
        target = target[key]
    target[path[-1]] = value
    with pytest.raises(TableError, match=message.replace("+", r"\+")):
        table_from_dict(data, "t.yaml")


def test_a_kicker_must_lose_energy_at_a_bounce():
    data = classic_dict()
    data["materials"]["bumper"]["restitution"] = 1.0
    with pytest.raises(TableError, match="kicker needs a material with restitution < 1"):
        table_from_dict(data)


ABSURD_STATE_SCRIPT = """
import numpy as np
from pinball_env.table import load_table
from pinball_env.sim.world import World
world = World(load_table("classic"))
world.step(np.array([[True, False]]))  # the left flipper swings
for speed in (1e6, 1e12, 1e300, float("inf")):
    world.state.balls[0] = (0.2, 0.14, speed, -speed, 0.0)
    world.state.active[0] = True
    try:
        for _ in range(3):
            world.step(np.array([[True, True]]))
        print(speed, "stepped")
    except FloatingPointError as error:
        print(speed, "reported:", error)
"""


def test_a_step_from_an_absurd_state_returns():
    # In a subprocess with a timeout: a regression that loops for ever cannot hang the suite.
    result = subprocess.run(
        [sys.executable, "-c", ABSURD_STATE_SCRIPT],
        cwd=ROOT, capture_output=True, text=True, timeout=120, check=True,
    )  # fmt: skip
    lines = result.stdout.splitlines()
    assert len(lines) == 4
    assert lines[-1].startswith("inf reported: the ball state of env(s) [0] is no longer finite")


def test_place_ball_rejects_non_finite_and_absurd_states():
    world = World(load_table("classic"))
    with pytest.raises(ValueError, match="finite"):
        world.place_ball(0, (0.2, 0.5), (math.inf, 0.0))
    with pytest.raises(ValueError, match="finite"):
        world.place_ball(0, (math.nan, 0.5))
    with pytest.raises(ValueError, match="above"):
        world.place_ball(0, (0.2, 0.5), (1e5, 0.0))


# --- 2. what is read is bounded ------------------------------------------------------------------


def test_a_yaml_alias_bomb_gives_a_short_error(tmp_path):
    levels = ["&a0 [x, x, x, x, x, x, x, x, x, x]"]
    levels += [f"&a{i} [" + ", ".join([f"*a{i - 1}"] * 10) + "]" for i in range(1, 9)]
    text = (builtin_tables_dir() / "box.yaml").read_text()
    path = tmp_path / "bomb.yaml"
    path.write_text(text.replace("name: box", "name: [" + ", ".join(levels) + "]"))
    with pytest.raises(TableError, match="name: expected a non-empty string") as error:
        load_table(path)
    assert len(str(error.value)) < 1000


def test_a_huge_file_is_not_read(tmp_path):
    path = tmp_path / "huge.yaml"
    path.write_text("# padding\n" * 200_000)
    with pytest.raises(TableError, match="a table file may have at most"):
        load_table(path)


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("deep", "nested too deeply"),
        (None, r"gravity: 9999999999.*is out of range \(too large\)"),
    ],
)
def test_bad_files_give_table_errors_not_other_exceptions(tmp_path, text, message):
    if text == "deep":  # deeper than the recursion limit (moviepy, once imported, raises it)
        depth = 2 * sys.getrecursionlimit()
        text = "name: " + "[" * depth + "]" * depth + "\n"
    if text is None:  # an integer literal of 400 digits
        text = (builtin_tables_dir() / "box.yaml").read_text()
        text = text.replace("gravity: 9.81", "gravity: " + "9" * 400)
    path = tmp_path / "bad.yaml"
    path.write_text(text)
    with pytest.raises(TableError, match=message):
        load_table(path)


def test_odd_names_and_options_give_clear_errors():
    with pytest.raises(TableError, match="cannot read the file") as error:
        load_table("a" * 5000 + ".yaml")
    assert len(str(error.value)) < 400
    with pytest.raises(TypeError, match="a table is a name or a path, got NoneType"):
        load_table(None)
    env = gym.make("Pinball-v0")
    env.reset(seed=0)
    for options in ({1: 1, "a": 2}, {"x" * 10**6: 1}):
        with pytest.raises(ValueError, match="unknown reset option") as error:
            env.reset(options=options)
        assert len(str(error.value)) < 200
    with pytest.raises(ValueError, match=r"speed 100.0000001 m/s is above 100 m/s"):
        env.reset(options={"ball_velocity": [0.0, 100.0000001]})


# --- 3. tables that would let the ball out --------------------------------------------------------


def test_a_one_sided_outline_is_rejected():
    data = classic_dict()
    data["walls"][0]["one_sided"] = True
    data["walls"][0]["points"] = data["walls"][0]["points"][::-1]  # normals facing out
    with pytest.raises(TableError, match=r"outline .* must be two-sided"):
        table_from_dict(data)


@pytest.mark.parametrize(
    ("key", "element"),
    [
        ("walls", {"name": "x", "points": [[0.17, 0.14], [0.26, 0.14]], "material": "wall"}),
        ("posts", {"name": "x", "center": [0.20, 0.135], "radius": 0.004, "material": "rubber"}),
    ],
)
def test_nothing_may_lie_in_a_flippers_swing(key, element):
    data = classic_dict()
    data[key].append(element)
    with pytest.raises(TableError, match="lies in the flipper's swing"):
        table_from_dict(data)


def test_a_ball_pinched_against_a_wall_stays_out_of_it_and_stops_spinning():
    data = classic_dict()
    data["walls"].append(
        {"name": "lid", "points": [[0.10, 0.168], [0.30, 0.168]], "material": "wall"}
    )
    world = World(table_from_dict(data))
    world.place_ball(0, (0.216, 0.1525), (0.0, -0.25))
    pinched = 0
    for _ in range(60):
        world.step(np.array([[True, False]]))
        assert_sound(world)
        ball = world.balls[0, 0]
        if ball[BALL_VX] == ball[BALL_VY] == 0.0:
            pinched += 1
            assert ball[BALL_SPIN] == 0.0
    assert pinched > 10


def test_a_ball_squeezed_against_a_slanted_wall_stays_out_of_it_and_of_the_flipper():
    # Found in review: flipper, wall, flipper, ... the last push, the flipper's, went into the
    # wall (56 skins deep). The flipper's push is now swept against the walls.
    data = classic_dict()
    data["walls"].append(
        {"name": "lid", "points": [[0.12, 0.184], [0.32, 0.172]], "material": "wall"}
    )
    world = World(table_from_dict(data))
    world.place_ball(0, (0.215, 0.145))
    for _ in range(240):
        world.step(np.array([[True, False]]))
        assert_sound(world)


def test_a_cut_sweep_is_no_pinch():
    # Found in review: a flipper sweep that ran out of slices was taken for a pinch, and the
    # flipper was put back onto the ball (11.8 mm deep).
    data = classic_dict()
    data["simulation"] = {"frame_rate": 1.0, "substeps": 1, "max_passes": 4, "skin": 1.0e-7}
    data["posts"].append(
        {"name": "x0", "center": [0.2722, 0.1797], "radius": 0.0187, "material": "rubber"}
    )
    world = World(table_from_dict(data))
    world.step(np.array([[True, True]]))
    world.place_ball(0, (0.2317, 0.1500), (-2.90, 4.11))
    for _ in range(5):
        world.step(np.array([[False, False]]))
        assert_sound(world)


def test_a_small_ball_between_a_resting_flipper_and_a_guide_stays_out_of_both():
    data = classic_dict()
    data["ball"]["radius"] = 0.0079
    world = World(table_from_dict(data))
    world.place_ball(0, (0.1392, 0.1383))
    for _ in range(600):
        world.step(np.array([[False, False]]))
        assert_sound(world)


def pocket_table(radius, walls=(), posts=(), flippers=("left_flipper", "right_flipper"), **sim):
    """Classic's outline and flippers, no plunger, a ball of ``radius`` and the given walls and
    posts: the pockets a reviewer built around the flippers (tables without a plunger, balls
    placed through World)."""
    data = classic_dict()
    data["ball"].update(radius=radius, start=[0.2365, 0.45])
    data["simulation"].update(sim)
    data["walls"] = [w for w in data["walls"] if w["name"] == "outline"]
    data["walls"] += [
        {"name": f"w{i}", "points": points, "material": "wall"} for i, points in enumerate(walls)
    ]
    data["posts"] = [
        {"name": f"p{i}", "center": centre, "radius": size, "material": "bumper"}
        for i, (centre, size) in enumerate(posts)
    ]
    data["flippers"] = [f for f in data["flippers"] if f["name"] in flippers]
    data["sensors"] = []
    del data["plunger"]
    return table_from_dict(data)


POCKETS = {
    # A big ball on both flippers, under a post the rising flippers push it into (it crept
    # 15 um a frame into the post, to 3.3 mm).
    "post over both flippers": (
        dict(radius=0.02299, walls=[[[0.17498, 0.16435], [0.20293, 0.17747]]],
             posts=[([0.22534, 0.173], 0.01811)], frame_rate=119),
        (0.23666, 0.10969), (0.0, 0.0),
    ),
    # A V of walls over the left flipper, closed by it (10.6 mm into a wall).
    "V over a flipper": (
        dict(radius=0.02733, walls=[[[0.08337, 0.10847], [0.22736, 0.20402]],
                                    [[0.41148, 0.1036], [0.22033, 0.17756]]],
             flippers=("left_flipper",)),
        (0.20624, 0.15292), (-4.263, 3.91),
    ),
    # A small ball under a bent wall over the left flipper (3.3 mm into the wall).
    "bent wall over a flipper": (
        dict(radius=0.0093, walls=[[[0.1744, 0.1513], [0.1815, 0.1649], [0.1932, 0.1623]]],
             frame_rate=50),
        (0.1872, 0.1537), (0.0, 0.0),
    ),
    # A long wall over both raised flippers, closer than a ball (1.6 mm into it).
    "wall over both flippers": (
        dict(radius=0.0274, walls=[[[0.1187, 0.1347], [0.3088, 0.2291]]], frame_rate=42,
             substeps=9, max_passes=5, skin=3.4e-05),
        (0.2262, 0.1213), (0.0, 0.0),
    ),
}  # fmt: skip
STALLED = {"post over both flippers", "V over a flipper", "bent wall over a flipper"}


@pytest.mark.parametrize("name", POCKETS)
def test_a_pocket_that_flippers_close_on_a_ball_stalls_them(name):
    # Found in review: among three or more surfaces no position clears them all, and the
    # rising flippers closed the pocket a little further every frame. Now the substep that
    # would leave the ball inside a surface is undone, and the flippers stall.
    kwargs, position, velocity = POCKETS[name]
    world = World(pocket_table(**kwargs))
    world.place_ball(0, position, velocity)
    for _ in range(120):
        world.step(np.array([[True, True]]))
        assert_sound(world)
    up = world.geometry.flippers[:, FLIPPER_UP_ANGLE]
    stalled = (world.state.flipper_angle[0] != up).any()
    assert stalled == (name in STALLED)  # in the last pocket the ball slips out
    for _ in range(120):  # released, the flippers fall back and free the ball
        world.step(np.array([[False, False]]))
        assert_sound(world)
    rest = world.geometry.flippers[:, FLIPPER_REST_ANGLE]
    assert_array_equal(world.state.flipper_angle[0], rest)


def test_a_ball_is_never_nudged_through_a_wall():
    # Found in review: clearing a ball wedged between two nearly parallel surfaces moved it
    # 21 cm in one go, out through the outline. Moves made without a sweep are now short.
    data = classic_dict()
    data["ball"]["radius"] = 0.00927
    data["simulation"] = {
        "frame_rate": 37.47, "substeps": 14, "max_passes": 28, "skin": 3.02e-05,
        "resting_speed": 0.0,
    }  # fmt: skip
    data["materials"]["wall"] = {"restitution": 0.556, "friction": 1.807}
    data["materials"]["flipper"] = {"restitution": 0.125, "friction": 1.377}
    data["walls"].append(
        {"name": "x1", "points": [[0.16624, 0.14398], [0.17693, 0.15395], [0.18243, 0.15463]],
         "material": "bumper"}
    )  # fmt: skip
    world = World(table_from_dict(data))
    world.place_ball(0, (0.16962, 0.13181))
    for _ in range(60):
        world.step(np.array([[True, True]]))
        assert_sound(world)


@settings(max_examples=60, deadline=None)
@given(
    radius=st.floats(0.004, 0.03),
    along=st.floats(0.0, 1.0),
    gap=st.floats(0.0003, 0.06),
    lean=st.floats(-0.5, 0.5),
    post=st.one_of(st.none(), st.floats(0.002, 0.02)),
    seed=st.integers(0, 2**32 - 1),
)
def test_balls_in_tight_places_around_the_flippers_stay_sound(radius, along, gap, lean, post, seed):
    # A wall (or a post of radius ``post``) ``gap`` above the raised left flipper, a fraction
    # ``along`` of its length out (outside the swing, as the loader requires); balls placed
    # wherever they fit near it; the buttons held for random spells.
    pivot, length, up = np.array([0.146, 0.12]), 0.07, math.radians(25.0)
    u = np.array([math.cos(up), math.sin(up)])  # along the raised flipper
    v = np.array([-u[1], u[0]])  # its upper side
    half_width = 0.0116 + (0.007 - 0.0116) * along
    spot = pivot + length * along * u + (half_width + gap) * v
    if post is None:
        d = np.array([math.cos(up + lean), math.sin(up + lean)]) * 0.05
        walls, posts = [[(spot - d).tolist(), (spot + d).tolist()]], []
    else:
        walls, posts = [], [((spot + post * v).tolist(), post)]
    try:
        table = pocket_table(radius, walls=walls, posts=posts)
    except TableError:  # it lay in the swing, or left no room for the ball's start
        reject()
    world = World(table, n_envs=8)
    rng = np.random.default_rng(seed)
    angles = world.geometry.flippers[:, FLIPPER_REST_ANGLE].copy()
    placed = 0
    for _ in range(2000):
        x, y = spot + rng.uniform(-0.06, 0.06, size=2)
        up = world.state.targets_up[0]
        if deepest_overlap(x, y, world.geometry, angles, up, radius) < -table.simulation.skin:
            world.place_ball(placed, (x, y), rng.normal(0.0, 0.5, size=2))
            placed += 1
            if placed == 8:
                break
    held = np.zeros((8, 2), dtype=bool)
    for _ in range(150):
        flip = rng.random((8, 2)) < 0.1  # spells of about 10 frames
        held = np.where(flip, ~held, held)
        world.step(held)
        assert_sound(world)


@settings(max_examples=12)
@given(seed=st.integers(0, 2**32 - 1))
def test_random_play_keeps_every_ball_sound(seed):
    world = World(load_table("classic"), n_envs=8)
    rng = np.random.default_rng(seed)
    for env in range(8):
        world.launch(env, rng.uniform(2.2, 3.2))
    for _ in range(400):
        world.step(rng.integers(0, 2, size=(8, 2)).astype(bool))
        assert_sound(world)


# --- 4. every game can end ------------------------------------------------------------------------


def test_a_ball_at_rest_in_the_shooter_lane_is_served_again():
    env = gym.make("Pinball-v0", balls=1)
    env.reset(seed=0, options={"ball_velocity": [0.0, 0.5]})
    frames = round((BALL_SEARCH_TIME + 3.0) * 60)  # it settles in about 2 s
    heights = [env.step(0)[4]["ball_position"][1] for _ in range(frames)]
    assert max(heights[:120]) < 0.2  # it rose 11 cm and fell back onto the plunger
    assert max(heights) > 0.5  # then the ball search fired it up the lane
    # And with random play the game ends.
    rng = np.random.default_rng(0)
    for _ in range(20_000):
        if env.step(int(rng.integers(0, 4)))[2]:
            break
    else:
        pytest.fail("the game did not end")


def test_a_table_whose_drain_no_ball_can_reach_cannot_be_played():
    data = classic_dict()
    data["sensors"][-1]["points"] = [[0.088, 0.26], [0.11, 0.26]]  # inside the left slingshot
    table = table_from_dict(data)
    assert not table.drain_reachable and load_table("classic").drain_reachable
    with pytest.raises(ValueError, match="no drain can be reached from the plunger"):
        gym.make("Pinball-v0", table=table)


def test_the_ball_search_clock_is_part_of_the_snapshot():
    game = Game(load_table("classic"))
    game.new_game(0, np.random.default_rng(0), {"ball_velocity": [0.0, 0.5]})
    rngs = [np.random.default_rng(1)]
    for _ in range(100):
        game.step(np.array([0]), rngs)
    snapshot = game.snapshot()
    assert snapshot.still_frames[0] > 0
    game.restore(snapshot)
    assert game.state.still_frames[0] == snapshot.still_frames[0]


# --- 5. fuzz: every table the loader accepts is sound -------------------------------------------

NUMBERS = st.one_of(
    st.floats(allow_nan=True, allow_infinity=True),
    st.integers(-(2**70), 2**70),
    st.sampled_from([0, 1, -1, 0.5, 1e-300, 1e300, 2**63, 0.0135, 0.3, 1.0]),
)
# Most mutations nudge a number (so that many fuzzed tables load and are played); the rest put
# anything anywhere.
NUDGE = st.tuples(st.just("nudge"), st.floats(0.8, 1.25), st.floats(-0.005, 0.005))
WILD = st.one_of(NUMBERS, st.none(), st.text(max_size=5), st.lists(NUMBERS, max_size=3))
VALUES = st.integers(0, 3).flatmap(lambda n: WILD if n == 0 else NUDGE)


def mutate(data: dict, picks: list, values: list) -> None:
    """Change leaves of ``data`` chosen by ``picks`` (indices into its leaf paths): set them to
    ``values``, or for a ("nudge", factor, offset) scale a number and shift it."""
    for pick, value in zip(picks, values, strict=True):
        paths = list(leaf_paths(data))
        path = paths[pick % len(paths)]
        target = data
        for key in path[:-1]:
            target = target[key]
        old = target[path[-1]]
        if isinstance(value, tuple):
            _, factor, offset = value
            if isinstance(old, bool) or not isinstance(old, (int, float)):
                continue
            value = round(old * factor) if isinstance(old, int) else old * factor + offset
        target[path[-1]] = value


def leaf_paths(node, prefix=()):
    if isinstance(node, dict):
        for key, value in node.items():
            yield from leaf_paths(value, (*prefix, key))
    elif isinstance(node, list) and node:
        for i, value in enumerate(node):
            yield from leaf_paths(value, (*prefix, i))
    else:
        yield prefix


@settings(max_examples=300)
@given(
    base=st.sampled_from(["classic", "box"]),
    picks=st.lists(st.integers(0, 10_000), min_size=1, max_size=3),
    data=st.data(),
)
def test_fuzzed_tables_are_rejected_clearly_or_play_soundly(base, picks, data):
    raw = copy.deepcopy(classic_dict() if base == "classic" else box_dict())
    mutate(raw, picks, [data.draw(VALUES) for _ in picks])
    try:
        table = table_from_dict(raw, "fuzz.yaml")
    except TableError as error:  # rejected clearly
        assert str(error).startswith("fuzz.yaml: ") and len(str(error)) < 1000
    else:  # or plays soundly
        world = World(table, n_envs=2)
        rng = np.random.default_rng(0)
        if table.plunger is not None:
            world.launch(1, table.plunger.speed[1])
        for _ in range(120):
            world.step(rng.integers(0, 2, size=(2, 2)).astype(bool))
            assert_sound(world)


# --- 6. a new user's first tries ----------------------------------------------------------------


def test_image_size_may_be_one_int_and_is_checked():
    env = gym.make("Pinball-v0", obs_type="grayscale", image_size=64)
    assert env.reset(seed=0)[0].shape == (64, 64, 1)
    with pytest.raises(ValueError, match="image_size must be an int or"):
        gym.make("Pinball-v0", obs_type="rgb", image_size="big")


def test_stepping_before_reset_needs_a_reset():
    env = gym.make("Pinball-v0").unwrapped
    with pytest.raises(ResetNeeded):
        env.step(0)


def test_frames_show_a_scoreboard_and_the_drained_ball():
    env = gym.make("Pinball-v0", render_mode="rgb_array", balls=1)
    env.reset(seed=0)
    width, height = render_size(env.unwrapped.table)
    first = env.render()
    assert first.shape == (height, width + SCOREBOARD_WIDTH, 3)
    while not env.step(0)[2]:
        pass
    last = env.render()
    assert not np.array_equal(first[:, width:], last[:, width:])  # the balls left changed
    empty = env.unwrapped.core.frame_renderers(env.unwrapped.table).frame(
        None, env.unwrapped.game.world.state.flipper_angle[0]
    )
    assert not np.array_equal(last[:, :width], empty)  # the drained ball is drawn


def test_every_scoreboard_character_is_distinct():
    glyphs = [text_mask(char, 1).tobytes() for char in "0123456789ABCELORS"]
    assert len(set(glyphs)) == len(glyphs) - 2  # O is 0 and S is 5, as on a real display
