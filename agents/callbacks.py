"""The callbacks of a stable-baselines3 training, one job each, composed with SB3's
``CallbackList`` (:class:`TrainingCallbacks`):

- :class:`Checkpoints`: a checkpoint every ``checkpoint_every`` env steps;
- :class:`Validations`: the validation games every ``validate_every`` env steps;
- :class:`KLAnchorPull`: the pull towards the warm start after each update;
- :class:`EntropySchedule`: the entropy coefficient of the next update, on its schedule;
- :class:`Budget`: the stop at ``total_frames``, after ``max_minutes`` or when asked;
- :class:`Progress`: the games' scores and the frames logged, and the progress bar.

Each reads the env steps of the model; those that count frames read them from the env chain
(:class:`~agents.envs.FrameCounter`), so none depends on another but :class:`Progress`, whose
bar ends at the :class:`Budget`'s deadline.
"""

import collections
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np
from stable_baselines3.common.callbacks import BaseCallback, CallbackList

from agents.config import TrainConfig, entropy_schedule
from agents.envs import FrameCounter
from agents.imitation import KLAnchor
from agents.runs import CHECKPOINTS, ProgressBar, StopRequest, next_multiple, save_model
from agents.validation import Validation


class Checkpoints(BaseCallback):
    """Save the model as ``RUN/checkpoints/step_N.zip`` every ``checkpoint_every`` env steps
    (0: never)."""

    def __init__(self, config: TrainConfig, run: Path) -> None:
        super().__init__()
        self.config, self.run = config, run

    def _on_training_start(self) -> None:
        self.next = next_multiple(self.num_timesteps, self.config.checkpoint_every)

    def _on_step(self) -> bool:
        if self.next and self.num_timesteps >= self.next:
            save_model(
                self.model, self.run / CHECKPOINTS, f"step_{self.num_timesteps}", self.config
            )
            self.next += self.config.checkpoint_every
        return True


class Validations(BaseCallback):
    """Play ``validation``'s games every ``validate_every`` env steps, its score logged as
    ``validation/score_mean``; ``frames``: those played before this training session."""

    def __init__(self, config: TrainConfig, validation: Validation, frames: int = 0) -> None:
        super().__init__()
        self.config, self.validation, self.frames = config, validation, frames

    def _on_training_start(self) -> None:
        self.counter = FrameCounter(self.training_env, self.frames)
        self.next = next_multiple(self.num_timesteps, self.config.validate_every)

    def _on_step(self) -> bool:
        if self.next and self.num_timesteps >= self.next:
            row = self.validation(self.model, self.counter.frames)
            self.logger.record("validation/score_mean", row["score_mean"])
            self.next += self.config.validate_every
        return True


class KLAnchorPull(BaseCallback):
    """``kl_anchor``'s pull after each update, on the rollout it learned from: taken at its end,
    pulled at the next start (the update in between), the KL before the pull logged as
    ``anchor/kl``."""

    def __init__(self, kl_anchor: KLAnchor) -> None:
        super().__init__()
        self.kl_anchor = kl_anchor

    def _on_rollout_start(self) -> None:  # (the update of the last rollout is done)
        kl = self.kl_anchor.pull(self.model.policy)
        if kl is not None:
            self.logger.record("anchor/kl", kl)

    def _on_step(self) -> bool:
        return True

    def _on_rollout_end(self) -> None:
        self.kl_anchor.remember(self.model.rollout_buffer.observations)


class Budget(BaseCallback):
    """Stop at ``total_frames`` frames played (counted on from ``frames``), after
    ``max_minutes`` from ``started`` (``time.monotonic()``; default: when learning starts), or
    when ``stop`` is asked."""

    def __init__(
        self,
        config: TrainConfig,
        frames: int = 0,
        started: float | None = None,
        stop: StopRequest | None = None,
    ) -> None:
        super().__init__()
        self.config, self.frames, self.started, self.stop = config, frames, started, stop

    def _on_training_start(self) -> None:
        self.counter = FrameCounter(self.training_env, self.frames)
        self.deadline = (self.started or time.monotonic()) + 60.0 * self.config.max_minutes

    def _on_step(self) -> bool:
        if self.config.total_frames and self.counter.frames >= self.config.total_frames:
            return False
        limited = self.config.max_minutes and time.monotonic() >= self.deadline
        return not self.stop and not limited


class Progress(BaseCallback):
    """The mean game score of the last 100 training games logged as ``rollout/ep_score_mean``
    (the score, not the shaped return) with their share cut by the time limit
    (``rollout/ep_truncated``), the frames played by all envs as ``time/frames``, and a
    progress bar to ``budget``'s end (see :class:`~agents.runs.ProgressBar`; ``show``: drawn)."""

    def __init__(self, config: TrainConfig, budget: Budget, show: bool = False) -> None:
        super().__init__()
        self.config, self.budget, self.show = config, budget, show
        self.scores: collections.deque = collections.deque(maxlen=100)
        self.truncated: collections.deque = collections.deque(maxlen=100)

    def _on_training_start(self) -> None:  # (after the budget's: its deadline is set)
        self.counter = FrameCounter(self.training_env, self.budget.frames)
        self.bar = ProgressBar(self.config, self.num_timesteps, self.budget.deadline, self.show,
                               self.counter.frames)  # fmt: skip

    def _on_training_end(self) -> None:
        self.bar.close(self.num_timesteps, self.counter.frames)

    def _on_step(self) -> bool:
        dones, infos = self.locals["dones"], self.locals["infos"]
        for env in np.flatnonzero(dones):
            self.scores.append(infos[env]["score"])
            self.truncated.append(infos[env].get("TimeLimit.truncated", False))
        self.bar.update(self.num_timesteps, frames=self.counter.frames)
        return True

    def _on_rollout_end(self) -> None:
        self.logger.record("time/frames", self.counter.frames)
        if self.scores:
            self.logger.record("rollout/ep_score_mean", float(np.mean(self.scores)))
            self.logger.record("rollout/ep_truncated", float(np.mean(self.truncated)))
            self.bar.score(float(np.mean(self.scores)))


class EntropySchedule(BaseCallback):
    """Set the entropy coefficient that the next update reads (``model.ent_coef``, which PPO's
    and A2C's ``train`` read) from ``schedule`` of the progress left, once a rollout is
    collected, and log it as ``train/ent_coef``. (The progress is stable-baselines3's own,
    ``1 - num_timesteps / total_timesteps``, as it is about to update it for that rollout.)"""

    def __init__(self, schedule: Callable[[float], float]) -> None:
        super().__init__()
        self.schedule = schedule

    def _on_step(self) -> bool:
        return True

    def _on_rollout_end(self) -> None:
        total = self.model._total_timesteps
        coefficient = self.schedule(1.0 - float(self.num_timesteps) / float(total))
        self.model.ent_coef = coefficient  # type: ignore[attr-defined]
        self.logger.record("train/ent_coef", coefficient)


class TrainingCallbacks(CallbackList):
    """The callbacks of a training, in the order each step runs them: the KL anchor's pull (with
    ``kl_anchor``), the entropy schedule (with one in the config), checkpoints, validations
    (with ``validation``; none if ``validate_every`` is 0), the budget and the progress.
    ``frames``: those played so far (the frames are counted on from them); the others as their
    callbacks take them."""

    def __init__(
        self,
        config: TrainConfig,
        run: Path,
        frames: int = 0,
        started: float | None = None,
        validation: Validation | None = None,
        stop: StopRequest | None = None,
        progress_bar: bool = False,
        kl_anchor: KLAnchor | None = None,
    ) -> None:
        self.budget = Budget(config, frames, started, stop)
        callbacks: list[BaseCallback] = [KLAnchorPull(kl_anchor)] if kl_anchor else []
        schedule = entropy_schedule(config)
        if schedule is not None:
            callbacks.append(EntropySchedule(schedule))
        callbacks.append(Checkpoints(config, run))
        if validation is not None and config.validate_every:
            callbacks.append(Validations(config, validation, frames))
        callbacks += [self.budget, Progress(config, self.budget, progress_bar)]
        super().__init__(callbacks)

    @property
    def frames(self) -> int:
        """The frames played so far by all envs (the training session's and those before)."""
        return self.budget.counter.frames
