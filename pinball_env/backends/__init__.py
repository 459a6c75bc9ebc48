"""Physics backends behind the World interface: ``"swept"`` (ours) and ``"pymunk"``."""

from pinball_env.table import Table
from pinball_env.world import World

PHYSICS = ("swept", "pymunk")


def make_world(table: Table, n_envs: int = 1, physics: str = "swept") -> World:
    """A World of ``n_envs`` games on ``table``, simulated by the ``physics`` backend."""
    if physics == "swept":
        return World(table, n_envs)
    if physics == "pymunk":
        from pinball_env.backends.pymunk_backend import PymunkWorld  # pymunk is an extra

        return PymunkWorld(table, n_envs)
    raise ValueError(f"physics must be one of {', '.join(map(repr, PHYSICS))}, got {physics!r}")
