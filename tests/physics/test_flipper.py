"""Flippers: capsule geometry, swept contact with a rotating capsule, kinematics, realism."""

import math

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from pinball_env.physics import capsule_distance, respond, sweep_capsule, sweep_flipper
from pinball_env.physics.columns import BALL_SPIN, BALL_VX, BALL_VY, BALL_X, BALL_Y
from pinball_env.physics.flipper import flipper_distance
from pinball_env.sim.world import World
from pinball_env.table import load_table, table_from_dict

R = 0.0135
L, RB, RT = 0.07, 0.0116, 0.007
TOL = 0.25e-6
CLASSIC = load_table("classic")
LEFT_UP = np.array([[True, False]])
RELEASED = np.array([[False, False]])


# --- geometry of the tapered capsule ---------------------------------------------------------


def test_capsule_distance_on_the_axis_and_faces():
    assert capsule_distance(L + 0.05, 0.0, L, RB, RT)[0] == pytest.approx(0.05 - RT)
    assert capsule_distance(-0.05, 0.0, L, RB, RT)[0] == pytest.approx(0.05 - RB)
    d, nx, ny = capsule_distance(L / 2, 0.05, L, RB, RT)
    face_nx = (RB - RT) / L
    assert (nx, ny) == pytest.approx((face_nx, math.sqrt(1 - face_nx**2)))
    assert d == pytest.approx(L / 2 * nx + 0.05 * ny - RB)
    # Below the axis the normal mirrors.
    assert capsule_distance(L / 2, -0.05, L, RB, RT)[2] == pytest.approx(-ny)


@settings(max_examples=300, deadline=None)
@given(u=st.floats(-0.1, 0.2), v=st.floats(-0.1, 0.1))
def test_capsule_distance_matches_the_hull_of_its_circles(u, v):
    """Outside the capsule, the distance is the distance to the hull of base and tip circles."""
    d, nx, ny = capsule_distance(u, v, L, RB, RT)
    # Brute force over a dense outline of the hull.
    phi = math.acos((RB - RT) / L)
    tip = np.linspace(-phi, phi, 2000)
    base = np.linspace(phi, 2 * math.pi - phi, 2000)
    outline = np.vstack(
        [np.column_stack([L + RT * np.cos(tip), RT * np.sin(tip)]),
         np.column_stack([RB * np.cos(base), RB * np.sin(base)])]
    )  # fmt: skip
    if d > 0:
        # Distance to the edges of the dense outline polygon (within 1e-6 of the hull).
        a, b = outline, np.roll(outline, -1, axis=0)
        e = b - a
        s = np.clip(((u - a[:, 0]) * e[:, 0] + (v - a[:, 1]) * e[:, 1]) / (e**2).sum(1), 0, 1)
        brute = np.min(np.hypot(a[:, 0] + s * e[:, 0] - u, a[:, 1] + s * e[:, 1] - v))
        assert d == pytest.approx(brute, abs=1e-6)
        assert math.hypot(nx, ny) == pytest.approx(1.0)


def test_static_capsule_sweep_hits_tip_and_face():
    # Point moving down onto the upper face at mid-length, reach = R.
    t, nx, ny = sweep_capsule(L / 2, 0.1, 0.0, -0.2, R, L, RB, RT)
    face_nx = (RB - RT) / L
    face_ny = math.sqrt(1 - face_nx**2)
    # Contact where (L/2) nx + y ny = RB + R.
    y_contact = (RB + R - L / 2 * face_nx) / face_ny
    assert t == pytest.approx((0.1 - y_contact) / 0.2)
    assert (nx, ny) == pytest.approx((face_nx, face_ny))
    # Moving left along the axis onto the tip circle.
    t, nx, ny = sweep_capsule(L + 0.1, 0.0, -0.2, 0.0, R, L, RB, RT)
    assert t == pytest.approx((0.1 - RT - R) / 0.2)
    assert (nx, ny) == pytest.approx((1.0, 0.0))


# --- contact with a rotating flipper ---------------------------------------------------------


def test_swinging_straight_flipper_meets_a_resting_ball_at_the_analytic_time():
    # A straight capsule (equal radii) rotating counter-clockwise at w from angle 0 about the
    # origin; a ball at rest at polar (rho, beta). Its face reaches the ball when
    # rho sin(beta - theta) = rb + r.
    radius, rho, beta, omega = 0.01, 0.05, math.radians(40), 40.0
    cx, cy = rho * math.cos(beta), rho * math.sin(beta)
    tau, nx, ny, svx, svy = sweep_flipper(
        cx, cy, 0.0, 0.0, 0.05, R, 0.0, 0.0, L, radius, radius, 0.0, omega, 1.0, TOL
    )
    theta = beta - math.asin((radius + R) / rho)
    assert tau == pytest.approx(theta / omega, abs=1e-6)
    assert (nx, ny) == pytest.approx((-math.sin(theta), math.cos(theta)), abs=1e-4)
    # Surface velocity w x (contact - pivot), the contact point R below the ball centre.
    px, py = cx - R * nx, cy - R * ny
    assert (svx, svy) == pytest.approx((-omega * py, omega * px), abs=1e-3)


def test_bounce_off_a_moving_surface_uses_the_relative_velocity():
    # Ball at rest, surface moving at 2 m/s along the normal: it leaves at (1 + e) 2 m/s.
    vx, vy, _, speed = respond(0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 2.0, R, 0.8, 0.0, 0.0, 0.02)
    assert speed == pytest.approx(2.0)
    assert (vx, vy) == pytest.approx((0.0, 3.6))
    # A surface moving away faster than the ball: no contact response.
    assert respond(0.0, -1.0, 0.0, 0.0, 1.0, 0.0, -2.0, R, 0.8, 0.0, 0.0, 0.02)[3] == 0.0


def flipper_gap_path(cx, cy, vx, vy, duration, angle0, omega, t_stop, samples):
    """Brute force: gap between ball and flipper at ``samples`` times over the duration."""
    taus = np.linspace(0.0, duration, samples)
    gaps = np.array([
        flipper_distance(cx + vx * t, cy + vy * t, 0.0, 0.0, L, RB, RT,
                         angle0 + omega * min(t, t_stop))[0] - R
        for t in taus
    ])  # fmt: skip
    return taus, gaps


@settings(max_examples=200, deadline=None)
@given(
    start_angle=st.floats(0.0, 2 * math.pi),
    start_distance=st.floats(0.03, 0.2),
    speed=st.floats(0.0, 1000.0),
    heading=st.floats(0.0, 2 * math.pi),
    omega=st.sampled_from([-40.0, 0.0, 40.0, 80.0]),
    phase=st.floats(-math.pi, math.pi),
    t_stop=st.floats(0.0, 0.002),
    duration=st.floats(1e-4, 1 / 240),
)
def test_no_contact_is_missed_with_a_swinging_flipper(
    start_angle, start_distance, speed, heading, omega, phase, t_stop, duration
):
    """The sweep never reports a contact later than the first touch of the true motion."""
    cx, cy = start_distance * math.cos(start_angle), start_distance * math.sin(start_angle)
    assume(flipper_distance(cx, cy, 0.0, 0.0, L, RB, RT, phase)[0] > R + 1e-6)  # start clear
    vx, vy = speed * math.cos(heading), speed * math.sin(heading)
    tau, nx, ny, _, _ = sweep_flipper(
        cx, cy, vx, vy, duration, R, 0.0, 0.0, L, RB, RT, phase, omega, t_stop, TOL
    )
    taus, gaps = flipper_gap_path(cx, cy, vx, vy, duration, phase, omega, t_stop, 4001)
    before = taus < tau if math.isfinite(tau) else np.ones_like(taus, dtype=bool)
    assert gaps[before].min() > -1e-9  # never inside the flipper before the reported contact
    if math.isfinite(tau):
        angle = phase + omega * min(tau, t_stop)
        gap, gnx, gny = flipper_distance(cx + vx * tau, cy + vy * tau, 0, 0, L, RB, RT, angle)
        assert -1e-9 <= gap - R <= 2 * TOL + 1e-9
        assert (nx, ny) == pytest.approx((gnx, gny), abs=1e-6)


# --- flippers in the world -------------------------------------------------------------------


BOX_WALL = {
    "name": "box",
    "closed": True,
    "material": "wall",
    "points": [[0.01, 0.01], [0.5, 0.01], [0.5, 1.06], [0.01, 1.06]],
}


def flipper_world(slope_deg=0.0, friction=0.0, walls=True, substeps=10, extra_walls=()):
    """A closed box (or nothing, ``walls=False``) with one left flipper: pivot (0.2, 0.3),
    rest -25 deg, up +25 deg."""
    data = {
        "name": "flipper_box",
        "playfield": {"width": 0.51, "height": 1.07},
        "slope_deg": slope_deg,
        "ball": {"radius": R, "mass": 0.08, "start": [0.4, 0.9]},
        "materials": {
            "wall": {"restitution": 0.3, "friction": friction},
            "flipper": {"restitution": 0.8, "friction": friction},
        },
        "walls": ([BOX_WALL] if walls else [])
        + [
            {"name": f"extra{i}", "points": p, "material": "wall"}
            for i, p in enumerate(extra_walls)
        ],
        "simulation": {"substeps": substeps},
        "flippers": [
            {
                "name": "left",
                "pivot": [0.2, 0.3],
                "length": L,
                "base_radius": RB,
                "tip_radius": RT,
                "rest_angle": -25,
                "up_angle": 25,
                "stroke_time": 0.022,
                "return_time": 0.04,
                "material": "flipper",
                "button": "left",
            },
        ],
    }
    return World(table_from_dict(data))


def local_v(world):
    """The ball centre's coordinate across the flipper axis, in the flipper frame."""
    angle = world.state.flipper_angle[0, 0]
    dx, dy = world.balls[0, 0, BALL_X] - 0.2, world.balls[0, 0, BALL_Y] - 0.3
    return -math.sin(angle) * dx + math.cos(angle) * dy


def test_flipper_swings_to_its_stops_in_the_stroke_time():
    world = flipper_world()
    rest, up = math.radians(-25), math.radians(25)
    speed = (up - rest) / 0.022
    world.step(LEFT_UP)  # 1/60 s < 0.022 s: still moving
    assert world.state.flipper_angle[0, 0] == pytest.approx(rest + speed / 60)
    assert world.state.flipper_omega[0, 0] == pytest.approx(speed)
    world.step(LEFT_UP)
    assert world.state.flipper_angle[0, 0] == up  # exactly at the stop, not past it
    assert world.state.flipper_omega[0, 0] == 0.0
    for _ in range(10):
        world.step(LEFT_UP)
        assert world.state.flipper_angle[0, 0] == up
    world.step(RELEASED)
    world.step(RELEASED)
    world.step(RELEASED)
    assert world.state.flipper_angle[0, 0] == rest
    world.state.active[0, 0] = False  # flippers move whether or not a ball is in play
    world.step(LEFT_UP)
    assert world.state.flipper_angle[0, 0] > rest


def test_ball_falling_on_a_resting_flipper_bounces_off_its_face():
    world = flipper_world()
    world.place_ball(0, (0.235, 0.45), (0.0, -3.0))
    hits = []
    while not hits:
        world.step(RELEASED)
        hits = [c for c in world.frame_contacts() if c.name == "left"]
    assert len(hits) == 1
    # The approach speed is the normal part of the 3 m/s fall: the face's normal in the
    # flipper frame is (sin a, cos a), tilted by the taper a = asin((rb - rt) / L).
    taper = math.asin((RB - RT) / L)
    assert hits[0].speed == pytest.approx(3.0 * math.cos(math.radians(25) + taper), rel=1e-6)
    assert local_v(world) > 0  # still above the flipper


@pytest.mark.parametrize("speed", [1.0, 10.0, 100.0, 1000.0, 10000.0])
@pytest.mark.parametrize("substeps", [1, 10])
@pytest.mark.parametrize("along", [0.0, 0.035, 0.07])
def test_fast_ball_meets_the_swinging_flipper_and_never_passes_through(speed, substeps, along):
    """Aimed so as to meet the flipper mid-swing (angle 0, at full angular speed) at its base,
    face or tip: the ball bounces back to the side it came from, at every speed."""
    world = flipper_world(walls=False, substeps=substeps)
    mid_swing = 0.011  # s: the flipper swings from -25 to +25 degrees in 22 ms
    target = (0.2 + along, 0.3 + RB + R)  # a point just above the flipper at angle 0
    distance = speed * mid_swing
    world.place_ball(0, (target[0], target[1] + distance), (0.0, -speed))
    hit = False
    for _ in range(3):
        world.step(LEFT_UP)
        hit = hit or any(c.name == "left" for c in world.frame_contacts())
    assert hit
    assert world.balls[0, 0, BALL_Y] > 0.3 and world.balls[0, 0, BALL_VY] > 0  # back up, not in


def test_swinging_face_launches_a_resting_ball_by_the_relative_velocity_rule():
    """A ball at rest on the flipper's path is hit by the moving face: it leaves along the normal
    at (1 + e) times the surface's normal speed at the contact point, from which we check the
    relative-velocity rule end to end (no gravity, no friction)."""
    world = flipper_world()
    # Ball resting just above the flipper face, 50 mm from the pivot, flipper at rest.
    angle = math.radians(-25)
    nx, ny = -math.sin(angle), math.cos(angle)
    face = 0.05 * ((RB - RT) / L) + RB  # capsule half-thickness across the axis at u = 50 mm
    base = (0.2 + 0.05 * math.cos(angle), 0.3 + 0.05 * math.sin(angle))
    world.place_ball(0, (base[0] + (face + R + 1e-4) * nx, base[1] + (face + R + 1e-4) * ny))
    world.step(LEFT_UP)
    hits = [c for c in world.frame_contacts() if c.name == "left"]
    assert len(hits) == 1
    speed_after = math.hypot(world.balls[0, 0, BALL_VX], world.balls[0, 0, BALL_VY])
    assert speed_after == pytest.approx(1.8 * hits[0].speed, rel=1e-9)
    # The approach speed is the surface's normal speed: w times the lever arm of the contact.
    omega = math.radians(50) / 0.022
    assert hits[0].speed == pytest.approx(omega * 0.05, rel=0.05)


# --- the classic table: cradle, release, flip, drain -----------------------------------------


def cradled_world():
    """Classic table, left flipper held up, the ball settled in the crook above its base."""
    world = World(CLASSIC)
    world.step(LEFT_UP)
    world.step(LEFT_UP)
    flipper = CLASSIC.flippers[0]
    angle = math.radians(flipper.up_angle)
    nx, ny = -math.sin(angle), math.cos(angle)
    along, clearance = 0.04, RB + R + 0.002
    start = (flipper.pivot[0] + along * math.cos(angle) + clearance * nx,
             flipper.pivot[1] + along * math.sin(angle) + clearance * ny)  # fmt: skip
    world.place_ball(0, start)
    for _ in range(120):
        world.step(LEFT_UP)
    return world


def test_cradled_ball_stays_still_on_the_raised_flipper():
    world = cradled_world()
    flipper = CLASSIC.flippers[0]
    held = world.balls[0, 0, :2].copy()
    for _ in range(240):
        world.step(LEFT_UP)
        position = world.balls[0, 0, :2]
        assert np.abs(position - held).max() < 2e-6  # no drift, no jitter beyond the skin
        gap = flipper_distance(*position, *flipper.pivot, flipper.length, flipper.base_radius,
                               flipper.tip_radius, world.state.flipper_angle[0, 0])[0]  # fmt: skip
        assert gap >= R - 1e-7  # no sinking
        assert world.state.active[0, 0]


def test_released_cradle_rolls_down_the_flipper_past_the_tip():
    world = cradled_world()
    flipper = CLASSIC.flippers[0]
    tip_x = flipper.pivot[0] + flipper.length * math.cos(math.radians(flipper.rest_angle))
    xs = []
    for _ in range(240):
        world.step(RELEASED)
        xs.append(world.balls[0, 0, BALL_X])
    assert max(xs) > tip_x  # rolled down past the tip


def test_flip_under_a_cradled_ball_sends_it_to_the_upper_third():
    world = cradled_world()
    flipper = CLASSIC.flippers[0]
    # Release, let the ball roll to the middle of the flipper, then a full flip.
    sweet_spot = flipper.pivot[0] + 0.04 * math.cos(math.radians(flipper.rest_angle))
    frames = 0
    while world.balls[0, 0, BALL_X] < sweet_spot and frames < 300:
        world.step(RELEASED)
        frames += 1
    assert frames < 300
    top = 0.0
    for _ in range(90):
        world.step(LEFT_UP)
        top = max(top, world.balls[0, 0, BALL_Y])
    assert top > 2 / 3 * CLASSIC.height


def test_ball_dropped_on_a_resting_flipper_rolls_off_into_the_drain():
    world = World(CLASSIC)
    world.place_ball(0, (0.17, 0.16))
    for _ in range(600):
        world.step(RELEASED)
        if not world.state.active[0, 0]:
            break
    assert not world.state.active[0, 0]
    drain_y = CLASSIC.sensors[-1].points[0][1]
    assert world.balls[0, 0, BALL_Y] == pytest.approx(drain_y, abs=1e-9)


def test_flipper_stalls_against_a_ball_wedged_under_a_lid():
    """A ball lying on the flipper under a lid 10 mm above the top of the flipper's swing (no
    wall may cross the swing): energised, the flipper lifts the ball into the lid and cannot
    drive it through; like a real coil it stalls while the ball is wedged, the pinched ball at
    rest and not spinning, and it drops when released."""
    x, rest = 0.245, math.radians(-25)  # 45 mm along the flipper from its pivot (0.2, 0.3)
    low, high = 0.25, 0.4  # bisect for the height at which the ball sits on the face
    for _ in range(100):
        mid = (low + high) / 2
        if flipper_distance(x, mid, 0.2, 0.3, L, RB, RT, rest)[0] < R + 1e-5:
            low = mid
        else:
            high = mid
    swing_top = 0.3 + max(RB, L * math.sin(math.radians(25)) + RT)
    lid = swing_top + 0.010
    world = flipper_world(extra_walls=[[[0.02, lid], [0.49, lid]]])
    world.place_ball(0, (x, high))
    up = math.radians(25)
    stalled = 0
    for _ in range(60):
        world.step(LEFT_UP)
        angle = world.state.flipper_angle[0, 0]
        stalled += angle < up - math.radians(1)
        assert world.balls[0, 0, BALL_Y] <= lid - R + 1e-6  # never through the lid (skin scale)
        gap = flipper_distance(*world.balls[0, 0, :2], 0.2, 0.3, L, RB, RT, angle)[0]
        assert gap >= R - 1e-6  # nor through the flipper
        if angle < up - math.radians(1) and world.state.flipper_omega[0, 0] == 0.0:
            assert world.balls[0, 0, BALL_SPIN] == 0.0  # a pinched ball does not spin
    assert stalled >= 1  # held back by the wedged ball for a while
    for _ in range(6):
        world.step(RELEASED)
    assert world.state.flipper_angle[0, 0] == rest  # free again once released
