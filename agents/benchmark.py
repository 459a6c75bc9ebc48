"""The benchmark: named methods x training seeds under the protocol (``pinball_env.protocol``).

    python -m agents.benchmark                                   # every method, seeds 0-4
    python -m agents.benchmark --methods ppo-v1 heuristic-v1 --seeds 0 1 2 --parallel 2
    python -m agents.benchmark --address auto                    # each run a Ray task
    python -m agents.benchmark --merge docs/benchmark.json       # the published runs reused
    python -m agents.benchmark --tiny --out /tmp/bench           # a minute: the whole pipeline

A method (:data:`METHODS`) is a training config of ``configs/agents/`` on a protocol env, or a
baseline (``random``, ``heuristic``; one run, no training). Each method x seed is a job: train
the config with ``seed=S`` for the protocol's frames (``total_frames``, no time limit) into
``OUT/METHOD/seedS/RUN`` (``agents.train``'s run folder), then evaluate the run's model on the
protocol's games (``RUN/protocol_eval``: ``agents.evaluate --protocol``). Jobs are resumable: a
run with its evaluation is reused, a run without a model goes on from its last checkpoint, and
a run whose config is not the one the job would train is an error (delete it or pick another
``--out``). Locally the jobs run one at a time (``--parallel N``: N at once, each in its own
process); with ``--address`` each is a Ray task with its own CPUs (the config's threads) on the
cluster, which gets this code, trains and evaluates in a scratch folder and sends the run folder
back (a partial run is sent out to go on with), so that a cluster gives the whole table in the
time of one run.

Then the results are aggregated into ``OUT``:

- ``benchmark.json``: the protocol, the commit, and per method its env, config, runs (seed,
  score mean and IQM, frames, minutes of training) and the protocol's metrics
  (``pinball_env.protocol.aggregate``: mean and IQM of the score and of the normalised score,
  with stratified bootstrap 95% intervals), and the reference means measured (random and the
  heuristic, per env);
- ``benchmark.csv`` (a row per method), ``runs.csv`` (a row per run) and ``benchmark.md`` (the
  table in Markdown);
- ``scores.png`` (the score distribution of every method's games, per env) and
  ``profiles.png`` (performance profiles of the normalised scores with 95% bands, per env).

``--merge BENCHMARK_JSON ...`` takes the runs OUT lacks from earlier benchmarks (another
machine's, or the results published in ``docs/benchmark.json``: run folders are outputs, the
published file keeps every run's game scores, its commit and the digest of its config); their
jobs are not run again, and a file of another protocol or a run of a config changed since is
refused. A table can so grow over machines and sessions, a run at a time.

``--ship METHOD[=NAME] ...`` makes each method's best run (by its validation games, never the
held-out ones) a pretrained agent that ships with the project: ``agents/pretrained/NAME.zip``
and its card ``NAME.json`` (method, config, commit, training, scores under the protocol),
loadable as ``pretrained:NAME`` (``agents.policy.load_policy``). NAME is the method's unless
given: ``--ship ppo-gentle-v1=ppo-v1`` ships the best recipe under the name users load. The
chosen run must be in OUT, where its model is; ``--ship-from-out`` ships the best run there when
a better merged one's model is gone, and its card says so.

``--tiny`` trains a few thousand frames of small settings and plays a few games: the whole
pipeline in about a minute, for tests.
"""

import argparse
import concurrent.futures
import csv
import dataclasses
import hashlib
import io
import json
import os
import shutil
import subprocess
import sys
import tarfile
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

from agents.config import ConfigError, TrainConfig, config_from_dict, load_config, load_run_config
from agents.report import PROTOCOL_EVAL, evaluate
from agents.runs import (
    MODEL_FILE,
    best_validation,
    latest_checkpoint,
    progress_rows,
    read_meta,
    source_commit,
    validation_rows,
)
from pinball_env import protocol

CONFIGS = Path(__file__).resolve().parent.parent / "configs" / "agents"
COMMIT_VARIABLE = "PINBALL_SOURCE_COMMIT"  # a cluster node's commit: the driver's (agents.runs)
JOB_FILE = "job.json"  # in OUT/METHOD/seedS: where and how long the job trained and evaluated
SUMMARY = "summary.json"
# Runs of earlier benchmarks (--merge): per method, its runs as benchmark.json has them.
Merged = dict[str, list[dict[str, Any]]]


@dataclasses.dataclass(frozen=True)
class Method:
    """A row of the benchmark: a training ``config`` (a file of configs/agents) trained for
    ``frames`` (one of the protocol's ``TRAINING_BUDGETS``) or a ``baseline``, on ``env_id``;
    ``tiny``: the overrides of ``--tiny``."""

    env_id: str
    config: str | None = None
    baseline: str | None = None
    tiny: tuple[str, ...] = ()
    frames: int = protocol.TRAINING_FRAMES

    def __post_init__(self) -> None:
        if self.frames not in protocol.TRAINING_BUDGETS:
            raise ValueError(f"frames={self.frames}: not a budget of the protocol")

    @property
    def trained(self) -> bool:
        return self.config is not None


# Small settings for --tiny: a few updates of small networks.
_TINY = ("imitation_steps=0", "validate_every=0", "checkpoint_every=0", "env.num_envs=2")
_TINY_PPO = (*_TINY, "hyperparams.n_steps=64", "hyperparams.batch_size=64",
             "hyperparams.n_epochs=1")  # fmt: skip
_TINY_A2C = (*_TINY, "hyperparams.n_steps=8")
_TINY_DQN = (*_TINY, "hyperparams.learning_starts=200", "hyperparams.buffer_size=2000",
             "hyperparams.batch_size=64")  # fmt: skip

METHODS: dict[str, Method] = {
    "random-v2": Method("Pinball-v2", baseline="random"),
    "heuristic-v2": Method("Pinball-v2", baseline="heuristic"),
    "ppo-scale-v2": Method("Pinball-v2", "ppo_scale_v2.yaml", tiny=_TINY_PPO),
    "ppo-scale-v2-200m": Method(
        "Pinball-v2", "ppo_scale_v2.yaml", tiny=_TINY_PPO, frames=protocol.LONG_TRAINING_FRAMES
    ),
    "a2c-scale-v2": Method("Pinball-v2", "a2c_scale_v2.yaml", tiny=_TINY_A2C),
    "dqn-scale-v2": Method("Pinball-v2", "dqn_scale_v2.yaml", tiny=_TINY_DQN),
    "random-v1": Method("Pinball-v1", baseline="random"),
    "heuristic-v1": Method("Pinball-v1", baseline="heuristic"),
    "ppo-v1": Method("Pinball-v1", "ppo_v1.yaml", tiny=_TINY_PPO),
    "ppo-sticky-v1": Method("Pinball-v1", "ppo_sticky_v1.yaml", tiny=_TINY_PPO),
    "ppo-wide-v1": Method("Pinball-v1", "ppo_wide_v1.yaml", tiny=_TINY_PPO),
    "ppo-finetune-v1": Method("Pinball-v1", "ppo_finetune_v1.yaml", tiny=_TINY_PPO),
    "ppo-steady-v1": Method("Pinball-v1", "ppo_steady_v1.yaml", tiny=_TINY_PPO),
    "ppo-gentle-v1": Method("Pinball-v1", "ppo_gentle_v1.yaml", tiny=_TINY_PPO),
    "ppo-close-v1": Method("Pinball-v1", "ppo_close_v1.yaml", tiny=_TINY_PPO),
    "ppo-broad-v1": Method("Pinball-v1", "ppo_broad_v1.yaml", tiny=_TINY_PPO),
    "ppo-anchor-v1": Method("Pinball-v1", "ppo_anchor_v1.yaml", tiny=_TINY_PPO),
    "a2c-v1": Method("Pinball-v1", "a2c_v1.yaml", tiny=_TINY_A2C),
    "dqn-v1": Method("Pinball-v1", "dqn_v1.yaml", tiny=_TINY_DQN),
    "ppo-pixels-v1": Method("Pinball-v1", "ppo_pixels_v1.yaml", tiny=_TINY_PPO),
    "random-v0": Method("Pinball-v0", baseline="random"),
    "heuristic-v0": Method("Pinball-v0", baseline="heuristic"),
    "ppo-v0": Method("Pinball-v0", "ppo.yaml", tiny=_TINY_PPO),
}
TINY_FRAMES = 3000
TINY_EPISODES = 3


@dataclasses.dataclass(frozen=True)
class Settings:
    """What every job of one benchmark shares."""

    out: Path
    episodes: int = len(protocol.EVAL_SEEDS)
    tiny: bool = False

    def frames(self, name: str) -> int:
        """The frames method ``name`` trains for: its budget (--tiny: TINY_FRAMES)."""
        return TINY_FRAMES if self.tiny else METHODS[name].frames


def job_folder(settings: Settings, name: str, seed: int) -> Path:
    """Where a job's results go: ``OUT/METHOD/seedS`` (a baseline: ``OUT/METHOD``)."""
    return settings.out / name / f"seed{seed}" if METHODS[name].trained else settings.out / name


# Keys counted in steps that a method on the long budget scales with it (its schedules and
# validations spread over ten times the frames).
SCALED_BY_BUDGET = ("total_timesteps", "checkpoint_every", "validate_every")


def job_config(name: str, seed: int, settings: Settings) -> TrainConfig:
    """The training config of a job: the method's config, seed ``seed``, the method's budget in
    frames and no time limit (and ``--tiny``'s settings). On a budget above the protocol's
    first, the config's ``SCALED_BY_BUDGET`` keys are scaled by the budget's ratio to it."""
    method = METHODS[name]
    overrides = [f"seed={seed}", "max_minutes=0", f"total_frames={settings.frames(name)}"]
    if method.frames != protocol.TRAINING_FRAMES and not settings.tiny:
        config = load_config(CONFIGS / method.config)
        ratio = method.frames // protocol.TRAINING_FRAMES
        overrides += [f"{key}={getattr(config, key) * ratio}" for key in SCALED_BY_BUDGET]
    return load_config(
        CONFIGS / method.config, [*overrides, *(method.tiny if settings.tiny else ())]
    )


def job_run(
    name: str, seed: int, settings: Settings, config: TrainConfig | None = None
) -> Path | None:
    """The run folder of a job (None before it starts); ConfigError if it holds another config
    than the job's (``config``, by default :func:`job_config`'s) or several runs."""
    folder = job_folder(settings, name, seed)
    runs = sorted(p for p in folder.glob("*") if (p / "config.yaml").is_file())
    if len(runs) > 1:
        raise ConfigError(f"{folder}: several run folders ({', '.join(p.name for p in runs)})")
    if not runs:
        return None
    expected = config or job_config(name, seed, settings)
    found, wanted = _trained_by(load_run_config(runs[0])), _trained_by(expected)
    differ = sorted(key for key in found | wanted if found.get(key) != wanted.get(key))
    if differ:
        raise ConfigError(
            f"{runs[0]}: trained with another config than {name} seed {seed} under the protocol "
            f"({', '.join(f'{key}: {found.get(key)!r}, not {wanted.get(key)!r}' for key in differ)}"
            "; delete it, or give another --out)"
        )
    return runs[0]


# Keys added to the configs after runs were published, each with its default, which trains as
# before the key was there: at it, the key stays out of the digest, so those runs keep theirs.
LATER_KEYS = {"anchor_coef": 0.0}


def _trained_by(config: TrainConfig) -> dict[str, Any]:
    """What of a config trains, flat: all of it but its ``notes`` (words do not train) and the
    later keys at their defaults (``LATER_KEYS``)."""
    return {
        key: value for key, value in _flat(config.to_dict()).items()
        if key != "notes" and not (key in LATER_KEYS and value == LATER_KEYS[key])
    }  # fmt: skip


def config_digest(config: TrainConfig) -> str:
    """A short digest of what of ``config`` trains: a run of another config has another."""
    text = json.dumps(_trained_by(config), sort_keys=True, default=str)
    return hashlib.sha256(text.encode()).hexdigest()[:16]


def _flat(data: dict[str, Any], prefix: str = "") -> dict[str, Any]:
    """A nested config as ``{"env.kwargs.frame_skip": 1, ...}``."""
    flat = {}
    for key, value in data.items():
        if isinstance(value, dict) and value:
            flat.update(_flat(value, f"{prefix}{key}."))
        else:
            flat[f"{prefix}{key}"] = value
    return flat


def job_done(name: str, seed: int, settings: Settings, config: TrainConfig | None = None) -> bool:
    """The job's evaluation of this benchmark's games is written (so its training finished)."""
    if METHODS[name].trained:
        run = job_run(name, seed, settings, config)
        if run is None or not (run / MODEL_FILE).is_file():
            return False
        summary = run / PROTOCOL_EVAL / SUMMARY
    else:
        summary = job_folder(settings, name, seed) / PROTOCOL_EVAL / SUMMARY
    if not summary.is_file():
        return False
    first = protocol.EVAL_SEEDS.start
    return json.loads(summary.read_text())["seeds"] == [first, first + settings.episodes - 1]


def run_job(name: str, seed: int, settings: Settings, config: TrainConfig | None = None) -> Path:
    """Train (or go on training) and evaluate one method x seed; returns its results folder.
    A finished job is left as it is. ``config``: the job's training config (by default
    :func:`job_config`'s; a cluster node gets it from the driver, it has no configs/)."""
    method, folder = METHODS[name], job_folder(settings, name, seed)
    if method.trained and config is None:
        config = job_config(name, seed, settings)
    if job_done(name, seed, settings, config):
        return folder
    folder.mkdir(parents=True, exist_ok=True)
    if not method.trained:
        _evaluate_job(folder, settings, folder / PROTOCOL_EVAL, policy=method.baseline,
                      env=method.env_id)  # fmt: skip
        return folder
    from agents.train import start, train

    run = job_run(name, seed, settings, config)
    if run is not None and latest_checkpoint(run) is None:  # stopped before its first: anew
        shutil.rmtree(run)
        (folder / JOB_FILE).unlink(missing_ok=True)  # (and the minutes thrown away with it)
        run = None
    if run is None or not (run / MODEL_FILE).is_file():
        resume = run is not None
        training_started = time.monotonic()
        if run is None:
            run = start(config, folder, ["agents.benchmark", name, f"seed={seed}"])
        try:
            train(config, run, resume=resume, progress_bar=False)
        finally:  # a stopped job's minutes count in the run's, which goes on from its checkpoint
            _log_job(folder, train_seconds=time.monotonic() - training_started)
    _evaluate_job(folder, settings, run / PROTOCOL_EVAL, model_path=run)
    return folder


def _evaluate_job(folder: Path, settings: Settings, out: Path, **agent: Any) -> None:
    """Play the protocol's games with ``agent`` (evaluate's policy/env or model_path) into
    ``out``, timed in the job's record."""
    started = time.monotonic()
    evaluate(episodes=settings.episodes, out=out, protocol=True, **agent)
    _log_job(folder, evaluate_seconds=time.monotonic() - started)


def _log_job(folder: Path, node: str | None = None, **seconds: float) -> None:
    """Add ``seconds`` (train_seconds, evaluate_seconds) to the job's record, with the host (and
    the Ray ``node`` it ran on)."""
    path = folder / JOB_FILE
    record = json.loads(path.read_text()) if path.is_file() else {}
    for key, value in seconds.items():
        record[key] = round(record.get(key, 0.0) + value, 3)  # (a tenth would lose short pieces)
    if node is not None:
        record["node"] = node
    else:
        record["host"] = os.uname().nodename
    path.write_text(json.dumps(record, indent=1))


# --- running the jobs ---------------------------------------------------------------------------


def run_local(jobs: list[tuple[str, int]], settings: Settings, parallel: int) -> None:
    """Each job in its own process (``python -m agents.benchmark --job``), ``parallel`` at once."""

    def one(job: tuple[str, int]) -> None:
        name, seed = job
        command = [sys.executable, "-m", "agents.benchmark", "--job", f"{name}:{seed}",
                   *_settings_args(settings)]  # fmt: skip
        print(f"{name} seed {seed}: running")
        done = subprocess.run(command, cwd=CONFIGS.parent.parent)
        if done.returncode != 0:
            raise RuntimeError(f"{name} seed {seed} failed (exit status {done.returncode})")
        print(f"{name} seed {seed}: done")

    with concurrent.futures.ThreadPoolExecutor(max_workers=parallel) as pool:
        for future in [pool.submit(one, job) for job in jobs]:
            future.result()


def _settings_args(settings: Settings) -> list[str]:
    return ["--out", str(settings.out), "--episodes", str(settings.episodes),
            *(["--tiny"] if settings.tiny else [])]  # fmt: skip


def pack(folder: Path) -> bytes:
    """A folder as a gzipped tar (empty bytes for a missing folder)."""
    if not folder.is_dir():
        return b""
    buffer = io.BytesIO()
    with tarfile.open(fileobj=buffer, mode="w:gz") as archive:
        archive.add(folder, arcname=".")
    return buffer.getvalue()


def unpack(data: bytes, folder: Path) -> None:
    """:func:`pack`'s bytes into ``folder``, replacing what it held once they are unpacked
    whole (nothing changes if they are not)."""
    folder.parent.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(dir=folder.parent) as scratch:
        unpacked = Path(scratch) / folder.name
        with tarfile.open(fileobj=io.BytesIO(data), mode="r:gz") as archive:
            # (the "data" filter refuses links and paths out of the folder; Python >= 3.10.12)
            safe = {"filter": "data"} if hasattr(tarfile, "data_filter") else {}
            archive.extractall(unpacked, **safe)
        if folder.exists():
            shutil.rmtree(folder)
        os.replace(unpacked, folder)


def remote_job(
    name: str, seed: int, settings: Settings, config: dict[str, Any] | None, partial: bytes,
    commit: str | None,
) -> tuple[bytes, str, str | None]:  # fmt: skip
    """A job on a cluster node: in a scratch folder, from ``partial`` (the folder as the driver
    has it), run with ``config`` (the driver's, as data; the node has no configs/ and no git,
    so the driver's ``commit`` is recorded). Returns the folder (as far as it got, also when the
    job failed), the node's id and the error, if any."""
    import ray

    if commit:
        os.environ[COMMIT_VARIABLE] = commit
    node = ray.get_runtime_context().get_node_id()
    with tempfile.TemporaryDirectory() as scratch:
        here = dataclasses.replace(settings, out=Path(scratch))
        folder = job_folder(here, name, seed)
        if partial:
            unpack(partial, folder)
        try:
            run_job(name, seed, here, None if config is None else config_from_dict(config))
        except Exception as error:  # the folder comes back all the same: a rerun goes on
            return pack(folder), node, f"{type(error).__name__}: {error}"
        return pack(folder), node, None


def run_on_cluster(jobs: list[tuple[str, int]], settings: Settings, address: str) -> None:
    """Each job as a Ray task on the cluster at ``address``, its folder gathered into OUT; a
    job that fails is reported (its folder kept, to go on from) after the others are in."""
    import ray

    from agents.rllib import init_ray

    init_ray(address)
    task = ray.remote(remote_job)
    pending = {}
    for name, seed in jobs:
        config = job_config(name, seed, settings) if METHODS[name].trained else None
        folder = job_folder(settings, name, seed)
        cpus = float(max(config.torch_threads, config.env_threads)) if config else 1.0
        sent = task.options(num_cpus=cpus).remote(
            name, seed, settings, config and config.to_dict(), pack(folder), source_commit()
        )
        pending[sent] = (name, seed)
    print(f"{len(pending)} jobs sent to the cluster at {address}")
    failed = []
    while pending:
        ready, _ = ray.wait(list(pending))
        name, seed = pending.pop(ready[0])
        try:
            data, node, error = ray.get(ready[0])
        except ray.exceptions.RayError as lost:  # the task or its node died
            failed.append(f"{name} seed {seed}: {lost}")
            continue
        folder = job_folder(settings, name, seed)
        if data:
            unpack(data, folder)
            _log_job(folder, node=node)
        if error is not None:
            failed.append(f"{name} seed {seed} (node {node}): {error}")
        print(f"{name} seed {seed}: {'failed' if error else 'done'} on node {node}")
    if failed:
        raise ConfigError(f"{len(failed)} job(s) failed (run again to go on): {'; '.join(failed)}")


# --- the table ----------------------------------------------------------------------------------


def method_results(
    name: str, seeds: list[int], settings: Settings, merged: Merged | None = None
) -> dict[str, Any] | None:
    """The runs of a method that are done (in OUT, else in ``merged``: :func:`merged_runs`) and
    the protocol's metrics over them (None: none)."""
    method = METHODS[name]
    runs = []
    for seed in seeds if method.trained else [0]:
        if not job_done(name, seed, settings):
            if (earlier := _merged_run(merged, name, seed)) is not None:
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
            **(_training(run, job) if method.trained else {}),
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


def merged_runs(paths: list[Path], names: list[str], settings: Settings) -> Merged:
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
                if _merged_run(merged, name, run["seed"]) is not None:
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


def _merged_run(merged: Merged | None, name: str, seed: int | None) -> dict[str, Any] | None:
    """The merged run of a method x seed (a baseline's: its one run), or None."""
    wanted = seed if METHODS[name].trained else None
    return next((run for run in (merged or {}).get(name, []) if run["seed"] == wanted), None)


def _training(run: Path, job: dict[str, Any]) -> dict[str, Any]:
    """A run's frames and steps trained, its minutes of training (the job's record, or for a run
    trained outside the benchmark, from its start to its model), its best validation score (its
    model's), its commit and its config's digest."""
    meta = read_meta(run)
    rows = progress_rows(run)  # (a run from before meta.json's "trained": its last rollout's)
    trained = meta.get("trained") or {
        "frames": max((int(float(row["time/frames"])) for row in rows if row.get("time/frames")),
                      default=0),
        "steps": max((int(float(row["time/total_timesteps"])) for row in rows), default=0),
    }  # fmt: skip
    frames, steps = trained["frames"], trained["steps"]
    digest = config_digest(load_run_config(run))
    validated = best_validation(validation_rows(run))
    seconds = job.get("train_seconds")
    if seconds is None:
        started = time.mktime(time.strptime(meta["started"], "%Y-%m-%dT%H:%M:%S"))
        seconds = (run / MODEL_FILE).stat().st_mtime - started
    return {"frames": frames, "steps": steps, "train_minutes": round(seconds / 60.0, 1),
            "validation": validated and validated["score_mean"], "commit": meta.get("commit"),
            "config_digest": digest}  # fmt: skip


def protocol_record(settings: Settings) -> dict[str, Any]:
    """The protocol as this benchmark applies it (``benchmark.json``'s ``protocol``)."""
    first = protocol.EVAL_SEEDS.start
    return {
        "env_ids": list(protocol.ENV_IDS),
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
    names: list[str], seeds: list[int], settings: Settings, merged: Merged | None = None
) -> dict[str, Any]:
    """Write benchmark.json, benchmark.csv, runs.csv and the plots; returns the table."""
    results = {name: method_results(name, seeds, settings, merged) for name in names}
    methods = {name: result for name, result in results.items() if result is not None}
    reference: dict[str, dict[str, float]] = {}
    for name, result in methods.items():
        if METHODS[name].baseline is not None:
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


def markdown_table(methods: dict[str, Any]) -> str:
    """The table as Markdown (``benchmark.md``, the README's): a row per method."""
    lines = [
        "| method | env | runs | score: mean [95% CI] | IQM [95% CI] | normalised IQM [95% CI] "
        "| training per run |",
        "|---|---|---|---|---|---|---|",
    ]
    for name, result in methods.items():
        cells = []
        for key, digits in (("score_mean", 0), ("score_iqm", 0), ("normalized_iqm", 2)):
            low, high = result[f"{key}_ci95"]
            cells.append(f"{result[key]:.{digits}f} [{low:.{digits}f}, {high:.{digits}f}]")
        runs = [run for run in result["runs"] if "frames" in run]
        training = "-"
        if runs:
            frames = np.mean([run["frames"] for run in runs]) / 1e6
            minutes = np.mean([run["train_minutes"] for run in runs])
            training = f"{frames:.1f}M frames, {minutes:.0f} min"
        lines.append(f"| {name} | {result['env_id']} | {len(result['runs'])} | "
                     f"{' | '.join(cells)} | {training} |")  # fmt: skip
    return "\n".join(lines) + "\n"


def plot_benchmark(methods: dict[str, Any], out: Path) -> None:
    """``scores.png`` (every method's game scores, per env) and ``profiles.png`` (performance
    profiles of the normalised scores with 95% bands, per env)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    envs = [env for env in protocol.ENV_IDS if any(m["env_id"] == env for m in methods.values())]
    for kind, draw in (("scores", _draw_scores), ("profiles", _draw_profiles)):
        figure, axes = plt.subplots(1, len(envs), figsize=(6.0 * len(envs), 4.0), squeeze=False)
        for ax, env_id in zip(axes[0], envs, strict=True):
            runs = {name: [np.asarray(run["scores"], dtype=np.float64) for run in m["runs"]]
                    for name, m in methods.items() if m["env_id"] == env_id}  # fmt: skip
            draw(ax, runs, env_id)
            ax.set_title(f"{env_id}, the protocol's games")
        figure.tight_layout()
        figure.savefig(out / f"{kind}.png", dpi=100)
        plt.close(figure)


def _draw_scores(ax: Any, runs: dict[str, list[np.ndarray]], env_id: str) -> None:
    ax.boxplot([np.concatenate(games) for games in runs.values()], showmeans=True)
    ax.set_xticks(range(1, len(runs) + 1), list(runs), rotation=20)
    ax.set_ylabel("game score")


def _draw_profiles(ax: Any, runs: dict[str, list[np.ndarray]], env_id: str) -> None:
    normalized = {name: [protocol.normalized(games, env_id) for games in method_runs]
                  for name, method_runs in runs.items()}  # fmt: skip
    # The protocol's thresholds, widened to hold 98% of these games.
    taus = protocol.PROFILE_TAUS
    pooled = np.concatenate([np.concatenate(method_runs) for method_runs in normalized.values()])
    low, high = np.percentile(pooled, [1, 99])
    if low < taus[0] or high > taus[-1]:
        taus = np.linspace(min(low, taus[0]), max(high, taus[-1]), len(taus))
    for name, method_runs in normalized.items():
        ax.plot(taus, protocol.performance_profile(method_runs, taus), label=name)
        ax.fill_between(taus, *protocol.profile_band(method_runs, taus), alpha=0.2)
    ax.axvline(1.0, color="grey", linewidth=0.8, linestyle=":")
    ax.set_xlabel("normalised score τ (random 0, heuristic 1)")
    ax.set_ylabel("share of games scoring > τ")
    ax.legend(fontsize=8)


# The first protocol games a pretrained agent's card lists the scores of (its test plays them).
CHECK_GAMES = 5


def parse_ship(text: str) -> tuple[str, str]:
    """``METHOD`` or ``METHOD=NAME`` (of ``--ship``): the method and the name it ships as."""
    method, _, name = text.partition("=")
    name = name or method
    if method not in METHODS or not METHODS[method].trained:
        trained = ", ".join(key for key, value in METHODS.items() if value.trained)
        raise ConfigError(f"--ship {text}: {method!r} is not a trained method (one of {trained})")
    if not name.replace("-", "").replace("_", "").isalnum():
        raise ConfigError(f"--ship {text}: the name {name!r} is not letters, digits, - and _")
    return method, name


def ship(
    name: str,
    seeds: list[int],
    settings: Settings,
    ship_as: str | None = None,
    into: Path | None = None,
    merged: Merged | None = None,
    from_out: bool = False,
) -> Path:
    """Make the best run of method ``name`` (by its validation games, never the held-out ones;
    of the runs in OUT and ``merged``, the chosen one in OUT; with ``from_out``, of those in OUT
    alone, the card naming the better run whose model is not here) a pretrained agent ``ship_as``
    (default: the method's name) in ``into`` (default: ``agents/pretrained``): ``SHIP_AS.zip``
    (its model) and ``SHIP_AS.json``, its card: the method and config, the commit it was
    trained at, its frames and minutes of training, its scores under the protocol, and the
    scores of the first CHECK_GAMES protocol games."""
    from agents.policy import PRETRAINED_DIR

    ship_as, into = ship_as or name, into or PRETRAINED_DIR
    result = method_results(name, seeds, settings, merged)
    if result is None or not METHODS[name].trained:
        raise ConfigError(f"{name}: no finished training run to ship in {settings.out}")
    runs = result["runs"]
    short = [run["seed"] for run in runs if run["frames"] < 0.99 * settings.frames(name)]
    if short or len(runs) < len(protocol.TRAINING_SEEDS):
        raise ConfigError(
            f"{name}: ships the best of at least {len(protocol.TRAINING_SEEDS)} runs trained for "
            f"the protocol's frames; {len(runs)} are done"
            + (f", seeds {short} stopped short" if short else "")
        )
    unvalidated = [run["seed"] for run in runs if run.get("validation") is None]
    if unvalidated:
        raise ConfigError(f"{name}: seeds {unvalidated} have no validation games to choose by")
    best = max(runs, key=lambda run: run["validation"])
    chosen_by = f"the best validation score of {len(runs)} seeds ({best['validation']:.0f})"
    here = [run for run in runs if "from" not in run]
    if "from" in best and not (from_out and here):
        raise ConfigError(
            f"{name}: its best run, seed {best['seed']} ({chosen_by}), is in {best['from']} "
            f"but not in {settings.out}: train it there (--seeds {best['seed']}) to ship it, "
            f"or ship the best of the runs there (--ship-from-out)"
        )
    chosen = max(here, key=lambda run: run["validation"])
    if chosen is not best:
        chosen_by = (
            f"the best validation score of the {len(here)} of {len(runs)} seeds whose models "
            f"are here ({chosen['validation']:.0f}; seed {best['seed']}'s model, "
            f"{best['validation']:.0f}, was not kept)"
        )
    run = settings.out / chosen["run"]
    card = {
        "name": ship_as,
        "method": name,
        "env_id": result["env_id"],
        "config": METHODS[name].config,
        "seed": chosen["seed"],
        "commit": chosen["commit"],
        "trained": {key: chosen[key] for key in ("frames", "steps", "train_minutes")},
        "chosen_by": chosen_by,
        "protocol": {
            key: value
            for key, value in protocol.aggregate([chosen["scores"]], result["env_id"]).items()
            if key != "run_means"
        },
        "check_games": {
            "seeds": list(protocol.EVAL_SEEDS[:CHECK_GAMES]),
            "scores": chosen["scores"][:CHECK_GAMES],
        },
        "load": f'agents.policy.load_policy("pretrained:{ship_as}")',
    }
    into.mkdir(exist_ok=True)
    shutil.copyfile(run / MODEL_FILE, into / f"{ship_as}.zip")
    (into / f"{ship_as}.json").write_text(json.dumps(card, indent=1) + "\n")
    print(f"shipped {run} as pretrained:{ship_as} ({card['chosen_by']})")
    return into / f"{ship_as}.zip"


def print_table(table: dict[str, Any]) -> None:
    for name, result in table["methods"].items():
        low, high = result["score_iqm_ci95"]
        print(
            f"{name:14s} {result['env_id']}  runs {len(result['runs'])}  score mean "
            f"{result['score_mean']:8.0f}  IQM {result['score_iqm']:8.0f} ({low:.0f}-{high:.0f})  "
            f"normalised {result['normalized_mean']:.2f}"
        )


def main(argv: list[str] | None = None) -> dict[str, Any] | None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--methods", nargs="+", choices=list(METHODS), default=list(METHODS),
                        help="the rows (default: all)")  # fmt: skip
    parser.add_argument("--seeds", nargs="+", type=int, default=list(protocol.TRAINING_SEEDS),
                        help="training seeds (default: the protocol's)")  # fmt: skip
    parser.add_argument("--out", type=Path, default=Path("runs/benchmark"), help="results")
    parser.add_argument("--episodes", type=int, help="held-out games per run (default: 100)")
    parser.add_argument("--parallel", type=int, default=1, help="local jobs at once")
    parser.add_argument("--address", help="a Ray cluster to run the jobs on (auto, HOST:PORT)")
    parser.add_argument("--tiny", action="store_true", help="tiny settings, for tests")
    parser.add_argument("--job", help=argparse.SUPPRESS)  # METHOD:SEED, one job (run_local's)
    parser.add_argument("--table-only", action="store_true", help="aggregate what is done")
    parser.add_argument("--merge", nargs="+", type=Path, default=[], metavar="BENCHMARK_JSON",
                        help="runs of earlier benchmarks that OUT lacks")  # fmt: skip
    parser.add_argument("--ship", nargs="+", default=[], metavar="METHOD[=NAME]",
                        help="make each method's best run a pretrained agent (NAME)")  # fmt: skip
    parser.add_argument("--ship-from-out", action="store_true",
                        help="--ship the best run in OUT, not of merged ones")  # fmt: skip
    args = parser.parse_args(argv)
    if args.episodes is None:
        args.episodes = TINY_EPISODES if args.tiny else len(protocol.EVAL_SEEDS)
    if args.parallel < 1 or not 1 <= args.episodes <= len(protocol.EVAL_SEEDS):
        parser.error("--parallel must be >= 1 and --episodes in 1..100")
    if any(seed < 0 for seed in args.seeds):
        parser.error("seeds must be >= 0")
    if args.ship and args.tiny:
        parser.error("--ship ships agents trained under the protocol, not --tiny ones")
    settings = Settings(args.out.resolve(), args.episodes, args.tiny)
    try:
        ships = [parse_ship(text) for text in args.ship]
        if args.job is not None:
            name, _, seed = args.job.partition(":")
            run_job(name, int(seed), settings)
            return None
        args.methods, args.seeds = list(dict.fromkeys(args.methods)), sorted(set(args.seeds))
        jobs = [(name, seed) for name in args.methods
                for seed in (args.seeds if METHODS[name].trained else [0])]  # fmt: skip
        merged = merged_runs(args.merge, args.methods, settings)
        todo = [job for job in jobs
                if not job_done(*job, settings) and _merged_run(merged, *job) is None]  # fmt: skip
        if todo and not args.table_only:
            print(f"{len(jobs) - len(todo)} of {len(jobs)} jobs done already; running {len(todo)}")
            if args.address:
                run_on_cluster(todo, settings, args.address)
            else:
                run_local(todo, settings, args.parallel)
        table = aggregate_table(args.methods, args.seeds, settings, merged)
        for name, ship_as in ships:
            ship(name, args.seeds, settings, ship_as, merged=merged, from_out=args.ship_from_out)
    except ConfigError as error:
        parser.exit(2, f"error: {error}\n")
    print_table(table)
    print(f"-> {settings.out}/benchmark.json, benchmark.csv, runs.csv, scores.png, profiles.png")
    return table


if __name__ == "__main__":
    main()
