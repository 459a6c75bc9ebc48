"""The simulation of N envs: ``World`` (the kernel's arrays and the call into the kernel),
``EnvTables`` (every env's table, the static record the World owns), the threads that share
the envs (``parallel``), and the physics backends behind the World interface (``backends``:
the swept kernel, pymunk)."""

from pinball_env.sim.tables import EnvTables
from pinball_env.sim.world import World

__all__ = ["EnvTables", "World"]
