"""Whole games, their summary, and who plays them: the baselines (``random``, ``heuristic``; and
``search``, the planner that looks ahead in the simulator: a reference, not a learner) and
trained agents (loaded by ``agents.policy.load_policy``), each as a policy over a VecEnv of the
env chain (``agents.envs.make_env_chain``)."""

import dataclasses
import math
from collections.abc import Callable
from functools import partial
from pathlib import Path
from typing import Any

import numpy as np

from agents.config import AnyConfig, ConfigError, TrainConfig, config_from_dict
from agents.envs import make_env_chain, native_env
from agents.policy import ObsNormalization, Predictor, load_policy
from pinball_env.players import HeuristicPolicy, RandomPolicy, VectorSearch

BASELINES = ("random", "heuristic")
# Players that use the simulator itself (a reference of how far play goes, not a learner), played
# as a baseline is but never beside every run: the planner is slow.
REFERENCES = ("search",)
POLICIES = BASELINES + REFERENCES
# The baselines play frame by frame, on the model's table (or layouts) with the default rewards.
BASELINE_KWARGS = ("table", "balls", "num_layouts", "start_layout", "difficulty", "targets")

# A policy over a VecEnv: (observations, infos) -> actions.
VecPolicy = Callable[[np.ndarray, list[dict[str, Any]]], np.ndarray]


def baseline_config(name: str, config: AnyConfig | None = None) -> TrainConfig:
    """The config a baseline plays with: the env, table (or layouts) and balls of ``config``,
    one frame a step."""
    kwargs = {} if config is None else config.env.kwargs
    env = {"kwargs": {key: kwargs[key] for key in BASELINE_KWARGS if key in kwargs}}
    if config is not None:
        env["id"] = config.env.id
    seed = {} if config is None else {"eval_seed": config.eval_seed}
    return config_from_dict({"env": env, **seed}, f"<{name} baseline>")


class HeuristicPlayers:
    """A ``HeuristicPolicy`` for each env of a world, made for the env's table when it first
    plays, again when the env's table changes (generated tables change from game to game), and
    again after :meth:`new_game` (a fresh player: it holds the flippers' state)."""

    def __init__(self, world: Any) -> None:
        self.world = world
        self.players: dict[int, tuple[Any, HeuristicPolicy]] = {}  # env -> (table, player)

    def __call__(self, env: int, info: dict[str, Any]) -> int:
        """The action of env ``env``'s player for ``info`` (the ball's position and velocity)."""
        table = self.world.table_of(env)
        if env not in self.players or self.players[env][0] is not table:
            self.players[env] = (table, HeuristicPolicy(table))
        return self.players[env][1](info)

    def new_game(self, env: int) -> None:
        self.players.pop(env, None)


def baseline_policy(name: str, venv: Any, seed: int) -> VecPolicy:
    """``random``, ``heuristic`` or ``search`` as a function of (observations, infos) ->
    actions."""
    n = venv.num_envs
    if name == "random":
        player = RandomPolicy(venv.action_space.n, seed)
        return lambda obs, infos: player(n)
    if name == "search":
        return search_policy(venv)
    players = HeuristicPlayers(venv.get_attr("game")[0].world)

    def heuristic(obs: np.ndarray, infos: list[dict[str, Any]]) -> np.ndarray:
        actions = np.empty(n, dtype=np.int64)
        for env, info in enumerate(infos):
            actions[env] = players(env, info)
        return actions

    return heuristic


def search_policy(venv: Any) -> VecPolicy:
    """The planner (``players.VectorSearch``, its default settings) over the native vector env
    at the bottom of ``venv``; an env whose game ended plays no more (its player rests: the
    rollouts keep only each env's first game)."""
    search = VectorSearch(native_env(venv))
    ended = np.zeros(venv.num_envs, dtype=bool)

    def policy(obs: np.ndarray, infos: list[dict[str, Any]]) -> np.ndarray:
        ended[[env for env, info in enumerate(infos) if "episode" in info]] = True
        return np.array([0 if ended[env] else search.players[env](info)
                         for env, info in enumerate(infos)], dtype=np.int64)  # fmt: skip

    return policy


def model_policy(model: Any) -> VecPolicy:
    """A stable-baselines3 model's greedy actions (a recurrent one's from a fresh memory: one
    game per env, as :func:`rollouts` plays)."""
    predict = Predictor(model)
    return lambda obs, infos: predict(obs)


@dataclasses.dataclass(frozen=True)
class Player:
    """Who plays: its ``name``, the ``config`` whose env chain it plays through, the frozen
    observation statistics that chain ends with (``normalization``, a trained agent's), and
    ``policy(venv, seed)``: its policy in a VecEnv of that chain."""

    name: str
    config: AnyConfig
    normalization: ObsNormalization | None
    policy: Callable[[Any, int], VecPolicy]
    trained: bool


def baseline_player(name: str, like: AnyConfig | None = None) -> Player:
    """A baseline, on the env, table (or layouts) and balls of ``like``."""
    if name not in POLICIES:
        raise ConfigError(f"unknown policy {name!r} (known: {', '.join(POLICIES)})")
    return Player(name, baseline_config(name, like), None, partial(baseline_policy, name), False)


def trained_player(path: Path) -> Player:
    """The agent saved at ``path`` (``load_policy``), greedy, on the torch threads of its
    config."""
    import torch

    trained = load_policy(path)
    torch.set_num_threads(trained.config.torch_threads)

    def policy(venv: Any, seed: int) -> VecPolicy:
        trained.reset()  # new games
        return lambda obs, infos: trained.act(obs)

    return Player(str(path), trained.config, trained.normalization, policy, True)


def play_games(
    player: Player, seeds: list[int], config: AnyConfig | None = None,
    layouts: list[int] | None = None,
) -> list[dict]:  # fmt: skip
    """``rollouts`` of ``player``, one game per seed, through the env chain of ``config`` (by
    default its own)."""
    venv = make_env_chain(config or player.config, num_envs=len(seeds), seed=seeds[0],
                    frozen=player.normalization)  # fmt: skip
    rows = rollouts(venv, player.policy(venv, seeds[0]), seeds, layouts)
    venv.close()
    return rows


def rollouts(
    venv: Any, policy: VecPolicy, seeds: list[int], layouts: list[int] | None = None
) -> list[dict]:
    """One whole game per env of ``venv`` (whose env i was seeded with ``seeds[i]``), played by
    ``policy`` (on layout ``layouts[i]`` of PinballProcgen-v0); a row of metrics per game."""
    n = venv.num_envs
    if layouts is not None:
        venv.unwrapped.set_options({"layout": list(layouts)})
    obs = venv.reset()
    infos = list(venv.unwrapped.reset_infos)  # the wrappers keep none
    rows: list[dict | None] = [None] * n
    returns = np.zeros(n)
    balls = venv.get_attr("game")[0].balls_per_game
    while any(row is None for row in rows):
        obs, rewards, dones, infos = venv.step(policy(obs, infos))
        playing = np.array([row is None for row in rows])
        returns[playing] += rewards[playing]  # raw: an evaluation VecNormalize leaves them
        for env in np.flatnonzero(dones & playing):
            info = infos[env]
            rows[env] = {
                "seed": seeds[env],
                **({} if layouts is None else {"layout": int(info["layout"])}),
                "score": int(info["score"]),
                "return": round(float(returns[env]), 6),
                "length": int(info["frames"]),
                "balls_lost": int(balls - info["balls_left"]),
                "truncated": bool(info.get("TimeLimit.truncated", False)),
                # Points the rules scored (modes, awards, end-of-ball bonuses), on a table with
                # rules: the rest came from plain hits.
                **({"rule_score": int(info["rule_score"])} if "rule_score" in info else {}),
            }
    return rows  # type: ignore[return-value]


def summarize(rows: list[dict]) -> dict[str, Any]:
    """Mean, std and 95% confidence interval (normal approximation) of the score, and means."""
    scores = np.array([row["score"] for row in rows], dtype=np.float64)
    n = len(scores)
    std = float(scores.std(ddof=1)) if n > 1 else 0.0
    half = 1.96 * std / math.sqrt(n) if n > 1 else 0.0
    mean = float(scores.mean())
    return {
        "episodes": n,
        "score_mean": mean,
        "score_std": std,
        "score_ci95": [mean - half, mean + half],
        "return_mean": float(np.mean([row["return"] for row in rows])),
        "length_mean": float(np.mean([row["length"] for row in rows])),
        "truncated_share": float(np.mean([row["truncated"] for row in rows])),
    }
