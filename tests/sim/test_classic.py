"""The classic table in play: scoring events, sensors, the drain, launches, long random games."""

import math

import numpy as np
import pytest

from pinball_env.physics.columns import BALL_VY, BALL_X, BALL_Y
from pinball_env.physics.flipper import flipper_distance
from pinball_env.physics.targets import sensor_crossing
from pinball_env.sim.backends import make_world
from pinball_env.sim.world import World
from pinball_env.table import load_table, table_from_dict

CLASSIC = load_table("classic")
R = CLASSIC.ball.radius
NONE = np.array([[False, False]])


def element_id(world, name):
    return world.table.element_names.index(name)


def run_until(world, condition, frames=600, buttons=NONE):
    for _ in range(frames):
        world.step(buttons)
        if condition(world):
            return True
    return False


def test_pop_bumper_scores_once_per_hit_and_kicks():
    world = World(CLASSIC)
    bumper = next(p for p in CLASSIC.posts if p.name == "bumper_bottom")
    world.place_ball(0, (bumper.center[0], bumper.center[1] + 0.1), (0.0, -1.0))
    bumper_id = element_id(world, "bumper_bottom")
    assert run_until(world, lambda w: w.state.hits[0, bumper_id] > 0, frames=30)
    assert world.state.hits[0, bumper_id] == 1
    assert world.frame_points()[0] == 100
    # The kick sends the ball back up faster than restitution alone would (0.9 x ~1.1 m/s).
    assert world.balls[0, 0, BALL_VY] > 0.9 * 1.2 + 1.0
    # Over a longer run: one hit per logged contact with the bumper, never two, never none.
    hits = contacts = 0
    for _ in range(600):
        world.step(NONE)
        hits += int(world.state.hits[0, bumper_id])
        contacts += sum(c.name == "bumper_bottom" for c in world.frame_contacts())
    assert hits == contacts


def test_slingshot_kicks_and_scores_ten():
    world = World(CLASSIC)
    sling = element_id(world, "left_slingshot[0]")
    # Roll the ball at the middle of the left slingshot's kicking face from the centre.
    (x0, y0), (x1, y1) = next(w for w in CLASSIC.walls if w.name == "left_slingshot").points
    mid = ((x0 + x1) / 2, (y0 + y1) / 2)
    world.place_ball(0, (mid[0] + 0.08, mid[1] + 0.03), (-1.0, -0.3))
    assert run_until(world, lambda w: w.state.hits[0, sling] > 0, frames=60)
    assert world.state.hits[0, sling] == 1
    assert world.frame_points()[0] == 10


def test_sensor_crossing_counts_a_path_through_the_line_once():
    sensor = np.array([0.0, 0.0, 1.0, 0.0])
    # Ends exactly on the line, then goes on: one crossing, not two.
    first = sensor_crossing(0.5, 0.1, 0.0, -0.1, sensor)
    second = sensor_crossing(0.5, 0.0, 0.0, -0.1, sensor)
    assert (math.isfinite(first), math.isfinite(second)) == (True, False)
    assert first == pytest.approx(1.0)
    # Beyond the ends, no crossing; back across, a crossing again.
    assert sensor_crossing(1.5, 0.1, 0.0, -0.2, sensor) == math.inf
    assert sensor_crossing(0.5, -0.1, 0.0, 0.2, sensor) == pytest.approx(0.5)


def test_inlane_rollover_scores_once_as_the_ball_rolls_over_it():
    world = World(CLASSIC)
    inlane = element_id(world, "left_inlane")
    world.place_ball(0, (0.06, 0.32))
    total = 0
    for _ in range(120):
        world.step(NONE)
        total += int(world.state.hits[0, inlane])
    assert total == 1


def test_drain_takes_the_ball_out_of_play_where_it_crosses():
    world = World(CLASSIC)
    drain = element_id(world, "drain")
    world.place_ball(0, (0.2365, 0.08), (0.0, -1.0))  # between the flippers, heading down
    assert run_until(world, lambda w: not w.state.active[0, 0], frames=30)
    assert world.state.hits[0, drain] == 1
    assert world.balls[0, 0, BALL_Y] == pytest.approx(CLASSIC.sensors[-1].points[0][1], abs=1e-12)
    frozen = world.balls[0, 0].copy()
    world.step(NONE)
    np.testing.assert_array_equal(world.balls[0, 0], frozen)
    assert world.state.hits[0, drain] == 0


def test_default_plunger_sends_the_ball_through_the_gate_into_the_playfield():
    world = World(CLASSIC)
    low, high = CLASSIC.plunger.speed
    for speed in np.linspace(low, high, 5):
        world.launch(0, speed)
        path = world.trace(240, buttons=NONE)
        assert path[:, 1].max() > 0.95  # up the lane and round the arch
        # Once out of the lane the gate keeps it out: it never comes back down the lane.
        out = np.nonzero(path[:, 1] > 0.9)[0][0]
        in_lane = (path[out:, 0] > 0.468) & (path[out:, 1] < 0.8)
        assert not in_lane.any()


# --- long random games -------------------------------------------------------------------------


def outline_polygon():
    return np.array(next(w for w in CLASSIC.walls if w.name == "outline").points)


def inside(points, polygon):
    """Even-odd point-in-polygon for many points, (n, 2) -> (n,) bool."""
    x, y = points[:, 0:1], points[:, 1:2]
    x0, y0 = polygon[:, 0], polygon[:, 1]
    x1, y1 = np.roll(x0, -1), np.roll(y0, -1)
    crosses = ((y0 > y) != (y1 > y)) & (x < x0 + (y - y0) * (x1 - x0) / (y1 - y0 + 1e-300))
    return crosses.sum(axis=1) % 2 == 1


def solid_gaps(world, points):
    """Smallest distance from each point to any two-sided wall, post surface and flipper
    (a ball passes through a one-sided gate from behind)."""
    seg = np.asarray(world.geometry.segments)[~world.geometry.segment_one_sided]
    a, e = seg[None, :, :2], seg[None, :, 2:] - seg[None, :, :2]
    p = points[:, None, :]
    s = np.clip(((p - a) * e).sum(-1) / (e**2).sum(-1), 0.0, 1.0)
    gaps = np.linalg.norm(a + s[..., None] * e - p, axis=-1).min(axis=1)
    circles = np.asarray(world.geometry.circles)
    post_gaps = np.linalg.norm(p - circles[None, :, :2], axis=-1) - circles[None, :, 2]
    gaps = np.minimum(gaps, post_gaps.min(axis=1))
    for env, (x, y) in enumerate(points):
        for j, f in enumerate(CLASSIC.flippers):
            angle = world.state.flipper_angle[env, j]
            d = flipper_distance(x, y, *f.pivot, f.length, f.base_radius, f.tip_radius, angle)[0]
            gaps[env] = min(gaps[env], d)
    return gaps


@pytest.mark.slow
def test_random_games_keep_the_ball_on_the_table():
    """1e5 ball-frames of random flipping and launches: the ball never leaves the playfield
    except through the drain, never overlaps a solid, never becomes NaN, never hangs in the air."""
    n_envs, frames = 32, 3125
    rng = np.random.default_rng(2026)
    world = World(CLASSIC, n_envs=n_envs)
    low, high = CLASSIC.plunger.speed
    for env in range(n_envs):
        world.launch(env, rng.uniform(low, high))
    polygon = outline_polygon()
    buttons = np.zeros((n_envs, 2), dtype=bool)
    still_frames = np.zeros(n_envs, dtype=int)
    drains = 0
    for _ in range(frames):
        flip = rng.random((n_envs, 2)) < 0.08  # toggle buttons now and then: holds and flips
        buttons ^= flip
        before = world.balls[:, 0, [BALL_X, BALL_Y]].copy()
        world.step(buttons)
        balls = world.balls[:, 0]
        assert np.all(np.isfinite(balls))
        active = world.state.active[:, 0].copy()
        points = balls[:, [BALL_X, BALL_Y]]
        assert np.all(inside(points, polygon))
        gaps = solid_gaps(world, points)
        assert np.all(gaps[active] >= R - 1e-5), gaps[active].min() - R
        # Hanging in the air: no movement and no contact at all, frame after frame.
        moved = np.abs(points - before).max(axis=1) > 1e-9
        touching = world.state.contact_count > 0
        still_frames = np.where(active & ~moved & ~touching, still_frames + 1, 0)
        assert still_frames.max() < 3
        for env in np.nonzero(~active)[0]:
            drains += 1
            world.launch(env, rng.uniform(low, high))
    assert drains > 50  # the games really were played to the drain, many times


def sensor_table(sensors):
    return table_from_dict(
        {
            "name": "sensors",
            "playfield": {"width": 1.0, "height": 1.0},
            "slope_deg": 0.0,
            "ball": {"radius": R, "mass": 0.08, "start": [0.5, 0.9]},
            "materials": {"m": {"restitution": 0.5, "friction": 0.3}},
            "sensors": sensors,
        }
    )


@pytest.mark.parametrize("physics", ["swept", "pymunk"])
@pytest.mark.parametrize("drain_first", [True, False])
def test_crossings_before_a_drain_count_whatever_the_listing_order(physics, drain_first):
    drain = {"name": "drain", "points": [[0.1, 0.50], [0.9, 0.50]], "drain": True}
    rollover = {"name": "rollover", "points": [[0.1, 0.505], [0.9, 0.505]], "score": 10}
    sensors = [drain, rollover] if drain_first else [rollover, drain]
    world = make_world(sensor_table(sensors), 1, physics)
    world.place_ball(0, (0.5, 0.6), (0.0, -6.0))  # crosses both within one substep
    total = 0
    for _ in range(5):
        world.step()
        total += int(world.frame_points()[0])
    assert total == 10 and not world.state.active[0, 0]


def test_sensors_meeting_end_to_end_count_a_crossing_at_the_joint_once():
    left = {"name": "a", "points": [[0.1, 0.5], [0.5, 0.5]], "score": 10}
    right = {"name": "b", "points": [[0.5, 0.5], [0.9, 0.5]], "score": 10}
    world = World(sensor_table([left, right]))
    world.place_ball(0, (0.5, 0.52), (0.0, -3.0))
    world.step()
    assert [c.name for c in world.frame_contacts()] == ["b"]
