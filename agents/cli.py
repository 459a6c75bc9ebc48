"""The command line that ``agents.train`` and ``agents.rllib`` share: a new run from
``--config FILE [key=value ...]`` or ``--resume RUN [key=value ...]``, the run folder made (or
extended), the training, its stop on a signal (exit status 128 + the signal) and ``--report``.
A bad config, option or run folder exits with status 2 and one line that names it."""

import argparse
import shutil
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

from agents.config import (
    AnyConfig,
    ConfigError,
    TrainConfig,
    check_evaluation_seeds,
    load_config,
)
from agents.report import report
from agents.runs import (
    CONFIG_FILE,
    CommandInterrupted,
    TrainingInterrupted,
    checkpoints_of,
    extend_run,
    stopped_before_learning,
)
from pinball_env.tools import command_parser
from pinball_env.versions import older_version_note

# train(config, run, resume, progress_bar, args) -> the final model's path
Train = Callable[[AnyConfig, Path, bool, bool, argparse.Namespace], Path]


def training_parser(
    module: str, doc: str | None, configs: str, overrides: str
) -> argparse.ArgumentParser:
    """The options of every training (``python -m MODULE``, described by the first line of
    ``doc``): ``--config`` (one of ``configs``), the ``key=value`` overrides, ``--resume``,
    ``--runs``, ``--report``, ``--episodes``, ``--no-progress``."""
    parser = command_parser(module, doc)
    parser.add_argument("--config", type=Path, help=f"a YAML config ({configs})")
    parser.add_argument("overrides", nargs="*", help=overrides)
    parser.add_argument("--resume", type=Path, metavar="RUN", help="a run folder to go on with")
    parser.add_argument("--runs", type=Path, default=Path("runs"), help="where run folders go")
    parser.add_argument("--report", action="store_true", help="evaluate and report at the end")
    parser.add_argument("--episodes", type=int, default=100, help="games for --report")
    parser.add_argument("--no-progress", action="store_true", help="no progress bar")
    return parser


def run_config(args: argparse.Namespace, kind: type, command: list[str]) -> AnyConfig:
    """The config of the command: the resumed run's, extended by the overrides, or
    ``--config``'s. A run without a checkpoint is refused before anything is written, but for a
    stable-baselines3 run stopped before learning (no model either): it is trained again."""
    if args.resume is not None:
        if args.config is not None:
            raise ConfigError("--resume goes on with the run's own config: no --config")
        resumable = checkpoints_of(args.resume) or (
            kind is TrainConfig and stopped_before_learning(args.resume)
        )
        if (args.resume / CONFIG_FILE).is_file() and not resumable:
            raise ConfigError(f"{args.resume}: no checkpoint to resume from")
        return extend_run(args.resume, args.overrides, kind, command)
    if args.config is None:
        raise ConfigError("give --config FILE (or --resume RUN)")
    return load_config(args.config, args.overrides, kind=kind)


def run_training(
    parser: argparse.ArgumentParser,
    argv: list[str] | None,
    kind: type,
    start: Callable[[AnyConfig, Path, list[str]], Path],
    train: Train,
    check: Callable[[argparse.Namespace], None] = lambda args: None,
    prepare: Callable[[AnyConfig, argparse.Namespace], Any] = lambda config, args: None,
) -> Any:
    """Run the command line ``argv`` (default ``sys.argv``) of a training of configs of
    ``kind``: ``start(config, runs, command)`` makes a run folder, ``train`` trains in it.
    ``check(args)`` runs before the config is read (or a resumed run's extended), ``prepare(
    config, args)`` after it (setup); a result of ``prepare`` other than None ends the command
    with it, before any run. Returns the final model's path."""
    args = parser.parse_args(argv)
    command = sys.argv if argv is None else argv
    try:
        check(args)
        config = run_config(args, kind, command)
        prepared = prepare(config, args)
        if prepared is not None:
            return prepared
        if args.report:  # before training: the report's games must be new to the model
            check_evaluation_seeds(config, config.eval_seed, args.episodes)
        run = args.resume if args.resume is not None else start(config, args.runs, command)
        print(f"run folder: {run}")
        if (note := older_version_note(config.env.id)) is not None:
            print(note)
        try:
            model = train(config, run, args.resume is not None, not args.no_progress, args)
        except ConfigError:
            if args.resume is None:  # nothing was trained: leave no run folder behind
                shutil.rmtree(run)
            raise
    except ConfigError as error:
        parser.exit(2, f"error: {error}\n")
    except TrainingInterrupted as stopped:
        print(stopped, file=sys.stderr)
        raise CommandInterrupted(stopped.exit_code) from None
    print(f"model: {model}")
    if args.report:
        report(run, episodes=args.episodes)
    return model
