"""The Gymnasium environment Pinball-v0: API, checkers, determinism, options, rewards, errors."""

import dataclasses
import os
import pickle
import subprocess
import sys
import warnings
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

import pinball_env
from pinball_env.players import HeuristicPolicy
from pinball_env.table import TableError, builtin_tables_dir, load_table
from pinball_env.tools.demo import main as demo_main

try:  # (the env's core tests run on other Pythons without the agents' extra: .ci/other-pythons)
    from stable_baselines3.common.env_checker import check_env as sb3_check_env
except ImportError:
    sb3_check_env = None

ROOT = Path(__file__).resolve().parents[2]
OBS_TYPES = ["state", "rgb", "grayscale"]
V0_NOTICE = ".*Pinball-v0 is out of date"

# Run as a script in fresh processes, and exec'd in this one: the digest of a seeded rollout.
ROLLOUT_SCRIPT = """
import dataclasses
import hashlib
import gymnasium as gym
import numpy as np
import pinball_env

def digest():
    env = gym.make("Pinball-v0")
    result = hashlib.sha256()
    env.reset(seed=7)
    rng = np.random.default_rng(1)
    for _ in range(600):
        obs, reward, terminated, truncated, info = env.step(int(rng.integers(4)))
        result.update(obs.tobytes())
        result.update(np.float64(reward).tobytes())
        result.update(repr(sorted(info["events"].items())).encode())
        if terminated or truncated:
            env.reset()
    return result.hexdigest()

if __name__ == "__main__":
    print(digest())
"""


@pytest.fixture(autouse=True)
def _headless(monkeypatch):
    monkeypatch.setenv("SDL_VIDEODRIVER", "dummy")
    monkeypatch.setenv("SDL_AUDIODRIVER", "dummy")


def test_registration_and_time_limit():
    spec = gym.spec("Pinball-v0")
    assert spec.entry_point == "pinball_env.envs:PinballEnv"
    assert spec.max_episode_steps == pinball_env.MAX_EPISODE_STEPS
    env = gym.make("Pinball-v0")
    assert isinstance(env.action_space, gym.spaces.Discrete) and env.action_space.n == 4
    assert env.observation_space.shape == (10,)
    assert env.observation_space.dtype == np.float32


def test_table_by_name_or_yaml_path():
    by_path = gym.make("Pinball-v0", table=str(builtin_tables_dir() / "classic.yaml"))
    by_name = gym.make("Pinball-v0", table="classic")
    assert by_path.unwrapped.table.walls == by_name.unwrapped.table.walls
    assert by_path.reset(seed=1)[0].tobytes() == by_name.reset(seed=1)[0].tobytes()


@pytest.mark.parametrize("physics", ["swept", "pymunk"])
@pytest.mark.parametrize("obs_type", OBS_TYPES)
@pytest.mark.parametrize("action_type", ["discrete", "multibinary"])
def test_checkers_pass_without_warnings(obs_type, action_type, physics):
    kwargs = {"obs_type": obs_type, "action_type": action_type, "physics": physics}
    if action_type == "multibinary":  # and the training options, once per obs_type and physics
        kwargs |= {"frame_skip": 4, "drain_penalty": 1.0, "height_shaping": 0.5}
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        # Gymnasium's registry notice that a newer version exists, not a warning about the env.
        warnings.filterwarnings("ignore", V0_NOTICE, DeprecationWarning)
        env = gym.make("Pinball-v0", render_mode="rgb_array", **kwargs)
        check_env(env.unwrapped)
        if sb3_check_env is not None:
            sb3_check_env(gym.make("Pinball-v0", **kwargs))


def test_pymunk_backend_plays_a_game_with_the_same_spaces_reward_and_info():
    swept = gym.make("Pinball-v0")
    pym = gym.make("Pinball-v0", physics="pymunk")
    assert swept.observation_space == pym.observation_space
    assert swept.action_space == pym.action_space
    obs_s, info_s = swept.reset(seed=3)
    obs_p, info_p = pym.reset(seed=3)
    assert obs_s.tobytes() == obs_p.tobytes()  # same plunger shot from the same seed
    assert info_s.keys() == info_p.keys()
    # A bumper hit scores the same on both.
    options = {"ball_position": [0.2365, 0.70], "ball_velocity": [0.0, -1.0]}
    for env in (swept, pym):
        env.reset(seed=0, options=options)
        events = {}
        for _ in range(30):
            _, reward, _, _, info = env.step(0)
            events.update(info["events"])
            if events:
                break
        assert events == {"bumper_bottom": 1} and reward == pytest.approx(1.0)
    # And a drained ball ends the game the same way.
    pym.reset(seed=0, options={"ball_position": [0.2365, 0.06], "ball_velocity": [0.0, -1.0]})
    for _ in range(5):
        _, _, _, _, info = pym.step(0)
        if info["drained"]:
            break
    assert info["drained"] and info["balls_left"] == 2


def test_pymunk_env_pickles():
    env = gym.make("Pinball-v0", physics="pymunk")
    env.reset(seed=0)
    env.step(1)
    copy = pickle.loads(pickle.dumps(env))
    obs, *_ = copy.step(1)
    assert copy.observation_space.contains(obs)


def test_image_observations_and_frames_have_the_documented_shapes():
    for obs_type, channels in (("rgb", 3), ("grayscale", 1)):
        env = gym.make("Pinball-v0", obs_type=obs_type)
        obs, _ = env.reset(seed=0)
        assert obs.shape == (84, 84, channels) and obs.dtype == np.uint8
        assert env.observation_space.contains(env.step(1)[0])
    env = gym.make("Pinball-v0", obs_type="rgb", image_size=(64, 48))
    assert env.reset(seed=0)[0].shape == (64, 48, 3)
    env = gym.make("Pinball-v0", render_mode="rgb_array")
    env.reset(seed=0)
    frame = env.render()
    assert frame.dtype == np.uint8 and frame.ndim == 3 and frame.shape[2] == 3
    assert frame.shape[0] > frame.shape[1]  # the table is taller than wide


def rollout(env, seed, actions):
    out = []
    obs, info = env.reset(seed=seed)
    out.append((obs.copy(), 0.0, False, False, info))
    for action in actions:
        obs, reward, terminated, truncated, info = env.step(action)
        out.append((obs.copy(), reward, terminated, truncated, info))
        if terminated or truncated:
            obs, info = env.reset()
    return out


def assert_same_rollouts(a, b):
    assert len(a) == len(b)
    for (obs_a, r_a, te_a, tr_a, info_a), (obs_b, r_b, te_b, tr_b, info_b) in zip(
        a, b, strict=True
    ):
        assert obs_a.tobytes() == obs_b.tobytes()
        assert (r_a, te_a, tr_a) == (r_b, te_b, tr_b)
        assert info_a.keys() == info_b.keys()
        for key in info_a:
            if isinstance(info_a[key], np.ndarray):
                assert info_a[key].tobytes() == info_b[key].tobytes()
            else:
                assert info_a[key] == info_b[key]


@pytest.mark.parametrize("obs_type", OBS_TYPES)
def test_same_seed_and_actions_give_bitwise_identical_rollouts(obs_type):
    actions = np.random.default_rng(3).integers(0, 4, size=1500)
    a = rollout(gym.make("Pinball-v0", obs_type=obs_type), 11, actions)
    b = rollout(gym.make("Pinball-v0", obs_type=obs_type), 11, actions)
    assert_same_rollouts(a, b)
    c = rollout(gym.make("Pinball-v0", obs_type=obs_type), 12, actions)
    assert a[1][0].tobytes() != c[1][0].tobytes()  # another seed, another plunger shot


def test_rollouts_are_bitwise_identical_across_processes():
    def run():
        result = subprocess.run(
            [sys.executable, "-c", ROLLOUT_SCRIPT], cwd=ROOT, capture_output=True, text=True,
            check=True, timeout=300,
        )  # fmt: skip
        return result.stdout.strip()

    first, second = run(), run()
    assert first == second and len(first) == 64
    namespace = {"__name__": "in_process"}
    exec(ROLLOUT_SCRIPT, namespace)
    assert namespace["digest"]() == first


def test_env_pickles_and_the_copy_plays_on_identically():
    env = gym.make("Pinball-v0", render_mode="rgb_array")
    env.reset(seed=5)
    for _ in range(50):
        env.step(3)
    env.render()
    copy = pickle.loads(pickle.dumps(env))
    actions = np.random.default_rng(0).integers(0, 4, size=200)
    for action in actions:
        a, b = env.step(action), copy.step(action)
        assert a[0].tobytes() == b[0].tobytes() and a[1:4] == b[1:4]


def test_runs_in_sb3_subprocess_vec_env():
    make_vec_env = pytest.importorskip("stable_baselines3.common.env_util").make_vec_env
    from stable_baselines3.common.vec_env import SubprocVecEnv

    # "module:id" makes each worker process import pinball_env (and so register the env).
    vec = make_vec_env("pinball_env:Pinball-v0", n_envs=2, seed=0, vec_env_cls=SubprocVecEnv)
    try:
        obs = vec.reset()
        assert obs.shape == (2, 10)
        for _ in range(20):
            obs, _, _, infos = vec.step(np.array([1, 2]))
        assert obs.shape == (2, 10) and len(infos) == 2
    finally:
        vec.close()


# --- reset options ---------------------------------------------------------------------------


def test_reset_options_put_the_ball_where_asked():
    env = gym.make("Pinball-v0")
    options = {"ball_position": [0.12, 0.5], "ball_velocity": [0.5, -1.25]}
    obs, info = env.reset(seed=0, options=options)
    np.testing.assert_array_equal(info["ball_position"], [0.12, 0.5])
    np.testing.assert_array_equal(info["ball_velocity"], [0.5, -1.25])
    np.testing.assert_array_equal(obs[:4], np.float32([0.12, 0.5, 0.5, -1.25]))
    obs, _ = env.reset(options={"ball_position": [0.3, 0.45]})
    np.testing.assert_array_equal(obs[:4], np.float32([0.3, 0.45, 0.0, 0.0]))
    _, info = env.reset(options={"ball_velocity": [0.0, 2.0]})  # on the plunger, this speed
    np.testing.assert_array_equal(info["ball_position"], env.unwrapped.table.plunger.position)
    # The ball really moves from there as asked: first frame of free flight.
    _, info = env.reset(options={"ball_position": [0.2, 0.9], "ball_velocity": [0.0, 0.0]})
    _, _, _, _, info = env.step(0)
    assert info["ball_position"][1] < 0.9 and info["ball_position"][0] == 0.2


@pytest.mark.parametrize(
    ("options", "message"),
    [
        ({"ball_pos": [0.2, 0.6]}, "unknown reset option.*'ball_pos'"),
        ({"ball_position": [float("nan"), 0.6]}, r"ball_position\[0\].*finite"),
        ({"ball_velocity": [0.0, float("inf")]}, r"ball_velocity\[1\].*finite"),
        ({"ball_position": [0.2, 2.0]}, "outside the playfield"),
        ({"ball_position": [0.16, 0.72]}, "overlaps post 'bumper_left'"),
        ({"ball_position": [0.2]}, "pair"),
        ({"ball_position": [0.03, 1.05]}, "outside the table's outline"),  # above the arch
        ({"ball_velocity": [0.0, 150.0]}, "above 100 m/s"),
        ({"ball_position": [0.0964, 0.2585]}, "cannot be reached in play"),  # in a slingshot
        ({"ball_position": [0.2, 0.0186]}, "cannot be reached in play"),  # below the drain
    ],
)
def test_bad_reset_options_are_rejected_clearly(options, message):
    env = gym.make("Pinball-v0")
    env.reset(seed=0)
    twin = gym.make("Pinball-v0")
    twin.reset(seed=0)
    with pytest.raises(ValueError, match=message):
        env.reset(seed=1, options=options)
    # A rejected reset changes nothing: the env plays on exactly as its twin.
    for _ in range(20):
        assert env.step(1)[0].tobytes() == twin.step(1)[0].tobytes()


def test_reset_takes_the_ball_state_from_an_info():
    env = gym.make("Pinball-v0")
    _, info = env.reset(seed=0)
    for _ in range(40):
        _, _, _, _, info = env.step(0)
    options = {"ball_position": info["ball_position"], "ball_velocity": info["ball_velocity"]}
    _, again = env.reset(seed=0, options=options)
    np.testing.assert_array_equal(again["ball_position"], info["ball_position"])


# --- bad input -------------------------------------------------------------------------------


@pytest.mark.parametrize("action", [4, -1, 1.5, "left", None, np.array([1, 0])])
def test_discrete_action_outside_the_space_is_an_error(action):
    env = gym.make("Pinball-v0")
    env.reset(seed=0)
    with pytest.raises(ValueError, match="invalid action"):
        env.step(action)


@pytest.mark.parametrize("action", [[2, 0], [1, 0, 1], 1, [0.5, 0.5]])
def test_multibinary_action_outside_the_space_is_an_error(action):
    env = gym.make("Pinball-v0", action_type="multibinary")
    env.reset(seed=0)
    with pytest.raises(ValueError, match="invalid action"):
        env.step(action)


def without_drain():
    classic = load_table("classic")
    return dataclasses.replace(classic, sensors=classic.sensors[:-1])


@pytest.mark.parametrize(
    ("kwargs", "error", "message"),
    [
        ({"table": "clasic"}, TableError, "unknown table 'clasic'.*classic"),
        ({"obs_type": "pixels"}, ValueError, "obs_type must be one of"),
        ({"action_type": "box"}, ValueError, "action_type must be one of"),
        ({"render_mode": "ansi"}, ValueError, "render_mode must be one of"),
        ({"balls": 0}, ValueError, "balls must be"),
        ({"reward_scale": float("nan")}, ValueError, "reward_scale must be a finite"),
        (
            {"table": "box"},
            ValueError,
            "'box' cannot be played \\(it is a physics test rig\\): it has no plunger",
        ),
        ({"physics": "box2d"}, ValueError, "physics must be one of"),
        ({"table": without_drain()}, ValueError, "no drain sensor"),
    ],
)
@pytest.mark.filterwarnings("ignore:.*render_mode='ansi'")  # gymnasium's own warning first
def test_bad_arguments_are_rejected_clearly(kwargs, error, message):
    with pytest.raises(error, match=message):
        gym.make("Pinball-v0", **kwargs)


def test_unknown_keyword_is_an_error():
    with pytest.raises(TypeError, match="unexpected keyword"):
        gym.make("Pinball-v0", tabel="classic")


# --- rewards and episode end -----------------------------------------------------------------


def test_bumper_hit_rewards_its_points_times_the_scale():
    env = gym.make("Pinball-v0", reward_scale=0.01)
    env.reset(seed=0, options={"ball_position": [0.2365, 0.70], "ball_velocity": [0.0, -1.0]})
    for _ in range(30):
        _, reward, _, _, info = env.step(0)
        if info["events"]:
            break
    assert info["events"] == {"bumper_bottom": 1}
    assert info["points"] == 100 and reward == pytest.approx(1.0)
    assert info["score"] == 100


def test_height_shaping_rewards_the_rise_of_the_ball():
    env = gym.make("Pinball-v0", height_shaping=2.0)
    _, info = env.reset(seed=0, options={"ball_position": [0.2, 0.9], "ball_velocity": [0, 0]})
    y0 = info["ball_position"][1]
    _, reward, _, _, info = env.step(0)
    assert reward == pytest.approx(2.0 * (info["ball_position"][1] - y0) / 1.07)
    assert reward < 0  # falling


def test_game_ends_when_the_last_ball_drains():
    env = gym.make("Pinball-v0", balls=3)
    _, info = env.reset(seed=0)
    assert info["balls_left"] == 3
    drains = 0
    for ball in range(3):
        # Put the ball right above the drain, between the flippers, heading down.
        env.unwrapped.game.world.place_ball(0, (0.2365, 0.06), (0.0, -1.0))
        for _ in range(10):
            obs, _, terminated, truncated, info = env.step(0)
            if info["drained"]:
                drains += 1
                break
        assert info["balls_left"] == 2 - ball
        assert terminated == (ball == 2) and not truncated
    assert drains == 3
    assert obs[8] == 0.0 and obs[9] == 0.0  # no ball in play, none left


def test_episode_is_truncated_only_by_the_time_limit():
    env = gym.make("Pinball-v0", max_episode_steps=50)
    env.reset(seed=0)
    for step in range(50):
        _, _, terminated, truncated, _ = env.step(0)
        assert not terminated
        assert truncated == (step == 49)


@pytest.mark.slow
def test_observation_bounds_hold_over_long_random_rollouts():
    env = gym.make("Pinball-v0", max_episode_steps=100_000)
    space = env.observation_space
    rng = np.random.default_rng(0)
    obs, _ = env.reset(seed=0)
    action = 0
    for _ in range(30_000):
        if rng.random() < 0.1:
            action = int(rng.integers(4))
        obs, _, terminated, truncated, _ = env.step(action)
        assert space.contains(obs), obs
        if terminated or truncated:
            obs, _ = env.reset()
            assert space.contains(obs)


def play(policy, seed, steps=2400):
    env = gym.make("Pinball-v0", max_episode_steps=steps)
    _, info = env.reset(seed=seed)
    rng = np.random.default_rng(seed)
    heuristic = HeuristicPolicy(env.unwrapped.table)
    while True:
        action = heuristic(info) if policy == "heuristic" else int(rng.integers(4))
        _, _, terminated, truncated, info = env.step(action)
        if terminated or truncated:
            return info["score"]


@pytest.mark.slow
def test_heuristic_scores_more_than_random_on_average():
    seeds = range(20)
    heuristic = np.mean([play("heuristic", seed) for seed in seeds])
    random = np.mean([play("random", seed) for seed in seeds])
    assert heuristic > 1.2 * random


# --- rendering -------------------------------------------------------------------------------


def test_render_without_a_mode_warns_and_returns_none():
    env = gym.make("Pinball-v0")
    env.reset(seed=0)
    with pytest.warns(UserWarning, match="render_mode"):
        assert env.render() is None


def test_human_mode_opens_a_window_headless():
    env = gym.make("Pinball-v0", render_mode="human")
    env.reset(seed=0)
    for _ in range(3):
        env.step(3)
    assert env.unwrapped._window is not None
    env.close()


def test_demo_plays_headless_and_writes_a_snapshot(tmp_path):
    scores = demo_main(["--headless", "--max-steps", "300", "--snapshot", str(tmp_path / "d.png")])
    assert len(scores) == 1 and scores[0] >= 0
    assert (tmp_path / "d.png").stat().st_size > 0


def test_demo_module_runs_as_a_script(tmp_path):
    env = {**os.environ, "SDL_VIDEODRIVER": "dummy"}
    result = subprocess.run(
        [sys.executable, "-m", "pinball_env.tools.demo", "--max-steps", "120", "--snapshot",
         str(tmp_path / "demo.png")],
        cwd=ROOT, env=env, capture_output=True, text=True, timeout=300,
    )  # fmt: skip
    assert result.returncode == 0, result.stderr
    assert "game 1: score" in result.stdout


def test_height_shaping_sums_to_the_net_rise_of_each_ball():
    env = gym.make("Pinball-v0", reward_scale=0.0, height_shaping=1.0)
    start = [0.2365, 0.3]
    env.reset(seed=0, options={"ball_position": start, "ball_velocity": [0.0, 0.5]})
    total = 0.0
    for _ in range(600):
        _, reward, _, _, info = env.step(0)
        total += reward
        if info["drained"]:
            break
    assert info["drained"]
    drain_y = env.unwrapped.table.sensors[-1].points[0][1]
    assert total == pytest.approx((drain_y - start[1]) / env.unwrapped.table.height, abs=1e-12)


def test_reward_scale_accepts_numpy_numbers_and_rejects_bools():
    assert gym.make("Pinball-v0", reward_scale=np.float32(0.5)).unwrapped.reward_scale == 0.5
    with pytest.raises(ValueError, match="reward_scale must be a finite number"):
        gym.make("Pinball-v0", reward_scale=True)


def test_a_bool_action_is_the_discrete_action_it_equals():
    """Gymnasium's Discrete(4) contains True (== 1): it holds the left flipper, as 1 does."""
    envs = [gym.make("Pinball-v0") for _ in range(2)]
    for env in envs:
        env.reset(seed=3)
    for _ in range(5):
        as_bool, as_int = envs[0].step(True), envs[1].step(1)
        np.testing.assert_array_equal(as_bool[0], as_int[0])
    assert envs[0].action_space.contains(True)
