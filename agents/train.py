"""Train an agent with stable-baselines3 from a YAML config.

    python -m agents.train --config configs/agents/ppo.yaml [key=value ...] [--report]
    python -m agents.train --resume runs/Pinball-v0_ppo_seed0_20261127-140000

A run folder (``runs/`` by default, named from env, algorithm, seed and start time) holds the
exact config (``config.yaml``), ``meta.json`` (package versions, command), TensorBoard logs
(``events.out.tfevents.*``), ``progress.csv``, checkpoints written atomically every
``checkpoint_every`` env steps (``checkpoints/step_N.zip``), and the final ``model.zip`` (with
``model_vecnormalize.pkl`` when the config normalises). ``--resume RUN`` continues a run from
its last checkpoint with the same config. Training stops at ``total_timesteps`` or after
``max_minutes`` of wall time. ``--report`` then evaluates the model against the random and
heuristic baselines and writes the report into the run folder (see ``agents.evaluate``).

Models are pickles inside zips: load only models you trust.
"""

import argparse
import collections
import csv
import shutil
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

from agents.common import (
    CHECKPOINTS,
    CONFIG_FILE,
    MODEL_FILE,
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
    load_config,
    sb3_hyperparams,
)
from agents.imitation import imitate


def make_callback(
    config: TrainConfig, run: Path, frames: int = 0, started: float | None = None
) -> Any:
    """Checkpoints every ``checkpoint_every`` env steps, the mean game score of the last 100
    training games logged as ``rollout/ep_score_mean`` (the score, not the shaped return), the
    frames played by all envs as ``time/frames`` (counted on from ``frames``), and the stop at
    ``max_minutes`` after ``started`` (``time.monotonic()``; default: when learning starts)."""
    from stable_baselines3.common.callbacks import BaseCallback

    class TrainingCallback(BaseCallback):
        def __init__(self) -> None:
            super().__init__()
            self.scores: collections.deque = collections.deque(maxlen=100)
            self.truncated: collections.deque = collections.deque(maxlen=100)
            self.next_checkpoint = 0
            self.frames = frames
            self.game_frames = np.zeros(config.env.num_envs, dtype=np.int64)  # of each game

        def _on_training_start(self) -> None:
            every = config.checkpoint_every
            self.next_checkpoint = (self.num_timesteps // every + 1) * every if every else 0
            self.deadline = (started or time.monotonic()) + 60.0 * config.max_minutes

        def _on_step(self) -> bool:
            infos = self.locals["infos"]
            for env, (done, info) in enumerate(zip(self.locals["dones"], infos, strict=True)):
                # A step's frames vary with skip_above and the end of a game: count them.
                self.frames += info["frames"] - self.game_frames[env]
                self.game_frames[env] = 0 if done else info["frames"]
                if done:
                    self.scores.append(info["score"])
                    self.truncated.append(info.get("TimeLimit.truncated", False))
            if self.next_checkpoint and self.num_timesteps >= self.next_checkpoint:
                save_model(self.model, run / CHECKPOINTS, f"step_{self.num_timesteps}")
                self.next_checkpoint += config.checkpoint_every
            return not config.max_minutes or time.monotonic() < self.deadline

        def _on_rollout_end(self) -> None:
            self.logger.record("time/frames", self.frames)
            if self.scores:
                self.logger.record("rollout/ep_score_mean", float(np.mean(self.scores)))
                self.logger.record("rollout/ep_truncated", float(np.mean(self.truncated)))

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
    """Train (or go on training) in ``run``; returns the final model's path."""
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
        fit = imitate(model, venv, config.imitation_steps, config.imitation_epochs, config.seed)
        print(
            f"warm start: the heuristic played {fit['steps']} steps ({fit['frames']} frames); "
            f"the policy now takes its action {fit['accuracy']:.1%} of the time "
            f"({fit['seconds']:.0f} s)"
        )
        for key in ("steps", "frames", "accuracy", "value_loss", "seconds"):
            model.logger.record(f"imitation/{key}", fit[key])
        frames = fit["frames"]
    left = config.total_timesteps - model.num_timesteps
    if left > 0:
        model.learn(
            left, callback=make_callback(config, run, frames, started),
            reset_num_timesteps=not resume, progress_bar=progress_bar,
        )  # fmt: skip
    # The last checkpoint is the final model, so a resume (after max_minutes) goes on from it.
    save_model(model, run / CHECKPOINTS, f"step_{model.num_timesteps}")
    save_model(model, run, Path(MODEL_FILE).stem)
    venv.close()
    return run / MODEL_FILE


def main(argv: list[str] | None = None) -> Path:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--config", type=Path, help="a YAML config (configs/agents/*.yaml)")
    parser.add_argument("overrides", nargs="*", help="key=value settings over the config")
    parser.add_argument("--resume", type=Path, metavar="RUN", help="a run folder to go on with")
    parser.add_argument("--runs", type=Path, default=Path("runs"), help="where run folders go")
    parser.add_argument("--report", action="store_true", help="evaluate and report at the end")
    parser.add_argument("--episodes", type=int, default=100, help="games for --report")
    parser.add_argument("--no-progress", action="store_true", help="no progress bar")
    args = parser.parse_args(argv)
    try:
        if args.resume is not None:
            if args.config is not None or args.overrides:
                raise ConfigError("--resume goes on with the run's own config: give nothing else")
            if not (args.resume / CONFIG_FILE).is_file():
                raise ConfigError(f"{args.resume}: not a run folder (no {CONFIG_FILE})")
            run = args.resume
            config = load_config(run / CONFIG_FILE)
        elif args.config is None:
            raise ConfigError("give --config FILE (or --resume RUN)")
        else:
            config = load_config(args.config, args.overrides)
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
    print(f"model: {model}")
    if args.report:
        from agents.evaluate import report

        report(run, episodes=args.episodes)
    return model


if __name__ == "__main__":
    main()
