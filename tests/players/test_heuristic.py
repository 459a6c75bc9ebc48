"""The scripted heuristic: it flips at a ball landing on a flipper, on any table, and plays
clearly better than random; with the cabinet (Pinball-v1) it makes the skill shot and nudges
balls out of the outlanes without ever tilting, and it plays Pinball-v0 as it always has."""

import dataclasses
import hashlib
import math

import gymnasium as gym
import numpy as np
import pytest

import pinball_env  # noqa: F401  (registers Pinball-v0 and Pinball-v1)
from pinball_env.physics.columns import BOB_X, BOB_Y, CABINET_SHOVE_X
from pinball_env.players import HeuristicPolicy, plunger_pulls, skill_shot_frames
from pinball_env.sim.world import World
from pinball_env.table import BUTTONS, Flipper, Table, load_table

CLASSIC = load_table("classic")
V1 = load_table("classic_v1")
NOOP, PLUNGER = 0, 4
# x -> MIRROR - x maps classic_v1's left outlane onto its right one.
MIRROR = sum(post.center[0] for post in V1.posts if post.name.endswith("_guide_post"))


def above_face(flipper: Flipper, along: float, height: float) -> np.ndarray:
    """A point ``along`` [m] from the pivot on the resting flipper's centre line, ``height`` [m]
    above it on the side it swings to."""
    angle = math.radians(flipper.rest_angle)
    side = 1.0 if flipper.up_angle > flipper.rest_angle else -1.0
    x = flipper.pivot[0] + along * math.cos(angle) - side * height * math.sin(angle)
    y = flipper.pivot[1] + along * math.sin(angle) + side * height * math.cos(angle)
    return np.array([x, y])


def falling_onto(flipper: Flipper, table: Table) -> np.ndarray:
    """A ball just above the middle of the resting flipper."""
    return above_face(flipper, 0.5 * flipper.length, table.ball.radius + flipper.base_radius + 0.01)


def mirrored(table: Table) -> Table:
    """``table`` with its flippers mirrored left to right (x -> width - x), buttons swapped."""
    swap = {"left": "right", "right": "left"}
    flippers = tuple(
        dataclasses.replace(
            f,
            pivot=(table.width - f.pivot[0], f.pivot[1]),
            rest_angle=180.0 - f.rest_angle,
            up_angle=180.0 - f.up_angle,
            button=swap[f.button],
        )
        for f in table.flippers
    )
    return dataclasses.replace(table, flippers=flippers)


def test_flips_a_ball_falling_onto_each_flipper_and_not_a_far_one():
    for flipper in CLASSIC.flippers:
        policy = HeuristicPolicy(CLASSIC, action_type="multibinary")
        pressed = policy.buttons(falling_onto(flipper, CLASSIC), np.array([0.0, -1.0]))
        assert pressed.tolist() == [b == flipper.button for b in BUTTONS]
    policy = HeuristicPolicy(CLASSIC)
    assert not policy.buttons(np.array([0.24, 0.7]), np.array([0.0, -1.0])).any()
    # Over a flipper but rising away from it, or falling but still far above it.
    left = CLASSIC.flippers[0]
    assert not policy.buttons(falling_onto(left, CLASSIC), np.array([0.0, 1.0])).any()
    high = above_face(left, 0.5 * left.length, 0.2)
    assert not policy.buttons(high, np.array([0.0, -0.5])).any()


def test_a_fast_ball_is_flipped_just_before_it_arrives():
    left = CLASSIC.flippers[0]
    policy = HeuristicPolicy(CLASSIC)
    normal = math.radians(left.rest_angle + 90.0)
    velocity = -4.0 * np.array([math.cos(normal), math.sin(normal)])  # 4 m/s onto the face
    touching = CLASSIC.ball.radius + left.base_radius + 0.5 * (left.tip_radius - left.base_radius)
    # 6 cm away is 15 ms (under the stroke time): flip now; 12 cm away is 30 ms: wait.
    far, near = (above_face(left, 0.5 * left.length, touching + d) for d in (0.12, 0.06))
    assert not policy.buttons(far, velocity).any()
    assert policy.buttons(near, velocity)[left.button_index]


def test_flip_is_released_and_reset_clears_it():
    left = CLASSIC.flippers[0]
    policy = HeuristicPolicy(CLASSIC, hold_frames=2, catch=False)
    far, down = np.array([0.24, 0.7]), np.array([0.0, -1.0])
    assert policy.buttons(falling_onto(left, CLASSIC), down)[left.button_index]
    assert policy.buttons(far, down)[left.button_index]  # held through the stroke
    assert not policy.buttons(far, down).any()  # then released
    policy.buttons(falling_onto(left, CLASSIC), down)
    policy.reset()
    assert not policy.buttons(far, down).any()


def test_discrete_and_multibinary_actions_agree():
    rng = np.random.default_rng(1)
    discrete = HeuristicPolicy(CLASSIC)
    multibinary = HeuristicPolicy(CLASSIC, action_type="multibinary")
    flippers = CLASSIC.flippers
    for _ in range(300):
        flipper = flippers[rng.integers(len(flippers))]
        position = above_face(flipper, rng.uniform(-0.01, 0.09), rng.uniform(0.0, 0.06))
        info = {"ball_position": position, "ball_velocity": rng.normal(0.0, 1.0, 2)}
        action, bits = discrete(info), multibinary(info)
        assert isinstance(action, int)
        assert bits.dtype == np.int8 and bits.shape == (len(BUTTONS),)
        assert action == sum(int(b) << i for i, b in enumerate(bits))


def test_mirrored_table_mirrors_the_buttons():
    mirror = mirrored(CLASSIC)
    rng = np.random.default_rng(2)
    for _ in range(200):
        flipper = CLASSIC.flippers[rng.integers(len(CLASSIC.flippers))]
        position = above_face(flipper, rng.uniform(0.0, 0.08), rng.uniform(0.02, 0.06))
        velocity = np.array([rng.normal(0.0, 0.5), rng.uniform(-2.0, 0.5)])
        pressed = HeuristicPolicy(CLASSIC).buttons(position, velocity)
        flipped = np.array([CLASSIC.width - position[0], position[1]])
        mirrored_pressed = HeuristicPolicy(mirror).buttons(flipped, velocity * [-1.0, 1.0])
        assert mirrored_pressed.tolist() == pressed[::-1].tolist()


def test_other_gravity_and_swapped_buttons():
    steep = dataclasses.replace(CLASSIC, slope_deg=12.0)
    left = CLASSIC.flippers[0]
    pressed = HeuristicPolicy(steep).buttons(falling_onto(left, steep), np.array([0.0, -1.0]))
    assert pressed[left.button_index] and not pressed[1 - left.button_index]
    # The same flippers, each on the other button.
    swapped = dataclasses.replace(
        CLASSIC,
        flippers=tuple(
            dataclasses.replace(f, button=BUTTONS[1 - f.button_index]) for f in CLASSIC.flippers
        ),
    )
    pressed = HeuristicPolicy(swapped).buttons(falling_onto(left, CLASSIC), np.array([0.0, -1.0]))
    assert pressed[1 - left.button_index] and not pressed[left.button_index]


def play(policy: str, seeds: list[int]) -> np.ndarray:
    """Final scores of one game per seed (a time limit of 3600 frames), played side by side."""
    n = len(seeds)
    envs = gym.make_vec(
        "Pinball-v0", num_envs=n, vectorization_mode="vector_entry_point", max_episode_steps=3600
    )
    _, info = envs.reset(seed=seeds)
    table = envs.unwrapped.game.table
    policies = [HeuristicPolicy(table) for _ in range(n)]
    rng = np.random.default_rng(0)
    done, score = np.zeros(n, dtype=bool), np.zeros(n)
    while not done.all():
        if policy == "random":
            actions = rng.integers(0, 4, n)
        else:
            actions = np.array(
                [
                    policies[e]({key: info[key][e] for key in ("ball_position", "ball_velocity")})
                    for e in range(n)
                ]
            )
        _, _, terminated, truncated, info = envs.step(actions)
        score[~done] = info["score"][~done]
        done |= terminated | truncated
    envs.close()
    return score


def test_heuristic_beats_random_clearly():
    seeds = list(range(500, 532))
    heuristic, random = play("heuristic", seeds).mean(), play("random", seeds).mean()
    assert heuristic > 1.3 * random, (heuristic, random)


def test_plays_pinball_v0_as_before_the_cabinet():
    """Its answers to 3000 ball states about the flippers, one after another (it holds flips),
    pinned as the heuristic gave them before the cabinet came (commit 601e8ae)."""
    rng = np.random.default_rng(23)
    policy = HeuristicPolicy(CLASSIC)
    actions = []
    for _ in range(3000):
        flipper = CLASSIC.flippers[rng.integers(len(CLASSIC.flippers))]
        position = above_face(flipper, rng.uniform(-0.02, 0.1), rng.uniform(0.0, 0.08))
        info = {"ball_position": position, "ball_velocity": rng.normal(0.0, 1.5, 2)}
        actions.append(policy(info))
    answers = np.array(actions, dtype=np.int8)
    assert np.bincount(answers).tolist() == [1505, 695, 645, 155]
    digest = hashlib.sha256(answers.tobytes()).hexdigest()
    assert digest == "327ae2c66a503f5da77ff560ae3d74bcf7d50abcf4a8792cbb3fb9b672391cf3"


# --- the cabinet (Pinball-v1) ---------------------------------------------------------------


def plunge(env: gym.Env, frames: int, seed: int) -> bool:
    """Hold the plunger ``frames`` frames from a reset, let go: whether the skill shot is made."""
    env.reset(seed=seed)
    for _ in range(frames):
        env.step(PLUNGER)
    made = False
    for _ in range(round(V1.plunger.skill_shot.time * 60) + 5):
        made |= env.step(NOOP)[4]["skill_shot"]
    return made


def test_the_skill_shot_pull_is_the_one_that_makes_it_most_often():
    frames = skill_shot_frames(V1)
    pulls = plunger_pulls(V1)
    assert pulls[-1] == V1.plunger.stroke and 1 < frames < len(pulls)
    env = gym.make("Pinball-v1").unwrapped
    # Found by the kernel across the plunger's scatter, checked in seeded games: it makes the
    # skill shot nearly always, better than a frame either way, and the whole stroke rarely.
    rates = {n: sum(plunge(env, n, seed) for seed in range(10)) for n in
             (frames - 2, frames, frames + 2, len(pulls))}  # fmt: skip
    assert rates[frames] >= 9 and rates[frames] >= max(rates[frames - 2], rates[frames + 2])
    assert rates[len(pulls)] <= 2


@pytest.mark.parametrize("action_type", ["discrete", "multibinary"])
def test_the_heuristic_makes_the_skill_shot_on_classic_v1(action_type):
    env = gym.make("Pinball-v1", action_type=action_type)
    _, info = env.reset(seed=3)
    policy = HeuristicPolicy(env.unwrapped.game.table, action_type=action_type)
    assert info["ball_on_plunger"]
    made = 0
    for _ in range(240):
        _, _, _, _, info = env.step(policy(info))
        made += info["skill_shot"]
    assert made == 1 and info["score"] >= V1.plunger.skill_shot.bonus


def test_cabinet_buttons_need_the_cabinet_infos_and_no_warning():
    policy = HeuristicPolicy(V1)
    hugging = {"ball_position": np.array([0.0186, 0.43]), "ball_velocity": np.array([0.0, -1.0])}
    info = {**hugging, "frames": 100, "tilt_warnings": 0, "tilted": False,
            "ball_on_plunger": False, "plunger_pull": 0.0}  # fmt: skip
    assert policy(info) >> 3 == 2  # nudged (right: see below)
    for changes in ({"tilt_warnings": 1}, {"tilted": True}, {"ball_on_plunger": True}):
        assert HeuristicPolicy(V1)({**info, **changes}) >> 3 == 0
    assert HeuristicPolicy(V1)(hugging) == NOOP  # no cabinet entries: no nudge, no plunge
    assert HeuristicPolicy(V1, nudge=False)(info) == NOOP
    waiting = {**info, "ball_on_plunger": True, "ball_position": np.array(V1.plunger.position)}
    assert HeuristicPolicy(V1)(waiting) == PLUNGER
    assert HeuristicPolicy(V1, plunge=False)(waiting) == NOOP


def outlane_crossed(nudging: bool, position: tuple, velocity: tuple, mirror: bool) -> bool:
    """A ball at ``position``, ``velocity`` (mirrored onto the right outlane with ``mirror``),
    played 2 s in the kernel, the heuristic's nudges applied: whether it falls in the outlane."""
    if mirror:
        position, velocity = (MIRROR - position[0], position[1]), (-velocity[0], velocity[1])
    world = World(V1, 1)
    world.place_ball(0, position, velocity)
    policy = HeuristicPolicy(V1, nudge=nudging)
    lane = V1.element_names.index("right_outlane" if mirror else "left_outlane")
    for frame in range(120):
        info = {"ball_position": world.balls[0, 0, :2], "ball_velocity": world.balls[0, 0, 2:4],
                "frames": frame, "tilt_warnings": 0, "tilted": False,
                "ball_on_plunger": False, "plunger_pull": 0.0}  # fmt: skip
        action = policy(info)
        if action >> 3:  # 1: left, 2: right
            direction = -1.0 if action >> 3 == 1 else 1.0
            world.state.cabinet[0, CABINET_SHOVE_X] = direction * V1.cabinet.nudge_impulse
        world.step(np.array([[action & 1, action >> 1 & 1]], dtype=bool))
        if world.state.hits[0, lane]:
            return True
    return False


@pytest.mark.parametrize("mirror", [False, True])
def test_a_nudge_saves_a_ball_falling_down_the_outer_wall(mirror):
    """The wall slams it towards the inlane: a right nudge for the left outlane's wall."""
    ball = ((0.0186, 0.43), (0.0, -1.0))  # on the left wall, 7 cm above the post
    assert outlane_crossed(False, *ball, mirror)
    assert not outlane_crossed(True, *ball, mirror)


def bob_angle(env: gym.Env) -> float:
    cabinet = env.unwrapped.game.world.state.cabinet[0]
    return math.hypot(cabinet[BOB_X], cabinet[BOB_Y])


@pytest.mark.parametrize("margin", [0.8, 100.0])
def test_nudges_never_swing_the_bob_to_the_ring(margin):
    """Balls on both outer walls in turn, each due a nudge (left and right in turn: the rhythm
    that builds the bob's swing): the heuristic nudges whenever its model of the bob allows,
    and the bob stays inside its margin; without the margin the same play warns."""
    env = gym.make("Pinball-v1")
    _, info = env.reset(seed=0)
    policy = HeuristicPolicy(V1, plunge=False, tilt_margin=margin)
    ring = math.radians(V1.tilt.ring_angle)
    interval = round(V1.cabinet.nudge_interval * 60)
    nudges, widest, warned = [], 0.0, False
    for step in range(1200):
        x = 0.0186 if step % 2 else MIRROR - 0.0186
        doctored = {**info, "ball_position": np.array([x, 0.43]),
                    "ball_velocity": np.array([0.0, -1.0]), "ball_on_plunger": False}  # fmt: skip
        action = policy(doctored)
        if action >> 3:
            nudges.append(info["frames"])
        _, _, _, _, info = env.step(action)
        widest = max(widest, bob_angle(env))
        warned |= info["tilt_warnings"] > 0
    if margin > 1.0:
        assert warned
        return
    assert not warned and widest < margin * ring
    assert len(nudges) >= 10 and min(np.diff(nudges)) >= interval


def test_the_heuristic_never_tilts():
    """Whole games (the machine's random launches, and the heuristic's own plunges): nudges
    given, never a warning."""
    seeds = list(range(600, 608))
    envs = gym.make_vec(
        "Pinball-v1", num_envs=len(seeds), vectorization_mode="vector_entry_point",
        max_episode_steps=3600,
    )  # fmt: skip
    _, info = envs.reset(seed=seeds)
    keys = list(info)  # the game's entries (a step's infos add the vector env's)
    policies = [HeuristicPolicy(V1, plunge=e < 2) for e in range(len(seeds))]
    done, nudges = np.zeros(len(seeds), dtype=bool), 0
    while not done.all():
        actions = np.array([p({k: info[k][e] for k in keys}) for e, p in enumerate(policies)])
        nudges += int((actions[~done] >> 3).astype(bool).sum())
        _, _, terminated, truncated, info = envs.step(actions)
        assert not (info["tilt_warnings"][~done] > 0).any()
        assert not info["tilted"][~done].any()
        done |= terminated | truncated
    envs.close()
    assert nudges > 0
