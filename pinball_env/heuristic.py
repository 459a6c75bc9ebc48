"""``pinball_env.heuristic.HeuristicPolicy``, the import path the documentation gave; its home
is :mod:`pinball_env.players`."""

from pinball_env.players.heuristic import HeuristicPolicy

__all__ = ["HeuristicPolicy"]
