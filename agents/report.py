"""Evaluations, reports and learning curves.

``evaluate`` plays whole games with a trained agent or a baseline on fixed seeds (by default
the config's ``eval_seed`` on, games training never played) and writes ``episodes.csv`` and
``summary.json`` (see ``agents.evaluate``, its command line); ``report(run)`` evaluates a run's
model and both baselines on the same games and writes ``report.json``, ``learning_curve.png``
and ``game.gif`` into the run folder; ``plot_learning_curve`` draws a run's training games (its
``progress*.csv``) and validation games (``validation.csv``) against the frames played.
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
    load_run_config,
    protocol_config,
)
from agents.policy import PRETRAINED_PREFIX, resolve_model_path
from agents.rollouts import (
    BASELINES,
    Player,
    baseline_player,
    play_games,
    summarize,
    trained_player,
)
from agents.runs import best_validation, progress_rows, validation_rows
from agents.watch import record_video, watch_games
from pinball_env.protocol import (
    EVAL_SEEDS,
    GAME_OPTIONS,
    REPEAT_ACTION_PROBABILITY,
    aggregate,
    check_agent_options,
)

REPORT_FILE = "report.json"
PROTOCOL_EVAL = "protocol_eval"  # a run's evaluation under the benchmark protocol


def evaluate(
    policy: str | None = None,
    model_path: Path | None = None,
    table: str | None = None,
    env: str | None = None,
    episodes: int = 100,
    seed: int | None = None,
    out: Path | None = None,
    video: Path | None = None,
    curve: bool = False,
    like: AnyConfig | None = None,
    watch: bool = False,
    protocol: bool = False,
) -> dict[str, Any]:
    """Play ``episodes`` games with a model or a baseline, write the results into ``out``;
    returns the summary. A baseline plays the env ``env`` (default ``Pinball-v0``) on ``table``
    (default the env's), or the env (and layouts) of the config ``like``. With ``watch``, the
    games are shown in a window instead (nothing is written). With ``protocol``, the games are
    the benchmark protocol's (``pinball_env.protocol``: its held-out seeds, its game, sticky
    actions) and the summary adds its metrics (``"protocol"``: IQM, bootstrap intervals,
    normalised scores)."""
    if (policy is None) == (model_path is None):
        raise ConfigError("give a model or a policy (random or heuristic), not both")
    if episodes < 1:
        raise ConfigError(f"episodes must be >= 1, got {episodes}")
    if policy is not None:
        if policy in BASELINES and like is None:
            kwargs = {"kwargs": {"table": table} if table else {}}
            like = config_from_dict({"env": {**kwargs, **({"id": env} if env else {})}})
        player = baseline_player(policy, like)
        default = Path("evals") / policy
    elif str(model_path).startswith(PRETRAINED_PREFIX):
        player = trained_player(resolve_model_path(model_path))
        default = Path("evals") / str(model_path).replace(":", "-")
    else:
        player = trained_player(model_path)
        default = (model_path if model_path.is_dir() else model_path.parent) / "eval"
    if protocol:
        if table is not None or seed is not None or episodes > len(EVAL_SEEDS):
            raise ConfigError(
                "the protocol plays its own games: no --table or --seed, and --episodes at most "
                f"{len(EVAL_SEEDS)} (its held-out games)"
            )
        player = dataclasses.replace(player, config=protocol_config(player.config))
        seed = EVAL_SEEDS.start
        default = default.with_name(PROTOCOL_EVAL if default.name == "eval" else
                                    f"{default.name}-protocol")  # fmt: skip
    out = out or default
    first = player.config.eval_seed if seed is None else seed
    if player.trained:
        check_evaluation_seeds(player.config, first, episodes)
    if watch:
        return watch_games(player.config, player.normalization, player.policy, first, episodes)
    rows = play_games(player, list(range(first, first + episodes)))
    summary = {"policy": player.name, "seeds": [first, first + episodes - 1], **summarize(rows)}
    if protocol:
        scores = [row["score"] for row in rows]
        summary["protocol"] = {"env_id": player.config.env.id,
                               **aggregate([scores], player.config.env.id)}  # fmt: skip
    write_results(out, rows, summary)
    if video is not None:
        record_video(player.config, player.normalization, player.policy, first, video)
    if curve and model_path is not None and model_path.is_dir():
        curve_with_baselines(model_path, player, first, episodes, out)
    print(
        f"{player.name}: score {summary['score_mean']:.0f} (95% CI "
        f"{summary['score_ci95'][0]:.0f}-{summary['score_ci95'][1]:.0f}) over {episodes} games, "
        f"mean length {summary['length_mean']:.0f} frames, {summary['truncated_share']:.0%} "
        f"truncated -> {out}"
    )
    return summary


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


def curve_with_baselines(run: Path, player: Player, first: int, episodes: int, out: Path) -> None:
    """``OUT/learning_curve.png`` of a run, with the baselines of its report, or, without one,
    the baselines played now on the same games (their results in ``OUT/random`` and
    ``OUT/heuristic``)."""
    baselines = baselines_for(run) or {
        baseline: evaluate(
            policy=baseline, episodes=episodes, seed=first, out=out / baseline, like=player.config
        )["score_mean"]
        for baseline in BASELINES
    }  # fmt: skip
    plot_learning_curve(run, out / "learning_curve.png", baselines)


def write_results(out: Path, rows: list[dict], summary: dict[str, Any]) -> None:
    out.mkdir(parents=True, exist_ok=True)
    with open(out / "episodes.csv", "w", newline="") as file:
        writer = csv.DictWriter(file, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    (out / "summary.json").write_text(json.dumps(summary, indent=1))


def baselines_for(run: Path) -> dict[str, float]:
    """The baselines' mean scores from a run's report, when it has one."""
    report = run / REPORT_FILE
    if not report.is_file():
        return {}
    data = json.loads(report.read_text())
    return {name: data[name]["score_mean"] for name in BASELINES if name in data}


def plot_learning_curve(run: Path, out: Path, baselines: dict[str, float]) -> None:
    """The training games' mean score (``rollout/ep_score_mean``) against frames played, and
    the validation games' (``validation.csv``) when the run has them."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    config = load_run_config(run)
    rows = [row for row in progress_rows(run) if row.get("rollout/ep_score_mean")]
    if not rows:
        print(f"no learning curve: {run} has no finished training games logged yet")
        return
    skip = config.env.frame_skip  # runs from before time/frames was logged: steps x skip
    frames = [float(row.get("time/frames") or float(row["time/total_timesteps"]) * skip)
              for row in rows]  # fmt: skip
    scores = [float(row["rollout/ep_score_mean"]) for row in rows]
    fig, ax = plt.subplots(figsize=(6, 3.5), dpi=100)
    ax.plot(frames, scores, label=f"{config.algo.upper()} (training games, last 100)")
    checks = validation_rows(run)
    if checks:
        ax.plot([row["frames"] for row in checks], [row["score_mean"] for row in checks], "o",
                markersize=4, label=f"validation games ({config.validate_episodes})")  # fmt: skip
        chosen = best_validation(checks)  # the run's model
        ax.plot(chosen["frames"], chosen["score_mean"], "*", color="black", markersize=11,
                label=f"the model (at {chosen['steps']:,} steps)")  # fmt: skip
    for (name, score), style in zip(baselines.items(), ("--", ":"), strict=False):
        ax.axhline(score, linestyle=style, color="grey", label=f"{name} (evaluation)")
    ax.set_xlabel("frames played (1/60 s each)")
    ax.set_ylabel("game score")
    ax.set_title(f"{config.env.id} on {config.env.kwargs.get('table', 'classic')}")
    ax.legend(loc="lower right", fontsize=8)
    ax.grid(alpha=0.3)
    fig.tight_layout()
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out)
    plt.close(fig)


def report(run: Path, episodes: int = 100) -> dict[str, Any]:
    """Evaluate a run's model and both baselines on the same seeds; write ``report.json``,
    ``learning_curve.png`` and ``game.gif`` into the run folder."""
    config = load_run_config(run)
    results = {}
    for name in BASELINES:
        out = run / "eval" / name
        results[name] = evaluate(
            policy=name, episodes=episodes, seed=config.eval_seed, out=out, like=config
        )
    results["model"] = evaluate(
        model_path=run, episodes=episodes, out=run / "eval" / "model", video=run / "game.gif"
    )
    (run / REPORT_FILE).write_text(json.dumps(results, indent=1))
    plot_learning_curve(run, run / "learning_curve.png", baselines_for(run))
    print(f"report: {run / REPORT_FILE}, {run / 'learning_curve.png'}, {run / 'game.gif'}")
    return results
