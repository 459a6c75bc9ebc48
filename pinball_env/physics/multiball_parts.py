"""The parts of a several-ball pass (``multiball.step_balls``): the overlap with the other
balls and the settle out of them, a wedged ball's stop (and the flippers it holds), the
separation of two balls, and the lines (spinners, kickbacks) a ball crosses on its move."""

from numba import njit

from pinball_env.physics.columns import (
    BALL_SPIN,
    BALL_VX,
    BALL_VY,
    BALL_X,
    BALL_Y,
    W_BEFORE,
    W_BEFORE_NX,
    W_BEFORE_NY,
    W_CHECK,
    W_LAST,
    W_LAST_NX,
    W_LAST_NY,
    W_LAST_REM,
    W_MOVING,
    W_PUSHERS,
    W_WEDGED,
)
from pinball_env.physics.contact import (
    SETTLE_ROUNDS,
    earliest_static_contact,
    flipper_angle_at,
    settle,
    unwedge,
    within_reach,
)
from pinball_env.physics.data import (
    first_kickback,
)
from pinball_env.physics.sweep import INF, norm
from pinball_env.physics.targets import (
    count_kickbacks,
    sensor_crossing,
    spin_spinner,
)

# --- overlaps with the other balls -----------------------------------------------------------


@njit(cache=True, inline="always")
def ball_overlap(x, y, i, balls, active, r):
    """How deep a ball of radius ``r`` at (x, y) lies in the ball in play it overlaps most,
    ball ``i`` (itself) left out [m]; 0 or less when it overlaps none. The other ball counts as
    a circle of radius 2r at its centre, so the depth is ``2r - d`` at centre distance d."""
    deepest = -INF
    for j in range(balls.shape[0]):
        if j != i and active[j]:
            deepest = max(deepest, 2.0 * r - norm(x - balls[j, BALL_X], y - balls[j, BALL_Y]))
    return deepest


@njit(cache=True)
def settle_balls(x, y, i, balls, active, geometry, angles, up, r, skin):
    """``contact.settle`` with the other balls in play as fixed circles of radius 2r: push ball
    ``i`` at (x, y) out of every element (``settle``'s rounds, each move at most MAX_NUDGE
    radii: no room near here leaves it where it was) and out of every ball it overlaps by more
    than half the skin, to 2r + skin from its centre, in rounds (projected Gauss-Seidel) until
    it overlaps none or SETTLE_ROUNDS have passed. A push off a ball is swept against the walls
    and posts and stops a skin short of them (so it may be long: balls placed into one another
    are pushed apart whatever the overlap, never through a wall). Returns the new centre."""
    target = 2.0 * r + skin
    for _ in range(SETTLE_ROUNDS):
        x, y = settle(x, y, geometry, angles, up, r, skin)
        moved = False
        for j in range(balls.shape[0]):
            if j == i or not active[j]:
                continue
            gx, gy = x - balls[j, BALL_X], y - balls[j, BALL_Y]
            d = norm(gx, gy)
            if d >= target - 0.5 * skin:
                continue
            nx, ny = (gx / d, gy / d) if d > 0.0 else (0.0, 1.0)  # coincident: up the table
            push = target - d
            t, _, _, _ = earliest_static_contact(
                x, y, nx * push, ny * push, r + skin, geometry.segments, geometry.segment_bounds,
                geometry.segment_one_sided, geometry.circles,
            )  # fmt: skip
            push *= min(t, 1.0)
            if push > 0.0:
                x += nx * push
                y += ny * push
                moved = True
        if not moved:
            break
    return x, y


@njit(cache=True)
def hold_flippers(x, y, r, flippers, angle, omegas, stops, targets, elapsed, pushers, pinch):
    """Stop, at ``elapsed`` seconds into the substep, every flipper still turning that could
    reach a wedged ball at (x, y) (``contact.release_wedge``: or it would sweep through the ball
    unchecked): its stop moves to now, its target to its angle now. Where ``pinch`` is set, a
    flipper that pushed into the ball (bit j of ``pushers``) stalls where it started the
    substep (as ``step_ball`` does for a pinched ball). Returns whether one did (the ball is
    pinched)."""
    pinched = False
    for j in range(flippers.shape[0]):
        if omegas[j] != 0.0 and stops[j] > elapsed and within_reach(x, y, r, flippers[j]):
            stops[j] = elapsed
            targets[j] = flipper_angle_at(angle[j], omegas[j], stops[j], elapsed)
            if (pushers >> j) & 1 == 1:
                pinched = True
                if pinch:
                    stops[j] = 0.0
                    targets[j] = angle[j]
    return pinched


@njit(cache=True)
def wedge(ball, w, remaining, h, geometry, angle, omegas, stops, targets, angles, r, skin, cut):
    """Ball ``ball`` (its bookkeeping row ``w``) stops moving for the rest of the substep,
    ``remaining`` seconds before its end, as a wedged ball does in ``step.step_ball``: unless
    its flipper sweep was cut, it is cleared of its last two elements (``contact.unwedge``); the
    flippers that could reach it stop where they are, and where one of them pushed into it
    the ball is pinched: at rest, the pushing flippers stalled where they started the substep
    (:func:`hold_flippers`)."""
    w[W_MOVING] = 0.0
    w[W_WEDGED] = 1.0
    w[W_CHECK] = 1.0
    w[W_LAST_REM] = remaining
    elapsed = h - remaining
    flippers = geometry.flippers
    if not cut and w[W_BEFORE] >= 0.0:
        for j in range(flippers.shape[0]):
            angles[j] = flipper_angle_at(angle[j], omegas[j], stops[j], elapsed)
        ball[BALL_X], ball[BALL_Y] = unwedge(
            ball[BALL_X], ball[BALL_Y], int(w[W_LAST]), w[W_LAST_NX], w[W_LAST_NY],
            int(w[W_BEFORE]), w[W_BEFORE_NX], w[W_BEFORE_NY], geometry, angles, r, skin,
        )  # fmt: skip
    pushers = int(w[W_PUSHERS])
    if hold_flippers(ball[BALL_X], ball[BALL_Y], r, flippers, angle, omegas, stops, targets,
                     elapsed, pushers, not cut) and not cut:  # fmt: skip
        ball[BALL_VX] = ball[BALL_VY] = ball[BALL_SPIN] = 0.0


@njit(cache=True)
def separate(ball, nx, ny, push, r, skin, geometry):
    """Move ``ball`` (a row of ``State.balls``) by ``push`` along n, away from the ball
    it touched. A push of up to a skin is made as it is (the ball, at least r off every
    surface, stays out of them); a longer one (balls that overlapped deeply, or a ball pushed
    off a fixed one) is swept against the walls and posts, as a swinging flipper's push is in
    ``step_ball``, and stops a skin short of the first it would touch."""
    if push > skin:
        t, _, _, _ = earliest_static_contact(
            ball[BALL_X], ball[BALL_Y], nx * push, ny * push, r + skin, geometry.segments,
            geometry.segment_bounds, geometry.segment_one_sided, geometry.circles,
        )  # fmt: skip
        push *= min(t, 1.0)
    ball[BALL_X] += nx * push
    ball[BALL_Y] += ny * push
    return push


@njit(cache=True)
def cross_lines(state, env, geometry, x, y, vx, vy, dt, start):
    """The spinner and kickback lines of env ``env`` that a ball moving from (x, y) at
    (vx, vy) for ``dt`` seconds, from ``start`` [s into the frame], crosses: each spinner it
    crosses is spun (``targets.spin_spinner``), each dark kickback crossed against its kick is
    a hit (``targets.count_kickbacks``). (A lit one is an event of the ball: the move ends on
    its line, see :func:`step_balls`.)"""
    kickbacks, lit = geometry.kickbacks, state.kickback_lit[env]
    if kickbacks.shape[0] > 0:
        count_kickbacks(state, env, x, y, vx, vy, dt, kickbacks, lit, first_kickback(geometry),
                        start + dt)  # fmt: skip
    spinners = geometry.spinners
    for j in range(spinners.shape[0]):
        u = sensor_crossing(x, y, vx * dt, vy * dt, spinners[j])
        if u < INF:
            spin_spinner(spinners[j], state.spinners[env, j], vx, vy, start + dt * u)
