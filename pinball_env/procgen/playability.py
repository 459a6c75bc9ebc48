"""Whether a drawn table plays, checked on the swept kernel:

- the plunger shot enters the playfield at every launch speed, and at a third of them or more
  it comes down to a flipper (not straight down an outlane);
- a ball rolling down each inlane reaches its flipper, and a fair share of the balls dropped
  anywhere in the playfield touch a flipper on the way down;
- with the flippers at rest, every ball from random reachable places, sent across between the
  slingshots, or launched, drains within ``DRAIN_TIME``: no pocket holds a ball, and no pair of
  kickers keeps one bouncing for ever.

The kernel has the table's drop targets and spinners, so the balls meet them as in play. A ball
knocks a drop target down, though, so a bank standing across the way would not stop the balls of
the check: before them, the check finds that a ball can get from the plunger into the playfield
and down to the drain with every drop target standing (:func:`_standing_targets`), and the balls
dropped at random places start where they can with the targets standing.

The balls are rolled in one compiled call, each to its end (:func:`_roll_balls`), with the
verdict of stepping them all together frame by frame (envs are independent, so each ball's
trajectory is the same either way).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit

from pinball_env.physics import Geometry, first_flipper
from pinball_env.physics.columns import BALL_X, BALL_Y, CONTACT_ELEMENT
from pinball_env.physics.step import step_ball
from pinball_env.procgen.layout import DRAIN_Y
from pinball_env.table import Table
from pinball_env.table.reachable import CELL, free_space, touches

# With the flippers at rest, every ball must drain within this [s].
DRAIN_TIME = 60.0
# A ball that moves less than its radius in this long is resting [s] (as the game's ball search).
REST_TIME = 10.0
# Balls dropped at random reachable places in the playability check, and the share of them
# that must touch a flipper on the way down.
DROPS = 48
MIN_FLIPPER_SHARE = 0.25
# Plunger shots tried (launch speeds spread over the plunger's range), and the share of them
# that must come down to a flipper before draining (not straight down an outlane).
LAUNCHES = 9
MIN_LAUNCH_SHARE = 1 / 3
# Balls sent across between the slingshots: heights from the kickers' bottoms to above their
# tops, and speeds [m/s] either way.
SLING_HEIGHTS = 16
SLING_SPEEDS = (-1.2, -0.8, -0.5, -0.3, 0.3, 0.5, 0.8, 1.2)

Start = tuple[tuple[float, float], tuple[float, float]]  # (position, velocity) of a ball


@dataclass(frozen=True)
class Starts:
    """The balls of a check, in groups: ``balls[:launches]`` plunger shots, then up to
    ``fixed`` a ball down each inlane, then up to ``checked`` balls between the slingshots,
    then the balls dropped at random places."""

    balls: list[Start]
    launches: int
    fixed: int
    checked: int


def playability(table: Table, rng: np.random.Generator, drops: int = DROPS) -> str | None:
    """What keeps ``table`` from being played (None: nothing): the checks of the module's
    docstring, run on the swept kernel with ``drops`` balls at places drawn from ``rng``."""
    lane_x = min(s[0] for s in _lane_walls(table))
    if table.drop_targets:
        geometry = table.pack()
        space = _free_space_with_targets(table, geometry)
        problem = _standing_targets(table, geometry, space, lane_x)
        if problem is not None:
            return problem
    else:
        space = table.free_space
    starts = _starts(table, rng, drops, lane_x, space)
    outcome = _roll(table, starts, lane_x)
    if isinstance(outcome, str):
        return outcome
    return _shares(starts, *outcome)


def _free_space_with_targets(table: Table, geometry: Geometry) -> np.ndarray:
    """``table.free_space`` with every drop target standing: where a ball centre can get to
    from the plunger without knocking one down (``geometry``: ``table.pack()``)."""
    start = table.plunger.position if table.plunger is not None else table.ball.start
    segments = geometry.segments[~geometry.segment_one_sided]
    drains = geometry.sensors[geometry.sensor_drain]
    return free_space(
        table.width, table.height, table.ball.radius,
        np.concatenate([segments, geometry.drop_targets]), geometry.circles, geometry.flippers,
        start, drains,
    )  # fmt: skip


def _standing_targets(
    table: Table, geometry: Geometry, space: np.ndarray, lane_x: float
) -> str | None:
    """What the drop targets, all standing, block (None: nothing): the launch (no place in the
    playfield proper reachable from the plunger, ``space``) or the drain."""
    x = (np.flatnonzero(space.any(axis=0)) + 0.5) * CELL  # columns with a reachable cell
    if not (x < lane_x - table.ball.radius).any():
        return "the drop targets block the plunger's launch path"
    if not touches(space, geometry.sensors[geometry.sensor_drain], 2.5 * CELL, CELL):
        return "the drop targets keep the ball from the drain"
    return None


def _starts(
    table: Table, rng: np.random.Generator, drops: int, lane_x: float, space: np.ndarray
) -> Starts:
    """The balls of the check: plunger shots at speeds across the plunger's range, a ball down
    each inlane, balls sent across between the slingshots (where kicks that balance gravity
    could keep one bouncing from side to side for ever), and ``drops`` balls at random
    reachable places (``space``, a ``free_space`` grid), at random speeds."""
    plunger = table.plunger
    assert plunger is not None  # (a generated table's machine plunger)
    speeds = np.linspace(plunger.speed[0], plunger.speed[1], LAUNCHES)
    inlanes = [s for s in table.sensors if s.name.endswith("_inlane")]
    balls = [(plunger.position, (0.0, float(v))) for v in speeds]
    balls += [(((s.points[0][0] + s.points[1][0]) / 2.0, s.points[0][1]), (0.0, 0.0))
              for s in inlanes]  # fmt: skip
    fixed = len(balls)
    balls += _sling_starts(table)
    checked = len(balls)
    radius = table.ball.radius
    # The reachable cells above the drain and left of the shooter lane, in row-major order:
    # those of the grid's upper rows and left columns (cell centres rise with the index).
    low = np.count_nonzero((np.arange(space.shape[0]) + 0.5) * CELL <= DRAIN_Y + radius)
    width = np.count_nonzero((np.arange(space.shape[1]) + 0.5) * CELL < lane_x - radius)
    cells = np.flatnonzero(space[low:, :width])
    picks = cells[rng.choice(len(cells), drops, replace=len(cells) < drops)]
    for pick in picks.tolist():
        row, column = divmod(pick, width)
        speed, heading = rng.uniform(0.0, 1.5), rng.uniform(0.0, 2.0 * math.pi)
        start = ((column + 0.5) * CELL, (low + row + 0.5) * CELL)
        balls.append((start, (speed * math.cos(heading), speed * math.sin(heading))))
    return Starts(balls, len(speeds), fixed, checked)


def _sling_starts(table: Table) -> list[Start]:
    """Balls sent either way across the gap between the slingshots, at heights from the
    kickers' bottoms to a ball above their tops."""
    slings = [w for w in table.walls if w.name.endswith("_slingshot")]
    if not slings:
        return []
    low = max(min(p[1] for p in w.points) for w in slings)
    high = min(max(p[1] for p in w.points) for w in slings) + 2.0 * table.ball.radius
    middle = sum(p[0] for w in slings for p in w.points) / (2 * len(slings))
    return [
        ((middle, float(height)), (speed, 0.0))
        for height in np.linspace(low, high, SLING_HEIGHTS)
        for speed in SLING_SPEEDS
    ]


# What became of a ball of the check (see :func:`_roll_balls`).
DRAINED, RESTED, NOT_FINITE, TIMED_OUT = range(4)


def _roll(table: Table, starts: Starts, lane_x: float) -> str | tuple[np.ndarray, np.ndarray]:
    """Every ball of ``starts`` rolled with the flippers at rest until all drain: a problem
    (a ball at rest, or not drained in time), or which balls entered the playfield and which
    touched a flipper. The verdict is that of stepping every ball together frame by frame and
    stopping at the first frame where one rests (its lowest env on a tie), or, all frames done,
    at the first ball still in play."""
    from pinball_env.sim.world import World  # the world imports the table package, as this does

    n = len(starts.balls)
    world = World(table, n)
    for env, (position, velocity) in enumerate(starts.balls):
        world.place_ball(env, position, velocity)
    frame_rate = table.simulation.frame_rate
    outcome = np.empty(n, dtype=np.int64)
    last_frame = np.empty(n, dtype=np.int64)
    entered = np.zeros(n, dtype=bool)
    touched = np.zeros(n, dtype=bool)
    _roll_balls(
        world.geometry, world.settings, world.state, world.scratch, lane_x, table.ball.radius,
        round(DRAIN_TIME * frame_rate), round(REST_TIME * frame_rate), outcome, last_frame,
        entered, touched,
    )  # fmt: skip
    # The first ball to rest, or to break (World.step raised that before any rest was seen),
    # by frame, then env: where stepping every ball together would have stopped.
    ended = np.flatnonzero((outcome == RESTED) | (outcome == NOT_FINITE))
    if ended.size:
        frame, _, env = min((last_frame[e], outcome[e] == RESTED, int(e)) for e in ended)
        if outcome[env] == NOT_FINITE:
            bad = ended[(last_frame[ended] == frame) & (outcome[ended] == NOT_FINITE)].tolist()
            raise FloatingPointError(f"the ball state of env(s) {bad} is no longer finite")
        if env < starts.launches and not entered[env]:
            return "a plunger shot does not enter the playfield"
        x, y = world.balls[env, 0, BALL_X], world.balls[env, 0, BALL_Y]
        return f"a ball rests at ({x:.3f}, {y:.3f})"
    if (outcome == TIMED_OUT).any():
        x, y = starts.balls[int(np.argmax(outcome == TIMED_OUT))][0]
        return f"a ball from ({x:.3f}, {y:.3f}) has not drained in {DRAIN_TIME:g} s"
    return entered, touched


# No reference counting, as step_world: numba would count one for every array taken out of the
# records at every frame (measured: 2.3x slower).
@njit(cache=True, nogil=True, _nrt=False)  # type: ignore[call-overload]  # _nrt: not in the stubs
def _roll_balls(
    geometry, settings, state, scratch, lane_x, radius, frames, rest_frames, outcome,
    last_frame, entered, touched,
):  # fmt: skip
    """Roll each env's ball, one after another, for up to ``frames`` frames of the swept
    kernel (``step_ball``, as ``World.step``), to its end: its ``outcome`` (DRAINED, RESTED:
    it moved less than ``radius`` in ``rest_frames``, NOT_FINITE, or TIMED_OUT) at
    ``last_frame``. Along the way, while in play, whether it ``entered`` the playfield (left of
    ``lane_x``, less a radius) and ``touched`` a flipper. Once a ball rests or breaks at frame
    ``f``, the later balls are rolled to ``f`` at most: only there can one end the check first.
    """
    balls, active = state.balls, state.active  # a table of one ball: its slot 0
    contacts, contact_count = state.contacts, state.contact_count
    flipper_id = first_flipper(geometry)
    flipper_end = flipper_id + geometry.flippers.shape[0]
    limit = frames
    for env in range(balls.shape[0]):
        anchor_x, anchor_y = balls[env, 0, BALL_X], balls[env, 0, BALL_Y]
        still = 0
        outcome[env], last_frame[env] = TIMED_OUT, limit
        for frame in range(limit):
            if not step_ball(geometry, settings, state, scratch, env, flipper_id):
                outcome[env], last_frame[env] = NOT_FINITE, frame
                limit = frame + 1
                break
            if not active[env, 0]:
                outcome[env], last_frame[env] = DRAINED, frame
                break
            x, y = balls[env, 0, BALL_X], balls[env, 0, BALL_Y]
            if x < lane_x - radius:
                entered[env] = True
            for i in range(min(contact_count[env], contacts.shape[1])):
                if flipper_id <= contacts[env, i, CONTACT_ELEMENT] < flipper_end:
                    touched[env] = True
            if math.hypot(x - anchor_x, y - anchor_y) >= radius:  # as np.hypot, bitwise
                anchor_x, anchor_y, still = x, y, 0
            else:
                still += 1
                if still >= rest_frames:
                    outcome[env], last_frame[env] = RESTED, frame
                    limit = frame + 1
                    break


def _shares(starts: Starts, entered: np.ndarray, touched: np.ndarray) -> str | None:
    """The checks on where the drained balls went: every plunger shot entered the playfield,
    enough of them and every inlane ball reached a flipper, enough dropped balls touched one."""
    launches = slice(0, starts.launches)
    if not entered[launches].all():
        return "a plunger shot does not enter the playfield"
    if touched[launches].mean() < MIN_LAUNCH_SHARE:
        return f"only {touched[launches].mean():.0%} of plunger shots reach a flipper"
    if not touched[starts.launches : starts.fixed].all():
        return "a ball rolling down an inlane misses its flipper"
    share = touched[starts.checked :].mean()
    if share < MIN_FLIPPER_SHARE:
        return f"only {share:.0%} of dropped balls touch a flipper"
    return None


def _lane_walls(table: Table) -> list[tuple[float, float, float, float]]:
    """The shooter lane's inner wall as segments."""
    return [s for w in table.walls if w.name == "lane_wall" for s in w.segments()]
