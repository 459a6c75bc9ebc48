"""The benchmark's jobs: a method x seed trained (or gone on training from its last checkpoint)
and evaluated on the protocol's games, in its own folder of ``OUT``; run locally, each in its own
process, or each as a Ray task on a cluster that sends its folder back."""

import concurrent.futures
import dataclasses
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
from typing import TYPE_CHECKING, Any

from agents.benchmark.methods import CONFIGS, METHODS, SCALED_BY_BUDGET, TINY_FRAMES, trained_by
from agents.config import ConfigError, config_from_dict, load_config, load_run_config
from agents.evaluation import PROTOCOL_EVAL, evaluate_protocol, player_for
from agents.runs import MODEL_FILE, latest_checkpoint, source_commit
from pinball_env import protocol

if TYPE_CHECKING:
    from agents.benchmark.methods import JobConfig

COMMIT_VARIABLE = "PINBALL_SOURCE_COMMIT"  # a cluster node's commit: the driver's (agents.runs)
JOB_FILE = "job.json"  # in OUT/METHOD/seedS: where and how long the job trained and evaluated
SUMMARY = "summary.json"


@dataclasses.dataclass(frozen=True)
class JobSettings:
    """What every job of one benchmark shares."""

    out: Path
    episodes: int = len(protocol.EVAL_SEEDS)
    tiny: bool = False

    def frames(self, name: str) -> int:
        """The frames method ``name`` trains for: its budget (--tiny: TINY_FRAMES)."""
        return TINY_FRAMES if self.tiny else METHODS[name].frames


def job_folder(settings: JobSettings, name: str, seed: int) -> Path:
    """Where a job's results go: ``OUT/METHOD/seedS`` (a baseline: ``OUT/METHOD``)."""
    return settings.out / name / f"seed{seed}" if METHODS[name].trained else settings.out / name


def job_config(name: str, seed: int, settings: JobSettings) -> "JobConfig":
    """The training config of a job: the method's config, seed ``seed``, the method's budget in
    frames and no time limit (and ``--tiny``'s settings). On a budget above the protocol's
    first, the config's ``SCALED_BY_BUDGET`` keys are scaled by the budget's ratio to it. A
    distilled method's: its distillation config, the budget its ``total_frames``."""
    method = METHODS[name]
    tiny = method.tiny if settings.tiny else ()
    if method.distilled:
        from agents.distill import load_distill_config

        return load_distill_config(
            method.config_path, [f"seed={seed}", f"total_frames={settings.frames(name)}", *tiny]
        )
    overrides = [f"seed={seed}", "max_minutes=0", f"total_frames={settings.frames(name)}"]
    if method.frames != protocol.TRAINING_FRAMES and not settings.tiny:
        config = load_config(method.config_path)
        ratio = method.frames // protocol.TRAINING_FRAMES
        overrides += [f"{key}={getattr(config, key) * ratio}" for key in SCALED_BY_BUDGET]
    return load_config(method.config_path, [*overrides, *tiny])


def run_config(name: str, run: Path) -> "JobConfig":
    """The config a run of method ``name`` was trained with (a distillation's: its own)."""
    if METHODS[name].distilled:
        from agents.distill import DISTILL_FILE, load_distill_config

        return load_distill_config(run / DISTILL_FILE)
    return load_run_config(run)


def config_of_data(name: str, data: dict[str, Any]) -> "JobConfig":
    """The config of method ``name`` from its ``to_dict()`` (a cluster node's, which has no
    configs/)."""
    if METHODS[name].distilled:
        from agents.distill import distill_config_from_dict

        return distill_config_from_dict(data, f"{name}'s config")
    return config_from_dict(data)


def job_run(
    name: str, seed: int, settings: JobSettings, config: "JobConfig | None" = None
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
    found, wanted = trained_by(run_config(name, runs[0])), trained_by(expected)
    differ = sorted(key for key in found | wanted if found.get(key) != wanted.get(key))
    if differ:
        raise ConfigError(
            f"{runs[0]}: trained with another config than {name} seed {seed} under the protocol "
            f"({', '.join(f'{key}: {found.get(key)!r}, not {wanted.get(key)!r}' for key in differ)}"
            "; delete it, or give another --out)"
        )
    return runs[0]


def job_done(
    name: str, seed: int, settings: JobSettings, config: "JobConfig | None" = None
) -> bool:
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


def run_job(name: str, seed: int, settings: JobSettings, config: "JobConfig | None" = None) -> Path:
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
    if method.distilled:
        return _distill_job(name, seed, settings, config)
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


def _distill_job(name: str, seed: int, settings: JobSettings, config: Any) -> Path:
    """:func:`run_job` of a distilled method: distilled (anew, where a run stopped before its
    model: a distillation does not go on from a checkpoint) and evaluated."""
    from agents.distill import distill

    folder, run = job_folder(settings, name, seed), job_run(name, seed, settings, config)
    if run is not None and not (run / MODEL_FILE).is_file():
        shutil.rmtree(run)
        (folder / JOB_FILE).unlink(missing_ok=True)
        run = None
    if run is None:
        started = time.monotonic()
        try:
            run = distill(config, folder, ["agents.benchmark", name, f"seed={seed}"])
        finally:
            _log_job(folder, train_seconds=time.monotonic() - started)
    _evaluate_job(folder, settings, run / PROTOCOL_EVAL, model_path=run)
    return folder


def _evaluate_job(folder: Path, settings: JobSettings, out: Path, **agent: Any) -> None:
    """Play the protocol's games with ``agent`` (evaluate's policy/env or model_path) into
    ``out``, timed in the job's record."""
    started = time.monotonic()
    evaluate_protocol(player_for(**agent), out, settings.episodes)
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


def run_local(jobs: list[tuple[str, int]], settings: JobSettings, parallel: int) -> None:
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


def _settings_args(settings: JobSettings) -> list[str]:
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
    name: str, seed: int, settings: JobSettings, config: dict[str, Any] | None, partial: bytes,
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
            run_job(name, seed, here, None if config is None else config_of_data(name, config))
        except Exception as error:  # the folder comes back all the same: a rerun goes on
            return pack(folder), node, f"{type(error).__name__}: {error}"
        return pack(folder), node, None


def run_on_cluster(jobs: list[tuple[str, int]], settings: JobSettings, address: str) -> None:
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
