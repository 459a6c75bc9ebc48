"""A player that looks ahead in the simulator itself: :class:`SearchPolicy`.

Before each action it saves the game it plays (``clone_state``, without the env's random
stream: the look-ahead does not see the draws to come, of the sticky actions or the
launches), branches it into a small native vector env, one env per candidate, and plays every
branch ``horizon`` steps on: a candidate holds one flipper action (none, left, right, both)
for its first ``hold`` steps, after which the scripted heuristic (``HeuristicPolicy``, each
branch its own copy as it is now) plays on; one more candidate is the heuristic throughout.
Each branch is scored by the points it made, less ``drain_cost`` for each ball it lost; the
best candidate's first action is played (ties go to the heuristic's, then to the order of the
candidates). The look-ahead plays without sticky actions (a planner cannot know the draws);
the game it chooses for plays under whatever the env has (the benchmark protocol's sticky
actions act on the actions it plays). While no ball in play is below ``low`` (a share of the
table's height) there is nothing to choose: the heuristic plays (its plunge and nudges too).

Its compute per decision is the settings': ``len(holds) * 4 + 1`` branches of ``horizon``
steps each, one decision every ``decide_every`` steps (the action held in between). It is a
reference of what looking ahead in the simulator reaches (the benchmark's ``search-v3`` and
``search-v2``), not a learner, and a teacher a policy can be trained from.
"""

import dataclasses
from collections.abc import Mapping
from typing import Any

import gymnasium as gym
import numpy as np

from pinball_env.players.heuristic import HeuristicPolicy

# The discrete actions of the flippers alone (bit 0 the left flipper, bit 1 the right): none,
# left, right, both; the same numbers in every env version.
FLIPPER_ACTIONS = (0, 1, 2, 3)
# What of an info the heuristic reads (the vector env's infos are arrays, one entry per env).
HEURISTIC_INFO = ("ball_position", "ball_velocity", "ball_positions", "ball_velocities",
                  "balls_in_play", "frames", "tilt_warnings", "ball_on_plunger", "plunger_pull",
                  "tilted")  # fmt: skip


@dataclasses.dataclass(frozen=True)
class SearchSettings:
    """The planner's compute and scoring (module docstring)."""

    horizon: int = 45
    """Steps each branch plays on (at frame skip 1, 60 steps are a second)."""
    holds: tuple[int, ...] = (2, 8)
    """Steps a candidate holds its flipper action before the heuristic plays on."""
    decide_every: int = 1
    """A decision every this many steps, its action held in between."""
    low: float = 0.45
    """The search runs while a ball in play is below this share of the table's height."""
    drain_cost: float = 20_000.0
    """Points a lost ball costs a branch."""

    def __post_init__(self) -> None:
        for name in ("horizon", "decide_every"):
            if not (isinstance(getattr(self, name), int) and getattr(self, name) >= 1):
                raise ValueError(f"{name} must be an integer >= 1, got {getattr(self, name)!r}")
        if not self.holds or not all(isinstance(h, int) and 1 <= h <= self.horizon
                                     for h in self.holds):  # fmt: skip
            raise ValueError(f"holds must be integers from 1 to horizon, got {self.holds!r}")
        if not 0.0 <= self.low <= 1.0:
            raise ValueError(f"low must be a share of the table's height (0-1), got {self.low}")

    @property
    def candidates(self) -> list[tuple[int, int]]:
        """(action, hold) of each candidate but the heuristic's (action -1)."""
        return [(-1, 0)] + [(action, hold) for hold in self.holds for action in FLIPPER_ACTIONS]


class SearchPolicy:
    """Plays ``env`` (a ``gym.make`` pinball env, discrete actions) by looking ahead in the
    simulator (module docstring): ``policy(info)`` after each ``reset`` and ``step`` of it;
    :meth:`reset` at each new game. ``decisions`` and ``branch_steps`` count its work."""

    def __init__(self, env: gym.Env, settings: SearchSettings | None = None) -> None:
        self.env = env
        game_env: Any = env.unwrapped  # (a PinballEnv: its options, table and clone_state)
        self.game_env = game_env
        self.settings = settings or SearchSettings()
        options = self.game_env.options
        if options.action_type != "discrete":
            raise ValueError("SearchPolicy plays discrete actions")
        kwargs = {**options.to_kwargs(), "render_mode": None, "repeat_action_probability": 0.0}
        self.table = self.game_env.table
        self.heuristic = HeuristicPolicy(self.table)
        if env.spec is None:
            raise ValueError("SearchPolicy plays an env made by gym.make (its id)")
        self.branches: Any = gym.make_vec(env.spec.id, num_envs=len(self.settings.candidates),
                                          num_threads=1, **kwargs)  # fmt: skip
        self.decisions = self.branch_steps = 0
        self._held = (0, 0)  # the action being held, and steps left

    def reset(self) -> None:
        """A new game: the heuristic forgets the last."""
        self.heuristic.reset()
        self._held = (0, 0)

    def close(self) -> None:
        self.branches.close()

    def __call__(self, info: Mapping[str, Any]) -> int:
        scripted = int(self.heuristic(info))  # (its state moves on with every step it sees)
        action, left = self._held
        if left > 0:
            self._held = (action, left - 1)
            return action
        if not self._low(info):
            return scripted
        action = self._search(scripted)
        self._held = (action, self.settings.decide_every - 1)
        return action

    def _low(self, info: Mapping[str, Any]) -> bool:
        line = self.settings.low * self.table.height
        if "balls_in_play" in info:
            playing = np.asarray(info["balls_in_play"], dtype=bool)
            return bool((np.asarray(info["ball_positions"])[playing, 1] < line).any())
        return bool(info["ball_position"][1] < line)

    def _search(self, scripted: int) -> int:
        """The first action of the best branch from the game as it is."""
        self.decisions += 1
        candidates = self.settings.candidates
        n = len(candidates)
        state = self.game_env.clone_state()  # (its stream stays the game's)
        _, infos = self.branches.restore_state(state)
        players = [self.heuristic.fork() for _ in range(n)]
        start_score, start_balls = infos["score"][0], infos["balls_left"][0]
        value = np.zeros(n)
        live = np.ones(n, dtype=bool)
        actions = np.zeros(n, dtype=np.int64)
        for step in range(self.settings.horizon):
            for k, (action, hold) in enumerate(candidates):
                if action >= 0 and step < hold:
                    actions[k] = action
                elif step == 0:
                    actions[k] = scripted  # (this step's heuristic action is the one played)
                else:
                    info = {key: infos[key][k] for key in HEURISTIC_INFO if key in infos}
                    actions[k] = int(players[k](info))
            _, _, terminated, truncated, infos = self.branches.step(actions)
            self.branch_steps += int(live.sum())
            gain = infos["score"] - start_score
            lost = start_balls - infos["balls_left"]
            value = np.where(live, gain - self.settings.drain_cost * lost, value)
            live &= ~(terminated | truncated)
            if not live.any():
                break
        best = int(np.argmax(value))  # (the first of equals: the heuristic's, candidate 0)
        action, _ = candidates[best]
        return scripted if action < 0 else action
