"""A policy distilled from the planner (DAgger): the learner plays, the planner labels.

    python -m agents.distill --config configs/distill/search_v3.yaml [key=value ...]
        [--runs runs]

The teacher is ``pinball_env.players.VectorSearch`` (the planner, its ``teacher`` settings),
which looks ahead in the simulator; the learner is a stable-baselines3 actor-critic's policy
network that sees only the observation, so that it plays without the simulator. Each
iteration plays one whole game in each of the ``env.num_envs`` envs (the training games, seeds
``10000 * seed`` on: never a validation or evaluation game): in the first the teacher plays, in
every later one the learner (greedily), while the teacher says at every step what it would play
there (its heuristic's flippers following the learner's buttons: ``HeuristicPolicy.played``).
Every labelled step so far is kept (the aggregated data set) and the policy is fitted to the
teacher's labels (cross-entropy, ``epochs`` passes in minibatches of ``batch_size`` at
``learning_rate``), going on from the last iteration's weights. The observation statistics
(``VecNormalize``'s) are those of the first iteration's games, then frozen.

After each iteration the learner plays the ``validate_episodes`` validation games (from
``validate_seed``, with the env's options: the protocol's sticky actions if the config has
them); the best becomes the run's ``model.zip``, which ``agents.policy.load_policy`` loads as
any trained agent (the run's ``config.yaml`` is the learner's: PPO's policy network on the
config's env). The run's ``distill.yaml`` is this config and ``distill.csv`` a row per
iteration: the games and steps played, the share of the learner's actions the teacher agreed
with, the learner's (or the teacher's) mean score on its games, the data set, the fit's
accuracy, the validation's score and the seconds.

The frames a run trains on count every frame it simulates but the validations': the games of
its iterations and every branch of the planner's look-ahead (the planner's frames are most of
them). ``total_frames`` (0: none) is a ceiling: an iteration runs only while one as long as the
last still fits under it (the first always runs). ``meta.json``'s ``trained`` has the frames
and the learner's steps, as a trained run's.
"""

import csv
import dataclasses
import io
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from agents.config import (
    ConfigError,
    EnvConfig,
    TrainConfig,
    apply_override,
    check_keys,
    config_from_dict,
    read_config_data,
)
from agents.envs import make_env_chain, native_env
from agents.imitation import fit_policy
from agents.runs import CHECKPOINTS, atomic_write, save_model, say
from agents.train import keep_best, record_trained, set_threads, start
from agents.validation import Validation
from pinball_env.players import SearchSettings, VectorSearch
from pinball_env.protocol import EVAL_SEEDS
from pinball_env.tools import command_parser

DISTILL_FILE = "distill.yaml"  # the distillation's config, in the run folder
ITERATIONS_FILE = "distill.csv"
SEED_STRIDE = 10_000  # training seed s plays the games from SEED_STRIDE * s on


@dataclass(frozen=True)
class DistillConfig:
    """A distillation run (module docstring)."""

    env: EnvConfig = field(default_factory=EnvConfig)
    """The learner's env (and the teacher's game): ``num_envs`` games an iteration."""
    seed: int = 0
    """Seed of the network's start, the minibatches and the training games."""
    iterations: int = 6
    """Rounds of play, label and fit (the first played by the teacher)."""
    total_frames: int = 0
    """The frames the run may simulate, the planner's included (0: no ceiling; docstring)."""
    epochs: int = 4
    """Passes over the data set at each fit."""
    learning_rate: float = 1e-3
    batch_size: int = 1024
    balance: float = 0.0
    """How far the fit evens out the actions' shares: each step's cross-entropy weighed by
    (its action's share of the labels) to the power ``-balance``: 0, plain; 1, every action
    weighs as much in all (a flip, a few frames a shot, as much as the many frames of none)."""
    net_arch: list[int] = field(default_factory=lambda: [128, 128])
    """The policy network's hidden layers."""
    teacher: dict[str, Any] = field(default_factory=dict)
    """The planner's ``SearchSettings`` (missing keys: its defaults)."""
    validate_episodes: int = 100
    validate_seed: int = 300_000
    eval_seed: int = EVAL_SEEDS.start
    torch_threads: int = 1
    env_threads: int = 1
    notes: str = ""

    def to_dict(self) -> dict[str, Any]:
        """The config as its YAML file has it (the run's ``distill.yaml``)."""
        return dataclasses.asdict(self)

    def learner(self) -> TrainConfig:
        """The learner's config (the run's ``config.yaml``): PPO's policy network on the env."""
        data = {
            "algo": "ppo", "policy": "MlpPolicy", "seed": self.seed,
            "torch_threads": self.torch_threads, "env_threads": self.env_threads,
            "env": dataclasses.asdict(self.env), "checkpoint_every": 0,
            "hyperparams": {"learning_rate": self.learning_rate,
                            "policy_kwargs": {"net_arch": list(self.net_arch)}},
            "validate_every": 1, "validate_episodes": self.validate_episodes,
            "validate_seed": self.validate_seed, "eval_seed": self.eval_seed,
            "notes": f"distilled from the planner (agents.distill, its {DISTILL_FILE})",
        }  # fmt: skip
        return config_from_dict(data, "<the distilled learner>")

    def check(self, source: str) -> None:
        def fail(problem: str) -> None:
            raise ConfigError(f"{source}: {problem}")

        for key in ("iterations", "epochs", "batch_size", "validate_episodes"):
            if not (isinstance(getattr(self, key), int) and getattr(self, key) >= 1):
                fail(f"{key}: must be an integer >= 1, got {getattr(self, key)!r}")
        for key in ("seed", "total_frames"):
            if not (isinstance(getattr(self, key), int) and getattr(self, key) >= 0):
                fail(f"{key}: must be an integer >= 0, got {getattr(self, key)!r}")
        last = SEED_STRIDE * self.seed + self.iterations * self.env.num_envs
        if last > min(EVAL_SEEDS.start, self.validate_seed) or last > SEED_STRIDE * (self.seed + 1):
            fail(f"seed {self.seed} x {self.iterations} iterations of {self.env.num_envs} games "
                 "reach the validation or evaluation games, or another seed's")  # fmt: skip
        if not (isinstance(self.balance, int | float) and 0.0 <= self.balance <= 1.0):
            fail(f"balance: must be from 0 to 1, got {self.balance!r}")
        if not (isinstance(self.learning_rate, int | float) and self.learning_rate > 0):
            fail(f"learning_rate: must be > 0, got {self.learning_rate!r}")
        try:
            SearchSettings(**self.teacher)
        except (TypeError, ValueError) as error:
            fail(f"teacher: {error}")
        self.learner()  # (its env and network checked as any training config's)


def load_distill_config(path: Path, overrides: list[str] = ()) -> DistillConfig:
    """The distillation config in the YAML file ``path`` (over its ``base``), with ``key=value``
    overrides, checked."""
    data = read_config_data(Path(path))
    for item in overrides:
        apply_override(data, item, path)
    return distill_config_from_dict(data, str(path))


def distill_config_from_dict(data: dict[str, Any], source: str) -> DistillConfig:
    """The distillation config of ``data`` (a YAML file's, or :meth:`DistillConfig.to_dict`'s),
    checked; ``source`` names it in errors."""
    data = dict(data)
    env = data.pop("env", {}) or {}
    check_keys(data, DistillConfig, source, "")
    check_keys(env, EnvConfig, source, "env.")
    config = DistillConfig(**data, env=EnvConfig(**env))
    config.check(source)
    return config


class Iteration:
    """One round's games: each env's first game played by the teacher (``learner`` None) or
    the learner, every step of it labelled by the teacher."""

    def __init__(self, venv: Any, search: VectorSearch, first_seed: int) -> None:
        self.venv, self.search = venv, search
        venv.seed(first_seed)
        self.obs = venv.reset()
        self.infos = list(venv.unwrapped.reset_infos)
        for env in range(venv.num_envs):
            search.new_game(env)

    def play(self, learner: Any | None) -> dict[str, Any]:
        n = self.venv.num_envs
        raw = getattr(self.venv, "get_original_obs", lambda: self.obs)  # (unnormalised)
        observations, labels = [], []
        scores, frames = np.full(n, -1.0), np.zeros(n, dtype=np.int64)
        agreed = steps = 0
        playing = np.ones(n, dtype=bool)
        while playing.any():
            live = np.flatnonzero(playing)
            said = np.array([self.search.players[env](self.infos[env]) for env in live])
            actions = np.zeros(n, dtype=np.int64)
            actions[live] = said
            if learner is not None:
                chosen = learner.predict(self.obs, deterministic=True)[0]
                actions[live] = chosen[live]
                for env in live:  # (the teacher's flippers follow what was played)
                    self.search.players[env].played(int(chosen[env]))
                agreed += int((chosen[live] == said).sum())
            observations.append(raw()[live])
            labels.append(said)
            steps += len(live)
            self.obs, _, _, self.infos = self.venv.step(actions)
            for env in live:
                if "episode" in self.infos[env]:
                    playing[env] = False
                    scores[env] = float(self.infos[env]["score"])
                    frames[env] = int(self.infos[env]["frames"])
        return {"obs": np.concatenate(observations), "labels": np.concatenate(labels),
                "steps": steps, "frames": int(frames.sum()),
                "agreement": agreed / steps if learner is not None else 1.0,
                "score_mean": float(scores.mean())}  # fmt: skip


def distill(config: DistillConfig, runs: Path, command: list[str]) -> Path:
    """Run the distillation (module docstring) in a new run folder of ``runs``; returns it."""
    from stable_baselines3 import PPO

    learner = config.learner()
    set_threads(learner)
    run = start(learner, runs, command)
    (run / DISTILL_FILE).write_text(yaml.safe_dump(config.to_dict(), sort_keys=False))
    venv = make_env_chain(learner, seed=SEED_STRIDE * config.seed)
    search = VectorSearch(native_env(venv), SearchSettings(**config.teacher))
    model = PPO(learner.policy, venv, seed=config.seed, device=learner.device, verbose=0,
                learning_rate=config.learning_rate,
                policy_kwargs={"net_arch": list(config.net_arch)})  # fmt: skip
    validation = Validation(learner, run)
    data_obs: list[np.ndarray] = []
    data_labels: list[np.ndarray] = []
    rows: list[dict[str, Any]] = []
    n, frames, last = venv.num_envs, 0, 0
    for k in range(config.iterations):
        if k > 0 and config.total_frames and frames + last > config.total_frames:
            say(f"{frames} frames: another iteration would pass total_frames; stopping")
            break
        started, planned = time.monotonic(), search.planner.branch_frames
        if hasattr(venv, "training"):
            venv.training = k == 0  # (the statistics of the teacher's games, then frozen)
        first = SEED_STRIDE * config.seed + k * n
        games = Iteration(venv, search, first).play(None if k == 0 else model)
        data_obs.append(games["obs"])
        data_labels.append(games["labels"])
        obs = np.concatenate(data_obs)
        normalize = getattr(venv, "normalize_obs", None)
        labels = np.concatenate(data_labels)
        fitted = fit_policy(model.policy, normalize(obs) if normalize else obs, labels,
                            config.epochs, config.seed + k, batch_size=config.batch_size,
                            class_weights=class_weights(labels, venv.action_space.n,
                                                        config.balance))  # fmt: skip
        last = games["frames"] + search.planner.branch_frames - planned
        frames += last
        model.num_timesteps += games["steps"]
        save_model(model, run / CHECKPOINTS, f"iteration_{k}", learner)
        validated = validation(model, frames)
        rows.append({"iteration": k, "player": "teacher" if k == 0 else "learner",
                     "games": n, "steps": games["steps"], "frames": last,
                     "agreement": round(games["agreement"], 4),
                     "score_mean": round(games["score_mean"], 1), "data": len(obs),
                     "accuracy": round(fitted["accuracy"], 4),
                     "validation": validated["score_mean"],
                     "seconds": round(time.monotonic() - started, 1)})  # fmt: skip
        _write_rows(run / ITERATIONS_FILE, rows)
        say(f"iteration {k}: {rows[-1]}")
    validation.close()
    assert validation.best is not None
    record_trained(run, model.num_timesteps, frames)
    keep_best(run, validation.best)
    search.close()
    venv.close()
    return run


def class_weights(labels: np.ndarray, actions: int, balance: float) -> np.ndarray | None:
    """Each action's weight in the fit: its share of ``labels`` to the power ``-balance``
    (None for 0: plain cross-entropy); an action never labelled weighs nothing."""
    if balance == 0.0:
        return None
    counts = np.bincount(labels, minlength=actions).astype(np.float64)
    shares = counts / counts.sum()
    weights = np.zeros(actions)
    weights[counts > 0] = shares[counts > 0] ** -balance
    return weights


def _write_rows(path: Path, rows: list[dict[str, Any]]) -> None:
    table = io.StringIO()
    writer = csv.DictWriter(table, fieldnames=list(rows[0]), lineterminator="\n")
    writer.writeheader()
    writer.writerows(rows)
    atomic_write(path, lambda file: file.write(table.getvalue().encode()))


def main(argv: list[str] | None = None) -> Path:
    parser = command_parser("agents.distill", __doc__)
    parser.add_argument("--config", type=Path, required=True, help="a YAML distillation config")
    parser.add_argument("overrides", nargs="*", help="key=value settings over the config")
    parser.add_argument("--runs", type=Path, default=Path("runs"), help="where run folders go")
    args = parser.parse_args(argv)
    try:
        config = load_distill_config(args.config, args.overrides)
    except ConfigError as error:
        parser.exit(2, f"{parser.prog}: error: {error}\n")
    run = distill(config, args.runs, ["agents.distill", *(argv or [])])
    print(f"distilled: {run}")
    return run


if __name__ == "__main__":
    main()
