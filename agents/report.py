"""Reports and learning curves.

``report(run)`` evaluates a run's model and both baselines on the same games
(``agents.evaluation``) and writes ``report.json``, ``learning_curve.png`` and ``game.gif`` into
the run folder; ``plot_learning_curve`` draws a run's training games (its ``progress*.csv``) and
validation games (``validation.csv``) against the frames played, and ``curve_with_baselines``
with the baselines drawn in.
"""

import json
from pathlib import Path
from typing import Any

from agents.config import AnyConfig, load_run_config
from agents.evaluation import evaluate, player_for
from agents.rollouts import BASELINES, Player
from agents.runs import best_validation, progress_rows, validation_rows
from agents.watch import record_video
from pinball_env.versions import ENV_VERSIONS

REPORT_FILE = "report.json"


def curve_with_baselines(run: Path, player: Player, first: int, episodes: int, out: Path) -> None:
    """``OUT/learning_curve.png`` of a run, with the baselines of its report, or, without one,
    the baselines played now on the same games (their results in ``OUT/random`` and
    ``OUT/heuristic``)."""
    baselines = baselines_for(run) or {
        baseline: evaluate(
            player_for(baseline, like=player.config), out / baseline, episodes, first
        )["score_mean"]
        for baseline in BASELINES
    }
    plot_learning_curve(run, out / "learning_curve.png", baselines)


def baselines_for(run: Path) -> dict[str, float]:
    """The baselines' mean scores from a run's report, when it has one."""
    report = run / REPORT_FILE
    if not report.is_file():
        return {}
    data = json.loads(report.read_text())
    return {name: data[name]["score_mean"] for name in BASELINES if name in data}


def played_table(config: AnyConfig) -> str:
    """The table a config's env plays: its ``table`` option, else its env version's own."""
    table = config.env.kwargs.get("table")
    if table is None:
        version = ENV_VERSIONS.get(config.env.id)
        return version.table if version is not None else "its table"
    return str(table)


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
    ax.set_title(f"{config.env.id} on {played_table(config)}")
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
        print(f"report: playing the {name} baseline's {episodes} games", flush=True)
        baseline = player_for(name, like=config)
        results[name] = evaluate(baseline, run / "eval" / name, episodes, config.eval_seed)
    print(f"report: playing the model's {episodes} games", flush=True)
    model = player_for(model_path=run)
    results["model"] = evaluate(model, run / "eval" / "model", episodes)
    first = results["model"]["seeds"][0]
    print(f"report: recording the model's game on seed {first} as {run / 'game.gif'}", flush=True)
    record_video(model.config, model.normalization, model.policy, first, run / "game.gif")
    (run / REPORT_FILE).write_text(json.dumps(results, indent=1))
    plot_learning_curve(run, run / "learning_curve.png", baselines_for(run))
    print(f"report: {run / REPORT_FILE}, {run / 'learning_curve.png'}, {run / 'game.gif'}")
    return results
