"""The generated-table source of the envs (``table="generated"``, ``PinballProcgen-v0``): the
layouts an env plays and the making of their tables, as Procgen's levels.

Tables are made by the env (its :class:`Layouts`): the table of each env's next game generated in
the background while this one is played, those a reset needs at once on several threads.
"""

import functools
import math
import os
import sys
import time
from collections.abc import Iterable
from concurrent.futures import Future, ThreadPoolExecutor, as_completed
from typing import Any

import numpy as np

from pinball_env import checks
from pinball_env.procgen import RANGES, UNLIMITED_LAYOUTS, generate_table, layout_seeds
from pinball_env.render import PIXELS_PER_METRE
from pinball_env.table import Table

# Generated tables kept in memory (a table is about 50 KB; generating one takes 0.6-1 s on 2
# shared cores).
CACHED_TABLES = 512
# Threads that generate the tables a reset needs at once (the playability check's simulation
# releases the GIL, so they share the cores).
GENERATION_THREADS = min(os.cpu_count() or 1, 8)
# Tables that take longer than this to make show their progress on stderr [s], every so often [s].
PROGRESS_AFTER = 2.0
PROGRESS_EVERY = 1.0


def layout_table(seed: int, difficulty: str, targets: bool = False) -> Table:
    """The generated table of a layout (``generate_table``, cached: the same object for the
    same arguments, however they are passed)."""
    return _cached_table(seed, difficulty, bool(targets))


@functools.lru_cache(maxsize=CACHED_TABLES)
def _cached_table(seed: int, difficulty: str, targets: bool) -> Table:
    return generate_table(seed, difficulty, targets)


def frame_size(difficulty: str) -> tuple[int, int]:
    """(width, height) in pixels of the playfield of every rendered frame of ``difficulty``'s
    tables (the scoreboard is beside it): the largest table the generator draws (``RANGES``)
    at the render scale, rounded up to even numbers (as video encoders need); each table is
    fitted into it (``FrameRenderer``)."""
    ranges = RANGES[difficulty]
    size = (ranges.width[1], ranges.width[1] * ranges.aspect[1])  # [m]
    width, height = (2 * math.ceil(round(metres * PIXELS_PER_METRE) / 2) for metres in size)
    return width, height


class Layouts:
    """The layouts an env plays, seeds ``[start, start + count)`` (``count`` 0: unlimited), of
    ``difficulty``, with a drop bank and a spinner if ``targets``, and the making of their
    tables, which belongs to the env: the table of each env's next game is generated on a
    thread in the background while this one is played, and tables needed at once (a reset's)
    on ``GENERATION_THREADS`` threads. Fork-safe: a forked child has none of its parent's
    threads, so it forgets the work pending there and starts its own threads. Which layouts are
    drawn does not depend on any of this."""

    def __init__(self, count: int, start: int, difficulty: str, targets: bool = False) -> None:
        # The options are checked where they are declared (PinballOptions); the seeds are
        # procgen's to check.
        self.seeds = layout_seeds(count, start)
        self.difficulty = difficulty
        self.targets = targets
        self._upcoming: dict[int, int] = {}  # env -> the layout of its next game
        self._to_prefetch: list[int] = []  # upcoming layouts not yet sent to the prefetcher
        self._pending: dict[int, Future[Table]] = {}  # layout -> its table, being generated
        self._prefetcher: ThreadPoolExecutor | None = None  # one thread, beside the training
        self._generators: ThreadPoolExecutor | None = None  # for the tables needed now
        self._pid = os.getpid()  # the process whose threads the executors have

    def draw(self, rng: np.random.Generator) -> int:
        """A layout drawn uniformly from the env's."""
        return self.seeds[int(rng.integers(len(self.seeds)))]

    def check(self, layout: object) -> int:
        """``layout`` (a reset option) if it is one of the env's; a ValueError if not."""
        if not checks.is_int(layout) or layout not in self.seeds:
            seeds = self.seeds
            raise ValueError(
                f"layout must be an integer in [{seeds.start}, {seeds.stop}), got {layout!r}"
            )
        return int(layout)

    def upcoming(self, env: int) -> int | None:
        """The layout drawn for env ``env``'s next game (None: none drawn yet)."""
        return self._upcoming.get(env)

    def set_upcoming(self, env: int, layout: int | None) -> None:
        """Make ``layout`` env ``env``'s next game (None: drawn when it starts), as a saved
        game has it (``envs.states``)."""
        if layout is None:
            self._upcoming.pop(env, None)
        else:
            self._upcoming[env] = self.check(layout)

    def pick(self, env: int, rng: np.random.Generator, chosen: object = None) -> int:
        """The layout of env ``env``'s next game: ``chosen`` (checked), or the one drawn for it
        at its last game. Then the one after is drawn; the next :meth:`tables` has it generated
        in the background while this game is played (unlimited layouts would wait for each
        table otherwise)."""
        if chosen is not None:
            return self.check(chosen)
        layout = self._upcoming.pop(env, None)
        if layout is None:
            layout = self.draw(rng)
        self._upcoming[env] = upcoming = self.draw(rng)
        self._to_prefetch.append(upcoming)
        return layout

    def forget(self, envs: Iterable[int] | None = None) -> None:
        """Drop the layouts drawn ahead for ``envs`` (default: all), whose random generators
        were seeded again."""
        if envs is not None:
            for env in envs:
                self._upcoming.pop(int(env), None)
            return
        self._upcoming.clear()
        self._to_prefetch.clear()
        self._pending.clear()  # their tables still land in the cache

    def table(self, layout: int) -> Table:
        """The table of ``layout`` (see :meth:`tables`)."""
        return self.tables([layout])[layout]

    def tables(self, layouts: Iterable[int]) -> dict[int, Table]:
        """The tables of ``layouts``, by layout: cached, awaited where the background thread has
        begun them, or generated now, on threads if more than one (with progress on stderr
        when that takes a while). Then the layouts drawn ahead by :meth:`pick` are sent to the
        background thread."""
        self._in_this_process()
        futures: dict[int, Future[Table]] = {}
        missing = []
        for layout in dict.fromkeys(layouts):
            future = self._pending.pop(layout, None)
            if future is not None and not future.cancel():  # begun (or done): wait for it
                futures[layout] = future
            else:
                missing.append(layout)
        tables = {}
        if len(missing) == 1:
            tables[missing[0]] = layout_table(missing[0], self.difficulty, self.targets)
        elif missing:
            if self._generators is None:
                self._generators = ThreadPoolExecutor(
                    GENERATION_THREADS, thread_name_prefix="pinball-tables"
                )
            for layout in missing:
                futures[layout] = self._generators.submit(
                    layout_table, layout, self.difficulty, self.targets
                )
        tables.update(self._wait(futures))
        self._prefetch()
        return tables

    def close(self) -> None:
        """Stop the threads (their work is dropped; a later use starts new ones)."""
        self._in_this_process()
        for executor in (self._prefetcher, self._generators):
            if executor is not None:
                executor.shutdown(wait=False, cancel_futures=True)
        self._prefetcher = self._generators = None
        self._pending.clear()

    def _wait(self, futures: dict[int, Future[Table]]) -> dict[int, Table]:
        """The futures' tables, once all are done; their progress on stderr after
        PROGRESS_AFTER seconds, every PROGRESS_EVERY seconds and at the end."""
        start = shown = time.monotonic()
        for done, _ in enumerate(as_completed(futures.values()), 1):
            now = time.monotonic()
            last = done == len(futures)
            if now - start >= PROGRESS_AFTER and (last or now - shown >= PROGRESS_EVERY):
                shown = now
                kind = f"{self.difficulty} tables{' with targets' if self.targets else ''}"
                line = f"generating {len(futures)} {kind}: {done}/{len(futures)}"
                tty = sys.stderr.isatty()  # a terminal's line is rewritten, a log gets lines
                end = "\n" if last or not tty else ""
                print(f"\r{line}" if tty else line, end=end, file=sys.stderr, flush=True)
        return {layout: future.result() for layout, future in futures.items()}

    def _prefetch(self) -> None:
        """Send the layouts drawn ahead to the background thread."""
        for layout in self._to_prefetch:
            if layout not in self._pending and len(self._pending) < CACHED_TABLES:
                if self._prefetcher is None:
                    self._prefetcher = ThreadPoolExecutor(1, thread_name_prefix="pinball-layouts")
                self._pending[layout] = self._prefetcher.submit(
                    layout_table, layout, self.difficulty, self.targets
                )
        self._to_prefetch.clear()

    def _in_this_process(self) -> None:
        """In a forked child: forget the parent's executors and futures (their threads are not
        in this process: the futures would never finish, the executors never work)."""
        if self._pid != os.getpid():
            self._pid = os.getpid()
            self._prefetcher = self._generators = None
            self._pending = {}

    def __getstate__(self) -> dict[str, Any]:
        # A copy starts its own threads, and generates again what was pending here.
        return {**self.__dict__, "_pending": {}, "_prefetcher": None, "_generators": None}


__all__ = ["CACHED_TABLES", "UNLIMITED_LAYOUTS", "Layouts", "frame_size", "layout_table"]
