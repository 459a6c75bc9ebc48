"""Run folders and what they hold: names, ``meta.json``, resumes, atomic writes, checkpoints
(stable-baselines3's zips and RLlib's folders) and the progress logged; and the stop on a signal
and the progress bar of a training.

A run folder::

    config.yaml           the exact config (CONFIG_FILE)
    meta.json             versions, the commit, the command, the start time, the resumes
    progress.csv          the logged rows (progress_K.csv: before the K-th resume of an SB3 run)
    validation.csv        the validation games' results (VALIDATION_FILE), best_model.zip
    checkpoints/step_N.zip, step_N_vecnormalize.pkl   (SB3), or step_N/ (RLlib folders)
    model.zip, model_vecnormalize.pkl                 (SB3), or model/ (RLlib)
"""

import csv
import importlib
import io
import json
import os
import platform
import re
import signal
import sys
import tempfile
import threading
import time
import zipfile
from collections.abc import Callable
from pathlib import Path
from typing import Any

from agents.config import AnyConfig, ConfigError, RllibConfig, TrainConfig, load_config, save_config

CONFIG_FILE = "config.yaml"
META_FILE = "meta.json"
MODEL_FILE = "model.zip"
STATS_FILE = "vecnormalize.pkl"
CHECKPOINTS = "checkpoints"
PROGRESS_FILE = "progress.csv"
VALIDATION_FILE = "validation.csv"
BEST_MODEL = "best_model"  # the best validated model so far: best_model.zip
# A checkpoint: step_N.zip (stable-baselines3) or the folder step_N (RLlib).
CHECKPOINT_NAME = re.compile(r"step_(\d+)(\.zip)?")
# The entry of a model zip that carries its config and observation statistics (agents.policy).
AGENT_ENTRY = "pinball/agent.json"
# RLlib's layout: the final checkpoint of a run folder, the file that marks a checkpoint folder,
# and where in one the RL module and the observation filter are.
RLLIB_MODEL_DIR = "model"
RLLIB_CHECKPOINT_FILE = "rllib_checkpoint.json"
MODULE_PATH = ("learner_group", "learner", "rl_module", "default_policy")
FILTER_PATH = ("env_runner", "env_to_module_connector", "MeanStdFilter")


class StopRequest:
    """SIGINT (Ctrl-C) and SIGTERM, while a training runs inside ``with StopRequest() as
    stop:``, ask it to stop: ``stop`` turns true (``stop.signal`` names the signal) and the
    training saves a checkpoint at its next step and says how to resume. A second SIGINT
    stops at once (KeyboardInterrupt). Outside the main thread it installs nothing."""

    SIGNALS = (signal.SIGINT, signal.SIGTERM)

    def __init__(self) -> None:
        self.signal: signal.Signals | None = None
        self._previous: dict[int, Any] = {}

    def __enter__(self) -> "StopRequest":
        if threading.current_thread() is threading.main_thread():
            self._previous = {sig: signal.signal(sig, self._handle) for sig in self.SIGNALS}
        return self

    def __exit__(self, *exc: object) -> None:
        for sig, handler in self._previous.items():
            signal.signal(sig, handler)
        self._previous = {}

    def __bool__(self) -> bool:
        return self.signal is not None

    def _handle(self, signum: int, frame: Any) -> None:
        if self.signal is not None and signum == signal.SIGINT:
            raise KeyboardInterrupt
        self.signal = signal.Signals(signum)
        print(
            f"\n{self.signal.name}: saving a checkpoint, then stopping "
            "(Ctrl-C again stops at once, saving nothing)", file=sys.stderr, flush=True,
        )  # fmt: skip


class ProgressBar:
    """A tqdm bar of the env steps to the step the training will stop at: ``total_timesteps``,
    or sooner where the frame budget (``total_frames``) or ``max_minutes`` comes first, that
    step estimated from the session's rate so far (frames a step, steps a second; shown as
    ``stops at total_frames`` or ``stops at max_minutes``), so that the bar ends at 100%."""

    def __init__(
        self, config: AnyConfig, steps: int, deadline: float, show: bool, frames: int = 0
    ) -> None:
        self.total, self.first, self.deadline = config.total_timesteps, steps, deadline
        self.first_frames = frames
        self.frame_budget = int(getattr(config, "total_frames", 0) or 0)
        self.limited = bool(config.max_minutes)
        self.began = time.monotonic()
        self.shown = 0.0
        self.bar = None
        if show:
            from tqdm import tqdm

            self.bar = tqdm(total=self.total, initial=steps, unit="step", dynamic_ncols=True)

    def update(self, steps: int, force: bool = False, frames: int | None = None) -> None:
        """Show ``steps`` done (``frames`` played by then; at most twice a second, unless
        ``force``)."""
        now = time.monotonic()
        if self.bar is None or (now - self.shown < 0.5 and not force):
            return
        self.shown = now
        end, why = self.total, ""
        if steps > self.first and frames is not None and self.frame_budget:
            per_step = (frames - self.first_frames) / (steps - self.first)
            if per_step > 0:
                by_frames = steps + max(0.0, self.frame_budget - frames) / per_step
                if by_frames < end:
                    end, why = int(by_frames), "stops at total_frames"
        if self.limited and steps > self.first and now > self.began:
            rate = (steps - self.first) / (now - self.began)
            reachable = steps + rate * max(0.0, self.deadline - now)
            if reachable < end:
                end, why = int(reachable), "stops at max_minutes"
        end = max(steps, end)
        if end != self.bar.total:
            self.bar.total = end
            self.bar.set_description(why)
        self.bar.update(steps - self.bar.n)

    def score(self, score: float) -> None:
        if self.bar is not None:
            self.bar.set_postfix(score=f"{score:.0f}", refresh=False)

    def close(self, steps: int | None = None, frames: int | None = None) -> None:
        """Show the last ``steps`` (and ``frames``) however soon after the last update, so
        that a training the budget stopped ends at 100%; then close the bar."""
        if steps is not None:
            self.update(steps, force=True, frames=frames)
        if self.bar is not None:
            self.bar.close()


def say(text: str) -> None:
    """Print a line of a training's news (a validation, the model kept) without breaking its
    progress bar: through tqdm, which prints it above the bar."""
    try:
        from tqdm import tqdm
    except ImportError:  # (no bar without tqdm either)
        print(text)
        return
    tqdm.write(text)


class TrainingInterrupted(Exception):
    """A training stopped by a signal, after saving ``checkpoint`` (None: stopped in its warm
    start, which a checkpoint would cut short for good, so nothing is saved and the resume
    starts the run again); the message says how to resume it."""

    def __init__(
        self, run: Path, checkpoint: Path | None, steps: int, stop: StopRequest, module: str
    ):
        self.run, self.checkpoint, self.steps = run, checkpoint, steps
        self.exit_code = 128 + int(stop.signal or signal.SIGINT)
        name = (stop.signal or signal.SIGINT).name
        if checkpoint is None:
            super().__init__(
                f"{name}: stopped in the warm start, before learning: nothing saved\n"
                f"resume with: python -m {module} --resume {run} (it starts the run again)"
            )
            return
        super().__init__(
            f"{name}: stopped at {steps:,} steps; checkpoint {checkpoint}\n"
            f"resume with: python -m {module} --resume {run}"
        )


class CommandInterrupted(SystemExit, KeyboardInterrupt):
    """The exit of a training command that a signal stopped, once its checkpoint is saved: a
    ``SystemExit`` for the shell (status 128 + the signal, no traceback) and a
    ``KeyboardInterrupt`` for whatever runs the command in its own process, so that Ctrl-C
    stops a pytest session (or a notebook cell) as it always does, not only the training."""


def run_name(config: AnyConfig, when: str) -> str:
    """A run folder's name: env, algorithm (``rllib-ppo`` for RLlib), seed and start time."""
    env = config.env.id.replace("/", "-")
    return f"{env}_{config.label}_seed{config.seed}_{when}"


def start_run(config: AnyConfig, runs: Path, command: list[str], libraries: list[str]) -> Path:
    """Create a run folder (named by ``run_name``) with the exact config and ``meta.json``: the
    versions of pinball_env, gymnasium, torch and ``libraries``, the command, the start time."""
    run = runs / run_name(config, time.strftime("%Y%m%d-%H%M%S"))
    if run.exists():
        raise ConfigError(f"run folder {run} exists already")
    (run / CHECKPOINTS).mkdir(parents=True)
    save_config(config, run / CONFIG_FILE)
    versions = {
        name: importlib.import_module(name).__version__
        for name in ("pinball_env", "gymnasium", "torch", *libraries)
    }
    meta = {
        **versions,
        "commit": source_commit(),
        "python": platform.python_version(),
        "command": command,
        "started": time.strftime("%Y-%m-%dT%H:%M:%S"),
    }
    write_meta(run, meta)
    return run


def source_commit() -> str | None:
    """The git commit of the checkout this code runs from (a ``+`` marks uncommitted changes),
    or None outside a checkout; ``PINBALL_SOURCE_COMMIT`` where it is set (a Ray node running
    code shipped from a checkout, see ``agents.benchmark``)."""
    import subprocess

    if os.environ.get("PINBALL_SOURCE_COMMIT"):
        return os.environ["PINBALL_SOURCE_COMMIT"]
    root = Path(__file__).resolve().parent.parent

    def git(*args: str) -> str:
        return subprocess.run(
            ["git", *args], cwd=root, capture_output=True, text=True, check=True
        ).stdout.strip()

    try:
        commit, dirty = git("rev-parse", "HEAD"), git("status", "--porcelain", "-uno")
    except (OSError, subprocess.CalledProcessError):
        return None
    return commit + ("+" if dirty else "")


# What ``--resume RUN key=value`` may change: how long and how often, not what is learned.
RESUME_KEYS = {
    TrainConfig: ("total_timesteps", "max_minutes", "total_frames", "checkpoint_every",
                  "validate_every", "validate_episodes", "validate_seed"),
    RllibConfig: ("total_timesteps", "max_minutes", "checkpoint_every"),
}  # fmt: skip


def extend_run(run: Path, overrides: list[str], kind: type, command: list[str]) -> AnyConfig:
    """The config of run folder ``run`` for a resume, ``overrides`` (``key=value``, only
    ``RESUME_KEYS``) applied and saved into its ``config.yaml``; ``meta.json`` records the
    resume."""
    if not (run / CONFIG_FILE).is_file():
        raise ConfigError(f"{run}: not a run folder (no {CONFIG_FILE})")
    allowed = RESUME_KEYS[kind]
    for item in overrides:
        key = item.partition("=")[0]
        if key not in allowed:
            raise ConfigError(
                f"--resume: {key!r} would change what the run learned; a resume may change "
                f"only {', '.join(allowed)}"
            )
    config = load_config(run / CONFIG_FILE, overrides, kind=kind)
    if overrides:
        save_config(config, run / CONFIG_FILE)
    meta = read_meta(run)
    meta.setdefault("resumes", []).append(
        {"command": command, "overrides": list(overrides),
         "started": time.strftime("%Y-%m-%dT%H:%M:%S")}
    )  # fmt: skip
    write_meta(run, meta)
    return config


def read_meta(run: Path) -> dict[str, Any]:
    """The run's ``meta.json`` (empty for a folder without one)."""
    path = run / META_FILE
    return json.loads(path.read_text()) if path.is_file() else {}


def write_meta(run: Path, meta: dict[str, Any]) -> None:
    """Replace the run's ``meta.json`` with ``meta``, atomically."""
    atomic_write(run / META_FILE, lambda file: file.write(json.dumps(meta, indent=1).encode()))


def atomic_write(path: Path, write: Callable[[Any], None]) -> None:
    """Write ``path`` through ``write(file)`` into a temporary file beside it, then rename it
    into place: a run killed mid-write leaves the old file (or none), never half a file."""
    path.parent.mkdir(parents=True, exist_ok=True)
    handle, temporary = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    try:
        with os.fdopen(handle, "wb") as file:
            write(file)
            file.flush()
            os.fsync(file.fileno())
        os.chmod(temporary, 0o644)  # mkstemp's 0600 is for secrets, not models
        os.replace(temporary, path)
    except BaseException:
        Path(temporary).unlink(missing_ok=True)
        raise


def save_model(model: Any, folder: Path, name: str, config: AnyConfig) -> None:
    """Save ``model`` as ``folder/name.zip`` and, when it trains on a ``VecNormalize``, its
    statistics as ``folder/name_vecnormalize.pkl`` (first, so a model never lacks them; a
    resume reads them). The zip also carries ``config`` and the observation statistics
    (``AGENT_ENTRY``), so that it loads copied alone (``agents.policy``)."""
    import pickle

    venv = model.get_env()
    normalization = None
    if hasattr(venv, "obs_rms"):  # a VecNormalize: it pickles its statistics, not its envs
        atomic_write(folder / f"{name}_{STATS_FILE}", lambda file: pickle.dump(venv, file))
        if venv.norm_obs:
            normalization = {
                "mean": venv.obs_rms.mean.tolist(), "var": venv.obs_rms.var.tolist(),
                "epsilon": venv.epsilon, "clip_obs": venv.clip_obs,
            }  # fmt: skip
    buffer = io.BytesIO()
    model.save(buffer)
    entry = {"format": 1, "config": config.to_dict(), "obs_normalization": normalization}
    with zipfile.ZipFile(buffer, "a") as archive:  # stable-baselines3 reads only its entries
        archive.writestr(AGENT_ENTRY, json.dumps(entry, indent=1))
    atomic_write(folder / f"{name}.zip", lambda file: file.write(buffer.getvalue()))


def stats_for(model_path: Path) -> Path | None:
    """The VecNormalize statistics saved beside a model, if any."""
    stats = model_path.with_name(f"{model_path.stem}_{STATS_FILE}")
    return stats if stats.exists() else None


def checkpoints_of(run: Path) -> list[tuple[int, Path]]:
    """``(steps, path)`` of each complete checkpoint of a run, oldest first: the
    ``step_N.zip`` of stable-baselines3, the ``step_N`` folders of RLlib (with their
    ``rllib_checkpoint.json``). Half-written ones (hidden temporary names) are not listed."""
    found = []
    for path in (run / CHECKPOINTS).glob("step_*"):
        match = CHECKPOINT_NAME.fullmatch(path.name)
        if match and (match.group(2) or (path / RLLIB_CHECKPOINT_FILE).is_file()):
            found.append((int(match.group(1)), path))
    return sorted(found)


def latest_checkpoint(run: Path) -> tuple[int, Path] | None:
    """``(steps, path)`` of the newest complete checkpoint of a run, or None."""
    found = checkpoints_of(run)
    return found[-1] if found else None


def stopped_before_learning(run: Path) -> bool:
    """Whether a stable-baselines3 run stopped before it learned (in its warm start): no
    checkpoint and no model. Resumed, it is trained again from the start."""
    return not checkpoints_of(run) and not (run / MODEL_FILE).exists()


def is_rllib_checkpoint(path: Path) -> bool:
    """Whether ``path`` is an RLlib run folder (with its final model) or checkpoint folder."""
    return (path / RLLIB_CHECKPOINT_FILE).is_file() or (
        path / RLLIB_MODEL_DIR / RLLIB_CHECKPOINT_FILE
    ).is_file()


def rllib_checkpoint(path: Path) -> tuple[Path, RllibConfig]:
    """The checkpoint folder and the run's config of an RLlib run folder or checkpoint."""
    checkpoint = path if (path / RLLIB_CHECKPOINT_FILE).is_file() else path / RLLIB_MODEL_DIR
    folders = (checkpoint, checkpoint.parent, checkpoint.parent.parent)  # its own config first
    run = next((p for p in folders if (p / CONFIG_FILE).is_file()), None)
    if run is None:
        raise ConfigError(
            f"{path}: no {CONFIG_FILE} in the checkpoint or its run folder: cannot rebuild its env"
        )
    return checkpoint, load_config(run / CONFIG_FILE, kind=RllibConfig)


def progress_rows(run: Path) -> list[dict[str, str]]:
    """The rows of every progress file of a run (progress_K.csv: before each resume), in the
    order of the env steps."""
    rows = []
    for path in sorted(run.glob("progress*.csv")):
        with open(path) as file:
            rows += list(csv.DictReader(file))
    return sorted(rows, key=lambda row: float(row["time/total_timesteps"]))


def keep_progress(run: Path) -> int:
    """Move a run's ``progress.csv`` aside as ``progress_K.csv`` before a resume writes a new
    one (stable-baselines3 overwrites it); the learning curve reads them all. Returns the last
    ``time/frames`` logged, for the count to go on from."""
    progress = run / PROGRESS_FILE
    if progress.exists():
        progress.rename(run / f"progress_{len(list(run.glob('progress_*.csv')))}.csv")
    frames = [row.get("time/frames") for row in progress_rows(run)]
    return max((int(float(f)) for f in frames if f), default=0)


def validation_rows(run: Path) -> list[dict[str, Any]]:
    """The rows of a run's ``validation.csv`` (none without one): ``steps`` and ``frames`` as
    ints, the scores as floats (``score_iqm`` only in the rows of runs that recorded it)."""
    if not (run / VALIDATION_FILE).is_file():
        return []
    with open(run / VALIDATION_FILE) as file:
        return [
            {key: (int if key in ("steps", "frames") else float)(value)
             for key, value in row.items() if value not in ("", None)}  # (older: no IQM)
            for row in csv.DictReader(file)
        ]  # fmt: skip


def best_validation(rows: list[dict[str, Any]]) -> dict[str, Any] | None:
    """The row of the best validation (the earliest of equals), or None."""
    return max(rows, key=lambda row: row["score_mean"], default=None)


def next_multiple(steps: int, every: int) -> int:
    """The first multiple of ``every`` past ``steps`` (0 when ``every`` is 0: never)."""
    return (steps // every + 1) * every if every else 0
