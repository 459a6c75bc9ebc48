"""Agents that travel: ``agents.policy.load_policy`` plays plain ``gym.make`` games exactly as
``agents.evaluate`` does, from a run folder, a zip copied alone, a checkpoint; and says what is
missing when it cannot."""

import csv
import shutil
import zipfile
from pathlib import Path

import numpy as np
import pytest

from agents import evaluate
from agents.config import ConfigError
from agents.policy import load_policy
from agents.runs import AGENT_ENTRY
from tests.agents.tiny_runs import ROOT, readme_example, strip_agent_entry, tiny_run

EPISODES = 3


def evaluated_scores(path: Path, out: Path) -> list[int]:
    evaluate.main(["--model", str(path), "--episodes", str(EPISODES), "--out", str(out)])
    with open(out / "episodes.csv") as file:
        return [int(row["score"]) for row in csv.DictReader(file)]


@pytest.fixture(scope="module")
def ppo_run(tmp_path_factory) -> Path:
    """A tiny PPO run of the shipped config (normalised state observations, skip_above)."""
    return tiny_run(ROOT / "configs/agents/ppo.yaml", tmp_path_factory.mktemp("runs"))


def test_the_readme_example_scores_the_games_of_agents_evaluate(ppo_run, tmp_path):
    expected = evaluated_scores(ppo_run, tmp_path / "eval")
    scores = [readme_example(ppo_run, 100_000 + game) for game in range(EPISODES)]
    assert scores == expected
    # The native vector env of the same chain plays them alike.
    policy = load_policy(ppo_run)
    venv = policy.make_vec(EPISODES)
    obs, _ = venv.reset(seed=100_000)
    final = [None] * EPISODES
    while any(score is None for score in final):
        obs, _, terminated, truncated, infos = venv.step(policy.act(obs))
        for env in np.flatnonzero(terminated | truncated):
            if final[env] is None:
                final[env] = int(infos["score"][env])
    venv.close()
    assert final == expected


def test_a_model_zip_copied_alone_carries_its_config_and_statistics(ppo_run, tmp_path):
    alone = tmp_path / "elsewhere" / "agent.zip"
    alone.parent.mkdir()
    shutil.copy(ppo_run / "model.zip", alone)
    policy = load_policy(alone)
    assert policy.env_id == "Pinball-v0" and policy.env_kwargs["skip_above"] > 0
    assert policy.normalization is not None
    trained = load_policy(ppo_run)
    np.testing.assert_array_equal(policy.normalization.scale, trained.normalization.scale)
    assert readme_example(alone, 100_000) == readme_example(ppo_run, 100_000)


def test_an_older_zip_alone_names_what_is_missing(ppo_run, tmp_path):
    alone = tmp_path / "model.zip"
    shutil.copy(ppo_run / "model.zip", alone)
    strip_agent_entry(alone)
    with pytest.raises(ConfigError, match=r"no config\.yaml is beside it"):
        load_policy(alone)
    shutil.copy(ppo_run / "config.yaml", tmp_path / "config.yaml")
    with pytest.raises(ConfigError, match="VecNormalize statistics are missing"):
        load_policy(alone)
    shutil.copy(ppo_run / "model_vecnormalize.pkl", tmp_path / "model_vecnormalize.pkl")
    assert readme_example(alone, 100_000) == readme_example(ppo_run, 100_000)


def test_checkpoints_and_a_run_without_its_model_load(ppo_run, tmp_path):
    run = tmp_path / "run"
    shutil.copytree(ppo_run, run)
    (run / "model.zip").unlink()  # stopped before the end: the newest checkpoint plays
    policy = load_policy(run)
    assert policy.source == run / "checkpoints" / "step_256.zip"
    assert load_policy(run / "checkpoints" / "step_128.zip").model.num_timesteps == 128
    with zipfile.ZipFile(run / "checkpoints" / "step_128.zip") as archive:
        assert AGENT_ENTRY in archive.namelist()
    with pytest.raises(ConfigError, match="no such file"):
        load_policy(tmp_path / "nothing")
    shutil.rmtree(run / "checkpoints")
    with pytest.raises(ConfigError, match=r"no model\.zip and no checkpoint"):
        load_policy(run)


def test_act_takes_one_observation_or_a_batch(ppo_run):
    policy = load_policy(ppo_run)
    env = policy.make_env()
    obs, _ = env.reset(seed=7)
    action = policy.act(obs)
    assert isinstance(action, int) and env.action_space.contains(action)
    batch = np.stack([obs, obs, obs])
    np.testing.assert_array_equal(policy.act(batch), [action] * 3)
    assert env.observation_space.contains(obs) and obs.dtype == np.float32
    with pytest.raises(ValueError, match="not the policy's"):
        policy.make_env(obs_type="grayscale")


def test_a_pixel_agent_plays_through_its_frame_stack(tmp_path):
    run = tiny_run(ROOT / "configs/agents/ppo_pixels.yaml", tmp_path / "runs")
    policy = load_policy(run)
    env = policy.make_env()
    obs, _ = env.reset(seed=100_000)
    assert (
        obs.shape == (4, 84, 84) == policy.model.observation_space.shape
    )  # 4 frames, channels first
    assert not obs[:3].any() and obs[3].any()  # zero-padded at the start, as VecFrameStack
    expected = evaluated_scores(run, tmp_path / "eval")
    assert [readme_example(run, 100_000 + game) for game in range(EPISODES)] == expected


def test_a_recurrent_agent_carries_its_memory_from_step_to_step_until_reset(tmp_path):
    # RecurrentPPO's LSTM state is threaded through act() as model.predict threads it by hand,
    # each env its own, from a fresh memory at the first step and again after reset().
    run = tiny_run(ROOT / "configs/agents/recurrent_ppo_v3.yaml", tmp_path / "runs")
    policy = load_policy(run)
    venv = policy.make_vec(2)
    obs, _ = venv.reset(seed=[100_000, 100_001])
    model, state, starts = policy.model, None, np.ones(2, dtype=bool)
    first = None
    for _ in range(30):
        expected, state = model.predict(obs, state=state, episode_start=starts, deterministic=True)
        starts[:] = False
        actions = policy.act(obs)
        assert (actions == expected).all()
        first = expected if first is None else first
        obs = venv.step(actions)[0]
    obs, _ = venv.reset(seed=[100_000, 100_001])
    policy.reset()
    assert (policy.act(obs) == first).all()  # a fresh memory, the same first games
    assert policy._act.recurrent and policy._act._state is not None
    venv.close()
