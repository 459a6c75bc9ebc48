"""Pinball-v2's tilt: any sustained nudging trips it; a single shove and the heuristic's do not.

Pinball-v1's bob ignores one-way nudging (kept bitwise, and tested here as documented); v2's is
set as Visual Pinball X sets it by default, so that a firm shove swings it onto its ring, and
each shove is one warning.
"""

import math

import gymnasium as gym
import numpy as np
import pytest

import pinball_env  # noqa: F401  (registers Pinball-v1 and -v2)
from pinball_env.physics.cabinet import cabinet_substep
from pinball_env.physics.columns import (
    BOB_TOUCHES,
    BOB_VX,
    BOB_X,
    BOB_Y,
    CABINET_SHOVE_X,
    CABINET_STATE_SIZE,
)
from pinball_env.players import HeuristicPolicy
from pinball_env.table import load_table
from pinball_env.tools.tilt import EVERY, NUDGES, heuristic_games, pattern_times

# The fastest rate the cabinet allows: one shove per nudge_interval (0.25 s, 15 frames).
FASTEST = 15
# "Within a few seconds": the patterns tilt Pinball-v2 within this [s].
FEW_SECONDS = 3.0


@pytest.mark.parametrize("every", EVERY)
@pytest.mark.parametrize("nudge", ["NUDGE_LEFT", "NUDGE_RIGHT", "NUDGE_UP"])
def test_one_way_nudging_tilts_v2_within_seconds(nudge, every):
    result = pattern_times("Pinball-v2", [NUDGES[nudge]], every, 2 * FEW_SECONDS)
    assert result["warning"] is not None and result["warning"] < 0.1  # the first shove warns
    assert result["tilt"] is not None and result["tilt"] <= FEW_SECONDS


@pytest.mark.parametrize("every", EVERY)
def test_alternating_nudging_tilts_v2_within_seconds(every):
    pattern = [NUDGES["NUDGE_LEFT"], NUDGES["NUDGE_RIGHT"]]
    result = pattern_times("Pinball-v2", pattern, every, 2 * FEW_SECONDS)
    assert result["tilt"] is not None and result["tilt"] <= FEW_SECONDS


@pytest.mark.parametrize("nudge", ["NUDGE_LEFT", "NUDGE_UP"])
def test_v1_ignores_one_way_nudging_as_documented(nudge):
    """Pinball-v1 stays what it is: one-way shoves at the fastest rate never even warn (its
    docs say so, and that Pinball-v2 is the one to use), while alternating ones tilt it."""
    assert pattern_times("Pinball-v1", [NUDGES[nudge]], FASTEST, 20.0)["warning"] is None
    pattern = [NUDGES["NUDGE_LEFT"], NUDGES["NUDGE_RIGHT"]]
    assert pattern_times("Pinball-v1", pattern, FASTEST, 20.0)["tilt"] is not None


@pytest.mark.parametrize("nudge", sorted(NUDGES))
def test_a_single_shove_is_one_warning_forgotten_later(nudge):
    tilt = load_table("classic_v2").tilt
    seconds = tilt.warning_time + 2.0
    result = pattern_times("Pinball-v2", [NUDGES[nudge]], round(seconds * 60) + 1, seconds)
    assert result["warning"] is not None and result["warning"] < 0.1 and result["tilt"] is None
    assert result["warnings"] == 0  # forgotten after warning_time without another


def test_shoves_within_settle_time_are_one_warning_and_later_ones_their_own():
    tilt = load_table("classic_v2").tilt
    settle = round(tilt.settle_time * 60)
    for gap, warnings in ((settle // 2, 1), (settle + 15, 2)):
        env = gym.make("Pinball-v2")
        env.reset(seed=0)
        most = 0
        for frame in range(2 * settle + 60):
            _, _, _, _, info = env.step(NUDGES["NUDGE_LEFT"] if frame in (0, gap) else 0)
            most = max(most, info["tilt_warnings"])
        assert most == warnings and not info["tilted"]


def test_the_bob_answers_one_shove_as_its_ode_until_the_ring():
    """After one shove, v2's bob follows the coupled ODE of cabinet and bob (the exact solution
    of the linear system, by its eigenvectors) until the ODE's swing reaches the ring; the
    kernel touches the ring then, never passes it, and touches it no more after settle_time."""
    table = load_table("classic_v2")
    cab, tilt = table.cabinet, table.tilt
    constants = table.pack().cabinet[0]
    h = 1.0 / (table.simulation.frame_rate * table.simulation.substeps)
    length, ring = tilt.bob_length, math.radians(tilt.ring_angle)
    # y = (x, v, theta, omega) along the shove: y' = A y, from just after the impulse.
    spring, drag = cab.stiffness / cab.mass, cab.damping / cab.mass
    rates = np.array([
        [0.0, 1.0, 0.0, 0.0],
        [-spring, -drag, 0.0, 0.0],
        [0.0, 0.0, 0.0, 1.0],
        [spring / length, drag / length, -table.gravity / length, -tilt.bob_damping],
    ])  # fmt: skip
    v0 = cab.nudge_impulse / cab.mass
    start = np.array([0.0, v0, 0.0, -v0 / length])  # the bob stays as the cabinet leaves
    values, vectors = np.linalg.eig(rates)
    weights = np.linalg.solve(vectors, start)

    def exact(t: float) -> float:
        return float((vectors @ (weights * np.exp(values * t))).real[2])

    state = np.zeros(CABINET_STATE_SIZE)
    state[CABINET_SHOVE_X] = cab.nudge_impulse
    reached = touched = None  # the substeps where the ODE reaches the ring, the kernel touches
    worst, peak, last_touch, touches = 0.0, 0.0, 0.0, 0.0
    for k in range(1, round(2.0 / h)):
        cabinet_substep(state, constants, h)  # (touches add up: no frame clears them)
        assert math.hypot(state[BOB_X], state[BOB_Y]) <= ring * (1 + 1e-12)
        theta = exact(k * h)
        if reached is None and abs(theta) < ring:
            worst = max(worst, abs(state[BOB_X] - theta))
            peak = max(peak, abs(theta))
        elif reached is None:
            reached = k
        if touched is None and state[BOB_TOUCHES]:
            touched = k
        if state[BOB_TOUCHES] > touches:
            last_touch, touches = k * h, state[BOB_TOUCHES]
    assert reached is not None  # one shove swings the bob onto the ring ...
    assert worst < 0.05 * peak  # ... along its ODE (first order in the substep) ...
    assert touched is not None and abs(touched - reached) <= 1  # ... and touches it then
    # Its rebounds touch again, all within settle_time: one shove is one warning.
    assert last_touch < tilt.settle_time


def test_its_swing_inside_the_ring_leaves_every_shove_a_touch():
    """The ring caps the bob's own swing at its angle; a shove's lag alone is more than twice
    that, so a shove touches whatever the bob was doing: a bob against the ring on the far side,
    swinging out at full speed, is shoved onto the near side."""
    table = load_table("classic_v2")
    constants = table.pack().cabinet[0]
    h = 1.0 / (table.simulation.frame_rate * table.simulation.substeps)
    ring = math.radians(table.tilt.ring_angle)
    state = np.zeros(CABINET_STATE_SIZE)
    state[BOB_X] = ring  # on the far side (a shove towards +x swings the bob to -x) ...
    state[BOB_VX] = 3.0  # ... swinging out hard
    state[CABINET_SHOVE_X] = table.cabinet.nudge_impulse
    sides = set()
    for _ in range(round(0.2 / h)):
        cabinet_substep(state, constants, h)
        if math.hypot(state[BOB_X], state[BOB_Y]) >= ring * (1 - 1e-9):
            sides.add(np.sign(state[BOB_X]))
    assert -1.0 in sides


def test_the_heuristic_never_tilts_v2_over_100_games():
    """The heuristic under the protocol (sticky actions) on its 100 held-out games: on v2 every
    nudge warns, so it nudges only while no warning stands, and never tilts."""
    assert HeuristicPolicy(load_table("classic_v2"))._shove_warns
    assert not HeuristicPolicy(load_table("classic_v1"))._shove_warns
    games = heuristic_games("Pinball-v2", 100)
    assert games["games"] == 100 and games["tilts"] == 0 and games["most_warnings"] == 1
    assert games["nudges"] > 100  # it does nudge (each a warning)


def test_nudges_more_than_warning_time_apart_never_tilt_v2():
    tilt = load_table("classic_v2").tilt
    every = round((tilt.warning_time + 1.0) * 60)
    result = pattern_times("Pinball-v2", [NUDGES["NUDGE_LEFT"]], every, 4.5 * every / 60)
    assert result["tilt"] is None and result["warnings"] <= 1
