"""The benchmark's plots: every method's game scores, performance profiles and learning curves,
per env."""

from pathlib import Path
from typing import Any

import numpy as np

from agents.benchmark.curves import draw_curves
from pinball_env import protocol


def plot_benchmark(methods: dict[str, Any], out: Path) -> None:
    """``scores.png`` (every method's game scores, per env), ``profiles.png`` (performance
    profiles of the normalised scores with 95% bands, per env) and ``curves.png`` (the learning
    curves: ``curves.draw_curves``)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    envs = [
        env
        for env in protocol.PROTOCOL_ENV_IDS
        if any(m["env_id"] == env for m in methods.values())
    ]
    for kind, draw in (("scores", _draw_scores), ("profiles", _draw_profiles)):
        figure, axes = plt.subplots(1, len(envs), figsize=(6.0 * len(envs), 4.0), squeeze=False)
        for ax, env_id in zip(axes[0], envs, strict=True):
            runs = {name: [np.asarray(run["scores"], dtype=np.float64) for run in m["runs"]]
                    for name, m in methods.items() if m["env_id"] == env_id}  # fmt: skip
            draw(ax, runs, env_id)
            ax.set_title(f"{env_id}, the protocol's games")
        _save(plt, figure, out / f"{kind}.png")
    figure, axes = plt.subplots(1, len(envs), figsize=(6.0 * len(envs), 4.0), squeeze=False)
    for ax, env_id in zip(axes[0], envs, strict=True):
        draw_curves(ax, methods, env_id)
        ax.set_title(f"{env_id}, validation games")
    _save(plt, figure, out / "curves.png")


def _save(plt: Any, figure: Any, path: Path) -> None:
    figure.tight_layout()
    figure.savefig(path, dpi=100)
    plt.close(figure)


def _draw_scores(ax: Any, runs: dict[str, list[np.ndarray]], env_id: str) -> None:
    ax.boxplot([np.concatenate(games) for games in runs.values()], showmeans=True)
    ax.set_xticks(range(1, len(runs) + 1), list(runs), rotation=20)
    ax.set_ylabel("game score")


def _draw_profiles(ax: Any, runs: dict[str, list[np.ndarray]], env_id: str) -> None:
    normalized = {name: [protocol.normalized(games, env_id) for games in method_runs]
                  for name, method_runs in runs.items()}  # fmt: skip
    # The protocol's thresholds, widened to hold 98% of these games.
    taus = protocol.PROFILE_TAUS
    pooled = np.concatenate([np.concatenate(method_runs) for method_runs in normalized.values()])
    low, high = np.percentile(pooled, [1, 99])
    if low < taus[0] or high > taus[-1]:
        taus = np.linspace(min(low, taus[0]), max(high, taus[-1]), len(taus))
    for name, method_runs in normalized.items():
        ax.plot(taus, protocol.performance_profile(method_runs, taus), label=name)
        ax.fill_between(taus, *protocol.profile_band(method_runs, taus), alpha=0.2)
    ax.axvline(1.0, color="grey", linewidth=0.8, linestyle=":")
    ax.set_xlabel("normalised score τ (random 0, heuristic 1)")
    ax.set_ylabel("share of games scoring > τ")
    ax.legend(fontsize=8)
