"""Saved games: the state of one env's game, cloned and restored, as ALE's ``cloneState`` and
``restoreState`` (``PinballEnv.clone_state`` and ``restore_state``, and the native vector
env's per env, for branching one game into many).

A :class:`PinballState` carries everything the game's continuation depends on: every ball slot
(in play, held, in the trough), the flippers, the plunger's pull, the cabinet and its plumb bob,
the tilt and its warnings, the drop targets, spinners and kickbacks, the lamps, counters,
timers and rules, the score, the balls left, the frames played, the buttons of the last frame
(which sticky actions repeat), the ball search's clocks, the multiball's queue and locks, the
kernel's candidate sets (a cache, carried so that nothing of the continuation depends on
where the state was restored), a generated table's layout (and the one drawn for the next game)
and, on the vector env, the episode's return and length so far. It does not carry the env's
random stream (``np_random``: sticky actions, launches and serves draw from it) unless cloned
with ``include_rng=True``, as ALE separates ``cloneState`` from ``cloneSystemState``; the
options an env was made with (they are the env's, checked to be the same game); anything of the
wrappers around the env (``TimeLimit``'s steps, say: the game's own time is its ``frames``).

A state restores only into an env of the same id, table, package version and ball slots (a
ValueError naming what differs, with nothing changed). Restored and stepped with the same
actions (and, cloned with its stream, the same draws), an env plays bitwise the continuation
the cloned env played.
"""

import dataclasses
from collections.abc import Callable
from typing import Any

import numpy as np

from pinball_env.envs.core import PinballCore
from pinball_env.game.state import GameState
from pinball_env.table import Table, table_sha256
from pinball_env.version import __version__


@dataclasses.dataclass(frozen=True)
class PinballState:
    """One env's game, saved (module docstring): opaque, picklable, restored by the env's
    ``restore_state``. Its fields are for the checks and the curious, not to be edited."""

    env_id: str | None  # the env's registered id (None: an env not made by gym.make)
    package_version: str  # pinball_env.__version__
    table_sha256: str  # the table's digest (recording.table_sha256)
    ball_slots: int  # the table's ball slots (its trough)
    game: GameState  # the env's rows of every array of the game's state, (1, ...) each
    near: tuple[np.ndarray, np.ndarray, np.ndarray]  # the kernel's candidate sets, (1, ...)
    layout: int | None  # a generated table's layout (None: a fixed table)
    upcoming: int | None  # the layout drawn for the next game (None: not drawn yet)
    # A vector env's episode so far: its return, its length, and whether it ended at the last
    # step (the next step starts a new game); None: a single env's (restored as a new episode).
    episode: tuple[float, int, bool] | None
    rng: dict[str, Any] | None  # the env's random stream (bit generator state), if included


def clone_env(
    core: PinballCore,
    env: int,
    env_id: str | None,
    rng: np.random.Generator | None,
    episode: tuple[float, int, bool] | None = None,
) -> PinballState:
    """The state of env ``env`` of ``core`` (``rng``: its random stream to include, or None)."""
    game, scratch = core.game, core.game.world.scratch
    layouts = core.layouts
    return PinballState(
        env_id=env_id,
        package_version=__version__,
        table_sha256=table_sha256(game.world.table_of(env)),
        ball_slots=game.world.n_balls,
        game=_rows(game.state, env),
        near=tuple(
            array[env : env + 1].copy()
            for array in (scratch.near, scratch.near_ends, scratch.near_zone)
        ),
        layout=None if core.layout is None else int(core.layout[env]),
        upcoming=None if layouts is None else layouts.upcoming(env),
        episode=episode,
        rng=None if rng is None else dict(rng.bit_generator.state),
    )


def restore_env(
    core: PinballCore, env: int, state: object, env_id: str | None, rng: np.random.Generator
) -> Callable[[], None]:
    """Check that ``state`` restores into env ``env`` of ``core`` (a ValueError saying what
    differs, with nothing changed) and return the restore, to be called once every env of a
    restore is checked: it puts the game back, and ``rng`` at the state's stream if it has one."""
    if not isinstance(state, PinballState):
        raise TypeError(f"restore_state takes a PinballState (clone_state's), not {type(state)}")
    known = state.env_id is not None and env_id is not None  # (an env made without gym.make)
    differs = [
        f"{what}: the state's {saved!r}, the env's {here!r}"
        for what, saved, here in (
            ("env id", state.env_id if known else None, env_id if known else None),
            ("package version", state.package_version, __version__),
            ("ball slots", state.ball_slots, core.game.world.n_balls),
            ("generated tables", state.layout is not None, core.layouts is not None),
        )
        if saved != here
    ]
    if differs:
        raise ValueError(f"this state is of another game ({'; '.join(differs)})")
    table = core.game.world.table_of(env)
    if state.layout is not None:
        assert core.layouts is not None  # (checked above)
        table = core.layouts.table(core.layouts.check(state.layout))
    if table_sha256(table) != state.table_sha256:
        raise ValueError(
            f"this state is of another table (its digest {state.table_sha256[:12]}..., the "
            f"env's table {table.name!r} {table_sha256(table)[:12]}...)"
        )
    return lambda: _restore(core, env, state, table, rng)


def _restore(
    core: PinballCore, env: int, state: PinballState, table: Table, rng: np.random.Generator
) -> None:
    game, scratch = core.game, core.game.world.scratch
    if state.layout is not None:
        assert core.layouts is not None and core.layout is not None  # (restore_env's checks)
        if table is not game.world.table_of(env):
            game.set_table(env, table)
        core.layout[env] = state.layout
        core.layouts.set_upcoming(env, state.upcoming)
    _put_rows(state.game, game.state, env)
    for saved, array in zip(state.near, (scratch.near, scratch.near_ends, scratch.near_zone),
                            strict=True):  # fmt: skip
        _put_row(saved[0], array, env)
    game.restored(env)
    if state.rng is not None:
        rng.bit_generator.state = state.rng


def _rows(record: tuple, env: int) -> Any:
    """A copy of env ``env``'s rows of every array of ``record`` (a record of arrays and
    records), each keeping its env axis of length 1."""
    return type(record)(*(_rows(value, env) if isinstance(value, tuple)
                          else value[env : env + 1].copy() for value in record))  # fmt: skip


def _put_rows(source: tuple, target: tuple, env: int) -> None:
    """Copy the rows of record ``source`` (:func:`_rows`') into env ``env``'s of ``target``."""
    for saved, array in zip(source, target, strict=True):
        if isinstance(array, tuple):
            _put_rows(saved, array, env)
        else:
            _put_row(saved[0], array, env)


def _put_row(saved: np.ndarray, array: np.ndarray, env: int) -> None:
    """``array[env] = saved``; where the envs' rows are wider than one table needs (generated
    tables: ``World.set_table``) and differ in width, the part both have is copied and the
    rest is zero (the rows past a table's own elements are unused)."""
    if saved.shape == array.shape[1:]:
        array[env] = saved
        return
    row = array[env]
    common = tuple(slice(0, min(a, b)) for a, b in zip(saved.shape, row.shape, strict=True))
    row[...] = 0
    row[common] = saved[common]
