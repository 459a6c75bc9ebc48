"""The compiled passes around the physics of a frame of several balls (``game.multiball``):
the game's ball written back to its slot, the locks the rules released, the auto-plunger's turn,
and after the physics the drains, the ball search of the other balls, the multiball's start and
end and the game's ball picked again.

Each pass is written for one env (``*_ball``/``*_frame``, inlined) so that the game's compiled
step loop (``game.play``) plays a several-ball frame env by env, in its threads, handing back to
Python only for a draw from an env's random stream (the auto-plunger's launch speed); the
all-env passes (``write_back_balls``, ``after_frames``, ``before_frames``, ``sync_balls``) serve the
Python path (another physics backend, the ``on_frame`` hook) with the same bodies.
"""

from typing import NamedTuple

import numpy as np
from numba import njit

from pinball_env.physics.columns import BALL_X, BALL_Y
from pinball_env.physics.multiball import step_balls
from pinball_env.sim.holders import Holders, place_slot, play_env_holders


class Memory(NamedTuple):
    """What :class:`~pinball_env.game.multiball.Multiball` keeps between frames, for the
    compiled passes."""

    proxy: np.ndarray  # (N, 5): the game's ball as last written here (write_back)
    proxy_active: np.ndarray  # (N,) bool: ... and whether it was in play
    was_active: np.ndarray  # (N, M) bool: the balls in play before the frame's physics
    watching: np.ndarray  # (N,) int64: the slot the loop's ball search clock is (-1: none)


class MultiballParameters(NamedTuple):
    """What the compiled passes of a game of several balls play by, with the work arrays of
    its saucers and locks (``sim.holders``), one row per env."""

    lock_ids: np.ndarray  # (K,) int64: the locks' element ids, consecutive
    locks_first: int  # the first lock's element id
    locks_end: int  # one past the last's
    radius2: float  # the ball search's squared radius [m^2]
    search_frames: int  # its wait [frames]
    plunger_x: float  # the plunger's position [m]
    plunger_y: float
    lane_y: float  # where the game's ball waits for a queued one [m]
    lane_clear: float  # the shooter lane is clear beyond this distance of the plunger [m]
    pair: np.ndarray  # (PROP_SIZE,) the ball-ball material
    holders: Holders  # the table's saucers and locks
    dt: float  # a frame [s]
    work_xy: np.ndarray  # (N, M, 2) float64: sim.holders.holder_work, per env
    work_speed: np.ndarray  # (N, M) float64
    work_free: np.ndarray  # (N, M) bool
    work_taken: np.ndarray  # (N, S) bool
    work_gaps: np.ndarray  # (N, M, S) float64


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
def sync_balls(state, memory, envs, first, end, plunger_x, lane_y):
    """:func:`sync_ball` of each of ``envs`` (none drained): one dispatch for a batch."""
    for env in envs:
        sync_ball(state, memory, env, -1, first, end, plunger_x, lane_y)


@njit(cache=True, inline="always")
def after_frame(state, memory, params, env):
    """:meth:`Multiball.after_frame` of env ``env`` (module docstring): ``memory.was_active``
    holds its balls in play before the frame's physics, ``params`` is the game's
    :class:`MultiballParameters`."""
    world = state.world
    active, held, holder = world.active, world.held, state.holders.holder
    pending, save = state.pending_balls, state.multiball_save
    n_balls = active.shape[1]
    first, end = params.locks_first, params.locks_end
    frames = params.search_frames
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
        state.ball_still, game_ball, params.radius2, frames,
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
    count_in_play(state, params, env, n_drained)
    sync_ball(state, memory, env, drained, first, end, params.plunger_x, params.lane_y)


@njit(cache=True, inline="always")
def count_in_play(state, params, env, n_drained):
    """The balls in play of env ``env`` after its frame (the queued ones counted), ``n_drained``
    having drained in it: a lock that took the only ball in play has one served (or, the
    trough empty, its balls let go); the multiball starts at two and ends at one."""
    world = state.world
    active, held, holder = world.active, world.held, state.holders.holder
    first, end, pending = params.locks_first, params.locks_end, state.pending_balls
    tilted = world.tilted[env]
    in_play = pending[env]
    trough = False
    for ball in range(active.shape[1]):
        if active[env, ball] and not _locked(held[env, ball], holder[env, ball], first, end):
            in_play += 1
        trough |= not active[env, ball] and not held[env, ball]
    took = 0
    for k in range(len(params.lock_ids)):
        took += world.hits[env, params.lock_ids[k]]
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


# Without reference counting (``_nrt=False``, as ``game.play.play_frames``): it allocates nothing,
# and counting the references of every array taken out of ``state`` cost it half its time.
@njit(cache=True, _nrt=False)  # type: ignore[call-overload]  # _nrt: not in the stubs
def after_frames(state, memory, params, stepped):
    """:func:`after_frame` of every env that ``stepped`` marks, in one compiled pass."""
    for env in range(len(stepped)):
        if stepped[env]:
            after_frame(state, memory, params, env)


# --- before the physics, and the frame (the game's compiled step loop) ------------------------


@njit(cache=True, inline="always")
def write_back_ball(state, memory, env):
    """Carry the loop's writes to env ``env``'s game's ball (``state.game_ball``) since it was
    last written here (``memory``) into its slot: a ball put on the player's plunger (the next
    ball: a trough ball; a ball caught in the shooter lane: its own), a ball given up (a
    tilt), a ball moved (:meth:`Multiball.write_back`)."""
    proxy, proxy_active = state.game_ball, state.game_ball_active
    same = proxy_active[env] == memory.proxy_active[env]
    for column in range(proxy.shape[1]):
        same &= proxy[env, column] == memory.proxy[env, column]  # NaN: changed
    if same:
        return
    world, h = state.world, state.holders
    active, held = world.active, world.held
    slot = state.ball_slot[env]
    if state.on_plunger[env] and not proxy_active[env]:
        if not (slot >= 0 and active[env, slot] and not held[env, slot]):  # not its own
            slot = 0
            for ball in range(active.shape[1]):  # the trough's first
                if not active[env, ball] and not held[env, ball]:
                    slot = ball
                    break
        place_slot(world.balls, active, held, h.holder, h.slot, h.held_time, h.released_from, env,
               slot, proxy[env, BALL_X], proxy[env, BALL_Y], 0.0, 0.0)  # fmt: skip
        active[env, slot] = False
        state.ball_slot[env] = slot
        memory.watching[env] = -1
    elif memory.proxy_active[env] and not proxy_active[env]:
        if slot >= 0 and not held[env, slot]:
            active[env, slot] = False  # given up: back to the trough
        memory.watching[env] = -1
    elif slot >= 0:
        _copy_row_back(world.balls, proxy, env, slot)
    for column in range(proxy.shape[1]):
        memory.proxy[env, column] = proxy[env, column]
    memory.proxy_active[env] = proxy_active[env]


@njit(cache=True, inline="always")
def _copy_row_back(balls, proxy, env, slot):
    """``balls[env, slot] = proxy[env]``, column by column (a row copy allocates)."""
    for column in range(proxy.shape[1]):
        balls[env, slot, column] = proxy[env, column]


@njit(cache=True, _nrt=False)  # type: ignore[call-overload]  # _nrt: not in the stubs
def write_back_balls(state, memory):
    """:func:`write_back_ball` of every env."""
    for env in range(len(state.game_ball_active)):
        write_back_ball(state, memory, env)


@njit(cache=True, inline="always")
def release_locks(state, params, env):
    """The locks the rules released in env ``env`` (``state.lock_release``) let their balls go
    at their kicks (``World.release_lock``)."""
    world, h = state.world, state.holders
    for lock in range(state.lock_release.shape[1]):
        if not state.lock_release[env, lock]:
            continue
        element = params.lock_ids[lock]
        kick_x, kick_y = params.holders.lock_kick[lock, 0], params.holders.lock_kick[lock, 1]
        for ball in range(world.active.shape[1]):
            if h.holder[env, ball] == element:
                place_slot(world.balls, world.active, world.held, h.holder, h.slot, h.held_time,
                       h.released_from, env, ball, world.balls[env, ball, BALL_X],
                       world.balls[env, ball, BALL_Y], kick_x, kick_y)  # fmt: skip
                h.released_from[env, ball] = element
        state.lock_release[env, lock] = False


@njit(cache=True, inline="always")
def trough_ball(state, env):
    """The first ball of env ``env`` in the trough (neither in play nor held, nor waiting on
    the player's plunger); -1: none."""
    world, slot = state.world, state.ball_slot[env]
    for ball in range(world.active.shape[1]):
        waiting = state.on_plunger[env] and ball == slot
        if not world.active[env, ball] and not world.held[env, ball] and not waiting:
            return ball
    return -1


@njit(cache=True, inline="always")
def lane_clear(state, params, env):
    """Whether the shooter lane of env ``env`` is clear for the auto-plunger: no ball waits on
    the player's plunger, none in play lies within ``params.lane_clear`` of the plunger."""
    if state.on_plunger[env]:
        return False
    balls, active = state.world.balls, state.world.active
    for ball in range(active.shape[1]):
        gap = np.hypot(balls[env, ball, BALL_X] - params.plunger_x,
                       balls[env, ball, BALL_Y] - params.plunger_y)  # fmt: skip
        if active[env, ball] and gap < params.lane_clear:
            return False
    return True


@njit(cache=True, inline="always")
def before_physics(state, memory, params, env):
    """Env ``env`` before its frame's physics (:meth:`Multiball.before_frame`): the game's ball
    written back, the locks released, the auto-plunger's queue seen to. Returns whether a
    queued ball is due (the lane clear, a ball in the trough): its launch speed is a draw
    from the env's random stream, which Python makes (:meth:`Multiball.serve`), then this is
    called again (it does nothing twice)."""
    write_back_ball(state, memory, env)
    release_locks(state, params, env)
    if state.pending_balls[env] > 0:
        if trough_ball(state, env) < 0:
            state.pending_balls[env] = 0  # the trough is empty
        elif lane_clear(state, params, env):
            return True
    for ball in range(memory.was_active.shape[1]):
        memory.was_active[env, ball] = state.world.active[env, ball]
    return False


@njit(cache=True, inline="always")
def multiball_frame(geometry, settings, state, scratch, memory, params, env):
    """The physics of env ``env``'s frame of several balls and what follows it at once: the
    several-ball kernel, the saucers and locks (``sim.holders``), :func:`after_frame`.
    Returns whether every ball's state is finite."""
    world, h = state.world, state.holders
    finite = step_balls(geometry, settings, world, scratch, params.pair, env)
    play_env_holders(world.balls, world.active, world.held, h.holder, h.slot, h.held_time,
                     h.released_from, world, env, True, params.holders, params.dt,
                     params.work_xy[env], params.work_speed[env], params.work_free[env],
                     params.work_taken[env], params.work_gaps[env])  # fmt: skip
    after_frame(state, memory, params, env)
    return finite


@njit(cache=True, _nrt=False)  # type: ignore[call-overload]  # _nrt: not in the stubs
def before_frames(state, memory, params, stepped, due):
    """:func:`before_physics` of every env that ``stepped`` marks; ``due`` (N,) bool: set
    where a queued ball is due (:meth:`Multiball.serve` launches it)."""
    for env in range(len(stepped)):
        if stepped[env]:
            due[env] = before_physics(state, memory, params, env)
