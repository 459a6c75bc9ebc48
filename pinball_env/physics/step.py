"""The world step: advance a batch of balls (one per env) through the table by swept collision.

Every state array has a leading env axis, so the single env is a batch of one and a vector env
calls the very same kernel, :func:`step_world`, whose body for one env is :func:`step_ball`.
Each frame of length ``dt`` is cut into fixed substeps. In a substep the flippers follow their
commands (kinematic: a constant angular speed towards the stop the command selects, see
:func:`flipper_motion`), gravity updates the ball's velocity (semi-implicit Euler), then the ball
sweeps along its straight path and stops at the earliest contact over all walls, posts and
flippers (ties go to the lowest element id: :func:`near_static_contact`,
:func:`earliest_flipper_contact`; only the ball's candidate set is swept, ``physics.near``,
which holds every element its path can touch), responds, and sweeps the remaining time again:
the contact passes. A pass cap and a minimum-progress rule end the passes for a wedged ball:
the rest of that substep is dropped, never skipped over, so the ball can stall for an instant
but cannot tunnel; a flipper pushing a wedged ball stalls too, as a real coil does
(:func:`release_wedge`).
Only a turning flipper or a wedge can leave the ball inside a surface, so after a substep in
which the ball touched a turning flipper or was wedged, its deepest overlap is measured
(:func:`deepest_overlap`); a ball deeper than the skin is pushed clear (:func:`settle`), and
where no room is left (a pocket that turning flippers close on the ball) the substep is undone:
the ball is put back, at rest, and the flippers that could reach it stall where they started
it. A sound state thus stays sound, substep by substep. A
flipper sweep that runs out of slices (an absurd speed) ends the substep the same way, so the
work of a frame is bounded whatever the state. Sensors (rollovers, the drain) are crossed, not
collided with: a crossing of the ball's centre is an event, and a drain crossing takes the ball
out of play (``targets.record_crossings``).

The parts of a pass (the contact search, the response, the wedge rules) are
``physics.contact``'s.
"""

import math

from numba import njit

from pinball_env.physics.cabinet import cabinet_frame
from pinball_env.physics.columns import (
    BALL_SPIN,
    BALL_VX,
    BALL_VY,
    BALL_X,
    BALL_Y,
    KICKBACK_VX,
    KICKBACK_VY,
    PROP_FRICTION,
    PROP_KICK,
    PROP_RESTITUTION,
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
    release_wedge,
    respond,
    settle,
    surface_distance,
    unwedge,
    within_reach,
)
from pinball_env.physics.data import (
    first_drop_target,
    first_flipper,
    log_contact,
)
from pinball_env.physics.near import (
    NEAR_DROP_TARGETS,
    NEAR_SENSORS,
)
from pinball_env.physics.sweep import (
    INF,
    norm,
)
from pinball_env.physics.targets import (
    cross_target_lines,
    record_near_crossings,
    update_targets,
)


@njit(cache=True, inline="always")
def step_ball(geometry, settings, state, scratch, env, flipper_id):
    """Advance env ``env`` by one frame in place: its flippers, and its ball if in play.
    Returns whether the ball's state is finite afterwards.

    ``flipper_id`` is the first flipper's element id. Per substep: the flipper schedule,
    gravity, the contact passes (sweep to the earliest contact, count the sensors crossed on
    the way, respond, separate, sweep the time left), the wedge release, and the flippers
    moved to the end of the substep.

    The pass loop is written out here, calling the sweeps over the table's arrays and helpers
    that take numbers (or that run only on a contact or a crossing): numba counts a reference
    to every array that a compiled function receives or takes out of a tuple, inlined or not,
    and more helpers taking arrays in this loop cost more than the physics (measured: 4-5x
    slower per ball-frame).
    """
    h = settings.dt / settings.substeps
    r = settings.radius
    tol = FLIPPER_CONTACT_TOLERANCE * settings.skin
    segments, bounds = geometry.segments, geometry.segment_bounds
    one_sided, circles = geometry.segment_one_sided, geometry.circles
    flippers = geometry.flippers
    n_flippers = flippers.shape[0]
    skin = settings.skin
    gravity = norm(settings.gravity_x, settings.gravity_y)
    # A table of one ball: its slot 0 (``data.State``).
    near, near_ends = scratch.near[env, 0], scratch.near_ends[env, 0]
    zone = scratch.near_zone[env, 0]
    angle, omega = state.flipper_angle, state.flipper_omega
    targets, omegas, stops = scratch.targets[env], scratch.omegas[env], scratch.stops[env]
    angles, pass_stops = scratch.angles[env], scratch.pass_stops[env]
    held, hit_elements = scratch.held[env], scratch.hit_elements[env]
    state.contact_count[env] = 0
    state.hits[env, :] = 0
    # The cabinet, on a table with one: its frame first (the velocity change of each substep),
    # then the ball's substeps. A tilted machine's kickers are dead.
    has_cabinet = geometry.cabinet.shape[0] > 0
    cabinet_dv = scratch.cabinet_dv[env]
    dvx = dvy = 0.0
    if has_cabinet:
        cabinet_frame(state.cabinet[env], geometry.cabinet[0], h, cabinet_dv)
    kick_scale = 0.0 if state.tilted[env] else 1.0
    # Targets and their kin, on a table with them (``physics.targets``): each pass calls two
    # helpers for them, only there (a call in the pass loop costs every table, taken or not).
    n_targets = geometry.drop_targets.shape[0]
    n_lines = geometry.spinners.shape[0] + geometry.kickbacks.shape[0]
    has_targets = n_targets + n_lines > 0
    target_id = first_drop_target(geometry)
    ball = state.balls[env, 0]
    x, y, vx, vy, spin = ball[BALL_X], ball[BALL_Y], ball[BALL_VX], ball[BALL_VY], ball[BALL_SPIN]
    for k in range(settings.substeps):
        # The flipper schedule: each flipper's motion over the substep.
        for j in range(n_flippers):
            targets[j], omegas[j], stops[j] = flipper_motion(
                flippers[j], angle[env, j], state.flipper_command[env, j]
            )
            held[j] = False
        held_time = h
        x0, y0 = x, y
        if has_cabinet:
            dvx, dvy = cabinet_dv[k, 0], cabinet_dv[k, 1]
        if state.active[env, 0]:
            # Relative to the cabinet, the ball feels its acceleration opposite (a frame force).
            vx += settings.gravity_x * h - dvx
            vy += settings.gravity_y * h - dvy
            remaining = h
            stalled = n_hits = 0
            pushers = 0  # bit j: flipper j pushed into the ball in this substep
            turning_contact = False  # the ball touched a turning flipper in this substep
            cut = False
            # The last two different elements touched, and their normals (for a wedge).
            last, last_nx, last_ny, before, before_nx, before_ny = -1, 0.0, 0.0, -1, 0.0, 0.0
            for _ in range(settings.max_passes):
                if remaining <= 0.0:
                    break
                elapsed = h - remaining
                for j in range(n_flippers):
                    angles[j] = flipper_angle_at(angle[env, j], omegas[j], stops[j], elapsed)
                    pass_stops[j] = max(stops[j] - elapsed, 0.0)
                t, nx, ny, svx, svy, element, cut = earliest_contact(
                    state, env, geometry, x, y, vx, vy, remaining, r, skin, gravity, tol, angles,
                    omegas, pass_stops, near, near_ends, zone, flipper_id,
                )  # fmt: skip
                kicked = -1
                if has_targets:  # spinners, kickbacks: see physics.targets
                    used = remaining * min(t, 1.0)
                    kicked, used = cross_target_lines(
                        state, env, geometry, x, y, vx, vy, used, k * h + h - remaining
                    )
                else:
                    used = remaining * min(t, 1.0)
                # Sensor crossings on the way to the contact (or to the end of the substep).
                drain = record_near_crossings(
                    state, env, geometry, x, y, vx * used, vy * used, k * h + elapsed, used,
                    scratch.crossings[env], near, near_ends[NEAR_DROP_TARGETS],
                    near_ends[NEAR_SENSORS],
                )  # fmt: skip
                if drain < INF:
                    x += vx * used * drain
                    y += vy * used * drain
                    state.active[env, 0] = False
                    break
                x += vx * used
                y += vy * used
                remaining -= used
                if kicked >= 0:  # a lit kickback fired: the ball leaves its line at the kick
                    kick = geometry.kickbacks[kicked]
                    vx, vy, spin = kick[KICKBACK_VX], kick[KICKBACK_VY], 0.0
                    continue
                if element < 0 or cut:  # a cut drops the rest of the substep, as a wedge does
                    break
                props = element_props(element, geometry)
                vx, vy, spin, speed = respond(
                    vx, vy, spin, nx, ny, svx, svy, r,
                    props[PROP_RESTITUTION], props[PROP_FRICTION], kick_scale * props[PROP_KICK],
                    settings.resting_speed,
                )  # fmt: skip
                # Separation: leave the ball exactly skin off the surface it touched.
                for j in range(n_flippers):
                    angles[j] = flipper_angle_at(angle[env, j], omegas[j], stops[j], h - remaining)
                push = r + settings.skin - surface_distance(x, y, element, geometry, angles)
                if element >= flipper_id and push > 0.0 and svx * nx + svy * ny > 0.0:
                    # A swinging flipper's push is swept against the walls and posts, so that a
                    # ball squeezed between them stays out of the wall (and the flipper,
                    # blocked, stalls): the ball stops a skin short of the first it would touch.
                    t_push, _, _, _ = earliest_static_contact(
                        x, y, nx * push, ny * push, r + settings.skin, segments, bounds,
                        one_sided, circles,
                    )  # fmt: skip
                    push *= min(t_push, 1.0)
                x += nx * push
                y += ny * push
                if element != last:
                    before, before_nx, before_ny = last, last_nx, last_ny
                last, last_nx, last_ny = element, nx, ny
                log_contact(state, env, element, k * h + h - remaining, speed)
                if is_hit(speed, kick_scale * props[PROP_KICK], settings.resting_speed):
                    hit_elements[n_hits] = element
                    n_hits += 1
                # Only a flipper's contact reads its row (drop targets' ids come after theirs).
                if flipper_id <= element < flipper_id + n_flippers:
                    if svx * nx + svy * ny > 0.0:
                        pushers |= 1 << (element - flipper_id)
                    if omegas[element - flipper_id] != 0.0:
                        turning_contact = True
                stalled = stalled + 1 if used <= MIN_PROGRESS * h else 0
                if stalled >= MAX_STALLED_PASSES:
                    break
            pinched = False
            if remaining > 0.0 and state.active[env, 0]:
                if not cut and before >= 0:  # a wedge: clear of both surfaces at once
                    x, y = unwedge(
                        x, y, last, last_nx, last_ny, before, before_nx, before_ny, geometry,
                        angles, r, settings.skin,
                    )  # fmt: skip
                held_time = h - remaining
                pinched = release_wedge(x, y, r, flippers, omegas, stops, held_time, pushers, held)
                if pinched and not cut:
                    # The pinched ball is at rest, and its pinch is no hit. The flippers that
                    # pinch it stay where they started the substep: moving on to where they
                    # met the ball, they would squeeze into it a little further each time.
                    vx = vy = spin = 0.0
                    for j in range(n_flippers):
                        if held[j] and (pushers >> j) & 1 == 1:
                            stops[j] = 0.0
                pinched = pinched and not cut
            if state.active[env, 0] and (remaining > 0.0 or turning_contact):
                # Only a turning flipper or a wedge can leave the ball inside a surface: the
                # sweeps stop it at the first. Where it is left deeper than the skin, it is
                # settled; where the surfaces leave it no room (a pocket that turning flippers
                # close on it), the substep is undone: the ball is back where it started it,
                # at rest, and the flippers that could reach it stall where they started.
                for j in range(n_flippers):
                    angles[j], _ = flipper_end(
                        angle[env, j], targets[j], omegas[j], stops[j], held[j], held_time, h
                    )
                up = state.targets_up[env]
                if deepest_overlap(x, y, geometry, angles, up, r) > settings.skin:
                    x, y = settle(x, y, geometry, angles, up, r, settings.skin)
                if deepest_overlap(x, y, geometry, angles, up, r) > settings.skin:
                    x, y, vx, vy, spin = x0, y0, 0.0, 0.0, 0.0
                    for j in range(n_flippers):
                        if omegas[j] != 0.0 and within_reach(x, y, r, flippers[j]):
                            held[j], stops[j] = True, 0.0
                    pinched = True
            if not pinched:
                for n in range(n_hits):
                    state.hits[env, hit_elements[n]] += 1
                    if target_id <= hit_elements[n] < target_id + n_targets:
                        state.targets_up[env, hit_elements[n] - target_id] = False  # it drops
        # Commit the flippers' angles at the end of the substep.
        for j in range(n_flippers):
            angle[env, j], omega[env, j] = flipper_end(
                angle[env, j], targets[j], omegas[j], stops[j], held[j], held_time, h
            )
    ball[BALL_X], ball[BALL_Y] = x, y
    ball[BALL_VX], ball[BALL_VY], ball[BALL_SPIN] = vx, vy, spin
    if has_targets:
        update_targets(geometry, state, env, state.balls[env], state.active[env], r,
                       settings.dt)  # fmt: skip
    return math.isfinite(x + y + vx + vy + spin)


@njit(cache=True, nogil=True, _nrt=False)  # type: ignore[call-overload]  # _nrt: not in the stubs
def step_world(geometry, settings, state, scratch, moving, start, stop):
    """Advance the envs from ``start`` to ``stop`` (``0, n_envs``: every env) for which
    ``moving`` ((n_envs,) bool) is set by one frame ``settings.dt`` in place, logging contacts
    and hits; the others are left exactly as they are. Returns the number of stepped envs whose
    ball state is not finite after the frame (0 for any valid table and state; the caller
    reports the others).

    Envs are independent: each reads and writes only its own rows of ``state`` and
    ``scratch``. The GIL is released, so threads can step disjoint ranges of envs at once,
    with bitwise the results of one call. (The range is not optional: numba dispatches a call
    that omits arguments some 40 times slower.) Compiled without reference counting
    (``_nrt=False``): it allocates nothing, and numba's atomic counts of the arrays it takes
    out of the records cost more than the physics (see ``game.play.play_frames``).
    """
    flipper_id = first_flipper(geometry)
    faults = 0
    for env in range(start, stop):
        if moving[env] and not step_ball(geometry, settings, state, scratch, env, flipper_id):
            faults += 1
    return faults


@njit(cache=True, nogil=True)
def step_tables(geometries, settings, state, scratch, moving, start, stop):
    """:func:`step_world` for envs that each play their own table: env ``i`` on
    ``geometries[i]`` with ``settings[i]`` (typed lists, one entry per env). Every table has
    as many flippers; the per-element rows of ``state`` and ``scratch`` (hits, sensor
    crossings, a substep's hits) are as long as the largest table needs, and each env uses the
    start of its rows. The physics of an env is bitwise that of :func:`step_world` on its
    table."""
    faults = 0
    for env in range(start, stop):
        if not moving[env]:
            continue
        geometry = geometries[env]
        if not step_ball(geometry, settings[env], state, scratch, env, first_flipper(geometry)):
            faults += 1
    return faults
