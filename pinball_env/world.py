"""``pinball_env.world.World``, importable here as before; its home is ``pinball_env.sim``."""

from pinball_env.sim.world import CONTACT_CAPACITY, Contact, World, compiled_entry

__all__ = ["CONTACT_CAPACITY", "Contact", "World", "compiled_entry"]
