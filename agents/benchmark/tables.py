"""The benchmark's table in words: Markdown (``benchmark.md``, and the docs' results page, which
``docs/generate.py`` writes with it) and the terminal's."""

from typing import Any

import numpy as np

from agents.rollouts import REFERENCES


def markdown_table(methods: dict[str, Any]) -> str:
    """The table as Markdown (``benchmark.md``, the docs' results page): a row per method."""
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
        elif result.get("baseline") in REFERENCES:
            seconds = [run["play_seconds"] / len(run["scores"])
                       for run in result["runs"] if "play_seconds" in run]  # fmt: skip
            cost = f", {np.mean(seconds):.0f} s a game" if seconds else ""
            training = f"none: looks ahead in the simulator{cost}"
        lines.append(f"| {name} | {result['env_id']} | {len(result['runs'])} | "
                     f"{' | '.join(cells)} | {training} |")  # fmt: skip
    return "\n".join(lines) + "\n"


def print_table(table: dict[str, Any]) -> None:
    """A line per method of ``table`` (:func:`~agents.benchmark.results.aggregate_table`'s)."""
    for name, result in table["methods"].items():
        low, high = result["score_iqm_ci95"]
        print(
            f"{name:14s} {result['env_id']}  runs {len(result['runs'])}  score mean "
            f"{result['score_mean']:8.0f}  IQM {result['score_iqm']:8.0f} ({low:.0f}-{high:.0f})  "
            f"normalised {result['normalized_mean']:.2f}"
        )
