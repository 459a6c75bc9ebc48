"""The benchmark's results: the runs of each method (done in ``OUT``, or merged from earlier
benchmarks), the protocol's metrics over them, and the published files (``benchmark.json``,
``benchmark.csv``, ``runs.csv``, ``benchmark.md`` and the plots)."""

import csv
import json
import time
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from agents.benchmark.jobs import (
    JOB_FILE,
    JobSettings,
    job_config,
    job_done,
    job_folder,
    job_run,
    run_config,
)
from agents.benchmark.methods import METHODS, TINY_FRAMES, config_digest
from agents.benchmark.plots import plot_benchmark
from agents.benchmark.tables import markdown_table
from agents.config import ConfigError
from agents.evaluation import PROTOCOL_EVAL
from agents.rollouts import BASELINES
from agents.runs import (
    MODEL_FILE,
    best_validation,
    progress_rows,
    read_meta,
    source_commit,
    validation_rows,
)
from pinball_env import protocol

if TYPE_CHECKING:
    from agents.benchmark.methods import JobConfig

# Runs of earlier benchmarks (--merge): per method, its runs as benchmark.json has them.
Merged = dict[str, list[dict[str, Any]]]


def method_results(
    name: str, seeds: list[int], settings: JobSettings, merged: Merged | None = None
) -> dict[str, Any] | None:
    """The runs of a method that are done (in OUT, else in ``merged``: :func:`merged_runs`) and
    the protocol's metrics over them (None: none)."""
    method = METHODS[name]
    runs = []
    for seed in seeds if method.trained else [0]:
        if not job_done(name, seed, settings):
            if (earlier := merged_run(merged, name, seed)) is not None:
                runs.append(earlier)
            continue
        folder = job_folder(settings, name, seed)
        run = job_run(name, seed, settings) if method.trained else folder
        with open(run / PROTOCOL_EVAL / "episodes.csv") as file:
            scores = [int(row["score"]) for row in csv.DictReader(file)]
        job = json.loads((folder / JOB_FILE).read_text()) if (folder / JOB_FILE).is_file() else {}
        runs.append({
            "seed": seed if method.trained else None,
            "run": str(run.relative_to(settings.out)),
            "scores": scores,
            "score_mean": float(np.mean(scores)),
            "score_iqm": protocol.iqm(scores),
            **(_training(run, job, run_config(name, run)) if method.trained else {}),
            # Seconds its games took to play (the planner's are its compute).
            **({"play_seconds": round(job["evaluate_seconds"], 1)}
               if "evaluate_seconds" in job else {}),
        })  # fmt: skip
    if not runs:
        return None
    metrics = protocol.aggregate([run["scores"] for run in runs], method.env_id)
    return {"env_id": method.env_id, "config": method.config, "baseline": method.baseline,
            "training_frames": settings.frames(name) if method.trained else None,
            **metrics, "runs": runs}  # fmt: skip


# What of the protocol a run's scores depend on: a merged run was measured under the same (and
# on an env the protocol still has: a protocol may gain envs, as it gained Pinball-v2).
SCORED_UNDER = ("repeat_action_probability", "game", "training_frames", "eval_seeds", "tiny")


def merged_runs(paths: list[Path], names: list[str], settings: JobSettings) -> Merged:
    """The runs of earlier ``benchmark.json`` files (another machine's, or the one published in
    ``docs/``) for methods ``names``, the first file's run of a seed before a later one's;
    ConfigError where one was measured under another protocol than this benchmark's or trained
    by another config than its method's now."""
    ours = json.loads(json.dumps(protocol_record(settings)))
    merged: Merged = {}
    for path in paths:
        try:
            table = json.loads(path.read_text())
            theirs, methods = table["protocol"], table["methods"]
        except (OSError, ValueError, KeyError, TypeError) as error:
            raise ConfigError(f"--merge {path}: not a benchmark.json ({error})") from None
        differ = [key for key in SCORED_UNDER if theirs.get(key) != ours[key]]
        if not set(theirs.get("env_ids", ())) <= set(ours["env_ids"]):
            differ.append("env_ids")
        if differ:
            raise ConfigError(
                f"--merge {path}: measured under another protocol than this benchmark's ("
                + ", ".join(f"{key}: {theirs.get(key)!r}, not {ours[key]!r}" for key in differ)
                + ")"
            )
        for name in names:
            for run in methods.get(name, {}).get("runs", []):
                if merged_run(merged, name, run["seed"]) is not None:
                    continue
                if METHODS[name].trained:
                    digest = config_digest(job_config(name, run["seed"], settings))
                    if run.get("config_digest") != digest:
                        raise ConfigError(
                            f"--merge {path}: {name} seed {run['seed']} was trained by another "
                            f"config than {METHODS[name].config} is now (train it again)"
                        )
                merged.setdefault(name, []).append({**run, "from": run.get("from", str(path))})
    return merged


def merged_run(merged: Merged | None, name: str, seed: int | None) -> dict[str, Any] | None:
    """The merged run of a method x seed (a baseline's: its one run), or None."""
    wanted = seed if METHODS[name].trained else None
    return next((run for run in (merged or {}).get(name, []) if run["seed"] == wanted), None)


def _training(run: Path, job: dict[str, Any], config: "JobConfig") -> dict[str, Any]:
    """A run's frames and steps trained, its minutes of training (the job's record, or for a run
    trained outside the benchmark, from its start to its model), its best validation score (its
    model's) and every validation (its learning curve), its commit and its config's digest."""
    meta = read_meta(run)
    rows = progress_rows(run)  # (a run from before meta.json's "trained": its last rollout's)
    trained = meta.get("trained") or {
        "frames": max((int(float(row["time/frames"])) for row in rows if row.get("time/frames")),
                      default=0),
        "steps": max((int(float(row["time/total_timesteps"])) for row in rows), default=0),
    }  # fmt: skip
    frames, steps = trained["frames"], trained["steps"]
    digest = config_digest(config)
    rows = validation_rows(run)
    validated = best_validation(rows)
    seconds = job.get("train_seconds")
    if seconds is None:
        started = time.mktime(time.strptime(meta["started"], "%Y-%m-%dT%H:%M:%S"))
        seconds = (run / MODEL_FILE).stat().st_mtime - started
    return {"frames": frames, "steps": steps, "train_minutes": round(seconds / 60.0, 1),
            "validation": validated and validated["score_mean"], "commit": meta.get("commit"),
            "config_digest": digest,
            # The learning curve: each validation's frames, mean and IQM (null: not recorded).
            "validations": [[row["frames"], row["score_mean"], row.get("score_iqm")]
                            for row in rows]}  # fmt: skip


def protocol_record(settings: JobSettings) -> dict[str, Any]:
    """The protocol as this benchmark applies it (``benchmark.json``'s ``protocol``)."""
    first = protocol.EVAL_SEEDS.start
    return {
        "env_ids": list(protocol.PROTOCOL_ENV_IDS),
        "repeat_action_probability": protocol.REPEAT_ACTION_PROBABILITY,
        "game": protocol.GAME_OPTIONS,
        "training_frames": TINY_FRAMES if settings.tiny else protocol.TRAINING_FRAMES,
        "training_budgets": [TINY_FRAMES] if settings.tiny else list(protocol.TRAINING_BUDGETS),
        "eval_seeds": [first, first + settings.episodes - 1],
        "reference_scores": protocol.REFERENCE_SCORES,
        "human_scores": protocol.HUMAN_SCORES,
        "tiny": settings.tiny,
    }


def aggregate_table(
    names: list[str], seeds: list[int], settings: JobSettings, merged: Merged | None = None
) -> dict[str, Any]:
    """Write benchmark.json, benchmark.csv, runs.csv and the plots; returns the table."""
    results = {name: method_results(name, seeds, settings, merged) for name in names}
    methods = {name: result for name, result in results.items() if result is not None}
    reference: dict[str, dict[str, float]] = {}
    for name, result in methods.items():
        if METHODS[name].baseline in BASELINES:  # (the normalisation's 0 and 1: not the planner)
            reference.setdefault(result["env_id"], {})[METHODS[name].baseline] = result[
                "score_mean"
            ]
    table = {
        "protocol": protocol_record(settings),
        "commit": source_commit(),
        "reference_measured": reference,
        "methods": methods,
    }
    settings.out.mkdir(parents=True, exist_ok=True)
    (settings.out / "benchmark.json").write_text(json.dumps(table, indent=1))
    _write_csvs(methods, settings.out)
    (settings.out / "benchmark.md").write_text(markdown_table(methods))
    if methods:
        plot_benchmark(methods, settings.out)
    return table


METHOD_COLUMNS = ("method", "env_id", "training_frames", "runs", "games", "score_mean",
                  "score_mean_low", "score_mean_high", "score_iqm", "score_iqm_low",
                  "score_iqm_high", "normalized_mean", "normalized_mean_low",
                  "normalized_mean_high", "normalized_iqm", "normalized_iqm_low",
                  "normalized_iqm_high", "train_minutes_mean")  # fmt: skip
RUN_COLUMNS = ("method", "env_id", "seed", "run", "score_mean", "score_iqm", "frames", "steps",
               "train_minutes", "validation", "commit", "from")  # fmt: skip


def _write_csvs(methods: dict[str, Any], out: Path) -> None:
    rows, run_rows = [], []
    for name, result in methods.items():
        row = {"method": name, "env_id": result["env_id"],
               "training_frames": result.get("training_frames") or "",
               "runs": len(result["runs"]), "games": result["games"]}  # fmt: skip
        for key in ("score_mean", "score_iqm", "normalized_mean", "normalized_iqm"):
            row[key] = round(result[key], 3)
            row[f"{key}_low"], row[f"{key}_high"] = (round(v, 3) for v in result[f"{key}_ci95"])
        minutes = [run["train_minutes"] for run in result["runs"] if "train_minutes" in run]
        row["train_minutes_mean"] = round(float(np.mean(minutes)), 1) if minutes else ""
        rows.append(row)
        for run in result["runs"]:
            run_rows.append({"method": name, "env_id": result["env_id"],
                             **{key: run.get(key, "") for key in RUN_COLUMNS[2:]}})  # fmt: skip
    for path, columns, table in ((out / "benchmark.csv", METHOD_COLUMNS, rows),
                                 (out / "runs.csv", RUN_COLUMNS, run_rows)):  # fmt: skip
        with open(path, "w", newline="") as file:
            writer = csv.DictWriter(file, fieldnames=columns)
            writer.writeheader()
            writer.writerows(table)
