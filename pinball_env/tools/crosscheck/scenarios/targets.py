"""Targets: a drop target struck, and fallen; a spinner passed through."""

from typing import Any

import numpy as np

from pinball_env.physics.columns import BALL_Y
from pinball_env.sim.backends import make_world
from pinball_env.table import Table, table_from_dict, table_to_dict
from pinball_env.tools.crosscheck.scenarios.shots import (
    ENGINES,
    FRAME_RATE,
    HIT_TIME,
    RADIUS,
    compare,
    reflect,
    scenario_table,
    shoot,
)


def _targets_table(restitution: float = 0.5) -> Table:
    """The open scenario table with a drop target across x in [0.3, 0.7] at y = 0.3 and a
    spinner across the same span at y = 0.6, both flat, level (slope 0)."""
    data = table_to_dict(scenario_table(restitution=restitution))
    data["drop_targets"] = [{
        "name": "bank", "material": "m", "reset_time": 60.0,
        "targets": [{"name": "target", "points": [[0.3, 0.3], [0.7, 0.3]], "score": 1}],
    }]  # fmt: skip
    data["spinners"] = [{"name": "spinner", "points": [[0.3, 0.6], [0.7, 0.6]], "radius": 0.015,
                         "damping": 0.5, "friction": 20.0, "score": 1}]  # fmt: skip
    return table_from_dict(data, "<crosscheck targets>")


def target_hits(speeds: list[float], restitution: float = 0.5) -> list:
    """A ball shot straight down at the standing drop target at ``speed``: it bounces as off a
    wall, the target falls, and the same shot again passes through where it stood."""
    table = _targets_table(restitution)
    worlds = {engine: make_world(table, 1, engine) for engine in ENGINES}
    rows = []
    for speed in speeds:
        velocity = np.array([0.0, -speed])
        start = np.array([0.5, 0.3 + RADIUS]) - velocity * HIT_TIME
        frames = int(HIT_TIME * FRAME_RATE) + 6
        row: dict[str, Any] = {"speed": speed}
        shots = {}
        for engine, world in worlds.items():
            world.reset_targets(0)
            shots[engine] = shoot(world, tuple(start), tuple(velocity), frames)
            fell = not world.state.targets_up[0, 0]
            again = shoot(world, tuple(start), tuple(velocity), frames)
            row[engine] = {"fell": fell, "passed_when_down": bool(again.position[1] < 0.3)}
        expected = reflect(velocity, np.array([0.0, 1.0]), restitution)
        for engine, result in compare(expected, shots, speed).items():
            row[engine].update(result)
        rows.append(row)
    return rows


def spinner_turns(speeds: list[float], seconds: float = 8.0) -> list:
    """A ball passes once, straight up, through the spinner at ``speed``: the revolutions each
    engine counts (the spin is the kernel's on both: pymunk's crossing velocity is the mean over
    the substep)."""
    table = _targets_table()
    worlds = {engine: make_world(table, 1, engine) for engine in ENGINES}
    spinner = table.element_names.index("spinner")
    rows = []
    for speed in speeds:
        row: dict[str, Any] = {"speed": speed}
        for engine, world in worlds.items():
            world.reset_targets(0)
            world.place_ball(0, (0.5, 0.5), (0.0, speed))
            turns = 0
            for _ in range(int(seconds * FRAME_RATE)):
                world.step()
                turns += int(world.state.hits[0, spinner])
                if world.active[0, 0] and world.balls[0, 0, BALL_Y] > 0.65:
                    world.state.active[0, 0] = False  # once through is enough
            row[engine] = turns
        rows.append(row)
    return rows
