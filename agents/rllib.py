"""Train PPO on Ray RLlib from a YAML config: on this machine, or across a Ray cluster.

    python -m agents.rllib --config configs/agents/rllib_ppo.yaml [key=value ...] [--address ADDR]
    python -m agents.rllib --resume runs/Pinball-v0_rllib-ppo_seed0_20261127-140000
    python -m agents.rllib --config configs/agents/rllib_ppo.yaml --scaling 1 2 4

Without ``--address`` a local Ray instance is started; with one (``auto``, or ``HOST:6379``)
the run joins that cluster, and the ``agents`` and ``pinball_env`` packages travel to its nodes
in the job's ``runtime_env`` (the nodes need the dependencies: ``pip install
'pinball-env[distributed]'``). The env runners step the native vector env: the env is
registered with ``ray.tune.registry.register_env`` (which reaches remote actors, where
Gymnasium's registry does not) and made in RLlib's ``vector_entry_point`` mode.

The run folder has the layout of ``agents.train``: ``config.yaml``, ``meta.json``, TensorBoard
logs, ``progress.csv`` (the same columns: ``time/total_timesteps``, ``time/frames``,
``rollout/ep_score_mean``...), checkpoints written atomically every ``checkpoint_every`` env
steps (``checkpoints/step_N/``, RLlib checkpoint folders) and the final ``model/``.
``--resume RUN`` goes on from the last checkpoint. ``python -m agents.evaluate --model RUN``
(or a checkpoint folder) evaluates it like an SB3 model. ``--scaling`` measures sampled env
steps per second against the number of env runners and writes ``scaling.json``.

Checkpoints hold pickles: load only checkpoints you trust.
"""

import argparse
import csv
import dataclasses
import json
import os
import shutil
import time
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np

from agents.cli import run_training, training_parser
from agents.config import ConfigError, RllibConfig, save_config
from agents.runs import (
    CHECKPOINTS,
    CONFIG_FILE,
    PROGRESS_FILE,
    ProgressBar,
    StopRequest,
    TrainingInterrupted,
    latest_checkpoint,
    next_multiple,
    start_run,
)

# The layout of RLlib checkpoints is in agents.runs; these are the names agents.rllib gave it.
from agents.runs import FILTER_PATH as FILTER_PATH
from agents.runs import RLLIB_CHECKPOINT_FILE as RLLIB_CHECKPOINT_FILE
from agents.runs import RLLIB_MODEL_DIR as MODEL_DIR
from agents.runs import checkpoints_of as checkpoints_of
from agents.runs import is_rllib_checkpoint as is_checkpoint  # noqa: F401
from agents.runs import rllib_checkpoint as load_checkpoint  # noqa: F401

ENV_NAME = "pinball"  # the env's name in ray.tune's registry
# The game metrics the env runners log (under env_runners/ in a result).
SCORE, TRUNCATED, FRAMES = "game_score", "game_truncated", "game_frames_lifetime"


def make_rllib_env(env_config: dict[str, Any]) -> gym.Env | gym.vector.VectorEnv:
    """RLlib's env creator: ``env_config`` holds the env id and its options; with ``num_envs``
    (RLlib's ``vector_entry_point`` mode) it makes the native vector env."""
    import pinball_env  # noqa: F401  (registers the ids in this worker)

    options = dict(env_config)
    env_id, first_seed = options.pop("id"), options.pop("seed")
    num_envs = options.pop("num_envs", None)
    if num_envs is None:
        options.pop("num_threads", None)
        return gym.make(env_id, **options)
    env = gym.make_vec(env_id, num_envs, vectorization_mode="vector_entry_point", **options)
    return SeedBlocks(env, first_seed)


class SeedBlocks(gym.vector.VectorWrapper):
    """RLlib resets env runner k's vector env with seed + k, and the vector env seeds its env i
    with that + i: neighbouring runners would share all but one game stream. This gives runner
    k the block seed + k * num_envs + i instead."""

    def __init__(self, env: gym.vector.VectorEnv, first_seed: int) -> None:
        super().__init__(env)
        self.first_seed = first_seed

    def reset(self, *, seed: Any = None, options: Any = None) -> Any:
        if isinstance(seed, int):
            seed = self.first_seed + (seed - self.first_seed) * self.num_envs
        return self.env.reset(seed=seed, options=options)


def record_game(*, episode: Any, metrics_logger: Any, **_: Any) -> None:
    """RLlib's ``on_episode_end``: log the game's score (not the shaped return), whether the
    time limit ended it, and its frames. (RLlib reduces the means over the games that ended in
    each iteration.)"""
    info = episode.get_infos(-1)
    metrics_logger.log_value(SCORE, float(info["score"]), window=100)
    metrics_logger.log_value(TRUNCATED, float(episode.is_truncated), window=100)
    metrics_logger.log_value(FRAMES, int(info["frames"]), reduce="lifetime_sum")


def algorithm_config(config: RllibConfig) -> Any:
    """RLlib's ``PPOConfig`` for a run config."""
    from ray.rllib.algorithms.ppo import PPOConfig
    from ray.rllib.connectors.env_to_module import MeanStdFilter
    from ray.rllib.core.rl_module.default_model_config import DefaultModelConfig

    env_config = {
        "id": config.env.id, "seed": config.seed, "num_threads": config.env_threads,
        **config.env.make_kwargs,
    }  # fmt: skip
    connectors = {}
    if config.env.normalize:
        connectors["env_to_module_connector"] = lambda env, spaces, device: MeanStdFilter()
    return (
        PPOConfig()
        .environment(ENV_NAME, env_config=env_config)
        .env_runners(
            num_env_runners=config.env_runners,
            num_envs_per_env_runner=config.env.num_envs,
            num_cpus_per_env_runner=config.cpus_per_env_runner,
            gym_env_vectorize_mode="vector_entry_point",
            **connectors,
        )
        .training(**config.hyperparams)
        .rl_module(model_config=DefaultModelConfig(**config.model))
        .callbacks(on_episode_end=record_game)
        .debugging(seed=config.seed, log_level="ERROR")
    )


def init_ray(address: str | None = None, num_cpus: int | None = None) -> None:
    """Start a local Ray instance, or join the cluster at ``address`` and ship the code to it."""
    import ray
    from ray.tune.registry import register_env

    import agents
    import pinball_env

    if not ray.is_initialized():
        runtime_env = {}
        if address is not None:  # the cluster's nodes get this very code
            modules = [Path(m.__path__[0]) for m in (agents, pinball_env)]
            runtime_env = {"py_modules": [str(m) for m in modules], "excludes": ["__pycache__"]}
        ray.init(
            address=address, num_cpus=num_cpus if address is None else None,
            runtime_env=runtime_env, include_dashboard=False, log_to_driver=False,
        )  # fmt: skip
    register_env(ENV_NAME, make_rllib_env)


def build(config: RllibConfig, local: bool = False) -> Any:
    """The RLlib algorithm of a config (Ray must be initialised). On a ``local`` Ray instance
    (no autoscaler to add nodes), env runners that need more CPUs than it has are an error,
    not a wait for ever."""
    import ray
    import torch

    needed = config.env_runners * config.cpus_per_env_runner
    cpus = ray.cluster_resources().get("CPU", 0)
    if local and needed > cpus:
        raise ConfigError(
            f"env_runners: {config.env_runners} x cpus_per_env_runner "
            f"{config.cpus_per_env_runner} needs {needed:g} CPUs, Ray has {cpus:g} here "
            "(lower cpus_per_env_runner to share them)"
        )
    torch.set_num_threads(config.torch_threads)
    try:
        return algorithm_config(config).build_algo()
    except (ValueError, TypeError) as error:  # RLlib's own checks of the settings
        raise ConfigError(f"RLlib rejects the config: {error}") from None


def save_checkpoint(algo: Any, path: Path, config: RllibConfig) -> None:
    """Save the algorithm into the folder ``path``, with the run's ``config.yaml`` (so that it
    loads copied alone): written beside it, then renamed into place, so a run killed mid-write
    never leaves half a checkpoint under the name."""
    temporary = path.with_name(f".{path.name}.tmp")
    shutil.rmtree(temporary, ignore_errors=True)
    algo.save_to_path(str(temporary.resolve()))
    save_config(config, temporary / CONFIG_FILE)
    if path.exists():  # the final model, saved again on resume
        old = path.with_name(f".{path.name}.old")
        shutil.rmtree(old, ignore_errors=True)
        path.rename(old)
        temporary.rename(path)
        shutil.rmtree(old)
    else:
        temporary.rename(path)


def start(config: RllibConfig, runs: Path, command: list[str]) -> Path:
    """Create a run folder with the config and meta data; returns it."""
    return start_run(config, runs, command, ["ray"])


def progress_row(result: dict[str, Any], elapsed: float) -> dict[str, Any]:
    """A training iteration's result as a ``progress.csv`` row (agents.train's column names)."""
    runners = result.get("env_runners", {})
    learner = result.get("learners", {}).get("default_policy", {})
    row = {
        "time/total_timesteps": int(result["num_env_steps_sampled_lifetime"]),
        "time/frames": int(runners.get(FRAMES, 0)),
        "time/iterations": int(result["training_iteration"]),
        "time/time_elapsed": round(elapsed, 3),
        "time/fps": round(runners.get("num_env_steps_sampled", 0) / result["time_this_iter_s"]),
        "rollout/ep_score_mean": runners.get(SCORE, ""),
        "rollout/ep_truncated": runners.get(TRUNCATED, ""),
        "rollout/ep_rew_mean": runners.get("episode_return_mean", ""),
        "rollout/ep_len_mean": runners.get("episode_len_mean", ""),
    }
    for key in ("policy_loss", "vf_loss", "entropy", "mean_kl_loss", "vf_explained_var"):
        row[f"train/{key}"] = learner.get(key, "")
    return {key: (float(value) if isinstance(value, np.floating) else value)
            for key, value in row.items()}  # fmt: skip


def forget_progress_after(path: Path, steps: int) -> None:
    """Drop the rows a killed run logged after its last checkpoint: the resume logs them
    again, from the checkpoint on."""
    if not path.is_file():
        return
    with open(path, newline="") as file:
        rows = list(csv.DictReader(file))
    if not rows:
        return
    kept = [row for row in rows if int(row["time/total_timesteps"]) <= steps]
    with open(path, "w", newline="") as file:
        writer = csv.DictWriter(file, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(kept)


class ProgressLog:
    """``progress.csv`` (appended on resume) and TensorBoard scalars of a run."""

    def __init__(self, run: Path) -> None:
        from torch.utils.tensorboard import SummaryWriter

        self.path = run / PROGRESS_FILE
        self.writer = SummaryWriter(str(run))
        self.fields: list[str] | None = None
        if self.path.is_file():
            with open(self.path) as file:
                self.fields = next(csv.reader(file), None)

    def write(self, row: dict[str, Any]) -> None:
        new = self.fields is None
        self.fields = self.fields or list(row)
        with open(self.path, "a", newline="") as file:
            writer = csv.DictWriter(file, fieldnames=self.fields, extrasaction="ignore")
            if new:
                writer.writeheader()
            writer.writerow(row)
        steps = row["time/total_timesteps"]
        for key, value in row.items():
            if isinstance(value, (int, float)) and key != "time/total_timesteps":
                self.writer.add_scalar(key, value, steps)
        self.writer.flush()

    def close(self) -> None:
        self.writer.close()


def train(
    config: RllibConfig, run: Path, resume: bool = False, progress_bar: bool = True,
    local: bool = True,
) -> Path:  # fmt: skip
    """Train (or go on training) in ``run``; returns the final checkpoint's folder. Ray must be
    initialised (``init_ray``); ``local``: a Ray instance of this machine only."""
    checkpoint = latest_checkpoint(run) if resume else None
    if resume and checkpoint is None:
        raise ConfigError(f"{run}: no checkpoint to resume from")
    algo = build(config, local)
    if checkpoint is not None:
        print(f"resuming {run} from {checkpoint[1].name} ({checkpoint[0]} steps)")
        algo.restore_from_path(str(checkpoint[1].resolve()))
    steps = checkpoint[0] if checkpoint else 0
    if checkpoint is not None:
        forget_progress_after(run / PROGRESS_FILE, steps)
    log = ProgressLog(run)
    every = config.checkpoint_every
    next_checkpoint = next_multiple(steps, every)
    began = time.monotonic()
    bar = ProgressBar(config, steps, began + 60.0 * config.max_minutes, progress_bar)
    try:
        with StopRequest() as stop:  # a signal ends the iteration under way, then stops
            while steps < config.total_timesteps and not stop:
                result = algo.train()
                row = progress_row(result, time.monotonic() - began)
                steps = row["time/total_timesteps"]
                bar.update(steps, force=True)
                if row["rollout/ep_score_mean"] != "":
                    bar.score(row["rollout/ep_score_mean"])
                log.write(row)
                if next_checkpoint and steps >= next_checkpoint:
                    save_checkpoint(algo, run / CHECKPOINTS / f"step_{steps}", config)
                    next_checkpoint = next_multiple(steps, every)
                if config.max_minutes and time.monotonic() - began > 60.0 * config.max_minutes:
                    break
            # The last checkpoint is the final model, so a resume goes on from it.
            last = run / CHECKPOINTS / f"step_{steps}"
            if not last.exists():
                save_checkpoint(algo, last, config)
            if stop:
                raise TrainingInterrupted(run, last, steps, stop, "agents.rllib")
            save_checkpoint(algo, run / MODEL_DIR, config)
    finally:
        bar.close()
        log.close()
        algo.stop()
    return run / MODEL_DIR


def sample_steps(algo: Any, steps: int) -> tuple[int, float]:
    """Let every env runner (the driver's own if there are none) sample ``steps`` env steps at
    once, as training does; returns the steps sampled and the wall time it took."""
    group = algo.env_runner_group
    remote = group.num_remote_env_runners() > 0
    began = time.perf_counter()
    counts = group.foreach_env_runner(
        lambda runner: sum(len(episode) for episode in runner.sample(num_timesteps=steps)),
        local_env_runner=not remote,
    )
    return sum(counts), time.perf_counter() - began


def scaling(config: RllibConfig, runners: list[int], iterations: int, out: Path) -> list[dict]:
    """Env steps per second for each number of env runners, the same config each time (after
    one training iteration to warm up): sampling alone (``iterations`` rounds of a training
    batch split between the runners) and whole training iterations (sampling and learning).
    Returns the rows, also written to ``out``."""
    import ray

    rows = []
    cpus = ray.cluster_resources().get("CPU", 1)
    batch = config.hyperparams.get("train_batch_size_per_learner", 4000)
    for count in runners:
        # More runners than CPUs share them (Ray would otherwise wait for CPUs for ever).
        share = min(config.cpus_per_env_runner, cpus / count) if count else 1
        algo = build(dataclasses.replace(config, env_runners=count, cpus_per_env_runner=share))
        try:
            before = algo.train()["num_env_steps_sampled_lifetime"]  # compile, connect, warm up
            began = time.perf_counter()
            for _ in range(iterations):
                result = algo.train()
            train_time = time.perf_counter() - began
            trained = int(result["num_env_steps_sampled_lifetime"] - before)
            # Then sampling alone (after training: its steps would count in the results).
            sampled, sample_time = 0, 0.0
            for _ in range(iterations):
                steps, seconds = sample_steps(algo, -(-batch // max(count, 1)))
                sampled, sample_time = sampled + steps, sample_time + seconds
        finally:
            algo.stop()
        row = {
            "env_runners": count,
            "envs_per_runner": config.env.num_envs,
            "cpus_per_runner": round(share, 3),
            "steps": sampled,
            "sampled_steps_per_s": round(sampled / sample_time),
            "steps_per_s_with_learning": round(trained / train_time),
        }
        print(json.dumps(row))
        rows.append(row)
    info = {
        "cpus": os.cpu_count(),
        "ray": ray.__version__,
        "iterations": iterations,
        "train_batch_size_per_learner": config.hyperparams.get("train_batch_size_per_learner"),
        "rows": rows,
    }
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps(info, indent=1))
    print("| env runners | envs each | sampled env steps/s | with learning |")
    print("|---|---|---|---|")
    for row in rows:
        cells = (row["env_runners"], row["envs_per_runner"], row["sampled_steps_per_s"],
                 row["steps_per_s_with_learning"])  # fmt: skip
        print("| {} | {} | {:,} | {:,} |".format(*cells))
    print(f"-> {out}")
    return rows


def check_options(args: argparse.Namespace) -> None:
    """The options of ``--scaling`` (a measurement of a config: no resume)."""
    if args.resume is not None and args.scaling:
        raise ConfigError("--resume goes on with the run's own config: no --config")
    if args.iterations < 1:
        raise ConfigError(f"--iterations must be >= 1, got {args.iterations}")
    if args.scaling and min(args.scaling) < 0:
        raise ConfigError(f"--scaling: env runner counts must be >= 0, got {args.scaling}")


def prepare(config: RllibConfig, args: argparse.Namespace) -> list[dict] | None:
    """Start Ray or join the cluster; with ``--scaling``, the measurement, and no training."""
    init_ray(args.address)
    if args.scaling:
        return scaling(config, args.scaling, args.iterations, args.out)
    return None


def main(argv: list[str] | None = None) -> Path | list[dict]:
    parser = training_parser(
        "agents.rllib", __doc__, "configs/agents/rllib_*.yaml", "key=value settings over the config"
    )
    parser.add_argument("--address", help="a Ray cluster to join (auto, or HOST:PORT)")
    parser.add_argument("--scaling", type=int, nargs="+", metavar="RUNNERS",
                        help="measure sampled steps/s with these env runner counts")  # fmt: skip
    parser.add_argument("--iterations", type=int, default=3, help="iterations per --scaling row")
    parser.add_argument("--out", type=Path, default=Path("runs/scaling.json"),
                        help="where --scaling writes its JSON")  # fmt: skip

    def train_in(
        config: RllibConfig, run: Path, resume: bool, progress: bool, args: argparse.Namespace
    ) -> Path:
        return train(config, run, resume, progress, local=args.address is None)

    return run_training(parser, argv, RllibConfig, start, train_in, check_options, prepare)


if __name__ == "__main__":
    main()
