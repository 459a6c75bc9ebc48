"""``--ship``: a method's best run (by its validation games) made a pretrained agent that ships
with the project (``agents/pretrained/NAME.zip`` and its card ``NAME.json``)."""

import json
import shutil
from pathlib import Path
from typing import Any

from agents.benchmark.jobs import JobSettings
from agents.benchmark.methods import METHODS
from agents.benchmark.results import Merged, method_results
from agents.config import ConfigError
from agents.runs import MODEL_FILE
from pinball_env import protocol

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
    settings: JobSettings,
    ship_as: str | None = None,
    into: Path | None = None,
    merged: Merged | None = None,
    from_out: bool = False,
) -> Path:
    """Make the best run of method ``name`` (by its validation games, never the held-out ones;
    of the runs in OUT and ``merged``, the chosen one in OUT; with ``from_out``, of those in OUT
    alone, the card naming the better run whose model is not here) a pretrained agent ``ship_as``
    (default: the method's name) in ``into`` (default: ``agents/pretrained``): ``SHIP_AS.zip``
    (its model) and ``SHIP_AS.json``, its card (:func:`pretrained_card`)."""
    from agents.policy import PRETRAINED_DIR

    ship_as, into = ship_as or name, into or PRETRAINED_DIR
    result = method_results(name, seeds, settings, merged)
    if result is None or not METHODS[name].trained:
        raise ConfigError(f"{name}: no finished training run to ship in {settings.out}")
    check_shippable(name, result["runs"], settings)
    chosen, chosen_by = choose_run(name, result["runs"], settings, from_out)
    run = settings.out / chosen["run"]
    card = pretrained_card(ship_as, name, result["env_id"], chosen, chosen_by)
    into.mkdir(exist_ok=True)
    shutil.copyfile(run / MODEL_FILE, into / f"{ship_as}.zip")
    (into / f"{ship_as}.json").write_text(json.dumps(card, indent=1) + "\n")
    print(f"shipped {run} as pretrained:{ship_as} ({card['chosen_by']})")
    return into / f"{ship_as}.zip"


def check_shippable(name: str, runs: list[dict[str, Any]], settings: JobSettings) -> None:
    """ConfigError unless method ``name`` has a validated run of the protocol's frames for
    every training seed of the protocol."""
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


def choose_run(
    name: str, runs: list[dict[str, Any]], settings: JobSettings, from_out: bool
) -> tuple[dict[str, Any], str]:
    """The run of ``runs`` to ship and how it was chosen: the best in validation, which must be
    in OUT (with ``from_out``: the best of those in OUT, saying what was better)."""
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
    return chosen, chosen_by


def pretrained_card(
    ship_as: str, name: str, env_id: str, chosen: dict[str, Any], chosen_by: str
) -> dict[str, Any]:
    """The card of run ``chosen`` of method ``name`` shipped as ``ship_as``: the method and
    config, the commit it was trained at, its frames and minutes of training, its scores under
    the protocol, and the scores of the first CHECK_GAMES protocol games."""
    return {
        "name": ship_as,
        "method": name,
        "env_id": env_id,
        "config": METHODS[name].config,
        "seed": chosen["seed"],
        "commit": chosen["commit"],
        "trained": {key: chosen[key] for key in ("frames", "steps", "train_minutes")},
        "chosen_by": chosen_by,
        "protocol": {
            key: value
            for key, value in protocol.aggregate([chosen["scores"]], env_id).items()
            if key != "run_means"
        },
        "check_games": {
            "seeds": list(protocol.EVAL_SEEDS[:CHECK_GAMES]),
            "scores": chosen["scores"][:CHECK_GAMES],
        },
        "load": f'agents.policy.load_policy("pretrained:{ship_as}")',
    }
