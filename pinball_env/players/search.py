"""A player that looks ahead in the simulator itself: :class:`SearchPolicy` (one env),
:class:`VectorSearch` (every env of a native vector env), both a :class:`SearchPlayer` per game
over a :class:`Planner`.

It decides at the moments a choice matters: by default (``decide="flips"``) where the scripted
heuristic would begin a flip with a ball low, so about once a shot (with ``decide="steps"``, at
every step while a ball is low). To decide, it saves the game it plays (``clone_state``,
without the env's random stream: the look-ahead does not see the draws to come, of the sticky
actions or the launches), branches it into a small native vector env, one env per candidate
plan, and plays every branch ``horizon`` steps on, each drawing what it draws (a launch's
speed, a serve) from one stream seeded by the game's frame count: the same draws for every
plan, and the same decision from the same game wherever it is taken. A plan is the scripted
heuristic (``HeuristicPolicy``, each branch its own copy as it is now) with, first, one flipper
action (none, left, right, both) held for ``hold`` steps, or with another ``aim`` (where on a
flipper it shoots a ball rolling down it, a share of the flipper's length); one plan is the
heuristic as it is. Each branch is scored by the points it made, less ``drain_cost`` for each
ball it lost, and the best plan (ties go to the heuristic's, then to the order of the plans)
plays as it played in its branch for its hold, at least ``decide_every`` steps, before the next
decision may come; a chosen aim stays the heuristic's until another is chosen. The look-ahead
plays without sticky actions (a planner cannot know the draws); the game it chooses for plays
under whatever the env has (the benchmark protocol's sticky actions act on the actions it
plays). While no ball in play is below ``low`` (a share of the table's height) there is nothing
to choose: the heuristic plays (its plunge and nudges too).

Its compute per decision is the settings': ``1 + len(aims) + 4 * len(holds)`` branches of
``horizon`` steps each. It is a reference of what looking ahead in the simulator reaches (the
benchmark's ``search-v3`` and ``search-v2``), not a learner, and a teacher a policy can be
trained from.
"""

import dataclasses
from collections.abc import Callable, Mapping, Sequence
from typing import Any, NamedTuple

import gymnasium as gym
import numpy as np

from pinball_env.players.heuristic import HeuristicPolicy
from pinball_env.table import Table

# The discrete actions of the flippers alone (bit 0 the left flipper, bit 1 the right): none,
# left, right, both; the same numbers in every env version.
FLIPPER_ACTIONS = (0, 1, 2, 3)
# What of an info the heuristic reads (the vector env's infos are arrays, one entry per env).
HEURISTIC_INFO = ("ball_position", "ball_velocity", "ball_positions", "ball_velocities",
                  "balls_in_play", "frames", "tilt_warnings", "ball_on_plunger", "plunger_pull",
                  "tilted")  # fmt: skip

DECIDE = ("flips", "steps")  # SearchSettings.decide's values


class Plan(NamedTuple):
    """A candidate of the look-ahead: ``action`` (a flipper action, -1 for none) held for its
    first ``hold`` steps, then the heuristic, with ``aim`` (None: the aim it has)."""

    action: int = -1
    hold: int = 0
    aim: float | None = None


@dataclasses.dataclass(frozen=True)
class SearchSettings:
    """The planner's compute and scoring (module docstring)."""

    horizon: int = 120
    """Steps each branch plays on (at frame skip 1, 60 steps are a second)."""
    holds: tuple[int, ...] = (2, 8)
    """Steps a plan holds its flipper action before the heuristic plays on."""
    aims: tuple[float, ...] = (0.3, 0.7)
    """The heuristic's other aims a plan may take (shares of a flipper's length)."""
    decide: str = "flips"
    """When it decides, while a ball is low: ``flips``, when the heuristic would begin a flip
    (the moments a flip's timing matters); ``steps``, at every step."""
    decide_every: int = 1
    """Steps a chosen plan plays (at least its hold) before the next decision may come."""
    low: float = 0.45
    """The search runs while a ball in play is below this share of the table's height."""
    drain_cost: float = 20_000.0
    """Points a lost ball costs a branch."""

    def __post_init__(self) -> None:
        for name in ("horizon", "decide_every"):
            if not (isinstance(getattr(self, name), int) and getattr(self, name) >= 1):
                raise ValueError(f"{name} must be an integer >= 1, got {getattr(self, name)!r}")
        if not all(isinstance(h, int) and 1 <= h <= self.horizon for h in self.holds):
            raise ValueError(f"holds must be integers from 1 to horizon, got {self.holds!r}")
        if not all(isinstance(a, int | float) and 0.0 < a <= 1.0 for a in self.aims):
            raise ValueError(f"aims must be shares of a flipper's length (0-1], got {self.aims!r}")
        if self.decide not in DECIDE:
            raise ValueError(f"decide must be one of {DECIDE}, got {self.decide!r}")
        if not (self.holds or self.aims):
            raise ValueError("holds or aims must give a plan besides the heuristic's")
        if not 0.0 <= self.low <= 1.0:
            raise ValueError(f"low must be a share of the table's height (0-1), got {self.low}")

    @property
    def candidates(self) -> list[Plan]:
        """The plans of each decision: the heuristic as it is first, then its other aims, then
        each flipper action held for each of ``holds``."""
        held = [Plan(action, hold) for hold in self.holds for action in FLIPPER_ACTIONS]
        return [Plan()] + [Plan(aim=float(aim)) for aim in self.aims] + held


class Planner:
    """The look-ahead (module docstring) for games of one env id, options and table: a native
    vector env of one branch per plan of ``settings``. ``decisions``, ``branch_steps`` and
    ``branch_frames`` count its work."""

    def __init__(
        self, env_id: str, kwargs: Mapping[str, Any], table: Table, settings: SearchSettings
    ) -> None:
        self.table, self.settings = table, settings
        self.plans = settings.candidates
        kwargs = {**kwargs, "render_mode": None, "repeat_action_probability": 0.0}
        self.branches: Any = gym.make_vec(env_id, num_envs=len(self.plans), num_threads=1,
                                          **kwargs)  # fmt: skip
        self.decisions = self.branch_steps = self.branch_frames = 0

    def close(self) -> None:
        self.branches.close()

    def best(self, state: Any, info: Mapping[str, Any], heuristic: HeuristicPolicy) -> Plan:
        """The best plan from the saved game ``state`` (``info``: its last step's), each
        branch's heuristic a fork of ``heuristic`` (the player's, as it is)."""
        self.decisions += 1
        plans = self.plans
        # Every branch draws (launches, serves) from one stream seeded by the game's frame:
        # the same draws for every plan, and the same decision from the same game anywhere.
        stream = np.random.default_rng(int(info["frames"])).bit_generator.state
        _, infos = self.branches.restore_state(dataclasses.replace(state, rng=stream))
        players = [heuristic.fork() for _ in plans]
        for player, plan in zip(players, plans, strict=True):
            if plan.aim is not None:
                player.aim = plan.aim
        start_score, start_balls = infos["score"][0], infos["balls_left"][0]
        value = np.zeros(len(plans))
        live = np.ones(len(plans), dtype=bool)
        actions = np.zeros(len(plans), dtype=np.int64)
        for step in range(self.settings.horizon):
            for k, plan in enumerate(plans):
                seen = info if step == 0 else {key: infos[key][k] for key in HEURISTIC_INFO
                                                if key in infos}  # fmt: skip
                scripted = int(players[k](seen))  # (each copy sees its own branch)
                actions[k] = plan.action if plan.action >= 0 and step < plan.hold else scripted
            frames = infos["frames"]
            _, _, terminated, truncated, infos = self.branches.step(actions)
            self.branch_steps += int(live.sum())
            self.branch_frames += int((infos["frames"] - frames)[live].sum())
            gain = infos["score"] - start_score
            lost = start_balls - infos["balls_left"]
            value = np.where(live, gain - self.settings.drain_cost * lost, value)
            live &= ~(terminated | truncated)
            if not live.any():
                break
        return plans[int(np.argmax(value))]  # (the first of equals: the heuristic's, plan 0)


class SearchPlayer:
    """Plays one game with ``planner``'s look-ahead (module docstring): ``clone()`` saves the
    game as it is now (without its random stream); ``player(info)`` after each reset and step
    of the game; :meth:`reset` at each new game."""

    def __init__(self, planner: Planner, clone: Callable[[], Any]) -> None:
        self.planner, self.clone = planner, clone
        self.settings = planner.settings
        self.heuristic = HeuristicPolicy(planner.table)
        self.base_aim = self.heuristic.aim
        self._plan, self._played, self._left = Plan(), 0, 0

    @property
    def decisions(self) -> int:
        return self.planner.decisions

    @property
    def branch_steps(self) -> int:
        return self.planner.branch_steps

    @property
    def branch_frames(self) -> int:
        return self.planner.branch_frames

    def reset(self) -> None:
        """A new game: the heuristic forgets the last, and takes its own aim again."""
        self.heuristic.reset()
        self.heuristic.aim = self.base_aim
        self._plan, self._played, self._left = Plan(), 0, 0

    def __call__(self, info: Mapping[str, Any]) -> int:
        if self._left == 0 and self._decides(info):
            self._plan = self._search(info)
            self._played, self._left = 0, max(self.settings.decide_every, self._plan.hold)
            if self._plan.aim is not None:
                self.heuristic.aim = self._plan.aim
        scripted = int(self.heuristic(info))  # (its state moves on with every step it sees)
        if self._left == 0:
            return scripted
        step, plan = self._played, self._plan
        self._played, self._left = step + 1, self._left - 1
        return plan.action if plan.action >= 0 and step < plan.hold else scripted

    def played(self, action: int) -> None:
        """The game played ``action``, not its last answer (a learner's: ``agents.distill``):
        its heuristic's flippers follow it; a plan being played goes on."""
        self.heuristic.played(action)

    def _decides(self, info: Mapping[str, Any]) -> bool:
        """A moment to choose: a ball is low (and, deciding on flips, a flip begins)."""
        if not self._low(info):
            return False
        return self.settings.decide == "steps" or self.heuristic.starts_flip(info)

    def _search(self, info: Mapping[str, Any]) -> Plan:
        return self.planner.best(self.clone(), info, self.heuristic)

    def _low(self, info: Mapping[str, Any]) -> bool:
        line = self.settings.low * self.table.height
        if "balls_in_play" in info:
            playing = np.asarray(info["balls_in_play"], dtype=bool)
            return bool((np.asarray(info["ball_positions"])[playing, 1] < line).any())
        return bool(info["ball_position"][1] < line)

    @property
    def table(self) -> Table:
        return self.planner.table


class SearchPolicy(SearchPlayer):
    """Plays ``env`` (a ``gym.make`` pinball env, discrete actions) by looking ahead in the
    simulator (module docstring): ``policy(info)`` after each ``reset`` and ``step`` of it;
    :meth:`reset` at each new game; :meth:`close` when done."""

    def __init__(self, env: gym.Env, settings: SearchSettings | None = None) -> None:
        self.env = env
        game_env: Any = env.unwrapped  # (a PinballEnv: its options, table and clone_state)
        options = game_env.options
        if options.action_type != "discrete":
            raise ValueError("SearchPolicy plays discrete actions")
        if env.spec is None:
            raise ValueError("SearchPolicy plays an env made by gym.make (its id)")
        planner = Planner(env.spec.id, options.to_kwargs(), game_env.table,
                          settings or SearchSettings())  # fmt: skip
        super().__init__(planner, game_env.clone_state)  # (its stream stays the game's)

    def close(self) -> None:
        self.planner.close()


class VectorSearch:
    """Plays every game of a native vector env (``gym.make_vec(..., vectorization_mode=
    "vector_entry_point")``, discrete actions, a fixed table) with the look-ahead: a
    :class:`SearchPlayer` per env, one :class:`Planner` for all (their decisions taken one
    after another). ``policy(infos)`` (one info per env) after each reset and step;
    :meth:`new_game` for an env whose game ended, before its next."""

    def __init__(self, venv: Any, settings: SearchSettings | None = None) -> None:
        if venv.spec is None or venv.options.action_type != "discrete":
            raise ValueError("VectorSearch plays a native vector env of discrete actions, "
                             "made by gym.make_vec")  # fmt: skip
        if venv.core.layouts is not None:
            raise ValueError("the planner plays a fixed table, not generated ones")
        self.venv = venv
        self.planner = Planner(venv.spec.id, venv.options.to_kwargs(), venv.first_table,
                               settings or SearchSettings())  # fmt: skip
        self.players = [self._player(env) for env in range(venv.num_envs)]

    def _player(self, env: int) -> SearchPlayer:
        return SearchPlayer(self.planner, lambda: self.venv.clone_state([env])[0])

    def new_game(self, env: int) -> None:
        self.players[env].reset()

    def close(self) -> None:
        self.planner.close()

    def __call__(self, infos: Sequence[Mapping[str, Any]]) -> np.ndarray:
        return np.array([player(info) for player, info in zip(self.players, infos, strict=True)],
                        dtype=np.int64)  # fmt: skip
