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

The kernel (``step.step_ball``) sweeps standing drop targets with the walls, tests spinner and
kickback lines as it tests sensors, and calls :func:`update_targets` once a frame.
"""

import math

from numba import njit

from pinball_env.physics.columns import (
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
from pinball_env.physics.data import first_spinner
from pinball_env.physics.sweep import point_segment_distance

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
def raise_banks(geometry, state, env, x, y, r, dt):
    """Advance the clock of every bank of env ``env`` whose targets are all down by ``dt``, and
    stand a bank up once its clock reaches its reset time, unless the ball in play (at (x, y),
    radius ``r``) lies within a radius of one of its targets: then it waits for the ball to
    leave."""
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
        for j in range(targets.shape[0] if state.active[env] else 0):
            t = targets[j]
            if bank_of[j] == bank and point_segment_distance(x, y, t[0], t[1], t[2], t[3]) < 2 * r:
                clear = False
        if clear:
            for j in range(targets.shape[0]):
                if bank_of[j] == bank:
                    up[j] = True
            clock[bank] = 0.0


@njit(cache=True)
def update_targets(geometry, state, env, x, y, r, dt):
    """Env ``env``'s targets at the end of a frame of ``dt`` seconds, the ball at (x, y): the
    spinners turn (their revolutions counted as hits), the banks rise."""
    spinner_id = first_spinner(geometry)
    for j in range(geometry.spinners.shape[0]):
        turns = turn_spinner(geometry.spinners[j], state.spinners[env, j], dt)
        state.hits[env, spinner_id + j] += turns
    raise_banks(geometry, state, env, x, y, r, dt)
