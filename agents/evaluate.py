"""Evaluation rollouts: whole games on fixed seeds that training never used.

    python -m agents.evaluate --model RUN_OR_ZIP --episodes 100 [--video game.mp4] [--curve]
    python -m agents.evaluate --policy heuristic --episodes 100 [--env Pinball-v1]
    python -m agents.evaluate --model RUN_OR_ZIP --watch [--episodes 3]
    python -m agents.evaluate --model pretrained:ppo-gentle-v1 --protocol
    python -m agents.evaluate --recording my_games.json

Each game is played to its end (the last ball drained, or the two-minute time limit), on seeds
``seed .. seed + episodes - 1`` (``--seed``, by default the config's ``eval_seed``, 100000). A
model plays through the env chain it was trained on (frame skip, frame stacking, frozen
``VecNormalize`` statistics), choosing its actions deterministically; ``random`` (uniform over
the actions, every frame), ``heuristic`` (``pinball_env.players.HeuristicPolicy``) and
``search`` (the planner, ``pinball_env.players.VectorSearch``: a reference that looks ahead in
the simulator, seconds a game) play frame by frame. Written to ``--out`` (default:
``RUN/eval`` for a run, ``evals/POLICY``):

- ``episodes.csv``: per game the seed, score, return (the env's reward, shaping included),
  length (frames), balls lost and whether the time limit truncated it;
- ``summary.json``: mean, std and 95% confidence interval of the score (normal approximation),
  mean return and length, share truncated;
- with ``--video PATH``: the first game as an MP4 or GIF (by the suffix), score on screen,
  every frame of it (every third in a GIF), those a step runs on included;
- with ``--curve`` (a run): ``learning_curve.png``, the training games' mean score against
  frames, with the random and heuristic baselines drawn in (from the run's report, or played
  on the same games, their results in ``OUT/random`` and ``OUT/heuristic``).

``--protocol`` plays the benchmark protocol's games instead (``pinball_env.protocol``: the
held-out seeds 100000-100099, the env's own table, 3 balls, two minutes, sticky actions 0.25;
the agent keeps its own view of the game) and adds the protocol's metrics to ``summary.json``
(``"protocol"``: mean and interquartile mean with 95% bootstrap intervals, the score normalised
by random play and the heuristic), written to ``RUN/protocol_eval`` by default.
``--recording FILE`` scores a play-tool recording (``python -m pinball_env.tools.play --protocol
--record FILE``) on the protocol: every game is replayed and checked, the recording must be of
the protocol's game, and its mean is the human score the protocol normalises by
(``pinball_env.protocol.HUMAN_SCORES``).

``--watch`` plays the games in a window instead, at real speed (every frame shown at the
table's frame rate), printing each score; close the window or press Ctrl-C to stop.

``report(run)`` (``python -m agents.train ... --report``) does all of it for a run and its two
baselines and writes ``report.json`` (``evaluate`` is ``agents.evaluation``'s, ``report``
``agents.report``'s; the games are played by ``agents.rollouts`` and shown by
``agents.watch``). Models load through ``agents.policy.load_policy``: a run folder, a model or
checkpoint zip (copied alone, it carries its config and statistics), or an RLlib run or
checkpoint folder (``agents.rllib``), which plays the same games through its checkpoint's RL
module and observation filter. Models are pickles: load only models you trust.
"""

import argparse
from pathlib import Path
from typing import Any

from agents.config import ConfigError
from agents.evaluation import (
    check_protocol_games,
    default_out,
    evaluate,
    evaluate_protocol,
    first_seed,
    player_for,
    protocol_player,
    score_recording,
)
from agents.report import curve_with_baselines

# The functions of an evaluation, as agents.evaluate has always had them.
from agents.report import report as report
from agents.rollouts import POLICIES
from agents.rollouts import model_policy as model_policy
from agents.rollouts import rollouts as rollouts
from agents.watch import record_video
from agents.watch import watch_games as watch_games
from pinball_env.protocol import EVAL_SEEDS, PROTOCOL_ENV_IDS
from pinball_env.tools import command_parser
from pinball_env.tools.demo import has_display


def main(argv: list[str] | None = None) -> dict[str, Any]:
    parser = command_parser("agents.evaluate", __doc__)
    who = parser.add_mutually_exclusive_group(required=True)
    who.add_argument(
        "--model",
        type=Path,
        help="a run folder, a model or checkpoint zip, "
        "pretrained:NAME (an agent that ships), or an RLlib run or checkpoint folder",
    )
    who.add_argument(
        "--policy", choices=POLICIES, help="a baseline (search: the planner, a reference)"
    )
    who.add_argument("--recording", type=Path, help="score a play-tool recording (a human's)")
    parser.add_argument("--protocol", action="store_true", help="the benchmark protocol's games")
    parser.add_argument(
        "--env", help=f"the baselines' env id (default: the protocol's, {PROTOCOL_ENV_IDS[0]})"
    )
    parser.add_argument("--table", help="the baselines' table (default: the env's)")
    parser.add_argument("--episodes", type=int, default=100, help="games to play")
    parser.add_argument("--seed", type=int, help="first game's seed (default: eval_seed)")
    parser.add_argument("--out", type=Path, help="where to write the results")
    parser.add_argument("--video", type=Path, help="record the first game (.mp4 or .gif)")
    parser.add_argument("--curve", action="store_true", help="draw a run's learning curve")
    parser.add_argument("--watch", action="store_true", help="show the games in a window")
    args = parser.parse_args(argv)
    if args.watch and not has_display():
        parser.exit(2, "error: --watch shows the games in a window, and no display was found: "
                       "watch in the browser instead (python -m pinball_env.tools.serve --model "
                       "MODEL, docs/browser.md)\n")  # fmt: skip
    if args.recording is not None:
        given = [flag for flag, value in (("--protocol", args.protocol), ("--env", args.env),
                 ("--table", args.table), ("--seed", args.seed), ("--video", args.video),
                 ("--curve", args.curve), ("--watch", args.watch)) if value]  # fmt: skip
        if given:
            parser.error(f"--recording scores the recorded games on the protocol: no {given[0]}")
    try:
        if args.recording is not None:
            return score_recording(args.recording, args.out)
        return run_evaluation(args)
    except ConfigError as error:
        parser.exit(2, f"error: {error}\n")


def run_evaluation(args: argparse.Namespace) -> dict[str, Any]:
    """The games ``args`` ask for: watched in a window, or played and written (on the protocol
    with ``--protocol``), then the first one's video and the run's learning curve if asked."""
    env = args.env or (PROTOCOL_ENV_IDS[0] if args.policy is not None else None)
    player = player_for(args.policy, args.model, args.table, env)
    out = args.out or default_out(args.policy, args.model, args.protocol)
    if args.protocol:
        check_protocol_games(args.table, args.seed, args.episodes)
    played = protocol_player(player) if args.protocol else player  # (the game it plays)
    if args.watch:
        seed = EVAL_SEEDS.start if args.protocol else args.seed
        first = first_seed(played, seed, args.episodes)
        return watch_games(played.config, played.normalization, played.policy, first, args.episodes)
    if args.protocol:
        summary = evaluate_protocol(player, out, args.episodes)
    else:
        summary = evaluate(player, out, args.episodes, args.seed)
    first = summary["seeds"][0]
    if args.video is not None:
        record_video(played.config, played.normalization, played.policy, first, args.video)
    if args.curve and args.model is not None and args.model.is_dir():
        curve_with_baselines(args.model, played, first, args.episodes, out)
    return summary


if __name__ == "__main__":
    main()
