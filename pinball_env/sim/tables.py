"""The static side of a batch of envs: every env's table and what compiled code reads of it.

As MuJoCo MJX's ``Model`` beside its ``Data``: :class:`EnvTables` is what does not change
during play (the packed geometry and settings, points per element, sizes, flipper numbers),
one record per World, beside the kernel's ``State``. While every env plays the World's first
table it holds that table once; :meth:`EnvTables.set` gives an env a table of its own.
"""

import math
from typing import Any

import numpy as np
from numba.typed import List

from pinball_env.physics import element_count
from pinball_env.table import Table

# Tables whose packed arrays are kept, to give them to an env again at no cost.
MAX_PACKED = 1024


def flipper_numbers(table: Table) -> np.ndarray:
    """(4, F): the flippers' rest angles [rad], upstroke signs (+1 counter-clockwise), swings
    [rad] and top angular speeds [rad/s]."""
    rest = np.array([math.radians(f.rest_angle) for f in table.flippers])  # as Table.pack
    up = np.radians([f.up_angle for f in table.flippers])
    top = [max(f.up_speed, f.down_speed) for f in table.flippers]
    return np.array([rest, np.sign(up - rest), np.abs(up - rest), top])


class EnvTables:
    """Every env's table, packed for the kernel, and the per-env numbers the rules and the
    observation read (rows are envs).

    Attributes:
        first: the table every env plays until :meth:`set` gives it another.
        geometry, settings: ``first`` packed (``Table.pack()``, ``Table.pack_settings()``).
        scores: (N, elements) int64 points per element id (rows zero-padded once envs differ).
        width, height: (N,) float64 playfield sizes [m].
        flipper_rest, flipper_up_sign, flipper_swing, flipper_top_speed: (N, F) float64, see
            :func:`flipper_numbers`.
        scoring: per env, the ids of the elements that score.
    """

    def __init__(self, table: Table, n_envs: int) -> None:
        self.first = table
        self.geometry = table.pack()
        self.settings = table.pack_settings()
        self.scores = np.tile(np.asarray(table.element_scores, dtype=np.int64), (n_envs, 1))
        self.width = np.full(n_envs, table.width)
        self.height = np.full(n_envs, table.height)
        flippers = np.array([flipper_numbers(table)] * n_envs).reshape(n_envs, 4, -1)
        (self.flipper_rest, self.flipper_up_sign, self.flipper_swing,
         self.flipper_top_speed) = flippers.transpose(1, 0, 2)  # fmt: skip
        self.scoring = [np.flatnonzero(table.element_scores)] * n_envs
        # Per-env tables once set() has given an env its own: the tables and their packed
        # arrays (typed lists, the kernel's).
        self._tables: list[Table] | None = None
        self._geometries: List | None = None
        self._settings: List | None = None
        self._packed: dict[int, tuple[Table, Any, Any]] = {}  # id -> (table, packed arrays)
        self._same_geometries: List | None = None  # geometries() while every env has `first`

    @property
    def n_envs(self) -> int:
        return self.width.shape[0]

    @property
    def varied(self) -> bool:
        """Whether envs have tables of their own (set by :meth:`set`)."""
        return self._tables is not None

    def table(self, env: int) -> Table:
        """The table env ``env`` plays."""
        return self.first if self._tables is None else self._tables[env]

    def geometry_of(self, env: int) -> Any:
        """The packed table (``physics.Geometry``) env ``env`` plays."""
        return self.geometry if self._geometries is None else self._geometries[env]

    def geometries(self) -> List:
        """Every env's packed table, a typed list (for compiled code that takes one per env)."""
        if self._geometries is None:
            if self._same_geometries is None:
                self._same_geometries = List([self.geometry] * self.n_envs)
            return self._same_geometries
        return self._geometries

    def kernel_arrays(self) -> tuple[Any, Any]:
        """The packed tables and settings of the envs, for compiled code that steps each env
        with ``physics.step_ball``: typed lists with an entry per env, or, while every env plays
        ``first``, 1-tuples (numba then compiles the loop for the one table, which steps 2
        threads about 20% faster than a typed list)."""
        if self._geometries is None:
            return (self.geometry,), (self.settings,)
        return self._geometries, self._settings

    def set(self, env: int, table: Table) -> tuple[int, int, int, tuple[int, ...]]:
        """Make ``table`` env ``env``'s. Returns the element count, sensor count and passes its
        packed arrays need, and its numbers of drop targets, banks, spinners and kickbacks, for
        the World to widen the per-element rows of its state."""
        if self._tables is None:
            self._tables = [self.first] * self.n_envs
            self._pack_all()
        assert self._geometries is not None and self._settings is not None  # (_pack_all's)
        geometry, settings = self._pack(table)
        targets = tuple(len(a) for a in (geometry.drop_targets, geometry.bank_reset,
                                         geometry.spinners, geometry.kickbacks))  # fmt: skip
        needs = (element_count(geometry), geometry.sensors.shape[0], settings.max_passes, targets)
        if self.scores.shape[1] < needs[0]:
            wider = np.zeros((self.n_envs, needs[0]), dtype=np.int64)
            wider[:, : self.scores.shape[1]] = self.scores
            self.scores = wider
        self._tables[env] = table
        self._geometries[env] = geometry
        self._settings[env] = settings
        self.scores[env] = 0
        self.scores[env, : len(table.element_scores)] = table.element_scores
        for array, row in zip(
            (self.flipper_rest, self.flipper_up_sign, self.flipper_swing, self.flipper_top_speed),
            flipper_numbers(table), strict=True,
        ):  # fmt: skip
            array[env] = row
        self.width[env] = table.width
        self.height[env] = table.height
        self.scoring[env] = np.flatnonzero(table.element_scores)
        return needs

    def _pack(self, table: Table) -> tuple[Any, Any]:
        """``table``'s packed arrays and settings, packed once per table."""
        packed = self._packed.get(id(table))
        if packed is None or packed[0] is not table:
            if len(self._packed) >= MAX_PACKED:
                self._packed.clear()
            packed = self._packed[id(table)] = (table, table.pack(), table.pack_settings())
        return packed[1], packed[2]

    def _pack_all(self) -> None:
        """The kernel's typed lists of every env's packed table."""
        assert self._tables is not None
        packed = [self._pack(t) for t in self._tables]
        self._geometries = List([geometry for geometry, _ in packed])
        self._settings = List([settings for _, settings in packed])

    def __getstate__(self) -> dict:
        state = self.__dict__.copy()
        state["_geometries"] = state["_settings"] = None  # typed lists cannot be pickled
        state["_same_geometries"] = None
        state["_packed"] = {}  # keyed by ids, which a copy's tables do not keep
        return state

    def __setstate__(self, state: dict) -> None:
        self.__dict__.update(state)
        if self._tables is not None:  # a copy packs its tables again
            self._pack_all()
