"""Random play: the protocol's lower reference (``random`` in the benchmark)."""

import numpy as np


class RandomPolicy:
    """Uniformly random discrete actions, ``0 .. n_actions - 1``, from a generator of its own
    seeded with ``seed``: the same seed, the same actions."""

    def __init__(self, n_actions: int, seed: int | None = None) -> None:
        self.n_actions = n_actions
        self.rng = np.random.default_rng(seed)

    def __call__(self, size: int | None = None) -> int | np.ndarray:
        """One action, or an array of ``size`` (one per env of a vector env)."""
        return self.rng.integers(0, self.n_actions, size=size)
