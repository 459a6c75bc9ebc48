"""Wrappers users need around the envs.

- ``SB3VecEnv``: a stable-baselines3 ``VecEnv`` over the native vector env. stable-baselines3 is
  imported only when it is used (the ``train`` extra).
"""

from typing import Any

__all__ = ["SB3VecEnv"]


def __getattr__(name: str) -> Any:
    if name == "SB3VecEnv":  # imports stable-baselines3 (and torch) only now
        from pinball_env.wrappers.sb3 import SB3VecEnv

        return SB3VecEnv
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
