"""Several balls in one env (multiball): the frame step by swept collision with
ball-ball contact, a kernel path of its own: ``sim.World`` steps a table of several balls (or
with saucers or locks) with it; the game (``game.multiball``) serves several balls from the
trough.

What it holds:

- the balls are ``data.State``'s slots, ``(N, M, BALL_STATE_SIZE)``, whether each is in play
  and whether it is held (in a lock or saucer: it does not move and is a fixed circle), as for
  ``step.step_ball`` (which steps slot 0 of a one-ball table); ``data.Scratch`` has each slot's
  candidate set (``physics.near``), its cached earliest element contact and its bookkeeping
  over a substep (columns ``EV_*`` and ``W_*`` of ``physics.columns``);
- :func:`step_balls`: one env's frame with M balls; :func:`step_multiworld`: the envs of a batch;
- ``multiball_parts``: the overlap and settle of ``contact.deepest_overlap`` and
  ``contact.settle`` with the other balls counted (as circles of radius 2r at their centres), a
  wedged ball's stop, the separation of two balls, the lines a ball crosses;
- ``MultiWorld``, :func:`make_multiball`, :func:`place`, :func:`step_multiball`: a Python
  helper to build and step a multi-ball world (for the kernel's tests; ``sim.World`` holds the
  same arrays and steps them bitwise the same).

Which kernel steps a World is decided once, when it is built (``sim.World``): this one for a
table of several balls (or with saucers or locks), ``step.step_world`` for the others, so every
one-ball game stays bitwise what it was.

The step. Per substep: the flipper schedule as ``step_ball`` has it; gravity (and the
cabinet's frame force) on every free ball; then an event loop over the substep's time. In
each pass every moving ball's earliest contact with the table over the time left is found
(walls, posts, flippers, standing drop targets: the very sweeps of ``step_ball``, over the
ball's own candidate set), and every pair's ``balls.sweep_ball_ball`` (two moving circles are,
in their relative motion, a point against a circle of radius 2r; a held or frozen ball is a
fixed circle). The earliest event wins (ties: element contacts before pairs, then the lower
ball index); every moving ball advances to its time (crossing sensors on the way: a drain
crossing takes a ball out of play there); only the ball(s) of the event respond, as
``step_ball`` does for an element, with ``balls.respond_ball_ball`` for a pair (the pair's
restitution, zero below ``resting_speed``; its friction), and are separated: a skin off the
element, or to 2r + skin apart, half each (all on the free one where the other is fixed; a
push longer than a skin, off a deep overlap, is swept against the walls and posts:
:func:`separate`).
A ball's element contact stays valid while the ball keeps its path (it is cached, and found
anew only for a ball that responded, or when a flipper was stopped), so a pass costs one
element sweep per responding ball and one cheap pair test per pair.

The passes end when the substep's time is used, or at the pass cap ``max_passes`` per moving
ball (summed): then every ball still moving stops for the rest of the substep, as a wedged ball
does in ``step_ball``. A ball whose own events make no progress MAX_STALLED_PASSES times in a
row is wedged and stops alone (the others go on; it is a fixed circle to them). A wedged
ball is unwedged from its last two elements, the flippers that could reach it are stopped
where they are, and a ball pinched by a pushing flipper is put at rest (``contact.release_wedge``).
At the substep's end every ball that was wedged, touched a turning flipper or another ball, or
started the substep inside another, is checked: one left deeper than the skin in an element or
another ball is settled out (:func:`settle_balls`), and where there is no room it is put back
where it started the substep (if that is clear of the other balls), at rest, and the flippers
within its reach stop.

Sensors, spinners and dark kickbacks are crossed on each ball's moves (:func:`cross_lines`); a
lit kickback's line is an event of the ball that crosses it (it fires: the ball leaves at the
kick). A drop target hit drops at the end of the substep; a bank rises only when no ball in
play is within a radius of it (``targets.raise_banks``).

Differences from ``step_ball`` (the games use it as it is; Pinball-v3): contacts
between balls are not logged in ``State.contacts`` nor counted in ``State.hits`` (they have no
element id); hits are counted when they happen (``step_ball`` drops those of a pinched
substep); a wedged ball stops the flippers near it at once, where ``step_ball`` holds them for
the rest of the substep (the same, with one ball).
"""

import math
from dataclasses import dataclass

import numpy as np
from numba import njit

from pinball_env.physics.balls import respond_ball_ball, sweep_ball_ball
from pinball_env.physics.cabinet import cabinet_frame
from pinball_env.physics.columns import (
    BALL_SPIN,
    BALL_VX,
    BALL_VY,
    BALL_X,
    BALL_Y,
    EV_CUT,
    EV_ELEMENT,
    EV_NX,
    EV_NY,
    EV_REMAINING,
    EV_SVX,
    EV_SVY,
    EV_USED,
    EV_VALID,
    FLIPPER_REST_ANGLE,
    KICKBACK_VX,
    KICKBACK_VY,
    PROP_FRICTION,
    PROP_KICK,
    PROP_RESTITUTION,
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
    W_STALLED,
    W_X0,
    W_Y0,
)
from pinball_env.physics.contact import (
    FLIPPER_CONTACT_TOLERANCE,
    MAX_STALLED_PASSES,
    MIN_PROGRESS,
    deepest_overlap,
    earliest_contact,
    earliest_static_contact,
    element_props,
    flipper_angle_at,
    flipper_end,
    flipper_motion,
    is_hit,
    respond,
    surface_distance,
    within_reach,
)
from pinball_env.physics.data import (
    Geometry,
    Scratch,
    Settings,
    State,
    first_drop_target,
    first_flipper,
    first_kickback,
    log_contact,
    make_scratch,
    make_state,
)
from pinball_env.physics.multiball_parts import (
    ball_overlap,
    cross_lines,
    separate,
    settle_balls,
    wedge,
)
from pinball_env.physics.near import (
    NEAR_DROP_TARGETS,
    NEAR_SENSORS,
)
from pinball_env.physics.sweep import INF, norm
from pinball_env.physics.targets import (
    kickback_crossing,
    record_near_crossings,
    update_targets,
)

# --- the step --------------------------------------------------------------------------------


# Long by design, as step.step_ball: the hot loop of a multi-ball frame, written out, since
# numba counts a reference to every array a compiled function receives, and helpers taking
# arrays in the pass loop cost more than the physics.
@njit(cache=True, inline="always")
def step_balls(geometry, settings, state, scratch, pair, env):
    """Advance env ``env`` by one frame in place with its M ball slots: its
    flippers and every ball in play (module docstring). ``pair`` is the ball-ball material,
    a ``PROP_SIZE`` row (restitution, friction; the kick is not used). Returns whether every
    ball's state is finite afterwards."""
    flipper_id = first_flipper(geometry)
    h = settings.dt / settings.substeps
    r = settings.radius
    skin = settings.skin
    tol = FLIPPER_CONTACT_TOLERANCE * skin
    reach2 = 2.0 * r
    segments, bounds = geometry.segments, geometry.segment_bounds
    one_sided, circles = geometry.segment_one_sided, geometry.circles
    flippers = geometry.flippers
    n_flippers = flippers.shape[0]
    gravity = norm(settings.gravity_x, settings.gravity_y)
    balls, active, fixed = state.balls[env], state.active[env], state.held[env]
    n_balls = balls.shape[0]
    near, near_ends, zone = scratch.near[env], scratch.near_ends[env], scratch.near_zone[env]
    events, work, dropped = scratch.events[env], scratch.work[env], scratch.dropped[env]
    angle, omega = state.flipper_angle[env], state.flipper_omega[env]
    targets, omegas, stops = scratch.targets[env], scratch.omegas[env], scratch.stops[env]
    angles, pass_stops = scratch.angles[env], scratch.pass_stops[env]
    up = state.targets_up[env]
    state.contact_count[env] = 0
    state.hits[env, :] = 0
    scratch.passes[env] = 0
    has_cabinet = geometry.cabinet.shape[0] > 0
    cabinet_dv = scratch.cabinet_dv[env]
    dvx = dvy = 0.0
    if has_cabinet:
        cabinet_frame(state.cabinet[env], geometry.cabinet[0], h, cabinet_dv)
    kick_scale = 0.0 if state.tilted[env] else 1.0
    n_targets = geometry.drop_targets.shape[0]
    target_id = first_drop_target(geometry)
    n_kickbacks = geometry.kickbacks.shape[0]
    n_lines = geometry.spinners.shape[0] + n_kickbacks
    kickback_id = first_kickback(geometry)
    pair_restitution, pair_friction = pair[PROP_RESTITUTION], pair[PROP_FRICTION]
    for k in range(settings.substeps):
        for j in range(n_flippers):
            targets[j], omegas[j], stops[j] = flipper_motion(
                flippers[j], angle[j], state.flipper_command[env, j]
            )
        if has_cabinet:
            dvx, dvy = cabinet_dv[k, 0], cabinet_dv[k, 1]
        moving = 0
        for i in range(n_balls):
            w = work[i]
            w[:] = 0.0
            w[W_X0], w[W_Y0] = balls[i, BALL_X], balls[i, BALL_Y]
            w[W_LAST] = w[W_BEFORE] = -1.0
            w[W_LAST_REM] = h
            events[i, EV_VALID] = 0.0
            if active[i] and not fixed[i]:
                w[W_MOVING] = 1.0
                moving += 1
                balls[i, BALL_VX] += settings.gravity_x * h - dvx
                balls[i, BALL_VY] += settings.gravity_y * h - dvy
                # A ball that starts the substep in another (placed there) is settled at its end.
                if ball_overlap(balls[i, BALL_X], balls[i, BALL_Y], i, balls, active, r) > skin:
                    w[W_CHECK] = 1.0
        remaining = h
        cap = settings.max_passes * moving
        passes = 0
        while remaining > 0.0 and moving > 0:
            if passes >= cap:  # the pass cap: every ball still moving stops where it is
                for i in range(n_balls):
                    if work[i, W_MOVING] == 1.0:
                        wedge(balls[i], work[i], remaining, h, geometry, angle, omegas, stops,
                              targets, angles, r, skin, False)  # fmt: skip
                moving = 0
                break
            passes += 1
            scratch.passes[env] += 1
            elapsed = h - remaining
            for j in range(n_flippers):
                angles[j] = flipper_angle_at(angle[j], omegas[j], stops[j], elapsed)
                pass_stops[j] = max(stops[j] - elapsed, 0.0)
            # Each moving ball's earliest element contact (cached while it keeps its path).
            best = INF
            best_i = best_j = -1
            for i in range(n_balls):
                if work[i, W_MOVING] == 0.0:
                    continue
                ev = events[i]
                x, y, vx, vy = (
                    balls[i, BALL_X],
                    balls[i, BALL_Y],
                    balls[i, BALL_VX],
                    balls[i, BALL_VY],
                )
                if ev[EV_VALID] == 0.0:
                    nr, ne = near[i], near_ends[i]
                    t, nx, ny, svx, svy, element, cut = earliest_contact(
                        state, env, geometry, x, y, vx, vy, remaining, r, skin, gravity, tol,
                        angles, omegas, pass_stops, nr, ne, zone[i], flipper_id,
                    )  # fmt: skip
                    used = remaining * min(t, 1.0)
                    if n_kickbacks > 0:  # a lit kickback's line on the way: it fires there
                        kicked, u = kickback_crossing(
                            x, y, vx, vy, used, geometry.kickbacks, state.kickback_lit[env]
                        )
                        if kicked >= 0:
                            used *= u
                            element, cut = kickback_id + kicked, False
                    ev[EV_VALID] = 1.0
                    ev[EV_USED] = used
                    ev[EV_REMAINING] = remaining
                    ev[EV_NX], ev[EV_NY], ev[EV_SVX], ev[EV_SVY] = nx, ny, svx, svy
                    ev[EV_ELEMENT] = element
                    ev[EV_CUT] = 1.0 if cut else 0.0
                if ev[EV_ELEMENT] < 0.0 and ev[EV_CUT] == 0.0:
                    continue  # a free path to the substep's end
                if ev[EV_REMAINING] == remaining:
                    dt = ev[EV_USED]
                else:  # found in an earlier pass: the same contact, so much later
                    dt = max(remaining - (ev[EV_REMAINING] - ev[EV_USED]), 0.0)
                if dt < best:
                    best, best_i, best_j = dt, i, -1
            # Every pair's contact, a fixed ball (held, wedged) not moving.
            for i in range(n_balls):
                if not active[i]:
                    continue
                mi = remaining if work[i, W_MOVING] == 1.0 else 0.0
                for j in range(i + 1, n_balls):
                    if not active[j]:
                        continue
                    mj = remaining if work[j, W_MOVING] == 1.0 else 0.0
                    if mi == 0.0 and mj == 0.0:
                        continue
                    t, _, _ = sweep_ball_ball(
                        balls[i, BALL_X], balls[i, BALL_Y], balls[i, BALL_VX] * mi,
                        balls[i, BALL_VY] * mi, balls[j, BALL_X], balls[j, BALL_Y],
                        balls[j, BALL_VX] * mj, balls[j, BALL_VY] * mj, reach2,
                    )  # fmt: skip
                    if t < INF and remaining * t < best:
                        best, best_i, best_j = remaining * t, i, j
            # Every moving ball advances to the event (or the substep's end), crossing sensors.
            dt = min(best, remaining)
            for i in range(n_balls):
                if work[i, W_MOVING] == 0.0:
                    continue
                x, y, vx, vy = (
                    balls[i, BALL_X],
                    balls[i, BALL_Y],
                    balls[i, BALL_VX],
                    balls[i, BALL_VY],
                )
                nr, ne = near[i], near_ends[i]
                if n_lines > 0:
                    cross_lines(state, env, geometry, x, y, vx, vy, dt, k * h + elapsed)
                drain = record_near_crossings(
                    state, env, geometry, x, y, vx * dt, vy * dt, k * h + elapsed, dt,
                    scratch.crossings[env], nr, ne[NEAR_DROP_TARGETS], ne[NEAR_SENSORS],
                )  # fmt: skip
                if drain < INF:
                    balls[i, BALL_X] = x + vx * dt * drain
                    balls[i, BALL_Y] = y + vy * dt * drain
                    active[i] = False
                    work[i, W_MOVING] = 0.0
                    work[i, W_CHECK] = 0.0
                    moving -= 1
                    continue
                balls[i, BALL_X] = x + vx * dt
                balls[i, BALL_Y] = y + vy * dt
            remaining -= dt
            if best_i < 0 or not active[best_i] or (best_j >= 0 and not active[best_j]):
                continue  # no event, or a ball of it drained on the way
            if best_j < 0:
                # An element contact of ball best_i: step_ball's response and separation.
                i = best_i
                ev, w, ball = events[i], work[i], balls[i]
                ev[EV_VALID] = 0.0
                element = int(ev[EV_ELEMENT])
                if element >= kickback_id:  # a kickback fires, if still lit: the ball's kick
                    lit = state.kickback_lit[env]
                    if lit[element - kickback_id]:
                        kick = geometry.kickbacks[element - kickback_id]
                        ball[BALL_VX], ball[BALL_VY], ball[BALL_SPIN] = (
                            kick[KICKBACK_VX], kick[KICKBACK_VY], 0.0
                        )  # fmt: skip
                        state.hits[env, element] += 1
                        log_contact(state, env, element, k * h + h - remaining, 0.0)
                        lit[element - kickback_id] = False
                    continue
                if ev[EV_CUT] == 1.0:  # a cut drops the rest of its substep, as a wedge does
                    wedge(ball, w, remaining, h, geometry, angle, omegas, stops, targets, angles,
                          r, skin, True)  # fmt: skip
                    moving -= 1
                    events[:, EV_VALID] = 0.0  # flippers may have stopped
                    continue
                nx, ny, svx, svy = ev[EV_NX], ev[EV_NY], ev[EV_SVX], ev[EV_SVY]
                props = element_props(element, geometry)
                vx, vy, spin, speed = respond(
                    ball[BALL_VX], ball[BALL_VY], ball[BALL_SPIN], nx, ny, svx, svy, r,
                    props[PROP_RESTITUTION], props[PROP_FRICTION], kick_scale * props[PROP_KICK],
                    settings.resting_speed,
                )  # fmt: skip
                ball[BALL_VX], ball[BALL_VY], ball[BALL_SPIN] = vx, vy, spin
                for j in range(n_flippers):
                    angles[j] = flipper_angle_at(angle[j], omegas[j], stops[j], h - remaining)
                x, y = ball[BALL_X], ball[BALL_Y]
                push = r + skin - surface_distance(x, y, element, geometry, angles)
                on_flipper = flipper_id <= element < flipper_id + n_flippers  # not a target
                if on_flipper and push > 0.0 and svx * nx + svy * ny > 0.0:
                    t_push, _, _, _ = earliest_static_contact(
                        x, y, nx * push, ny * push, r + skin, segments, bounds, one_sided,
                        circles,
                    )  # fmt: skip
                    push *= min(t_push, 1.0)
                ball[BALL_X], ball[BALL_Y] = x + nx * push, y + ny * push
                if element != w[W_LAST]:
                    w[W_BEFORE], w[W_BEFORE_NX], w[W_BEFORE_NY] = (
                        w[W_LAST],
                        w[W_LAST_NX],
                        w[W_LAST_NY],
                    )
                w[W_LAST], w[W_LAST_NX], w[W_LAST_NY] = element, nx, ny
                log_contact(state, env, element, k * h + h - remaining, speed)
                if is_hit(speed, kick_scale * props[PROP_KICK], settings.resting_speed):
                    state.hits[env, element] += 1
                    if target_id <= element < target_id + n_targets:
                        dropped[element - target_id] = True
                if on_flipper and svx * nx + svy * ny > 0.0:
                    w[W_PUSHERS] = int(w[W_PUSHERS]) | (1 << (element - flipper_id))
                if on_flipper and omegas[element - flipper_id] != 0.0:
                    w[W_CHECK] = 1.0
                involved_a, involved_b = i, -1
            else:
                # A pair: the equal-mass impulse, then apart to 2r + skin.
                i, j = best_i, best_j
                a, b = balls[i], balls[j]
                a_fixed = work[i, W_MOVING] == 0.0
                b_fixed = work[j, W_MOVING] == 0.0
                gx, gy = a[BALL_X] - b[BALL_X], a[BALL_Y] - b[BALL_Y]
                d = norm(gx, gy)
                if d > 0.0:
                    nx, ny = gx / d, gy / d
                else:  # coincident centres: against a's motion relative to b
                    rvx, rvy = a[BALL_VX] - b[BALL_VX], a[BALL_VY] - b[BALL_VY]
                    speed = norm(rvx, rvy)
                    nx, ny = (-rvx / speed, -rvy / speed) if speed > 0.0 else (0.0, 1.0)
                vn = (a[BALL_VX] - b[BALL_VX]) * nx + (a[BALL_VY] - b[BALL_VY]) * ny
                e = pair_restitution if -vn >= settings.resting_speed else 0.0
                (a[BALL_VX], a[BALL_VY], a[BALL_SPIN], b[BALL_VX], b[BALL_VY],
                 b[BALL_SPIN]) = respond_ball_ball(
                    a[BALL_VX], a[BALL_VY], a[BALL_SPIN], b[BALL_VX], b[BALL_VY], b[BALL_SPIN],
                    nx, ny, r, e, pair_friction, a_fixed, b_fixed,
                )  # fmt: skip
                push = reach2 + skin - d
                if push > 0.0:
                    share_a = 0.0 if a_fixed else (1.0 if b_fixed else 0.5)
                    separate(a, nx, ny, push * share_a, r, skin, geometry)
                    separate(b, -nx, -ny, push * (1.0 - share_a), r, skin, geometry)
                events[i, EV_VALID] = events[j, EV_VALID] = 0.0
                work[i, W_CHECK] = work[j, W_CHECK] = 1.0
                involved_a, involved_b = (-1 if a_fixed else i), (-1 if b_fixed else j)
            # The stall guard of each ball of the event: no progress since its last event.
            for i in (involved_a, involved_b):
                if i < 0:
                    continue
                w = work[i]
                w[W_STALLED] = (
                    w[W_STALLED] + 1 if w[W_LAST_REM] - remaining <= MIN_PROGRESS * h else 0
                )
                w[W_LAST_REM] = remaining
                if w[W_STALLED] >= MAX_STALLED_PASSES:
                    wedge(balls[i], w, remaining, h, geometry, angle, omegas, stops, targets,
                          angles, r, skin, False)  # fmt: skip
                    moving -= 1
                    events[:, EV_VALID] = 0.0  # flippers may have stopped
        # The substep's end: settle a ball left deeper than the skin in an element or a ball.
        for i in range(n_balls):
            if work[i, W_CHECK] == 0.0 or not active[i] or fixed[i]:
                continue
            for j in range(n_flippers):
                angles[j], _ = flipper_end(angle[j], targets[j], omegas[j], stops[j], False, h, h)
            ball = balls[i]
            x, y = ball[BALL_X], ball[BALL_Y]
            deep = max(deepest_overlap(x, y, geometry, angles, up, r),
                       ball_overlap(x, y, i, balls, active, r))  # fmt: skip
            if deep <= skin:
                continue
            x, y = settle_balls(x, y, i, balls, active, geometry, angles, up, r, skin)
            deep = max(deepest_overlap(x, y, geometry, angles, up, r),
                       ball_overlap(x, y, i, balls, active, r))  # fmt: skip
            if deep > skin:
                # No room: back where it started the substep (if that is clear of the balls),
                # at rest, and the flippers within its reach stall where they started.
                x0, y0 = work[i, W_X0], work[i, W_Y0]
                if ball_overlap(x0, y0, i, balls, active, r) <= skin:
                    x, y = x0, y0
                ball[BALL_VX] = ball[BALL_VY] = ball[BALL_SPIN] = 0.0
                for j in range(n_flippers):
                    if omegas[j] != 0.0 and within_reach(x, y, r, flippers[j]):
                        stops[j], targets[j] = 0.0, angle[j]
            ball[BALL_X], ball[BALL_Y] = x, y
        for j in range(n_targets):
            if dropped[j]:
                up[j] = False
                dropped[j] = False
        for j in range(n_flippers):
            angle[j], omega[j] = flipper_end(angle[j], targets[j], omegas[j], stops[j], False, h, h)
    if n_targets > 0 or geometry.spinners.shape[0] > 0:
        update_targets(geometry, state, env, balls, active, r, settings.dt)
    finite = True
    for i in range(n_balls):
        b = balls[i]
        finite = finite and math.isfinite(
            b[BALL_X] + b[BALL_Y] + b[BALL_VX] + b[BALL_VY] + b[BALL_SPIN]
        )
    return finite


@njit(cache=True, nogil=True, _nrt=False)  # type: ignore[call-overload]  # _nrt: not in the stubs
def step_multiworld(geometry, settings, state, scratch, pair, moving, start, stop):
    """:func:`step_balls` for the envs from ``start`` to ``stop`` for which ``moving`` is set
    (``step.step_world``'s contract). Returns the number of stepped envs with a ball whose
    state is not finite afterwards."""
    faults = 0
    for env in range(start, stop):
        if moving[env] and not step_balls(geometry, settings, state, scratch, pair, env):
            faults += 1
    return faults


# --- a Python helper ---------------------------------------------------------------------------


@dataclass
class MultiWorld:
    """A multi-ball world's arrays: the packed table, the state and scratch (``n_balls`` slots
    per env) and the ball-ball material (a ``PROP_SIZE`` row)."""

    geometry: Geometry
    settings: Settings
    state: State
    scratch: Scratch
    pair: np.ndarray

    @property
    def n_envs(self) -> int:
        return self.state.balls.shape[0]


def make_multiball(
    table, n_envs: int, n_balls: int, pair: tuple[float, float] | None = None
) -> MultiWorld:
    """A multi-ball world of ``n_envs`` envs with ``n_balls`` slots each on ``table``: no ball
    in play, flippers at rest, drop targets up, kickbacks as the table has them. ``pair`` is the
    ball-ball (restitution, friction); by default the table's (``Table.pack_ball_pair``)."""
    geometry, settings = table.pack(), table.pack_settings()
    state = make_state(geometry, n_envs, n_balls)
    state.flipper_angle[:] = geometry.flippers[:, FLIPPER_REST_ANGLE]
    for env in range(n_envs):
        state.kickback_lit[env] = [k.lit for k in table.kickbacks]
    props = table.pack_ball_pair()
    if pair is not None:
        props[PROP_RESTITUTION], props[PROP_FRICTION] = pair
    scratch = make_scratch(geometry, settings, n_envs, n_balls)
    return MultiWorld(geometry, settings, state, scratch, props)


def place(
    world: MultiWorld,
    env: int,
    ball: int,
    position: tuple[float, float],
    velocity: tuple[float, float] = (0.0, 0.0),
    held: bool = False,
) -> None:
    """Put ball slot ``ball`` of env ``env`` in play at ``position`` with ``velocity``, no spin
    (``held``: fixed where it is)."""
    row = world.state.balls[env, ball]
    row[:] = 0.0
    row[BALL_X], row[BALL_Y] = position
    row[BALL_VX], row[BALL_VY] = velocity
    world.state.active[env, ball] = True
    world.state.held[env, ball] = held


def step_multiball(world: MultiWorld, moving: np.ndarray | None = None) -> int:
    """Advance every env of ``world`` (or those ``moving`` sets) by one frame; returns the
    number of envs with a non-finite ball state."""
    if moving is None:
        moving = np.ones(world.n_envs, dtype=np.bool_)
    return step_multiworld(
        world.geometry, world.settings, world.state, world.scratch, world.pair, moving, 0,
        world.n_envs,
    )  # fmt: skip
