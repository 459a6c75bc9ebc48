"""observation_rows: one row per entry of the state observation, its bounds the space's own."""

import gymnasium as gym
import numpy as np
import pytest

import pinball_env  # noqa: F401  (registers the envs)
from pinball_env.envs import PinballVectorEnv
from pinball_env.observation import MAX_OBS_EXTRA_BALLS

CASES = [
    ("Pinball-v0", {}),
    ("Pinball-v1", {}),
    ("Pinball-v2", {}),
    ("Pinball-v3", {}),
    ("Pinball-v3", {"rays": 4}),
    ("PinballProcgen-v0", {"rays": 8}),
    ("Pinball-v0", {"rays": 5}),
]


def rows_of(env_id, **kwargs):
    env = gym.make(env_id, **kwargs).unwrapped
    rows, space = env.observation_rows, env.observation_space
    env.close()
    return rows, space


@pytest.mark.filterwarnings("ignore::DeprecationWarning")  # v0 and v1 are out of date
@pytest.mark.parametrize(("env_id", "kwargs"), CASES)
def test_rows_match_the_space(env_id, kwargs):
    rows, space = rows_of(env_id, **kwargs)
    assert len(rows) == space.shape[0]
    # The rows hold the space's float32 numbers exactly.
    np.testing.assert_array_equal(np.array([r.low for r in rows], np.float32), space.low)
    np.testing.assert_array_equal(np.array([r.high for r in rows], np.float32), space.high)
    assert [r.low for r in rows] == space.low.tolist()
    assert [r.high for r in rows] == space.high.tolist()
    meanings = [r.meaning for r in rows]
    assert all(meanings) and len(set(meanings)) == len(meanings)


@pytest.mark.filterwarnings("ignore::DeprecationWarning")
def test_rows_name_what_the_docstring_names():
    v0, _ = rows_of("Pinball-v0")
    x = v0[0]
    assert (x.meaning, x.low, x.high, x.unit) == ("ball x", 0.0, np.float32(0.51), "m")
    assert v0[4].meaning == "left flipper angle above rest" and v0[4].unit == "rad"
    assert v0[7].meaning == "right flipper angular velocity, + going up"
    assert v0[9].meaning.startswith("balls left, the one in play included")
    assert v0[9].high == 3.0 + MAX_OBS_EXTRA_BALLS  # extra balls can pass the game's three
    v1, _ = rows_of("Pinball-v1")
    assert v1[16].meaning.startswith("tilt warnings standing")
    table = gym.make("Pinball-v1").unwrapped.table  # every touch of the tilting frame counts
    assert v1[16].high == table.tilt.warnings + table.simulation.substeps
    assert v1[18].meaning == "light lane_1_lit lit (1) or not (0)"
    assert v1[21].meaning == "drop target drop_1 up (1) or down (0)"
    assert v1[27].meaning == "bonus multiplier" and (v1[27].low, v1[27].high) == (1.0, 5.0)
    assert v1[28].meaning == "end-of-ball bonus, in thousands (clipped to 100)"
    procgen, _ = rows_of("PinballProcgen-v0", rays=8)
    assert procgen[0].unit == "table widths" and procgen[4].unit == "swings"
    assert procgen[-1].meaning == "ray 7 distance (direction 315 deg from +x)"
    assert procgen[-1].unit == "0.5 m"


def test_vector_env_gives_one_envs_rows():
    env = PinballVectorEnv(num_envs=2, rays=2)
    rows = env.observation_rows
    env.close()
    assert len(rows) == env.single_observation_space.shape[0] == 12
    assert [r.high for r in rows] == env.single_observation_space.high.tolist()


@pytest.mark.parametrize("make", [gym.make, lambda env_id, **kw: gym.make_vec(env_id, 2, **kw)])
def test_image_observations_have_no_rows(make):
    env = make("PinballProcgen-v0", obs_type="grayscale", image_size=32).unwrapped
    with pytest.raises(AttributeError, match="obs_type='state'"):
        _ = env.observation_rows
    env.close()
