"""The learning curves: each trained method's validation games against the frames it had
trained, as the normalised IQM of the games (random 0, the heuristic 1, by the protocol's
reference scores) averaged over its seeds, with a 95% interval over the seeds. Every point comes
from ``benchmark.json`` (each run's ``validations``: frames, mean, IQM), so the results page's
table and ``curves.png`` are generated from the published record alone."""

from typing import Any

import numpy as np

from pinball_env import protocol


def learning_curve(result: dict[str, Any]) -> list[tuple[float, float, float, float, int]]:
    """The curve of one method's ``result`` (``benchmark.json``'s): at each validation (the
    k-th of every run that has a k-th), the mean frames, the mean over the runs of the
    normalised validation IQM, its 95% percentile interval over the runs (a bootstrap of the
    seeds, ``protocol.BOOTSTRAP_SAMPLES`` draws from ``BOOTSTRAP_SEED``) and the runs. Runs
    that recorded no IQM (before it was recorded) have no curve."""
    runs = [[point for point in run.get("validations") or [] if point[2] is not None]
            for run in result["runs"]]  # fmt: skip
    runs = [run for run in runs if run]
    rng = np.random.default_rng(protocol.BOOTSTRAP_SEED)
    tail = 50.0 * (1.0 - protocol.CONFIDENCE)
    curve = []
    for k in range(max((len(run) for run in runs), default=0)):
        points = [run[k] for run in runs if len(run) > k]
        values = protocol.normalized([point[2] for point in points], result["env_id"])
        draws = values[rng.integers(len(values), size=(protocol.BOOTSTRAP_SAMPLES, len(values)))]
        low, high = np.percentile(draws.mean(axis=1), [tail, 100.0 - tail])
        frames = float(np.mean([point[0] for point in points]))
        curve.append((frames, float(values.mean()), float(low), float(high), len(points)))
    return curve


def curves_table(methods: dict[str, Any]) -> str:
    """Markdown: a row per validation of each method that has a curve."""
    lines = [
        "| method | env | frames | runs | normalised validation IQM [95% CI over the runs] |",
        "|---|---|---|---|---|",
    ]
    for name, result in methods.items():
        for frames, value, low, high, runs in learning_curve(result):
            lines.append(f"| {name} | {result['env_id']} | {frames / 1e6:.1f}M | {runs} | "
                         f"{value:.2f} [{low:.2f}, {high:.2f}] |")  # fmt: skip
    if len(lines) == 2:
        lines.append("| (no run has recorded its validations' IQM yet) | | | | |")
    return "\n".join(lines) + "\n"


def draw_curves(ax: Any, methods: dict[str, Any], env_id: str) -> None:
    """The curves of the methods of ``env_id`` on ``ax``, each with its band."""
    for name, result in methods.items():
        curve = learning_curve(result)
        if result["env_id"] != env_id or not curve:
            continue
        frames, value, low, high, _ = (np.array(column) for column in zip(*curve, strict=True))
        ax.plot(frames / 1e6, value, marker="o", markersize=3, label=name)
        ax.fill_between(frames / 1e6, low, high, alpha=0.2)
    ax.axhline(1.0, color="grey", linewidth=0.8, linestyle=":")
    ax.set_xlabel("frames trained [M]")
    ax.set_ylabel("normalised validation IQM (random 0, heuristic 1)")
    if ax.get_legend_handles_labels()[0]:  # (an env whose runs recorded no curve: no legend)
        ax.legend(fontsize=8)
