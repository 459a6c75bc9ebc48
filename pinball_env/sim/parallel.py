"""Threads that share a batch of envs: each steps (or draws) a contiguous range of them.

The kernels release the GIL (``nogil=True``) and every env reads and writes only its own rows, so
the results are bitwise those of one call over all envs, for any thread count. (Numba's own
``prange`` was tried first: compiled with ``parallel=True`` the world step gave different
trajectories than the serial kernel, even on one thread.)

Fork-safe: a process forked from one that has started the threads has none of them (a fork copies
only the forking thread), so the copy of the executor would take work and never do it; the child
starts its own instead.
"""

import itertools
import os
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from typing import Any

import numpy as np

# Most threads one batch may use.
MAX_THREADS = 64


def check_threads(num_threads: object) -> int:
    """``num_threads`` as an int in [1, MAX_THREADS], or a ValueError that says what is wrong."""
    if isinstance(num_threads, bool) or not isinstance(num_threads, (int, np.integer)):
        raise ValueError(f"num_threads must be an integer, got {num_threads!r}")
    if not 1 <= num_threads <= MAX_THREADS:
        raise ValueError(f"num_threads must be in [1, {MAX_THREADS}], got {num_threads}")
    return int(num_threads)


class EnvThreads:
    """Runs ``kernel(*args, start, stop)`` over ``[0, n_envs)`` in at most ``num_threads``
    contiguous ranges, this thread taking the first. Picklable, and fork-safe: a copy, or a
    forked child, starts its own threads."""

    def __init__(self, num_threads: int = 1) -> None:
        self.num_threads = check_threads(num_threads)
        self._pool: ThreadPoolExecutor | None = None
        self._pid = os.getpid()  # the process whose threads _pool has

    def run(self, kernel: Callable[..., Any], n_envs: int, *args: Any) -> list[Any]:
        """The kernel's results, one per range, in env order."""
        if self.num_threads == 1:
            return [kernel(*args, 0, n_envs)]
        parts = min(self.num_threads, n_envs)
        bounds = np.linspace(0, n_envs, parts + 1).astype(np.int64)
        ranges = [(int(a), int(b)) for a, b in itertools.pairwise(bounds)]
        if len(ranges) == 1:
            return [kernel(*args, *ranges[0])]
        if self._pool is None or self._pid != os.getpid():
            self._pool = ThreadPoolExecutor(self.num_threads - 1, thread_name_prefix="pinball")
            self._pid = os.getpid()
        futures = [self._pool.submit(kernel, *args, start, stop) for start, stop in ranges[1:]]
        first = kernel(*args, *ranges[0])
        return [first, *(future.result() for future in futures)]

    def close(self) -> None:
        """Stop the threads (a later run starts new ones)."""
        if self._pool is not None and self._pid == os.getpid():
            self._pool.shutdown()
        self._pool = None  # a parent's executor, in a forked child: nothing of it runs here

    def __getstate__(self) -> dict[str, Any]:
        return {"num_threads": self.num_threads, "_pool": None, "_pid": os.getpid()}
