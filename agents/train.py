"""Train an agent with stable-baselines3 from a YAML config.

    python -m agents.train --config configs/agents/ppo.yaml [key=value ...] [--report]
    python -m agents.train --resume runs/Pinball-v0_ppo_seed0_20261127-140000

A run folder (``runs/`` by default, named from env, algorithm, seed and start time) holds the
exact config (``config.yaml``), ``meta.json`` (package versions, command), TensorBoard logs
(``events.out.tfevents.*``), ``progress.csv``, checkpoints written atomically every
``checkpoint_every`` env steps (``checkpoints/step_N.zip``), and the final ``model.zip`` (with
``model_vecnormalize.pkl`` when the config normalises). ``--resume RUN`` continues a run from
its last checkpoint with the same config; ``--resume RUN key=value ...`` extends it first
(``total_timesteps``, ``max_minutes``, ``checkpoint_every`` and the validation keys: the
others would change what was learned and are refused). Training stops at ``total_timesteps``
or after ``max_minutes`` of wall time (the progress bar's remaining time counts to whichever
comes first). SIGINT (Ctrl-C) or SIGTERM, warm start included, saves a checkpoint with the
normalisation statistics and prints it and the resume command. With ``validate_every``, the
model plays the validation games (``validate_seed`` on) every that many steps and at the end;
the scores go to ``validation.csv``, the best model so far to ``best_model.zip``, and the best
of all becomes ``model.zip`` (the last one stays in ``checkpoints/``). ``--report`` then
evaluates the model against the random and heuristic baselines and writes the report into the
run folder (see ``agents.evaluate``).

Models are pickles inside zips: load only models you trust.
"""

import argparse
import collections
import copy
import csv
import io
import shutil
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

from agents.common import (
    CHECKPOINTS,
    MODEL_FILE,
    STATS_FILE,
    FrameCounter,
    ProgressBar,
    StopRequest,
    TrainingInterrupted,
    atomic_write,
    extend_run,
    latest_checkpoint,
    make_env,
    save_model,
    start_run,
    stats_for,
)
from agents.config import (
    ConfigError,
    TrainConfig,
    algorithm_class,
    check_evaluation_seeds,
    load_config,
    sb3_hyperparams,
)
from agents.imitation import imitate

VALIDATION_FILE = "validation.csv"
BEST_MODEL = "best_model"


class Validation:
    """The validation games of a run: ``validate_episodes`` whole games from ``validate_seed``
    on, the same games each time, played deterministically by the model being trained through
    a copy of its env chain (``VecNormalize``'s statistics frozen at their current values).
    Each result is a row of ``RUN/validation.csv``; the best model so far is kept as
    ``RUN/best_model.zip`` (a resumed run goes on from the rows already written)."""

    FIELDS = ("steps", "frames", "score_mean", "score_low", "score_high", "length_mean",
              "truncated_share")  # fmt: skip

    def __init__(self, config: TrainConfig, run: Path) -> None:
        self.config, self.run = config, run
        self.venv: Any = None
        self.rows: list[dict[str, Any]] = []
        if (run / VALIDATION_FILE).is_file():
            with open(run / VALIDATION_FILE) as file:
                self.rows = [
                    {key: (int if key in ("steps", "frames") else float)(value)
                     for key, value in row.items()}
                    for row in csv.DictReader(file)
                ]  # fmt: skip

    @property
    def best(self) -> dict[str, Any] | None:
        """The row of the best validation so far (the earliest of equals), or None."""
        return max(self.rows, key=lambda row: row["score_mean"], default=None)

    def __call__(self, model: Any, frames: int) -> dict[str, float]:
        """Validate ``model`` (``frames`` played in training so far); returns its row."""
        from agents.evaluate import model_policy, rollouts, summarize

        games = self.config.validation_seeds
        if self.venv is None:
            self.venv = make_env(self.config, num_envs=len(games), seed=games.start)
        if hasattr(self.venv, "obs_rms"):
            self.venv.obs_rms = copy.deepcopy(model.get_env().obs_rms)
            self.venv.training = False  # (before the reset, which would update them)
            self.venv.norm_reward = False
        self.venv.seed(games.start)  # the same games every time
        summary = summarize(rollouts(self.venv, model_policy(model), list(games)))
        best = self.best
        row = {
            "steps": model.num_timesteps, "frames": frames,
            "score_mean": round(summary["score_mean"], 2),
            "score_low": round(summary["score_ci95"][0], 2),
            "score_high": round(summary["score_ci95"][1], 2),
            "length_mean": round(summary["length_mean"], 2),
            "truncated_share": summary["truncated_share"],
        }  # fmt: skip
        if best is None or row["score_mean"] > best["score_mean"]:
            save_model(model, self.run, BEST_MODEL, self.config)
        self.rows.append(row)
        table = io.StringIO()
        writer = csv.DictWriter(table, fieldnames=self.FIELDS, lineterminator="\n")
        writer.writeheader()
        writer.writerows(self.rows)
        atomic_write(self.run / VALIDATION_FILE, lambda file: file.write(table.getvalue().encode()))
        print(
            f"validation at {row['steps']} steps: score {row['score_mean']:.0f} (95% CI "
            f"{row['score_low']:.0f}-{row['score_high']:.0f}) over {len(games)} games; best "
            f"{self.best['score_mean']:.0f}"
        )
        return row

    def close(self) -> None:
        if self.venv is not None:
            self.venv.close()


def make_callback(
    config: TrainConfig,
    run: Path,
    frames: int = 0,
    started: float | None = None,
    validation: Validation | None = None,
    stop: StopRequest | None = None,
    progress_bar: bool = False,
) -> Any:
    """Checkpoints every ``checkpoint_every`` env steps, ``validation`` every
    ``validate_every`` (its score logged as ``validation/score_mean``), the mean game score of
    the last 100 training games logged as ``rollout/ep_score_mean`` (the score, not the shaped
    return), the frames played by all envs as ``time/frames`` (counted on from ``frames``), the
    stop at ``max_minutes`` after ``started`` (``time.monotonic()``; default: when learning
    starts) or when ``stop`` is asked, and a progress bar (see :class:`ProgressBar`)."""
    from stable_baselines3.common.callbacks import BaseCallback

    class TrainingCallback(BaseCallback):
        def __init__(self) -> None:
            super().__init__()
            self.scores: collections.deque = collections.deque(maxlen=100)
            self.truncated: collections.deque = collections.deque(maxlen=100)
            self.next_checkpoint = 0
            self.next_validation = 0
            self.counter = FrameCounter(config.env.num_envs, frames)

        def _on_training_start(self) -> None:
            self.next_checkpoint = self._next(config.checkpoint_every)
            self.next_validation = self._next(config.validate_every if validation else 0)
            self.deadline = (started or time.monotonic()) + 60.0 * config.max_minutes
            self.bar = ProgressBar(config, self.num_timesteps, self.deadline, progress_bar)

        def _on_training_end(self) -> None:
            self.bar.close()

        def _on_step(self) -> bool:
            dones, infos = self.locals["dones"], self.locals["infos"]
            self.counter.update(dones, infos)
            for env in np.flatnonzero(dones):
                self.scores.append(infos[env]["score"])
                self.truncated.append(infos[env].get("TimeLimit.truncated", False))
            if self.next_checkpoint and self.num_timesteps >= self.next_checkpoint:
                save_model(self.model, run / CHECKPOINTS, f"step_{self.num_timesteps}", config)
                self.next_checkpoint += config.checkpoint_every
            if self.next_validation and self.num_timesteps >= self.next_validation:
                row = validation(self.model, self.counter.frames)
                self.logger.record("validation/score_mean", row["score_mean"])
                self.next_validation += config.validate_every
            self.bar.update(self.num_timesteps)
            if stop:
                return False
            return not config.max_minutes or time.monotonic() < self.deadline

        def _next(self, every: int) -> int:
            """The first multiple of ``every`` past the steps done (0: never)."""
            return (self.num_timesteps // every + 1) * every if every else 0

        def _on_rollout_end(self) -> None:
            self.logger.record("time/frames", self.counter.frames)
            if self.scores:
                self.logger.record("rollout/ep_score_mean", float(np.mean(self.scores)))
                self.logger.record("rollout/ep_truncated", float(np.mean(self.truncated)))
                self.bar.score(float(np.mean(self.scores)))

    return TrainingCallback()


def keep_progress(run: Path) -> int:
    """Move a run's ``progress.csv`` aside as ``progress_K.csv`` before a resume writes a new
    one (stable-baselines3 overwrites it); the learning curve reads them all. Returns the last
    ``time/frames`` logged, for the count to go on from."""
    progress = run / "progress.csv"
    if progress.exists():
        progress.rename(run / f"progress_{len(list(run.glob('progress_*.csv')))}.csv")
    frames = [row.get("time/frames") for row in progress_rows(run)]
    return max((int(float(f)) for f in frames if f), default=0)


def progress_rows(run: Path) -> list[dict[str, str]]:
    """The rows of every progress file of a run (progress_K.csv: before each resume), in the
    order of the env steps."""
    rows = []
    for path in sorted(run.glob("progress*.csv")):
        with open(path) as file:
            rows += list(csv.DictReader(file))
    return sorted(rows, key=lambda row: float(row["time/total_timesteps"]))


def set_threads(config: TrainConfig) -> None:
    import torch

    torch.set_num_threads(config.torch_threads)


def start(config: TrainConfig, runs: Path, command: list[str]) -> Path:
    """Create a run folder with the config and meta data; returns it."""
    return start_run(config, runs, command, ["stable_baselines3"])


def train(config: TrainConfig, run: Path, resume: bool = False, progress_bar: bool = True) -> Path:
    """Train (or go on training) in ``run``; returns the final model's path. SIGINT or SIGTERM
    saves a checkpoint and raises :class:`TrainingInterrupted`."""
    with StopRequest() as stop:
        return _train(config, run, resume, progress_bar, stop)


def _train(
    config: TrainConfig, run: Path, resume: bool, progress_bar: bool, stop: StopRequest
) -> Path:
    from stable_baselines3.common.logger import configure

    started = time.monotonic()
    set_threads(config)
    algorithm = algorithm_class(config.algo)
    checkpoint = latest_checkpoint(run) if resume else None
    if resume and checkpoint is None:
        raise ConfigError(f"{run}: no checkpoint to resume from")
    stats = stats_for(checkpoint[1]) if checkpoint else None
    if checkpoint and config.env.normalize and stats is None:
        raise ConfigError(f"{checkpoint[1]}: its VecNormalize statistics are missing")
    venv = make_env(config, stats=stats)
    if checkpoint is not None and hasattr(venv, "obs_rms"):
        venv.training = True  # the loaded statistics go on learning
        venv.norm_reward = True
    if checkpoint is not None:
        steps, path = checkpoint
        print(f"resuming {run} from {path.name} ({steps} steps)")
        model = algorithm.load(path, env=venv, device=config.device)
        if hasattr(model, "replay_buffer"):  # checkpoints hold no buffer: refill it first
            model.learning_starts += model.num_timesteps
        frames = keep_progress(run)
    else:
        frames = 0
        try:
            model = algorithm(
                config.policy, venv, seed=config.seed, device=config.device, verbose=0,
                **sb3_hyperparams(config),
            )  # fmt: skip
        except (TypeError, ValueError, AssertionError) as error:  # SB3 checks with asserts too
            venv.close()
            raise ConfigError(f"hyperparams: {config.algo.upper()} rejects them: {error}") from None
    model.set_logger(configure(str(run), ["csv", "tensorboard"]))
    if config.imitation_steps and checkpoint is None:
        fit = imitate(
            model, venv, config.imitation_steps, config.imitation_epochs, config.seed, stop
        )  # fmt: skip
        print(
            f"warm start: the heuristic played {fit['steps']} steps ({fit['frames']} frames); "
            f"the policy now takes its action {fit['accuracy']:.1%} of the time "
            f"({fit['seconds']:.0f} s){' (cut short)' if stop else ''}"
        )
        for key in ("steps", "frames", "accuracy", "value_loss", "seconds"):
            model.logger.record(f"imitation/{key}", fit[key])
        frames = fit["frames"]
    validation = Validation(config, run) if config.validate_every else None
    callback = make_callback(config, run, frames, started, validation, stop, progress_bar)
    left = config.total_timesteps - model.num_timesteps
    if left > 0 and not stop:
        model.learn(left, callback=callback, reset_num_timesteps=not resume)
    # The last checkpoint is the final model, so a resume (after max_minutes) goes on from it.
    last = f"step_{model.num_timesteps}"
    save_model(model, run / CHECKPOINTS, last, config)
    if stop:  # asked to stop: the checkpoint is saved, the rest waits for the resume
        if validation is not None:
            validation.close()
        venv.close()
        raise TrainingInterrupted(
            run, run / CHECKPOINTS / f"{last}.zip", model.num_timesteps, stop, "agents.train"
        )
    save_model(model, run, Path(MODEL_FILE).stem, config)
    if validation is not None:
        if not validation.rows or validation.rows[-1]["steps"] != model.num_timesteps:
            validation(model, callback.counter.frames)
        validation.close()
        keep_best(run, validation.best)
    venv.close()
    return run / MODEL_FILE


def keep_best(run: Path, best: dict[str, Any]) -> None:
    """Make the best validated model (``best_model.zip``) the run's ``model.zip``."""
    for name in (f"{BEST_MODEL}_{STATS_FILE}", f"{BEST_MODEL}.zip"):  # as save_model does
        if (run / name).exists():
            target = run / name.replace(BEST_MODEL, Path(MODEL_FILE).stem)
            atomic_write(target, lambda file, source=run / name: file.write(source.read_bytes()))
    print(
        f"model: the best on the validation games, at {int(best['steps'])} steps "
        f"(score {best['score_mean']:.0f}); the last is in {CHECKPOINTS}/"
    )


def main(argv: list[str] | None = None) -> Path:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--config", type=Path, help="a YAML config (configs/agents/*.yaml)")
    parser.add_argument(
        "overrides", nargs="*", help="key=value settings over the config (--resume: extensions)"
    )
    parser.add_argument("--resume", type=Path, metavar="RUN", help="a run folder to go on with")
    parser.add_argument("--runs", type=Path, default=Path("runs"), help="where run folders go")
    parser.add_argument("--report", action="store_true", help="evaluate and report at the end")
    parser.add_argument("--episodes", type=int, default=100, help="games for --report")
    parser.add_argument("--no-progress", action="store_true", help="no progress bar")
    args = parser.parse_args(argv)
    try:
        if args.resume is not None:
            if args.config is not None:
                raise ConfigError("--resume goes on with the run's own config: no --config")
            run = args.resume
            config = extend_run(
                run, args.overrides, TrainConfig, sys.argv if argv is None else argv
            )
        elif args.config is None:
            raise ConfigError("give --config FILE (or --resume RUN)")
        else:
            config = load_config(args.config, args.overrides)
        if args.report:  # before training: the report's games must be new to the model
            check_evaluation_seeds(config, config.eval_seed, args.episodes)
        if args.resume is None:
            run = start(config, args.runs, sys.argv if argv is None else argv)
        print(f"run folder: {run}")
        try:
            model = train(config, run, args.resume is not None, not args.no_progress)
        except ConfigError:
            if args.resume is None:  # nothing was trained: leave no run folder behind
                shutil.rmtree(run)
            raise
    except ConfigError as error:
        parser.exit(2, f"error: {error}\n")
    except TrainingInterrupted as stopped:
        parser.exit(stopped.exit_code, f"{stopped}\n")
    print(f"model: {model}")
    if args.report:
        from agents.evaluate import report

        report(run, episodes=args.episodes)
    return model


if __name__ == "__main__":
    main()
