"""Saved games (``pinball_env.envs.states``): a game cloned and restored goes on bitwise as it
went on, single and vector, across a pickle and in another process, on every env version and
on generated tables; a game branched into many envs; a state of another game refused with
nothing changed; what a state carries of the random stream."""

import dataclasses
import pickle
import subprocess
import sys
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest

from pinball_env.envs import PinballState

ROOT = Path(__file__).resolve().parents[2]

# Every env version and generated tables, with sticky actions (which draw from the stream).
ENVS = [(env_id, {}) for env_id in ("Pinball-v0", "Pinball-v1", "Pinball-v2", "Pinball-v3")]
ENVS.append(("PinballProcgen-v0", {"num_layouts": 4}))


def play(env, actions):
    """Step ``env`` with ``actions`` to the end of its game: every observation, reward and
    info's score, frames and balls as bytes."""
    played = []
    for action in actions:
        obs, reward, terminated, truncated, info = env.step(int(action))
        numbers = np.array([reward, info["score"], info["frames"], info["balls_left"]])
        played.append(obs.tobytes() + numbers.tobytes())
        if terminated or truncated:
            break
    return played


def warmed(env_id, kwargs, seed=1, steps=250):
    env = gym.make(env_id, repeat_action_probability=0.25, **kwargs)
    env.reset(seed=seed)
    for action in np.random.default_rng(seed).integers(env.action_space.n, size=steps):
        env.step(int(action))
    return env


@pytest.mark.parametrize(("env_id", "kwargs"), ENVS, ids=[e for e, _ in ENVS])
def test_a_restored_game_goes_on_bitwise_as_it_went_on(env_id, kwargs):
    env = warmed(env_id, kwargs)
    state = env.unwrapped.clone_state(include_rng=True)
    actions = np.random.default_rng(7).integers(env.action_space.n, size=1500)
    went_on = play(env, actions)
    for again in (state, pickle.loads(pickle.dumps(state))):
        obs, info = env.unwrapped.restore_state(again)
        assert env.observation_space.contains(obs) and "score" in info
        assert play(env, actions) == went_on
    # Another env of the same game (a new one, another seed) goes on alike from the state.
    other = gym.make(env_id, repeat_action_probability=0.25, **kwargs)
    other.reset(seed=99)
    other.unwrapped.restore_state(state)
    assert play(other, actions) == went_on
    assert len(went_on) > 100


def test_a_state_restores_in_another_process(tmp_path):
    env = warmed("Pinball-v3", {})
    state = env.unwrapped.clone_state(include_rng=True)
    actions = np.random.default_rng(3).integers(env.action_space.n, size=600)
    (tmp_path / "state.pkl").write_bytes(pickle.dumps((state, actions)))
    expected = play(env, actions)
    script = (
        "import pickle, sys, gymnasium as gym, pinball_env\n"
        "from tests.envs.test_states import play\n"
        "state, actions = pickle.loads(open(sys.argv[1], 'rb').read())\n"
        "env = gym.make('Pinball-v3', repeat_action_probability=0.25)\n"
        "env.reset(seed=5)\n"
        "env.unwrapped.restore_state(state)\n"
        "open(sys.argv[2], 'wb').write(pickle.dumps(play(env, actions)))\n"
    )
    files = [str(tmp_path / "state.pkl"), str(tmp_path / "played.pkl")]
    subprocess.run([sys.executable, "-c", script, *files], check=True, cwd=ROOT)
    assert pickle.loads((tmp_path / "played.pkl").read_bytes()) == expected


def test_without_the_stream_a_restored_game_draws_from_the_envs_own():
    env = warmed("Pinball-v3", {})
    state = env.unwrapped.clone_state()
    assert state.rng is None
    stream = env.unwrapped.np_random.bit_generator.state
    env.unwrapped.restore_state(state)
    assert env.unwrapped.np_random.bit_generator.state == stream  # left as it was
    with_stream = env.unwrapped.clone_state(include_rng=True)
    assert with_stream.rng == stream


@pytest.mark.parametrize(("env_id", "kwargs"), [ENVS[3], ENVS[4]], ids=["v3", "procgen"])
def test_one_game_branched_into_every_env_of_the_vector_env(env_id, kwargs):
    # A single env's game, put into 6 envs of a vector env: each plays on as the single env
    # does, given its actions and its stream; a vector env's own states restore alike.
    single = warmed(env_id, kwargs)
    state = single.unwrapped.clone_state(include_rng=True)
    actions = np.random.default_rng(11).integers(single.action_space.n, size=400)
    expected = play(single, actions)
    venv = gym.make_vec(env_id, num_envs=6, repeat_action_probability=0.25, **kwargs)
    venv.reset(seed=3)
    venv.restore_state(state)  # one state for every env: a branch each
    saved = venv.clone_state([2, 4], include_rng=True)
    assert [s.episode for s in saved] == [(0.0, 0, False)] * 2
    rows = [[] for _ in range(6)]
    done = np.zeros(6, dtype=bool)
    for action in actions:
        obs, reward, terminated, truncated, infos = venv.step(np.full(6, action))
        for env in np.flatnonzero(~done):
            numbers = np.array([reward[env], infos["score"][env], infos["frames"][env],
                                infos["balls_left"][env]])  # fmt: skip
            rows[env].append(obs[env].tobytes() + numbers.tobytes())
        done |= terminated | truncated
        if done.all():
            break
    assert all(row == expected[: len(row)] for row in rows) and len(rows[0]) == len(expected)
    # The vector env's own states, put back in other envs, play on as those envs did.
    venv.restore_state(saved, [0, 1])
    assert [s.episode for s in venv.clone_state([0, 1])] == [(0.0, 0, False)] * 2
    venv.close()


def test_a_state_of_another_game_is_refused_and_nothing_changes():
    v3, v2 = warmed("Pinball-v3", {}), warmed("Pinball-v2", {})
    state = v3.unwrapped.clone_state()
    before = v2.unwrapped.clone_state()
    with pytest.raises(ValueError, match=r"another game.*env id"):
        v2.unwrapped.restore_state(state)
    with pytest.raises(ValueError, match="package version"):
        v3.unwrapped.restore_state(dataclasses.replace(state, package_version="0.0.1"))
    with pytest.raises(ValueError, match="ball slots"):
        v3.unwrapped.restore_state(dataclasses.replace(state, ball_slots=1))
    with pytest.raises(ValueError, match="another table"):
        v3.unwrapped.restore_state(dataclasses.replace(state, table_sha256="0" * 64))
    with pytest.raises(TypeError, match="PinballState"):
        v3.unwrapped.restore_state({"score": 10})
    assert pickle.dumps(v2.unwrapped.clone_state()) == pickle.dumps(before)
    venv = gym.make_vec("Pinball-v3", num_envs=3)
    venv.reset(seed=0)
    kept = pickle.dumps(venv.clone_state())
    bad = dataclasses.replace(state, package_version="0.0.1")
    with pytest.raises(ValueError, match="package version"):
        venv.restore_state([state, state, bad])  # checked before any env changes
    with pytest.raises(ValueError, match="2 states for 3 envs"):
        venv.restore_state([state, state])
    with pytest.raises(ValueError, match=r"env indices \[7\]"):
        venv.clone_state([7])
    assert pickle.dumps(venv.clone_state()) == kept
    assert isinstance(state, PinballState)
