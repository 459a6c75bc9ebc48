"""``pinball_env.env.PinballEnv``, importable here as before; its home is ``pinball_env.envs``."""

from pinball_env.envs.single import PinballEnv

__all__ = ["PinballEnv"]
