"""The benchmark protocol: how agents are trained, evaluated and compared, declared once.

As ALE's (Machado et al. 2018) and Procgen's protocols, and with rliable's aggregate metrics
(Agarwal et al. 2021):

- **Envs** (:data:`PROTOCOL_ENV_IDS`, from the versions' records): ``Pinball-v3`` (the whole
  cabinet, its full action set of 32 actions, a tilt that any sustained nudging trips,
  multiball); ``Pinball-v2`` (the same game of one ball), ``Pinball-v1`` (v2's game with v1's
  tilt, which ignores one-way nudging) and ``Pinball-v0`` (flippers only), each a track of its
  own: each on its own table, 3 balls, a game of two minutes (:data:`GAME_OPTIONS`). An agent
  may choose how it sees and acts (``obs_type``, ``frame_skip``, ``skip_above``, ``rays``,
  ``nudge_actions``, its reward shaping), not the game.
- **Sticky actions** in evaluation: ``repeat_action_probability`` 0.25, as ALE v5, drawn frame by
  frame from each game's own random stream, so that no evaluation is a sequence an agent could
  learn by heart.
- **Training**: :data:`TRAINING_FRAMES` frames per run (all envs' frames, a warm start's
  included), or the long budget, :data:`LONG_TRAINING_FRAMES` (ALE's 200M), each row saying its
  budget; :data:`TRAINING_SEEDS` (5 per method; a published row with fewer says so in its runs
  column); training never plays a held-out game.
- **Evaluation**: every run plays the :data:`EVAL_SEEDS` games (held out: seeds 100000-100099),
  its policy deterministic.
- **Metrics**: the mean and the interquartile mean (IQM) of the score (of all games of all runs
  pooled), each with a 95% bootstrap interval over seeds and games (:func:`bootstrap_interval`:
  two levels, the seeds drawn, then each drawn seed's games; a method without training seeds
  is one run, its interval the games' alone), a performance
  profile (:func:`performance_profile`), and every game's score normalised by random play (0)
  and the heuristic (1) (:func:`normalized`, from :data:`REFERENCE_SCORES`), and by a human
  score where one is recorded (:data:`HUMAN_SCORES`; ``python -m agents.evaluate --recording
  FILE`` scores a play-tool recording on the protocol).

``python -m agents.benchmark`` runs the protocol; the documentation's pages "Benchmark protocol"
and "Results" (``docs/benchmark.md``, ``docs/results.md``) describe it and give its table.
"""

from collections.abc import Callable, Mapping, Sequence
from typing import Any

import numpy as np

from pinball_env.options import GAME_FRAMES
from pinball_env.versions import ENV_VERSIONS, benchmark_versions

# The envs of the protocol, in the order of its tables (the versions' tracks): the whole
# cabinet with the tilt any sustained nudging trips and multiball first, then the same game of
# one ball, v1's cabinet (whose tilt ignores one-way nudging) and the flippers-only game.
PROTOCOL_ENV_IDS = tuple(version.id for version in benchmark_versions())
# ALE v5's sticky actions: each frame repeats the last one's buttons with this probability.
REPEAT_ACTION_PROBABILITY = 0.25
# The game every protocol evaluation plays, whatever the agent's own options: its table (the
# env id's), 3 balls, two minutes (GAME_FRAMES), the swept physics. An agent's config
# may not change these.
GAME_OPTIONS: dict[str, Any] = {"balls": 3, "max_frames": GAME_FRAMES, "physics": "swept"}
# Env options that change the game rather than the agent's view of it, which the protocol fixes
# (see check_agent_options): the game's (a step limit would cut it short; the time is
# max_frames'); the sticky actions are the protocol's whatever an agent trained with.
PROTOCOL_FIXED_OPTIONS = ("table", "balls", "max_frames", "physics", "max_episode_steps")
# A training run's budget: frames summed over its envs, a warm start's included
# (``total_frames`` of a training config). The shipped PPO trains this in 38 minutes alone on a
# 2-core machine (configs/agents/ppo_gentle_v1.yaml, seed 3: 37.8 minutes).
TRAINING_FRAMES = 20_000_000
# The second budget, ALE's 200M frames (Machado et al. 2018): what PPO learns when samples are
# cheap (a recipe at the env's speed trains it in about half an hour on 2 cores).
LONG_TRAINING_FRAMES = 200_000_000
TRAINING_BUDGETS = (TRAINING_FRAMES, LONG_TRAINING_FRAMES)
# The training seeds of every method (its config's ``seed``).
TRAINING_SEEDS = (0, 1, 2, 3, 4)
# The held-out games: no training or validation game is one of them.
EVAL_SEEDS = range(100_000, 100_100)
# The metrics' bootstrap: replicates, interval and the generator's seed (fixed: the same table
# gives the same intervals).
BOOTSTRAP_SAMPLES = 2000
CONFIDENCE = 0.95
BOOTSTRAP_SEED = 0
# The thresholds of the performance profile, in normalised score (0 random, 1 the heuristic).
PROFILE_TAUS = np.linspace(-0.5, 2.5, 121)

# Mean scores of random play (uniform actions) and of the heuristic
# (pinball_env.players.HeuristicPolicy) over EVAL_SEEDS under the protocol: the 0 and the 1 of
# normalised scores. Measured by ``python -m agents.benchmark --methods random-v3 heuristic-v3
# random-v2 heuristic-v2 random-v1 heuristic-v1 random-v0 heuristic-v0`` (benchmark.json,
# "reference_measured"); fixed here so that every paper normalises alike. (Random play tilts
# Pinball-v2 and -v3 in each ball's first seconds: 3 of its 4 actions nudge.)
REFERENCE_SCORES: dict[str, dict[str, float]] = {
    "Pinball-v3": {"random": 13.8, "heuristic": 158914.8},
    "Pinball-v2": {"random": 3.8, "heuristic": 49423.4},
    "Pinball-v1": {"random": 6402.7, "heuristic": 53590.7},
    "Pinball-v0": {"random": 4140.6, "heuristic": 6392.2},
}
# Mean human scores over recorded games under the protocol (``agents.evaluate --recording``),
# by env id; none is recorded yet.
HUMAN_SCORES: dict[str, float] = {}


def protocol_options(env_id: str, agent_options: Mapping[str, Any] | None = None) -> dict:
    """The ``gym.make`` options of a protocol evaluation of an agent that trained with
    ``agent_options``: its own view of the game (obs_type, frame_skip, skip_above, rays,
    shaping) on the protocol's game, with sticky actions. ValueError if ``env_id`` is not a
    protocol env or the agent's options change the game (:func:`check_agent_options`)."""
    agent_options = dict(agent_options or {})
    check_agent_options(env_id, agent_options)
    agent_options.pop("table", None)  # (the env's own)
    return {
        **agent_options,
        **GAME_OPTIONS,
        "repeat_action_probability": REPEAT_ACTION_PROBABILITY,
    }


def check_agent_options(
    env_id: str, options: Mapping[str, Any], source: str = "the agent's env options"
) -> None:
    """ValueError if ``env_id`` is not a protocol env, or naming each option of ``options``
    that would change the protocol's game (another table, balls, time or physics) rather than
    the agent's view of it."""
    if env_id not in PROTOCOL_ENV_IDS:
        raise ValueError(
            f"{env_id!r} is not an env of the protocol ({', '.join(PROTOCOL_ENV_IDS)})"
        )
    game = {
        **GAME_OPTIONS,
        "table": ENV_VERSIONS[env_id].table,
        "max_episode_steps": None,
    }
    changed = [
        f"{key}={options[key]!r}"
        for key in PROTOCOL_FIXED_OPTIONS
        if key in options and (key not in game or options[key] != game[key])
    ]
    if changed:
        raise ValueError(
            f"{source} change the protocol's game: {', '.join(changed)} (the protocol plays "
            f"{env_id} on table {game['table']!r} with {GAME_OPTIONS}, and sets the sticky "
            f"actions, {REPEAT_ACTION_PROBABILITY})"
        )


def normalized(scores: Any, env_id: str, human: bool = False) -> np.ndarray:
    """Each game's score normalised: 0 is random play's mean and 1 the heuristic's (with
    ``human``, the recorded human mean's) on the protocol's games (:data:`REFERENCE_SCORES`)."""
    reference = REFERENCE_SCORES[env_id]
    top = HUMAN_SCORES[env_id] if human else reference["heuristic"]
    return (np.asarray(scores, dtype=np.float64) - reference["random"]) / (
        top - reference["random"]
    )


def iqm(scores: Any) -> float:
    """The interquartile mean: the mean of the middle half of ``scores`` (all games of all runs
    together), a quarter cut from each end (as ``scipy.stats.trim_mean(x, 0.25)``)."""
    values = np.sort(np.asarray(scores, dtype=np.float64).ravel())
    cut = int(0.25 * len(values))
    return float(values[cut : len(values) - cut].mean())


def _pooled(runs: Sequence[np.ndarray], statistic: Callable[[Any], float]) -> float:
    return float(statistic(np.concatenate([np.ravel(run) for run in runs])))


def bootstrap_interval(
    runs: Sequence[Any],
    statistic: Callable[[Any], float] = iqm,
    samples: int = BOOTSTRAP_SAMPLES,
    confidence: float = CONFIDENCE,
    seed: int = BOOTSTRAP_SEED,
) -> tuple[float, float]:
    """The ``confidence`` percentile interval of ``statistic`` (of all scores pooled) by a
    two-level bootstrap stratified by seed: each of ``samples`` replicates draws the runs
    (training seeds) with replacement and, within each run drawn (its stratum), as many of its
    games with replacement, so that the interval holds both the seeds' and the games' spread
    (rliable resamples runs within each task; here the games of one env are the draws of its
    task). ``runs``: one array of game scores per run (a method without training seeds is one
    run: its interval is the games' alone)."""
    runs = [np.asarray(run, dtype=np.float64).ravel() for run in runs]
    if not runs or any(len(run) == 0 for run in runs):
        raise ValueError("bootstrap_interval needs at least one run, each with games")
    rng = np.random.default_rng(seed)
    values = np.empty(samples)
    for sample in range(samples):
        picked = rng.integers(len(runs), size=len(runs))
        values[sample] = statistic(
            np.concatenate([runs[r][rng.integers(len(runs[r]), size=len(runs[r]))] for r in picked])
        )
    tail = 50.0 * (1.0 - confidence)
    low, high = np.percentile(values, [tail, 100.0 - tail])
    return float(low), float(high)


def performance_profile(runs: Sequence[Any], taus: Any = PROFILE_TAUS) -> np.ndarray:
    """The run-score distribution (rliable's performance profile): for each threshold of
    ``taus``, the share of games scoring above it, averaged over the runs. ``runs``: one array
    of normalised game scores per run."""
    taus = np.asarray(taus, dtype=np.float64)
    shares = [(np.asarray(run, dtype=np.float64).ravel()[:, None] > taus).mean(0) for run in runs]
    return np.mean(shares, axis=0)


def profile_band(
    runs: Sequence[Any],
    taus: Any = PROFILE_TAUS,
    samples: int = 500,
    confidence: float = CONFIDENCE,
    seed: int = BOOTSTRAP_SEED,
) -> tuple[np.ndarray, np.ndarray]:
    """A pointwise ``confidence`` band of :func:`performance_profile`, by the same stratified
    bootstrap as :func:`bootstrap_interval`."""
    runs = [np.asarray(run, dtype=np.float64).ravel() for run in runs]
    rng = np.random.default_rng(seed)
    curves = np.empty((samples, len(np.asarray(taus))))
    for sample in range(samples):
        picked = rng.integers(len(runs), size=len(runs))
        drawn = [runs[r][rng.integers(len(runs[r]), size=len(runs[r]))] for r in picked]
        curves[sample] = performance_profile(drawn, taus)
    tail = 50.0 * (1.0 - confidence)
    return np.percentile(curves, tail, axis=0), np.percentile(curves, 100.0 - tail, axis=0)


def aggregate(runs: Sequence[Any], env_id: str) -> dict[str, Any]:
    """The protocol's metrics of one method on ``env_id``: ``runs`` one array of game scores
    per run. Mean and IQM of the score and of the normalised score, each with its 95% interval
    (and normalised by the human score where one is recorded)."""
    runs = [np.asarray(run, dtype=np.float64).ravel() for run in runs]
    result: dict[str, Any] = {"runs": len(runs), "games": int(sum(len(run) for run in runs))}
    scales: dict[str, Callable[[np.ndarray], np.ndarray]] = {
        "score": lambda run: run,
        "normalized": lambda run: normalized(run, env_id),
    }
    if env_id in HUMAN_SCORES:
        scales["human_normalized"] = lambda run: normalized(run, env_id, human=True)
    for name, scale in scales.items():
        scaled = [scale(run) for run in runs]
        for metric, statistic in (("mean", np.mean), ("iqm", iqm)):
            result[f"{name}_{metric}"] = _pooled(scaled, statistic)
            result[f"{name}_{metric}_ci95"] = list(bootstrap_interval(scaled, statistic))
    result["run_means"] = [float(run.mean()) for run in runs]
    return result


__all__ = [
    "BOOTSTRAP_SAMPLES",
    "CONFIDENCE",
    "EVAL_SEEDS",
    "GAME_OPTIONS",
    "HUMAN_SCORES",
    "LONG_TRAINING_FRAMES",
    "PROFILE_TAUS",
    "PROTOCOL_ENV_IDS",
    "PROTOCOL_FIXED_OPTIONS",
    "REFERENCE_SCORES",
    "REPEAT_ACTION_PROBABILITY",
    "TRAINING_BUDGETS",
    "TRAINING_FRAMES",
    "TRAINING_SEEDS",
    "aggregate",
    "bootstrap_interval",
    "check_agent_options",
    "iqm",
    "normalized",
    "performance_profile",
    "profile_band",
    "protocol_options",
]
