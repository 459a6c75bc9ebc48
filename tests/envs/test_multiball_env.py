"""Pinball-v3: its state rows (a block per ball), its per-ball infos, the native
vector env bitwise N single envs through multiballs, check_env, seeding and pickling."""

import pickle
import warnings

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

import pinball_env
from pinball_env.envs import PinballVectorEnv
from pinball_env.table import available_tables

BALL_KEYS = ("ball_positions", "ball_velocities", "balls_in_play", "balls_locked", "multiball",
             "multiballs")  # fmt: skip
INFO_KEYS = ("ball_position", "ball_velocity", "score", "balls_left", "points", "drained",
             "frames", *BALL_KEYS)  # fmt: skip


# A reset with the first ball in play (not waiting on the player's plunger, which blocks the
# shooter lane for the auto-plunger).
ON_TABLE = {"ball_position": (0.25, 0.5)}


def more_balls(env, envs, count=2):
    """Queue ``count`` balls for the auto-plunger in each of ``envs`` (as add_balls does)."""
    env.unwrapped.game.state.pending_balls[envs] = count


def test_pinball_v3_is_registered_on_classic_v3():
    assert pinball_env.ENV_VERSIONS["Pinball-v3"].table == "classic_v3"
    assert "classic_v3" in available_tables()
    env = gym.make("Pinball-v3")
    assert env.unwrapped.table.name == "classic_v3" and env.unwrapped.table.n_balls == 3
    env.close()


def test_the_state_rows_have_a_block_per_ball_then_v2s_rows():
    v3, v2 = gym.make("Pinball-v3").unwrapped, gym.make("Pinball-v2").unwrapped
    rows, rows2 = v3.observation_rows, v2.observation_rows
    assert [r.meaning for r in rows[:5]] == [
        "ball 0 x", "ball 0 y (up the table)", "ball 0 vx (clipped to +-20)",
        "ball 0 vy (clipped to +-20)",
        "ball 0 in play (1: on the table or the player's plunger), held in a lock or saucer "
        "(0.5) or in the trough (0; x, y, vx, vy 0)",
    ]  # fmt: skip
    assert rows[10].meaning == "ball 2 x" and rows[14].meaning.startswith("ball 2 in play")
    # Then v2's rows from the flippers on, and the rules' rows of v3's lights and counters.
    assert [r.meaning for r in rows[15:29]] == [r.meaning for r in rows2[4:18]]
    assert len(rows) == v3.observation_space.shape[0]
    obs, _ = v3.reset(seed=0)
    assert obs[4] == 1.0 and obs[9] == 0.0 and obs[14] == 0.0  # the first on the plunger
    assert obs[0] == np.float32(v3.table.plunger.position[0])
    v3.reset(seed=0, options=ON_TABLE)
    more_balls(v3, 0)
    for _ in range(120):
        obs, *_ = v3.step(0)
        assert v3.observation_space.contains(obs)
    assert obs[9] == 1.0 and obs[14] == 1.0  # the auto-plunger's two in play too


def test_the_infos_have_every_ball_single_and_vector():
    env = gym.make("Pinball-v3")
    _, info = env.reset(seed=1)
    assert info["ball_positions"].shape == (3, 2) and info["balls_in_play"].shape == (3,)
    assert np.array_equal(info["ball_positions"][0], info["ball_position"])
    env.reset(seed=1, options=ON_TABLE)
    more_balls(env, 0)
    for _ in range(120):
        _, _, _, _, info = env.step(0)
    assert info["balls_in_play"].sum() >= 2 and info["multiball"]
    first = int(np.flatnonzero(info["balls_in_play"])[0])
    assert np.array_equal(info["ball_positions"][first], info["ball_position"])
    vector = gym.make_vec("Pinball-v3", num_envs=2)
    _, infos = vector.reset(seed=1)
    assert infos["ball_positions"].shape == (2, 3, 2) and infos["balls_in_play"].shape == (2, 3)
    vector.close()


def test_the_vector_env_is_bitwise_n_single_envs_through_multiballs():
    n, steps, seed = 3, 500, 11
    vector = gym.make_vec("Pinball-v3", num_envs=n, max_episode_steps=250)
    assert isinstance(vector, PinballVectorEnv)
    singles = [gym.make("Pinball-v3", max_episode_steps=250) for _ in range(n)]
    obs, _ = vector.reset(seed=seed, options=ON_TABLE)
    for env, single in enumerate(singles):
        obs1, _ = single.reset(seed=seed + env, options=ON_TABLE)
        assert obs[env].tobytes() == obs1.tobytes()
        more_balls(vector, env)
        more_balls(single, 0)
    vector.action_space.seed(1)
    ended = np.zeros(n, dtype=bool)
    most = ends = 0
    for _ in range(steps):
        actions = vector.action_space.sample()
        obs, reward, terminated, truncated, infos = vector.step(actions)
        for env, single in enumerate(singles):
            if ended[env]:
                obs1, info1 = single.reset()
                reward1, terminated1, truncated1 = 0.0, False, False
            else:
                obs1, reward1, terminated1, truncated1, info1 = single.step(actions[env])
            assert obs[env].tobytes() == obs1.tobytes()
            assert reward[env] == reward1
            assert (terminated[env], truncated[env]) == (terminated1, truncated1)
            for key in INFO_KEYS:
                assert np.array_equal(infos[key][env], info1[key]), key
        ended = terminated | truncated
        ends += int(ended.sum())
        most = max(most, int(infos["balls_in_play"].sum(axis=1).max()))
    assert most == 3 and ends >= n  # multiballs, and the comparison went through resets


def test_check_env_is_clean():
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        check_env(gym.make("Pinball-v3", render_mode="rgb_array").unwrapped)


def test_the_same_seed_plays_the_same_game_and_a_pickle_goes_on_alike():
    def play(env, steps=300):
        env.action_space.seed(3)
        trace = []
        for _ in range(steps):
            obs, reward, *_ = env.step(env.action_space.sample())
            trace.append((obs.tobytes(), reward))
        return trace

    a, b = gym.make("Pinball-v3").unwrapped, gym.make("Pinball-v3").unwrapped
    for env in (a, b):
        env.reset(seed=7, options=ON_TABLE)
        more_balls(env, 0)
    assert play(a) == play(b)
    copy = pickle.loads(pickle.dumps(a))
    assert play(a) == play(copy)


def test_the_frame_and_the_picture_show_every_ball():
    from pinball_env.render.colours import BALL, rgb

    def ball_pixels(picture):
        return int((picture == np.array(rgb(BALL), dtype=np.uint8)).all(axis=-1).sum())

    env = gym.make("Pinball-v3", render_mode="rgb_array")
    pictures = gym.make("Pinball-v3", obs_type="rgb", image_size=(214, 102))
    counts = []
    for one in (env, pictures):
        obs, _ = one.reset(seed=0, options=ON_TABLE)
        first = ball_pixels(one.render() if one is env else obs)
        more_balls(one, 0)
        for _ in range(40):
            obs, *_ = one.step(0)
        assert one.unwrapped.game.world.active[0].sum() == 3
        counts.append((first, ball_pixels(one.render() if one is env else obs)))
    for first, three in counts:
        assert first > 0 and three >= 2.5 * first


def test_ball_order_lowest_puts_the_lowest_ball_in_play_first_and_keeps_each_block():
    # The same game seen in slot order and lowest first: the blocks are the same blocks, the
    # balls in play first by height, then the held ones, then the trough's; the space holds it.
    slot_env = gym.make("Pinball-v3")
    lowest_env = gym.make("Pinball-v3", ball_order="lowest")
    n_balls = slot_env.unwrapped.table.n_balls
    seen_orders = set()
    for env in (slot_env, lowest_env):
        env.reset(seed=3, options=ON_TABLE)
        more_balls(env, 0)
    rng = np.random.default_rng(0)
    for _ in range(600):
        action = int(rng.integers(8))
        by_slot = slot_env.step(action)[0]
        lowest = lowest_env.step(action)[0]
        assert lowest_env.observation_space.contains(lowest)
        blocks = by_slot[: 5 * n_balls].reshape(n_balls, 5)
        ordered = lowest[: 5 * n_balls].reshape(n_balls, 5)
        assert (by_slot[5 * n_balls :] == lowest[5 * n_balls :]).all()  # the rest as it was
        assert sorted(map(tuple, blocks)) == sorted(map(tuple, ordered))  # the same blocks
        rank = np.select([ordered[:, 4] == 1.0, ordered[:, 4] == 0.5], [0, 1], 2)
        assert (np.diff(rank) >= 0).all()
        for group in (0, 1):
            heights = ordered[rank == group, 1]
            assert (np.diff(heights) >= 0).all()
        in_play = blocks[:, 4] == 1.0
        if in_play.sum() > 1:
            seen_orders.add(tuple(np.argsort(blocks[in_play, 1], kind="stable")))
    assert len(seen_orders) > 1  # the balls in play changed places in the order
    assert lowest_env.unwrapped.observation_rows[0].meaning.startswith("ball 0 (by urgency")


def test_ball_order_is_refused_where_there_is_no_state_observation():
    with pytest.raises(ValueError, match="ball_order"):
        gym.make("Pinball-v3", obs_type="rgb", ball_order="lowest")
