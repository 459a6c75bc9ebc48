"""The loader of ``python -m pinball_env.tools.serve --model RUN_OR_ZIP``: a trained agent
playing in the browser.

    python -m pinball_env.tools.serve --model pretrained:ppo-gentle-v1 --games 3

The tool finds :func:`agent_players` through its entry point (group
``pinball_env.agent_loaders``, pyproject.toml), since the package never imports ``agents``. It
loads the agent saved at ``--model`` (what :func:`agents.policy.load_policy` takes: a run folder,
a model or checkpoint zip, an RLlib checkpoint, ``pretrained:NAME``) once, from that path only,
before the server starts; each game is played through the env chain the agent was trained on,
greedy.
"""

from collections.abc import Callable

from agents.config import ConfigError
from agents.policy import Policy, load_policy
from pinball_env.tools.web.sessions import WatchedPlayer


def agent_player(policy: Policy) -> WatchedPlayer:
    """A game of ``policy``'s env chain, played by it (greedy)."""
    return WatchedPlayer(policy.make_env(), lambda obs, info: policy.act(obs))


def agent_players(model: str) -> tuple[Callable[[], WatchedPlayer], str]:
    """A maker of games played by the agent at ``model`` and its env id; SystemExit naming the
    problem where it cannot be loaded."""
    try:
        policy = load_policy(model)
    except (ConfigError, ValueError, OSError) as error:
        raise SystemExit(f"cannot load the agent {model}: {error}") from None
    return (lambda: agent_player(policy)), policy.env_id
