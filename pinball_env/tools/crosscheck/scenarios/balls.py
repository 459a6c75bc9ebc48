"""Several balls (a trough of two): ball-ball shots, and two balls cradled on a raised flipper."""

import math
from typing import Any

import numpy as np

from pinball_env.physics.columns import BALL_VX, BALL_VY, BALL_X, BALL_Y
from pinball_env.sim.backends import make_world
from pinball_env.table import Table, load_table, table_from_dict, table_to_dict
from pinball_env.tools.crosscheck.scenarios.shots import (
    CABINET_TABLE,
    ENGINES,
    FRAME_RATE,
    HIT_TIME,
    LEFT_BUTTON,
    RADIUS,
    SUBSTEP,
    TIME_TOLERANCE,
    VELOCITY_TOLERANCE,
    scenario_table,
)

# Ball-ball shots: name -> (ball a's velocity direction, ball b moving towards a too, the line of
# centres at contact, from a to b, in degrees from a's direction).
PAIR_SHOTS = {
    "head-on": (True, 0.0),
    "onto a resting ball": (False, 0.0),
    "oblique (45 deg)": (False, 45.0),
}
# The balls meet half a substep after HIT_TIME: no engine sees the contact on a substep's boundary.
PAIR_TIME = HIT_TIME + SUBSTEP / 2.0
PAIR_SPEEDS = (1.0, 2.0)  # [m/s]: at most a sixth of a ball radius per substep at 2 m/s
PAIR_RESTITUTIONS = (1.0, 0.5)


def with_balls(data: dict[str, Any], restitution: float, friction: float = 0.0) -> Table:
    """Table description ``data`` with a trough of two balls (and a machine plunger where it
    has none, which a trough needs) and the ball-ball material ``ball`` (restitution,
    friction)."""
    data = {**data, "materials": {**data["materials"]}}
    data["materials"]["ball"] = {"restitution": restitution, "friction": friction}
    data["ball"] = {**data["ball"], "material": "ball"}
    data.setdefault("plunger", {"position": [0.95, 0.05], "speed": [1.0, 2.0]})
    data["trough"] = {"balls": 2}
    return table_from_dict(data, "<crosscheck balls>")


def pair_expected(
    va: np.ndarray, vb: np.ndarray, normal: np.ndarray, restitution: float
) -> tuple[np.ndarray, np.ndarray]:
    """Equal masses, frictionless: the normal components of the velocities exchange, scaled by
    the restitution about their mean (momentum kept); the tangential ones stay."""
    ua, ub = float(va @ normal), float(vb @ normal)
    mean, half = 0.5 * (ua + ub), 0.5 * restitution * (ua - ub)
    return va + (mean - half - ua) * normal, vb + (mean + half - ub) * normal


def ball_ball_hits(
    speeds: tuple[float, ...] = PAIR_SPEEDS, restitutions: tuple[float, ...] = PAIR_RESTITUTIONS
) -> list:
    """Two balls on the level open table meet after PAIR_TIME (:data:`PAIR_SHOTS`: head-on,
    one onto a resting ball, oblique at 45 degrees), on both engines: each ball's velocity
    after against the analytic answer (:func:`pair_expected`), and the contact time each
    engine's paths imply: the balls' separation along the line of centres is 2r at the contact
    and grows at the relative normal speed after it, so the time is read from where they are a
    few frames later (ours: exact to the skin; pymunk: late by up to a substep, its overlap
    then pushed out by its position correction)."""
    rows = []
    frames = int(HIT_TIME * FRAME_RATE) + 4
    end = frames / FRAME_RATE
    for restitution in restitutions:
        table = with_balls(table_to_dict(scenario_table()), restitution)
        worlds = {engine: make_world(table, 1, engine) for engine in ENGINES}
        for name, (both, angle) in PAIR_SHOTS.items():
            for speed in speeds:
                va = np.array([speed, 0.0])
                vb = -va if both else np.zeros(2)
                a = math.radians(angle)
                normal = np.array([math.cos(a), math.sin(a)])
                contact_a = np.array([0.5, 0.5])
                contact_b = contact_a + 2.0 * RADIUS * normal
                starts = (contact_a - va * PAIR_TIME, contact_b - vb * PAIR_TIME)
                expected = pair_expected(va, vb, normal, restitution)
                row: dict[str, Any] = {
                    "shot": name,
                    "speed": speed,
                    "angle": angle,
                    "restitution": restitution,
                    "relative_speed": float(np.linalg.norm(va - vb)),
                }
                for engine, world in worlds.items():
                    for ball, (start, velocity) in enumerate(zip(starts, (va, vb), strict=True)):
                        world.place_ball(0, tuple(start), tuple(velocity), ball=ball)
                    for _ in range(frames):
                        world.step()
                    after = world.balls[0, :2]
                    velocities = after[:, [BALL_VX, BALL_VY]]
                    gap = float((after[1, [BALL_X, BALL_Y]] - after[0, [BALL_X, BALL_Y]]) @ normal)
                    separating = float((velocities[1] - velocities[0]) @ normal)
                    errors = [float(np.linalg.norm(velocities[i] - expected[i])) for i in (0, 1)]
                    row[engine] = {
                        "velocities": velocities.tolist(),
                        "velocity_error": max(errors),
                        "relative_velocity_error": max(errors) / speed,
                        "contact_time_error": end - (gap - 2.0 * RADIUS) / separating - PAIR_TIME,
                        "momentum_error": float(np.linalg.norm(velocities.sum(axis=0) - (va + vb))),
                    }
                row["expected"] = [v.tolist() for v in expected]
                rows.append(row)
    return rows


def pair_tolerance(row: dict[str, Any], engine: str) -> dict[str, float]:
    """The tolerances of a :func:`ball_ball_hits` row, from how the engines work.

    Velocities: the wall bounces' (1% of the speed plus 1 mm/s: both engines apply the same
    impulse law along the line of centres); pymunk resolves the pair up to a substep late, after
    the balls have moved on into each other, so its line of centres is turned by up to
    ``atan(w h sin(angle) / 2r)`` (w the relative speed), which turns the exchanged normal
    velocity, ``(1 + e) / 2 (w . n) n``, by ``(1 + e) / 2 w`` per radian. The contact time its
    paths imply: ours is exact up to the skin it leaves between them (``skin / (e w)``, a few
    microseconds; held to TIME_TOLERANCE as the walls); pymunk's is late by the detection delay
    (up to a substep) and by the overlap that its position correction has hardly removed a few
    frames later (the approach over that delay, closed at ``e`` times the speed): up to
    ``h (1 + 1 / e)``."""
    relative, absolute = VELOCITY_TOLERANCE
    velocity = relative * row["speed"] + absolute
    time = TIME_TOLERANCE
    if engine == "pymunk":
        w, e = row["relative_speed"], row["restitution"]
        turn = math.atan(w * SUBSTEP * math.sin(math.radians(row["angle"])) / (2.0 * RADIUS))
        velocity += 0.5 * (1.0 + e) * w * turn
        time = SUBSTEP * (1.0 + 1.0 / e)
    return {"velocity": velocity, "contact_time": time}


def pair_agrees(row: dict[str, Any], engine: str) -> bool:
    """Whether ``engine``'s ball-ball shot is within :func:`pair_tolerance` of the analytic
    answer (the contact not early)."""
    result, tolerance = row[engine], pair_tolerance(row, engine)
    error = result["contact_time_error"]
    late = error <= tolerance["contact_time"] + 1e-9 and error >= -TIME_TOLERANCE - 1e-9
    return result["velocity_error"] <= tolerance["velocity"] and late


def two_balls_cradled(seconds: float = 4.0) -> dict[str, Any]:
    """Two balls dropped one after the other into the raised left flipper's cradle on
    classic_v1 (the button held), a ball-ball restitution of 0.5: where they come to rest, on
    both engines. The analytic answer: at rest, touching (centres 2r apart), neither in the
    other. Ours leaves a pair a skin apart after a contact (so at most a skin beyond 2r, never
    inside); pymunk lets a resting contact overlap by up to its collision slop (COLLISION_SLOP,
    1e-4 m) before its position correction acts."""
    data = table_to_dict(load_table(CABINET_TABLE))
    table = with_balls(data, 0.5, 0.1)
    result: dict[str, Any] = {"seconds": seconds, "radius": RADIUS}
    for engine in ENGINES:
        world = make_world(table, 1, engine)
        for _ in range(4):  # the left flipper up against its stop
            world.step(LEFT_BUTTON)
        world.place_ball(0, (0.17, 0.2), (0.0, 0.0), ball=0)
        world.place_ball(0, (0.20, 0.24), (0.0, 0.0), ball=1)
        least = math.inf
        for _ in range(int(seconds * FRAME_RATE)):
            world.step(LEFT_BUTTON)
            centres = world.balls[0, :2][:, [BALL_X, BALL_Y]]
            least = min(least, float(np.linalg.norm(centres[1] - centres[0])))
        balls = world.balls[0, :2]
        result[engine] = {
            "in_play": world.active[0, :2].tolist(),
            "positions": balls[:, [BALL_X, BALL_Y]].tolist(),
            "speeds": np.hypot(balls[:, BALL_VX], balls[:, BALL_VY]).tolist(),
            "gap": float(np.linalg.norm(balls[1, [BALL_X, BALL_Y]] - balls[0, [BALL_X, BALL_Y]]))
            - 2.0 * RADIUS,
            "least_gap": least - 2.0 * RADIUS,
        }
    result["apart"] = float(
        np.abs(np.array(result["swept"]["positions"]) - result["pymunk"]["positions"]).max()
    )
    return result
