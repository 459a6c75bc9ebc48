"""The cabinet (classic_v1's): nudges on a ball in free flight and on one resting on or rolling
along a wall or lying in a flipper's cradle, and the player's plunger's launches."""

import math
from typing import Any

import numpy as np

from pinball_env.game.actions import NUDGE_DIRECTIONS
from pinball_env.physics.columns import (
    BALL_SPIN,
    BALL_VX,
    BALL_VY,
    BALL_Y,
    CABINET_SHOVE_X,
    CABINET_SHOVE_Y,
    CABINET_VX,
    CABINET_VY,
)
from pinball_env.sim.backends import make_world
from pinball_env.sim.world import World
from pinball_env.table import Table, load_table
from pinball_env.tools.crosscheck.scenarios.shots import (
    CABINET_TABLE,
    ENGINES,
    FRAME_RATE,
    LEFT_BUTTON,
    RADIUS,
    ROUNDING,
    SUBSTEP,
    scenario_table,
)


def nudge(world: World, direction: tuple[float, float], impulse: float) -> None:
    """The game's nudge on env 0: a shove of ``impulse`` [N s] along ``direction`` (a unit
    vector), which the cabinet takes in its next substep."""
    world.state.cabinet[0, [CABINET_SHOVE_X, CABINET_SHOVE_Y]] = impulse * np.array(direction)


def nudge_free_flight(frames: int = 20) -> list:
    """A ball in free flight over the classic_v1 playfield when the cabinet is nudged: relative
    to the table it must change velocity by the cabinet's change, opposite (beside gravity)."""
    table = load_table(CABINET_TABLE)
    assert table.cabinet is not None
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
        assert table.cabinet is not None
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
    assert plunger is not None and plunger.stroke is not None  # (the player's)
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
            "gate_speed": None if expected_time is None else speed - g * expected_time,
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
