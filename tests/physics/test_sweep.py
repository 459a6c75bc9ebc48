"""Analytic and property tests of the swept ball-segment and ball-circle tests."""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pinball_env.physics import sweep_circle_circle, sweep_circle_segment

R = 0.5
A = np.array([-1.0, 0.0])
B = np.array([1.0, 0.0])  # segment along x; its normal rot+90(B - A) is +y


def sweep(center, displacement, p0=A, p1=B, radius=R, one_sided=False):
    return sweep_circle_segment(
        np.array(center, float), np.array(displacement, float), radius, p0, p1, one_sided
    )


def assert_hit(result, t, normal):
    got_t, got_n = result
    assert got_t == pytest.approx(t, abs=1e-12)
    np.testing.assert_allclose(got_n, normal, atol=1e-12)


def assert_miss(result):
    assert result[0] == math.inf


# --- faces: the lecture's D2 = +r / -r -------------------------------------------------------


def test_face_head_on_from_the_normal_side():
    # Centre at y = 2 moving down 4: touches the line offset by +r at y = 0.5 -> t = 1.5 / 4.
    assert_hit(sweep([0.2, 2.0], [0.0, -4.0]), 1.5 / 4.0, [0.0, 1.0])


def test_face_head_on_from_the_other_side():
    # D2 = -r: the offset line at y = -0.5, normal pointing down towards the ball.
    assert_hit(sweep([0.2, -2.0], [0.0, 4.0]), 1.5 / 4.0, [0.0, -1.0])


def test_face_oblique():
    # dv = n.d = -2, d0 = 1.5 -> t = (0.5 - 1.5) / -2 = 0.5; contact point x = -0.5 + 0.5 = 0.
    assert_hit(sweep([-0.5, 1.5], [1.0, -2.0]), 0.5, [0.0, 1.0])


def test_face_hit_beyond_the_displacement_is_no_contact():
    assert_miss(sweep([0.0, 2.0], [0.0, -1.49]))


def test_motion_away_from_the_face_is_no_contact():
    assert_miss(sweep([0.0, 2.0], [0.0, 3.0]))


def test_parallel_motion_beside_the_segment_is_no_contact():
    assert_miss(sweep([-3.0, 0.6], [6.0, 0.0]))


def test_path_passing_beyond_the_end_is_no_contact():
    # Crosses the line at x = 1.6, more than r past the end at x = 1.
    assert_miss(sweep([1.6, 2.0], [0.0, -4.0]))


# --- segment ends: the seed's "B_i not on the segment, but the ball collides" case -----------


def test_end_hit_where_the_offset_line_intersection_misses_the_segment():
    # The face test puts the contact at x = 1.3, off the segment; the ball still clips end P1.
    # |(1.3, 2 - 2t) - (1, 0)| = 0.5 -> (2 - 2t)^2 = 0.16 -> t = 0.8, normal (0.3, 0.4) / 0.5.
    assert_hit(sweep([1.3, 2.0], [0.0, -2.0]), 0.8, [0.6, 0.8])


def test_end_hit_at_the_first_end():
    assert_hit(sweep([-1.3, 2.0], [0.0, -2.0]), 0.8, [-0.6, 0.8])


def test_motion_along_the_line_hits_the_near_end():
    # On the line itself, coming from the right: first contact with the P1 end circle at x = 1.5.
    assert_hit(sweep([3.0, 0.0], [-4.0, 0.0]), 1.5 / 4.0, [1.0, 0.0])
    # Coming from the left it is the P0 end.
    assert_hit(sweep([-3.0, 0.0], [4.0, 0.0]), 1.5 / 4.0, [-1.0, 0.0])


def test_both_ends_on_the_path_the_earlier_wins():
    # A short segment on the path, offset 0.3 from the ray: both end circles are crossed.
    p0, p1 = np.array([0.0, 0.0]), np.array([0.1, 0.0])
    y = 0.3
    dx_end = math.sqrt(R**2 - y**2)  # 0.4
    # Moving right from x = -2: the P0 circle comes first, at x = -0.4.
    t, n = sweep([-2.0, y], [4.0, 0.0], p0, p1)
    assert t == pytest.approx((2.0 - dx_end) / 4.0)
    np.testing.assert_allclose(n, [-dx_end / R, y / R], atol=1e-12)
    # Moving left from x = 2: the P1 circle first, at x = 0.5.
    t, n = sweep([2.0, y], [-4.0, 0.0], p0, p1)
    assert t == pytest.approx((2.0 - 0.1 - dx_end) / 4.0)
    np.testing.assert_allclose(n, [dx_end / R, y / R], atol=1e-12)


def test_in_the_slab_beyond_the_end_moving_in_hits_the_end():
    # Centre within r of the line but past the end: the face test is behind, the end is ahead.
    t, n = sweep([1.6, 0.3], [-1.0, 0.0])
    assert t == pytest.approx(0.2)  # x = 1.4: |(0.4, 0.3)| = 0.5
    np.testing.assert_allclose(n, [0.8, 0.6], atol=1e-12)


# --- start overlap -----------------------------------------------------------------------------


def test_start_overlap_moving_towards_is_contact_at_zero():
    assert_hit(sweep([0.3, 0.2], [0.0, -1.0]), 0.0, [0.0, 1.0])


def test_start_overlap_near_an_end_uses_the_closest_point():
    # Closest point is the end P1 = (1, 0); the normal points from it to the centre.
    assert_hit(sweep([1.3, 0.4], [-1.0, -1.0]), 0.0, [0.6, 0.8])


def test_start_overlap_moving_away_is_no_contact():
    assert_miss(sweep([0.3, 0.2], [0.0, 1.0]))
    assert_miss(sweep([1.3, 0.4], [1.0, 0.0]))


def test_touching_moving_towards_is_contact_at_zero():
    assert_hit(sweep([0.0, R], [0.0, -1.0]), 0.0, [0.0, 1.0])


def test_touching_moving_along_is_no_contact():
    assert_miss(sweep([0.0, R], [1.0, 0.0]))


def test_centre_on_the_segment_pushes_back_against_the_motion():
    assert_hit(sweep([0.0, 0.0], [0.0, -1.0]), 0.0, [0.0, 1.0])
    assert_hit(sweep([0.0, 0.0], [0.0, 1.0]), 0.0, [0.0, -1.0])


def test_zero_displacement_is_no_contact_even_when_overlapping():
    assert_miss(sweep([0.0, 2.0], [0.0, 0.0]))
    assert_miss(sweep([0.0, 0.2], [0.0, 0.0]))


# --- degenerate segment --------------------------------------------------------------------


@pytest.mark.parametrize(
    ("center", "displacement"),
    [([0.0, 2.0], [0.0, -4.0]), ([0.3, 2.0], [0.0, -4.0]), ([2.0, 0.0], [-3.0, 0.1])],
)
def test_zero_length_segment_is_a_point(center, displacement):
    p = np.array([0.0, 0.0])
    t, n = sweep(center, displacement, p, p)
    t_point, n_point = sweep_circle_circle(np.array(center), np.array(displacement), R, p, 0.0)
    assert t == t_point
    np.testing.assert_array_equal(n, n_point)
    assert math.isfinite(t)


# --- one-sided segments ---------------------------------------------------------------------


def test_one_sided_stops_a_ball_from_the_normal_side():
    # n = rot+90(B - A) = +y: a ball from above is stopped.
    assert_hit(sweep([0.0, 2.0], [0.0, -4.0], one_sided=True), 1.5 / 4.0, [0.0, 1.0])


def test_one_sided_lets_a_ball_from_the_other_side_pass():
    assert_miss(sweep([0.0, -2.0], [0.0, 4.0], one_sided=True))
    # Also while overlapping it from behind, and at its ends.
    assert_miss(sweep([0.0, -0.2], [0.0, 1.0], one_sided=True))
    assert_miss(sweep([1.3, -0.4], [-1.0, 1.0], one_sided=True))


def test_one_sided_lets_a_ball_still_partly_through_fall_back():
    # Centre just in front of the line but within r of it, moving back: like a ball that did
    # not fully pass a one-way gate, it goes back through instead of being shoved forward.
    assert_miss(sweep([0.0, 0.2], [0.0, -1.0], one_sided=True))
    # Wholly in front and touching: a contact, as for a two-sided segment.
    assert_hit(sweep([0.0, R], [0.0, -1.0], one_sided=True), 0.0, [0.0, 1.0])


def test_one_sided_orientation_follows_the_point_order():
    # Reversing the points flips the normal to -y: now the ball from below is stopped.
    assert_hit(sweep([0.0, -2.0], [0.0, 4.0], B, A, one_sided=True), 1.5 / 4.0, [0.0, -1.0])
    assert_miss(sweep([0.0, 2.0], [0.0, -4.0], B, A, one_sided=True))


# --- circles (posts, bumpers) -----------------------------------------------------------------


def circle(center, displacement, c=(0.0, 0.0), big_r=0.25):
    return sweep_circle_circle(
        np.array(center, float), np.array(displacement, float), R, np.array(c, float), big_r
    )


def test_circle_head_on():
    assert_hit(circle([0.0, 2.0], [0.0, -4.0]), (2.0 - 0.75) / 4.0, [0.0, 1.0])


def test_circle_oblique():
    # Offset 0.45 from the centre line: contact where |(0.45, y)| = 0.75 -> y = 0.6.
    t, n = circle([0.45, 2.0], [0.0, -4.0])
    assert t == pytest.approx((2.0 - 0.6) / 4.0)
    np.testing.assert_allclose(n, [0.6, 0.8], atol=1e-12)


def test_circle_miss_and_away():
    assert_miss(circle([0.76, 2.0], [0.0, -4.0]))
    assert_miss(circle([0.0, 2.0], [0.0, 4.0]))


def test_circle_overlap():
    assert_hit(circle([0.0, 0.6], [0.0, -1.0]), 0.0, [0.0, 1.0])
    assert_miss(circle([0.0, 0.6], [0.0, 1.0]))
    assert_hit(circle([0.0, 0.0], [1.0, 0.0]), 0.0, [-1.0, 0.0])


def test_array_arguments_are_checked():
    with pytest.raises(ValueError, match="center must have shape"):
        sweep_circle_segment(np.zeros(3), np.zeros(2), R, A, B)


# --- properties -------------------------------------------------------------------------------


def distance_to_segment(point, p0, p1):
    e = p1 - p0
    length2 = float(e @ e)
    s = 0.0 if length2 == 0.0 else min(max(float((point - p0) @ e) / length2, 0.0), 1.0)
    return float(np.linalg.norm(point - (p0 + s * e)))


coordinate = st.floats(-3.0, 3.0, allow_nan=False)
point = st.tuples(coordinate, coordinate).map(np.array)


@settings(max_examples=400, deadline=None)
@given(center=point, displacement=point, p0=point, p1=point, radius=st.floats(0.01, 1.0))
def test_contact_is_the_first_touch(center, displacement, p0, p1, radius):
    """At t the ball touches the segment with the stated normal, and never overlaps it before."""
    t, n = sweep_circle_segment(center, displacement, radius, p0, p1)
    start_gap = distance_to_segment(center, p0, p1)
    scale = 1e-9 * (1.0 + float(np.abs(displacement).max()))
    if math.isfinite(t):
        assert 0.0 <= t <= 1.0
        assert float(np.linalg.norm(n)) == pytest.approx(1.0, abs=1e-12)
        at_contact = center + displacement * t
        gap = distance_to_segment(at_contact, p0, p1)
        if t > 0.0:
            assert gap == pytest.approx(radius, abs=scale)
        else:
            assert start_gap <= radius + scale  # touching (up to rounding) or overlapping
            assert float(displacement @ n) < 0.0  # moving into the contact
            return
        earlier = center + np.outer(np.linspace(0.0, t, 65)[:-1], displacement)
    else:
        earlier = center + np.outer(np.linspace(0.0, 1.0, 257), displacement)
        if start_gap <= radius:
            return  # overlapping and not closing in: free to separate
    gaps = [distance_to_segment(q, p0, p1) for q in earlier]
    assert min(gaps) >= radius - scale
