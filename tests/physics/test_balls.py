"""Analytic and property tests of ball-ball contact: the swept test and the response."""

import math
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pinball_env.physics import respond, respond_ball_ball, sweep_ball_ball

ROOT = Path(__file__).resolve().parents[2]
R = 0.0135  # ball radius [m]
REACH = 2.0 * R

coordinate = st.floats(-1.0, 1.0, allow_nan=False)
displacement = st.floats(-0.5, 0.5, allow_nan=False)
offset = st.floats(-0.4, 0.4, allow_nan=False)  # of b from a: contacts are common (about 1 in 6)
velocity = st.floats(-10.0, 10.0, allow_nan=False)
spin = st.floats(-500.0, 500.0, allow_nan=False)
angle = st.floats(0.0, 2.0 * math.pi, allow_nan=False)
unit = st.floats(0.0, 1.0, allow_nan=False)


def sweep(a, da, b, db, reach=REACH):
    return sweep_ball_ball(a[0], a[1], da[0], da[1], b[0], b[1], db[0], db[1], reach)


def assert_hit(result, t, normal):
    got_t, nx, ny = result
    assert got_t == pytest.approx(t, abs=1e-12)
    np.testing.assert_allclose([nx, ny], normal, atol=1e-12)


def assert_miss(result):
    assert result == (math.inf, 0.0, 0.0)


def distance(a, da, b, db, t):
    return math.hypot(a[0] + da[0] * t - b[0] - db[0] * t, a[1] + da[1] * t - b[1] - db[1] * t)


def textbook_root(a, da, b, db, reach):
    """The smaller root of |m + d t|^2 = reach^2, (-b - sqrt(b^2 - a c)) / a, or None."""
    mx, my = a[0] - b[0], a[1] - b[1]
    dx, dy = da[0] - db[0], da[1] - db[1]
    qa = dx * dx + dy * dy
    qb = mx * dx + my * dy
    qc = mx * mx + my * my - reach * reach
    disc = qb * qb - qa * qc
    if qa == 0.0 or disc < 0.0:
        return None
    return (-qb - math.sqrt(disc)) / qa


def momentum(v):
    return v[0] + v[3], v[1] + v[4]


def energy(v, r=R):
    # Per unit mass: translation 1/2 v^2 and rotation 1/2 (2/5 r^2) spin^2 of each ball.
    return 0.5 * (v[0] ** 2 + v[1] ** 2 + v[3] ** 2 + v[4] ** 2) + 0.2 * r * r * (
        v[2] ** 2 + v[5] ** 2
    )


# --- the sweep: analytic cases ----------------------------------------------------------------


def test_head_on_both_moving():
    # Centres 1 apart closing at 2 + 1.5: they are REACH apart when 1 - 3.5 t = REACH.
    assert_hit(
        sweep((0.0, 0.0), (2.0, 0.0), (1.0, 0.0), (-1.5, 0.0)), (1.0 - REACH) / 3.5, [-1.0, 0.0]
    )


def test_a_moving_onto_a_ball_at_rest_is_a_ball_onto_a_post():
    # b at rest: the relative motion is a's own, the lecture's ray against a circle of radius
    # reach around b.
    assert_hit(sweep((0.0, 0.5), (0.0, -1.0), (0.0, 0.0), (0.0, 0.0)), 0.5 - REACH, [0.0, 1.0])


def test_same_motion_is_no_contact():
    # Both moving by the same displacement, even overlapping: no relative motion.
    assert_miss(sweep((0.0, 0.0), (0.3, -0.2), (0.04, 0.0), (0.3, -0.2)))
    assert_miss(sweep((0.0, 0.0), (0.3, -0.2), (0.01, 0.0), (0.3, -0.2)))
    assert_miss(sweep((0.0, 0.0), (0.0, 0.0), (0.01, 0.0), (0.0, 0.0)))


def test_oblique_graze_and_miss():
    # b at rest at the origin; a passes along y = h. Touching needs h <= REACH.
    t, nx, ny = sweep((-1.0, 0.5 * REACH), (2.0, 0.0), (0.0, 0.0), (0.0, 0.0))
    x = math.sqrt(REACH**2 - (0.5 * REACH) ** 2)
    assert t == pytest.approx((1.0 - x) / 2.0, abs=1e-12)
    np.testing.assert_allclose([nx, ny], [-x / REACH, 0.5], atol=1e-12)
    assert_miss(sweep((-1.0, 1.01 * REACH), (2.0, 0.0), (0.0, 0.0), (0.0, 0.0)))


def test_contact_beyond_the_sweep_is_no_contact():
    assert_miss(sweep((0.0, 0.0), (0.1, 0.0), (1.0, 0.0), (-0.1, 0.0)))


def test_moving_apart_is_no_contact():
    assert_miss(sweep((0.0, 0.0), (-0.1, 0.0), (1.0, 0.0), (0.1, 0.0)))


def test_start_overlap_approaching_is_a_contact_at_zero():
    # Centres 0.02 apart (< REACH), a moving towards b: t = 0, normal from the centres.
    assert_hit(sweep((0.0, 0.02), (0.0, -0.1), (0.0, 0.0), (0.0, 0.0)), 0.0, [0.0, 1.0])
    # Exactly touching and approaching, by b's motion alone.
    assert_hit(sweep((REACH, 0.0), (0.0, 0.0), (0.0, 0.0), (0.1, 0.05)), 0.0, [1.0, 0.0])


def test_start_overlap_separating_or_sliding_is_no_contact():
    assert_miss(sweep((0.0, 0.02), (0.0, 0.1), (0.0, 0.0), (0.0, 0.0)))
    # Touching, moving tangentially: the distance does not shrink.
    assert_miss(sweep((REACH, 0.0), (0.0, 0.1), (0.0, 0.0), (0.0, 0.0)))


def test_coincident_centres_push_back_against_the_relative_motion():
    # a moves by (0.3, 0.4) relative to b: the normal is -(0.6, 0.8), a is sent back.
    assert_hit(sweep((0.2, 0.2), (0.1, 0.1), (0.2, 0.2), (-0.2, -0.3)), 0.0, [-0.6, -0.8])
    # and swapped, the opposite normal.
    assert_hit(sweep((0.2, 0.2), (-0.2, -0.3), (0.2, 0.2), (0.1, 0.1)), 0.0, [0.6, 0.8])
    # Coincident without relative motion: nothing to go by, no contact.
    assert_miss(sweep((0.2, 0.2), (0.1, 0.1), (0.2, 0.2), (0.1, 0.1)))


# --- the sweep: properties ---------------------------------------------------------------------


@settings(max_examples=600, deadline=None)
@given(
    coordinate, coordinate, displacement, displacement,
    offset, offset, displacement, displacement,
    st.floats(0.005, 0.2),
)  # fmt: skip
def test_sweep_is_the_first_root_of_the_quadratic(ax, ay, adx, ady, ox, oy, bdx, bdy, reach):
    bx, by = ax + ox, ay + oy
    a, da, b, db = (ax, ay), (adx, ady), (bx, by), (bdx, bdy)
    t, nx, ny = sweep(a, da, b, db, reach)
    start = distance(a, da, b, db, 0.0)
    closing = (ax - bx) * (adx - bdx) + (ay - by) * (ady - bdy)
    samples = np.linspace(0.0, 1.0 if t == math.inf else t, 2001)
    mx, my, dx, dy = ax - bx, ay - by, adx - bdx, ady - bdy
    if mx * mx + my * my == 0.0:
        # Coincident centres (to the square's underflow): pushed back against the motion.
        speed = math.hypot(dx, dy)
        if speed == 0.0:
            assert t == math.inf
        else:
            assert (t, nx, ny) == pytest.approx((0.0, -dx / speed, -dy / speed), abs=1e-12)
        return
    if start <= reach:
        # Start overlap: a contact at 0 exactly when approaching.
        if closing < 0.0:
            assert t == 0.0
            np.testing.assert_allclose(
                [nx, ny], [(ax - bx) / start, (ay - by) / start], rtol=0, atol=1e-12
            )
        else:
            assert t == math.inf
        return
    root = textbook_root(a, da, b, db, reach)
    if t == math.inf:
        # No root in [0, 1] (away from the ends, where rounding may decide), and no sample of
        # the sweep comes closer than reach.
        assert root is None or not (1e-12 < root < 1.0 - 1e-9)
        for s in samples:
            assert distance(a, da, b, db, s) >= reach * (1.0 - 1e-9)
        return
    assert 0.0 <= t <= 1.0
    assert root is not None
    assert t == pytest.approx(root, rel=1e-7, abs=1e-9)
    assert distance(a, da, b, db, t) == pytest.approx(reach, rel=1e-9)
    for s in samples[:-1]:
        assert distance(a, da, b, db, s) >= reach * (1.0 - 1e-9)
    # The normal is the unit vector from b to a at contact.
    gx = ax + adx * t - bx - bdx * t
    gy = ay + ady * t - by - bdy * t
    g = math.hypot(gx, gy)
    np.testing.assert_allclose([nx, ny], [gx / g, gy / g], rtol=0, atol=1e-9)
    assert math.hypot(nx, ny) == pytest.approx(1.0, abs=1e-12)


@settings(max_examples=300, deadline=None)
@given(
    coordinate, coordinate, displacement, displacement,
    offset, offset, displacement, displacement,
    st.floats(0.005, 0.2),
)  # fmt: skip
def test_swapping_the_balls_gives_the_same_time_and_the_opposite_normal(
    ax, ay, adx, ady, ox, oy, bdx, bdy, reach
):
    bx, by = ax + ox, ay + oy
    t, nx, ny = sweep((ax, ay), (adx, ady), (bx, by), (bdx, bdy), reach)
    t2, nx2, ny2 = sweep((bx, by), (bdx, bdy), (ax, ay), (adx, ady), reach)
    assert t2 == t  # bitwise: the relative motion only changes sign
    assert (nx2, ny2) == (-nx, -ny)


@settings(max_examples=200, deadline=None)
@given(coordinate, coordinate, displacement, displacement, coordinate, coordinate)
def test_no_relative_motion_is_never_a_contact(ax, ay, dx, dy, bx, by):
    assert_miss(sweep((ax, ay), (dx, dy), (bx, by), (dx, dy)))


# --- the response: analytic cases -------------------------------------------------------------


def collide(va, vb, normal, e=1.0, mu=0.0, spins=(0.0, 0.0), a_fixed=False, b_fixed=False):
    return respond_ball_ball(
        va[0], va[1], spins[0], vb[0], vb[1], spins[1], normal[0], normal[1], R, e, mu,
        a_fixed, b_fixed,
    )  # fmt: skip


def test_head_on_equal_masses_exchange_velocities():
    # a on the left moving right, b on the right moving left: n from b to a is -x.
    out = collide((3.0, 0.0), (-1.25, 0.0), (-1.0, 0.0))
    np.testing.assert_allclose(out, [-1.25, 0.0, 0.0, 3.0, 0.0, 0.0], rtol=0, atol=1e-12)
    # A ball onto one at rest stops dead and sets the other off at its speed (Newton's cradle).
    out = collide((0.0, -2.0), (0.0, 0.0), (0.0, 1.0))
    np.testing.assert_allclose(out, [0.0, 0.0, 0.0, 0.0, -2.0, 0.0], rtol=0, atol=1e-12)


def test_oblique_exchanges_the_normal_parts_and_keeps_the_tangential_ones():
    n = (math.cos(0.7), math.sin(0.7))
    t = (-n[1], n[0])
    va, vb = (1.5, -2.0), (-0.5, 0.75)
    out = collide(va, vb, n)
    van, vat = va[0] * n[0] + va[1] * n[1], va[0] * t[0] + va[1] * t[1]
    vbn, vbt = vb[0] * n[0] + vb[1] * n[1], vb[0] * t[0] + vb[1] * t[1]
    assert van - vbn < 0.0  # approaching
    expected_a = (vbn * n[0] + vat * t[0], vbn * n[1] + vat * t[1])
    expected_b = (van * n[0] + vbt * t[0], van * n[1] + vbt * t[1])
    np.testing.assert_allclose(out[0:2], expected_a, rtol=0, atol=1e-12)
    np.testing.assert_allclose(out[3:5], expected_b, rtol=0, atol=1e-12)
    assert out[2] == 0.0 and out[5] == 0.0
    before = energy((va[0], va[1], 0.0, vb[0], vb[1], 0.0))
    assert energy(out) == pytest.approx(before, rel=1e-12)


def test_separating_balls_are_left_alone():
    out = collide((-1.0, 0.5), (1.0, 2.0), (-1.0, 0.0), e=0.5, mu=0.4, spins=(3.0, -4.0))
    assert out == (-1.0, 0.5, 3.0, 1.0, 2.0, -4.0)
    # Sliding past each other (no normal approach) is no contact either.
    out = collide((0.0, 1.0), (0.0, -1.0), (1.0, 0.0), mu=0.4)
    assert out == (0.0, 1.0, 0.0, 0.0, -1.0, 0.0)


@pytest.mark.parametrize("e, mu", [(1.0, 0.0), (0.8, 0.0), (0.3, 0.4), (0.0, 1.0)])
def test_a_fixed_ball_at_rest_is_a_post(e, mu):
    # The other ball bounces off it as contact.respond bounces a ball off a post: bitwise.
    n = (0.6, -0.8)
    va, sa = (-2.0, 3.5), 40.0
    post = respond(va[0], va[1], sa, n[0], n[1], 0.0, 0.0, R, e, mu, 0.0, 0.0)
    out = collide(va, (0.0, 0.0), n, e, mu, (sa, 0.0), b_fixed=True)
    assert out[0:3] == post[0:3]
    assert out[3:6] == (0.0, 0.0, 0.0)
    # The same with the roles swapped: b onto a fixed a, the pair's normal (from b to a) -n.
    out = collide((0.0, 0.0), va, (-n[0], -n[1]), e, mu, (0.0, sa), a_fixed=True)
    assert out[3:6] == post[0:3]
    assert out[0:3] == (0.0, 0.0, 0.0)


def test_a_fixed_ball_reflects_the_other():
    out = collide((1.0, -2.0), (0.0, 0.0), (0.0, 1.0), b_fixed=True)
    np.testing.assert_allclose(out, [1.0, 2.0, 0.0, 0.0, 0.0, 0.0], rtol=0, atol=1e-12)


def test_two_fixed_balls_do_not_move():
    out = collide((1.0, -2.0), (0.5, 0.0), (0.0, 1.0), a_fixed=True, b_fixed=True)
    assert out == (1.0, -2.0, 0.0, 0.5, 0.0, 0.0)


def test_friction_sets_equal_balls_rolling_on_each_other():
    # a slides down past b (tangent -y is the slip) with full friction: the slip of the contact
    # points stops, and each ball gets the same spin (impulses equal and opposite at one point).
    n = (1.0, 0.0)
    out = collide((-1.0, -2.0), (0.0, 0.0), n, e=0.0, mu=10.0)
    avx, avy, aspin, bvx, bvy, bspin = out
    slip = (avx - bvx) * -n[1] + (avy - bvy) * n[0] - R * (aspin + bspin)
    assert slip == pytest.approx(0.0, abs=1e-12)
    assert aspin == bspin != 0.0
    assert avx - bvx == pytest.approx(0.0, abs=1e-12)  # e = 0: no normal rebound


# --- the response: properties -------------------------------------------------------------------


@settings(max_examples=400, deadline=None)
@given(
    velocity, velocity, spin, velocity, velocity, spin, angle, unit, st.floats(0.0, 1.5)
)  # fmt: skip
def test_response_conserves_momentum_and_scales_the_normal_speed(
    avx, avy, aspin, bvx, bvy, bspin, theta, e, mu
):
    nx, ny = math.cos(theta), math.sin(theta)
    before = (avx, avy, aspin, bvx, bvy, bspin)
    out = respond_ball_ball(avx, avy, aspin, bvx, bvy, bspin, nx, ny, R, e, mu, False, False)
    vn = (avx - bvx) * nx + (avy - bvy) * ny
    vn_after = (out[0] - out[3]) * nx + (out[1] - out[4]) * ny
    scale = 1.0 + max(abs(v) for v in (avx, avy, bvx, bvy))
    if vn >= 0.0:
        assert out == before
        return
    # Relative normal speed after is e times before (friction acts along the tangent only).
    assert vn_after == pytest.approx(-e * vn, abs=1e-12 * scale)
    # Linear momentum (equal masses) and angular momentum about the contact point (the impulses
    # act there: m (x v) and (2/5) m r^2 spin per ball, a at +r n, b at -r n from it) are kept.
    pa, pb = momentum(before), momentum(out)
    assert pb[0] == pytest.approx(pa[0], abs=1e-12 * scale)
    assert pb[1] == pytest.approx(pa[1], abs=1e-12 * scale)

    def angular(v):
        cross_a = R * (nx * v[1] - ny * v[0])
        cross_b = -R * (nx * v[4] - ny * v[3])
        return cross_a + cross_b + 0.4 * R * R * (v[2] + v[5])

    assert angular(out) == pytest.approx(angular(before), abs=1e-12 * scale)
    # Energy: kept without friction at e = 1, never gained.
    if mu == 0.0 and e == 1.0:
        assert energy(out) == pytest.approx(energy(before), rel=1e-12)
    assert energy(out) <= energy(before) * (1.0 + 1e-12)


@settings(max_examples=200, deadline=None)
@given(velocity, velocity, spin, angle, unit, st.floats(0.0, 1.5))
def test_response_against_a_fixed_ball_at_rest_is_the_post_response(vx, vy, s, theta, e, mu):
    nx, ny = math.cos(theta), math.sin(theta)
    post = respond(vx, vy, s, nx, ny, 0.0, 0.0, R, e, mu, 0.0, 0.0)
    out = respond_ball_ball(vx, vy, s, 0.0, 0.0, 0.0, nx, ny, R, e, mu, False, True)
    assert out[0:3] == post[0:3]
    assert out[3:6] == (0.0, 0.0, 0.0)


# --- plain Python --------------------------------------------------------------------------------

CASES_SCRIPT = """
import sys
import numpy as np
from pinball_env.physics.balls import respond_ball_ball, sweep_ball_ball
rng = np.random.default_rng(49)
rows = []
for i in range(400):
    p = rng.uniform(-1.0, 1.0, 8) * ([1, 1, 0.1, 0.1] * 2)
    if i % 4 == 0:
        p[4:6] = p[0:2] + rng.uniform(-0.02, 0.02, 2)  # start overlaps
    if i % 50 == 1:
        p[4:8] = p[0:4]  # coincident, no relative motion
    if i % 50 == 2:
        p[4:6] = p[0:2]  # coincident centres
    rows.append(sweep_ball_ball(*[float(v) for v in p], 0.027))
    v = rng.uniform(-5.0, 5.0, 8)
    n = v[6:8] / np.hypot(v[6], v[7])
    rows.append(respond_ball_ball(
        float(v[0]), float(v[1]), 100.0 * float(v[2]), float(v[3]), float(v[4]),
        100.0 * float(v[5]), float(n[0]), float(n[1]), 0.0135, 0.8, 0.4, i % 7 == 0, i % 5 == 0,
    ))
np.save(sys.argv[1], np.array([x for row in rows for x in row], dtype=np.float64))
"""


def run_cases(out, disable_jit):
    env = {**os.environ, "NUMBA_DISABLE_JIT": "1" if disable_jit else "0"}
    subprocess.run(
        [sys.executable, "-c", CASES_SCRIPT, str(out)], cwd=ROOT, env=env, check=True, timeout=600
    )
    return np.load(out)


def test_pure_python_is_bitwise_the_compiled_kernels(tmp_path):
    compiled = run_cases(tmp_path / "compiled.npy", False)
    plain = run_cases(tmp_path / "plain.npy", True)
    assert np.isfinite(compiled).sum() > len(compiled) // 2
    np.testing.assert_array_equal(plain, compiled)
    assert np.array_equal(np.signbit(plain), np.signbit(compiled))
