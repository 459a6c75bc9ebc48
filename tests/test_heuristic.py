"""The scripted heuristic: it flips at a ball landing on a flipper, on any table, and plays
clearly better than random."""

import dataclasses
import math

import gymnasium as gym
import numpy as np

import pinball_env  # noqa: F401  (registers Pinball-v0)
from pinball_env.heuristic import HeuristicPolicy
from pinball_env.table import BUTTONS, Flipper, Table, load_table

CLASSIC = load_table("classic")


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
