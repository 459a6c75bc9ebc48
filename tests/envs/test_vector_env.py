"""The native vector env: N envs in one batch are bitwise N single envs; threads; autoreset."""

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.vector import AutoresetMode

import pinball_env  # noqa: F401  (registers Pinball-v0)
from pinball_env.envs import PinballVectorEnv

INFO_KEYS = ("ball_position", "ball_velocity", "score", "balls_left", "points", "drained", "frames")


def random_actions(space: gym.Space, steps: int, seed: int) -> list:
    space.seed(seed)
    return [space.sample() for _ in range(steps)]


@pytest.mark.parametrize(
    "kwargs",
    [
        {"balls": 1, "max_episode_steps": 400},
        {"action_type": "multibinary", "height_shaping": 0.5, "max_episode_steps": 300},
        {"obs_type": "grayscale", "image_size": 48, "balls": 1, "max_episode_steps": 200},
        {"obs_type": "rgb", "image_size": (40, 24), "max_episode_steps": 150},
        {"frame_skip": 3, "drain_penalty": 1.0, "balls": 2, "max_episode_steps": 300},
        {
            "frame_skip": 2,
            "skip_above": 0.3,
            "balls": 1,
            "max_frames": 1500,
            "max_episode_steps": None,
        },
        {
            "frame_skip": 2,
            "skip_above": 0.3,
            "repeat_action_probability": 0.25,
            "balls": 1,
            "max_frames": 1500,
            "max_episode_steps": None,
        },
    ],
)
def test_vector_env_is_bitwise_n_single_envs(kwargs):
    n, steps, seed = 3, 900, 11
    vector = gym.make_vec("Pinball-v0", num_envs=n, **kwargs)
    assert isinstance(vector, PinballVectorEnv)
    singles = [gym.make("Pinball-v0", **kwargs) for _ in range(n)]
    obs, infos = vector.reset(seed=seed)
    for env, single in enumerate(singles):
        obs1, info1 = single.reset(seed=seed + env)
        assert obs[env].tobytes() == obs1.tobytes()
    ended = np.zeros(n, dtype=bool)
    ends = 0
    for actions in random_actions(vector.action_space, steps, seed=1):
        obs, reward, terminated, truncated, infos = vector.step(actions)
        for env, single in enumerate(singles):
            if ended[env]:  # NEXT_STEP: this step reset the env and ignored its action
                obs1, info1 = single.reset()
                reward1, terminated1, truncated1 = 0.0, False, False
            else:
                obs1, reward1, terminated1, truncated1, info1 = single.step(actions[env])
            assert obs[env].tobytes() == obs1.tobytes()
            assert reward[env] == reward1 and type(reward1) is float
            assert (terminated[env], truncated[env]) == (terminated1, truncated1)
            for key in INFO_KEYS:
                assert np.array_equal(infos[key][env], info1[key]), key
        ended = terminated | truncated
        ends += int(ended.sum())
    assert ends >= n  # the comparison went through resets


def test_threads_give_bitwise_the_same_results():
    def run(num_threads):
        env = gym.make_vec("Pinball-v0", num_envs=64, num_threads=num_threads)
        env.reset(seed=5)
        trace = []
        for actions in random_actions(env.action_space, 300, seed=2):
            obs, reward, terminated, truncated, _ = env.step(actions)
            assert not truncated.any()
            trace.append((obs.tobytes(), reward.tobytes(), terminated.tobytes()))
        return trace

    assert run(1) == run(2)


def test_same_step_autoreset_keeps_the_final_observation():
    kwargs = {"balls": 1, "max_episode_steps": 200}
    vector = gym.make_vec(
        "Pinball-v0", num_envs=2, autoreset_mode=AutoresetMode.SAME_STEP, **kwargs
    )
    assert vector.metadata["autoreset_mode"] == AutoresetMode.SAME_STEP
    single = gym.make("Pinball-v0", **kwargs)
    vector.reset(seed=3)
    single.reset(seed=3)
    for step in range(450):
        obs, _, _, _, infos = vector.step(np.array([0, 0]))
        obs1, _, terminated1, truncated1, info1 = single.step(0)
        if terminated1 or truncated1:
            assert infos["_final_obs"][0]
            assert infos["final_obs"][0].tobytes() == obs1.tobytes()
            assert infos["final_info"]["score"][0] == info1["score"]
            assert infos["_episode_length"][0] and infos["episode_length"][0] == step + 1
            assert infos["final_info"]["_score"][0] and not infos["final_info"]["_score"][1]
            obs1, _ = single.reset()
            assert obs[0].tobytes() == obs1.tobytes()  # already the next episode
            return
    pytest.fail("no episode ended")


def test_episode_statistics_and_the_time_limit():
    env = gym.make_vec("Pinball-v0", num_envs=4, max_episode_steps=50)
    env.reset(seed=0)
    total = np.zeros(4)
    for _ in range(50):
        _, reward, terminated, truncated, infos = env.step(np.zeros(4, dtype=np.int64))
        total += reward
    assert truncated.all() and not terminated.any()
    assert infos["_episode_length"].all()
    np.testing.assert_array_equal(infos["episode_length"], [50] * 4)
    np.testing.assert_array_equal(infos["episode_return"], total)
    # Gymnasium's own episode statistics go on top without a clash.
    stats = gym.wrappers.vector.RecordEpisodeStatistics(
        gym.make_vec("Pinball-v0", num_envs=2, max_episode_steps=5)
    )
    stats.reset(seed=0)
    for _ in range(5):
        *_, infos = stats.step(np.zeros(2, dtype=np.int64))
    assert infos["_episode"].all() and (infos["episode"]["l"] == 5).all()
    _, reward, terminated, truncated, _ = env.step(np.zeros(4, dtype=np.int64))
    assert not (terminated | truncated).any() and not reward.any()  # the autoreset step


def test_reset_mask_resets_only_the_masked_envs():
    env = gym.make_vec("Pinball-v0", num_envs=3)
    env.reset(seed=0)
    for _ in range(30):
        obs, *_ = env.step(np.ones(3, dtype=np.int64))
    again, infos = env.reset(options={"reset_mask": np.array([False, True, False])})
    assert again[0].tobytes() == obs[0].tobytes() and again[2].tobytes() == obs[2].tobytes()
    assert again[1].tobytes() != obs[1].tobytes()
    assert infos["_score"].tolist() == [False, True, False]
    with pytest.raises(TypeError, match="reset_mask"):  # as SyncVectorEnv: an array of bools
        env.reset(options={"reset_mask": [False, True, False]})
    with pytest.raises(ValueError, match="reset_mask"):
        env.reset(options={"reset_mask": np.zeros(3, dtype=bool)})


def test_close_stops_the_threads():
    env = gym.make_vec("Pinball-v0", num_envs=64, num_threads=2)
    env.reset(seed=0)
    env.step(np.zeros(64, dtype=np.int64))
    assert env.game.world.threads._pool is not None
    env.close()
    assert env.game.world.threads._pool is None


@pytest.mark.parametrize(
    ("kwargs", "actions", "message"),
    [
        ({}, np.array([0, 4]), "invalid actions"),
        ({}, np.array([0.5, 1.0]), "invalid actions"),
        ({"action_type": "multibinary"}, np.array([1, 0]), "invalid actions"),
    ],
)
def test_bad_actions_are_rejected(kwargs, actions, message):
    env = gym.make_vec("Pinball-v0", num_envs=2, **kwargs)
    env.reset(seed=0)
    with pytest.raises(ValueError, match=message):
        env.step(actions)


def test_bad_arguments_and_step_before_reset():
    with pytest.raises(ValueError, match="num_envs"):
        PinballVectorEnv(num_envs=0)
    with pytest.raises(ValueError, match="autoreset_mode"):
        PinballVectorEnv(autoreset_mode="Sometimes")
    with pytest.raises(ValueError, match="num_threads"):
        PinballVectorEnv(num_envs=2, num_threads=0)
    with pytest.raises(gym.error.ResetNeeded):
        PinballVectorEnv(num_envs=2).step(np.zeros(2, dtype=np.int64))


def test_a_refused_vector_env_closes_cleanly():
    env = PinballVectorEnv.__new__(PinballVectorEnv)
    with pytest.raises(ValueError, match="num_envs"):
        env.__init__(num_envs=0)
    env.close()  # as garbage collection does: nothing was started, nothing fails


def test_render_gives_every_envs_frame():
    env = gym.make_vec("Pinball-v0", num_envs=2, render_mode="rgb_array")
    env.reset(seed=0)
    frames = env.render()
    single = gym.make("Pinball-v0", render_mode="rgb_array")
    single.reset(seed=1)
    assert len(frames) == 2 and frames[1].tobytes() == single.render().tobytes()
