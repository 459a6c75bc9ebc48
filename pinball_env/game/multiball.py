"""The game's several balls: the trough, drains, locks and the auto-plunger, for a
table whose trough holds more than one ball.

The choice: such a table's frames are played in the same compiled step loop as one ball's
(``game.play``), env by env in its threads: before each frame's physics the game's ball is
written back, the released locks let go and the auto-plunger's queue seen to; then the
several-ball kernel, the saucers and locks, and after them the drains, the ball search of the
other balls, the multiball's start and end and the game's ball picked again
(``game.multiball_passes``, one body per env). Everything the loop does for one ball (the
buttons, the cabinet, the rules, the ball save, the end-of-ball bonus, the ball search, the
reward) it does for several too, on **the game's ball**: ``state.game_ball`` (N, 5) and
``state.game_ball_active`` (N,) hold the first ball in play (the lowest slot,
``GameState.ball_slot``) and whether any ball is in play. The loop's own writes to it (a ball
put on the player's plunger, a tilted ball given up) are written back to its slot
(:meth:`Multiball.write_back`) before anything else acts on the balls.

Python keeps what draws from an env's random stream, for the envs that have it: a queued ball's
launch (the loop hands the env back, ``StepProgress.serve``: :meth:`Multiball.serve`), the
player's and the machine's launches and serves (``Game.launch_balls``; their game's balls synced
in one call), a new game. Another physics backend or the ``on_frame`` hook take each frame's
physics to Python (``World.step``) with the same passes over every env (:meth:`before_frame`,
:meth:`after_frame`). The first version (per-env Python every frame, kept as the reference of
``tests/game/test_multiball_compiled.py``) ran Pinball-v3's native vector env of 1024 envs about
9x slower than the second (the passes compiled over every env, each frame's physics handed to
Python); the loop's own frames save that hand-back and its single-threaded passes, a small
share of a frame: what bounds v3 now is the several-ball kernel itself (docs/speed.md).

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

import numpy as np

from pinball_env.game.multiball_passes import (
    Memory,
    MultiballParameters,
    after_frames,
    before_frames,
    sync_ball,
    sync_balls,
    write_back_balls,
)
from pinball_env.game.parameters import ball_search_frames
from pinball_env.game.state import GameState
from pinball_env.sim.world import World, compiled_entry
from pinball_env.table import Table

# The shooter lane is clear for the auto-plunger when no ball is within this many ball radii of
# the plunger's position.
LANE_CLEAR = 3.0


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
        self.memory = Memory(self._proxy, self._proxy_active, self._was_active, self._watching)
        self.parameters = multiball_parameters(self, world, table)
        self._entries: dict[str, Callable[..., None]] = {}  # the passes' compiled entries

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
        """Carry the loop's writes to the game's ball into its slot, in every env (a few a
        frame have any): a ball put on the player's plunger (the next ball: a trough ball; a
        ball caught in the shooter lane: its own), a ball given up (a tilt), a ball moved."""
        self._run("write_back", write_back_balls, self.state, self.memory)

    def before_frame(self, envs: np.ndarray, rngs: Sequence[np.random.Generator]) -> None:
        """Before the physics of ``envs`` (indices): the game's ball written back, the locks
        the rules released let their balls go, and the auto-plunger launches a queued ball
        where the lane is clear (its speed drawn from the env's stream: :meth:`serve`)."""
        stepped = np.zeros(self.world.n_envs, dtype=np.bool_)
        stepped[envs] = True
        due = np.zeros_like(stepped)
        args = (self.state, self.memory, self.parameters, stepped, due)
        self._run("before", before_frames, *args)
        if due.any():
            self.serve(np.flatnonzero(due), rngs)
            self._run("before", before_frames, *args)  # the rest (it does nothing twice)

    def serve(self, envs: np.ndarray, rngs: Sequence[np.random.Generator]) -> None:
        """The auto-plunger launches the first trough ball of each of ``envs`` (the lane is
        clear, a ball queued), at a speed drawn from the env's stream."""
        low, high = self.auto_speed
        for env in envs:
            trough = int(np.flatnonzero(self.in_trough(env))[0])
            speed = float(rngs[env].uniform(low, high))
            self.world.place_ball(int(env), tuple(self.plunger), (0.0, speed), ball=trough)
            self.state.pending_balls[env] -= 1

    def after_frame(self, envs: np.ndarray) -> None:
        """After the physics of the envs that ``envs`` (N,) bool marks: drains (back to the
        trough; saved by a running ``ball_save``), the ball search of the other balls, a lock
        that took the only ball in play (a ball served), the multiball's start and end, and the
        game's ball; every env in one compiled pass (``multiball_passes.after_frames``:
        nothing there draws from an env's random stream)."""
        stepped = np.ascontiguousarray(envs, dtype=np.bool_)
        self._run("after", after_frames, self.state, self.memory, self.parameters, stepped)

    def _run(self, name: str, function: Callable[..., None], *args: object) -> None:
        """Call compiled ``function`` through its compiled entry (``compiled_entry``), found
        once: the passes run every frame, and numba's dispatch would cost more than they do."""
        entry = self._entries.get(name)
        if entry is None:
            entry = self._entries[name] = compiled_entry(function, args)
        else:
            entry(*args)

    def sync(self, env: int, drained: np.ndarray | None = None) -> None:
        """Make env ``env``'s game's ball the first in play (or the ball on the player's
        plunger; or, with a ball queued, a place in the lane just above the plunger, at rest;
        or out of play, where the last ball drained: ``drained`` (M,) bool). The loop's ball
        search clock goes with the game's ball: the last one's is kept in its slot
        (``GameState.ball_anchor``, ``ball_still``), the new one's taken from there
        (:func:`sync_ball`)."""
        first = -1 if drained is None or not drained.any() else int(np.flatnonzero(drained)[0])
        p = self.parameters
        sync_ball(self.state, self.memory, env, first, p.locks_first, p.locks_end, p.plunger_x,
                  p.lane_y)  # fmt: skip

    def sync_envs(self, envs: np.ndarray) -> None:
        """:meth:`sync` of each of ``envs`` (indices; none drained), in one compiled call."""
        envs = np.ascontiguousarray(envs, dtype=np.int64)
        p = self.parameters
        sync_balls(self.state, self.memory, envs, p.locks_first, p.locks_end, p.plunger_x,
                   p.lane_y)  # fmt: skip

    def __getstate__(self) -> dict:
        state = self.__dict__.copy()
        state["_entries"] = {}  # compiled entries cannot be pickled; a copy finds its own
        return state

    def remember(self, env: int) -> None:
        """Take env ``env``'s balls as they are (after a restore): the game's ball is watched by
        the loop where it is the ball in play that the loop's ball is."""
        state, world = self.state, self.world
        self._proxy[env] = state.game_ball[env]
        self._proxy_active[env] = state.game_ball_active[env]
        slot = int(state.ball_slot[env])
        proxy = state.game_ball[env]
        same = slot >= 0 and (proxy == world.balls[env, slot]).all()
        watched = same and state.game_ball_active[env] and self.playing(env)[slot]
        self._watching[env] = slot if watched else -1

    def remember_all(self) -> None:
        """:meth:`remember` of every env."""
        for env in range(self.world.n_envs):
            self.remember(env)


def multiball_parameters(multi: Multiball, world: World, table: Table) -> MultiballParameters:
    """What the compiled passes of ``multi`` play by (``multiball_passes``), with the holders'
    work arrays, one row per env."""
    first, end = multi._locks
    holders = world.holders
    n, m, s = world.n_envs, world.n_balls, holders.lock_slots.shape[1]
    return MultiballParameters(
        lock_ids=multi.lock_ids,
        locks_first=first,
        locks_end=end,
        radius2=multi.radius2,
        search_frames=multi.search_frames,
        plunger_x=float(multi.plunger[0]),
        plunger_y=float(multi.plunger[1]),
        lane_y=float(multi.plunger[1] + multi.lane_clear),
        lane_clear=multi.lane_clear,
        pair=world.pair,
        holders=holders,
        dt=world.settings.dt,
        work_xy=np.zeros((n, m, 2)),
        work_speed=np.zeros((n, m)),
        work_free=np.zeros((n, m), dtype=np.bool_),
        work_taken=np.zeros((n, s), dtype=np.bool_),
        work_gaps=np.zeros((n, m, s)),
    )


__all__ = ["LANE_CLEAR", "Memory", "Multiball"]
