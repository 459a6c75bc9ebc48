"""Several balls in one env (``physics.multiball``): analytic ball-ball collisions, the earliest
contact among a pair and a wall, momentum, the kernel's promises under random starts (no overlap
beyond the skin, no escape, finite state, bounded passes), balls at rest together, one ball as
``step_ball`` has it, and two balls cradled on a raised flipper."""

import math
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import yaml
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st

from pinball_env.physics.columns import BALL_VX, BALL_VY, BALL_X, BALL_Y
from pinball_env.physics.contact import deepest_overlap
from pinball_env.physics.multiball import make_multiball, place, step_multiball
from pinball_env.sim.world import World
from pinball_env.table import builtin_tables_dir, load_table, table_from_dict

BOX = load_table("box")
R = BOX.ball.radius
SKIN = BOX.simulation.skin
DT = 1.0 / BOX.simulation.frame_rate
# The box's outline, from box.yaml: walls at x = 0.01 and 0.50, y = 0.01 and 1.06.
LEFT, RIGHT, FLOOR, TOP = 0.01, 0.50, 0.01, 1.06


def level_box():
    """The box laid level (slope 0): no gravity in the plane, balls fly straight."""
    data = yaml.safe_load((builtin_tables_dir() / "box.yaml").read_text(encoding="utf-8"))
    data["slope_deg"] = 0.0
    return table_from_dict(data, "<level box>")


LEVEL = level_box()


def world_with(table, balls, pair=(1.0, 0.0), held=()):
    """A one-env world with ``balls`` ((position, velocity) each) in play."""
    world = make_multiball(table, 1, len(balls), pair=pair)
    for i, (position, velocity) in enumerate(balls):
        place(world, 0, i, position, velocity, held=i in held)
    return world


def state(world):
    """Env 0's balls, a copy."""
    return world.state.balls[0].copy()


def contacts(world):
    """Env 0's logged contacts of the last frame: (element, time) pairs."""
    count = min(world.state.contact_count[0], world.state.contacts.shape[1])
    return [(int(c[0]), c[1]) for c in world.state.contacts[0, :count]]


def min_distance(balls, active):
    """The least centre distance between two balls in play (inf for fewer than two)."""
    points = balls[active][:, [BALL_X, BALL_Y]]
    best = math.inf
    for i in range(len(points)):
        for j in range(i + 1, len(points)):
            best = min(best, math.dist(points[i], points[j]))
    return best


def test_head_on_at_restitution_1_exchanges_the_velocities_at_the_analytic_time():
    # Same height, so gravity (along -y) leaves the relative motion alone.
    world = world_with(BOX, [((0.15, 0.5), (1.0, 0.0)), ((0.35, 0.5), (-1.0, 0.0))])
    contact = (0.2 - 2 * R) / 2.0  # the gap closes at 2 m/s
    frames = math.ceil(contact / DT)
    for _ in range(frames):
        step_multiball(world)
    a, b = state(world)
    assert abs(a[BALL_VX] + 1.0) < 1e-9 and abs(b[BALL_VX] - 1.0) < 1e-9
    assert abs(a[BALL_VY] - b[BALL_VY]) < 1e-12
    # Back from where a is: it came at +1 until the contact, left half a skin back (the
    # separation), then went at -1.
    time = frames * DT
    measured = (a[BALL_X] - 0.15 + 0.5 * SKIN + time) / 2.0
    assert abs(measured - contact) < 1e-12
    assert abs(b[BALL_X] - 0.35 - (-contact + (time - contact)) - 0.5 * SKIN) < 1e-12


def test_a_ball_onto_a_resting_ball_stops_and_sets_it_moving():
    # Level: head-on, the moving ball stops and the resting one leaves at its velocity.
    world = world_with(LEVEL, [((0.15, 0.5), (1.5, 0.0)), ((0.30, 0.5), (0.0, 0.0))])
    for _ in range(8):
        step_multiball(world)
    a, b = state(world)
    assert abs(a[BALL_VX]) < 1e-9 and abs(b[BALL_VX] - 1.5) < 1e-9
    # Oblique, at an impact parameter of r sqrt(2) (45 degrees): they leave at right angles,
    # the energy kept (no friction, restitution 1).
    world = world_with(LEVEL, [((0.15, 0.5), (1.5, 0.0)), ((0.30, 0.5 - R * math.sqrt(2)), (0, 0))])
    for _ in range(8):
        step_multiball(world)
    a, b = state(world)
    va, vb = a[[BALL_VX, BALL_VY]], b[[BALL_VX, BALL_VY]]
    assert abs(va @ vb) < 1e-9
    assert abs(va @ va + vb @ vb - 1.5**2) < 1e-12
    assert np.allclose(va + vb, [1.5, 0.0], atol=1e-12)
    assert abs(math.atan2(vb[1], vb[0]) + math.pi / 4) < 1e-9


def test_a_ball_bounces_off_a_held_ball_as_off_a_post():
    world = world_with(
        LEVEL, [((0.15, 0.5), (1.5, 0.0)), ((0.30, 0.5), (0.0, 0.0))], pair=(0.5, 0.0), held=(1,)
    )
    for _ in range(8):
        step_multiball(world)
    a, b = state(world)
    assert abs(a[BALL_VX] + 0.75) < 1e-12
    assert b[BALL_X] == 0.30 and b[BALL_VX] == 0.0


def wall_and_pair(wall_gap):
    """Level box: ball a ``wall_gap`` short of the right wall at +1 m/s, ball b 12 mm behind
    it at +2 m/s (the pair would meet after 12 ms)."""
    xa = RIGHT - R - wall_gap
    return world_with(LEVEL, [((xa, 0.5), (1.0, 0.0)), ((xa - 2 * R - 0.012, 0.5), (2.0, 0.0))])


def test_the_wall_first_when_it_comes_first():
    world = wall_and_pair(0.005)
    step_multiball(world)
    right_wall = 1  # outline[1]: (0.50, 0.01) -> (0.50, 1.06)
    wall_restitution = 0.3
    log = contacts(world)
    assert log[0][0] == right_wall and abs(log[0][1] - 0.005) < 1e-12
    # Then the pair, then the wall again: the second wall time follows from the pair's.
    t1 = 0.005
    xa, xb = RIGHT - R - SKIN, RIGHT - R - 0.005 - 2 * R - 0.012 + 2.0 * t1
    t2 = t1 + (xa - xb - 2 * R) / (2.0 + wall_restitution)
    xa -= wall_restitution * (t2 - t1)
    xa += 0.5 * (2 * R + SKIN - (xa - (xb + 2.0 * (t2 - t1))))
    t3 = t2 + (RIGHT - R - xa) / 2.0
    assert log[1][0] == right_wall and abs(log[1][1] - t3) < 1e-9


def test_the_pair_first_when_it_comes_first():
    world = wall_and_pair(0.05)
    step_multiball(world)
    assert contacts(world) == []  # the pair met at 12 ms; a reaches the wall after the frame
    a, b = state(world)
    assert abs(a[BALL_VX] - 2.0) < 1e-12 and abs(b[BALL_VX] - 1.0) < 1e-12
    xa = RIGHT - R - 0.05 + 0.012 + 2.0 * (DT - 0.012) + 0.5 * SKIN
    assert abs(a[BALL_X] - xa) < 1e-12


def test_three_balls_in_a_row_pass_the_momentum_along():
    gap = 2 * R + SKIN
    world = world_with(
        LEVEL,
        [((0.10, 0.5), (1.0, 0.0)), ((0.20, 0.5), (0, 0)), ((0.20 + gap, 0.5), (0, 0))],
    )
    for _ in range(12):  # the end ball reaches the right wall after some 17 frames
        step_multiball(world)
        balls = state(world)
        assert abs(balls[:, BALL_VX].sum() - 1.0) < 1e-12
        assert abs(balls[:, BALL_VY].sum()) < 1e-12
        assert min_distance(balls, np.ones(3, bool)) >= 2 * R - 1e-12
    assert np.allclose(balls[:, BALL_VX], [0.0, 0.0, 1.0], atol=1e-9)


def clear_start(table, points):
    """Whether balls at ``points`` overlap no solid element and no other ball."""
    geometry = table.pack()
    angles = np.zeros(geometry.flippers.shape[0])
    up = np.ones(geometry.drop_targets.shape[0], dtype=bool)
    for i, (x, y) in enumerate(points):
        if deepest_overlap(x, y, geometry, angles, up, R) > -SKIN:
            return False
        if any(math.dist((x, y), q) < 2 * R + SKIN for q in points[:i]):
            return False
    return True


coordinate_x = st.floats(LEFT + R + 1e-4, RIGHT - R - 1e-4)
coordinate_y = st.floats(FLOOR + R + 1e-4, TOP - R - 1e-4)
velocity = st.floats(-5.0, 5.0)


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.filter_too_much])
@given(
    st.lists(st.tuples(coordinate_x, coordinate_y, velocity, velocity), min_size=2, max_size=4),
    st.booleans(),
)
def test_random_balls_in_the_box_never_overlap_escape_or_blow_up(balls, first_held):
    points = [(x, y) for x, y, _, _ in balls]
    assume(clear_start(BOX, points))
    held = (0,) if first_held else ()
    world = world_with(BOX, [((x, y), (vx, vy)) for x, y, vx, vy in balls], held=held)
    start = state(world)
    m = len(balls)
    cap = BOX.simulation.substeps * BOX.simulation.max_passes * m
    for _ in range(600):
        assert step_multiball(world) == 0
        assert world.scratch.passes[0] <= cap
        b = state(world)
        assert np.isfinite(b).all()
        assert world.state.active[0].all()  # the box has no drain
        assert min_distance(b, np.ones(m, bool)) >= 2 * R - SKIN - 1e-9
        assert (b[:, BALL_X] >= LEFT + R - SKIN).all() and (b[:, BALL_X] <= RIGHT - R + SKIN).all()
        assert (b[:, BALL_Y] >= FLOOR + R - SKIN).all() and (b[:, BALL_Y] <= TOP - R + SKIN).all()
        if first_held:  # a held ball does not move
            assert (b[0] == start[0]).all()


@pytest.mark.parametrize("held", [(), (0,)])
def test_balls_resting_in_a_corner_stay_still_for_a_minute(held):
    # Held: the first, in the corner, is a locked ball that the others queue against.
    corner = (LEFT + R + SKIN, FLOOR + R + SKIN)
    world = world_with(
        BOX,
        [
            (corner if held else (0.05, 0.10), (0, 0)),
            ((0.10, 0.12), (0, 0)),
            ((0.06, 0.16), (0, 0)),
        ],
        held=held,
    )
    # Gravity into the bottom left corner: the balls heap up there.
    world.settings = world.settings._replace(gravity_x=-0.6)
    tail = []
    for frame in range(3600):
        step_multiball(world)
        b = state(world)
        assert min_distance(b, np.ones(3, bool)) >= 2 * R - SKIN - 1e-9
        if frame >= 3540:
            tail.append(b[:, [BALL_X, BALL_Y]].copy())
    speeds = np.hypot(b[:, BALL_VX], b[:, BALL_VY])
    assert speeds.max() < 1e-2, speeds
    assert np.abs(np.array(tail) - tail[-1]).max() < 1e-5  # no jitter nor creep in the last second
    assert (b[:, BALL_X] >= LEFT + R - SKIN).all() and (b[:, BALL_Y] >= FLOOR + R - SKIN).all()


def test_one_ball_follows_step_ball_bitwise():
    world = World(BOX)
    world.place_ball(0, (0.30, 0.95), (2.0, -1.0))  # free flight, then the right wall, ...
    multi = world_with(BOX, [((0.30, 0.95), (2.0, -1.0))])
    for _ in range(600):
        world.step()
        step_multiball(multi)
        assert (state(multi)[0] == world.state.balls[0, 0]).all()


@pytest.mark.parametrize("seed", range(3))
def test_one_ball_on_classic_v1_under_random_flipping_is_step_ball_bitwise(seed):
    # Flippers, slingshots, drop targets, a spinner, kickbacks and the drain: as step_ball,
    # hits and flipper angles included (while nothing wedges: the wedge handling differs).
    rng = np.random.default_rng(seed)
    table = load_table("classic_v1")
    world, multi = World(table), make_multiball(table, 1, 1)
    position, velocity = (rng.uniform(0.05, 0.4), rng.uniform(0.2, 0.9)), rng.uniform(-3, 3, 2)
    world.place_ball(0, position, tuple(velocity))
    place(multi, 0, 0, position, tuple(velocity))
    multi.state.kickback_lit[:] = world.state.kickback_lit
    for frame in range(1500):
        if frame % 7 == 0:
            buttons = rng.random((1, 2)) < 0.5
        world.step(buttons)
        multi.state.flipper_command[0] = world.state.flipper_command[0]
        step_multiball(multi)
        assert multi.state.active[0, 0] == world.state.active[0, 0]
        assert (multi.state.hits == world.state.hits).all()
        assert (multi.state.flipper_angle == world.state.flipper_angle).all()
        if not world.state.active[0, 0]:
            break
        assert (state(multi)[0] == world.state.balls[0, 0]).all()


def test_two_balls_cradled_on_a_raised_flipper_rest_together():
    table = load_table("classic")
    world = world_with(table, [((0.17, 0.22), (0, 0)), ((0.20, 0.24), (0, 0))], pair=(0.9, 0.1))
    left = [f.button for f in table.flippers].index("left")
    world.state.flipper_command[0, left] = True
    for _ in range(600):
        step_multiball(world)
        b = state(world)
        assert world.state.active[0].all()
        assert min_distance(b, np.ones(2, bool)) >= 2 * R - SKIN - 1e-9
    speeds = np.hypot(b[:, BALL_VX], b[:, BALL_VY])
    assert speeds.max() < 1e-2, (b, speeds)


def test_balls_placed_into_one_another_are_pushed_apart_and_stay_in_the_box():
    # Overlapping by half a radius, at rest: settled apart at the first substep's end.
    world = world_with(LEVEL, [((0.25, 0.5), (0, 0)), ((0.25 + 1.5 * R, 0.5), (0, 0))])
    step_multiball(world)
    assert min_distance(state(world), np.ones(2, bool)) >= 2 * R - SKIN
    # Deeply, one against a wall and closing in: the push off the other stops short of the wall.
    x = LEFT + R + 1e-4
    world = world_with(LEVEL, [((x, 0.5), (0, 0)), ((x + 0.2 * R, 0.5), (-1.0, 0))])
    for _ in range(30):
        step_multiball(world)
        b = state(world)
        assert (b[:, BALL_X] >= LEFT + R - SKIN).all()
    assert min_distance(b, np.ones(2, bool)) >= 2 * R - SKIN


def test_a_lit_kickback_fires_the_first_ball_and_lets_the_second_through():
    # The level box with a lit kickback across it at y = 0.5, kicking up the table; two balls
    # come down side by side, the left one 10 mm ahead.
    data = yaml.safe_load((builtin_tables_dir() / "box.yaml").read_text(encoding="utf-8"))
    data["slope_deg"] = 0.0
    data["walls"] = data["walls"][:1]  # the outline only
    data["posts"] = []
    across = [[0.011, 0.5], [0.499, 0.5]]
    data["kickbacks"] = [{"name": "kick", "points": across, "kick": [0.0, 2.0], "lit": True}]
    table = table_from_dict(data, "<kickback box>")
    world = make_multiball(table, 1, 2)
    world.state.kickback_lit[0] = True
    place(world, 0, 0, (0.15, 0.52), (0.0, -1.0))
    place(world, 0, 1, (0.35, 0.53), (0.0, -1.0))
    kickback = table.element_names.index("kick")
    hits = 0
    for _ in range(3):
        step_multiball(world)
        hits += world.state.hits[0, kickback]
    a, b = state(world)
    assert a[BALL_VY] == 2.0 and a[BALL_Y] > 0.5  # fired back up
    assert b[BALL_VY] == -1.0 and b[BALL_Y] < 0.5  # the kickback was dark: through
    assert not world.state.kickback_lit[0, 0] and hits == 2


TRACE_SCRIPT = """
import sys
import numpy as np
from pinball_env.table import load_table
from pinball_env.physics.multiball import make_multiball, place, step_multiball
world = make_multiball(load_table("classic_v1"), 2, 3, pair=(0.9, 0.1))
place(world, 0, 0, (0.1, 0.95), (4.0, -2.5))
place(world, 0, 1, (0.3, 0.6), (-3.0, 1.0))
place(world, 0, 2, (0.2, 0.4), (0.5, 2.0))
place(world, 1, 0, (0.15, 0.3))
place(world, 1, 1, (0.18, 0.33))
place(world, 1, 2, (0.35, 0.5), (-20.0, 31.0))
rng = np.random.default_rng(1)
for frame in range(240):
    if frame % 9 == 0:
        world.state.flipper_command[:] = rng.random(world.state.flipper_command.shape) < 0.5
    step_multiball(world)
np.save(sys.argv[1], np.concatenate([world.state.balls.ravel(), world.state.active.ravel(),
                                     world.state.flipper_angle.ravel()]))
"""


def test_pure_python_multiball_step_is_bitwise_the_compiled_one(tmp_path):
    root = Path(__file__).resolve().parents[2]
    traces = []
    for jit, name in (("0", "compiled.npy"), ("1", "pure.npy")):
        env = {**os.environ, "NUMBA_DISABLE_JIT": jit, "PYTHONPATH": str(root)}
        result = subprocess.run(
            [sys.executable, "-c", TRACE_SCRIPT, str(tmp_path / name)],
            cwd=root, env=env, capture_output=True, text=True, timeout=600,
        )  # fmt: skip
        assert result.returncode == 0, result.stderr[-3000:]
        traces.append(np.load(tmp_path / name))
    assert (traces[0] == traces[1]).all()
