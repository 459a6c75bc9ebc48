"""Cross-check our swept physics against pymunk: ``python -m pinball_env.tools.crosscheck``.

Runs the same scenarios on both engines (the same validated table object, built by
``pinball_env.sim.backends.make_world``) and writes a report to ``--out`` (default
``outputs/crosscheck``): a table on the terminal, ``crosscheck.json`` and ``crosscheck.png``.

Scenarios: single-wall bounces over a grid of angles and speeds; segment-end (corner) hits;
post hits; a ball falling on a resting flipper; a swinging flipper hit; a free run on the classic
table; and a tunnelling sweep (pass-through fraction against speed, for a thin wall, a resting
flipper and a swinging flipper). Needs the ``crosscheck`` extra (pymunk, matplotlib).

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
  so they are compared by how long they stay within 1 mm and 1 cm of each other, not by a bound.
"""

import argparse
import json
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from pinball_env.physics.columns import BALL_VX, BALL_VY, BALL_X, BALL_Y
from pinball_env.physics.flipper import flipper_distance
from pinball_env.sim.backends import make_world
from pinball_env.sim.world import World
from pinball_env.table import BUTTONS, Table, load_table, table_from_dict, table_to_dict

ENGINES = ("swept", "pymunk")
RADIUS = 0.0135
SUBSTEPS = 10
FRAME_RATE = 60.0
SUBSTEP = 1.0 / (FRAME_RATE * SUBSTEPS)
LOW_SPEED = 4.0  # [m/s]: at most half a ball radius per substep
TIME_TOLERANCE = SUBSTEP
DROP_TIME_TOLERANCE = 2 * SUBSTEP
VELOCITY_TOLERANCE = (0.01, 0.001)  # relative to the incoming speed, absolute [m/s]
FLIPPER_TOLERANCE = 0.10  # relative
HIT_TIME = 0.1  # [s] every aimed scenario is set up to meet its target after this time


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
) -> Table:
    """A 1 m x 1 m open table with the given elements and no outline."""
    return table_from_dict(
        {
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
        path.append(world.balls[0, [BALL_X, BALL_Y]].copy())
        contacts = [c for c in world.frame_contacts() if c.speed > 0.0]
        if contacts and contact_time is None:
            late = SUBSTEP if type(world).__name__ == "PymunkWorld" else 0.0
            contact_time = frame / FRAME_RATE + contacts[0].time + late
    ball = world.balls[0]
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
    offsets: list[float], speed: float = 2.0, restitution: float = 0.5, kick: float = 0.0
) -> list:
    """A ball hits a 1 cm post with impact parameter ``offset`` x (ball + post radius); with a
    ``kick`` it is a pop bumper, which adds that speed along the contact normal."""
    post_radius = 0.01
    table = scenario_table(posts=[([0.5, 0.3], post_radius, kick)], restitution=restitution)
    worlds = {engine: make_world(table, 1, engine) for engine in ENGINES}
    reach = RADIUS + post_radius
    rows = []
    for offset in offsets:
        b = offset * reach
        normal = np.array([b, math.sqrt(reach**2 - b**2)]) / reach
        target = np.array([0.5, 0.3]) + reach * normal
        velocity = np.array([0.0, -speed])
        start = target - velocity * HIT_TIME
        shots = {e: shoot(w, tuple(start), tuple(velocity), 10) for e, w in worlds.items()}
        expected = reflect(velocity, normal, restitution) + kick * normal
        row = {"offset": offset, "speed": speed, "kick": kick}
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
            shots[engine].velocity = world.balls[0, [BALL_VX, BALL_VY]].copy()
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


# --- the report ---------------------------------------------------------------------------------


def run(out: Path, trials: int = 100, free_frames: int = 600) -> dict[str, Any]:
    """Run every scenario, print the report, and write crosscheck.json and crosscheck.png."""
    angles = [15.0, 30.0, 45.0, 60.0, 75.0, 90.0]
    report: dict[str, Any] = {
        "tolerances": {
            "low_speed_m_per_s": LOW_SPEED,
            "contact_time_s": TIME_TOLERANCE,
            "drop_contact_time_s": DROP_TIME_TOLERANCE,
            "velocity_relative": VELOCITY_TOLERANCE[0],
            "velocity_absolute_m_per_s": VELOCITY_TOLERANCE[1],
            "flipper_relative": FLIPPER_TOLERANCE,
        },
        "wall_bounces": wall_bounces([0.5, 1.0, 2.0, 4.0, 8.0, 16.0, 32.0], angles),
        "corner_hits": corner_hits([0.2, 0.4, 0.6, 0.8, 0.95]),
        "post_hits": post_hits([0.0, 0.3, 0.6, 0.9]),
        "bumper_hits": post_hits([0.0, 0.3, 0.6, 0.9], restitution=0.9, kick=1.5),
        "flipper_drop": flipper_drop([0.01, 0.03, 0.1]),
        "flipper_swing": flipper_swing([0.02, 0.035, 0.05, 0.06]),
        "free_run": free_run(free_frames),
        "tunnelling": tunnelling([1.0, 3.0, 10.0, 20.0, 30.0, 50.0, 100.0, 300.0, 1000.0], trials),
    }
    report["summary"] = summarise(report)
    print_report(report)
    out.mkdir(parents=True, exist_ok=True)
    (out / "crosscheck.json").write_text(json.dumps(report, indent=1) + "\n")
    plot(report, out / "crosscheck.png")
    print(f"\nwrote {out / 'crosscheck.json'} and {out / 'crosscheck.png'}")
    return report


def summarise(report: dict[str, Any]) -> dict[str, Any]:
    """Agreement counts on the low-speed scenarios and the headline differences."""
    low = [row for row in report["wall_bounces"] if row["speed"] <= LOW_SPEED]
    tunnel = report["tunnelling"]
    first_pymunk_miss = {
        target: next(
            (v for v, f in zip(tunnel["speeds"], tunnel[target]["pymunk"], strict=True) if f > 0),
            None,
        )
        for target in ("wall", "resting flipper", "swinging flipper")
    }
    static = {
        "wall bounces at <= 4 m/s": low,
        "corner hits": report["corner_hits"],
        "post hits": report["post_hits"],
        "bumper hits": report["bumper_hits"],
    }
    shares = {name: {e: _share(rows, e) for e in ENGINES} for name, rows in static.items()}
    return {
        "findings": _findings(report, shares, first_pymunk_miss),
        "first_pymunk_pass_through_m_per_s": first_pymunk_miss,
        "low_speed_wall_bounces_within_tolerance": {e: _share(low, e) for e in ENGINES},
        "corner_hits_within_tolerance": {e: _share(report["corner_hits"], e) for e in ENGINES},
        "post_hits_within_tolerance": {e: _share(report["post_hits"], e) for e in ENGINES},
        "bumper_hits_within_tolerance": {e: _share(report["bumper_hits"], e) for e in ENGINES},
        "flipper_drop_max_relative_speed_difference": max(
            row["relative_speed_difference"] for row in report["flipper_drop"]
        ),
        "flipper_swing_max_relative_difference": max(
            row["relative_difference"] for row in report["flipper_swing"]
        ),
        "max_pass_through": {
            target: {e: max(tunnel[target][e]) for e in ENGINES}
            for target in ("wall", "resting flipper", "swinging flipper")
        },
        "free_run_diverges_1cm_at_s": report["free_run"]["diverges_1cm_at"],
    }


def _share(rows: list, engine: str) -> float:
    """Share of the scenario ``rows`` in which ``engine`` agrees with the analytic answer."""
    return sum(agrees(row, engine, row["speed"]) for row in rows) / len(rows)


def _findings(
    report: dict[str, Any], shares: dict[str, dict[str, float]], first_pymunk_miss: dict
) -> list[str]:
    """The findings in words, each computed from the measured results."""
    static_agree = all(value == 1.0 for both in shares.values() for value in both.values())
    drops = report["flipper_drop"]
    drop_agree = all(
        0.0 <= row["time_difference"] <= DROP_TIME_TOLERANCE + 1e-9
        and row["relative_speed_difference"] <= FLIPPER_TOLERANCE
        for row in drops
    )
    swing_worst = max(row["relative_difference"] for row in report["flipper_swing"])
    tunnel = report["tunnelling"]
    ours_through = max(max(tunnel[t]["swept"]) for t in first_pymunk_miss)
    g_h = abs(report["free_run"]["gravity"]) * SUBSTEP
    drift = report["free_run"]["divergence"][10]
    return [
        f"{'Agree' if static_agree else 'DISAGREE'}: share of shots within tolerance of the "
        f"analytic bounce, per engine: {shares}; pymunk sees a contact up to one substep late.",
        f"{'Agree' if drop_agree else 'DISAGREE'}: a ball dropped on a resting flipper lands "
        f"up to {1e3 * max(row['time_difference'] for row in drops):.2f} ms later in pymunk "
        "(one substep from its integration order, one from detection) and bounces within "
        f"{100 * max(row['relative_speed_difference'] for row in drops):.1f}% of our speed.",
        f"{'Agree' if swing_worst <= FLIPPER_TOLERANCE else 'DISAGREE'}: a swinging flipper "
        f"launches a resting ball at speeds within {100 * swing_worst:.1f}% of each other "
        f"(tolerance {100 * FLIPPER_TOLERANCE:.0f}%).",
        "Differ, by design: Chipmunk integrates positions before velocities, we integrate "
        "velocities first, so in free flight the paths differ by g h t: after 11 frames "
        f"measured {1e3 * drift:.3f} mm, predicted {1e3 * g_h * 11 / FRAME_RATE:.3f} mm.",
        "Differ, pymunk wrong: without continuous collision a fast ball passes through; first "
        f"pass-throughs at {first_pymunk_miss['wall']} m/s (wall), "
        f"{first_pymunk_miss['resting flipper']} m/s (resting flipper), "
        f"{first_pymunk_miss['swinging flipper']} m/s (swinging flipper). Ours: "
        f"{100 * ours_through:.0f}% at worst over all speeds.",
        "Free run: the paths drift apart by g h t until the first contact, where the "
        "one-substep detection delay separates them by "
        f"1 cm at {report['free_run']['diverges_1cm_at']} s; from there it is chaotic.",
    ]


def print_report(report: dict[str, Any]) -> None:
    """The report as tables on the terminal, then the summary."""
    _print_bounces(report)
    _print_flippers(report)
    free = report["free_run"]
    print(
        f"\nFree run on the classic table ({free['frames']} frames, plunger {free['launch_speed']}"
        f" m/s): paths differ by 1 mm after {free['diverges_1mm_at']} s, 1 cm after "
        f"{free['diverges_1cm_at']} s"
    )
    tunnel = report["tunnelling"]
    print(f"\nPass-through fraction ({tunnel['trials']} aimed shots per speed)")
    header = "".join(f"{speed:>8g}" for speed in tunnel["speeds"])
    print(f"{'target':>17} {'engine':>7} {header}  m/s")
    for target in ("wall", "resting flipper", "swinging flipper"):
        for engine in ENGINES:
            cells = "".join(f"{100 * f:7.0f}%" for f in tunnel[target][engine])
            print(f"{target:>17} {engine:>7} {cells}")
    print("\nSummary")
    for key, value in report["summary"].items():
        if key == "findings":
            for finding in value:
                print(f"  - {finding}")
        else:
            print(f"  {key}: {value}")


def _print_bounces(report: dict[str, Any]) -> None:
    """Wall bounces, corner, post and bumper hits against the analytic answer."""

    def fmt_time(value: float | None) -> str:
        return "  miss " if value is None else f"{1e3 * value:+6.2f}"

    print("Wall bounces: contact-time error [ms] and velocity error [% of speed] vs analytic")
    print(f"{'speed':>6} {'angle':>5} | {'swept dt':>8} {'dv%':>7} | {'pymunk dt':>9} {'dv%':>7}")
    for row in report["wall_bounces"]:
        s, p = row["swept"], row["pymunk"]
        through = " passed through" if p["passed_through"] else ""
        print(
            f"{row['speed']:6.1f} {row['angle']:5.0f} | {fmt_time(s['contact_time_error']):>8} "
            f"{100 * s['relative_velocity_error']:7.3f} | "
            f"{fmt_time(p['contact_time_error']):>9} {100 * p['relative_velocity_error']:7.3f}"
            f"{through}"
        )
    for name, key in (
        ("Corner hits", "offset"),
        ("Post hits", "offset"),
        ("Bumper hits", "offset"),
    ):
        rows = report[name.lower().replace(" ", "_")]
        print(f"\n{name}: velocity error [% of speed] vs analytic")
        for row in rows:
            swept, pym = row["swept"], row["pymunk"]
            print(
                f"  {key} {row[key]:4.2f}: swept {100 * swept['relative_velocity_error']:7.3f}"
                f"   pymunk {100 * pym['relative_velocity_error']:7.3f}"
            )


def _print_flippers(report: dict[str, Any]) -> None:
    """The flipper drop and swing scenarios, engine against engine."""
    print("\nBall dropped on a resting flipper (with gravity)")
    for row in report["flipper_drop"]:
        t, v = row["contact_time"], row["bounce_speed"]
        print(
            f"  height {100 * row['height']:4.1f} cm: contact swept {1e3 * t['swept']:7.2f} ms "
            f"pymunk {1e3 * t['pymunk']:7.2f} ms; bounce swept {v['swept']:.3f} m/s "
            f"pymunk {v['pymunk']:.3f} m/s ({100 * row['relative_speed_difference']:.1f}%)"
        )
    print("\nSwinging flipper hits a resting ball")
    for row in report["flipper_swing"]:
        v = row["speed"]
        print(
            f"  {1e3 * row['along']:4.0f} mm from the pivot: swept {v['swept']:.3f} m/s, pymunk "
            f"{v['pymunk']:.3f} m/s ({100 * row['relative_difference']:.1f}%), "
            f"one-hit estimate (1+e) w r = {row['expected_about']:.3f} m/s"
        )


def _label(ax: Any, title: str, ylabel: str, log: str) -> None:
    """A panel against ball speed: its title, axis labels, log scales on the axes in ``log``
    (``"x"``, ``"xy"``) and legend."""
    for axis in log:
        getattr(ax, f"set_{axis}scale")("log")
    ax.set_xlabel("ball speed [m/s]")
    ax.set_ylabel(ylabel)
    ax.set_title(title)
    ax.legend(fontsize=7)


def plot(report: dict[str, Any], path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(2, 2, figsize=(11, 8))
    ax = axes[0, 0]
    tunnel = report["tunnelling"]
    styles = {"wall": "-", "resting flipper": "--", "swinging flipper": ":"}
    for target, style in styles.items():
        for engine, colour in zip(ENGINES, ("tab:blue", "tab:red"), strict=True):
            ax.plot(tunnel["speeds"], 100 * np.array(tunnel[target][engine]), style, color=colour,
                    marker="o", label=f"{engine}: {target}")  # fmt: skip
    _label(ax, "Tunnelling: thin wall and flipper (substep 1/600 s)", "passed through [%]", "x")

    ax = axes[0, 1]
    rows = report["wall_bounces"]
    for engine, colour in zip(ENGINES, ("tab:blue", "tab:red"), strict=True):
        speeds = [row["speed"] for row in rows]
        errors = [max(100 * row[engine]["relative_velocity_error"], 1e-6) for row in rows]
        ax.scatter(speeds, errors, color=colour, s=12, label=engine)
    ax.axvline(LOW_SPEED, color="grey", ls=":")
    ax.axhline(100 * VELOCITY_TOLERANCE[0], color="grey", ls="--", label="tolerance")
    title = "Wall bounces vs analytic (all angles; exact shown at 1e-6)"
    _label(ax, title, "bounce velocity error [% of speed]", "xy")

    ax = axes[1, 0]
    free = report["free_run"]
    time = np.arange(len(free["divergence"])) / FRAME_RATE
    ax.semilogy(time, np.maximum(free["divergence"], 1e-12))
    ax.axhline(0.001, color="grey", ls=":")
    ax.axhline(0.01, color="grey", ls="--")
    ax.set_xlabel("time [s]")
    ax.set_ylabel("|swept - pymunk| [m]")
    ax.set_title("Free run on the classic table: divergence")

    ax = axes[1, 1]
    from pinball_env.tools.plot import draw_table

    draw_table(ax, load_table("classic"))
    for engine, colour in zip(ENGINES, ("tab:blue", "tab:red"), strict=True):
        p = np.array(free["paths"][engine])
        ax.plot(p[:, 0], p[:, 1], color=colour, lw=0.8, label=engine)
    ax.legend(fontsize=7, loc="upper left")
    ax.set_title("Free run paths")
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=90)
    plt.close(fig)


def main(argv: list[str] | None = None) -> dict[str, Any]:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=Path("outputs/crosscheck"))
    parser.add_argument("--trials", type=int, default=100, help="aimed shots per speed")
    parser.add_argument("--frames", type=int, default=600, help="frames of the free run")
    args = parser.parse_args(argv)
    return run(args.out, args.trials, args.frames)


if __name__ == "__main__":
    main()
