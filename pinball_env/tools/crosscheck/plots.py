"""The cross-check's figure: pass-through against speed, bounce errors, flippers, the cabinet,
ball-ball shots."""

from pathlib import Path
from typing import Any

import numpy as np

from pinball_env.table import load_table
from pinball_env.tools.crosscheck.scenarios import (
    CABINET_TABLE,
    ENGINES,
    FRAME_RATE,
    LOW_SPEED,
    SUBSTEP,
    VELOCITY_TOLERANCE,
)


def _label(ax: Any, title: str, ylabel: str, log: str) -> None:
    """A panel against ball speed: its title, axis labels, log scales on the axes in ``log``
    (``"x"``, ``"xy"``) and legend."""
    for axis in log:
        getattr(ax, f"set_{axis}scale")("log")
    ax.set_xlabel("ball speed [m/s]")
    ax.set_ylabel(ylabel)
    ax.set_title(title)
    ax.legend(fontsize=7)


def plot(report: dict[str, Any], path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(4, 2, figsize=(11, 16))
    ax = axes[0, 0]
    tunnel = report["tunnelling"]
    styles = {"wall": "-", "resting flipper": "--", "swinging flipper": ":"}
    for target, style in styles.items():
        for engine, colour in zip(ENGINES, ("tab:blue", "tab:red"), strict=True):
            ax.plot(tunnel["speeds"], 100 * np.array(tunnel[target][engine]), style, color=colour,
                    marker="o", label=f"{engine}: {target}")  # fmt: skip
    _label(ax, "Tunnelling: thin wall and flipper (substep 1/600 s)", "passed through [%]", "x")

    ax = axes[0, 1]
    rows = report["wall_bounces"]
    for engine, colour in zip(ENGINES, ("tab:blue", "tab:red"), strict=True):
        speeds = [row["speed"] for row in rows]
        errors = [max(100 * row[engine]["relative_velocity_error"], 1e-6) for row in rows]
        ax.scatter(speeds, errors, color=colour, s=12, label=engine)
    ax.axvline(LOW_SPEED, color="grey", ls=":")
    ax.axhline(100 * VELOCITY_TOLERANCE[0], color="grey", ls="--", label="tolerance")
    title = "Wall bounces vs analytic (all angles; exact shown at 1e-6)"
    _label(ax, title, "bounce velocity error [% of speed]", "xy")

    ax = axes[1, 0]
    free = report["free_run"]
    time = np.arange(len(free["divergence"])) / FRAME_RATE
    ax.semilogy(time, np.maximum(free["divergence"], 1e-12))
    ax.axhline(0.001, color="grey", ls=":")
    ax.axhline(0.01, color="grey", ls="--")
    ax.set_xlabel("time [s]")
    ax.set_ylabel("|swept - pymunk| [m]")
    ax.set_title("Free run on the classic table: divergence")

    ax = axes[1, 1]
    from pinball_env.tools.plot import draw_table

    draw_table(ax, load_table("classic"))
    for engine, colour in zip(ENGINES, ("tab:blue", "tab:red"), strict=True):
        p = np.array(free["paths"][engine])
        ax.plot(p[:, 0], p[:, 1], color=colour, lw=0.8, label=engine)
    ax.legend(fontsize=7, loc="upper left")
    ax.set_title("Free run paths")
    _plot_cabinet(report, axes[2])
    _plot_ball_ball(report, axes[3])
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=90)
    plt.close(fig)


def _plot_cabinet(report: dict[str, Any], axes: Any) -> None:
    """The nudge in free flight (the right nudge) and the plunger launches against analytic."""
    ax = axes[0]
    row = next(row for row in report["nudge_free_flight"] if row["nudge"] == "nudge_right")
    time = np.arange(1, row["frames"] + 1) / FRAME_RATE
    ax.plot(time, -np.array(row["swept"]["cabinet_velocity"])[:, 0], color="grey", lw=4,
            alpha=0.4, label="-cabinet velocity")  # fmt: skip
    for engine, colour, style in zip(ENGINES, ("tab:blue", "tab:red"), ("-", ":"), strict=True):
        dv = np.array(row[engine]["ball_velocity_change"])[:, 0]
        ax.plot(time, dv, style, color=colour, label=f"{engine}: ball")
    ax.set_xlabel("time after the nudge [s]")
    ax.set_ylabel("velocity change along x [m/s]")
    ax.set_title("Nudge right: a ball in free flight, relative to the table")
    ax.legend(fontsize=7)

    ax = axes[1]
    rows = report["plunger"]
    width = 0.35
    for k, (engine, colour) in enumerate(zip(ENGINES, ("tab:blue", "tab:red"), strict=True)):
        errors = [
            (r[engine]["apex"] - r["apex"]) / (r["speed"] * SUBSTEP)
            if r["apex"] is not None
            else (r[engine]["gate_time"] - r["gate_time"]) / SUBSTEP
            for r in rows
        ]
        ax.bar(np.arange(len(rows)) + (k - 0.5) * width, errors, width, color=colour,
               label=engine)  # fmt: skip
    ax.set_xticks(np.arange(len(rows)), [f"{r['pull']:g}" for r in rows])
    ax.axhline(0.5, color="grey", ls="--", label="tolerance")
    ax.axhline(-0.5, color="grey", ls="--")
    ax.set_xlabel("plunger pull [fraction of the stroke]")
    ax.set_ylabel("error [substeps: apex / (v h), gate time / h]")
    ax.set_title(f"Plunger launches on {CABINET_TABLE} vs analytic")
    ax.legend(fontsize=7)


def _plot_ball_ball(report: dict[str, Any], axes: Any) -> None:
    """The ball-ball shots against the analytic answer: the velocity error and the contact's
    time error of each shot (head-on, onto a resting ball, oblique; speeds; restitutions)."""
    rows = report["ball_ball"]
    labels = [f"{r['shot']}\n{r['speed']:g} m/s e={r['restitution']:g}" for r in rows]
    x = np.arange(len(rows))
    width = 0.35
    panels = (
        ("velocity_error", 1.0, "velocity error [m/s] (exact shown at 1e-16)", "log", 1e-16),
        ("contact_time_error", 1e3, "contact time error [ms]", "linear", None),
    )
    for ax, (key, scale, ylabel, yscale, floor) in zip(axes, panels, strict=True):
        for k, (engine, colour) in enumerate(zip(ENGINES, ("tab:blue", "tab:red"), strict=True)):
            values = np.array([scale * r[engine][key] for r in rows])
            if floor is not None:
                values = np.maximum(np.abs(values), floor)
            ax.bar(x + (k - 0.5) * width, values, width, color=colour, label=engine)
        ax.set_yscale(yscale)
        ax.set_xticks(x, labels, rotation=90, fontsize=6)
        ax.set_ylabel(ylabel)
        ax.set_title("Ball-ball shots (equal masses) vs analytic")
        ax.legend(fontsize=7)
