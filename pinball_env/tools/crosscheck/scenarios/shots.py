"""The cross-check's common ground: the scenario table, the engines, the tolerances, a shot
on each engine and its comparison with the analytic answer."""

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from pinball_env.physics.columns import BALL_VX, BALL_VY, BALL_X, BALL_Y
from pinball_env.sim.backends import PHYSICS
from pinball_env.sim.world import World
from pinball_env.table import BUTTONS, Table, load_table, table_from_dict, table_to_dict

ENGINES = PHYSICS  # the engines compared: ours ("swept") and pymunk
RADIUS = 0.0135
SUBSTEPS = 10
FRAME_RATE = 60.0
SUBSTEP = 1.0 / (FRAME_RATE * SUBSTEPS)
LOW_SPEED = 4.0  # [m/s]: at most half a ball radius per substep
TIME_TOLERANCE = SUBSTEP
DROP_TIME_TOLERANCE = 2 * SUBSTEP
VELOCITY_TOLERANCE = (0.01, 0.001)  # relative to the incoming speed, absolute [m/s]
FLIPPER_SPEED_TOLERANCE = 0.10  # relative: the flipper scenarios' speeds
HIT_TIME = 0.1  # [s] every aimed scenario is set up to meet its target after this time
# Agreement to rounding [m/s, m]: both engines do the same arithmetic, in another order.
ROUNDING = 1e-9
CABINET_TABLE = "classic_v1"  # the table in the whole cabinet (plunger, nudge, tilt)


def classic_left_flipper() -> dict[str, Any]:
    """The classic table's left flipper as a table entry, its pivot moved to (0.4, 0.4) of the
    scenario table and its material the scenario's ``flipper``."""
    entries = table_to_dict(load_table("classic"))["flippers"]
    left = next(entry for entry in entries if entry["button"] == "left")
    return {**left, "name": "flipper", "pivot": [0.4, 0.4], "material": "flipper"}


# Flipper used by the flipper scenarios, and the buttons (one env) that raise it.
FLIPPER = classic_left_flipper()
LEFT_BUTTON = np.array([[button == FLIPPER["button"] for button in BUTTONS]])


def scenario_table(
    walls: list | None = None,
    posts: list | None = None,
    flipper: bool = False,
    restitution: float = 0.5,
    friction: float = 0.0,
    slope_deg: float = 0.0,
    cabinet: bool = False,
) -> Table:
    """A 1 m x 1 m open table with the given elements and no outline; with ``cabinet``, in
    CABINET_TABLE's cabinet (its plunger, without the skill shot, in a corner)."""
    whole_cabinet = {}
    if cabinet:
        entries = table_to_dict(load_table(CABINET_TABLE))
        plunger = {key: value for key, value in entries["plunger"].items() if key != "skill_shot"}
        whole_cabinet = {
            "plunger": {**plunger, "position": [0.95, 0.05]},
            "cabinet": entries["cabinet"],
            "tilt": entries["tilt"],
        }
    return table_from_dict(
        {
            **whole_cabinet,
            "name": "crosscheck",
            "playfield": {"width": 1.0, "height": 1.0},
            "slope_deg": slope_deg,
            "ball": {"radius": RADIUS, "mass": 0.08, "start": [0.95, 0.95]},
            "materials": {
                "m": {"restitution": restitution, "friction": friction},
                "flipper": {"restitution": 0.8, "friction": friction},
            },
            "walls": [
                {"name": f"wall{i}", "points": points, "material": "m"}
                for i, points in enumerate(walls or [])
            ],
            "posts": [
                {"name": f"post{i}", "center": c, "radius": r, "material": "m", "kick": kick}
                for i, (c, r, kick) in enumerate(posts or [])
            ],
            "flippers": [FLIPPER] if flipper else [],
            "simulation": {"frame_rate": FRAME_RATE, "substeps": SUBSTEPS},
        }
    )


@dataclass
class Shot:
    """What one engine did with one ball: first contact time, velocity after, final state."""

    contact_time: float | None
    velocity: np.ndarray
    position: np.ndarray
    path: list = field(default_factory=list)


def shoot(
    world: World, start: tuple, velocity: tuple, frames: int, buttons: np.ndarray | None = None
) -> Shot:
    """Fire the ball from ``start`` and run ``frames`` frames; the first contact's time is the
    kernel's exact time for ours, the end of the detecting substep for pymunk."""
    world.place_ball(0, start, velocity)
    contact_time = None
    path = []
    for frame in range(frames):
        world.step(buttons)
        path.append(world.balls[0, 0, [BALL_X, BALL_Y]].copy())
        contacts = [c for c in world.frame_contacts() if c.speed > 0.0]
        if contacts and contact_time is None:
            late = SUBSTEP if type(world).__name__ == "PymunkWorld" else 0.0
            contact_time = frame / FRAME_RATE + contacts[0].time + late
    ball = world.balls[0, 0]
    return Shot(contact_time, ball[[BALL_VX, BALL_VY]].copy(), ball[[BALL_X, BALL_Y]].copy(), path)


def reflect(velocity: np.ndarray, normal: np.ndarray, restitution: float) -> np.ndarray:
    """Frictionless bounce off a static surface: v' = v - (1 + e)(v.n) n."""
    return velocity - (1.0 + restitution) * float(velocity @ normal) * normal


def compare(expected: np.ndarray, shots: dict[str, Shot], speed: float) -> dict[str, Any]:
    """Errors of each engine's contact time and bounce velocity against the analytic answer."""
    row: dict[str, Any] = {}
    for engine, shot in shots.items():
        time_error = None if shot.contact_time is None else shot.contact_time - HIT_TIME
        turn = math.atan2(
            expected[0] * shot.velocity[1] - expected[1] * shot.velocity[0],
            float(expected @ shot.velocity),
        )
        row[engine] = {
            "contact_time_error": time_error,
            "velocity_error": float(np.linalg.norm(shot.velocity - expected)),
            "relative_velocity_error": float(np.linalg.norm(shot.velocity - expected)) / speed,
            "speed_error": float(np.linalg.norm(shot.velocity) - np.linalg.norm(expected)),
            "direction_error_deg": math.degrees(turn),
        }
    return row


def agrees(row: dict[str, Any], engine: str, speed: float) -> bool:
    result = row[engine]
    relative, absolute = VELOCITY_TOLERANCE
    on_time = result["contact_time_error"] is not None and (
        abs(result["contact_time_error"]) <= TIME_TOLERANCE + 1e-9
    )
    return on_time and result["velocity_error"] <= relative * speed + absolute
