"""The planner's score against its compute: the protocol's first held-out games (sticky actions,
the protocol's game) played by ``players.VectorSearch`` at each setting of a ladder of
look-ahead budgets, with the heuristic on the same games beside them. The figures behind the
planner page's table and figure (``docs/planner.md``).

    python -m benchmarks.planner [--env Pinball-v3] [--games 30] [--ladder h15 h45 ...]
                                 [--json FILE] [--figure PNG]
    python -m benchmarks.planner --replot docs/planner.json --figure docs/planner.png

Each setting is named by its horizon and plans (``h120a``: a horizon of 120 steps, the held
flipper actions and two other aims: the planner's defaults; ``h120``: without the aims); its
compute is the branch steps a game takes (branches x horizon x decisions), and its seconds a
game on this machine (one core: decisions are taken one after another).
"""

import dataclasses
import json
import time
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np

import pinball_env  # noqa: F401  (registers the envs)
from pinball_env import protocol
from pinball_env.players import HeuristicPolicy, SearchSettings, VectorSearch
from pinball_env.tools import command_parser

# The ladder: each setting's name and its SearchSettings' fields (the rest its defaults): the
# horizon in steps, and "a" for the two other aims of the default plans (none without).
SETTINGS: dict[str, dict[str, Any]] = {
    "h15": {"horizon": 15, "aims": ()},
    "h45": {"horizon": 45, "aims": ()},
    "h120": {"horizon": 120, "aims": ()},
    "h120a": {"horizon": 120, "aims": (0.3, 0.7)},
    "h240a": {"horizon": 240, "aims": (0.3, 0.7)},
}


def protocol_games(env_id: str, games: int) -> Any:
    """A native vector env of the protocol's first ``games`` held-out games, reset."""
    venv = gym.make_vec(env_id, num_envs=games, vectorization_mode="vector_entry_point",
                        **protocol.protocol_options(env_id))  # fmt: skip
    first = protocol.EVAL_SEEDS.start
    _, infos = venv.reset(seed=list(range(first, first + games)))
    return venv, infos


def play(venv: Any, infos: dict[str, Any], players: list[Any]) -> list[int]:
    """Each env's first game played to its end by its player (``player(info) -> action``);
    the scores. An env whose game ended plays no-ops (its next game is not counted)."""
    n = venv.num_envs
    scores: list[int | None] = [None] * n
    while any(score is None for score in scores):
        actions = np.zeros(n, dtype=np.int64)
        for env in range(n):
            if scores[env] is None:
                actions[env] = players[env]({key: value[env] for key, value in infos.items()})
        _, _, terminated, truncated, infos = venv.step(actions)
        for env in np.flatnonzero(terminated | truncated):
            if scores[env] is None:
                scores[env] = int(infos["score"][env])  # (autoreset on the next step)
    return [int(score) for score in scores if score is not None]


def searched(env_id: str, games: int, fields: dict[str, Any]) -> dict[str, Any]:
    """The planner's games at ``fields`` (SearchSettings'), their metrics and compute."""
    venv, infos = protocol_games(env_id, games)
    search = VectorSearch(venv, SearchSettings(**fields))
    started = time.perf_counter()
    scores = play(venv, infos, search.players)
    seconds = time.perf_counter() - started
    planner = search.planner
    search.close()
    venv.close()
    return {"settings": dataclasses.asdict(SearchSettings(**fields)),
            "branches": len(planner.plans), "scores": scores,
            "decisions_per_game": planner.decisions / games,
            "branch_steps_per_game": planner.branch_steps / games,
            "seconds_per_game": seconds / games, **metrics(scores, env_id)}  # fmt: skip


def heuristic(env_id: str, games: int) -> dict[str, Any]:
    """The heuristic on the same games (the scale the planner's gain is read on)."""
    venv, infos = protocol_games(env_id, games)
    scores = play(venv, infos, [HeuristicPolicy(venv.first_table) for _ in range(games)])
    venv.close()
    return {"scores": scores, **metrics(scores, env_id)}


def metrics(scores: list[int], env_id: str) -> dict[str, float]:
    result = protocol.aggregate([scores], env_id)
    return {key: result[key] for key in ("score_mean", "score_iqm", "normalized_iqm",
                                         "normalized_iqm_ci95")}  # fmt: skip


def figure(result: dict[str, Any], path: Path) -> None:
    """Normalised IQM (and its interval) against branch steps a game, the heuristic's line."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6, 3.6))
    ladder = result["ladder"]
    x = [ladder[name]["branch_steps_per_game"] for name in ladder]
    y = [ladder[name]["normalized_iqm"] for name in ladder]
    low = [y[i] - ladder[name]["normalized_iqm_ci95"][0] for i, name in enumerate(ladder)]
    high = [ladder[name]["normalized_iqm_ci95"][1] - y[i] for i, name in enumerate(ladder)]
    ax.errorbar(x, y, yerr=[low, high], marker="o", capsize=3, label="planner")
    for name, xi, yi in zip(ladder, x, y, strict=True):
        ax.annotate(name, (xi, yi), textcoords="offset points", xytext=(4, -12), fontsize=8)
    scripted = result["heuristic"]["normalized_iqm"]
    ax.axhline(scripted, color="grey", ls="--", label="heuristic")
    ax.axhline(2 * scripted, color="grey", ls=":", label="twice the heuristic")
    ax.set_xscale("log")
    ax.set_xlabel("look-ahead: branch steps a game")
    ax.set_ylabel("normalised IQM")
    ax.set_title(f"{result['env_id']}: the planner against its compute "
                 f"({result['games']} protocol games)")  # fmt: skip
    ax.legend(loc="lower right")
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)


def main(argv: list[str] | None = None) -> dict[str, Any]:
    parser = command_parser("benchmarks.planner", __doc__)
    parser.add_argument("--env", default="Pinball-v3", choices=protocol.PROTOCOL_ENV_IDS)
    parser.add_argument("--games", type=int, default=30, help="protocol games a setting")
    parser.add_argument("--ladder", nargs="+", default=list(SETTINGS), choices=list(SETTINGS),
                        metavar="SETTING", help=f"settings: {', '.join(SETTINGS)}")  # fmt: skip
    parser.add_argument("--json", type=Path, help="write the results here")
    parser.add_argument("--figure", type=Path, help="draw the figure here (PNG)")
    parser.add_argument(
        "--replot", type=Path, metavar="JSON", help="draw --figure from an earlier run's JSON"
    )
    args = parser.parse_args(argv)
    if args.replot:
        if not args.figure:
            parser.error("--replot draws a --figure: give one")
        result = json.loads(args.replot.read_text())
        figure(result, args.figure)
        return result
    if not 1 <= args.games <= len(protocol.EVAL_SEEDS):
        parser.error(f"--games must be 1 to {len(protocol.EVAL_SEEDS)}")
    scripted = heuristic(args.env, args.games)
    result = {"env_id": args.env, "games": args.games, "heuristic": scripted, "ladder": {}}
    print(f"heuristic: normalised IQM {result['heuristic']['normalized_iqm']:.2f}", flush=True)
    for name in args.ladder:
        row = result["ladder"][name] = searched(args.env, args.games, SETTINGS[name])
        low, high = row["normalized_iqm_ci95"]
        print(f"{name}: normalised IQM {row['normalized_iqm']:.2f} [{low:.2f}, {high:.2f}], "
              f"mean {row['score_mean']:.0f}, {row['branch_steps_per_game']:.0f} branch steps "
              f"and {row['seconds_per_game']:.1f} s a game", flush=True)  # fmt: skip
    if args.json:
        args.json.write_text(json.dumps(result, indent=1))
    if args.figure:
        figure(result, args.figure)
    return result


if __name__ == "__main__":
    main()
