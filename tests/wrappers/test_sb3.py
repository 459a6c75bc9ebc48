"""The stable-baselines3 adapter over the native vector env: SB3's checks, autoreset, training."""

import gymnasium as gym
import numpy as np
import pytest
import torch
from hypothesis import given, settings
from hypothesis import strategies as st

import pinball_env  # noqa: F401  (registers Pinball-v0)
from pinball_env.wrappers import SB3VecEnv

torch.set_num_threads(1)  # torch's default thread count slows SB3 on small machines


def test_steps_report_terminal_observations_and_time_limits():
    env = SB3VecEnv(gym.make_vec("Pinball-v0", num_envs=4, max_episode_steps=40))
    env.seed(7)
    obs = env.reset()
    assert obs.shape == (4, 10)
    for _ in range(40):
        obs, rewards, dones, infos = env.step(np.zeros(4, dtype=np.int64))
    assert dones.all() and rewards.dtype == np.float32
    for info in infos:
        assert info["TimeLimit.truncated"] and info["episode"]["l"] == 40
        assert info["terminal_observation"].shape == (10,)
    # The observation returned is already the next episode's first: on the plunger, 3 balls.
    plunger = env.venv.table.plunger.position
    np.testing.assert_allclose(obs[:, :2], [plunger] * 4, rtol=1e-6)
    assert (obs[:, 9] == 3).all()


@pytest.mark.parametrize("step_infos", [False, True])
def test_infos_only_where_a_game_ended_unless_asked_and_frames_counted(step_infos):
    """Without ``step_infos`` an env's info dict is empty but in the step its game ends (then
    it is what SB3 reads: the last step's keys, ``terminal_observation``,
    ``TimeLimit.truncated``, ``episode``); with it, every env's keys every step. Either way
    ``frames`` is the sum of every game's frames, as the per-env infos count them."""
    venv = gym.make_vec("Pinball-v1", num_envs=6, frame_skip=3, max_episode_steps=70)
    env = SB3VecEnv(venv, step_infos=step_infos)
    env.seed(5)
    env.reset()
    rng = np.random.default_rng(0)
    reference = SB3VecEnv(gym.make_vec("Pinball-v1", num_envs=6, frame_skip=3,
                                       max_episode_steps=70), step_infos=True)  # fmt: skip
    reference.seed(5)
    reference.reset()
    counted, last, ended = 0, np.zeros(6, dtype=np.int64), 0
    for _ in range(150):
        actions = rng.integers(0, 32, size=6)
        obs, rewards, dones, infos = env.step(actions)
        obs1, rewards1, dones1, infos1 = reference.step(actions)
        assert obs.tobytes() == obs1.tobytes() and rewards.tobytes() == rewards1.tobytes()
        assert (dones == dones1).all()
        for done, info, info1 in zip(dones, infos, infos1, strict=True):
            assert info.keys() == info1.keys() if (done or step_infos) else info == {}
            if done:
                assert info["score"] == info1["score"] and "terminal_observation" in info
                assert set(info["episode"]) == {"r", "l", "t"}
        for e, info in enumerate(infos1):
            counted += int(info["frames"]) - last[e]
            last[e] = 0 if dones1[e] else info["frames"]
        ended += int(dones.sum())
    assert ended > 6 and env.frames == reference.frames == counted > 0


def test_sb3_vec_normalize_is_vec_normalize_bitwise_and_saves_as_it(tmp_path):
    from stable_baselines3.common.vec_env import VecNormalize

    from pinball_env.wrappers import SB3VecNormalize

    def chain(cls):
        venv = SB3VecEnv(gym.make_vec("Pinball-v1", num_envs=5, max_episode_steps=40))
        venv.seed(2)
        return cls(venv, gamma=0.99)

    ours, theirs = chain(SB3VecNormalize), chain(VecNormalize)
    assert ours.reset().tobytes() == theirs.reset().tobytes()
    rng = np.random.default_rng(1)
    ended = 0
    for _ in range(90):
        actions = rng.integers(0, 32, size=5)
        a, b = ours.step(actions), theirs.step(actions)
        ended += int(a[2].sum())
        for x, y in zip(a[:3], b[:3], strict=True):
            assert x.tobytes() == y.tobytes()
        for info, other in zip(a[3], b[3], strict=True):
            if "terminal_observation" in other:
                assert (
                    info["terminal_observation"].tobytes()
                    == other["terminal_observation"].tobytes()
                )
    assert ended >= 10  # games ended on the way
    ours.save(str(tmp_path / "stats.pkl"))
    loaded = VecNormalize.load(str(tmp_path / "stats.pkl"), chain(VecNormalize).venv)
    assert isinstance(loaded, SB3VecNormalize)
    assert loaded.obs_rms.mean.tobytes() == ours.obs_rms.mean.tobytes()


def test_seeding_attributes_and_images():
    env = SB3VecEnv(gym.make_vec("Pinball-v0", num_envs=2, render_mode="rgb_array"))
    env.seed(3)
    a = env.reset()
    env.seed(3)
    assert env.reset().tobytes() == a.tobytes()
    assert env.get_attr("num_envs") == [2, 2]
    assert env.env_is_wrapped(gym.Wrapper) == [False, False]
    assert len(env.get_images()) == 2 and env.get_images()[0].ndim == 3
    with pytest.raises(TypeError, match="PinballVectorEnv"):
        SB3VecEnv(gym.vector.SyncVectorEnv([lambda: gym.make("Pinball-v0")]))
    wrapped = gym.wrappers.vector.ClipReward(gym.make_vec("Pinball-v0", num_envs=2), 0.0, 0.001)
    with pytest.raises(TypeError, match="would be bypassed"):
        SB3VecEnv(wrapped)


@pytest.mark.parametrize("algorithm", ["PPO", "DQN"])
def test_sb3_trains_on_the_native_vector_env(algorithm):
    import stable_baselines3
    from stable_baselines3.common.logger import Logger

    env = SB3VecEnv(gym.make_vec("Pinball-v0", num_envs=16 if algorithm == "PPO" else 4))
    kwargs = {"n_steps": 16, "batch_size": 64} if algorithm == "PPO" else {"learning_starts": 64}
    model = getattr(stable_baselines3, algorithm)("MlpPolicy", env, seed=0, device="cpu", **kwargs)
    model.set_logger(Logger(folder=None, output_formats=[]))  # SB3's default makes a temp dir
    model.learn(total_timesteps=512)
    assert model.num_timesteps >= 512
    action, _ = model.predict(env.reset(), deterministic=True)
    assert env.action_space.contains(action[0])


def test_attributes_and_methods_are_each_envs_own():
    venv = gym.make_vec("PinballProcgen-v0", num_envs=3, num_layouts=3, render_mode="rgb_array")
    env = SB3VecEnv(venv)
    env.seed(0)
    env.reset()
    layouts = venv.get_attr("layout")
    assert env.get_attr("layout") == list(layouts) and len(set(layouts)) > 1
    assert [t.name for t in env.get_attr("table")] == [f"procgen:{n}" for n in layouts]
    assert env.get_attr("layout", indices=[2, 0]) == [layouts[2], layouts[0]]
    assert env.get_attr("render_mode", indices=1) == ["rgb_array"]  # shared
    frames = env.env_method("render", indices=[1])
    assert len(frames) == 1 and frames[0].tobytes() == venv.render()[1].tobytes()
    assert env.env_method("render")[2].tobytes() == venv.render()[2].tobytes()
    env.set_attr("note", "left", indices=[0])  # a user's attribute, per env
    env.set_attr("note", "right", indices=[1, 2])
    assert env.get_attr("note") == ["left", "right", "right"]
    env.set_attr("max_episode_steps", 100)  # shared: for every env at once
    assert venv.max_episode_steps == 100
    with pytest.raises(ValueError, match="shared by every env"):
        env.set_attr("max_episode_steps", 50, indices=[0])
    with pytest.raises(ValueError, match="acting on every env"):
        env.env_method("close_extras", indices=[0])
    with pytest.raises(AttributeError, match="read-only"):
        env.set_attr("layout", 1, indices=[0])


@settings(max_examples=200, deadline=None)
@given(
    rows=st.integers(1, 2100),
    columns=st.integers(2, 40),
    dtype=st.sampled_from([np.float32, np.float64]),
    seed=st.integers(0, 2**32 - 1),
)
def test_the_compiled_normalisation_passes_are_numpys_bitwise(rows, columns, dtype, seed):
    from pinball_env.wrappers.sb3 import batch_moments, normalized

    rng = np.random.default_rng(seed)
    scale = 10.0 ** rng.uniform(-3, 6, size=columns)  # features of very different sizes
    obs = rng.standard_normal((rows, columns)) * scale + rng.uniform(-1e4, 1e4, columns)
    obs = obs.astype(dtype)
    mean, var = batch_moments(obs)
    assert mean.tobytes() == np.mean(obs, axis=0).tobytes()
    assert var.tobytes() == np.var(obs, axis=0).tobytes()
    centre, std = rng.standard_normal(columns) * 100, np.sqrt(rng.uniform(0, 1e4, columns) + 1e-8)
    expected = np.clip((obs - centre) / std, -10.0, 10.0).astype(np.float32)
    assert normalized(obs, centre, std, 10.0).tobytes() == expected.tobytes()
