"""The validation games of a run: the model being trained plays the same held-apart games
every ``validate_every`` env steps; the rows go to ``RUN/validation.csv`` and the best model
so far to ``RUN/best_model.zip``."""

import copy
import csv
import io
from pathlib import Path
from typing import Any

from agents.config import TrainConfig
from agents.envs import make_env_chain
from agents.rollouts import model_policy, rollouts, summarize
from agents.runs import (
    BEST_MODEL,
    VALIDATION_FILE,
    atomic_write,
    best_validation,
    save_model,
    say,
    validation_rows,
)
from pinball_env import protocol


class Validation:
    """The validation games of a run: ``validate_episodes`` whole games from ``validate_seed``
    on, the same games each time, played deterministically by the model being trained through
    a copy of its env chain (``VecNormalize``'s statistics frozen at their current values).
    Each result is a row of ``RUN/validation.csv``; the best model so far is kept as
    ``RUN/best_model.zip`` (a resumed run goes on from the rows already written)."""

    FIELDS = ("steps", "frames", "score_mean", "score_low", "score_high", "length_mean",
              "truncated_share", "score_iqm")  # fmt: skip

    def __init__(self, config: TrainConfig, run: Path) -> None:
        self.config, self.run = config, run
        self.venv: Any = None
        self.rows = validation_rows(run)  # a resumed run's so far

    @property
    def best(self) -> dict[str, Any] | None:
        """The row of the best validation so far (the earliest of equals), or None."""
        return best_validation(self.rows)

    def __call__(self, model: Any, frames: int) -> dict[str, float]:
        """Validate ``model`` (``frames`` played in training so far); returns its row."""
        games = self.config.validation_seeds
        if self.venv is None:
            self.venv = make_env_chain(self.config, num_envs=len(games), seed=games.start)
        if hasattr(self.venv, "obs_rms"):
            self.venv.obs_rms = copy.deepcopy(model.get_env().obs_rms)
            self.venv.training = False  # (before the reset, which would update them)
            self.venv.norm_reward = False
        self.venv.seed(games.start)  # the same games every time
        say(f"validating at {model.num_timesteps} steps: {len(games)} games...")
        played = rollouts(self.venv, model_policy(model), list(games))
        summary = summarize(played)
        best = self.best
        row = {
            "steps": model.num_timesteps, "frames": frames,
            "score_mean": round(summary["score_mean"], 2),
            "score_low": round(summary["score_ci95"][0], 2),
            "score_high": round(summary["score_ci95"][1], 2),
            "length_mean": round(summary["length_mean"], 2),
            "truncated_share": summary["truncated_share"],
            "score_iqm": round(protocol.iqm([game["score"] for game in played]), 2),
        }  # fmt: skip
        if best is None or row["score_mean"] > best["score_mean"]:
            save_model(model, self.run, BEST_MODEL, self.config)
        self.rows.append(row)
        table = io.StringIO()
        writer = csv.DictWriter(table, fieldnames=self.FIELDS, lineterminator="\n")
        writer.writeheader()
        writer.writerows(self.rows)
        atomic_write(self.run / VALIDATION_FILE, lambda file: file.write(table.getvalue().encode()))
        say(
            f"validation at {row['steps']} steps: score {row['score_mean']:.0f} (95% CI "
            f"{row['score_low']:.0f}-{row['score_high']:.0f}) over {len(games)} games; best "
            f"{self.best['score_mean']:.0f}"
        )
        return row

    def close(self) -> None:
        if self.venv is not None:
            self.venv.close()
