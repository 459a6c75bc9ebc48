"""The options, declared once (pinball_env.options): checked when made, without an env; the
envs, the Game and the training configs take them; the documented imports still work."""

import gymnasium as gym
import numpy as np
import pytest

import pinball_env  # noqa: F401  (registers the envs)
from pinball_env.envs import PinballEnv, PinballVectorEnv
from pinball_env.options import PinballOptions, VectorOptions, split_options


def test_defaults_are_the_registered_games():
    options = PinballOptions()
    assert options.table == "classic" and options.balls == 3 and options.image_size == (84, 84)
    assert not options.generated and PinballOptions(table="generated").generated
    assert VectorOptions().max_episode_steps == 7200 == gym.spec("Pinball-v0").max_episode_steps
    assert gym.spec("PinballProcgen-v0").kwargs == {"table": "generated"}


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"balls": 0}, "balls must be an integer >= 1, got 0"),
        ({"frame_skip": 61}, "frame_skip must be an integer from 1 to 60"),
        ({"reward_scale": float("inf")}, "reward_scale must be a finite number"),
        ({"obs_type": "pixels"}, "obs_type must be one of 'state', 'rgb', 'grayscale'"),
        ({"image_size": (8, 84)}, "image_size must be an int or"),
        ({"table": 3}, "table must be a table name"),
        ({"num_layouts": 4}, "num_layouts: options of generated tables"),
        ({"table": "generated", "physics": "pymunk"}, "plays one fixed table"),
        ({"rays": 4, "obs_type": "rgb"}, "rays are part of the state observation"),
        ({"repeat_action_probability": 1.0}, r"repeat_action_probability must be a number in \["),
        ({"repeat_action_probability": float("nan")}, "repeat_action_probability must be"),
    ],
)
def test_bad_options_are_clear_errors_before_anything_is_built(kwargs, message):
    with pytest.raises(ValueError, match=message):
        PinballOptions(**kwargs)


def test_unknown_options_are_named():
    with pytest.raises(TypeError, match=r"PinballEnv got unexpected keyword.*'flipper_power'"):
        PinballEnv(flipper_power=2)
    with pytest.raises(TypeError, match=r"PinballVectorEnv got unexpected keyword.*'envs'"):
        PinballVectorEnv(envs=2)
    with pytest.raises(ValueError, match="num_threads must be in"):
        VectorOptions(num_threads=0)


def test_a_vector_env_splits_its_options_and_the_single_env_takes_a_record():
    game, vector = split_options(
        "test", {"num_envs": 3, "frame_skip": 2, "autoreset_mode": "SameStep"}
    )
    assert game == PinballOptions(frame_skip=2) and vector.num_envs == 3
    assert vector.autoreset_mode == gym.vector.AutoresetMode.SAME_STEP
    env = PinballEnv(PinballOptions(frame_skip=4), balls=1)
    assert env.options == PinballOptions(frame_skip=4, balls=1) and env.game.frame_skip == 4


def test_rays_work_on_a_fixed_table_too():
    env = gym.make("Pinball-v0", rays=8)
    obs, _ = env.reset(seed=0)
    assert obs.shape == (18,) and env.observation_space.contains(obs)
    assert 0.0 < obs[10:].min() <= obs[10:].max() <= 1.0
    plain, _ = gym.make("Pinball-v0").reset(seed=0)
    assert obs[:10].tobytes() == plain.tobytes()


def test_a_config_checks_its_env_options_without_building_an_env(monkeypatch):
    pytest.importorskip("torch", reason="the agents' extra (a config checks its torch device)")
    from agents.config import ConfigError, config_from_dict
    from pinball_env.envs import core

    def no_env(*args, **kwargs):
        raise AssertionError("an env was built to check a config")

    monkeypatch.setattr(core.PinballCore, "__init__", no_env)
    config_from_dict({"env": {"kwargs": {"frame_skip": 4, "rays": 8}}})
    config_from_dict({"env": {"id": "PinballProcgen-v0", "kwargs": {"num_layouts": 16}}})
    with pytest.raises(ConfigError, match="frame_skip must be an integer from 1 to 60"):
        config_from_dict({"env": {"kwargs": {"frame_skip": 0}}})
    with pytest.raises(ConfigError, match=r"env\.kwargs\.table: not a training option"):
        config_from_dict({"env": {"id": "PinballProcgen-v0", "kwargs": {"table": "classic"}}})


def test_the_documented_imports_still_work():
    from pinball_env.game import Game
    from pinball_env.physics import step_world, sweep_circle_segment
    from pinball_env.players import HeuristicPolicy
    from pinball_env.procgen import generate_table
    from pinball_env.sim import World
    from pinball_env.table import TableError, dump_table, load_table

    # The gym.make ids build the classes of their one home.
    assert isinstance(gym.make("Pinball-v0").unwrapped, PinballEnv)
    assert gym.spec("Pinball-v0").vector_entry_point == "pinball_env.envs:PinballVectorEnv"
    assert callable(step_world) and callable(sweep_circle_segment) and callable(dump_table)
    assert issubclass(TableError, ValueError)
    world = World(load_table("classic"), n_envs=2)
    world.place_ball(0, (0.25, 0.5))
    world.launch(1, 2.5)
    world.step(np.zeros((2, 2), dtype=bool))
    assert world.balls.shape[0] == 2
    game = Game(load_table("classic"), n_envs=1)
    # A ball high over the middle, falling: nothing to flip.
    pressed = HeuristicPolicy(game.table).buttons(np.array([0.24, 0.7]), np.array([0.0, -1.0]))
    assert pressed.dtype == bool and not pressed.any()
    assert generate_table(3).name == "procgen:3"


def test_the_documented_sb3_adapter_imports():
    pytest.importorskip("stable_baselines3", reason="the wrappers extra")
    from pinball_env.wrappers import SB3VecEnv

    assert SB3VecEnv.__name__ == "SB3VecEnv"
