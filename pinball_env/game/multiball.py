"""The game's several balls: the trough, drains, locks and the auto-plunger, for a
table whose trough holds more than one ball.

The choice: such a table's frames are stepped by Python, frame by frame (the World's several-ball
kernel, ``World.swept_kernel`` False), inside the same compiled step loop
(``game.play.play_frames``), which hands each frame's physics back to ``Game._play_frames``;
this module acts around that physics. Simplest correct first: everything the loop does for
one ball (the buttons, the cabinet, the rules, the ball save, the end-of-ball bonus, the ball
search, the reward) it does here too, on **the game's ball**: ``state.world.balls`` (N, 5) and
``state.world.active`` (N,), which the several-ball kernel does not use, hold the first ball
in play (the lowest slot, ``GameState.ball_slot``) and whether any ball is in play. The loop's
own writes to it (a ball put on the player's plunger, a tilted ball given up) are written back
to its slot (:meth:`Multiball.write_back`) before Python does anything else.

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

from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np
from numba import njit

from pinball_env.game.parameters import ball_search_frames
from pinball_env.physics.columns import BALL_X, BALL_Y

if TYPE_CHECKING:
    from pinball_env.game.game import Game

# The shooter lane is clear for the auto-plunger when no ball is within this many ball radii of
# the plunger's position.
LANE_CLEAR = 3.0


class Multiball:
    """The several balls of ``game``'s envs (module docstring): what Python does around each
    frame's physics."""

    def __init__(self, game: "Game") -> None:
        self.game = game
        world = game.world
        table = game.table
        self.n_balls = world.n_balls
        self.lock_ids = np.asarray(world.lock_ids, dtype=np.int64)
        # The locks' element ids run on from one another (World.lock_ids).
        self._locks = (
            (int(self.lock_ids[0]), int(self.lock_ids[-1]) + 1) if len(self.lock_ids) else (0, 0)
        )
        self.plunger = np.asarray(table.plunger.position, dtype=np.float64)
        auto = table.trough.auto_plunger
        self.auto_speed = auto.speed if auto is not None else table.plunger.speed
        self.lane_clear = LANE_CLEAR * table.ball.radius
        self.search_frames = ball_search_frames(table)
        self.radius2 = table.ball.radius * table.ball.radius
        n = world.n_envs
        # The game's ball as last written here: what the loop changes is written back.
        self._proxy = np.zeros((n, world.state.balls.shape[1]))
        self._proxy_active = np.zeros(n, dtype=bool)
        self._was_active = np.zeros((n, self.n_balls), dtype=bool)
        # The slot whose ball search clock is the loop's (GameState.anchor, still_frames): the
        # game's ball in play, -1 none (see sync).
        self._watching = np.full(n, -1, dtype=np.int64)

    # --- the balls -----------------------------------------------------------------------

    def locked(self, env: int | slice) -> np.ndarray:
        """(M,) bool: env ``env``'s balls held in a lock (or (N, M), of ``slice(None)``)."""
        world = self.game.world
        first, end = self._locks
        holder = world.holder[env]
        return world.ball_held[env] & (holder >= first) & (holder < end)

    def playing(self, env: int) -> np.ndarray:
        """(M,) bool: env ``env``'s balls in play (on the table, not held in a lock)."""
        return self.game.world.ball_active[env] & ~self.locked(env)

    def in_trough(self, env: int) -> np.ndarray:
        """(M,) bool: env ``env``'s balls in the trough (neither in play nor held, nor waiting
        on the player's plunger)."""
        world, state = self.game.world, self.game.state
        free = ~world.ball_active[env] & ~world.ball_held[env]
        slot = state.ball_slot[env]
        if state.on_plunger[env] and slot >= 0:
            free[slot] = False
        return free

    def launch_slot(self, env: int) -> int:
        """The slot a launch of env ``env`` fires: the game's ball where it is in play or waits
        on the plunger (a plunge, a ball search), else the trough's first."""
        world, state = self.game.world, self.game.state
        slot = int(state.ball_slot[env])
        if slot >= 0 and (state.on_plunger[env] or world.ball_active[env, slot]):
            return slot
        free = np.flatnonzero(self.in_trough(env))
        return int(free[0]) if len(free) else 0

    def new_game(self, env: int) -> None:
        """Every ball of env ``env`` back in the trough."""
        world = self.game.world
        world.ball_active[env] = False
        for ball in range(self.n_balls):
            world._free(env, ball)
            world.released_from[env, ball] = -1
        world.ball_states[env] = 0.0
        self.game.state.ball_slot[env] = -1
        self._watching[env] = -1

    def place(self, env: int, slot: int, velocity: tuple[float, float], active: bool) -> None:
        """Ball ``slot`` of env ``env`` at the plunger with ``velocity``; in play or (not
        ``active``) waiting there; it is the game's ball."""
        world, state = self.game.world, self.game.state
        world.place_ball(env, tuple(self.plunger), velocity, ball=slot)
        world.ball_active[env, slot] = active
        state.ball_slot[env] = slot
        # It has moved: its ball search starts again (the loop's clock is the game's ball's).
        state.ball_anchor[env, slot] = state.anchor[env] = self.plunger
        state.ball_still[env, slot] = state.still_frames[env] = 0

    # --- around the loop -----------------------------------------------------------------

    def write_back(self) -> None:
        """Carry the loop's writes to the game's ball into its slot: a ball put on the player's
        plunger (the next ball: a trough ball; a ball caught in the shooter lane: its own),
        a ball given up (a tilt), a ball moved."""
        state, world = self.game.state, self.game.world
        proxy, active = state.world.balls, state.world.active
        changed = (proxy != self._proxy).any(axis=1) | (active != self._proxy_active)
        for env in np.flatnonzero(changed):
            slot = int(state.ball_slot[env])
            if state.on_plunger[env] and not active[env]:
                own = slot >= 0 and world.ball_active[env, slot] and not world.ball_held[env, slot]
                if not own:
                    free = np.flatnonzero(~world.ball_active[env] & ~world.ball_held[env])
                    slot = int(free[0]) if len(free) else 0
                world.place_ball(env, (proxy[env, BALL_X], proxy[env, BALL_Y]), ball=slot)
                world.ball_active[env, slot] = False
                state.ball_slot[env] = slot
                self._watching[env] = -1
            elif self._proxy_active[env] and not active[env]:
                if slot >= 0 and not world.ball_held[env, slot]:
                    world.ball_active[env, slot] = False  # given up: back to the trough
                self._watching[env] = -1
            elif slot >= 0:
                world.ball_states[env, slot] = proxy[env]
            self._remember(env)

    def before_frame(self, envs: np.ndarray, rngs: Sequence[np.random.Generator]) -> None:
        """Before the physics of ``envs`` (indices): the locks the rules released let their
        balls go, and the auto-plunger launches a queued ball where the lane is clear."""
        state, world = self.game.state, self.game.world
        for env in envs:
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
        self._was_active[envs] = world.ball_active[envs]

    def after_frame(self, envs: np.ndarray) -> None:
        """After the physics of ``envs``: drains (back to the trough; saved by a running
        ``ball_save``), a lock that took the only ball in play (a ball served), the multiball's
        start and end, and the game's ball."""
        state, world = self.game.state, self.game.world
        hits = world.state.hits
        for env in envs:
            state.multiball_events[env] = 0
            tilted = bool(state.world.tilted[env])
            if tilted:  # no ball is served or let go until the tilt is over
                state.pending_balls[env] = 0
                state.multiball_save[env] = 0
                state.lock_release[env] = False
            drained = self._was_active[env] & ~world.ball_active[env]
            n_drained = int(drained.sum())
            if n_drained and state.multiball_save[env] > 0:
                state.pending_balls[env] += n_drained
            if state.multiball_save[env] > 0:
                state.multiball_save[env] -= 1
            self._search(env, tilted)
            playing = self.playing(env)
            in_play = int(playing.sum()) + int(state.pending_balls[env])
            took = len(self.lock_ids) and hits[env, self.lock_ids].sum() > 0
            if took and in_play == 0 and not (n_drained or state.on_plunger[env] or tilted):
                # A lock took the only ball in play: serve one (or, none left, let them go).
                if self.in_trough(env).any():
                    state.pending_balls[env] += 1
                else:
                    state.lock_release[env] = True
                in_play = 1
            if not state.multiball[env] and in_play >= 2:
                state.multiball[env] = True
                state.multiball_events[env, 0] = 1
                state.multiballs[env] += 1
            elif state.multiball[env] and in_play <= 1:
                state.multiball[env] = False
                state.multiball_events[env, 1] = 1
            self.sync(env, drained)

    def _search(self, env: int, tilted: bool) -> None:
        """The ball search of env ``env``'s balls in play but the game's ball (the loop's),
        after a frame's physics (module docstring): a ball that has not moved a radius in
        ``search_frames`` goes back to the trough, queued for the auto-plunger unless
        ``tilted``; tilted, the game's ball too once it has lain still as long (where another
        ball is in play; the last, the loop gives up)."""
        state, world = self.game.state, self.game.world
        game_ball = int(self._watching[env])
        first, end = self._locks
        stuck, playing = search_balls(
            world.ball_states[env], world.ball_active[env], world.ball_held[env],
            world.holder[env], first, end, state.ball_anchor[env], state.ball_still[env],
            game_ball, self.radius2, self.search_frames,
        )  # fmt: skip
        if stuck and not tilted:
            state.pending_balls[env] += stuck  # served again
        if (
            tilted
            and game_ball >= 0
            and playing > 1
            and not world.ball_held[env, game_ball]
            and state.still_frames[env] >= self.search_frames
        ):
            world.ball_active[env, game_ball] = False  # given up; another is the game's ball

    def sync(self, env: int, drained: np.ndarray | None = None) -> None:
        """Make env ``env``'s game's ball the first in play (or the ball on the player's
        plunger; or, with a ball queued, a place in the lane just above the plunger, at rest;
        or out of play, where the last ball drained: ``drained`` (M,) bool). The loop's ball
        search clock goes with the game's ball: the last one's is kept in its slot
        (``GameState.ball_anchor``, ``ball_still``), the new one's taken from there."""
        state, world = self.game.state, self.game.world
        proxy = state.world.balls[env]
        slot = int(state.ball_slot[env])
        playing = self.playing(env)
        watched = int(self._watching[env])
        if watched >= 0 and playing[watched]:
            state.ball_anchor[env, watched] = state.anchor[env]
            state.ball_still[env, watched] = state.still_frames[env]
        self._watching[env] = -1
        if state.on_plunger[env] and slot >= 0 and not world.ball_active[env, slot]:
            proxy[:] = world.ball_states[env, slot]
            state.world.active[env] = False
        elif playing.any():
            slot = int(np.flatnonzero(playing)[0])
            state.ball_slot[env] = slot
            proxy[:] = world.ball_states[env, slot]
            state.world.active[env] = True
            state.anchor[env] = state.ball_anchor[env, slot]
            state.still_frames[env] = state.ball_still[env, slot]
            self._watching[env] = slot
        elif state.pending_balls[env] > 0:  # in the lane, above the plunger (not waiting on it)
            proxy[:] = 0.0
            proxy[BALL_X] = self.plunger[0]
            proxy[BALL_Y] = self.plunger[1] + self.lane_clear
            state.world.active[env] = True
        else:
            if drained is not None and drained.any():
                slot = int(np.flatnonzero(drained)[0])
                state.ball_slot[env] = slot
            if slot >= 0:
                proxy[:] = world.ball_states[env, slot]
            state.world.active[env] = False
        self._remember(env)

    def _remember(self, env: int) -> None:
        self._proxy[env] = self.game.state.world.balls[env]
        self._proxy_active[env] = self.game.state.world.active[env]

    def remember_all(self) -> None:
        """Take the game's balls as they are (after a restore): the game's ball is watched by
        the loop where it is the ball in play that the loop's ball is."""
        state, world = self.game.state, self.game.world
        for env in range(self.game.n_envs):
            self._remember(env)
            slot = int(state.ball_slot[env])
            proxy = state.world.balls[env]
            same = slot >= 0 and (proxy == world.ball_states[env, slot]).all()
            watched = same and state.world.active[env] and self.playing(env)[slot]
            self._watching[env] = slot if watched else -1

    def _lane_clear(self, env: int) -> bool:
        world, state = self.game.world, self.game.state
        if state.on_plunger[env]:
            return False
        xy = world.ball_states[env][:, [BALL_X, BALL_Y]]
        near = np.hypot(*(xy - self.plunger).T) < self.lane_clear
        return not (near & world.ball_active[env]).any()


@njit(cache=True)
def search_balls(balls, active, held, holder, first, end, anchor, still, game_ball, r2, frames):
    """The ball search of one env's balls (``balls`` (M, 5), ``active``, ``held``, ``holder``
    (M,); its locks' element ids ``first`` to ``end``) but ``game_ball`` (the loop's; -1:
    none): each ball in play and free (not held) that is within ``sqrt(r2)`` of its ``anchor``
    (M, 2) counts a frame more in ``still`` (M,), else its anchor is where it is; one that has
    counted ``frames`` goes back to the trough (``active`` cleared). Returns the balls sent back
    and the balls in play (not locked) left, the game's ball included."""
    stuck = playing = 0
    for ball in range(balls.shape[0]):
        locked = held[ball] and first <= holder[ball] < end
        in_play = active[ball] and not locked
        x, y = balls[ball, BALL_X], balls[ball, BALL_Y]
        if ball == game_ball:
            playing += in_play
            continue
        dx, dy = x - anchor[ball, 0], y - anchor[ball, 1]
        if not in_play or held[ball] or dx * dx + dy * dy > r2:
            anchor[ball, 0], anchor[ball, 1] = x, y
            still[ball] = 0
        else:
            still[ball] += 1
            if still[ball] >= frames:
                active[ball] = False
                still[ball] = 0
                stuck += 1
                in_play = False
        playing += in_play
    return stuck, playing


__all__ = ["LANE_CLEAR", "Multiball"]
