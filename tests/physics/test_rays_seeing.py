"""The rays of a table of several balls (issue 49) also see the other balls (in play or held)
and the standing drop targets; on other tables they see the walls, posts and flippers alone
(``cast_all_rays`` given no ball slots and no targets), bitwise."""

import numpy as np
import pytest

from pinball_env.game import Game
from pinball_env.observation import StateObserver
from pinball_env.physics.rays import RAY_RANGE, cast_all_rays, ray_directions
from pinball_env.table import load_table

V3 = load_table("classic_v3")
N_RAYS = 8  # ray 0 points along +x


def observer_on(table, position, n_rays=N_RAYS):
    game = Game(table, 1)
    game.new_game(0, np.random.default_rng(0), {"ball_position": position})
    return game, StateObserver(game, rays=n_rays)


def walls_only(game, n_rays=N_RAYS):
    """The rays from the game's ball as cast_all_rays reads them seeing nothing more than the
    walls, posts and flippers (no ball slots, no targets)."""
    world, n = game.world, game.n_envs
    out = np.zeros((n, n_rays), dtype=np.float32)
    nothing = (np.zeros((n, 0, 5)), np.zeros((n, 0), dtype=bool), 0.0, np.zeros((n, 0), bool))
    cast_all_rays(game.state.game_ball, world.tables.geometries(), world.state.flipper_angle,
                  n_rays, world.state.hits.shape[1], out, *nothing, 0, n)  # fmt: skip
    return out


def rays_of(observer):
    return observer.observe()[0, -observer.rays :]


def test_a_ray_reads_the_distance_to_a_second_ball_in_its_way():
    x, y, gap = 0.25, 0.5, 0.1
    game, observer = observer_on(V3, (x, y))
    before = rays_of(observer)
    free = np.flatnonzero(~game.world.active[0])
    game.world.place_ball(0, (x + gap, y), ball=int(free[0]))
    game.multi.sync(0)  # (the game's ball is still the first in play, ours)
    assert game.state.game_ball[0, 0] == x
    after = rays_of(observer)
    expected = np.float32((gap - V3.ball.radius) / RAY_RANGE)
    assert before[0] > expected + 0.01  # the walls are further than the ball
    assert after[0] == pytest.approx(expected, abs=1e-6)
    np.testing.assert_array_equal(after[1:], before[1:])  # the other rays miss it
    assert after[0] < walls_only(game)[0, 0]


def test_a_held_ball_is_seen_and_a_ball_in_the_trough_is_not():
    x, y, gap = 0.25, 0.5, 0.1
    game, observer = observer_on(V3, (x, y))
    free = int(np.flatnonzero(~game.world.active[0])[0])
    game.world.place_ball(0, (x + gap, y), ball=free)
    game.world.held[0, free] = True  # held where it lies: still seen
    expected = np.float32((gap - V3.ball.radius) / RAY_RANGE)
    assert rays_of(observer)[0] == pytest.approx(expected, abs=1e-6)
    game.world.held[0, free] = False
    game.world.active[0, free] = False  # back in the trough: not seen
    assert rays_of(observer)[0] == walls_only(game)[0, 0]


def test_a_standing_drop_target_is_seen_and_a_fallen_one_is_not():
    (tx, ty0), (_, ty1) = V3.drop_target_list[0].points
    x, y = tx - 0.055, 0.5 * (ty0 + ty1)
    game, observer = observer_on(V3, (x, y))
    standing = rays_of(observer)
    assert game.world.state.targets_up[0, 0]
    assert standing[0] == pytest.approx(np.float32(0.055 / RAY_RANGE), abs=1e-6)
    assert standing[0] < walls_only(game)[0, 0]
    game.world.state.targets_up[0, 0] = False
    fallen = rays_of(observer)
    assert fallen[0] == walls_only(game)[0, 0] > standing[0] + 0.01
    np.testing.assert_array_equal(fallen[1:], standing[1:])


@pytest.mark.parametrize("name", ["classic", "classic_v2"])
def test_one_ball_tables_see_the_walls_alone(name):
    table = load_table(name)
    rng = np.random.default_rng(3)
    for _ in range(20):
        position = (rng.uniform(0.1, 0.45), rng.uniform(0.3, 1.0))
        try:
            game, observer = observer_on(table, position, 16)
        except ValueError:  # inside an element
            continue
        assert game.multi is None
        np.testing.assert_array_equal(rays_of(observer), walls_only(game, 16)[0])


def test_seeing_nothing_more_the_rays_are_bitwise_cast_all_rays():
    """With no other ball in play and every target down, the rays that see them read the
    walls alone, bitwise."""
    table = load_table("classic_v2")
    game = Game(table, 1)
    world = game.world
    geometries = world.tables.geometries()
    rng = np.random.default_rng(4)
    for _ in range(50):
        world.state.balls[0, 0, :2] = rng.uniform(0.05, 0.5), rng.uniform(0.1, 1.1)
        seeing = np.zeros((1, 16), dtype=np.float32)
        no_balls = np.zeros((1, 2, 5))
        cast_all_rays(game.state.game_ball, geometries, world.state.flipper_angle, 16,
                             world.state.hits.shape[1], seeing, no_balls,
                             np.zeros((1, 2), dtype=bool), table.ball.radius,
                             np.zeros_like(world.state.targets_up), 0, 1)  # fmt: skip
        np.testing.assert_array_equal(seeing, walls_only(game, 16))
    assert ray_directions(16).shape == (16, 2)
