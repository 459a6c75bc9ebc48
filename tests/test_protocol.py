"""The benchmark protocol's constants and metrics (pinball_env.protocol)."""

import gymnasium as gym
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pinball_env import protocol

scores_lists = st.lists(st.integers(0, 200_000), min_size=1, max_size=60)


def test_the_protocol_envs_take_its_options():
    for env_id in protocol.PROTOCOL_ENV_IDS:
        options = protocol.protocol_options(env_id, {"obs_type": "state", "skip_above": 0.3})
        assert options["repeat_action_probability"] == protocol.REPEAT_ACTION_PROBABILITY == 0.25
        env = gym.make(env_id, **options)
        assert env.unwrapped.game.repeat_action_probability == 0.25
        assert env.unwrapped.game.balls_per_game == 3 and env.unwrapped.game.max_frames == 7200
    assert protocol.TRAINING_FRAMES > 0 and len(protocol.TRAINING_SEEDS) >= 5
    assert range(100_000, 100_100) == protocol.EVAL_SEEDS


@pytest.mark.parametrize(
    ("env_id", "options", "message"),
    [
        ("Pinball-v1", {"balls": 1}, "balls=1"),
        ("Pinball-v1", {"table": "classic"}, "table='classic'"),
        ("Pinball-v0", {"max_frames": 100}, "max_frames=100"),
        ("Pinball-v0", {"physics": "pymunk"}, "physics='pymunk'"),
        ("Pinball-v0", {"max_episode_steps": 500}, "max_episode_steps=500"),
        ("PinballProcgen-v0", {}, "not an env of the protocol"),
    ],
)
def test_options_that_change_the_game_are_refused(env_id, options, message):
    with pytest.raises(ValueError, match=message):
        protocol.protocol_options(env_id, options)


def test_the_envs_own_table_and_any_sticky_training_are_the_agents_business():
    options = protocol.protocol_options(
        "Pinball-v0", {"table": "classic", "repeat_action_probability": 0.1}
    )
    assert "table" not in options and options["repeat_action_probability"] == 0.25


def test_iqm_is_the_mean_of_the_middle_half():
    assert protocol.iqm(np.arange(100)) == 49.5  # 25..74
    assert protocol.iqm([1, 2, 3, 1000]) == 2.5  # a quarter (one) cut from each end
    assert protocol.iqm([7]) == 7.0


@given(st.lists(scores_lists, min_size=1, max_size=5))
@settings(max_examples=40, deadline=None)
def test_bootstrap_intervals_lie_within_the_scores_and_repeat(runs):
    pooled = np.concatenate([np.asarray(run, dtype=float) for run in runs])
    for statistic in (np.mean, protocol.iqm):
        low, high = protocol.bootstrap_interval(runs, statistic, samples=300)
        assert pooled.min() <= low <= high <= pooled.max()
        assert protocol.bootstrap_interval(runs, statistic, samples=300) == (low, high)
    constant = [np.full(len(run), 5.0) for run in runs]
    assert protocol.bootstrap_interval(constant, samples=50) == (5.0, 5.0)


def test_more_games_and_seeds_narrow_the_interval():
    rng = np.random.default_rng(0)
    few = [rng.normal(100, 30, 20) for _ in range(2)]
    many = [rng.normal(100, 30, 200) for _ in range(8)]
    width = [np.subtract(*protocol.bootstrap_interval(r)[::-1]) for r in (few, many)]
    assert width[1] < width[0] / 3
    low, high = protocol.bootstrap_interval(many, np.mean)
    assert low < 100 < high


def test_the_interval_holds_the_seeds_spread_not_only_the_games():
    # Two seeds far apart, each with games that barely vary: the games alone would give a
    # narrow interval; resampling the seeds gives one spanning both.
    runs = [np.full(100, 10.0) + np.arange(100) * 1e-3, np.full(100, 90.0)]
    low, high = protocol.bootstrap_interval(runs, np.mean)
    assert low < 20 and high > 80


@given(st.lists(scores_lists, min_size=1, max_size=4))
@settings(max_examples=40, deadline=None)
def test_a_performance_profile_falls_from_one_to_zero(runs):
    normalized = [protocol.normalized(run, "Pinball-v1") for run in runs]
    taus = np.linspace(-5, 50, 200)
    curve = protocol.performance_profile(normalized, taus)
    assert curve[0] == 1.0 and curve[-1] == 0.0
    assert np.all(np.diff(curve) <= 0)
    low, high = protocol.profile_band(normalized, taus, samples=50)
    assert np.all(low <= high) and np.all((low >= 0) & (high <= 1))


def test_normalised_scores_put_random_at_0_and_the_heuristic_at_1():
    for env_id, reference in protocol.REFERENCE_SCORES.items():
        values = protocol.normalized([reference["random"], reference["heuristic"]], env_id)
        assert np.allclose(values, [0.0, 1.0])
        assert reference["heuristic"] > reference["random"]


def test_aggregate_gives_every_metric_with_its_interval():
    runs = [[1000, 5000, 9000, 20000], [3000, 4000, 60000, 7000]]
    result = protocol.aggregate(runs, "Pinball-v0")
    assert result["runs"] == 2 and result["games"] == 8
    assert result["score_mean"] == np.mean(np.concatenate(runs))
    for key in ("score_mean", "score_iqm", "normalized_mean", "normalized_iqm"):
        low, high = result[f"{key}_ci95"]
        assert low <= result[key] <= high
    assert result["normalized_mean"] == pytest.approx(
        float(np.mean(protocol.normalized(np.concatenate(runs), "Pinball-v0")))
    )
