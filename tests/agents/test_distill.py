"""The planner distilled into a policy (agents.distill): its config's checks, and a tiny
DAgger run whose model loads as any trained agent's and whose rows say what it did."""

import csv
import json
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest

from agents import distill
from agents.config import ConfigError, load_run_config
from agents.policy import load_policy
from pinball_env.players import HeuristicPolicy

CONFIG = Path(__file__).resolve().parents[2] / "configs" / "distill" / "search_v3.yaml"
TINY = ["iterations=2", "env.num_envs=2", "validate_episodes=2", "epochs=1",
        "teacher={horizon: 4, holds: [1]}", "env.kwargs.max_frames=600"]  # fmt: skip


def test_bad_configs_are_refused_with_the_key_that_is_wrong():
    for override, message in (("iterations=0", "iterations"),
                              ("colour=red", "unknown key 'colour'"),
                              ("teacher={horizon: 0}", "teacher: horizon"),
                              ("env.speed=2", "unknown key 'env.speed'"),
                              ("learning_rate=-1", "learning_rate"),
                              ("balance=1.5", "balance"),
                              ("total_frames=-1", "total_frames"),
                              ("seed=10", "reach the validation or evaluation games"),
                              ("iterations=700", "another seed's")):  # fmt: skip
        with pytest.raises(ConfigError, match=message):
            distill.load_distill_config(CONFIG, [override])
    assert distill.load_distill_config(CONFIG).learner().algo == "ppo"


def test_a_tiny_distillation_labels_fits_validates_and_saves_a_loadable_policy(tmp_path):
    config = distill.load_distill_config(CONFIG, TINY)
    run = distill.distill(config, tmp_path, ["test"])
    with open(run / distill.ITERATIONS_FILE) as file:
        rows = list(csv.DictReader(file))
    assert [row["player"] for row in rows] == ["teacher", "learner"]
    assert float(rows[0]["agreement"]) == 1.0 and 0.0 <= float(rows[1]["agreement"]) <= 1.0
    # The data set aggregates: the second fit saw both iterations' steps.
    assert int(rows[1]["data"]) == int(rows[0]["steps"]) + int(rows[1]["steps"])
    assert int(rows[0]["steps"]) == 2 * 600  # (two games of 600 frames, every frame labelled)
    # Its frames: the games' (600 each) and the planner's branches' (where it looked ahead).
    assert int(rows[0]["frames"]) > 2 * 600 and int(rows[1]["frames"]) >= 2 * 600
    trained = json.loads((run / "meta.json").read_text())["trained"]
    assert trained == {"steps": 2 * 1200, "frames": sum(int(row["frames"]) for row in rows)}
    assert load_run_config(run).env.id == "Pinball-v3"
    assert distill.load_distill_config(run / distill.DISTILL_FILE) == config
    policy = load_policy(run)
    env = gym.make("Pinball-v3", max_frames=600, ball_order="lowest")
    obs, _ = env.reset(seed=300_000)
    assert policy.act(policy.normalization(obs[None]))[0] in range(env.action_space.n)


def test_the_heuristic_follows_the_flippers_another_player_pressed():
    # After played(action), each flipper's held count is the steps its button has been held
    # in a row by the actions played, whatever the heuristic itself answered.
    env = gym.make("Pinball-v3")
    heuristic = HeuristicPolicy(env.unwrapped.table)
    _, info = env.reset(seed=4)
    rng = np.random.default_rng(0)
    in_a_row = [0, 0]
    for _ in range(400):
        heuristic(info)
        played = int(rng.integers(4))
        heuristic.played(played)
        in_a_row = [count + 1 if played >> j & 1 else 0 for j, count in enumerate(in_a_row)]
        assert heuristic._held == in_a_row
        info = env.step(played)[4]


def test_the_class_weights_even_out_the_actions_shares():
    labels = np.array([0] * 90 + [1] * 9 + [3])
    assert distill.class_weights(labels, 4, 0.0) is None
    weights = distill.class_weights(labels, 4, 1.0)
    counts = np.bincount(labels, minlength=4)
    # Fully balanced: every labelled action weighs as much in all; one never labelled, nothing.
    totals = weights * counts
    assert np.allclose(totals[counts > 0], totals[0]) and weights[2] == 0.0
    half = distill.class_weights(labels, 4, 0.5)
    assert np.allclose(half[[0, 1, 3]], np.sqrt(weights[[0, 1, 3]]))
