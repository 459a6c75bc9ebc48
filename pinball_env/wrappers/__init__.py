"""Wrappers users need around the envs.

- ``SB3VecEnv``: a stable-baselines3 ``VecEnv`` over the native vector env, and
  ``SB3VecNormalize``, SB3's ``VecNormalize`` without its per-env Python loop. stable-baselines3
  is imported only when one is used (the ``train`` extra).
"""

from typing import Any

__all__ = ["SB3VecEnv", "SB3VecNormalize"]


def __getattr__(name: str) -> Any:
    if name in __all__:  # imports stable-baselines3 (and torch) only now
        from pinball_env.wrappers import sb3

        return getattr(sb3, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
