"""World with several balls: the API, the several-ball kernel behind it, saucers and
locks (capture, hold time, kick, a fast ball passing over, slots filled in order, release)."""

import copy
import math
import pickle

import numpy as np
import pytest
import yaml

from pinball_env.physics.columns import BALL_VX, BALL_VY, BALL_X, BALL_Y
from pinball_env.physics.multiball import make_multiball, place, step_multiball
from pinball_env.sim.world import World
from pinball_env.table import builtin_tables_dir, load_table, table_from_dict
from tests.table.multiball import multiball_dict

DT = 1.0 / 60.0
SAUCER = {
    "name": "saucer",
    "center": [0.255, 0.50],
    "radius": 0.02,
    "capture_speed": 0.5,
    "hold_time": 0.5,
    "kick": [1.0, 0.5],
    "score": 500,
}
LOCK = {
    "name": "lock",
    "slots": [[0.10, 0.80], [0.10, 0.84]],
    "capture_speed": 1.0,
    "kick": [0.5, -0.5],
    "score": 1000,
}


def level_box(balls=3, saucers=(SAUCER,), locks=(LOCK,)):
    """The box laid level (balls fly straight), with a saucer, a lock and a trough."""
    data = yaml.safe_load((builtin_tables_dir() / "box.yaml").read_text(encoding="utf-8"))
    data["slope_deg"] = 0.0
    data["materials"]["steel"] = {"restitution": 0.95, "friction": 0.0}
    data["ball"]["material"] = "steel"
    data["plunger"] = {"position": [0.45, 0.05], "speed": [1.0, 2.0]}
    data["saucers"] = copy.deepcopy(list(saucers))
    data["locks"] = copy.deepcopy(list(locks))
    data["trough"] = {"balls": balls}
    return table_from_dict(data, "<level box>")


def frames_until(world, condition, limit):
    """Step until ``condition()`` holds; the number of frames it took (None: not in limit)."""
    for frame in range(1, limit + 1):
        world.step()
        if condition():
            return frame
    return None


def test_one_ball_tables_keep_the_one_ball_kernel_in_one_slot():
    world = World(load_table("classic_v1"), 2)
    assert world.n_balls == 1 and not world.several and world.swept_kernel
    assert world.balls.shape == (2, 1, 5) and world.active.shape == world.held.shape == (2, 1)
    assert world.balls is world.state.balls and world.active is world.state.active
    world.place_ball(1, (0.3, 0.5), (0.1, 0.2))
    assert world.balls[1, 0, BALL_X] == 0.3 and world.active[1, 0]
    with pytest.raises(ValueError, match="ball must be"):
        world.place_ball(0, (0.3, 0.5), ball=1)
    with pytest.raises(ValueError, match="nothing holds"):
        world.hold_ball(0, 0, (0.3, 0.5))


def test_several_balls_step_as_the_multiball_kernel_bitwise():
    table = table_from_dict(multiball_dict(), "<multiball>")
    world = World(table, 2)
    assert world.n_balls == 3 and world.balls.shape == (2, 3, 5)
    assert world.active.tolist() == [[True, False, False]] * 2
    assert world.several and world.swept_kernel  # the game's loop steps it itself
    reference = make_multiball(table, 2, 3)
    threaded = World(table, 2, num_threads=2)  # bitwise the same on any number of threads
    starts = [((0.25, 0.6), (0.5, 1.0)), ((0.3, 0.7), (-0.4, 0.2)), ((0.2, 0.8), (0.0, -1.0))]
    for env in range(2):
        for ball, (position, velocity) in enumerate(starts):
            world.place_ball(env, position, velocity, ball=ball)
            threaded.place_ball(env, position, velocity, ball=ball)
            place(reference, env, ball, position, velocity)
    rng = np.random.default_rng(3)
    for _ in range(120):
        buttons = rng.random((2, 2)) < 0.3
        world.step(buttons)
        threaded.step(buttons)
        np.testing.assert_array_equal(threaded.balls, world.balls)
        reference.state.flipper_command[:] = buttons[:, table.flipper_buttons]
        step_multiball(reference)
        np.testing.assert_array_equal(world.balls, reference.state.balls)
        np.testing.assert_array_equal(world.active, reference.state.active)
        np.testing.assert_array_equal(world.state.flipper_angle, reference.state.flipper_angle)


def test_launch_takes_a_ball_index():
    table = table_from_dict(multiball_dict(), "<multiball>")
    world = World(table, 1)
    world.launch(0, 2.5, ball=2)
    assert world.active[0].tolist() == [True, False, True]
    assert tuple(world.balls[0, 2, [BALL_X, BALL_Y]]) == table.plunger.position
    assert world.balls[0, 2, BALL_VY] == 2.5


def test_a_held_ball_stays_and_is_released_at_its_velocity():
    world = World(level_box(saucers=(), locks=()), 1)
    world.hold_ball(0, 1, (0.3, 0.3))
    for _ in range(10):
        world.step()
    assert world.held[0, 1]
    assert world.balls[0, 1, :4].tolist() == [0.3, 0.3, 0.0, 0.0]
    world.release_ball(0, 1, (0.2, 0.0))
    world.step()
    assert not world.held[0, 1]
    assert world.balls[0, 1, BALL_X] == pytest.approx(0.3 + 0.2 * DT)


def test_a_saucer_captures_scores_holds_and_kicks_out():
    world = World(level_box(), 1)
    world.place_ball(0, (0.255, 0.30), (0.0, 0.3))
    frames = frames_until(world, lambda: world.held[0, 0], 60)
    # Captured on the first frame that ends within the radius: 0.18 m at 0.3 m/s.
    assert frames == math.ceil(0.18 / 0.3 / DT)
    assert world.balls[0, 0, :4].tolist() == [0.255, 0.50, 0.0, 0.0]
    assert world.frame_points()[0] == 500
    assert [c.name for c in world.frame_contacts(0)] == ["saucer"]
    held = frames_until(world, lambda: not world.held[0, 0], 100)
    assert held == round(0.5 / DT)  # hold_time
    assert world.balls[0, 0, [BALL_VX, BALL_VY]].tolist() == [1.0, 0.5]  # the kick
    assert world.frame_points()[0] == 0
    for _ in range(10):  # it leaves along the kick, not captured again on its way out
        world.step()
        assert not world.held[0, 0]
    x, y = world.balls[0, 0, [BALL_X, BALL_Y]]
    assert math.atan2(y - 0.5, x - 0.255) == pytest.approx(math.atan2(0.5, 1.0))
    assert math.hypot(*world.balls[0, 0, [BALL_VX, BALL_VY]]) == pytest.approx(math.hypot(1.0, 0.5))


def test_a_fast_ball_passes_over_a_saucer():
    world = World(level_box(), 1)
    world.place_ball(0, (0.255, 0.30), (0.0, 1.0))
    for _ in range(30):
        world.step()
        assert not world.held[0, 0] and world.frame_points()[0] == 0
    assert world.balls[0, 0, BALL_Y] > 0.6


def test_a_held_saucer_takes_no_second_ball_and_is_a_post_to_it():
    world = World(level_box(saucers=({**SAUCER, "hold_time": 3.0},)), 1)
    world.hold_ball(0, 0, (0.255, 0.50))
    world.holder[0, 0] = world.saucer_ids[0]
    world.place_ball(0, (0.255, 0.30), (0.0, 0.3), ball=1)
    for _ in range(60):
        world.step()
        assert not world.held[0, 1]
    assert world.balls[0, 1, BALL_VY] < 0.0  # it bounced off the held ball


def test_a_lock_fills_its_slots_in_order_and_releases_them():
    world = World(level_box(), 1)
    lock = world.lock_ids[0]
    # Slot 1 first: not the next free slot, so a ball across it is not held.
    world.place_ball(0, (0.30, 0.84), (-0.5, 0.0), ball=1)
    for _ in range(30):
        world.step()
        assert not world.held[0, 1]
    world.place_ball(0, (0.10, 0.60), (0.0, 0.5), ball=0)
    assert frames_until(world, lambda: world.held[0, 0], 60) is not None
    assert world.balls[0, 0, :4].tolist() == [0.10, 0.80, 0.0, 0.0]
    assert world.frame_points()[0] == 1000 and world.slot[0, 0] == 0
    world.place_ball(0, (0.30, 0.84), (-0.5, 0.0), ball=1)
    assert frames_until(world, lambda: world.held[0, 1], 60) is not None
    assert world.balls[0, 1, :4].tolist() == [0.10, 0.84, 0.0, 0.0]
    assert world.slot[0, 1] == 1 and (world.holder[0, :2] == lock).all()
    for _ in range(120):  # a lock holds until a rule releases it
        world.step()
    assert world.held[0, :2].all()
    assert world.release_lock(0, 0) == 2
    assert not world.held[0].any()
    for _ in range(5):
        world.step()
        assert not world.held[0].any()
    assert world.balls[0, :2, BALL_VX].tolist() == [0.5, 0.5]
    assert world.balls[0, :2, BALL_VY].tolist() == [-0.5, -0.5]


def test_one_ball_with_a_saucer_takes_the_several_ball_kernel_in_one_slot():
    world = World(level_box(balls=1), 1)
    assert world.n_balls == 1 and world.several
    assert world.swept_kernel  # (a game of one ball hands its frames to world.step: Game)
    world.place_ball(0, (0.255, 0.30), (0.0, 0.3))
    assert frames_until(world, lambda: world.held[0, 0], 60) is not None
    assert world.balls[0, 0, :2].tolist() == [0.255, 0.50] and world.active[0, 0]
    copy_ = pickle.loads(pickle.dumps(world))
    assert copy_.balls is copy_.state.balls
    np.testing.assert_array_equal(copy_.balls, world.balls)


def test_several_balls_on_the_multiball_table_never_overlap_or_escape():
    table = table_from_dict(multiball_dict(), "<multiball>")
    world = World(table, 2, num_threads=2)
    for env in range(2):
        world.launch(env, 2.8, ball=0)
        world.place_ball(env, (0.25, 0.7), (0.3, -0.5), ball=1)
        world.place_ball(env, (0.3, 0.8), (-0.2, 0.1), ball=2)
    rng = np.random.default_rng(5)
    r = table.ball.radius
    for _ in range(600):
        world.step(rng.random((2, 2)) < 0.2)
        for env in range(2):
            live = world.balls[env, world.active[env]][:, :2]
            for i in range(len(live)):
                for j in range(i + 1, len(live)):
                    assert math.dist(live[i], live[j]) >= 2 * r - 2 * table.simulation.skin
            assert ((live >= 0.0) & (live <= [table.width, table.height])).all()


def overlap(world, env, table):
    """The deepest overlap of two balls on env ``env``'s table (in play or held) [m]."""
    live = world.balls[env, world.active[env]][:, :2]
    gaps = [math.dist(a, b) for i, a in enumerate(live) for b in live[i + 1 :]]
    return max((2 * table.ball.radius - gap for gap in gaps), default=-math.inf)


def test_a_capture_never_puts_a_ball_onto_another():
    # Found: a ball at rest by the saucer captured onto its centre, where another ball lay.
    table = load_table("classic_v3")
    world = World(table, 1)
    world.place_ball(0, (0.041, 0.70), ball=0)
    world.place_ball(0, (0.0725, 0.70), ball=1)
    for _ in range(3):
        world.step()
        assert overlap(world, 0, table) <= table.simulation.skin
    assert not world.held[0].any()  # no room at the centre: not taken


@pytest.mark.parametrize("seed", range(4))
def test_balls_placed_around_each_capture_point_are_taken_only_where_they_fit(seed):
    # Two or three slow balls dropped around a saucer's centre or a lock's slot, another
    # sometimes held there: whatever is taken, no two balls ever overlap past the skin.
    table = load_table("classic_v3")
    points = [s.center for s in table.saucers] + [slot for lock in table.locks
                                                  for slot in lock.slots]  # fmt: skip
    rng = np.random.default_rng(seed)
    r, skin = table.ball.radius, table.simulation.skin
    world = World(table, len(points) * 8)
    taken = 0
    for env in range(world.n_envs):
        x, y = points[env % len(points)]
        placed = []
        for ball in range(int(rng.integers(2, 4))):
            for _ in range(100):  # apart from the others, within a few radii of the point
                angle, reach = rng.uniform(0, 2 * math.pi), rng.uniform(0.0, 3.0 * r)
                spot = (x + reach * math.cos(angle), y + reach * math.sin(angle))
                if all(math.dist(spot, other) > 2 * r + skin for other in placed):
                    break
            else:
                continue
            try:
                world.place_ball(env, spot, tuple(rng.uniform(-0.2, 0.2, 2)), ball=ball)
            except ValueError:  # (inside a wall: not a state the loader accepts)
                continue
            placed.append(spot)
    for _ in range(90):
        world.step()
        taken += int(world.held.sum())
        for env in range(world.n_envs):
            assert overlap(world, env, table) <= skin, env
    assert taken > 0  # captures happened


pymunk = pytest.importorskip("pymunk")


def test_pymunk_plays_several_balls_with_the_same_api():
    from pinball_env.sim.backends import make_world

    table = table_from_dict(multiball_dict(), "<multiball>")
    world = make_world(table, 1, physics="pymunk")
    assert world.n_balls == 3 and world.balls.shape == (1, 3, 5)
    world.launch(0, 2.8, ball=0)
    world.place_ball(0, (0.25, 0.7), (0.3, -0.5), ball=1)
    world.place_ball(0, (0.3, 0.8), (-0.2, 0.1), ball=2)
    r = table.ball.radius
    rng = np.random.default_rng(2)
    for _ in range(300):
        world.step(rng.random((1, 2)) < 0.2)
        live = world.balls[0, world.active[0]][:, :2]
        for i in range(len(live)):
            for j in range(i + 1, len(live)):
                assert math.dist(live[i], live[j]) >= 2 * r - 1e-3  # pymunk's slop and more
        assert np.isfinite(world.balls).all()


def test_pymunk_saucer_and_held_balls():
    from pinball_env.sim.backends import make_world

    world = make_world(level_box(saucers=({**SAUCER, "hold_time": 3.0},)), 1, physics="pymunk")
    world.place_ball(0, (0.255, 0.30), (0.0, 0.3))
    assert frames_until(world, lambda: world.held[0, 0], 60) is not None
    assert world.frame_points()[0] == 500
    world.place_ball(0, (0.255, 0.20), (0.0, 0.3), ball=1)
    for _ in range(60):  # the second ball bounces off the held one, which does not move
        world.step()
        assert world.balls[0, 0, :4].tolist() == [0.255, 0.50, 0.0, 0.0]
        assert not world.held[0, 1]
    assert world.balls[0, 1, BALL_VY] < 0.0
    world.release_ball(0, 0, (0.0, 1.0))
    world.step()
    assert world.balls[0, 0, BALL_Y] == pytest.approx(0.5 + DT, rel=1e-6)
