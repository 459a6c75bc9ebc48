"""The invariants every frame of every world keeps, shared by the tests that play tight places."""

import math

import numpy as np

from pinball_env.physics import flipper_distance, point_segment_distance
from pinball_env.sim.world import World
from pinball_env.table.parts import inside


def assert_sound(world: World) -> None:
    """The invariants of every frame: finite, inside the outline, overlapping no two-sided
    wall, post or flipper by more than the skin."""
    table, state = world.table, world.state
    r, skin = table.ball.radius, table.simulation.skin
    assert np.isfinite(state.balls).all()
    outline = table.outline
    for env, ball in np.argwhere(state.active):
        x, y = state.balls[env, ball, :2]
        if outline is not None:
            assert inside((x, y), outline.points), (env, x, y)
        for wall in table.walls:
            if wall.one_sided:  # a ball may lie partly through a gate
                continue
            for segment in wall.segments():
                gap = point_segment_distance(x, y, *segment) - r
                assert gap >= -skin * 1.001, (env, wall.name, gap)
        for post in table.posts:
            gap = math.dist((x, y), post.center) - post.radius - r
            assert gap >= -skin * 1.001, (env, post.name, gap)
        for j, flipper in enumerate(table.flippers):
            angle = state.flipper_angle[env, j]
            gap = flipper_distance(
                x, y, *flipper.pivot, flipper.length, flipper.base_radius, flipper.tip_radius, angle
            )[0]
            assert gap - r >= -skin * 1.001, (env, flipper.name, gap - r)
