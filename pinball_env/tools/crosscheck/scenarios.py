"""The cross-check's scenarios and tolerances: the same shots on our swept kernel and on pymunk
(the same validated table object, built by ``pinball_env.sim.backends.make_world``), each row
with both engines' results against the analytic answer, and the checks of a row against the
tolerances. The tests take them as their oracle; :mod:`.cli` runs them all into a report.

Scenarios: single-wall bounces over a grid of angles and speeds; segment-end (corner) hits;
post hits; a ball falling on a resting flipper; a swinging flipper hit; a free run on the classic
table; and a tunnelling sweep (pass-through fraction against speed, for a thin wall, a resting
flipper and a swinging flipper). The cabinet (classic_v1's): bumper hits on a tilted machine;
nudges on a ball in free flight, and on one resting on or rolling along a wall or lying in a
flipper's cradle; plunger launches up the shooter lane. Several balls (a trough of two): ball-ball
shots (head-on, onto a resting ball, oblique at 45 degrees; restitution 1 and 0.5) and two balls
cradled together on a raised flipper. Needs pymunk (the ``crosscheck`` extra).

Tolerances, fixed from how the engines work (not tuned to the results):

- contact time: ours is exact up to float rounding; pymunk finds an overlap at the end of the
  substep in which it happens, so its contact time is late by up to one substep (1/600 s);
- velocities after a bounce: both apply v_n' = -e v_n and Coulomb friction to the same contact,
  so they agree to 1% of the incoming speed plus 1 mm/s where pymunk sees the contact before the
  ball has moved more than its slop into the wall, i.e. at low speed (<= 4 m/s: under half a ball
  radius per substep);
- a ball falling from rest: Chipmunk integrates positions before velocities, which under a
  constant force is the same path one substep later, so its landing may be up to two substeps
  late (DROP_TIME_TOLERANCE);
- flipper contacts: pymunk's kinematic flipper turns at the kernel's angular velocity, but it
  resolves the contact after the flipper has already swept into the ball, one substep late at
  worst; the hit speeds agree to 10% (a substep of a 40 rad/s flipper is 0.07 rad);
- free run: the trajectories are chaotic (every bounce off a curved post amplifies a difference),
  so they are compared by how long they stay within 1 mm and 1 cm of each other, not by a bound;
- the cabinet is the kernel's own function on both engines, so it moves bitwise the same; a ball
  in free flight adds its velocity change, opposite, in the same substeps: both agree with it to
  rounding (ROUNDING). A nudge along a wall: both apply the same Coulomb friction with the normal
  impulse of the substep's gravity, so they agree to rounding. A nudge into a surface differs by
  design (see :func:`nudge_contact`): by ``e (J/M + g h)`` on a wall exactly, and in a cradle by
  at most its largest restitution times that approach, plus what the settling left;
- plunger launches: each engine's path is the analytic parabola of launch speed ``v -/+ g h / 2``
  (the integration order), so the apex is within half a substep's travel at the launch speed,
  ``v h / 2`` (plus ``g h^2 / 8``), of the analytic one, the engines ``v h`` apart; the time to
  the gate within half a substep, h / 2 (the paths are ``g h t / 2`` off, which the ball covers in
  under h / 2 while it is faster than the speed it has lost);
- ball-ball shots (:func:`pair_tolerance`): ours is exact (the swept time of impact of two
  moving circles, then the equal-mass impulse); pymunk resolves the pair up to a substep late,
  after the balls have moved into each other, so its line of centres is turned by up to
  ``atan(w h sin(angle) / 2r)`` and the exchanged velocity with it, and the contact its paths
  imply is late by up to ``h (1 + 1 / e)`` (the delay, then the overlap its slow position
  correction leaves, closed at ``e`` times the speed); head-on, it agrees to the wall bounces'
  tolerance. Two cradled balls: at rest touching, ours a skin apart at most and never closer
  than 2r, pymunk's overlapping by up to its slop.
"""

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from pinball_env.game.actions import NUDGE_DIRECTIONS
from pinball_env.physics.columns import (
    BALL_SPIN,
    BALL_VX,
    BALL_VY,
    BALL_X,
    BALL_Y,
    CABINET_SHOVE_X,
    CABINET_SHOVE_Y,
    CABINET_VX,
    CABINET_VY,
)
from pinball_env.physics.flipper import flipper_distance
from pinball_env.sim.backends import PHYSICS, make_world
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


# --- scenarios ----------------------------------------------------------------------------------


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
            frames = int(shots[engine].contact_time * FRAME_RATE) + 1
            for _ in range(frames):
                world.step()
            shots[engine].velocity = world.balls[0, 0, [BALL_VX, BALL_VY]].copy()
        swept, pym = shots["swept"], shots["pymunk"]
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
        gap = flipper_distance(*(pivot + along * axis + 0.05 * normal), *pivot,
                               FLIPPER["length"], FLIPPER["base_radius"], FLIPPER["tip_radius"],
                               angle)[0] - 0.05  # fmt: skip
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
        passed = {engine: [] for engine in ENGINES}
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


# --- the cabinet: nudges, the tilt and the player's plunger -------------------------------------


def nudge(world: World, direction: tuple[float, float], impulse: float) -> None:
    """The game's nudge on env 0: a shove of ``impulse`` [N s] along ``direction`` (a unit
    vector), which the cabinet takes in its next substep."""
    world.state.cabinet[0, [CABINET_SHOVE_X, CABINET_SHOVE_Y]] = impulse * np.array(direction)


def nudge_free_flight(frames: int = 20) -> list:
    """A ball in free flight over the classic_v1 playfield when the cabinet is nudged: relative
    to the table it must change velocity by the cabinet's change, opposite (beside gravity)."""
    table = load_table(CABINET_TABLE)
    impulse, gravity = table.cabinet.nudge_impulse, np.array(table.gravity_vector)
    start, velocity = (0.25, 0.42), np.array([0.1, 0.5])  # clear of everything for 20 frames
    rows = []
    for name, direction in NUDGE_DIRECTIONS.items():
        row: dict[str, Any] = {"nudge": name, "frames": frames}
        for engine in ENGINES:
            world = make_world(table, 1, engine)
            world.place_ball(0, start, tuple(velocity))
            nudge(world, direction, impulse)
            ball, cabinet, contacts = [], [], 0
            for frame in range(frames):
                world.step()
                contacts += int(world.state.contact_count[0])
                time = (frame + 1) / FRAME_RATE
                ball.append(world.balls[0, 0, [BALL_VX, BALL_VY]] - velocity - gravity * time)
                cabinet.append(world.state.cabinet[0, [CABINET_VX, CABINET_VY]].copy())
            # The cabinet starts at rest: its velocity is its velocity change.
            error = np.abs(np.array(ball) + np.array(cabinet)).max()
            row[engine] = {
                "max_velocity_error": float(error),
                "contacts": contacts,
                "ball_velocity_change": np.array(ball).tolist(),
                "cabinet_velocity": np.array(cabinet).tolist(),
            }
        rows.append(row)
    return rows


def _floor_table() -> Table:
    """A long wooden floor (wall at y = 0.3) on the tilted 1 m table, in a cabinet."""
    floor = [[[0.02, 0.3], [0.98, 0.3]]]
    return scenario_table(walls=floor, restitution=0.5, friction=0.3, slope_deg=6.5, cabinet=True)


def _resting(world: World) -> np.ndarray | None:
    """A ball at rest on the floor, no buttons held."""
    world.place_ball(0, (0.5, 0.3 + RADIUS), (0.0, 0.0))
    return None


def _rolling(world: World) -> np.ndarray | None:
    """A ball rolling along the floor at 0.5 m/s, no buttons held."""
    world.place_ball(0, (0.3, 0.3 + RADIUS), (0.5, 0.0))
    world.balls[0, 0, BALL_SPIN] = -0.5 / RADIUS  # rolling: no slip at the contact point
    return None


def _cradled(world: World) -> np.ndarray | None:
    """A ball dropped into the raised left flipper's cradle on classic_v1, the button held."""
    buttons = LEFT_BUTTON
    for _ in range(4):  # the left flipper up against its stop
        world.step(buttons)
    world.place_ball(0, (0.17, 0.2), (0.0, 0.0))  # it rolls down into the cradle
    return buttons


# name: (table, set up env 0 (returns the buttons it holds), frames to settle, the surface's
# normal (None: several surfaces), its restitution (the largest of them))
NUDGE_SITUATIONS = {
    "resting on a wall": (_floor_table, _resting, 30, (0.0, 1.0), 0.5),
    "rolling along a wall": (_floor_table, _rolling, 10, (0.0, 1.0), 0.5),
    "in a flipper's cradle": (lambda: load_table(CABINET_TABLE), _cradled, 180, None, 0.8),
}


def nudge_contact() -> list:
    """A ball resting on or rolling along a wall, or lying in a raised flipper's cradle on
    classic_v1, settled, then nudged: its velocity one frame after the shove on both engines.

    Along the surface both engines apply the same Coulomb friction with the normal impulse of
    the substep's gravity, so they agree to rounding. A shove into the surface is an impact on
    ours (the shove's whole velocity change comes in one substep), bounced with restitution
    ``e``; pymunk fixes a contact's bounce from the velocities before the substep's velocity
    update (``cpArbiterPreStep``), so to it the same shove is a push: ours leaves at
    ``e (J/M + g h)`` more. In the cradle (a flipper, a guide) the difference is at most the
    largest restitution times that approach, plus the difference the settling left.
    """
    rows = []
    for situation, (make_table, setup, settle, normal, restitution) in NUDGE_SITUATIONS.items():
        table = make_table()
        impulse, mass = table.cabinet.nudge_impulse, table.cabinet.mass
        gravity = np.array(table.gravity_vector)
        for name, direction in NUDGE_DIRECTIONS.items():
            before, after = {}, {}
            for engine in ENGINES:
                world = make_world(table, 1, engine)
                buttons = setup(world)
                for _ in range(settle):
                    world.step(buttons)
                before[engine] = world.balls[0, 0, [BALL_VX, BALL_VY]].copy()
                nudge(world, direction, impulse)
                world.step(buttons)
                after[engine] = world.balls[0, 0, [BALL_VX, BALL_VY]].copy()
            difference = float(np.linalg.norm(after["swept"] - after["pymunk"]))
            settled = float(np.linalg.norm(before["swept"] - before["pymunk"]))
            row: dict[str, Any] = {
                "situation": situation,
                "nudge": name,
                "velocity_before": {e: v.tolist() for e, v in before.items()},
                "velocity": {e: v.tolist() for e, v in after.items()},
                "difference": difference,
            }
            if normal is None:
                approach = impulse / mass + float(np.linalg.norm(gravity)) * SUBSTEP
                row["bound"] = restitution * approach + settled
            else:  # our rebound off a surface the shove drives into the ball
                into = float(np.dot(direction, normal))
                approach = impulse / mass * into - float(gravity @ normal) * SUBSTEP
                row["expected_difference"] = restitution * approach if into > 0.0 else 0.0
            rows.append(row)
    return rows


def nudge_agrees(row: dict[str, Any]) -> bool:
    """Whether a :func:`nudge_contact` row is what the engines' contact rules predict."""
    if "bound" in row:
        return row["difference"] <= row["bound"]
    return abs(row["difference"] - row["expected_difference"]) <= ROUNDING


def plunger_launches(pulls: list[float]) -> list:
    """The player's plunger on classic_v1 let go at ``pulls`` (fractions of its stroke): the
    ball flies straight up the shooter lane, touching nothing, to its apex below the gate or
    across the gate's hinge (the top of the lane's wall). Against the analytic parabola, on
    both engines.

    Each engine's frames sample the exact parabola of launch speed ``v -/+ g h / 2``
    (velocities first: minus; positions first: plus), so a parabola through the last three
    frames gives its apex and its gate time exactly.
    """
    table = load_table(CABINET_TABLE)
    plunger = table.plunger
    g = -table.gravity_vector[1]
    y0 = plunger.position[1]
    gate_y = next(wall for wall in table.walls if wall.name == "gate").points[0][1]
    rows = []
    for pull in pulls:
        speed = plunger.launch_speed(pull * plunger.stroke)
        rise = gate_y - y0
        crosses = speed * speed > 2.0 * g * rise
        expected_time = (speed - math.sqrt(speed * speed - 2.0 * g * rise)) / g if crosses else None
        row: dict[str, Any] = {
            "pull": pull,
            "speed": speed,
            "apex": None if crosses else y0 + speed * speed / (2.0 * g),
            "gate_time": expected_time,
            "gate_speed": None if not crosses else speed - g * expected_time,
        }
        if crosses:
            row["gate_time_tolerance"] = SUBSTEP / 2.0
        else:  # (v -/+ g h / 2)^2 / 2 g: half a substep's travel at the launch speed, and a bit
            row["apex_tolerance"] = speed * SUBSTEP / 2.0 + g * SUBSTEP**2 / 8.0 + ROUNDING
        for engine in ENGINES:
            world = make_world(table, 1, engine)
            world.launch(0, speed)
            times, heights, contacts = [0.0], [y0], 0
            while heights[-1] < gate_y and (len(heights) < 3 or heights[-1] > heights[-2]):
                world.step()
                contacts += int(world.state.contact_count[0])
                times.append(len(times) / FRAME_RATE)
                heights.append(float(world.balls[0, 0, BALL_Y]))
            a, b, c = np.polyfit(times[-3:], heights[-3:], 2)
            if crosses:
                roots = np.roots([a, b, c - gate_y]).real
                result = {"gate_time": float(roots[(roots > times[-2]) & (roots <= times[-1])][0])}
            else:
                result = {"apex": float(c - b * b / (4.0 * a))}
            row[engine] = {**result, "contacts": contacts}
        rows.append(row)
    return rows


def plunger_agrees(row: dict[str, Any], engine: str) -> bool:
    """Whether ``engine``'s launch is within the stated tolerance of the analytic one: the
    apex within half a substep's travel at the launch speed; the gate time within half a
    substep (the path is g h t / 2 off, which the ball, still faster at the gate than the
    speed it has lost, covers in under h / 2)."""
    result = row[engine]
    if result["contacts"]:
        return False
    if row["apex"] is not None:
        return abs(result["apex"] - row["apex"]) <= row["apex_tolerance"]
    keeps_more = row["gate_speed"] > row["speed"] - row["gate_speed"]
    return keeps_more and abs(result["gate_time"] - row["gate_time"]) <= row["gate_time_tolerance"]


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


# --- several balls ---------------------------------------------------------------------

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
