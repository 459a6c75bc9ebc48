"""Contacts on the open scenario table: wall bounces, corner and post hits, a ball falling on a
resting flipper, a swinging flipper's hit, a free run on the classic table, tunnelling."""

import math
from typing import Any

import numpy as np

from pinball_env.physics.columns import BALL_VX, BALL_VY
from pinball_env.physics.flipper import flipper_distance
from pinball_env.sim.backends import make_world
from pinball_env.table import load_table
from pinball_env.tools.crosscheck.scenarios.shots import (
    ENGINES,
    FLIPPER,
    FRAME_RATE,
    HIT_TIME,
    LEFT_BUTTON,
    RADIUS,
    SUBSTEP,
    compare,
    reflect,
    scenario_table,
    shoot,
)


def wall_bounces(speeds: list[float], angles: list[float], restitution: float = 0.5) -> list:
    """A ball hits a long horizontal wall at y = 0.3 at ``angle`` degrees from the wall."""
    table = scenario_table(walls=[[[0.02, 0.3], [0.98, 0.3]]], restitution=restitution)
    worlds = {engine: make_world(table, 1, engine) for engine in ENGINES}
    rows = []
    for speed in speeds:
        for angle in angles:
            a = math.radians(angle)
            velocity = np.array([speed * math.cos(a), -speed * math.sin(a)])
            target = np.array([0.5, 0.3 + RADIUS])
            start = target - velocity * HIT_TIME
            frames = int(HIT_TIME * FRAME_RATE) + 6
            shots = {e: shoot(w, tuple(start), tuple(velocity), frames) for e, w in worlds.items()}
            expected = reflect(velocity, np.array([0.0, 1.0]), restitution)
            row = {"speed": speed, "angle": angle, **compare(expected, shots, speed)}
            for engine, shot in shots.items():
                row[engine]["passed_through"] = bool(shot.position[1] < 0.3)
            rows.append(row)
    return rows


def corner_hits(offsets: list[float], speed: float = 2.0, restitution: float = 0.5) -> list:
    """A ball falls past the end of a wall, ``offset`` x ball radius beyond it: it hits the end."""
    table = scenario_table(walls=[[[0.2, 0.3], [0.5, 0.3]]], restitution=restitution)
    worlds = {engine: make_world(table, 1, engine) for engine in ENGINES}
    rows = []
    for offset in offsets:
        b = offset * RADIUS
        normal = np.array([b, math.sqrt(RADIUS**2 - b**2)]) / RADIUS
        target = np.array([0.5, 0.3]) + RADIUS * normal  # ball centre at contact
        velocity = np.array([0.0, -speed])
        start = target - velocity * HIT_TIME
        shots = {e: shoot(w, tuple(start), tuple(velocity), 10) for e, w in worlds.items()}
        expected = reflect(velocity, normal, restitution)
        rows.append({"offset": offset, "speed": speed, **compare(expected, shots, speed)})
    return rows


def post_hits(
    offsets: list[float],
    speed: float = 2.0,
    restitution: float = 0.5,
    kick: float = 0.0,
    tilted: bool = False,
) -> list:
    """A ball hits a 1 cm post with impact parameter ``offset`` x (ball + post radius); with a
    ``kick`` it is a pop bumper, which adds that speed along the contact normal, unless the
    machine is ``tilted`` (its kickers dead)."""
    post_radius = 0.01
    table = scenario_table(posts=[([0.5, 0.3], post_radius, kick)], restitution=restitution)
    worlds = {engine: make_world(table, 1, engine) for engine in ENGINES}
    for world in worlds.values():
        world.state.tilted[0] = tilted
    reach = RADIUS + post_radius
    rows = []
    for offset in offsets:
        b = offset * reach
        normal = np.array([b, math.sqrt(reach**2 - b**2)]) / reach
        target = np.array([0.5, 0.3]) + reach * normal
        velocity = np.array([0.0, -speed])
        start = target - velocity * HIT_TIME
        shots = {e: shoot(w, tuple(start), tuple(velocity), 10) for e, w in worlds.items()}
        expected = reflect(velocity, normal, restitution) + (0.0 if tilted else kick) * normal
        row = {"offset": offset, "speed": speed, "kick": kick, "tilted": tilted}
        rows.append({**row, **compare(expected, shots, speed)})
    return rows


def flipper_drop(heights: list[float]) -> list:
    """A ball dropped from rest ``height`` above the middle of a resting flipper's face, under
    the table's gravity: when it lands and how fast it bounces, on both engines."""
    table = scenario_table(flipper=True, slope_deg=6.5)
    rows = []
    angle = math.radians(FLIPPER["rest_angle"])
    along = 0.035
    pivot = np.array(FLIPPER["pivot"])
    surface = pivot + along * np.array([math.cos(angle), math.sin(angle)])
    for height in heights:
        start = surface + np.array([0.0, 0.012 + RADIUS + height])  # face ~12 mm above the axis
        shots = {}
        for engine in ENGINES:
            world = make_world(table, 1, engine)
            shots[engine] = shoot(world, tuple(start), (0.0, 0.0), 90)
            # Speed right after the first bounce: rerun to the frame after the contact.
            world = make_world(table, 1, engine)
            world.place_ball(0, tuple(start), (0.0, 0.0))
            landed = shots[engine].contact_time
            assert landed is not None, f"{engine}: the dropped ball never landed"
            frames = int(landed * FRAME_RATE) + 1
            for _ in range(frames):
                world.step()
            shots[engine].velocity = world.balls[0, 0, [BALL_VX, BALL_VY]].copy()
        swept, pym = shots["swept"], shots["pymunk"]
        assert swept.contact_time is not None and pym.contact_time is not None  # (landed)
        speed = lambda shot: float(np.linalg.norm(shot.velocity))  # noqa: E731
        rows.append(
            {
                "height": height,
                "contact_time": {"swept": swept.contact_time, "pymunk": pym.contact_time},
                "bounce_speed": {"swept": speed(swept), "pymunk": speed(pym)},
                "time_difference": pym.contact_time - swept.contact_time,
                "relative_speed_difference": abs(speed(pym) - speed(swept)) / speed(swept),
            }
        )
    return rows


def flipper_swing(alongs: list[float]) -> list:
    """A ball at rest just above a resting flipper's face, ``along`` metres from the pivot; the
    flipper is energised: the ball leaves at about (1 + e) times the surface's normal speed."""
    table = scenario_table(flipper=True)
    rows = []
    angle = math.radians(FLIPPER["rest_angle"])
    pivot = np.array(FLIPPER["pivot"])
    axis = np.array([math.cos(angle), math.sin(angle)])
    normal = np.array([-math.sin(angle), math.cos(angle)])
    omega = math.radians(abs(FLIPPER["up_angle"] - FLIPPER["rest_angle"])) / FLIPPER["stroke_time"]
    buttons = LEFT_BUTTON
    for along in alongs:
        x, y = pivot + along * axis + 0.05 * normal
        gap = flipper_distance(x, y, pivot[0], pivot[1], FLIPPER["length"],
                               FLIPPER["base_radius"], FLIPPER["tip_radius"], angle)[0]  # fmt: skip
        gap -= 0.05
        start = pivot + along * axis + (RADIUS - gap + 1e-4) * normal
        speeds = {}
        for engine in ENGINES:
            world = make_world(table, 1, engine)
            shot = shoot(world, tuple(start), (0.0, 0.0), 3, buttons)
            speeds[engine] = float(np.linalg.norm(shot.velocity))
        expected = (1.0 + 0.8) * omega * along
        rows.append(
            {
                "along": along,
                "speed": speeds,
                "expected_about": expected,
                "relative_difference": abs(speeds["pymunk"] - speeds["swept"]) / speeds["swept"],
            }
        )
    return rows


def free_run(frames: int, launch_speed: float = 2.7) -> dict[str, Any]:
    """The same plunger shot on the classic table with no buttons, on both engines."""
    table = load_table("classic")
    paths = {}
    for engine in ENGINES:
        world = make_world(table, 1, engine)
        world.launch(0, launch_speed)
        paths[engine] = np.array(world.trace(frames))
    distance = np.linalg.norm(paths["swept"] - paths["pymunk"], axis=1)

    def first_above(limit: float) -> float | None:
        above = np.flatnonzero(distance > limit)
        return None if len(above) == 0 else float(above[0] / FRAME_RATE)

    return {
        "frames": frames,
        "launch_speed": launch_speed,
        "gravity": table.gravity_vector[1],
        "divergence": distance.tolist(),
        "diverges_1mm_at": first_above(0.001),
        "diverges_1cm_at": first_above(0.01),
        "paths": {engine: path.tolist() for engine, path in paths.items()},
    }


def tunnelling(speeds: list[float], trials: int, seed: int = 0) -> dict[str, Any]:
    """Pass-through fraction against speed for a thin wall, a resting and a swinging flipper.

    Each trial aims the ball's centre at a random point of the target's axis (the middle half of
    a flipper, the middle of a long wall) from a random direction (within 30 degrees of a
    flipper's normal, 60 of the wall's), in open space with no gravity, arriving at a random
    phase of the substep (where a discrete engine samples the path matters). A ball that ends on
    the far side of the target's line passed through it: nothing else is there to send it round.
    """
    rng = np.random.default_rng(seed)
    wall_table = scenario_table(walls=[[[0.05, 0.5], [0.95, 0.5]]], restitution=0.5)
    flipper_table = scenario_table(flipper=True)
    rest, up = math.radians(FLIPPER["rest_angle"]), math.radians(FLIPPER["up_angle"])
    pivot = np.array(FLIPPER["pivot"])

    def pose(angle: float) -> tuple[np.ndarray, np.ndarray]:
        return np.array([math.cos(angle), math.sin(angle)]), np.array(
            [-math.sin(angle), math.cos(angle)]
        )

    axis, normal = pose(rest)
    mid_axis, mid_normal = pose(0.5 * (rest + up))
    _, up_normal = pose(up)
    length = FLIPPER["length"]
    swing_buttons = LEFT_BUTTON
    # name: (table, first aim point, axis, normal at the shot, a point of the target's line and
    #        its normal at the end, aimed span, largest tilt, buttons, arrival time)
    targets = {
        "wall": (wall_table, np.array([0.3, 0.5]), np.array([1.0, 0.0]), np.array([0.0, 1.0]),
                 np.array([0.3, 0.5]), np.array([0.0, 1.0]), 0.4, 60.0, None, HIT_TIME),
        "resting flipper": (flipper_table, pivot + 0.25 * length * axis, axis, normal, pivot,
                            normal, 0.5 * length, 30.0, None, HIT_TIME),
        # The ball arrives as the flipper passes mid-swing (11 ms into its 22 ms stroke).
        "swinging flipper": (flipper_table, pivot + 0.25 * length * mid_axis, mid_axis,
                             mid_normal, pivot, up_normal, 0.5 * length, 30.0, swing_buttons,
                             0.011),
    }  # fmt: skip
    result: dict[str, Any] = {"speeds": speeds, "trials": trials}
    for name, (table, origin, along, shot_normal, line_point, end_normal, span, tilt_max,
               buttons, arrival) in targets.items():  # fmt: skip
        worlds = {engine: make_world(table, 1, engine) for engine in ENGINES}
        passed: dict[str, list[float]] = {engine: [] for engine in ENGINES}
        for speed in speeds:
            counts = dict.fromkeys(ENGINES, 0)
            for _ in range(trials):
                point = origin + rng.uniform(0.0, span) * along
                tilt = math.radians(rng.uniform(-tilt_max, tilt_max))
                velocity = -speed * (math.cos(tilt) * shot_normal + math.sin(tilt) * along)
                arrive = arrival + rng.uniform(-0.5, 0.5) * SUBSTEP
                start = point - velocity * arrive
                frames = int(arrive * FRAME_RATE) + 3
                for engine, world in worlds.items():
                    world.rest_flippers(0)
                    shot = shoot(world, tuple(start), tuple(velocity), frames, buttons)
                    counts[engine] += float((shot.position - line_point) @ end_normal) < 0.0
            for engine in ENGINES:
                passed[engine].append(counts[engine] / trials)
        result[name] = passed
    return result
