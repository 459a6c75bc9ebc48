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
others would change what was learned and are refused). Training stops at ``total_timesteps``,
after ``max_minutes`` of wall time (the progress bar's remaining time counts to whichever comes
first) or at ``total_frames`` frames played (the benchmark protocol's budget). SIGINT (Ctrl-C)
or SIGTERM saves a checkpoint with the normalisation statistics and prints it and the resume
command; in the warm start it saves nothing (a checkpoint would skip the rest of the warm start
for good), and a run without a checkpoint is trained again from the start when resumed. A
finished warm start is checkpointed as ``checkpoints/step_0.zip`` (whatever ``checkpoint_every``
says): a resume goes on from it without playing and fitting it again. With
``validate_every``, the model plays the validation games (``validate_seed`` on) every that many
steps and at the end; the scores go to ``validation.csv``, the best model so far to
``best_model.zip``, and the best of all becomes ``model.zip`` (the last one stays in
``checkpoints/``). ``--report`` then evaluates the model against the random and heuristic
baselines and writes the report into the run folder (see ``agents.report``).

Models are pickles inside zips: load only models you trust.
"""

import time
from pathlib import Path
from typing import Any

from agents.cli import run_training, training_parser
from agents.config import ConfigError, TrainConfig, algorithm_class, sb3_hyperparams
from agents.envs import make_env_chain
from agents.imitation import KLAnchor, imitate
from agents.runs import (
    BEST_MODEL,
    CHECKPOINTS,
    MODEL_FILE,
    STATS_FILE,
    VALIDATION_FILE,
    StopRequest,
    TrainingInterrupted,
    atomic_write,
    keep_progress,
    latest_checkpoint,
    read_meta,
    save_model,
    say,
    start_run,
    stats_for,
    stopped_before_learning,
    write_meta,
)
from agents.validation import Validation

WARM_START = "step_0"  # the checkpoint of a finished warm start
MODEL_NAME = Path(MODEL_FILE).stem  # model.zip, model_vecnormalize.pkl


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

    from agents.callbacks import TrainingCallbacks

    started = time.monotonic()
    set_threads(config)
    checkpoint = latest_checkpoint(run) if resume else None
    if resume and checkpoint is None:
        if not stopped_before_learning(run):
            raise ConfigError(f"{run}: no checkpoint to resume from")
        print(f"{run} has no checkpoint yet: training it again from the start")
        clear_training_logs(run)
        resume = False
    venv, model, frames = _model(config, run, checkpoint)
    model.set_logger(configure(str(run), ["csv", "tensorboard"]))
    if config.imitation_steps and checkpoint is None:
        frames = warm_start(model, venv, config, stop)
        if stop:  # cut short: a checkpoint now would skip the rest of it on resume
            venv.close()
            raise TrainingInterrupted(run, None, 0, stop, "agents.train")
        save_model(model, run / CHECKPOINTS, WARM_START, config)
        record_trained(run, 0, frames)
    try:
        kl_anchor = _kl_anchor(config, run, model)
    except ConfigError:
        venv.close()
        raise
    validation = Validation(config, run) if config.validate_every else None
    callback = TrainingCallbacks(
        config, run, frames, started, validation, stop, progress_bar, kl_anchor
    )
    left = config.total_timesteps - model.num_timesteps
    if left > 0 and not stop:
        model.learn(left, callback=callback, reset_num_timesteps=not resume)
        # Where learning stopped (progress.csv's last row is the last whole rollout's).
        record_trained(run, model.num_timesteps, callback.frames)
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
    save_model(model, run, MODEL_NAME, config)
    if validation is not None:
        if not validation.rows or validation.rows[-1]["steps"] != model.num_timesteps:
            validation(model, callback.frames)
        validation.close()
        keep_best(run, validation.best)
    venv.close()
    return run / MODEL_FILE


def _model(
    config: TrainConfig, run: Path, checkpoint: tuple[int, Path] | None
) -> tuple[Any, Any, int]:
    """The training env, the model (new, or loaded from ``checkpoint`` with its statistics)
    and the frames played so far (a resume's, from its progress files)."""
    algorithm = algorithm_class(config.algo)
    stats = stats_for(checkpoint[1]) if checkpoint else None
    if checkpoint and config.env.normalize and stats is None:
        raise ConfigError(f"{checkpoint[1]}: its VecNormalize statistics are missing")
    venv = make_env_chain(config, stats=stats, step_infos=False)
    if checkpoint is None:
        try:
            model = algorithm(
                config.policy, venv, seed=config.seed, device=config.device, verbose=0,
                **sb3_hyperparams(config),
            )  # fmt: skip
        except (TypeError, ValueError, AssertionError) as error:  # SB3 checks with asserts too
            venv.close()
            raise ConfigError(f"hyperparams: {config.algo.upper()} rejects them: {error}") from None
        return venv, model, 0
    if hasattr(venv, "obs_rms"):
        venv.training = True  # the loaded statistics go on learning
        venv.norm_reward = True
    steps, path = checkpoint
    print(f"resuming {run} from {path.name} ({steps} steps)")
    model = algorithm.load(path, env=venv, device=config.device)
    if hasattr(model, "replay_buffer"):  # checkpoints hold no buffer: refill it first
        model.learning_starts += model.num_timesteps
    # (a resume from the warm start's checkpoint has logged no rollout: meta.json has its frames)
    return venv, model, max(keep_progress(run), trained_frames(run))


def _kl_anchor(config: TrainConfig, run: Path, model: Any) -> KLAnchor | None:
    """The pull towards the warm start (``kl_anchor_coef``; None without one): the model's policy
    before it has learned (just fitted, or resumed from the warm start's checkpoint), else the
    warm start's checkpoint's."""
    if not config.kl_anchor_coef:
        return None
    reference = model.policy
    if model.num_timesteps:
        path = run / CHECKPOINTS / f"{WARM_START}.zip"
        if not path.is_file():
            raise ConfigError(f"{run}: kl_anchor_coef needs the warm start's checkpoint {path}")
        reference = algorithm_class(config.algo).load(path, device=config.device).policy
    batch_size = getattr(model, "batch_size", None) or model.n_steps * model.n_envs
    coef = config.kl_anchor_coef
    return KLAnchor(reference, coef, batch_size, config.seed, model.max_grad_norm)


def clear_training_logs(run: Path) -> None:
    """Remove what a training that left no checkpoint logged in ``run`` (its progress,
    validation rows and best model, TensorBoard events), before it is trained again."""
    logged = ["progress*.csv", VALIDATION_FILE, f"{BEST_MODEL}*", "events.out.tfevents.*"]
    for path in [path for pattern in logged for path in run.glob(pattern)]:
        path.unlink()


def trained_frames(run: Path) -> int:
    """The frames ``meta.json`` says were played (``trained``; 0 without it)."""
    return int(read_meta(run).get("trained", {}).get("frames", 0))


def record_trained(run: Path, steps: int, frames: int) -> None:
    """Write where training stopped, env steps and frames, into ``meta.json`` (``trained``)."""
    write_meta(run, {**read_meta(run), "trained": {"steps": int(steps), "frames": int(frames)}})


def warm_start(model: Any, venv: Any, config: TrainConfig, stop: StopRequest) -> int:
    """The heuristic's games and the fit to them (``agents.imitation``), logged under
    ``imitation/``; returns the frames they played."""
    fit = imitate(model, venv, config.imitation_steps, config.imitation_epochs, config.seed, stop,
                  config.imitation_learning_rate)  # fmt: skip
    say(
        f"warm start: the heuristic played {fit['steps']} steps ({fit['frames']} frames); "
        f"the policy now takes its action {fit['accuracy']:.1%} of the time "
        f"({fit['seconds']:.0f} s){' (cut short)' if stop else ''}"
    )
    for key in ("steps", "frames", "accuracy", "value_loss", "seconds"):
        model.logger.record(f"imitation/{key}", fit[key])
    return fit["frames"]


def keep_best(run: Path, best: dict[str, Any]) -> None:
    """Make the best validated model (``best_model.zip``) the run's ``model.zip``."""
    for name in (f"{BEST_MODEL}_{STATS_FILE}", f"{BEST_MODEL}.zip"):  # as save_model does
        if (run / name).exists():
            target = run / name.replace(BEST_MODEL, MODEL_NAME)
            atomic_write(target, lambda file, source=run / name: file.write(source.read_bytes()))
    say(
        f"model: the best on the validation games, at {int(best['steps'])} steps "
        f"(score {best['score_mean']:.0f}); the last is in {CHECKPOINTS}/"
    )


def main(argv: list[str] | None = None) -> Path:
    parser = training_parser(
        "agents.train", __doc__, "configs/agents/*.yaml",
        "key=value settings over the config (--resume: extensions)",
    )  # fmt: skip
    return run_training(
        parser, argv, TrainConfig, start,
        lambda config, run, resume, progress, args: train(config, run, resume, progress),
    )  # fmt: skip


if __name__ == "__main__":
    main()
