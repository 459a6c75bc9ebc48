"""``pinball_env.vector_env.PinballVectorEnv``, importable here as before; its home is
``pinball_env.envs``."""

from pinball_env.envs.vector import EnvAttribute, PinballVectorEnv

__all__ = ["EnvAttribute", "PinballVectorEnv"]
