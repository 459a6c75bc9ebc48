"""The scripted players: programs that play the env through its public interface (its ``info``
and action space), used alike by the tools (``python -m pinball_env.tools.demo``) and the
agents (the ``heuristic`` baseline, the warm start's teacher).

- :class:`HeuristicPolicy`: flips timed from the ball's predicted touch, catch and aim; on a
  table with the cabinet, the skill shot and nudges for outlane balls.
- :class:`RandomPolicy`: uniformly random actions (the protocol's lower reference).
- :class:`SearchPolicy`: each action chosen by looking ahead in the simulator (saved games
  branched into a vector env), the heuristic playing on in each branch: a reference above it;
  :class:`VectorSearch` plays every game of a native vector env so.
"""

from pinball_env.players.heuristic import HeuristicPolicy, plunger_pulls, skill_shot_frames
from pinball_env.players.random import RandomPolicy
from pinball_env.players.search import SearchPolicy, SearchSettings, VectorSearch

__all__ = ["HeuristicPolicy", "RandomPolicy", "SearchPolicy", "SearchSettings", "VectorSearch",
           "plunger_pulls", "skill_shot_frames"]  # fmt: skip
