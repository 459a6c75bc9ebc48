"""The benchmark's rows: named methods, each a training config on a protocol env trained for
one of the protocol's budgets, or a baseline; and what of a config trains (its digest)."""

import dataclasses
import hashlib
import json
from pathlib import Path
from typing import TYPE_CHECKING, Any

from agents.config import RENAMED_KEYS, TrainConfig
from pinball_env import protocol

if TYPE_CHECKING:
    from agents.distill import DistillConfig

    JobConfig = TrainConfig | DistillConfig  # a method's: agents.train's or agents.distill's

CONFIGS = Path(__file__).resolve().parents[2] / "configs" / "agents"
DISTILL_CONFIGS = CONFIGS.parent / "distill"


@dataclasses.dataclass(frozen=True)
class Method:
    """A row of the benchmark: a training ``config`` (a file of configs/agents) trained for
    ``frames`` (one of the protocol's ``TRAINING_BUDGETS``) or a ``baseline``, on ``env_id``;
    ``tiny``: the overrides of ``--tiny``. ``distilled``: trained by ``agents.distill`` from the
    planner (``config`` a file of configs/distill), for which ``frames`` is a ceiling that
    counts the planner's look-ahead, where ``agents.train`` trains to the budget."""

    env_id: str
    config: str | None = None
    baseline: str | None = None
    tiny: tuple[str, ...] = ()
    frames: int = protocol.TRAINING_FRAMES
    distilled: bool = False

    def __post_init__(self) -> None:
        if self.frames not in protocol.TRAINING_BUDGETS:
            raise ValueError(f"frames={self.frames}: not a budget of the protocol")

    @property
    def trained(self) -> bool:
        return self.config is not None

    @property
    def config_path(self) -> Path:
        assert self.config is not None
        return (DISTILL_CONFIGS if self.distilled else CONFIGS) / self.config


# Small settings for --tiny: a few updates of small networks.
_TINY = ("imitation_steps=0", "validate_every=0", "checkpoint_every=0", "env.num_envs=2")
_TINY_PPO = (*_TINY, "hyperparams.n_steps=64", "hyperparams.batch_size=64",
             "hyperparams.n_epochs=1")  # fmt: skip
_TINY_A2C = (*_TINY, "hyperparams.n_steps=8")
_TINY_DQN = (*_TINY, "hyperparams.learning_starts=200", "hyperparams.buffer_size=2000",
             "hyperparams.batch_size=64")  # fmt: skip
_TINY_DISTILL = ("iterations=2", "env.num_envs=1", "epochs=1", "validate_episodes=1",
                 "teacher.horizon=8", "teacher.aims=[]")  # fmt: skip

METHODS: dict[str, Method] = {
    "random-v3": Method("Pinball-v3", baseline="random"),
    "heuristic-v3": Method("Pinball-v3", baseline="heuristic"),
    "ppo-scale-v3": Method("Pinball-v3", "ppo_scale_v3.yaml", tiny=_TINY_PPO),
    "ppo-tuned-v3": Method("Pinball-v3", "ppo_tuned_v3.yaml", tiny=_TINY_PPO),
    "ppo-tuned-v3-200m": Method(
        "Pinball-v3", "ppo_tuned_v3.yaml", tiny=_TINY_PPO, frames=protocol.LONG_TRAINING_FRAMES
    ),
    # The planner (players.search): a reference that looks ahead in the simulator, not a learner.
    "search-v3": Method("Pinball-v3", baseline="search"),
    # The planner distilled into a policy (agents.distill: DAgger), which plays without it.
    "dagger-v3": Method("Pinball-v3", "search_v3.yaml", tiny=_TINY_DISTILL, distilled=True),
    "random-v2": Method("Pinball-v2", baseline="random"),
    "heuristic-v2": Method("Pinball-v2", baseline="heuristic"),
    "search-v2": Method("Pinball-v2", baseline="search"),
    "ppo-scale-v2": Method("Pinball-v2", "ppo_scale_v2.yaml", tiny=_TINY_PPO),
    "ppo-scale-v2-200m": Method(
        "Pinball-v2", "ppo_scale_v2.yaml", tiny=_TINY_PPO, frames=protocol.LONG_TRAINING_FRAMES
    ),
    "a2c-scale-v2": Method("Pinball-v2", "a2c_scale_v2.yaml", tiny=_TINY_A2C),
    "dqn-scale-v2": Method("Pinball-v2", "dqn_scale_v2.yaml", tiny=_TINY_DQN),
    "random-v1": Method("Pinball-v1", baseline="random"),
    "heuristic-v1": Method("Pinball-v1", baseline="heuristic"),
    "ppo-v1": Method("Pinball-v1", "ppo_v1.yaml", tiny=_TINY_PPO),
    "ppo-sticky-v1": Method("Pinball-v1", "ppo_sticky_v1.yaml", tiny=_TINY_PPO),
    "ppo-wide-v1": Method("Pinball-v1", "ppo_wide_v1.yaml", tiny=_TINY_PPO),
    "ppo-finetune-v1": Method("Pinball-v1", "ppo_finetune_v1.yaml", tiny=_TINY_PPO),
    "ppo-steady-v1": Method("Pinball-v1", "ppo_steady_v1.yaml", tiny=_TINY_PPO),
    "ppo-gentle-v1": Method("Pinball-v1", "ppo_gentle_v1.yaml", tiny=_TINY_PPO),
    "ppo-close-v1": Method("Pinball-v1", "ppo_close_v1.yaml", tiny=_TINY_PPO),
    "ppo-broad-v1": Method("Pinball-v1", "ppo_broad_v1.yaml", tiny=_TINY_PPO),
    "ppo-anchor-v1": Method("Pinball-v1", "ppo_anchor_v1.yaml", tiny=_TINY_PPO),
    "a2c-v1": Method("Pinball-v1", "a2c_v1.yaml", tiny=_TINY_A2C),
    "dqn-v1": Method("Pinball-v1", "dqn_v1.yaml", tiny=_TINY_DQN),
    "ppo-pixels-v1": Method("Pinball-v1", "ppo_pixels_v1.yaml", tiny=_TINY_PPO),
    "random-v0": Method("Pinball-v0", baseline="random"),
    "heuristic-v0": Method("Pinball-v0", baseline="heuristic"),
    "ppo-v0": Method("Pinball-v0", "ppo.yaml", tiny=_TINY_PPO),
}
TINY_FRAMES = 3000
TINY_EPISODES = 3

# Keys counted in steps that a method on the long budget scales with it (its schedules and
# validations spread over ten times the frames).
SCALED_BY_BUDGET = ("total_timesteps", "checkpoint_every", "validate_every")


# Keys added to the configs after runs were published, each with its default, which trains as
# before the key was there: at it, the key stays out of the digest, so those runs keep theirs.
LATER_KEYS = {"kl_anchor_coef": 0.0}
# Keys renamed after runs were published (agents.config.RENAMED_KEYS), new -> old: the digest
# names them as those runs' did.
DIGEST_NAMES = {new: old for old, new in RENAMED_KEYS.items()}


def trained_by(config: "JobConfig") -> dict[str, Any]:
    """What of a config trains, flat: all of it but its ``notes`` (words do not train) and the
    later keys at their defaults (``LATER_KEYS``), renamed keys under their published names
    (``DIGEST_NAMES``)."""
    return {
        DIGEST_NAMES.get(key, key): value for key, value in _flat(config.to_dict()).items()
        if key != "notes" and not (key in LATER_KEYS and value == LATER_KEYS[key])
    }  # fmt: skip


def config_digest(config: "JobConfig") -> str:
    """A short digest of what of ``config`` trains: a run of another config has another."""
    text = json.dumps(trained_by(config), sort_keys=True, default=str)
    return hashlib.sha256(text.encode()).hexdigest()[:16]


def _flat(data: dict[str, Any], prefix: str = "") -> dict[str, Any]:
    """A nested config as ``{"env.kwargs.frame_skip": 1, ...}``."""
    flat = {}
    for key, value in data.items():
        if isinstance(value, dict) and value:
            flat.update(_flat(value, f"{prefix}{key}."))
        else:
            flat[f"{prefix}{key}"] = value
    return flat
