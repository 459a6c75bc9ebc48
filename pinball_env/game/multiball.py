"""The game's several balls: the trough, drains, locks and the auto-plunger, for a
table whose trough holds more than one ball.

The choice: such a table's frames are stepped by Python, frame by frame (the World's several-ball
kernel, ``World.swept_kernel`` False), inside the same compiled step loop
(``game.play.play_frames``), which hands each frame's physics back to ``Game._play_frames``;
this module acts around that physics. Everything the loop does for
one ball (the buttons, the cabinet, the rules, the ball save, the end-of-ball bonus, the ball
search, the reward) it does here too, on **the game's ball**: ``state.game_ball`` (N, 5) and
``state.game_ball_active`` (N,) hold the first ball in play (the lowest slot,
``GameState.ball_slot``) and whether any ball is in play. The loop's
own writes to it (a ball put on the player's plunger, a tilted ball given up) are written back
to its slot (:meth:`Multiball.write_back`) before Python does anything else.

What runs around a frame's physics is split by how often it has work. The common path is
compiled over every env at once: after the physics, :func:`after_frames` (drains, the ball
search of the other balls, a lock that took the only ball, the multiball's start and end, the
game's ball) and, in the World, the saucers and locks (``sim.world.play_holders``): none of it
draws from an env's random stream, so all of it is compiled. Python keeps the rare events, for
the envs that have them: a lock released and a queued ball (:meth:`Multiball.before_frame`, whose
auto-plunger draws from the env's stream), a loop's write to the game's ball (the envs that
:func:`written` finds), launches and serves (``Game.launch_balls``; their game's balls synced in
one call, :func:`sync_balls`), a new game. The first version (per-env Python every frame, kept
as the reference of ``tests/game/test_multiball_compiled.py``) ran Pinball-v3's native vector
env of 1024 envs about 9x slower.

The rules of the balls:

- the trough holds the balls not in play (slots neither active nor held); the first ball of each
  ball in play is served to the plunger as today (the player's, or the machine's launch);
- ``add_balls`` (a rule's effect) queues balls (``GameState.pending_balls``) that the trough's
  auto-plunger launches from the plunger's position, straight up, at a speed drawn from
  ``auto_plunger.speed`` with the env's random stream, one a frame while the shooter lane is
  clear (no ball within LANE_CLEAR radii of the plunger, none waiting on the player's plunger);
  queued balls beyond what the trough holds are dropped;
- a ball that drains returns to the trough; the ball (of ``balls_left``) is lost, with its
  end-of-ball bonus, only when the last ball in play drains (the loop sees the game's ball out
  of play); a ball held in a saucer is in play, one held in a lock is not, and is not lost:
  where a lock takes the only ball in play, the auto-plunger serves one from the trough (or,
  with none there, the locks let theirs go);
- a multiball starts when a second ball comes into play (the ``multiball_starts`` trigger) and
  ends when one is left (``multiball_ends``), both seen after each frame's physics
  (``GameState.multiball_events``);
- ``ball_save`` (a rule's effect) runs ``GameState.multiball_save`` frames: a ball that drains
  meanwhile is queued for the auto-plunger again;
- ``release_lock`` lets the lock's balls go before the next frame's physics.

The ball search and the tilt watch every ball in play (not held in a saucer or a lock: a saucer
kicks its ball out itself, a lock holds its balls until a rule lets them go), each with its own
clock (``GameState.ball_anchor``, ``ball_still``), the one-ball rule for each: a ball that has not
moved a ball radius in BALL_SEARCH_TIME is stuck.

- The game's ball is watched by the loop, as on a table of one ball (``GameState.anchor``,
  ``still_frames``: served again off the plunger); where another ball becomes the game's ball,
  the clocks are handed over (:meth:`Multiball.sync`), so that no ball's wait starts again.
- Any other stuck ball is served again the simplest way that a machine's ball search (coils
  pulsed until the ball comes free) ends: it goes back to the trough and is queued for the
  auto-plunger (``pending_balls``), which launches it as soon as the shooter lane is clear.
  The balls in play plus the queued ones stay as many, so a multiball neither ends nor starts.
- A tilt gives up every ball in play: flippers and kickers are dead, so they drain; one that
  lies still as long as the ball search waits goes back to the trough (the game's ball too,
  while another ball is in play; the last by the loop, as on a table of one ball). During the
  tilt the auto-plunger's queue is emptied, the multiball's ball save stops, no lock lets its
  balls go (locked balls stay locked) and a lock that takes the last ball in play serves none:
  the ball is lost once, when the last ball in play is gone.
"""

from collections.abc import Callable, Sequence
from typing import NamedTuple

import numpy as np
from numba import njit

from pinball_env.game.parameters import ball_search_frames
from pinball_env.game.state import GameState
from pinball_env.physics.columns import BALL_X, BALL_Y
from pinball_env.sim.world import World, compiled_entry
from pinball_env.table import Table

# The shooter lane is clear for the auto-plunger when no ball is within this many ball radii of
# the plunger's position.
LANE_CLEAR = 3.0


class Memory(NamedTuple):
    """What :class:`Multiball` keeps between frames, for the compiled passes."""

    proxy: np.ndarray  # (N, 5): the game's ball as last written here (write_back)
    proxy_active: np.ndarray  # (N,) bool: ... and whether it was in play
    was_active: np.ndarray  # (N, M) bool: the balls in play before the frame's physics
    watching: np.ndarray  # (N,) int64: the slot the loop's ball search clock is (-1: none)


class Multiball:
    """The several balls of a game's envs (module docstring): what Python does around each
    frame's physics, on ``world`` (its ball slots) and the game's ``state`` (``GameState``:
    the game's ball, the trough's queue, the clocks), on ``table``."""

    def __init__(self, world: World, table: Table, state: GameState) -> None:
        self.world = world
        self.state = state
        self.n_balls = world.n_balls
        self.lock_ids = np.asarray(world.lock_ids, dtype=np.int64)
        # The locks' element ids run on from one another (World.lock_ids).
        self._locks = (
            (int(self.lock_ids[0]), int(self.lock_ids[-1]) + 1) if len(self.lock_ids) else (0, 0)
        )
        assert table.plunger is not None and table.trough is not None  # (a table of several balls)
        self.plunger = np.asarray(table.plunger.position, dtype=np.float64)
        auto = table.trough.auto_plunger
        self.auto_speed = auto.speed if auto is not None else table.plunger.speed
        self.lane_clear = LANE_CLEAR * table.ball.radius
        self.search_frames = ball_search_frames(table)
        self.radius2 = table.ball.radius * table.ball.radius
        n = world.n_envs
        # The game's ball as last written here: what the loop changes is written back.
        self._proxy = np.zeros((n, world.state.balls.shape[2]))
        self._proxy_active = np.zeros(n, dtype=bool)
        self._was_active = np.zeros((n, self.n_balls), dtype=bool)
        # The slot whose ball search clock is the loop's (GameState.anchor, still_frames): the
        # game's ball in play, -1 none (see sync).
        self._watching = np.full(n, -1, dtype=np.int64)
        # after_frames's numbers: the lock ids, those of the locks' element ids, the ball search's,
        # and where the game's ball waits for a queued one (sync).
        lane_y = float(self.plunger[1] + self.lane_clear)
        self._constants = (self.lock_ids, *self._locks, self.radius2, self.search_frames,
                           float(self.plunger[0]), lane_y)  # fmt: skip
        self._after: Callable[..., None] | None = None  # after_frames' compiled entry

    # --- the balls -----------------------------------------------------------------------

    def locked(self, env: int | slice) -> np.ndarray:
        """(M,) bool: env ``env``'s balls held in a lock (or (N, M), of ``slice(None)``)."""
        world = self.world
        first, end = self._locks
        holder = world.holder[env]
        return world.held[env] & (holder >= first) & (holder < end)

    def playing(self, env: int) -> np.ndarray:
        """(M,) bool: env ``env``'s balls in play (on the table, not held in a lock)."""
        return self.world.active[env] & ~self.locked(env)

    def in_trough(self, env: int) -> np.ndarray:
        """(M,) bool: env ``env``'s balls in the trough (neither in play nor held, nor waiting
        on the player's plunger)."""
        world, state = self.world, self.state
        free = ~world.active[env] & ~world.held[env]
        slot = state.ball_slot[env]
        if state.on_plunger[env] and slot >= 0:
            free[slot] = False
        return free

    def launch_slot(self, env: int) -> int:
        """The slot a launch of env ``env`` fires: the game's ball where it is in play or waits
        on the plunger (a plunge, a ball search), else the trough's first."""
        world, state = self.world, self.state
        slot = int(state.ball_slot[env])
        if slot >= 0 and (state.on_plunger[env] or world.active[env, slot]):
            return slot
        free = np.flatnonzero(self.in_trough(env))
        return int(free[0]) if len(free) else 0

    def new_game(self, env: int) -> None:
        """Every ball of env ``env`` back in the trough."""
        world = self.world
        world.active[env] = False
        for ball in range(self.n_balls):
            world._free(env, ball)
            world.released_from[env, ball] = -1
        world.balls[env] = 0.0
        self.state.ball_slot[env] = -1
        self._watching[env] = -1

    def place(self, env: int, slot: int, velocity: tuple[float, float], active: bool) -> None:
        """Ball ``slot`` of env ``env`` at the plunger with ``velocity``; in play or (not
        ``active``) waiting there; it is the game's ball."""
        world, state = self.world, self.state
        world.place_ball(env, tuple(self.plunger), velocity, ball=slot)
        world.active[env, slot] = active
        state.ball_slot[env] = slot
        # It has moved: its ball search starts again (the loop's clock is the game's ball's).
        state.ball_anchor[env, slot] = state.anchor[env] = self.plunger
        state.ball_still[env, slot] = state.still_frames[env] = 0

    # --- around the loop -----------------------------------------------------------------

    def write_back(self) -> None:
        """Carry the loop's writes to the game's ball into its slot: a ball put on the player's
        plunger (the next ball: a trough ball; a ball caught in the shooter lane: its own),
        a ball given up (a tilt), a ball moved."""
        state, world = self.state, self.world
        proxy, active = state.game_ball, state.game_ball_active
        for env in written(proxy, active, self._memory()):
            slot = int(state.ball_slot[env])
            if state.on_plunger[env] and not active[env]:
                own = slot >= 0 and world.active[env, slot] and not world.held[env, slot]
                if not own:
                    free = np.flatnonzero(~world.active[env] & ~world.held[env])
                    slot = int(free[0]) if len(free) else 0
                world.place_ball(env, (proxy[env, BALL_X], proxy[env, BALL_Y]), ball=slot)
                world.active[env, slot] = False
                state.ball_slot[env] = slot
                self._watching[env] = -1
            elif self._proxy_active[env] and not active[env]:
                if slot >= 0 and not world.held[env, slot]:
                    world.active[env, slot] = False  # given up: back to the trough
                self._watching[env] = -1
            elif slot >= 0:
                world.balls[env, slot] = proxy[env]
            self._remember(env)

    def before_frame(self, envs: np.ndarray, rngs: Sequence[np.random.Generator]) -> None:
        """Before the physics of ``envs`` (indices): the locks the rules released let their
        balls go, and the auto-plunger launches a queued ball where the lane is clear. Only
        the envs with a lock released or a ball queued have anything to do (a few)."""
        state, world = self.state, self.world
        busy = (state.pending_balls[envs] > 0) | state.lock_release[envs].any(axis=1)
        for env in envs[busy]:
            for lock in np.flatnonzero(state.lock_release[env]):
                world.release_lock(int(env), int(lock))
            state.lock_release[env] = False
            if state.pending_balls[env] > 0:
                trough = np.flatnonzero(self.in_trough(env))
                if len(trough) == 0:
                    state.pending_balls[env] = 0  # the trough is empty
                elif self._lane_clear(env):
                    low, high = self.auto_speed
                    speed = float(rngs[env].uniform(low, high))
                    world.place_ball(int(env), tuple(self.plunger), (0.0, speed),
                                     ball=int(trough[0]))  # fmt: skip
                    state.pending_balls[env] -= 1
        self._was_active[envs] = world.active[envs]

    def after_frame(self, envs: np.ndarray) -> None:
        """After the physics of the envs that ``envs`` (N,) bool marks: drains (back to the
        trough; saved by a running ``ball_save``), the ball search of the other balls, a lock
        that took the only ball in play (a ball served), the multiball's start and end, and the
        game's ball; every env in one compiled pass (:func:`after_frames`: nothing here draws
        from an env's random stream)."""
        args = (self.state, self._memory(), np.ascontiguousarray(envs, dtype=np.bool_),
                *self._constants)  # fmt: skip
        if self._after is None:
            nothing = np.zeros(self.world.n_envs, dtype=np.bool_)
            self._after = compiled_entry(after_frames, (*args[:2], nothing, *args[3:]))
        self._after(*args)

    def sync(self, env: int, drained: np.ndarray | None = None) -> None:
        """Make env ``env``'s game's ball the first in play (or the ball on the player's
        plunger; or, with a ball queued, a place in the lane just above the plunger, at rest;
        or out of play, where the last ball drained: ``drained`` (M,) bool). The loop's ball
        search clock goes with the game's ball: the last one's is kept in its slot
        (``GameState.ball_anchor``, ``ball_still``), the new one's taken from there
        (:func:`sync_ball`)."""
        first = -1 if drained is None or not drained.any() else int(np.flatnonzero(drained)[0])
        sync_ball(self.state, self._memory(), env, first, *self._locks,
                  *self._constants[-2:])  # fmt: skip

    def sync_envs(self, envs: np.ndarray) -> None:
        """:meth:`sync` of each of ``envs`` (indices; none drained), in one compiled call."""
        envs = np.ascontiguousarray(envs, dtype=np.int64)
        sync_balls(self.state, self._memory(), envs, *self._locks,
                   *self._constants[-2:])  # fmt: skip

    def _memory(self) -> "Memory":
        return Memory(self._proxy, self._proxy_active, self._was_active, self._watching)

    def __getstate__(self) -> dict:
        state = self.__dict__.copy()
        state["_after"] = None  # a compiled entry cannot be pickled; a copy finds its own
        return state

    def _remember(self, env: int) -> None:
        self._proxy[env] = self.state.game_ball[env]
        self._proxy_active[env] = self.state.game_ball_active[env]

    def remember_all(self) -> None:
        """Take the game's balls as they are (after a restore): the game's ball is watched by
        the loop where it is the ball in play that the loop's ball is."""
        state, world = self.state, self.world
        for env in range(self.world.n_envs):
            self._remember(env)
            slot = int(state.ball_slot[env])
            proxy = state.game_ball[env]
            same = slot >= 0 and (proxy == world.balls[env, slot]).all()
            watched = same and state.game_ball_active[env] and self.playing(env)[slot]
            self._watching[env] = slot if watched else -1

    def _lane_clear(self, env: int) -> bool:
        world, state = self.world, self.state
        if state.on_plunger[env]:
            return False
        xy = world.balls[env][:, [BALL_X, BALL_Y]]
        near = np.hypot(*(xy - self.plunger).T) < self.lane_clear
        return not (near & world.active[env]).any()


@njit(cache=True, inline="always")
def search_balls(env, balls, active, held, holder, first, end, anchor, still, game_ball, r2,
                 frames):  # fmt: skip
    """The ball search of env ``env``'s balls (``balls`` (N, M, 5), ``active``, ``held``,
    ``holder`` (N, M); its locks' element ids ``first`` to ``end``) but ``game_ball`` (the
    loop's; -1: none): each ball in play and free (not held) that is within ``sqrt(r2)`` of its
    ``anchor`` (N, M, 2) counts a frame more in ``still`` (N, M), else its anchor is where it
    is; one that has counted ``frames`` goes back to the trough (``active`` cleared). Returns
    the balls sent back and the balls in play (not locked) left, the game's ball included.
    (Whole arrays and an env, not the env's rows: a row taken out costs a reference count.)"""
    stuck = playing = 0
    for ball in range(balls.shape[1]):
        in_play = active[env, ball] and not _locked(held[env, ball], holder[env, ball], first, end)
        x, y = balls[env, ball, BALL_X], balls[env, ball, BALL_Y]
        if ball == game_ball:
            playing += in_play
            continue
        dx, dy = x - anchor[env, ball, 0], y - anchor[env, ball, 1]
        if not in_play or held[env, ball] or dx * dx + dy * dy > r2:
            anchor[env, ball, 0], anchor[env, ball, 1] = x, y
            still[env, ball] = 0
        else:
            still[env, ball] += 1
            if still[env, ball] >= frames:
                active[env, ball] = False
                still[env, ball] = 0
                stuck += 1
                in_play = False
        playing += in_play
    return stuck, playing


@njit(cache=True, inline="always")
def _locked(held, holder, first, end):
    """A ball held (``held``) by ``holder``, an element id from ``first`` to ``end`` (a lock)."""
    return held and first <= holder < end


@njit(cache=True, inline="always")
def _copy_row(proxy, balls, env, slot):
    """``proxy[env] = balls[env, slot]``, column by column (a row copy allocates)."""
    for column in range(proxy.shape[1]):
        proxy[env, column] = balls[env, slot, column]


@njit(cache=True)
def sync_ball(state, memory, env, drained, first, end, plunger_x, lane_y):
    """:meth:`Multiball.sync` of env ``env`` (``drained``: the first slot that drained in the
    frame, -1: none; ``first``, ``end``: the locks' element ids; ``plunger_x``, ``lane_y``:
    where the game's ball waits for a queued one), compiled."""
    world = state.world
    active, held, holder, balls = world.active, world.held, state.holders.holder, world.balls
    proxy, proxy_active = state.game_ball, state.game_ball_active
    slot = state.ball_slot[env]
    watched = memory.watching[env]
    if (
        watched >= 0
        and active[env, watched]
        and not _locked(held[env, watched], holder[env, watched], first, end)
    ):
        state.ball_anchor[env, watched, 0] = state.anchor[env, 0]
        state.ball_anchor[env, watched, 1] = state.anchor[env, 1]
        state.ball_still[env, watched] = state.still_frames[env]
    memory.watching[env] = -1
    playing = -1  # the first ball in play
    for ball in range(active.shape[1]):
        if active[env, ball] and not _locked(held[env, ball], holder[env, ball], first, end):
            playing = ball
            break
    if state.on_plunger[env] and slot >= 0 and not active[env, slot]:
        _copy_row(proxy, balls, env, slot)
        proxy_active[env] = False
    elif playing >= 0:
        state.ball_slot[env] = playing
        _copy_row(proxy, balls, env, playing)
        proxy_active[env] = True
        state.anchor[env, 0] = state.ball_anchor[env, playing, 0]
        state.anchor[env, 1] = state.ball_anchor[env, playing, 1]
        state.still_frames[env] = state.ball_still[env, playing]
        memory.watching[env] = playing
    elif state.pending_balls[env] > 0:  # in the lane, above the plunger (not waiting on it)
        proxy[env, :] = 0.0
        proxy[env, BALL_X] = plunger_x
        proxy[env, BALL_Y] = lane_y
        proxy_active[env] = True
    else:
        if drained >= 0:
            slot = drained
            state.ball_slot[env] = slot
        if slot >= 0:
            _copy_row(proxy, balls, env, slot)
        proxy_active[env] = False
    for column in range(proxy.shape[1]):
        memory.proxy[env, column] = proxy[env, column]
    memory.proxy_active[env] = proxy_active[env]


@njit(cache=True)
def written(proxy, active, memory):
    """The envs (indices) whose game's ball (``proxy``, ``active``) the loop changed since it
    was last written here (``memory``): a few a frame, which :meth:`Multiball.write_back`
    carries over in Python."""
    envs = np.empty(len(active), dtype=np.int64)
    n = 0
    for env in range(len(active)):
        same = active[env] == memory.proxy_active[env]
        for column in range(proxy.shape[1]):
            same &= proxy[env, column] == memory.proxy[env, column]  # NaN: changed
        if not same:
            envs[n] = env
            n += 1
    return envs[:n]


@njit(cache=True)
def sync_balls(state, memory, envs, first, end, plunger_x, lane_y):
    """:func:`sync_ball` of each of ``envs`` (none drained): one dispatch for a batch."""
    for env in envs:
        sync_ball(state, memory, env, -1, first, end, plunger_x, lane_y)


# Without reference counting (``_nrt=False``, as ``game.play.play_frames``): it allocates nothing,
# and counting the references of every array taken out of ``state`` cost it half its time.
@njit(cache=True, _nrt=False)  # type: ignore[call-overload]  # _nrt: not in the stubs
def after_frames(state, memory, stepped, lock_ids, first, end, r2, frames, plunger_x, lane_y):
    """:meth:`Multiball.after_frame` of every env that ``stepped`` marks, in one compiled
    pass (module docstring): ``memory.was_active`` holds the balls in play before the frame's
    physics; ``lock_ids`` the locks' element ids (``first`` to ``end``); ``r2``, ``frames``:
    the ball search's squared radius and wait; ``plunger_x``, ``lane_y``: see
    :func:`sync_ball`."""
    world = state.world
    active, held, holder = world.active, world.held, state.holders.holder
    hits, pending, save = world.hits, state.pending_balls, state.multiball_save
    n_balls = active.shape[1]
    for env in range(len(stepped)):
        if not stepped[env]:
            continue
        state.multiball_events[env, :] = 0
        tilted = world.tilted[env]
        if tilted:  # no ball is served or let go until the tilt is over
            pending[env] = 0
            save[env] = 0
            state.lock_release[env, :] = False
        n_drained = 0
        drained = -1  # the first ball that drained
        for ball in range(n_balls):
            if memory.was_active[env, ball] and not active[env, ball]:
                n_drained += 1
                if drained < 0:
                    drained = ball
        if n_drained and save[env] > 0:
            pending[env] += n_drained
        if save[env] > 0:
            save[env] -= 1
        # The ball search of the balls but the game's (the loop's).
        game_ball = memory.watching[env]
        stuck, playing = search_balls(
            env, world.balls, active, held, holder, first, end, state.ball_anchor,
            state.ball_still, game_ball, r2, frames,
        )  # fmt: skip
        if stuck and not tilted:
            pending[env] += stuck  # served again
        if (
            tilted
            and game_ball >= 0
            and playing > 1
            and not held[env, game_ball]
            and state.still_frames[env] >= frames
        ):
            active[env, game_ball] = False  # given up; another is the game's ball
        in_play = pending[env]
        trough = False
        for ball in range(n_balls):
            if active[env, ball] and not _locked(held[env, ball], holder[env, ball], first, end):
                in_play += 1
            trough |= not active[env, ball] and not held[env, ball]
        took = 0
        for k in range(len(lock_ids)):
            took += hits[env, lock_ids[k]]
        if took > 0 and in_play == 0 and not (n_drained or state.on_plunger[env] or tilted):
            # A lock took the only ball in play: serve one (or, none left, let them go). (Not
            # on the plunger: every ball neither in play nor held is in the trough.)
            if trough:
                pending[env] += 1
            else:
                state.lock_release[env, :] = True
            in_play = 1
        if not state.multiball[env] and in_play >= 2:
            state.multiball[env] = True
            state.multiball_events[env, 0] = 1
            state.multiballs[env] += 1
        elif state.multiball[env] and in_play <= 1:
            state.multiball[env] = False
            state.multiball_events[env, 1] = 1
        sync_ball(state, memory, env, drained, first, end, plunger_x, lane_y)


__all__ = ["LANE_CLEAR", "Multiball"]
