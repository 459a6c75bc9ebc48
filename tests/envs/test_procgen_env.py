"""PinballProcgen-v0: layouts per game, fixed spaces, rays, and the vector env of many tables."""

import math

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

import pinball_env  # noqa: F401  (registers the envs)
from pinball_env.envs import PinballEnv, PinballVectorEnv, layout_table
from pinball_env.options import PinballOptions
from pinball_env.physics.rays import (
    RAY_RANGE,
    cast_rays,
    ray_circle,
    ray_directions,
    ray_flipper,
    ray_segment,
)
from pinball_env.table import load_any_table, load_table


def procgen_env(**kwargs):  # the env PinballProcgen-v0 makes
    return PinballEnv(table="generated", **kwargs)


def procgen_vector_env(**kwargs):
    return PinballVectorEnv(table="generated", **kwargs)


INFO_KEYS = ("ball_position", "ball_velocity", "score", "balls_left", "points", "drained",
             "frames", "layout")  # fmt: skip


@pytest.mark.parametrize(
    "kwargs",
    [
        {"num_layouts": 3, "rays": 8},
        {"obs_type": "grayscale", "image_size": 48, "difficulty": "hard"},
        {"num_layouts": 0, "start_layout": 1000, "frame_skip": 2, "skip_above": 0.3,
         "drain_penalty": 2.0, "max_frames": 1200},
    ],
)  # fmt: skip
def test_check_env_passes_without_warnings(kwargs):
    with pytest.warns() as record:
        check_env(procgen_env(**kwargs), skip_render_check=True)
        import warnings

        warnings.warn("sentinel", stacklevel=1)
    assert [str(w.message) for w in record] == ["sentinel"]


@pytest.mark.parametrize(
    "kwargs",
    [
        {"num_layouts": 4, "rays": 6, "balls": 1, "max_episode_steps": 300},
        {"num_layouts": 0, "difficulty": "hard", "frame_skip": 2, "skip_above": 0.3,
         "balls": 1, "max_frames": 900, "max_episode_steps": None},
        {"num_layouts": 2, "obs_type": "rgb", "image_size": 32, "balls": 1,
         "max_episode_steps": 200},
    ],
)  # fmt: skip
def test_the_vector_env_of_many_tables_is_bitwise_n_single_envs(kwargs):
    n, steps, seed = 4, 700, 5
    vector = gym.make_vec("PinballProcgen-v0", num_envs=n, **kwargs)
    assert isinstance(vector, PinballVectorEnv)
    singles = [gym.make("PinballProcgen-v0", **kwargs) for _ in range(n)]
    obs, infos = vector.reset(seed=seed)
    for env, single in enumerate(singles):
        obs1, info1 = single.reset(seed=seed + env)
        assert obs[env].tobytes() == obs1.tobytes()
        assert infos["layout"][env] == info1["layout"]
    ended = np.zeros(n, dtype=bool)
    layouts, ends = set(infos["layout"]), 0
    vector.action_space.seed(1)
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
        layouts |= set(infos["layout"])
    assert ends >= n and len(layouts) > 1  # games ended, and new layouts were drawn


def test_layouts_come_from_the_env_range_and_can_be_chosen():
    env = procgen_env(num_layouts=3, start_layout=40)
    seen = {env.reset(seed=s)[1]["layout"] for s in range(30)}
    assert seen == {40, 41, 42}
    _, info = env.reset(options={"layout": 41})
    assert info["layout"] == 41 and env.unwrapped.table.name == "procgen:41"
    for bad in (39, 43, 41.0, "41"):
        with pytest.raises(ValueError, match=r"layout must be an integer in \[40, 43\)"):
            env.reset(options={"layout": bad})
    one = procgen_env(num_layouts=1, start_layout=7, difficulty="hard")
    assert {one.reset(seed=s)[1]["layout"] for s in range(5)} == {7}
    assert one.table == layout_table(7, "hard")


def test_the_vector_env_plays_the_layouts_it_is_given():
    vector = procgen_vector_env(num_envs=3, num_layouts=100, start_layout=500)
    _, infos = vector.reset(seed=0, options={"layout": [510, 520, 530]})
    assert list(infos["layout"]) == [510, 520, 530]
    assert [vector.game.world.table_of(i).name for i in range(3)] == [
        "procgen:510", "procgen:520", "procgen:530",
    ]  # fmt: skip
    with pytest.raises(ValueError, match="one per env"):
        vector.reset(options={"layout": [510, 520]})


def test_observations_keep_their_bounds_on_every_layout():
    env = procgen_env(num_layouts=0, rays=12, difficulty="hard", frame_skip=4)
    space = env.observation_space
    assert space.shape == (10 + 12,)
    env.action_space.seed(0)
    for seed in range(6):
        obs, _ = env.reset(seed=seed)
        for _ in range(150):
            assert space.contains(obs), obs
            obs, *_ = env.step(env.action_space.sample())


def test_rays_measure_the_distance_to_the_first_element():
    table = load_table("classic")
    geometry = table.pack()
    rest = np.radians([f.rest_angle for f in table.flippers])
    out = np.zeros(4)
    x, y = 0.2365, 0.45  # on the centre line, below the bottom bumper
    cast_rays(x, y, ray_directions(4), geometry, rest, out, *ray_work(geometry))
    up = 0.62 - 0.03 - y  # the bottom bumper's skirt
    left = x - 0.005  # the cabinet's left side (nothing in between at this height)
    assert out[1] == pytest.approx(up / RAY_RANGE)
    assert out[2] == pytest.approx(left / RAY_RANGE)
    assert out[0] == pytest.approx((0.468 - x) / RAY_RANGE)  # the shooter lane's wall
    # Down the centre line: between the flippers' tips, down to the drain area's floor (the
    # outline's bottom at y = 0.005), beyond RAY_RANGE? No: 0.445 m, within it.
    assert out[3] == pytest.approx((y - 0.005) / RAY_RANGE)
    cast_rays(x, 0.08, ray_directions(8), geometry, rest, out := np.zeros(8), *ray_work(geometry))
    assert math.isclose(out[0], out[4], rel_tol=1e-9)  # the flippers are mirror images


def ray_work(geometry) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """cast_rays's work arrays for ``geometry``."""
    size = sum(len(a) for a in (geometry.segments, geometry.circles, geometry.flippers))
    return np.empty(size), np.empty(size, dtype=np.int64), np.empty((len(geometry.flippers), 2))


def rays_of_everything(x, y, n_rays, geometry, angles) -> np.ndarray:
    """cast_rays's distances by testing every element for every ray (its tests, in Python)."""
    out = np.empty(n_rays)
    for k in range(n_rays):
        a = 2.0 * math.pi * k / n_rays
        dx, dy = math.cos(a), math.sin(a)
        hits = [ray_segment.py_func(x, y, dx, dy, *s) for s in geometry.segments]
        hits += [ray_circle.py_func(x, y, dx, dy, *c) for c in geometry.circles]
        hits += [ray_flipper.py_func(x, y, dx, dy, f, math.cos(angle), math.sin(angle))
                 for f, angle in zip(geometry.flippers, angles, strict=True)]  # fmt: skip
        out[k] = min([RAY_RANGE, *hits]) / RAY_RANGE
    return out


@pytest.mark.parametrize("name", ["classic", "classic_v1", "procgen:3", "procgen:11"])
def test_rays_read_bitwise_what_testing_every_element_reads(name):
    table = load_any_table(name)
    geometry = table.pack()
    rng = np.random.default_rng(0)
    angles = np.radians([f.rest_angle for f in table.flippers])
    for _ in range(40):
        x, y = rng.uniform(-0.1, table.width + 0.1), rng.uniform(-0.1, table.height + 0.1)
        angles = angles + rng.uniform(-0.5, 0.5, size=len(angles))
        out = np.zeros(16)
        cast_rays(x, y, ray_directions(16), geometry, angles, out, *ray_work(geometry))
        np.testing.assert_array_equal(out, rays_of_everything(x, y, 16, geometry, angles))


def test_the_procgen_env_is_in_gymnasiums_registry():
    spec = gym.spec("PinballProcgen-v0")
    assert spec.max_episode_steps == 7200
    env = gym.make("PinballProcgen-v0", num_layouts=2)
    assert isinstance(env.unwrapped, PinballEnv) and env.unwrapped.layouts is not None


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"num_layouts": -1}, "num_layouts must be an integer >= 0"),
        ({"start_layout": 1.5}, "start_layout must be an integer >= 0"),
        ({"start_layout": 2**63 - 10, "num_layouts": 0}, "beyond seed"),
        ({"difficulty": "medium"}, "difficulty must be one of"),
        ({"rays": 65}, r"rays must be in \[0, 64\]"),
        ({"rays": 8, "obs_type": "rgb"}, "rays are part of the state observation"),
    ],
)
def test_bad_procgen_options_are_clear_errors(kwargs, message):
    with pytest.raises(ValueError, match=message):
        procgen_env(**kwargs)
    with pytest.raises(ValueError, match=message):
        procgen_vector_env(num_envs=2, **kwargs)
    with pytest.raises(ValueError, match=message):  # the options alone, before any env is built
        PinballOptions(table="generated", **kwargs)


def test_a_reset_generates_its_tables_together_and_shows_progress(monkeypatch, capsys):
    from pinball_env.envs import layouts
    from pinball_env.procgen import generate_table

    monkeypatch.setattr(layouts, "PROGRESS_AFTER", 0.0)  # show it however quick
    monkeypatch.setattr(layouts, "PROGRESS_EVERY", 0.0)
    vector = procgen_vector_env(num_envs=4, num_layouts=0, start_layout=7_000_000)
    capsys.readouterr()
    _, infos = vector.reset(seed=0)
    layouts = sorted(set(infos["layout"].tolist()))
    shown = capsys.readouterr().err.replace("\r", "\n").splitlines()
    count = len(layouts)
    assert count > 1 and f"generating {count} easy tables: {count}/{count}" in shown
    for env, layout in enumerate(infos["layout"]):
        assert vector.get_attr("table")[env] is layout_table(int(layout), "easy")
    assert vector.get_attr("table")[0] == generate_table(int(infos["layout"][0]))
