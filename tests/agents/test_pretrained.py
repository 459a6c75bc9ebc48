"""The agents that ship (agents/pretrained): each loads by name and scores as its card says."""

import json
from pathlib import Path

import pytest

from agents.config import ConfigError
from agents.evaluation import evaluate_protocol, player_for
from agents.policy import (
    PRETRAINED,
    PRETRAINED_ALIASES,
    PRETRAINED_DIR,
    PRETRAINED_PREFIX,
    load_policy,
    pretrained_card,
    resolve_model_path,
)

pytestmark = pytest.mark.filterwarnings("ignore::DeprecationWarning")


def test_the_best_ppo_agents_ship():
    assert {"ppo-v0", "ppo-v1"} <= set(PRETRAINED)


def test_each_agent_ships_under_its_methods_name_and_its_old_name_still_loads_it():
    for model in PRETRAINED_DIR.glob("*.zip"):
        card = pretrained_card(model.stem)
        assert card["name"] == card["method"] == model.stem
    for alias, name in PRETRAINED_ALIASES.items():
        assert not (PRETRAINED_DIR / f"{alias}.zip").exists()  # (one file, one name)
        assert resolve_model_path(PRETRAINED_PREFIX + alias) == PRETRAINED_DIR / f"{name}.zip"
        assert pretrained_card(alias) == pretrained_card(name)


@pytest.mark.parametrize("name", PRETRAINED)
def test_a_pretrained_agent_scores_as_its_card_says(name, tmp_path):
    card = pretrained_card(name)
    policy = load_policy(f"pretrained:{name}")
    assert policy.env_id == card["env_id"] and policy.config.seed == card["seed"]
    games = card["check_games"]
    player = player_for(model_path=f"pretrained:{name}")
    summary = evaluate_protocol(player, tmp_path, episodes=len(games["seeds"]))
    assert summary["seeds"] == [games["seeds"][0], games["seeds"][-1]]
    scores = [int(line.split(",")[1]) for line in
              (tmp_path / "episodes.csv").read_text().splitlines()[1:]]  # fmt: skip
    assert scores == games["scores"]
    assert card["protocol"]["games"] == 100 and card["commit"]


@pytest.mark.parametrize("name", PRETRAINED)
def test_a_pretrained_agent_is_a_published_run(name):
    # Its card's figures are those of its run in the published table (docs/benchmark.json).
    card = pretrained_card(name)
    published = Path(__file__).resolve().parents[2] / "docs" / "benchmark.json"
    runs = json.loads(published.read_text())["methods"][card.get("method", name)]["runs"]
    (run,) = [run for run in runs if run["seed"] == card["seed"]]
    assert (run["commit"], run["frames"], run["steps"]) == (
        card["commit"], card["trained"]["frames"], card["trained"]["steps"])  # fmt: skip
    assert (run["score_mean"], run["score_iqm"]) == (
        card["protocol"]["score_mean"], card["protocol"]["score_iqm"])  # fmt: skip
    assert run["scores"][: len(card["check_games"]["scores"])] == card["check_games"]["scores"]


def test_an_unknown_pretrained_agent_is_named_with_those_that_ship():
    with pytest.raises(ConfigError, match="pretrained:nope: no such pretrained agent"):
        load_policy("pretrained:nope")
