"""Targets and their kin: the table's elements that change during play, per env.

- A **drop target** is a two-sided segment that stops the ball while it stands
  (``State.targets_up``) and drops when the ball hits it: from the end of that substep it is
  gone, no contact at any speed. Targets come in banks; a bank whose targets are all down rises
  again ``Geometry.bank_reset`` seconds after the last fell, but never onto the ball: it waits
  while the ball lies within a ball radius of any of its targets (:func:`raise_banks`).
- A **spinner** is a flap hung across a lane on a horizontal axle. The ball passes through it;
  its crossing spins the flap at the ball's normal speed over the flap's radius (when that is
  faster than it turns already, :func:`spin_spinner`), and the flap slows by viscous damping and
  bearing friction. Each revolution is a hit of the spinner (:func:`turn_spinner`): points per
  revolution, as on a real machine. The flap's pull on the ball is left out (a few percent of a
  fast ball's energy).
- A **kickback** is a kicker at the bottom of an outlane: a ball that crosses its line against
  the kick's direction is a hit; while the kickback is lit (``State.kickback_lit``) that ball
  leaves the line at the kick velocity, and the kickback goes dark. The rules light it.

Every crossing is here: the sensors' (rollovers, the drain: :func:`record_crossings`), the
spinner and kickback lines' (:func:`cross_target_lines`) and the standing drop targets' sweep
(:func:`sweep_drop_targets`). The kernel (``step.step_ball``) calls them in each contact pass,
and :func:`update_targets` once a frame.
"""

import math

from numba import njit

from pinball_env.physics.columns import (
    BALL_X,
    BALL_Y,
    KICKBACK_VX,
    KICKBACK_VY,
    SPIN_ANGLE,
    SPIN_OMEGA,
    SPINNER_DAMPING,
    SPINNER_FRICTION,
    SPINNER_RADIUS,
    SPINNER_X0,
    SPINNER_X1,
    SPINNER_Y0,
    SPINNER_Y1,
)
from pinball_env.physics.data import (
    first_drop_target,
    first_kickback,
    first_sensor,
    first_spinner,
    log_contact,
)
from pinball_env.physics.sweep import INF, point_segment_distance, segment_contact

TWO_PI = 2.0 * math.pi


@njit(cache=True)
def spin_spinner(spinner, spin, vx, vy, time):
    """A ball crossing ``spinner`` (a row of ``Geometry.spinners``) at (vx, vy), ``time``
    seconds into the frame, spins its flap (``spin``, the spinner's row of ``State.spinners``)
    at its normal speed over the flap's radius, in the direction it passed, unless the flap
    already turns faster. The angle is set back by what the new spin would have turned it
    before ``time``, so that :func:`turn_spinner`, at the end of the frame, turns it by the
    old spin until ``time`` and the new one after."""
    ex = spinner[SPINNER_X1] - spinner[SPINNER_X0]
    ey = spinner[SPINNER_Y1] - spinner[SPINNER_Y0]
    omega = (ex * vy - ey * vx) / (math.sqrt(ex * ex + ey * ey) * spinner[SPINNER_RADIUS])
    if abs(omega) > abs(spin[SPIN_OMEGA]):
        spin[SPIN_ANGLE] += (spin[SPIN_OMEGA] - omega) * time
        spin[SPIN_OMEGA] = omega


@njit(cache=True)
def turn_spinner(spinner, spin, dt):
    """Turn a spinner's flap on by a frame of ``dt`` seconds; returns the revolutions it
    completed (each counted where the flap passes upside down, at an odd multiple of pi, so a
    flap starting at rest counts its first whole turn either way round).

    The spin decays exactly under the damping over the frame, then loses the friction's share
    (stopping at zero); the angle advances by the mean of the two (the trapezoid rule)."""
    omega = spin[SPIN_OMEGA]
    if omega == 0.0:
        return 0
    speed = abs(omega) * math.exp(-spinner[SPINNER_DAMPING] * dt) - spinner[SPINNER_FRICTION] * dt
    after = math.copysign(max(speed, 0.0), omega)
    angle = spin[SPIN_ANGLE] + 0.5 * (omega + after) * dt
    turns = math.floor((angle + math.pi) / TWO_PI)
    spin[SPIN_ANGLE] = angle - turns * TWO_PI
    spin[SPIN_OMEGA] = after
    return abs(turns)


@njit(cache=True)
def raise_banks(geometry, state, env, balls, active, r, dt):
    """Advance the clock of every bank of env ``env`` whose targets are all down by ``dt``, and
    stand a bank up once its clock reaches its reset time, unless a ball in play (``balls``
    (M, 5) where ``active`` (M,), radius ``r``) lies within a radius of one of its targets: then
    it waits for the ball to leave."""
    bank_of, targets = geometry.drop_target_bank, geometry.drop_targets
    up, clock = state.targets_up[env], state.bank_clock[env]
    for bank in range(geometry.bank_reset.shape[0]):
        down = True
        for j in range(targets.shape[0]):
            if bank_of[j] == bank and up[j]:
                down = False
                break
        if not down:
            clock[bank] = 0.0
            continue
        clock[bank] += dt
        if clock[bank] < geometry.bank_reset[bank]:
            continue
        clear = True
        for i in range(balls.shape[0]):
            x, y = balls[i, BALL_X], balls[i, BALL_Y]
            for j in range(targets.shape[0] if active[i] else 0):
                t = targets[j]
                if (
                    bank_of[j] == bank
                    and point_segment_distance(x, y, t[0], t[1], t[2], t[3]) < 2 * r
                ):
                    clear = False
        if clear:
            for j in range(targets.shape[0]):
                if bank_of[j] == bank:
                    up[j] = True
            clock[bank] = 0.0


@njit(cache=True)
def update_targets(geometry, state, env, balls, active, r, dt):
    """Env ``env``'s targets at the end of a frame of ``dt`` seconds, its balls ``balls`` (M, 5)
    in play where ``active`` (M,) (its slots, ``state.balls[env]``): the spinners turn
    (their revolutions counted as hits), the banks rise."""
    spinner_id = first_spinner(geometry)
    for j in range(geometry.spinners.shape[0]):
        turns = turn_spinner(geometry.spinners[j], state.spinners[env, j], dt)
        state.hits[env, spinner_id + j] += turns
    raise_banks(geometry, state, env, balls, active, r, dt)


# --- crossings: sensors, kickbacks, drop targets --------------------------------------------------


@njit(cache=True)
def sensor_crossing(x, y, dx, dy, sensor):
    """Fraction of the move (x, y) -> (x + dx, y + dy) at which the centre crosses a sensor.

    Half-open: a point exactly on the sensor line counts as behind it (the side opposite its
    normal), so a path that ends on the line and goes on is counted once. ``inf`` for none.
    """
    x0 = sensor[0]
    y0 = sensor[1]
    ex = sensor[2] - x0
    ey = sensor[3] - y0
    side0 = ex * (y - y0) - ey * (x - x0)
    side1 = ex * (y + dy - y0) - ey * (x + dx - x0)
    if (side0 > 0.0) == (side1 > 0.0):
        return INF
    u = side0 / (side0 - side1)
    along = ((x + dx * u - x0) * ex + (y + dy * u - y0) * ey) / (ex * ex + ey * ey)
    if along < 0.0 or along >= 1.0:  # half-open too: sensors meeting end to end count once
        return INF
    return u


@njit(cache=True)
def cross_sensors(x, y, dx, dy, sensors, sensor_drain, crossings):
    """Fractions of the move (x, y) -> (x + dx, y + dy) at which the centre crosses each sensor,
    written to ``crossings`` (inf for none). Returns the earliest drain crossing (inf for none):
    the ball leaves play there, so only crossings up to it happen."""
    drain = INF
    for j in range(sensors.shape[0]):
        crossings[j] = sensor_crossing(x, y, dx, dy, sensors[j])
        if sensor_drain[j] and crossings[j] < drain:
            drain = crossings[j]
    return drain


@njit(cache=True)
def record_crossings(state, env, geometry, x, y, dx, dy, start, duration, crossings):
    """Count and log env's sensor crossings on the move (x, y) -> (x + dx, y + dy), made over
    ``duration`` seconds from ``start`` [s into the frame]; those past a drain crossing do not
    happen. Returns the fraction of the move at the drain crossing (inf for none)."""
    drain = cross_sensors(x, y, dx, dy, geometry.sensors, geometry.sensor_drain, crossings)
    offset = first_sensor(geometry)
    for j in range(geometry.sensors.shape[0]):  # the row may be longer (see step_tables)
        if crossings[j] <= drain and crossings[j] < INF:
            state.hits[env, offset + j] += 1
            log_contact(state, env, offset + j, start + duration * crossings[j], 0.0)
    return drain


@njit(cache=True)
def record_near_crossings(state, env, geometry, x, y, dx, dy, start, duration, crossings, near,
                          first, end):  # fmt: skip
    """:func:`record_crossings` of the move, after a cheap test that rules out the common case:
    where the ball crosses none of the sensors ``near[first:end]`` (its candidate set's), it
    crosses none; returns inf then."""
    for i in range(first, end):
        if sensor_crossing(x, y, dx, dy, geometry.sensors[near[i]]) < INF:
            return record_crossings(state, env, geometry, x, y, dx, dy, start, duration, crossings)
    return INF


@njit(cache=True)
def kickback_crossing(x, y, vx, vy, duration, kickbacks, lit):
    """The first lit kickback whose line the ball moving at (vx, vy) from (x, y) for
    ``duration`` seconds crosses against its kick, and the fraction of the move where:
    ``(kickback, fraction)``, ``(-1, inf)`` for none."""
    best, best_u = -1, INF
    for j in range(kickbacks.shape[0]):
        kick = kickbacks[j]
        if lit[j] and vx * kick[KICKBACK_VX] + vy * kick[KICKBACK_VY] < 0.0:
            u = sensor_crossing(x, y, vx * duration, vy * duration, kick)
            if u < best_u:
                best, best_u = j, u
    return best, best_u


@njit(cache=True)
def count_kickbacks(state, env, x, y, vx, vy, duration, kickbacks, lit, kickback_id, time):
    """Count (as hits) and log the dark kickbacks' lines that the move from (x, y) at (vx, vy)
    for ``duration`` seconds crossed against their kick; ``time`` is the move's end [s into the
    frame]. (A lit one crossed fires, see ``step_ball``.)"""
    for j in range(kickbacks.shape[0]):
        kick = kickbacks[j]
        against = vx * kick[KICKBACK_VX] + vy * kick[KICKBACK_VY] < 0.0
        if (
            not lit[j]
            and against
            and sensor_crossing(x, y, vx * duration, vy * duration, kick) < INF
        ):
            state.hits[env, kickback_id + j] += 1
            log_contact(state, env, kickback_id + j, time, 0.0)


@njit(cache=True)
def sweep_drop_targets(
    state, env, geometry, x, y, dx, dy, r, t, nx, ny, svx, svy, element, cut, near, start, stop
):  # fmt: skip
    """The pass's earliest contact ``(t, nx, ny, svx, svy, element, cut)`` (as found over the
    other solids) with env ``env``'s standing drop targets of its candidate set (indexes
    ``near[start:stop]``) swept too, the ball moving from (x, y) by (dx, dy); ties go to the
    lower id (the others')."""
    targets, bounds, up = geometry.drop_targets, geometry.drop_target_bounds, state.targets_up
    travel = math.sqrt(dx * dx + dy * dy)
    first = first_drop_target(geometry)
    for k in range(start, stop):
        j = near[k]
        if not up[env, j]:
            continue
        tt, tnx, tny = segment_contact(x, y, dx, dy, r, travel, targets[j], bounds[j], False)
        if tt < t:
            t, nx, ny, svx, svy, element, cut = tt, tnx, tny, 0.0, 0.0, first + j, False
    return t, nx, ny, svx, svy, element, cut


@njit(cache=True)
def cross_target_lines(state, env, geometry, x, y, vx, vy, used, start):
    """The spinner and kickback lines of env ``env`` on the ball's move from (x, y) at (vx, vy)
    for ``used`` seconds, from ``start`` [s into the frame]. A lit kickback's line crossed
    against its kick ends the move there: it fires (the caller gives the ball its kick) and goes
    dark. Each spinner crossed is spun (:func:`spin_spinner`); each kickback line
    crossed against its kick is a hit, lit or not. Returns ``(kicked, used)``: the kickback
    that fired (-1: none) and the move's time, cut short at its line."""
    kickbacks, lit = geometry.kickbacks, state.kickback_lit[env]
    kicked = -1
    if kickbacks.shape[0] > 0:
        kicked, u = kickback_crossing(x, y, vx, vy, used, kickbacks, lit)
        if kicked >= 0:
            used *= u
        count_kickbacks(state, env, x, y, vx, vy, used, kickbacks, lit,
                        first_kickback(geometry), start + used)  # fmt: skip
    spinners = geometry.spinners
    for j in range(spinners.shape[0]):
        u = sensor_crossing(x, y, vx * used, vy * used, spinners[j])
        if u < INF:
            spin_spinner(spinners[j], state.spinners[env, j], vx, vy, start + used * u)
    if kicked >= 0:
        element = first_kickback(geometry) + kicked
        state.hits[env, element] += 1
        log_contact(state, env, element, start + used, 0.0)
        lit[kicked] = False
    return kicked, used
