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
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from pinball_env.physics import first_flipper
from pinball_env.physics.columns import BALL_X, BALL_Y, CONTACT_ELEMENT
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
    space = table.free_space
    if table.drop_targets:
        space = _free_space_with_targets(table)
        problem = _standing_targets(table, space, lane_x)
        if problem is not None:
            return problem
    starts = _starts(table, rng, drops, lane_x, space)
    outcome = _roll(table, starts, lane_x)
    if isinstance(outcome, str):
        return outcome
    return _shares(starts, *outcome)


def _free_space_with_targets(table: Table) -> np.ndarray:
    """``table.free_space`` with every drop target standing: where a ball centre can get to
    from the plunger without knocking one down."""
    geometry = table.pack()
    start = table.plunger.position if table.plunger is not None else table.ball.start
    segments = geometry.segments[~geometry.segment_one_sided]
    drains = geometry.sensors[geometry.sensor_drain]
    return free_space(
        table.width, table.height, table.ball.radius,
        np.concatenate([segments, geometry.drop_targets]), geometry.circles, geometry.flippers,
        start, drains,
    )  # fmt: skip


def _standing_targets(table: Table, space: np.ndarray, lane_x: float) -> str | None:
    """What the drop targets, all standing, block (None: nothing): the launch (no place in the
    playfield proper reachable from the plunger, ``space``) or the drain."""
    x = (np.flatnonzero(space.any(axis=0)) + 0.5) * CELL  # columns with a reachable cell
    if not (x < lane_x - table.ball.radius).any():
        return "the drop targets block the plunger's launch path"
    geometry = table.pack()
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
    speeds = np.linspace(plunger.speed[0], plunger.speed[1], LAUNCHES)
    inlanes = [s for s in table.sensors if s.name.endswith("_inlane")]
    balls = [(plunger.position, (0.0, float(v))) for v in speeds]
    balls += [(((s.points[0][0] + s.points[1][0]) / 2.0, s.points[0][1]), (0.0, 0.0))
              for s in inlanes]  # fmt: skip
    fixed = len(balls)
    balls += _sling_starts(table)
    checked = len(balls)
    radius = table.ball.radius
    cells = np.argwhere(space)  # (row, column) of reachable 1 mm cells
    x = (cells[:, 1] + 0.5) * 0.001
    y = (cells[:, 0] + 0.5) * 0.001
    cells = cells[(x < lane_x - radius) & (y > DRAIN_Y + radius)]
    picks = cells[rng.choice(len(cells), drops, replace=len(cells) < drops)]
    for row, column in picks:
        speed, heading = rng.uniform(0.0, 1.5), rng.uniform(0.0, 2.0 * math.pi)
        start = ((column + 0.5) * 0.001, (row + 0.5) * 0.001)
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


def _roll(table: Table, starts: Starts, lane_x: float) -> str | tuple[np.ndarray, np.ndarray]:
    """Every ball of ``starts`` rolled with the flippers at rest until all drain: a problem
    (a ball at rest, or not drained in time), or which balls entered the playfield and which
    touched a flipper."""
    from pinball_env.sim.world import World  # the world imports the table package, as this does

    n = len(starts.balls)
    radius = table.ball.radius
    world = World(table, n)
    for env, (position, velocity) in enumerate(starts.balls):
        world.place_ball(env, position, velocity)
    flippers = first_flipper(world.geometry) + np.arange(len(table.flippers))
    entered = np.zeros(n, dtype=bool)
    touched = np.zeros(n, dtype=bool)
    anchor = world.balls[:, [BALL_X, BALL_Y]].copy()
    still = np.zeros(n, dtype=np.int64)
    frame_rate = table.simulation.frame_rate
    rest_frames = round(REST_TIME * frame_rate)
    for _ in range(round(DRAIN_TIME * frame_rate)):
        world.step()
        active = world.active
        if not active.any():
            break
        position = world.balls[:, [BALL_X, BALL_Y]]
        entered |= active & (position[:, 0] < lane_x - radius)
        _touch(world.state, active & ~touched, flippers, touched)
        moved = np.hypot(*(position - anchor).T) >= radius
        anchor[moved] = position[moved]
        still = np.where(moved | ~active, 0, still + 1)
        if (still >= rest_frames).any():
            env = int(np.argmax(still))
            if env < starts.launches and not entered[env]:
                return "a plunger shot does not enter the playfield"
            return f"a ball rests at ({position[env, 0]:.3f}, {position[env, 1]:.3f})"
    if world.active.any():
        env = int(np.argmax(world.active))
        x, y = starts.balls[env][0]
        return f"a ball from ({x:.3f}, {y:.3f}) has not drained in {DRAIN_TIME:g} s"
    return entered, touched


def _touch(state, candidates: np.ndarray, flippers: np.ndarray, touched: np.ndarray) -> None:
    """Mark in ``touched`` the ``candidates`` whose contacts this step include a flipper."""
    for env in np.flatnonzero(candidates & (state.contact_count > 0)):
        count = min(state.contact_count[env], state.contacts.shape[1])
        ids = state.contacts[env, :count, CONTACT_ELEMENT]
        touched[env] = np.isin(ids, flippers).any()


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
