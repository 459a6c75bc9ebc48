"""Saucers and locks: the balls they capture, hold and let go, at the end of each frame.

A free ball in play within a saucer's ``radius`` of its centre and slower than its
``capture_speed`` is captured (held at the centre, at rest), counted as a hit of the saucer (its
element id follows the kickbacks: ``World.frame_points`` scores it) and released at its ``kick``
after ``hold_time``; a lock holds a ball that comes within ``Lock.capture_radius`` of its next
free slot (slots fill in order) slower than its ``capture_speed``, a hit of the lock, until
``World.release_lock`` lets its balls go at its ``kick``. A released ball is not captured again by
the same saucer or lock until it has left its capture radius. A ball is taken only where it
fits: while another ball (in play or held) lies within two radii of the centre or slot it would
be put at, it stays free (and is taken in a later frame, once there is room), so that a capture
never puts a ball onto another. The test is on the frame's end state (a ball slow enough to be
captured moves less than a centimetre a frame).

One compiled body per env (:func:`play_env_holders`), which ``World.step`` runs over every env
(:func:`play_holders`) and the game's compiled frame loop runs env by env (``game.play``).
"""

import math
from typing import NamedTuple

import numpy as np
from numba import njit

from pinball_env.physics.columns import BALL_VX, BALL_VY, BALL_X, BALL_Y
from pinball_env.physics.data import log_contact
from pinball_env.table import Table


class Holders(NamedTuple):
    """A table's saucers and locks as :func:`play_holders` reads them (the table's numbers)."""

    saucer_ids: np.ndarray  # (S,) int64: element ids
    saucer_center: np.ndarray  # (S, 2) float64 [m]
    saucer_radius: np.ndarray  # (S,) float64 [m]
    saucer_capture: np.ndarray  # (S,) float64: capture speed [m/s]
    saucer_hold: np.ndarray  # (S,) float64: hold time [s]
    saucer_kick: np.ndarray  # (S, 2) float64 [m/s]
    lock_ids: np.ndarray  # (K,) int64: element ids
    lock_slots: np.ndarray  # (K, MAX_LOCK_SLOTS, 2) float64: the slots, in fill order [m]
    lock_n_slots: np.ndarray  # (K,) int64: slots of each lock
    lock_reach: np.ndarray  # (K,) float64: capture radius [m]
    lock_capture: np.ndarray  # (K,) float64: capture speed [m/s]
    lock_kick: np.ndarray  # (K, 2) float64 [m/s]
    ball_radius: float  # [m]: a ball is taken only where no other lies within twice it


def holder_arrays(table: Table, saucer_ids: np.ndarray, lock_ids: np.ndarray) -> Holders:
    """``table``'s saucers and locks (element ids ``saucer_ids``, ``lock_ids``) as arrays."""
    saucers, locks = table.saucers, table.locks
    n_slots = max((len(lock.slots) for lock in locks), default=0)
    slots = np.zeros((len(locks), n_slots, 2))
    for k, lock in enumerate(locks):
        slots[k, : len(lock.slots)] = lock.slots
    r = table.ball.radius
    return Holders(
        saucer_ids=np.asarray(saucer_ids, dtype=np.int64),
        saucer_center=np.array([s.center for s in saucers], dtype=np.float64).reshape(-1, 2),
        saucer_radius=np.array([s.radius for s in saucers], dtype=np.float64),
        saucer_capture=np.array([s.capture_speed for s in saucers], dtype=np.float64),
        saucer_hold=np.array([s.hold_time for s in saucers], dtype=np.float64),
        saucer_kick=np.array([s.kick for s in saucers], dtype=np.float64).reshape(-1, 2),
        lock_ids=np.asarray(lock_ids, dtype=np.int64),
        lock_slots=slots,
        lock_n_slots=np.array([len(lock.slots) for lock in locks], dtype=np.int64),
        lock_reach=np.array([lock.capture_radius(r) for lock in locks], dtype=np.float64),
        lock_capture=np.array([lock.capture_speed for lock in locks], dtype=np.float64),
        lock_kick=np.array([lock.kick for lock in locks], dtype=np.float64).reshape(-1, 2),
        ball_radius=float(r),
    )


@njit(cache=True)
def place_slot(balls, active, held, holder, slot, held_time, released_from, env, ball, x, y, vx,
               vy):  # fmt: skip
    """``World.place_ball`` of a checked state: in play, free, at (x, y), (vx, vy), no spin."""
    balls[env, ball, :] = 0.0
    balls[env, ball, BALL_X], balls[env, ball, BALL_Y] = x, y
    balls[env, ball, BALL_VX], balls[env, ball, BALL_VY] = vx, vy
    active[env, ball] = True
    holder[env, ball] = slot[env, ball] = -1
    held_time[env, ball] = 0.0
    held[env, ball] = False
    released_from[env, ball] = -1


@njit(cache=True, inline="always")
def _fits(balls, active, env, ball, x, y, radius):
    """Whether env ``env``'s ball ``ball`` fits at (x, y): no other ball on the table (in play or
    held) within two radii of it."""
    for other in range(active.shape[1]):
        if other != ball and active[env, other]:
            gap = math.hypot(balls[env, other, BALL_X] - x, balls[env, other, BALL_Y] - y)
            if gap < 2.0 * radius:
                return False
    return True


@njit(cache=True)
def _capture(balls, active, held, holder, slot, held_time, released_from, state, env, ball,
             element, x, y, into, dt):  # fmt: skip
    """Hold env ``env``'s ball ``ball`` at (x, y) for ``element`` (slot ``into`` of a lock): a
    hit of it, logged at the frame's end (``World.hold_ball`` and the hit)."""
    speed = math.hypot(balls[env, ball, BALL_VX], balls[env, ball, BALL_VY])
    place_slot(balls, active, held, holder, slot, held_time, released_from, env, ball, x, y, 0.0,
               0.0)  # fmt: skip
    held[env, ball] = True
    holder[env, ball], slot[env, ball] = element, into
    state.hits[env, element] += 1
    log_contact(state, env, element, dt, speed)


@njit(cache=True)
def play_holders(balls, active, held, holder, slot, held_time, released_from, state, stepped,
                 holders, dt):  # fmt: skip
    """The saucers and locks of every env at the end of a frame (module docstring), of the
    frame's end state (``balls`` (N, M, 5) ...; ``state`` the kernel's, for the hits and the
    contact log): in envs where ``stepped`` is set, a saucer's held ball counts ``dt`` and
    leaves at the kick after its hold time, a free ball in play near a free saucer or the next
    free slot of a lock, slower than its capture speed, is captured; in every env a ball
    released from one is forgotten by it once out of its reach (:func:`play_env_holders`)."""
    n_envs, n_balls = active.shape
    xy, speed, free, taken, gaps = holder_work(n_balls, holders.lock_slots.shape[1])
    for env in range(n_envs):
        play_env_holders(balls, active, held, holder, slot, held_time, released_from, state,
                         env, stepped[env], holders, dt, xy, speed, free, taken, gaps)  # fmt: skip


@njit(cache=True)
def holder_work(n_balls, n_slots):
    """The work arrays of :func:`play_env_holders` for ``n_balls`` ball slots and locks of up to
    ``n_slots`` slots: the balls' centres (M, 2), speeds (M,) and whether each is free (M,), the
    lock slots taken (S,) and each ball's gap to each slot (M, S)."""
    return (np.empty((n_balls, 2)), np.empty(n_balls), np.empty(n_balls, dtype=np.bool_),
            np.zeros(n_slots, dtype=np.bool_), np.empty((n_balls, n_slots)))  # fmt: skip


# One body per env, as the kernel's: the saucers, then the locks, each as the Python of the first
# version did it table-wide (so the order of captures and releases is the same).
@njit(cache=True, inline="always")
def play_env_holders(balls, active, held, holder, slot, held_time, released_from, state, env,
                     go, holders, dt, xy, speed, free, taken, gaps):  # fmt: skip
    """:func:`play_holders` of env ``env`` (``go``: it was stepped), with the work arrays of
    :func:`holder_work` (the game's compiled frame passes its own, allocating nothing)."""
    h = holders
    for ball in range(active.shape[1]):  # the frame's end state, before any capture or release
        xy[ball, 0], xy[ball, 1] = balls[env, ball, BALL_X], balls[env, ball, BALL_Y]
        speed[ball] = math.hypot(balls[env, ball, BALL_VX], balls[env, ball, BALL_VY])
        free[ball] = active[env, ball] and not held[env, ball] and go
    _play_saucers(balls, active, held, holder, slot, held_time, released_from, state, env, go,
                  h, dt, xy, speed, free)  # fmt: skip
    _play_locks(balls, active, held, holder, slot, held_time, released_from, state, env, h, dt,
                xy, speed, free, taken, gaps)  # fmt: skip


@njit(cache=True, inline="always")
def _play_saucers(balls, active, held, holder, slot, held_time, released_from, state, env, go, h,
                  dt, xy, speed, free):  # fmt: skip
    """The saucers of :func:`play_env_holders`: holds counted and ended, captures."""
    n_balls = active.shape[1]
    for s in range(len(h.saucer_ids)):
        element = h.saucer_ids[s]
        cx, cy = h.saucer_center[s, 0], h.saucer_center[s, 1]
        if go:
            for ball in range(n_balls):
                if holder[env, ball] == element:
                    held_time[env, ball] += dt
            for ball in range(n_balls):
                if holder[env, ball] == element and held_time[env, ball] >= (
                    h.saucer_hold[s] - 1e-9
                ):
                    place_slot(balls, active, held, holder, slot, held_time, released_from, env,
                           ball, balls[env, ball, BALL_X], balls[env, ball, BALL_Y],
                           h.saucer_kick[s, 0], h.saucer_kick[s, 1])  # fmt: skip
                    released_from[env, ball] = element
        catch = -1
        for ball in range(n_balls):
            near = math.hypot(xy[ball, 0] - cx, xy[ball, 1] - cy) <= h.saucer_radius[s]
            if released_from[env, ball] == element and not near:
                released_from[env, ball] = -1
            if (
                catch < 0
                and free[ball]
                and near
                and speed[ball] < h.saucer_capture[s]
                and released_from[env, ball] != element
            ):
                catch = ball
        if catch >= 0:
            busy = False  # one ball at a time
            for ball in range(n_balls):
                busy |= holder[env, ball] == element
            if not busy and _fits(balls, active, env, catch, cx, cy, h.ball_radius):
                _capture(balls, active, held, holder, slot, held_time, released_from, state,
                         env, catch, element, cx, cy, 0, dt)  # fmt: skip
                free[catch] = False


@njit(cache=True, inline="always")
def _play_locks(balls, active, held, holder, slot, held_time, released_from, state, env, h, dt,
                xy, speed, free, taken, gaps):  # fmt: skip
    """The locks of :func:`play_env_holders`: each captures balls into its next free slot."""
    n_balls = active.shape[1]
    for k in range(len(h.lock_ids)):
        element, reach, n_slots = h.lock_ids[k], h.lock_reach[k], h.lock_n_slots[k]
        for ball in range(n_balls):
            nearest = math.inf
            for j in range(n_slots):
                gap = math.hypot(xy[ball, 0] - h.lock_slots[k, j, 0],
                                 xy[ball, 1] - h.lock_slots[k, j, 1])  # fmt: skip
                gaps[ball, j] = gap
                nearest = min(nearest, gap)
            if released_from[env, ball] == element and nearest > reach:
                released_from[env, ball] = -1
        taken[:] = False
        for ball in range(n_balls):
            if holder[env, ball] == element:
                taken[slot[env, ball]] = True
        for ball in range(n_balls):
            if not (
                free[ball]
                and speed[ball] < h.lock_capture[k]
                and released_from[env, ball] != element
            ):
                continue
            into = -1
            for j in range(n_slots):
                if not taken[j]:
                    into = j
                    break
            if into < 0 or gaps[ball, into] > reach:
                continue
            x, y = h.lock_slots[k, into, 0], h.lock_slots[k, into, 1]
            if not _fits(balls, active, env, ball, x, y, h.ball_radius):
                continue
            _capture(balls, active, held, holder, slot, held_time, released_from, state, env,
                     ball, element, x, y, into, dt)  # fmt: skip
            taken[into] = True
            free[ball] = False
