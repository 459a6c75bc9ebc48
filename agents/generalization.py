"""The generalization benchmark: one PPO config trained on 1, 16, 256 and unlimited layouts of
``PinballProcgen-v0``, each tested on held-out layouts.

    python -m agents.generalization --config configs/agents/procgen_ppo.yaml [key=value ...]
        [--layouts 1 16 256 0] [--test-layouts 100] [--out DIR]

For each number of training layouts N (0: unlimited), the config is trained with
``num_layouts=N, start_layout=0`` for its ``total_timesteps`` (the same env steps for every N;
``max_minutes``, if set, caps each run's wall time), then plays one game on each of:

- **test**: ``--test-layouts`` layouts from ``TEST_START`` on, a range no training draw reaches;
- **train**: as many games on its own training layouts (layout ``i mod N``; ``i`` when unlimited).

The random and heuristic baselines play the very same games (layout and seed). A score is
normalised by the baselines on the same games, heuristic = 1 and random = 0:
``(model - random) / (heuristic - random)`` over the mean scores of the set, so that each layout
weighs as its games do (the ratio of single games would explode on a layout where the two
baselines happen to score alike). Its 95% confidence interval is a bootstrap over the layouts,
resampling the games of all three together. Where the heuristic does not beat random on a set,
there is no such scale: that set reports the raw scores, with a warning, and no normalised
score (null in the JSON). Written to ``--out`` (default
``runs/generalization_TIME``): ``generalization.json``, ``generalization.csv`` and
``generalization.png`` (train and test score against the number of training layouts), and a
run folder per N.
"""

import csv
import json
import time
from pathlib import Path
from typing import Any

import numpy as np

from agents.config import ConfigError, TrainConfig, config_from_dict, load_config
from agents.policy import load_policy
from agents.rollouts import BASELINES, baseline_player, play_games, trained_player
from agents.runs import MODEL_FILE
from agents.train import set_threads, start, train
from pinball_env.tools import command_parser

PROCGEN_ID = "PinballProcgen-v0"
LAYOUT_COUNTS = (1, 16, 256, 0)
# The first held-out layout: far beyond any training draw (unlimited draws [0, 2**31)).
TEST_START = 10**12
BOOTSTRAP_SAMPLES = 2000


def with_layouts(config: TrainConfig, count: int) -> TrainConfig:
    """``config`` training on layouts ``[0, count)`` (0: unlimited)."""
    data = config.to_dict()
    data["env"]["kwargs"] = {**data["env"]["kwargs"], "num_layouts": count, "start_layout": 0}
    return config_from_dict(data, f"<{config.env.id}, {count or 'unlimited'} layouts>")


def play(config: TrainConfig, who: str, layouts: list[int], run: Path | None = None) -> np.ndarray:
    """Scores of one game per layout (env seeds ``eval_seed + i``), played by ``who``: a
    baseline's name, or ``"model"`` (the run's), through ``config``'s env chain."""
    seeds = [config.eval_seed + i for i in range(len(layouts))]
    if who == "model":
        if run is None:
            raise ValueError("play: the model's games need its run folder (run=...)")
        player, through = trained_player(run / MODEL_FILE), config
    else:
        player, through = baseline_player(who, config), None  # the baseline's own config
    rows = play_games(player, seeds, through, layouts)
    if [row["layout"] for row in rows] != list(layouts):
        raise RuntimeError(f"{who} played other layouts than the {len(layouts)} asked for")
    return np.array([row["score"] for row in rows], dtype=np.float64)


def normalised(model: np.ndarray, random: np.ndarray, heuristic: np.ndarray, seed: int = 0):
    """``(model - random) / (heuristic - random)`` over the set's means, and its bootstrap 95%
    interval over the games (the three scores of a game resampled together)."""

    def ratio(index: np.ndarray) -> float:
        gap = heuristic[index].mean() - random[index].mean()
        return float((model[index].mean() - random[index].mean()) / gap) if gap else float("nan")

    rng = np.random.default_rng(seed)
    n = len(model)
    samples = np.array([ratio(rng.integers(0, n, n)) for _ in range(BOOTSTRAP_SAMPLES)])
    low, high = np.nanpercentile(samples, [2.5, 97.5])
    return ratio(np.arange(n)), [float(low), float(high)]


def score_set(
    model: np.ndarray, random: np.ndarray, heuristic: np.ndarray, name: str
) -> dict[str, Any]:
    """The mean scores of a set of games and the model's normalised score with its interval,
    or, where the heuristic does not beat random (the scale's unit would be zero or
    negative), none (``None``) and a warning: the raw scores are the result."""
    result: dict[str, Any] = {
        "normalised": None, "ci95": None, "model": float(model.mean()),
        "random": float(random.mean()), "heuristic": float(heuristic.mean()),
    }  # fmt: skip
    if result["heuristic"] > result["random"]:
        result["normalised"], result["ci95"] = normalised(model, random, heuristic)
    else:
        print(
            f"warning: on the {name} layouts the heuristic ({result['heuristic']:.0f}) does not "
            f"beat random ({result['random']:.0f}): no normalised score, raw scores only"
        )
    return result


def benchmark(
    config: TrainConfig, counts: tuple[int, ...], n_test: int, out: Path
) -> list[dict[str, Any]]:
    """Train and test per number of layouts; write the results into ``out``."""
    if config.env.id != PROCGEN_ID:
        raise ConfigError(f"env.id: the benchmark trains on {PROCGEN_ID}, got {config.env.id!r}")
    set_threads(config)
    out.mkdir(parents=True, exist_ok=True)
    test_layouts = list(range(TEST_START, TEST_START + n_test))
    test_config = config_from_dict(
        {**config.to_dict(), "env": {**config.to_dict()["env"], "kwargs": {
            **config.env.kwargs, "num_layouts": n_test, "start_layout": TEST_START}}},
        "<test layouts>",
    )  # fmt: skip
    test_baselines = {who: play(test_config, who, test_layouts) for who in BASELINES}
    results = []
    for count in counts:
        trained = with_layouts(config, count)
        run = start(trained, out / f"layouts_{count}", ["agents.generalization", f"{count}"])
        started = time.monotonic()
        train(trained, run, progress_bar=False)
        seconds = time.monotonic() - started
        train_layouts = [i % count if count else i for i in range(n_test)]
        sets = {
            "test": (test_config, test_layouts, test_baselines),
            "train": (trained, train_layouts, None),
        }
        steps = load_policy(run / MODEL_FILE).model.num_timesteps
        row: dict[str, Any] = {
            "layouts": count, "run": run.name, "train_seconds": seconds, "train_steps": steps
        }  # fmt: skip
        for name, (env_config, layouts, baselines) in sets.items():
            scores = baselines or {who: play(env_config, who, layouts) for who in BASELINES}
            model = play(env_config, "model", layouts, run)
            row[name] = score_set(model, scores["random"], scores["heuristic"], name)
        results.append(row)
        print(
            f"{count or 'unlimited'} layouts: test {_result(row['test'])}, "
            f"train {_result(row['train'])} ({steps} steps, {seconds / 60:.1f} min)"
        )
        write(results, out, config, n_test)
    return results


def _result(result: dict[str, Any]) -> str:
    """A set's normalised score and interval, or its raw scores when it has none."""
    if result["normalised"] is None:
        return (f"model {result['model']:.0f}, random {result['random']:.0f}, heuristic "
                f"{result['heuristic']:.0f} (raw scores)")  # fmt: skip
    low, high = result["ci95"]
    return f"{result['normalised']:.2f} ({low:.2f} to {high:.2f})"


def write(results: list[dict], out: Path, config: TrainConfig, n: int) -> None:
    summary = {"config": config.to_dict(), "test_layouts": n, "test_start": TEST_START,
               "results": results}  # fmt: skip
    (out / "generalization.json").write_text(json.dumps(summary, indent=1))
    with open(out / "generalization.csv", "w", newline="") as file:
        writer = csv.writer(file)
        writer.writerow(["layouts", "set", "normalised", "ci_low", "ci_high", "model",
                         "random", "heuristic"])  # fmt: skip
        for row in results:
            for name in ("train", "test"):
                r = row[name]
                ci95 = r["ci95"] or ["", ""]  # none: the heuristic did not beat random
                writer.writerow([row["layouts"] or "unlimited", name, r["normalised"],
                                 *ci95, r["model"], r["random"], r["heuristic"]])  # fmt: skip
    plot(results, out / "generalization.png", config.total_timesteps)


def plot(results: list[dict], path: Path, steps: int) -> None:
    """Train and test normalised score (with 95% intervals) against the training layouts."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    labels = [str(row["layouts"] or "unlimited") for row in results]
    x = np.arange(len(results))
    fig, ax = plt.subplots(figsize=(6, 3.6), dpi=100)
    for offset, name, marker in ((-0.06, "train", "o"), (0.06, "test", "s")):
        y = np.array([row[name]["normalised"] for row in results], dtype=float)  # None: NaN
        low, high = np.array([row[name]["ci95"] or [None] * 2 for row in results], float).T
        ax.errorbar(x + offset, y, yerr=[y - low, high - y], marker=marker, capsize=4,
                    label=f"{name} layouts")  # fmt: skip
    ax.axhline(1.0, color="grey", linestyle="--", label="heuristic")
    ax.axhline(0.0, color="grey", linestyle=":", label="random")
    ax.set_xticks(x, labels)
    ax.set_xlabel("training layouts")
    ax.set_ylabel("score, normalised (random 0, heuristic 1)")
    ax.set_title(f"PPO on PinballProcgen-v0, {steps:,} env steps of training each")
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)


def main(argv: list[str] | None = None) -> list[dict[str, Any]]:
    parser = command_parser("agents.generalization", __doc__)
    parser.add_argument("--config", type=Path, required=True, help="a PinballProcgen-v0 config")
    parser.add_argument("overrides", nargs="*", help="key=value settings over the config")
    parser.add_argument("--layouts", type=int, nargs="+", default=list(LAYOUT_COUNTS),
                        help="numbers of training layouts (0: unlimited)")  # fmt: skip
    parser.add_argument("--test-layouts", type=int, default=100, help="held-out layouts")
    parser.add_argument("--out", type=Path, help="output folder")
    args = parser.parse_args(argv)
    try:
        if any(count < 0 for count in args.layouts):
            raise ConfigError(f"--layouts must be >= 0 (0: unlimited), got {args.layouts}")
        if args.test_layouts < 2:
            raise ConfigError(f"--test-layouts must be >= 2, got {args.test_layouts}")
        config = load_config(args.config, args.overrides)
        out = args.out or Path("runs") / f"generalization_{time.strftime('%Y%m%d-%H%M%S')}"
        results = benchmark(config, tuple(args.layouts), args.test_layouts, out)
    except ConfigError as error:
        parser.exit(2, f"error: {error}\n")
    print(f"wrote {out / 'generalization.json'} and {out / 'generalization.png'}")
    return results


if __name__ == "__main__":
    main()
