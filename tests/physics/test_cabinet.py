"""The whole cabinet (Pinball-v1, and Pinball-v2 where it differs): the player's plunger, the
nudge and the tilt.

Analytic answers (a nudge's velocity change, the plunger's launch speed, the cabinet's and the
plumb bob's swings against their ODEs), the rules on scripted games, the bad-input errors,
properties under random and extreme play, and the env's promises (checkers, determinism, the
vector env bitwise N single envs).
"""

import dataclasses
import math
import subprocess
import sys
import warnings
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env
from hypothesis import given, settings
from hypothesis import strategies as st

import pinball_env  # noqa: F401  (registers Pinball-v1)
from pinball_env.envs import PinballEnv
from pinball_env.game import BALL_SEARCH_TIME, Game, action_meanings, discrete_action
from pinball_env.physics.cabinet import cabinet_substep
from pinball_env.physics.columns import (
    BALL_VX,
    BALL_VY,
    BOB_ON_RING,
    BOB_TOUCHES,
    BOB_VX,
    BOB_X,
    CABINET_SHOVE_X,
    CABINET_SHOVE_Y,
    CABINET_STATE_SIZE,
    CABINET_VX,
    CABINET_VY,
    CABINET_X,
)
from pinball_env.procgen import generate_table
from pinball_env.sim.world import World
from pinball_env.table import (
    TableError,
    load_table,
    table_description,
    table_from_dict,
)
from tests.sim.soundness import assert_sound

try:  # (the env's core tests run on other Pythons without the agents' extra: .ci/other-pythons)
    from stable_baselines3.common.env_checker import check_env as sb3_check_env
except ImportError:
    sb3_check_env = None

NOOP, PLUNGER = 0, 4
NUDGE_LEFT, NUDGE_RIGHT, NUDGE_UP = 8, 16, 24


@pytest.fixture(scope="module")
def table():
    return load_table("classic_v1")


def v1_dict() -> dict:
    return table_description("classic_v1")  # (its file gives only what differs from classic)


def substep(table) -> float:
    return 1.0 / (table.simulation.frame_rate * table.simulation.substeps)


# --- the physics: analytic answers -----------------------------------------------------------


def test_a_nudge_changes_a_flying_balls_velocity_by_the_cabinets_opposite(table):
    world = World(table, 1)
    world.place_ball(0, (0.25, 0.45), (0.3, 0.4))  # mid-table, clear of everything for a while
    cabinet = world.state.cabinet[0]
    cabinet[CABINET_SHOVE_X], cabinet[CABINET_SHOVE_Y] = -30.0, 12.0
    gx, gy = table.gravity_vector
    dt = 1.0 / table.simulation.frame_rate
    for frame in range(1, 9):
        world.step()
        assert world.state.contact_count[0] == 0
        t = frame * dt
        ball = world.balls[0, 0]
        # Relative to the table the ball lost exactly what the cabinet gained, beside gravity.
        assert ball[BALL_VX] - (0.3 + gx * t) == pytest.approx(-cabinet[CABINET_VX], abs=1e-12)
        assert ball[BALL_VY] - (0.4 + gy * t) == pytest.approx(-cabinet[CABINET_VY], abs=1e-12)
    # The shove itself: the cabinet's first substep took the impulse over its mass.
    assert cabinet[CABINET_SHOVE_X] == cabinet[CABINET_SHOVE_Y] == 0.0


def test_the_cabinet_swings_back_as_its_damped_spring(table):
    """An impulse J sets the cabinet moving at J / M, and it swings back as the damped
    oscillator x(t) = (v0 / wd) exp(-zeta w0 t) sin(wd t) (semi-implicit Euler: O(h))."""
    cab = table.cabinet
    constants = table.pack().cabinet[0]
    state = np.zeros(CABINET_STATE_SIZE)
    state[CABINET_SHOVE_X] = cab.nudge_impulse
    h = substep(table)
    v0 = cab.nudge_impulse / cab.mass
    w0, zeta = cab.natural_frequency, cab.damping_ratio
    wd = w0 * math.sqrt(1 - zeta**2)
    worst = 0.0
    for k in range(1, 601):
        cabinet_substep(state, constants, h)
        t = k * h
        exact = v0 / wd * math.exp(-zeta * w0 * t) * math.sin(wd * t)
        worst = max(worst, abs(state[CABINET_X] - exact))
    peak = v0 / wd
    assert worst < 0.03 * peak  # first order in h: w0 h = 0.06
    assert abs(state[CABINET_X]) < 1e-6  # at rest again after 1 s


def test_the_plumb_bob_swings_as_its_ode(table):
    """A bob set swinging (the cabinet at rest) follows theta'' = -(g/L) theta - d theta';
    driven by the cabinet's shove, it follows the coupled ODE (checked against RK4 with a
    100x finer step)."""
    constants = table.pack().cabinet[0]
    tilt, cab, g = table.tilt, table.cabinet, table.gravity
    h = substep(table)
    # Free: theta(t) = w / wd exp(-d t / 2) sin(wd t) for an initial angular velocity w.
    state = np.zeros(CABINET_STATE_SIZE)
    state[BOB_VX] = 0.5  # [rad/s]: 0.05 rad at most, inside the ring
    w2, d = g / tilt.bob_length, tilt.bob_damping
    wd = math.sqrt(w2 - d * d / 4)
    worst = 0.0
    for k in range(1, 601):
        cabinet_substep(state, constants, h)
        t = k * h
        worst = max(worst, abs(state[BOB_X] - 0.5 / wd * math.exp(-d * t / 2) * math.sin(wd * t)))
    assert worst < 0.01 * 0.5 / wd
    # Driven by the cabinet: y = (x, v, theta, omega), one axis.
    k_, c_, m_ = cab.stiffness, cab.damping, cab.mass

    def rates(y):
        x, v, theta, omega = y
        a = (-k_ * x - c_ * v) / m_
        return np.array([v, a, omega, -w2 * theta - d * omega - a / tilt.bob_length])

    # Just after the impulse: the cabinet at J / M, the bob (inertial) swinging back.
    v0 = cab.nudge_impulse / m_
    y = np.array([0.0, v0, 0.0, -v0 / tilt.bob_length])
    state = np.zeros(CABINET_STATE_SIZE)
    state[CABINET_SHOVE_X] = cab.nudge_impulse
    fine = h / 100
    worst, peak = 0.0, 0.0
    for _ in range(600):
        cabinet_substep(state, constants, h)
        for _ in range(100):
            k1 = rates(y)
            k2 = rates(y + fine / 2 * k1)
            k3 = rates(y + fine / 2 * k2)
            k4 = rates(y + fine * k3)
            y = y + fine / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        worst = max(worst, abs(state[BOB_X] - y[2]))
        peak = max(peak, abs(y[2]))
    assert peak > math.radians(1)  # the shove swings the bob ...
    assert peak < math.radians(tilt.ring_angle)  # ... but one does not reach the ring
    assert worst < 0.05 * peak


def test_the_ring_stops_the_bob_and_counts_one_touch_per_swing_out(table):
    constants = table.pack().cabinet[0]
    ring = math.radians(table.tilt.ring_angle)
    state = np.zeros(CABINET_STATE_SIZE)
    state[BOB_VX] = 3.0  # [rad/s]: well past the ring
    h = substep(table)
    touches = []
    for _ in range(1200):
        cabinet_substep(state, constants, h)
        assert math.hypot(state[BOB_X], state[7]) <= ring * (1 + 1e-12)
        touches.append(state[BOB_TOUCHES])
    counts = np.diff(np.concatenate([[0.0], touches]))
    assert set(np.unique(counts)) <= {0.0, 1.0}
    assert touches[-1] >= 2  # out one side, bounced, out the other
    # Each touch began a contact: between two touches the bob swung clear of the ring.
    assert state[BOB_ON_RING] in (0.0, 1.0)


def test_a_tilted_machines_kickers_are_dead(table):
    bumper = next(p for p in table.posts if p.name == "bumper_left")
    speeds = []
    for tilted in (False, True):
        world = World(table, 1)
        x, y = bumper.center
        world.place_ball(0, (x, y + bumper.radius + table.ball.radius + 0.01), (0.0, -1.0))
        world.state.tilted[0] = tilted
        for _ in range(3):
            world.step()
        speeds.append(math.hypot(*world.balls[0, 0, [BALL_VX, BALL_VY]]))
    assert speeds[0] > 1.5 > speeds[1]  # the kick of 1.5 m/s only while not tilted


# --- the plunger ----------------------------------------------------------------------------


def test_the_plunger_fires_at_the_speed_of_its_pull(table):
    """At the pull's speed, give or take the scatter; exactly the pull's without a scatter."""
    plunger = table.plunger
    step = plunger.stroke / (plunger.pull_time * table.simulation.frame_rate)
    gy = table.gravity_vector[1]
    exact = dataclasses.replace(table, plunger=dataclasses.replace(plunger, scatter=0.0))
    for source, tolerance in ((table, plunger.scatter), (exact, 1e-12)):
        env = PinballEnv(table=source)
        speeds = []
        for frames in (1, 20, 45, 60, 90):
            obs, info = env.reset(seed=frames)
            assert info["ball_on_plunger"] and obs[8] == 1.0  # a ball waiting is in play
            for _ in range(frames):
                obs, _, _, _, info = env.step(PLUNGER)
            pull = min(frames * step, plunger.stroke)
            assert info["plunger_pull"] == pytest.approx(pull) and obs[10] == pytest.approx(pull)
            assert info["ball_on_plunger"]
            obs, _, _, _, info = env.step(NOOP)  # let go: fired, then one frame of flight
            assert not info["ball_on_plunger"] and info["plunger_pull"] == 0.0
            speed = info["ball_velocity"][1] - gy / 60
            assert abs(speed - plunger.launch_speed(pull)) <= tolerance + 1e-12
            speeds.append(speed - plunger.launch_speed(pull))
        assert (np.ptp(speeds) > 1e-9) == (tolerance > 1e-12)  # the scatter is drawn


def test_a_weak_plunge_falls_back_onto_the_plunger():
    env = gym.make("Pinball-v1").unwrapped
    env.reset(seed=0)
    env.step(PLUNGER)
    for _ in range(120):
        _, _, _, _, info = env.step(NOOP)
    assert info["ball_on_plunger"] and info["balls_left"] == 3


def test_the_ball_search_fires_a_ball_left_waiting():
    env = gym.make("Pinball-v1").unwrapped
    env.reset(seed=0)
    wait = round(BALL_SEARCH_TIME * 60)
    for _ in range(wait - 1):
        _, _, _, _, info = env.step(NOOP)
    assert info["ball_on_plunger"]
    for _ in range(5):
        _, _, _, _, info = env.step(NOOP)
    assert not info["ball_on_plunger"] and info["ball_velocity"][1] > 1.0
    assert info["balls_left"] == 3


def test_a_well_judged_pull_makes_the_skill_shot(table):
    env = gym.make("Pinball-v1").unwrapped
    made = {}
    for frames in (50, 56, 60):
        made[frames] = 0
        for seed in range(8):
            env.reset(seed=seed)
            for _ in range(frames):
                env.step(PLUNGER)
            hit, score = False, 0
            for _ in range(90):
                _, _, _, _, info = env.step(NOOP)
                hit |= info["skill_shot"]
                score = info["score"]
            made[frames] += hit
            if hit:
                assert score >= table.plunger.skill_shot.bonus
    assert made[50] == 0 and made[56] >= 7 and made[60] <= 2


# --- the nudge and the tilt ---------------------------------------------------------------------


def shoves(env, actions) -> int:
    """The steps (of one frame) in which the cabinet was shoved."""
    frames = round(env.table.cabinet.nudge_interval * 60)
    count = 0
    for action in actions:
        env.step(action)
        count += env.game.state.nudge_wait[0] == frames  # set by this frame's shove
    return count


def test_a_held_nudge_shoves_once_per_interval(table):
    env = gym.make("Pinball-v1").unwrapped
    env.reset(seed=0)
    frames = round(table.cabinet.nudge_interval * 60)
    assert shoves(env, [NUDGE_LEFT] * (4 * frames)) == 4
    assert shoves(env, [NUDGE_RIGHT, NOOP] * (2 * frames)) == 4


def test_a_nudges_direction(table):
    for action, (sx, sy) in ((NUDGE_LEFT, (-1, 0)), (NUDGE_RIGHT, (1, 0)), (NUDGE_UP, (0, 1))):
        env = gym.make("Pinball-v1").unwrapped
        env.reset(seed=0)
        env.step(action)
        cabinet = env.game.world.state.cabinet[0]
        assert np.sign(cabinet[CABINET_VX]) == sx and np.sign(cabinet[CABINET_VY]) == sy
    # MultiBinary: left and right cancel, left and up shove diagonally with the same impulse.
    env = gym.make("Pinball-v1", action_type="multibinary").unwrapped
    env.reset(seed=0)
    env.step(np.array([0, 0, 0, 1, 1, 0]))
    assert env.game.world.state.cabinet[0, CABINET_VX] == 0.0
    env.step(np.array([0, 0, 0, 1, 0, 1]))
    velocity = env.game.world.state.cabinet[0, [CABINET_VX, CABINET_VY]]
    assert velocity[0] < 0 < velocity[1]


def rhythm(steps: int) -> list[int]:
    """Left and right nudges in turn every 15 frames: the bob's swing builds up."""
    return [NUDGE_LEFT if (k // 15) % 2 == 0 else NUDGE_RIGHT for k in range(steps)]


def test_rhythmic_nudging_warns_then_tilts_and_the_ball_is_lost(table):
    env = gym.make("Pinball-v1").unwrapped
    env.reset(seed=0)
    for _ in range(57):  # a plunge: the ball is in play on the table
        env.step(PLUNGER)
    env.step(NOOP)
    seen_warnings, tilt_step = [], None
    for k, action in enumerate(rhythm(600) + [3] * 1500):
        _, reward, _, _, info = env.step(action if tilt_step is None else 3)  # flippers held
        seen_warnings.append(info["tilt_warnings"])
        if info["tilted"] and tilt_step is None:
            tilt_step = k
            assert info["tilt_warnings"] == table.tilt.warnings + 1
        elif info["tilted"] and info["balls_left"] == 3:
            # Tilted: no points, flippers dead (held, they are released), kickers dead.
            assert reward == 0.0 and info["points"] == 0
            assert not env.game.world.state.flipper_command[0].any()
        if info["balls_left"] == 2:
            break
    assert 1 in seen_warnings and table.tilt.warnings in seen_warnings
    assert tilt_step is not None
    assert info["balls_left"] == 2 and info["ball_on_plunger"]  # the next ball waits
    assert not info["tilted"] and info["tilt_warnings"] == 0


def test_a_tilt_while_the_ball_waits_loses_it_at_once():
    env = gym.make("Pinball-v1").unwrapped
    env.reset(seed=0)
    for action in rhythm(300):
        _, _, _, _, info = env.step(action)
        if info["tilted"]:
            break
    assert info["tilted"] and info["balls_left"] == 2 and info["drained"]
    assert info["ball_on_plunger"]  # the next ball, served


def test_warnings_are_forgotten(table):
    env = gym.make("Pinball-v1").unwrapped
    env.reset(seed=0)
    for action in rhythm(300):
        _, _, _, _, info = env.step(action)
        if info["tilt_warnings"] == 1:
            break
    assert info["tilt_warnings"] == 1
    standing = []
    for _ in range(round(2 * table.tilt.warning_time * 60) + 120):
        _, _, _, _, info = env.step(NOOP)
        standing.append(info["tilt_warnings"])
    assert max(standing) <= table.tilt.warnings  # the swing died away without a tilt
    assert info["tilt_warnings"] == 0 and not info["tilted"]


def test_single_nudges_never_warn():
    env = gym.make("Pinball-v1").unwrapped
    env.reset(seed=0)
    for _ in range(10):
        for action in [NUDGE_LEFT] + [NOOP] * 59:
            _, _, _, _, info = env.step(action)
            assert info["tilt_warnings"] == 0


# --- actions, spaces and the env's promises ---------------------------------------------------


def test_the_action_set_as_ale_names_it():
    meanings = gym.make("Pinball-v1").unwrapped.get_action_meanings()
    assert len(meanings) == 32 and len(set(meanings)) == 32
    assert meanings[:8] == [
        "NOOP", "LEFT_FLIPPER", "RIGHT_FLIPPER", "BOTH_FLIPPERS", "PLUNGER",
        "LEFT_FLIPPER_PLUNGER", "RIGHT_FLIPPER_PLUNGER", "BOTH_FLIPPERS_PLUNGER",
    ]  # fmt: skip
    assert meanings[NUDGE_LEFT] == "NUDGE_LEFT" and meanings[NUDGE_UP] == "NUDGE_UP"
    assert meanings[31] == "BOTH_FLIPPERS_PLUNGER_NUDGE_UP"
    assert gym.make("Pinball-v0").unwrapped.get_action_meanings() == action_meanings(False)
    assert action_meanings(False) == ["NOOP", "LEFT_FLIPPER", "RIGHT_FLIPPER", "BOTH_FLIPPERS"]
    game = gym.make("Pinball-v1").unwrapped.game
    for action, buttons in enumerate(game.discrete_buttons):
        assert discrete_action(buttons) == action
        assert buttons[2] == ("PLUNGER" in meanings[action])
        assert buttons[3:].sum() == ("NUDGE" in meanings[action])


def test_the_action_set_without_nudges_is_the_first_eight():
    env = gym.make("Pinball-v2", nudge_actions=False)
    full = gym.make("Pinball-v2").unwrapped
    assert env.action_space == gym.spaces.Discrete(8)
    assert env.unwrapped.get_action_meanings() == full.get_action_meanings()[:8]
    buttons = env.unwrapped.game.discrete_buttons
    np.testing.assert_array_equal(buttons, full.game.discrete_buttons[:8])
    # An action of the smaller set plays as the same action of the full set.
    np.testing.assert_array_equal(env.reset(seed=3)[0], full.reset(seed=3)[0])
    for action in [4] * 60 + [0] * 200 + [3, 1, 2, 7, 5] * 40:
        step, full_step = env.step(action), full.step(action)
        np.testing.assert_array_equal(step[0], full_step[0])
        assert step[1:4] == full_step[1:4]
    with pytest.raises(ValueError, match=r"invalid action 8: expected an element of Discrete\(8\)"):
        env.step(8)
    assert sorted(set(env.unwrapped.get_keys_to_action().values())) == list(range(8))


@pytest.mark.parametrize(
    ("options", "message"),
    [
        ({"id": "Pinball-v0", "nudge_actions": False}, "tables with the cabinet"),
        ({"id": "Pinball-v2", "nudge_actions": False, "action_type": "multibinary"}, "discrete"),
        ({"id": "Pinball-v2", "nudge_actions": "no"}, "nudge_actions"),
    ],
)
def test_nudge_actions_off_where_there_is_nothing_to_leave_out_is_refused(options, message):
    with pytest.raises(ValueError, match=message):
        gym.make(**options)


def test_spaces_of_pinball_v1():
    env = gym.make("Pinball-v1")
    assert env.action_space == gym.spaces.Discrete(32)
    assert env.observation_space.shape == (29,)  # 18 with the cabinet, 11 more for the rules
    multi = gym.make("Pinball-v1", action_type="multibinary")
    assert multi.action_space == gym.spaces.MultiBinary(6)


@pytest.mark.parametrize("action", [32, -1, 4.5, "PLUNGER", None, np.array([1, 0, 1])])
def test_actions_outside_the_space_are_refused(action):
    env = gym.make("Pinball-v1")
    env.reset(seed=0)
    with pytest.raises(ValueError, match="invalid action"):
        env.step(action)


@pytest.mark.parametrize("env_id", ["Pinball-v1", "Pinball-v2"])
@pytest.mark.parametrize("obs_type", ["state", "grayscale"])
@pytest.mark.parametrize("action_type", ["discrete", "multibinary"])
def test_checkers_pass_without_warnings(env_id, obs_type, action_type):
    kwargs = {"obs_type": obs_type, "action_type": action_type}
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        # Gymnasium's registry notice that a newer version exists, not a warning about the env.
        warnings.filterwarnings("ignore", ".*Pinball-v[12] is out of date", DeprecationWarning)
        check_env(gym.make(env_id, render_mode="rgb_array", **kwargs).unwrapped)
        if sb3_check_env is not None:
            sb3_check_env(gym.make(env_id, **kwargs))


def rollout(env, seed: int, steps: int, action_seed: int) -> list:
    rng = np.random.default_rng(action_seed)
    obs, info = env.reset(seed=seed)
    out = [obs.tobytes()]
    for _ in range(steps):
        obs, reward, terminated, truncated, info = env.step(int(rng.integers(32)))
        out.append((obs.tobytes(), reward, terminated, info["score"], info["tilt_warnings"]))
        if terminated or truncated:
            obs, info = env.reset()
    return out


@pytest.mark.parametrize("env_id", ["Pinball-v1", "Pinball-v2"])
def test_same_seed_same_game(env_id):
    a = rollout(gym.make(env_id), 3, 1500, 1)
    b = rollout(gym.make(env_id), 3, 1500, 1)
    assert a == b


V1_INFO_KEYS = ("score", "balls_left", "points", "drained", "frames", "tilt_warnings", "tilted",
                "ball_on_plunger", "plunger_pull", "cabinet_offset", "skill_shot")  # fmt: skip


@pytest.mark.parametrize(
    ("env_id", "action_type"),
    [("Pinball-v1", "discrete"), ("Pinball-v1", "multibinary"), ("Pinball-v2", "discrete")],
)
def test_the_vector_env_is_bitwise_n_single_envs(env_id, action_type):
    n, seed = 3, 7
    kwargs = {"action_type": action_type, "balls": 1, "max_episode_steps": 500}
    vector = gym.make_vec(env_id, num_envs=n, **kwargs)
    singles = [gym.make(env_id, **kwargs) for _ in range(n)]
    obs, _ = vector.reset(seed=seed)
    for env, single in enumerate(singles):
        assert obs[env].tobytes() == single.reset(seed=seed + env)[0].tobytes()
    vector.action_space.seed(1)
    ended = np.zeros(n, dtype=bool)
    for _ in range(900):
        actions = vector.action_space.sample()
        obs, reward, terminated, truncated, infos = vector.step(actions)
        for env, single in enumerate(singles):
            if ended[env]:
                obs1, info1 = single.reset()
                reward1 = 0.0
            else:
                obs1, reward1, _, _, info1 = single.step(actions[env])
            assert obs[env].tobytes() == obs1.tobytes() and reward[env] == reward1
            for key in V1_INFO_KEYS:
                assert np.array_equal(infos[key][env], info1[key]), key
        ended = terminated | truncated


# --- properties: nothing leaves the table, whatever the player does ----------------------------


def with_cabinet(table, cabinet: str = "classic_v1"):
    """A generated table in ``cabinet``'s cabinet (its plunger made the player's)."""
    v1 = load_table(cabinet)
    plunger = dataclasses.replace(
        v1.plunger, position=table.plunger.position, speed=table.plunger.speed, skill_shot=None
    )
    return dataclasses.replace(table, plunger=plunger, cabinet=v1.cabinet, tilt=v1.tilt)


@settings(max_examples=8, deadline=None)
@given(
    table_seed=st.sampled_from([None, 3, 11]),
    cabinet=st.sampled_from(["classic_v1", "classic_v2"]),
    action_seed=st.integers(0, 2**31),
    extreme=st.booleans(),
)
def test_no_ball_leaves_the_table_under_random_and_extreme_play(
    table_seed, cabinet, action_seed, extreme
):
    """On v1's cabinet and v2's (generated tables in either)."""
    table = load_table(cabinet) if table_seed is None else with_cabinet(
        generate_table(table_seed), cabinet
    )  # fmt: skip
    game = Game(table, n_envs=4)
    rngs = [np.random.default_rng(action_seed + env) for env in range(4)]
    for env in range(4):
        game.new_game(env, rngs[env])
    rng = np.random.default_rng(action_seed)
    for _ in range(1500):
        if extreme:  # every nudge the cabinet allows, in rhythm, flippers flapping, plunging
            k = game.state.frames[0]
            nudge = NUDGE_LEFT if (k // 15) % 2 == 0 else NUDGE_RIGHT
            actions = np.full(4, nudge | PLUNGER * (k % 40 < 30) | int(k % 6 < 3) * 3)
        else:
            actions = rng.integers(0, 32, size=4)
        game.step(actions, rngs)
        assert_sound(game.world)
        assert np.isfinite(game.world.state.cabinet).all()
        for env in np.flatnonzero(game.balls_left == 0):
            game.new_game(env, rngs[env])


# --- bad tables ------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("edit", "message"),
    [
        (lambda d: d["cabinet"].update(mass=1.0), r"cabinet.mass: 1.0 is out of range"),
        (lambda d: d["cabinet"].update(stiffness=-5.0), "cabinet.stiffness"),
        (lambda d: d["cabinet"].update(nudge_impulse=500.0), "above 1 m/s"),
        (lambda d: d["cabinet"].update(stiffness=1e7, mass=100.0), "too fast for the substeps"),
        (lambda d: d["cabinet"].update(nudge_interval=0.0), "cabinet.nudge_interval"),
        (lambda d: d["cabinet"].pop("damping"), "missing required key 'damping'"),
        (lambda d: d["cabinet"].update(spring=1.0), "unknown key 'spring'"),
        (lambda d: d["tilt"].update(ring_angle=45.0), "tilt.ring_angle"),
        (lambda d: d["tilt"].update(warnings=2.5), "tilt.warnings: expected an integer"),
        (lambda d: d["tilt"].update(settle_time=-1.0), "tilt.settle_time"),
        (lambda d: d["tilt"].update(settle_time=10.0), "not shorter than warning_time"),
        (lambda d: d["tilt"].update(bob_length=float("nan")), "expected a finite number"),
        (lambda d: d["plunger"].update(stroke=1.0), "plunger.stroke"),
        (lambda d: d["plunger"].update(pull_speed=[3.0, 1.0]), "min <= max"),
        (lambda d: d["plunger"].pop("pull_time"), "missing pull_time"),
        (lambda d: d["plunger"].update(scatter=0.6), "could stop the shortest pull"),
        (lambda d: d["plunger"]["skill_shot"].update(sensor="drain"), "no rollover sensor 'drain'"),
        (lambda d: d.pop("tilt"), "the cabinet is a whole"),
        (lambda d: d.pop("cabinet"), "the cabinet is a whole"),
    ],
)
def test_bad_cabinet_tables_are_refused_naming_the_field(edit, message):
    data = v1_dict()
    edit(data)
    with pytest.raises(TableError, match=message) as error:
        table_from_dict(data, "classic_v1.yaml")
    assert "classic_v1.yaml" in str(error.value)


def test_the_v1_and_v2_tables_round_trip_and_v0_has_no_cabinet():
    from pinball_env.table import table_to_dict

    table = load_table("classic_v1")
    assert table_from_dict(table_to_dict(table), table.source) == table
    assert "settle_time" not in table_to_dict(table)["tilt"]  # v1 writes as it always did
    v2 = load_table("classic_v2")
    assert table_from_dict(table_to_dict(v2), v2.source) == v2
    assert v2.tilt.settle_time == 1.0 and v2.tilt.ring_angle == 1.0
    # Pinball-v2's table is Pinball-v1's but for the tilt.
    assert dataclasses.replace(v2, name=table.name, source=table.source, tilt=table.tilt) == table
    classic = load_table("classic")
    assert not classic.has_cabinet and classic.pack().cabinet.shape == (0, 8)
    assert "stroke" not in table_to_dict(classic)["plunger"]


def test_a_game_keeps_one_cabinet():
    game = Game(load_table("classic_v1"), n_envs=2)
    with pytest.raises(ValueError, match="another cabinet"):
        game.set_table(1, load_table("classic"))


@settings(max_examples=10, deadline=None)
@given(
    seed=st.integers(0, 2**31),
    nudge_share=st.floats(0.0, 1.0),
    env_id=st.sampled_from(["Pinball-v1", "Pinball-v2"]),
)
def test_tilt_rules_hold_under_any_nudging(seed, nudge_share, env_id):
    """Whatever the actions: the warnings stand between 0 and the allowed while the machine
    stands; one only comes with a touch of the ring and goes only after warning_time without
    another (a touch within settle_time of a warning being that warning); the frame that tilts
    the machine counts its touches (v1 and v2 count each, see the test below) and a tilted
    machine is deaf; it scores nothing and holds no flipper up; a tilt loses the ball (and only
    that one)."""
    env = gym.make(env_id).unwrapped
    tilt = env.table.tilt
    rng = np.random.default_rng(seed)
    env.reset(seed=seed)
    warnings_before, quiet, balls_before = 0, 0, 3
    for _ in range(900):
        action = int(rng.integers(32))
        if rng.random() < nudge_share:
            action = (action & 7) | int(rng.integers(1, 4)) << 3
        tilted_before = bool(env.game.world.state.tilted[0])
        _, reward, terminated, _, info = env.step(action)
        touches = env.game.world.state.cabinet[0, BOB_TOUCHES]
        if not env.game.world.state.tilted[0]:  # standing (or a new ball's clean slate)
            assert 0 <= info["tilt_warnings"] <= tilt.warnings
        elif tilted_before:
            assert info["tilt_warnings"] <= warnings_before  # deaf
        else:  # the frame that tilted it
            assert tilt.warnings < info["tilt_warnings"] <= warnings_before + touches
        if info["tilt_warnings"] > warnings_before:
            assert touches > 0
        warned = info["tilt_warnings"] > warnings_before if tilt.settle_time else touches > 0
        quiet = 0 if warned else quiet + 1
        forgotten = info["tilt_warnings"] < warnings_before and not info["tilted"]
        if forgotten and info["balls_left"] == balls_before:  # not a new ball's clean slate
            assert quiet >= round(tilt.warning_time * 60)
            quiet = 0
        if tilted_before:
            assert info["points"] == 0 and reward == 0.0
            assert not env.game.world.state.flipper_command[0].any()
        assert info["balls_left"] >= balls_before - 1
        warnings_before, balls_before = info["tilt_warnings"], info["balls_left"]
        if terminated:
            break


def test_v1_and_v2_count_every_touch_of_the_frame_that_tilts():
    # Two touches of the ring in the frame that tilts Pinball-v2 make its warnings two more,
    # one past the allowed + 1 (found by the property test above): the games keep it bitwise,
    # and a tilted machine is deaf from the next frame on, so only the count shows it.
    env = gym.make("Pinball-v2").unwrapped
    rng = np.random.default_rng(1)
    env.reset(seed=1)
    for step in range(395):
        action = int(rng.integers(32))
        if rng.random() < 0.5:
            action = (action & 7) | int(rng.integers(1, 4)) << 3
        _, _, _, _, info = env.step(action)
        if step == 393:
            assert (info["tilt_warnings"], info["tilted"]) == (2, False)
    assert env.game.world.state.cabinet[0, BOB_TOUCHES] == 2
    assert (info["tilt_warnings"], info["tilted"]) == (env.table.tilt.warnings + 2, True)


def test_a_snapshot_restores_the_whole_cabinet():
    env = gym.make("Pinball-v1").unwrapped
    env.reset(seed=4)
    for action in rhythm(40) + [PLUNGER] * 30:
        env.step(action)
    snapshot = env.game.snapshot()
    rng_state = env.np_random.bit_generator.state

    def play():
        out = []
        for action in [0, *rhythm(200)]:
            obs, reward, _, _, info = env.step(action)
            out.append((obs.tobytes(), reward, info["tilt_warnings"], info["tilted"]))
        return out

    first = play()
    env.game.restore(snapshot)
    env.np_random.bit_generator.state = rng_state
    assert play() == first


def test_soft_plunges_cannot_keep_a_ball_in_the_shooter_lane(table):
    """A ball plunged too softly falls back; the time it spends in the lane adds up, and the
    machine fires it after the ball search's wait, as it would a ball left waiting."""
    env = gym.make("Pinball-v1").unwrapped
    env.reset(seed=0)
    x_plunger = table.plunger.position[0]
    for step in range(round(BALL_SEARCH_TIME * 60) + 60):
        _, _, _, _, info = env.step(PLUNGER if step % 50 < 3 else NOOP)
        if abs(info["ball_position"][0] - x_plunger) > table.ball.radius:
            break
    assert info["ball_position"][1] > 0.8  # out over the gate, into the playfield
    assert step >= round(BALL_SEARCH_TIME * 60) - 1  # ... by the machine, after the wait


V1_ROLLOUT = """
import hashlib
import gymnasium as gym
import numpy as np
import pinball_env

env = gym.make("Pinball-v1")
result = hashlib.sha256()
env.reset(seed=7)
rng = np.random.default_rng(1)
for step in range(900):
    action = 4 if step < 56 else int(rng.integers(32))  # a plunge, then anything
    obs, reward, terminated, truncated, info = env.step(action)
    result.update(obs.tobytes() + np.float64(reward).tobytes())
    if terminated or truncated:
        env.reset()
print(result.hexdigest())
"""


def test_pinball_v1_games_are_bitwise_identical_across_processes():
    def run() -> str:
        result = subprocess.run(
            [sys.executable, "-c", V1_ROLLOUT], capture_output=True, text=True, check=True,
            timeout=300, cwd=Path(__file__).resolve().parents[2],
        )  # fmt: skip
        return result.stdout.strip()

    first = run()
    assert first == run() and len(first) == 64
