"""The agents that ship (agents/pretrained): each loads by name and scores as its card says."""

import pytest

from agents.config import ConfigError
from agents.policy import PRETRAINED, load_policy, pretrained_card
from agents.report import evaluate

pytestmark = pytest.mark.filterwarnings("ignore::DeprecationWarning")


def test_the_best_ppo_agents_ship():
    assert {"ppo-v0", "ppo-v1"} <= set(PRETRAINED)


@pytest.mark.parametrize("name", PRETRAINED)
def test_a_pretrained_agent_scores_as_its_card_says(name, tmp_path):
    card = pretrained_card(name)
    policy = load_policy(f"pretrained:{name}")
    assert policy.env_id == card["env_id"] and policy.config.seed == card["seed"]
    games = card["check_games"]
    summary = evaluate(model_path=f"pretrained:{name}", episodes=len(games["seeds"]),
                       protocol=True, out=tmp_path)  # fmt: skip
    assert summary["seeds"] == [games["seeds"][0], games["seeds"][-1]]
    scores = [int(line.split(",")[1]) for line in
              (tmp_path / "episodes.csv").read_text().splitlines()[1:]]  # fmt: skip
    assert scores == games["scores"]
    assert card["protocol"]["games"] == 100 and card["commit"]


def test_an_unknown_pretrained_agent_is_named_with_those_that_ship():
    with pytest.raises(ConfigError, match="pretrained:nope: no such pretrained agent"):
        load_policy("pretrained:nope")
