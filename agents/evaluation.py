"""Evaluating an agent: whole games on fixed seeds, by default the config's ``eval_seed`` on,
games training never played (``agents.evaluate`` is its command line).

Who plays is a :class:`~agents.rollouts.Player` (:func:`player_for`: a baseline or a saved
model); :func:`evaluate` plays its games and writes ``episodes.csv`` and ``summary.json``;
:func:`evaluate_protocol` plays the benchmark protocol's games (``pinball_env.protocol``) and
adds its metrics; :func:`score_recording` scores a play-tool recording (a human's) on the
protocol.
"""

import csv
import dataclasses
import json
from pathlib import Path
from typing import Any

from agents.config import (
    AnyConfig,
    ConfigError,
    check_evaluation_seeds,
    config_from_dict,
    protocol_config,
)
from agents.policy import PRETRAINED_PREFIX, resolve_model_path
from agents.rollouts import (
    POLICIES,
    Player,
    baseline_player,
    play_games,
    summarize,
    trained_player,
)
from pinball_env.protocol import (
    EVAL_SEEDS,
    GAME_OPTIONS,
    REPEAT_ACTION_PROBABILITY,
    aggregate,
    check_agent_options,
)

PROTOCOL_EVAL = "protocol_eval"  # a run's evaluation under the benchmark protocol


def player_for(
    policy: str | None = None,
    model_path: Path | str | None = None,
    table: str | None = None,
    env: str | None = None,
    like: AnyConfig | None = None,
) -> Player:
    """Who plays: the baseline ``policy`` on the env ``env`` (default ``Pinball-v0``) and
    ``table`` (default the env's), or on the env (and layouts) of the config ``like``; or the
    model saved at ``model_path`` (a run folder, a zip, ``pretrained:NAME``). One of the two."""
    if (policy is None) == (model_path is None):
        raise ConfigError("give a model or a policy (random, heuristic or search), not both")
    if policy is not None:
        if policy in POLICIES and like is None:
            kwargs = {"kwargs": {"table": table} if table else {}}
            like = config_from_dict({"env": {**kwargs, **({"id": env} if env else {})}})
        return baseline_player(policy, like)
    if str(model_path).startswith(PRETRAINED_PREFIX):
        return trained_player(resolve_model_path(model_path))
    return trained_player(Path(model_path))


def default_out(
    policy: str | None = None, model_path: Path | str | None = None, protocol: bool = False
) -> Path:
    """Where an evaluation goes unless told: ``RUN/eval`` for a run (``RUN/protocol_eval`` on
    the protocol), ``evals/POLICY`` (``evals/POLICY-protocol``) for a baseline or a
    pretrained agent."""
    if policy is not None:
        out = Path("evals") / policy
    elif str(model_path).startswith(PRETRAINED_PREFIX):
        out = Path("evals") / str(model_path).replace(":", "-")
    else:
        model_path = Path(model_path)
        out = (model_path if model_path.is_dir() else model_path.parent) / "eval"
    if protocol:
        out = out.with_name(PROTOCOL_EVAL if out.name == "eval" else f"{out.name}-protocol")
    return out


def first_seed(player: Player, seed: int | None, episodes: int) -> int:
    """The first game's seed (default: the config's ``eval_seed``); ConfigError unless there
    is a game to play, or if a trained player's games include one it learned from."""
    if episodes < 1:
        raise ConfigError(f"episodes must be >= 1, got {episodes}")
    first = player.config.eval_seed if seed is None else seed
    if player.trained:
        check_evaluation_seeds(player.config, first, episodes)
    return first


def check_protocol_games(table: str | None, seed: int | None, episodes: int) -> None:
    """ConfigError if the games asked for are not the protocol's own (held-out) games."""
    if table is not None or seed is not None or episodes > len(EVAL_SEEDS):
        raise ConfigError(
            "the protocol plays its own games: no --table or --seed, and --episodes at most "
            f"{len(EVAL_SEEDS)} (its held-out games)"
        )


def protocol_player(player: Player) -> Player:
    """``player`` on the protocol's game: its own view of the game, the protocol's table, balls,
    time and sticky actions (ConfigError if its env is not a protocol env)."""
    return dataclasses.replace(player, config=protocol_config(player.config))


def evaluate(
    player: Player, out: Path, episodes: int = 100, seed: int | None = None
) -> dict[str, Any]:
    """Play ``episodes`` whole games with ``player`` from ``seed`` on (default the config's
    ``eval_seed``) and write them into ``out`` (:func:`write_results`); returns the summary."""
    first = first_seed(player, seed, episodes)
    rows, summary = _play(player, first, episodes)
    write_results(out, rows, summary)
    _print_summary(summary, episodes, out)
    return summary


def evaluate_protocol(player: Player, out: Path, episodes: int = len(EVAL_SEEDS)) -> dict[str, Any]:
    """Play the benchmark protocol's first ``episodes`` held-out games with ``player`` on the
    protocol's game and write them into ``out``; the summary adds the protocol's metrics
    (``"protocol"``: IQM, bootstrap intervals, normalised scores)."""
    check_protocol_games(None, None, episodes)
    player = protocol_player(player)
    rows, summary = _play(player, first_seed(player, EVAL_SEEDS.start, episodes), episodes)
    env_id = player.config.env.id
    summary["protocol"] = {"env_id": env_id, **aggregate([[row["score"] for row in rows]], env_id)}
    write_results(out, rows, summary)
    _print_summary(summary, episodes, out)
    return summary


def _play(player: Player, first: int, episodes: int) -> tuple[list[dict], dict[str, Any]]:
    """The games ``first..first + episodes - 1`` played by ``player``: a row each, and their
    summary."""
    rows = play_games(player, list(range(first, first + episodes)))
    return rows, {"policy": player.name, "seeds": [first, first + episodes - 1], **summarize(rows)}


def _print_summary(summary: dict[str, Any], episodes: int, out: Path) -> None:
    print(
        f"{summary['policy']}: score {summary['score_mean']:.0f} (95% CI "
        f"{summary['score_ci95'][0]:.0f}-{summary['score_ci95'][1]:.0f}) over {episodes} games, "
        f"mean length {summary['length_mean']:.0f} frames, {summary['truncated_share']:.0%} "
        f"truncated -> {out}"
    )


def write_results(out: Path, rows: list[dict], summary: dict[str, Any]) -> None:
    """``OUT/episodes.csv`` (a row per game) and ``OUT/summary.json``."""
    out.mkdir(parents=True, exist_ok=True)
    with open(out / "episodes.csv", "w", newline="") as file:
        writer = csv.DictWriter(file, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    (out / "summary.json").write_text(json.dumps(summary, indent=1))


def score_recording(path: Path, out: Path | None = None) -> dict[str, Any]:
    """Score the games of a play-tool recording (a human's) on the benchmark protocol: each
    game replayed and checked (``pinball_env.recording.replay``), the recording refused
    unless it is of a protocol env with the protocol's game and sticky actions; the summary
    (the protocol's metrics of its games) is written to ``out`` (default ``evals/human``)."""
    from pinball_env.recording import RecordingError, load_recording, replay

    try:
        recording = load_recording(path)
        check_recording(recording)
        scores = replay(recording)  # (every game checked, the unfinished ones too)
    except RecordingError as error:
        raise ConfigError(str(error)) from None
    env_id = recording.env_id
    # A restarted or quit game is not a game's score: only those played to their end count.
    games = [(game.seed, score) for game, score in zip(recording.games, scores, strict=True)
             if game.end in ("game over", "time limit")]  # fmt: skip
    if not games:
        raise ConfigError(f"{path}: no game was played to its end (game over or time limit)")
    scores = [score for _, score in games]
    summary = {
        "policy": f"human ({path})",
        "seeds": [seed for seed, _ in games],
        "unfinished": len(recording.games) - len(games),
        "scores": scores,
        "protocol": {"env_id": env_id, **aggregate([scores], env_id)},
    }
    out = out or Path("evals") / "human"
    out.mkdir(parents=True, exist_ok=True)
    (out / "summary.json").write_text(json.dumps(summary, indent=1))
    metrics = summary["protocol"]
    print(
        f"{path}: {len(scores)} whole games of {env_id} on the protocol, replayed as recorded: "
        f"score {metrics['score_mean']:.0f} (IQM {metrics['score_iqm']:.0f}), normalised "
        f"{metrics['normalized_mean']:.2f} (random 0, heuristic 1) -> {out}"
    )
    return summary


def check_recording(recording: Any) -> None:
    """RecordingError unless ``recording`` was played on the protocol's game: a protocol env,
    its own table, 3 balls, two minutes, sticky actions of the protocol, one frame a step."""
    from pinball_env.recording import RecordingError

    options = dict(recording.options)
    try:
        check_agent_options(recording.env_id, options, "the recording's options")
    except ValueError as error:
        raise RecordingError(str(error)) from None
    wanted = {"repeat_action_probability": REPEAT_ACTION_PROBABILITY, "frame_skip": 1}
    played = {"repeat_action_probability": 0.0, "frame_skip": 1, **options}
    problems = [f"{key}={played[key]!r} (the protocol's: {value!r})"
                for key, value in wanted.items() if played[key] != value]  # fmt: skip
    limit = options.get("max_frames") or recording.max_episode_steps
    if limit != GAME_OPTIONS["max_frames"]:
        problems.append(f"a game of {limit} frames (the protocol's: {GAME_OPTIONS['max_frames']})")
    if problems:
        raise RecordingError(
            f"not a game of the benchmark protocol: {', '.join(problems)} (record one with "
            "python -m pinball_env.tools.play --protocol --record FILE)"
        )
