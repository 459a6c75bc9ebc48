"""Targets and their kin in the swept kernel: drop targets (and their banks), stand-up targets,
spinners and kickbacks, on small rigs with no gravity in the plane (balls fly straight)."""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pinball_env.physics.columns import SPIN_ANGLE, SPIN_OMEGA
from pinball_env.physics.targets import spin_spinner, turn_spinner
from pinball_env.sim.world import World
from pinball_env.table import table_from_dict

RADIUS = 0.0135
LINE = 0.5  # the rigs' elements lie across the box at this height [m]
ACROSS = [[0.011, LINE], [0.499, LINE]]


def rig(**sections) -> object:
    """A closed box 0.49 x 1.05 m, level (slope 0), with ``sections`` added."""
    data = {
        "name": "target_rig",
        "playfield": {"width": 0.51, "height": 1.07},
        "slope_deg": 0.0,
        "ball": {"radius": RADIUS, "mass": 0.08, "start": [0.255, 0.2]},
        "materials": {
            "wall": {"restitution": 0.3, "friction": 0.3},
            "target": {"restitution": 0.5, "friction": 0.3},
        },
        "walls": [
            {
                "name": "outline",
                "points": [[0.01, 0.01], [0.50, 0.01], [0.50, 1.06], [0.01, 1.06]],
                "closed": True,
                "material": "wall",
            }
        ],
        **sections,
    }
    return table_from_dict(data, "<target rig>")


def bank_rig(reset_time: float = 30.0) -> object:
    """One drop target across the box, and a sensor on its line: a ball centre that crosses
    the sensor has passed through the target."""
    bank = {
        "name": "bank",
        "material": "target",
        "reset_time": reset_time,
        # Wall to wall: no ball gets round it.
        "targets": [{"name": "target", "points": [[0.0101, LINE], [0.4999, LINE]], "score": 100}],
    }
    return rig(
        drop_targets=[bank],
        sensors=[{"name": "behind", "points": ACROSS}],
    )


def events(world: World, name: str) -> list[float]:
    """Times of the frame's contacts or crossings of element ``name`` [s]."""
    return [c.time for c in world.frame_contacts(0) if c.name == name]


@pytest.mark.parametrize("speed", [0.3, 3.0, 30.0, 300.0, 1000.0])
def test_a_standing_drop_target_stops_the_ball_and_a_fallen_one_lets_it_through(speed):
    table = bank_rig()
    world = World(table)
    h = 1.0 / 60.0 / table.simulation.substeps
    world.place_ball(0, (0.255, 0.3), (0.0, speed))
    hit_frame = None
    for frame in range(200):
        world.step()
        hits, crossings = events(world, "target"), events(world, "behind")
        if hit_frame is None and hits:
            hit_frame = frame
            # The target drops at the end of the substep that hit it: no crossing before.
            end = (math.floor(hits[0] / h) + 1) * h
            assert all(t >= end - 1e-12 for t in crossings), (hits, crossings)
        elif hit_frame is None:
            assert not crossings
        if hit_frame is not None:
            break
    assert hit_frame is not None
    assert not world.state.targets_up[0, 0]
    assert world.state.hits[0, table.element_names.index("target")] >= 1
    # Down, it is no contact at any speed: a ball fired at it goes through.
    world.place_ball(0, (0.255, 0.3), (0.0, speed))
    crossed = False
    for _ in range(200):
        world.step()
        assert not events(world, "target")
        crossed = crossed or bool(events(world, "behind"))
        if crossed:
            break
    assert crossed


@settings(max_examples=60, deadline=None)
@given(
    x=st.floats(0.06, 0.45),
    angle=st.floats(-1.2, 1.2),
    speed=st.floats(0.05, 1000.0),
)
def test_no_shot_passes_a_standing_drop_target(x, angle, speed):
    """Aimed shots from below, any direction upwards and any speed: while the target stands,
    the ball's centre never crosses its line."""
    table = bank_rig()
    world = World(table)
    h = 1.0 / 60.0 / table.simulation.substeps
    world.place_ball(0, (x, 0.3), (speed * math.sin(angle), speed * math.cos(angle)))
    for _ in range(120):
        world.step()
        hits, crossings = events(world, "target"), events(world, "behind")
        if hits:
            end = (math.floor(hits[0] / h) + 1) * h
            assert all(t >= end - 1e-12 for t in crossings)
            return
        assert not crossings
        assert world.state.balls[0, 0, 1] < LINE


def test_a_bank_rises_after_its_reset_time_but_never_onto_the_ball():
    table = bank_rig(reset_time=0.5)
    world = World(table)
    world.state.targets_up[0] = False
    # The ball lies still across the fallen target's line: the bank waits.
    world.place_ball(0, (0.255, LINE + 0.005), (0.0, 0.0))
    for _ in range(120):
        world.step()
        assert not world.state.targets_up[0, 0]
    # Gone from there, the bank rises at once (its time has long passed).
    world.place_ball(0, (0.255, 0.2), (0.0, 0.0))
    world.step()
    assert world.state.targets_up[0, 0]


def test_a_bank_rises_reset_time_after_its_last_target_fell():
    bank = {
        "name": "bank",
        "material": "target",
        "reset_time": 0.5,
        "targets": [
            {"name": "left", "points": [[0.05, LINE], [0.2, LINE]]},
            {"name": "right", "points": [[0.31, LINE], [0.46, LINE]]},
        ],
    }
    world = World(rig(drop_targets=[bank]))
    world.place_ball(0, (0.125, 0.3), (0.0, 2.0))  # knocks down the left one
    for _ in range(30):
        world.step()
    assert world.state.targets_up[0].tolist() == [False, True]
    for _ in range(120):  # one down: the bank waits for the other
        world.step()
    assert world.state.targets_up[0].tolist() == [False, True]
    world.place_ball(0, (0.385, 0.3), (0.0, 2.0))
    frames = 0
    while world.state.targets_up[0, 1]:
        world.step()
        frames += 1
    world.state.active[0, 0] = False  # the ball out of the way
    down = 0
    while not world.state.targets_up[0].all():
        world.step()
        down += 1
    assert down == 30  # 0.5 s at 60 frames per second


def test_a_standup_target_counts_every_hit_and_stays():
    world = World(rig(standup_targets=[{"name": "face", "points": ACROSS,
                                        "material": "target", "score": 50}]))  # fmt: skip
    face = world.table.element_names.index("face")
    world.place_ball(0, (0.255, 0.3), (0.0, 2.0))
    total = 0
    for _ in range(240):
        world.step()
        total += world.state.hits[0, face]
        assert world.state.balls[0, 0, 1] < LINE
    assert total >= 2  # back and forth between the face and the bottom wall


def spinner_rig(damping: float = 0.5, friction: float = 20.0) -> object:
    spinner = {"name": "spinner", "points": ACROSS, "radius": 0.015, "damping": damping,
               "friction": friction, "score": 10}  # fmt: skip
    return rig(spinners=[spinner])


def spin_down(speed: float, damping: float = 0.5, friction: float = 20.0) -> int:
    """Revolutions of the rig's spinner after one ball passes through it at ``speed``."""
    world = World(spinner_rig(damping, friction))
    spinner = world.table.element_names.index("spinner")
    world.place_ball(0, (0.255, LINE - 0.05), (0.0, speed))
    revolutions = 0
    while world.state.balls[0, 0, 1] < LINE:
        world.step()
        revolutions += world.state.hits[0, spinner]
    world.state.active[0, 0] = False  # it passes only once
    for _ in range(60 * 60):
        world.step()
        revolutions += world.state.hits[0, spinner]
    assert world.state.spinners[0, 0, SPIN_OMEGA] == 0.0  # it has stopped
    return revolutions


def test_a_spinners_revolutions_grow_with_the_balls_speed():
    revolutions = [spin_down(speed) for speed in (0.25, 0.5, 1.0, 2.0, 4.0, 8.0)]
    assert revolutions == sorted(revolutions)
    assert revolutions[0] < revolutions[-1]
    assert len(set(revolutions)) == len(revolutions)


@pytest.mark.parametrize("speed", [0.5, 2.0, 8.0])
def test_a_spinner_turns_as_its_ode_says(speed):
    """omega' = -c omega - f: it turns (omega0 + f/c)(1 - e^(-cT))/c - (f/c) T in all, T its
    stopping time; a revolution counts at each odd multiple of pi."""
    c, f = 0.5, 20.0
    omega = speed / 0.015
    stop = math.log((omega + f / c) / (f / c)) / c
    angle = (omega + f / c) * (1.0 - math.exp(-c * stop)) / c - (f / c) * stop
    expected = math.floor((angle + math.pi) / (2.0 * math.pi))
    assert abs(spin_down(speed, c, f) - expected) <= 1


def test_spin_spinner_spins_at_the_normal_speed_over_the_radius_and_never_slows_it():
    spinner = np.array([0.0, 0.0, 0.1, 0.0, 0.02, 0.5, 20.0])
    spin = np.zeros(2)
    spin_spinner(spinner, spin, 0.3, 1.0, 0.0)  # only the normal component counts
    assert spin[SPIN_OMEGA] == pytest.approx(1.0 / 0.02)
    spin_spinner(spinner, spin, 0.0, -0.5, 0.0)  # slower the other way: no change
    assert spin[SPIN_OMEGA] == pytest.approx(50.0)
    spin_spinner(spinner, spin, 0.0, -2.0, 0.0)
    assert spin[SPIN_OMEGA] == pytest.approx(-100.0)


def test_turn_spinner_counts_revolutions_either_way_round():
    spinner = np.array([0.0, 0.0, 0.1, 0.0, 0.02, 0.0, 0.0])  # no losses
    for omega in (2.0 * math.pi * 60.0 * 0.25, -2.0 * math.pi * 60.0 * 0.25):  # 1/4 turn a frame
        spin = np.array([0.0, omega])
        turns = sum(turn_spinner(spinner, spin, 1.0 / 60.0) for _ in range(40))
        assert turns == 10
        assert spin[SPIN_ANGLE] == pytest.approx(0.0, abs=1e-9)


def kickback_rig(lit: bool) -> object:
    kickback = {"name": "kickback", "points": ACROSS, "kick": [0.0, 2.0], "lit": lit, "score": 10}
    return rig(kickbacks=[kickback])


def test_a_lit_kickback_fires_the_ball_back_and_goes_dark():
    world = World(kickback_rig(lit=True))
    kickback = world.table.element_names.index("kickback")
    world.place_ball(0, (0.255, LINE + 0.1), (0.0, -3.0))
    fired = False
    for _ in range(60):
        world.step()
        if world.state.hits[0, kickback]:
            fired = True
            break
    assert fired
    assert not world.state.kickback_lit[0, 0]
    ball = world.state.balls[0, 0]
    assert ball[2] == 0.0 and ball[3] == 2.0  # at the kick velocity, exactly (no gravity)
    assert ball[1] >= LINE
    # Dark, the next ball over it goes through (and counts).
    world.place_ball(0, (0.255, LINE + 0.1), (0.0, -3.0))
    crossed = 0
    for _ in range(30):
        world.step()
        crossed += world.state.hits[0, kickback]
    assert crossed == 1
    assert world.state.balls[0, 0, 1] < LINE


def test_a_kickback_ignores_a_ball_going_its_way():
    world = World(kickback_rig(lit=True))
    world.place_ball(0, (0.255, LINE - 0.1), (0.0, 3.0))
    for _ in range(10):
        world.step()
    assert world.state.kickback_lit[0, 0]
    assert world.state.hits[0].sum() == 0 or world.state.balls[0, 0, 1] > LINE
