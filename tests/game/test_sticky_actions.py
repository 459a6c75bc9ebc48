"""Sticky actions (``repeat_action_probability``): each frame presses the last frame's buttons
again where its draw from the env's own stream says so, and nothing else changes."""

import copy

import gymnasium as gym
import numpy as np
import pytest

import pinball_env  # noqa: F401  (registers the envs)


def expected_presses(
    pressed: np.ndarray, buttons: np.ndarray, draws: np.ndarray, p: float, frames: int, skip: int
) -> np.ndarray:
    """The buttons the last of ``frames`` frames presses: each frame takes the action's
    ``buttons`` (released after the first ``skip`` frames) unless its draw is below ``p``, then
    it keeps the frame before's."""
    for frame in range(frames):
        if not draws[frame] < p:
            pressed = buttons if frame < skip else np.zeros_like(buttons)
    return pressed


@pytest.mark.parametrize(
    ("env_id", "skip_above"), [("Pinball-v0", 0.0), ("Pinball-v1", 0.0), ("Pinball-v1", 0.4)]
)
def test_each_frame_repeats_the_last_buttons_where_its_draw_says(env_id, skip_above):
    p, skip = 0.4, 3
    env = gym.make(env_id, repeat_action_probability=p, frame_skip=skip, balls=1,
                   skip_above=skip_above)  # fmt: skip
    game = env.unwrapped.game
    env.reset(seed=5)
    rng = np.random.default_rng(0)
    n_flippers = game.world.state.flipper_command.shape[1]
    cabinet = len(game.button_names) > 2
    repeats = takes = 0
    for _ in range(400):
        action = int(rng.integers(env.action_space.n))
        stream = copy.deepcopy(env.unwrapped.np_random)
        draws = stream.random(skip + (60 if skip_above else 0))  # first, before a launch's
        buttons = game.discrete_buttons[action]
        commands = buttons[game.world.flipper_buttons]
        wanted = np.concatenate([commands, buttons[2:] if cabinet else np.zeros(4, bool)])
        before = game.state.pressed[0].copy()
        frames_before = game.state.frames[0]
        _, _, terminated, truncated, _ = env.step(action)
        played = game.state.frames[0] - frames_before
        expected = expected_presses(before, wanted, draws, p, played, skip)
        assert np.array_equal(game.state.pressed[0], expected)
        flippers = game.state.pressed[0, :n_flippers] & ~game.world.state.tilted[0]
        assert np.array_equal(game.world.state.flipper_command[0], flippers)
        repeats += int((draws[:played] < p).sum())
        takes += int(played)
        if terminated or truncated:
            env.reset()
    assert 0.3 < repeats / takes < 0.5  # the share of frames that repeat is about p


def test_without_sticky_actions_a_step_draws_nothing():
    env = gym.make("Pinball-v0")
    env.reset(seed=1)
    for _ in range(30):  # the ball is in play: no launch draws either
        before = copy.deepcopy(env.unwrapped.np_random.bit_generator.state)
        env.step(1)
        assert env.unwrapped.np_random.bit_generator.state == before


def test_sticky_games_are_the_seeds_and_differ_from_plain_ones():
    def play(p: float, seed: int) -> tuple[int, bytes]:
        env = gym.make("Pinball-v1", repeat_action_probability=p, balls=1)
        obs, _ = env.reset(seed=seed)
        rng = np.random.default_rng(2)
        states = []
        for _ in range(600):
            obs, _, terminated, truncated, info = env.step(int(rng.integers(32)))
            states.append(obs.tobytes())
            if terminated or truncated:
                break
        return info["score"], b"".join(states)

    assert play(0.25, 7) == play(0.25, 7)
    assert play(0.25, 7)[1] != play(0.0, 7)[1]
