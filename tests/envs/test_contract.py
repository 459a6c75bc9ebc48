"""The envs' contract under any play: every observation inside its declared space and every
info number inside its documented range (``game.infos.info_ranges``), on every env version and
generated tables, single and vector, in long random, nudge-heavy and scripted games (multiball
included); and the two games found outside them, replayed."""

import gymnasium as gym
import numpy as np
import pytest

from pinball_env.game.infos import info_ranges
from pinball_env.players import HeuristicPolicy

ENVS = [("Pinball-v0", {}), ("Pinball-v1", {}), ("Pinball-v2", {}), ("Pinball-v3", {}),
        ("PinballProcgen-v0", {"num_layouts": 8, "targets": True})]  # fmt: skip
PLAYS = ("random", "nudges", "heuristic")
# The discrete actions of a table with the cabinet that nudge (bits 3-4: a nudge's direction).
NUDGES = np.arange(8, 32)


def within(value, low, high):
    value = np.asarray(value, dtype=np.float64)
    return bool(np.all(np.isfinite(value)) and np.all(value >= low) and np.all(value <= high))


def check_infos(game, infos, env=None, mask=None):
    """Every number of ``infos`` (a single env's, or a vector env's arrays) in its range."""
    envs = range(game.n_envs) if env is None else [env]
    for index in envs:
        ranges = info_ranges(game, index, game.max_frames)
        for key, (low, high) in ranges.items():
            if key not in infos or (mask is not None and not mask[index]):
                continue
            value = infos[key] if env is not None else infos[key][index]
            if isinstance(value, dict):  # the single env's rule events: name -> count
                value = list(value.values()) or [0]
            assert within(value, np.asarray(low), np.asarray(high)), (key, value, low, high)


class Players:
    """A play of each env of a vector env: random, nudge-heavy (a nudge 70% of the steps, on a
    table with the cabinet) or the heuristic (a player each, on its env's table)."""

    def __init__(self, play, venv, seed):
        self.play, self.venv = play, venv
        self.rng = np.random.default_rng(seed)
        self.heuristics = {}

    def __call__(self, infos):
        n, space = self.venv.num_envs, self.venv.single_action_space
        if self.play == "random" or (self.play == "nudges" and space.n < 32):
            return self.rng.integers(space.n, size=n)
        if self.play == "nudges":
            nudge = self.rng.random(n) < 0.7
            return np.where(nudge, self.rng.choice(NUDGES, size=n), self.rng.integers(8, size=n))
        game = self.venv.unwrapped.game
        actions = np.zeros(n, dtype=np.int64)
        for env in range(n):
            table = game.world.table_of(env)
            if self.heuristics.get(env, (None,))[0] is not table:
                self.heuristics[env] = (table, HeuristicPolicy(table))
            info = {key: value[env] for key, value in infos.items() if not key.startswith("_")}
            actions[env] = int(self.heuristics[env][1](info))
        return actions


@pytest.mark.parametrize("play", PLAYS)
@pytest.mark.parametrize(("env_id", "kwargs"), ENVS, ids=[e for e, _ in ENVS])
def test_every_observation_and_info_of_the_vector_env_is_in_its_space_and_range(
    env_id, kwargs, play
):
    venv = gym.make_vec(env_id, num_envs=8, repeat_action_probability=0.25, **kwargs)
    obs, infos = venv.reset(seed=11)
    game, players = venv.unwrapped.game, Players(play, venv, 5)
    ended = 0
    for _ in range(2500):
        assert venv.observation_space.contains(obs)
        check_infos(game, infos)
        obs, _, terminated, truncated, infos = venv.step(players(infos))
        ended += int((terminated | truncated).sum())
    assert ended > 0 or play != "random"  # whole games, and new ones
    venv.close()


@pytest.mark.parametrize(("env_id", "kwargs"), ENVS, ids=[e for e, _ in ENVS])
def test_every_observation_and_info_of_the_single_env_is_in_its_space_and_range(env_id, kwargs):
    env = gym.make(env_id, **kwargs)
    rng = np.random.default_rng(2)
    obs, info = env.reset(seed=4)
    for _ in range(2500):
        assert env.observation_space.contains(obs)
        check_infos(env.unwrapped.game, info, env=0)
        obs, _, terminated, truncated, info = env.step(int(rng.integers(env.action_space.n)))
        if terminated or truncated:
            obs, info = env.reset()


def test_the_frame_that_tilts_with_two_touches_is_in_the_space():
    # Found outside it: two touches of the ring in the frame that tilts (warnings 2 -> 4).
    env = gym.make("Pinball-v3")
    env.reset(seed=0)
    played = {0: 9, 16: 30, 33: 14, 48: 10, 63: 26, 78: 10, 93: 11, 109: 27, 118: 22, 124: 10}
    for step in range(126):
        obs, _, _, _, info = env.step(played.get(step, 0))
        assert env.observation_space.contains(obs), step
    assert info["tilt_warnings"] == 4 and info["tilted"]


def test_an_extra_ball_is_in_the_space():
    # Found outside it: the third bank's extra ball lifts the balls left past the game's 3.
    env = gym.make("Pinball-v3")
    heuristic = HeuristicPolicy(env.unwrapped.table)
    obs, info = env.reset(seed=7140)
    most = 0
    for _ in range(1800):
        obs, _, terminated, truncated, info = env.step(heuristic(info))
        assert env.observation_space.contains(obs)
        most = max(most, info["balls_left"])
        if terminated or truncated:
            break
    assert most == 4
