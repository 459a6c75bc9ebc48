"""Physics backends behind the World interface: ``"swept"`` (ours) and ``"pymunk"``."""

from pinball_env.sim.world import World
from pinball_env.table import Table

# The physics backends, declared once: the ``physics`` option's choices are these.
PHYSICS = ("swept", "pymunk")


def make_world(
    table: Table, n_envs: int = 1, physics: str = "swept", num_threads: int = 1
) -> World:
    """A World of ``n_envs`` games on ``table``, simulated by the ``physics`` backend (the
    swept kernel on ``num_threads`` threads; pymunk on one)."""
    if physics == "swept":
        return World(table, n_envs, num_threads)
    if physics == "pymunk":
        from pinball_env.sim.backends.pymunk_backend import PymunkWorld  # pymunk is an extra

        return PymunkWorld(table, n_envs)
    raise ValueError(f"physics must be one of {', '.join(map(repr, PHYSICS))}, got {physics!r}")
