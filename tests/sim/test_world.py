"""The batched world step: analytic motion, contact response, resting contact, robustness."""

import math

import numpy as np
import pytest
import yaml
from hypothesis import assume, example, given, settings
from hypothesis import strategies as st

from pinball_env.physics.columns import BALL_SPIN, BALL_VX, BALL_VY, BALL_X, BALL_Y
from pinball_env.physics.near import gather_near
from pinball_env.sim.world import CONTACT_CAPACITY, World
from pinball_env.table import builtin_tables_dir, load_table, table_from_dict

RADIUS = 0.0135
SKIN = 1e-6
BOX = [[0.01, 0.01], [0.50, 0.01], [0.50, 1.06], [0.01, 1.06]]


def make_world(
    walls=(),
    posts=(),
    *,
    start=(0.25, 0.5),
    slope_deg=6.5,
    restitution=0.3,
    friction=0.0,
    resting_speed=0.02,
    substeps=10,
    frame_rate=60,
    max_passes=16,
    n_envs=1,
):
    """A World on a 0.51 x 1.07 table with the given walls (point lists) and posts."""
    data = {
        "name": "test",
        "playfield": {"width": 0.51, "height": 1.07},
        "slope_deg": slope_deg,
        "ball": {"radius": RADIUS, "mass": 0.08, "start": list(start)},
        "materials": {
            "m": {"restitution": restitution, "friction": friction},
            "kicker": {"restitution": restitution, "friction": 0.0},
        },
        "walls": [
            {"name": f"w{i}", "points": points, "material": "m", **extra}
            for i, (points, extra) in enumerate(
                (w, {}) if isinstance(w, list) else (w["points"], w["extra"]) for w in walls
            )
        ],
        "posts": [
            {"name": f"p{i}", "center": c, "radius": rad, "material": "kicker", "kick": kick}
            for i, (c, rad, kick) in enumerate(posts)
        ],
        "simulation": {
            "frame_rate": frame_rate,
            "substeps": substeps,
            "max_passes": max_passes,
            "skin": SKIN,
            "resting_speed": resting_speed,
        },
    }
    return World(table_from_dict(data), n_envs=n_envs)


def ball(world, env=0):
    return world.balls[env, 0].copy()


def g_table(slope_deg=6.5):
    return 9.81 * math.sin(math.radians(slope_deg))


def test_free_fall_matches_semi_implicit_euler_exactly():
    world = make_world(start=(0.25, 0.9))
    world.place_ball(0, (0.25, 0.9), (0.3, 0.5))
    frames, substeps, h = 30, 10, 1.0 / 600
    world.trace(frames)
    n = frames * substeps
    # v_k = v0 - g h k, x_n = x0 + h sum_{k=1..n} v_k
    expected_y = 0.9 + 0.5 * h * n - g_table() * h * h * n * (n + 1) / 2
    state = ball(world)
    assert state[BALL_Y] == pytest.approx(expected_y, abs=1e-12)
    assert state[BALL_X] == pytest.approx(0.25 + 0.3 * n * h, abs=1e-12)
    assert state[BALL_VY] == pytest.approx(0.5 - g_table() * n * h, abs=1e-12)
    assert world.state.contact_count[0] == 0


def test_wall_bounce_restitution_and_contact_time():
    # A vertical wall at x = 0.4, no gravity: the ball at x = 0.3 moving right at 6 m/s touches
    # it when its centre reaches x = 0.4 - r.
    world = make_world([[[0.4, 0.2], [0.4, 0.8]]], slope_deg=0.0, restitution=0.6)
    world.place_ball(0, (0.3, 0.5), (6.0, 0.0))
    world.step()
    contacts = world.frame_contacts()
    assert [c.name for c in contacts] == ["w0[0]"]
    assert contacts[0].time == pytest.approx((0.1 - RADIUS) / 6.0, abs=1e-12)
    assert contacts[0].speed == pytest.approx(6.0)
    state = ball(world)
    assert state[BALL_VX] == pytest.approx(-3.6, abs=1e-12)
    remaining = 1 / 60 - contacts[0].time
    assert state[BALL_X] == pytest.approx(0.4 - RADIUS - SKIN - 3.6 * remaining, abs=1e-9)


def test_oblique_bounce_keeps_tangential_speed_without_friction():
    world = make_world([[[0.1, 0.3], [0.45, 0.3]]], slope_deg=0.0, restitution=0.5)
    world.place_ball(0, (0.2, 0.4), (4.0, -8.0))
    world.step()
    state = ball(world)
    assert state[BALL_VX] == pytest.approx(4.0)
    assert state[BALL_VY] == pytest.approx(4.0)


def test_ball_comes_to_rest_on_the_floor_without_jitter_or_sinking():
    world = make_world([BOX], start=(0.25, 0.3), restitution=0.5)
    world.trace(600)
    rest_y = 0.01 + RADIUS + SKIN
    heights = world.trace(300)[:, 1]
    np.testing.assert_allclose(heights, rest_y, rtol=0, atol=1e-12)
    assert abs(ball(world)[BALL_VY]) < 1e-12
    assert world.state.contact_count[0] >= 1  # resting contact every substep, each one inelastic


def test_sliding_ball_ends_rolling_at_five_sevenths_of_its_speed():
    # A solid sphere sliding on a surface: friction spins it up until the contact point stops
    # slipping, at v = 5/7 v0 (angular momentum about the contact point is conserved).
    world = make_world([BOX], start=(0.1, 0.01 + RADIUS + SKIN), friction=0.5)
    world.place_ball(0, (0.1, 0.01 + RADIUS + SKIN), (0.7, 0.0))
    world.trace(30)
    state = ball(world)
    assert state[BALL_VX] == pytest.approx(0.5, rel=1e-9)
    # Rolling: the contact point (at -r n = (0, -r)) is at rest, vx + r spin = 0.
    assert state[BALL_VX] + RADIUS * state[BALL_SPIN] == pytest.approx(0.0, abs=1e-12)
    assert state[BALL_Y] == pytest.approx(0.01 + RADIUS + SKIN, abs=1e-12)


def test_ball_rolls_down_an_incline_at_five_sevenths_of_gravity():
    # An incline at 30 degrees; with enough friction the ball rolls: a = 5/7 g sin(30 deg).
    angle = math.radians(30.0)
    x0, y0 = 0.05, 0.6
    x1, y1 = x0 + 0.4 * math.cos(angle), y0 - 0.4 * math.sin(angle)
    n = (math.sin(angle), math.cos(angle))
    start = (x0 + 0.05 * math.cos(angle) + n[0] * (RADIUS + SKIN),
             y0 - 0.05 * math.sin(angle) + n[1] * (RADIUS + SKIN))  # fmt: skip
    world = make_world([[[x0, y0], [x1, y1]]], start=start, friction=1.0)
    frames = 30
    world.trace(frames)
    travelled = math.dist(start, ball(world)[[BALL_X, BALL_Y]])
    expected = 0.5 * (5 / 7) * g_table() * math.sin(angle) * (frames / 60) ** 2
    assert travelled == pytest.approx(expected, rel=1e-2)


def test_corner_gives_two_contacts_in_one_frame():
    world = make_world([[[0.2, 0.3], [0.4, 0.3], [0.4, 0.6]]], slope_deg=0.0, restitution=1.0)
    world.place_ball(0, (0.35, 0.35), (3.0, -3.0))
    world.step()
    assert [c.name for c in world.frame_contacts()] in (["w0[0]", "w0[1]"], ["w0[1]", "w0[0]"])
    state = ball(world)
    assert state[BALL_VX] == pytest.approx(-3.0)
    assert state[BALL_VY] == pytest.approx(3.0)


def test_tie_goes_to_the_lowest_element_id():
    # Two collinear segments meeting at x = 0.25; the ball lands exactly on the joint.
    world = make_world(
        [[[0.1, 0.3], [0.25, 0.3]], [[0.25, 0.3], [0.4, 0.3]]], slope_deg=0.0, restitution=1.0
    )
    world.place_ball(0, (0.25, 0.4), (0.0, -8.0))
    world.step()
    assert [c.element for c in world.frame_contacts()] == [0]


def test_wedged_ball_in_a_sharp_notch_stops_without_sinking():
    # A 10 degree V notch pointing down the table; gravity pushes the ball into it.
    half = math.radians(5.0)
    tip = (0.25, 0.2)
    left = [tip[0] - 0.3 * math.sin(half), tip[1] + 0.3 * math.cos(half)]
    right = [tip[0] + 0.3 * math.sin(half), tip[1] + 0.3 * math.cos(half)]
    world = make_world([[left, list(tip), right]], start=(0.25, 0.45), restitution=0.0)
    world.place_ball(0, (0.25, 0.45), (0.0, -5.0))
    for _ in range(300):
        world.step()
        state = ball(world)
        assert np.all(np.isfinite(state))
    gap_from_tip = RADIUS / math.sin(half)  # centre height above the tip when touching both
    assert state[BALL_Y] - tip[1] == pytest.approx(gap_from_tip, rel=1e-3)
    assert state[BALL_Y] - tip[1] >= gap_from_tip - 2 * SKIN


def test_kick_adds_speed_along_the_normal():
    world = make_world(
        posts=[((0.25, 0.5), 0.02, 4.0)], start=(0.25, 0.6), slope_deg=0.0, restitution=0.5
    )
    world.place_ball(0, (0.25, 0.6), (0.0, -5.0))
    world.step()
    assert ball(world)[BALL_VY] == pytest.approx(0.5 * 5.0 + 4.0)


def test_inactive_ball_is_left_untouched():
    world = make_world([BOX], n_envs=2)
    world.active[1, 0] = False
    before = ball(world, 1)
    world.trace(10)
    np.testing.assert_array_equal(ball(world, 1), before)
    assert world.state.contact_count[1] == 0


def test_contact_log_overflow_counts_but_does_not_overrun():
    # Fast ball across a narrow channel: more bounces in one frame than the log holds.
    right = 0.1 + 2 * RADIUS + 0.001
    world = make_world(
        [[[0.1, 0.2], [0.1, 0.9]], [[right, 0.2], [right, 0.9]]],
        slope_deg=0.0, restitution=1.0, substeps=40, max_passes=16,
    )  # fmt: skip
    world.place_ball(0, (0.1 + RADIUS + 0.0005, 0.5), (60.0, 0.0))
    world.step()
    assert world.state.contact_count[0] > CONTACT_CAPACITY
    assert len(world.frame_contacts()) == CONTACT_CAPACITY


def test_batch_of_balls_matches_single_balls():
    starts = [(0.1, 0.9, 3.0, -1.0), (0.3, 0.5, -20.0, 7.0), (0.4, 0.2, 0.0, 0.0)]
    batch = make_world([BOX], posts=[((0.25, 0.6), 0.02, 0.0)], n_envs=3)
    singles = [make_world([BOX], posts=[((0.25, 0.6), 0.02, 0.0)]) for _ in starts]
    for env, (x, y, vx, vy) in enumerate(starts):
        batch.place_ball(env, (x, y), (vx, vy))
        singles[env].place_ball(0, (x, y), (vx, vy))
    batch.trace(120)
    for env, single in enumerate(singles):
        single.trace(120)
        np.testing.assert_array_equal(batch.balls[env, 0], single.balls[0, 0])


# --- properties -------------------------------------------------------------------------------

# A concave, star-like room, to go with the box: re-entrant corners and slanted walls.
STAR = [[0.25, 1.0], [0.32, 0.7], [0.48, 0.6], [0.33, 0.45], [0.42, 0.05],
        [0.25, 0.3], [0.08, 0.05], [0.17, 0.45], [0.02, 0.6], [0.18, 0.7]]  # fmt: skip
ROOMS = {"box": BOX, "star": STAR}
ROOM_STARTS = {"box": ((0.05, 0.45), (0.05, 1.0)), "star": ((0.2, 0.3), (0.45, 0.75))}


def inside_polygon(x, y, polygon):
    inside = False
    n = len(polygon)
    for i in range(n):
        (x0, y0), (x1, y1) = polygon[i], polygon[(i + 1) % n]
        if (y0 > y) != (y1 > y) and x < x0 + (y - y0) * (x1 - x0) / (y1 - y0):
            inside = not inside
    return inside


def min_gap(x, y, polygon):
    gaps = []
    n = len(polygon)
    for i in range(n):
        p0, p1 = np.array(polygon[i]), np.array(polygon[(i + 1) % n])
        e = p1 - p0
        s = min(max(float((np.array([x, y]) - p0) @ e / (e @ e)), 0.0), 1.0)
        gaps.append(math.dist((x, y), p0 + s * e))
    return min(gaps)


# A ball thrown in a closed room: where (fractions of the room's start box), how fast, and
# the simulation's settings.
ROOM_THROWS = {
    "room": st.sampled_from(sorted(ROOMS)),
    "fx": st.floats(0.0, 1.0),
    "fy": st.floats(0.0, 1.0),
    "speed": st.floats(0.0, 1000.0),
    "heading": st.floats(0.0, 2 * math.pi),
    "substeps": st.integers(1, 12),
    "frame_rate": st.floats(20.0, 480.0),
    "restitution": st.floats(0.0, 1.0),
}


def room_start(room: str, fx: float, fy: float) -> tuple[float, float]:
    """The point at fractions (fx, fy) of ``room``'s start box."""
    (x_lo, y_lo), (x_hi, y_hi) = ROOM_STARTS[room]
    return x_lo + fx * (x_hi - x_lo), y_lo + fy * (y_hi - y_lo)


@settings(max_examples=60, deadline=None)
@given(**ROOM_THROWS, friction=st.floats(0.0, 1.0))
def test_ball_never_leaves_a_closed_room(
    room, fx, fy, speed, heading, substeps, frame_rate, restitution, friction
):
    polygon, (x, y) = ROOMS[room], room_start(room, fx, fy)
    assume(inside_polygon(x, y, polygon) and min_gap(x, y, polygon) >= RADIUS * 1.01)
    world = make_world(
        [{"points": polygon, "extra": {"closed": True}}], start=(x, y),
        restitution=restitution, friction=friction, substeps=substeps, frame_rate=frame_rate,
    )  # fmt: skip
    world.place_ball(0, (x, y), (speed * math.cos(heading), speed * math.sin(heading)))
    for _ in range(100):
        world.step()
        state = ball(world)
        assert np.all(np.isfinite(state))
        assert inside_polygon(state[BALL_X], state[BALL_Y], polygon)
        assert min_gap(state[BALL_X], state[BALL_Y], polygon) >= RADIUS - 4 * SKIN


@settings(max_examples=40, deadline=None)
@given(**ROOM_THROWS)
# Substeps longer than physics.near.NEAR_TIME: a new zone must hold the whole path.
@example(room="box", fx=0.5, fy=0.9, speed=3.0, heading=4.0, substeps=1, frame_rate=20.0,
         restitution=1.0)  # fmt: skip
def test_candidate_sets_sweep_bitwise_as_everything_in_any_room(
    room, fx, fy, speed, heading, substeps, frame_rate, restitution
):
    polygon, (x, y) = ROOMS[room], room_start(room, fx, fy)
    assume(inside_polygon(x, y, polygon) and min_gap(x, y, polygon) >= RADIUS * 1.01)
    runs = []
    for brute in (False, True):
        world = make_world(
            [{"points": polygon, "extra": {"closed": True}}], start=(x, y),
            restitution=restitution, substeps=substeps, frame_rate=frame_rate,
        )  # fmt: skip
        world.place_ball(0, (x, y), (speed * math.cos(heading), speed * math.sin(heading)))
        if brute:
            sweep_everything(world)
        trace = []
        for _ in range(60):
            world.step()
            trace.append((world.balls.tobytes(), world.state.contacts.tobytes()))
        runs.append(trace)
    assert runs[0] == runs[1]


@pytest.mark.slow
def test_elastic_frictionless_bounces_conserve_energy():
    """Restitution 1, no gravity, no friction: kinetic energy constant over 1e5 bounces."""
    world = make_world(
        [{"points": STAR, "extra": {"closed": True}}], start=(0.25, 0.6), slope_deg=0.0,
        restitution=1.0, friction=0.0, resting_speed=0.0, substeps=16,
    )  # fmt: skip
    world.place_ball(0, (0.25, 0.6), (613.0, -377.0))
    energy0 = 613.0**2 + 377.0**2
    bounces = 0
    while bounces < 100_000:
        world.step()
        bounces += int(world.state.contact_count[0])
    state = ball(world)
    energy = state[BALL_VX] ** 2 + state[BALL_VY] ** 2
    assert abs(energy - energy0) / energy0 < 1e-9
    assert inside_polygon(state[BALL_X], state[BALL_Y], STAR)


def test_same_input_gives_bitwise_same_output():
    def run():
        world = make_world([BOX], posts=[((0.25, 0.6), 0.02, 2.0)], n_envs=4)
        for env in range(4):
            world.place_ball(env, (0.1 + 0.1 * env, 0.8), (5.0 * env - 7.0, 3.0 * env))
        contacts = []
        for _ in range(200):
            world.step()
            contacts.append(world.state.contacts.copy())
        return world.balls.copy(), np.array(contacts)

    (balls_a, contacts_a), (balls_b, contacts_b) = run(), run()
    assert balls_a.tobytes() == balls_b.tobytes()
    assert contacts_a.tobytes() == contacts_b.tobytes()


@pytest.mark.parametrize(
    ("buttons", "message"),
    [
        ([[True, False]], r"buttons must have shape \(2, 2\).*got shape \(1, 2\)"),
        ([[0.5, 0.0], [1, 0]], "buttons must be booleans or 0/1, got dtype float64"),
        ([[2, 0], [0, 0]], "buttons must be booleans or 0/1"),
    ],
)
def test_buttons_must_be_one_pair_of_booleans_per_env(buttons, message):
    world = World(load_table("classic"), n_envs=2)
    with pytest.raises(ValueError, match=message):
        world.step(buttons)


def test_a_bad_buttons_message_gives_the_shape_not_the_array():
    world = World(load_table("classic"), n_envs=1024)
    with pytest.raises(ValueError) as error:
        world.step(np.zeros((1024, 3), dtype=bool))
    assert len(str(error.value)) < 200


def test_ball_partly_through_a_gate_next_to_a_wall_goes_back_instead_of_into_the_wall():
    # A one-way gate (blocking from the left, where its normal points) 20 mm from the box's
    # left wall: too close for the ball to get wholly past it. A ball from the right pushes
    # half through, meets the wall, and must come back out the way it came, never into the wall.
    gate = {"points": [[0.03, 0.2], [0.03, 0.8]], "extra": {"one_sided": True}}
    box = {"points": BOX, "extra": {"closed": True}}
    world = make_world([box, gate], start=(0.1, 0.5), slope_deg=0.0, restitution=0.5)
    world.place_ball(0, (0.1, 0.5), (-1.0, 0.0))
    for _ in range(60):
        world.step()
        assert world.balls[0, 0, BALL_X] >= 0.01 + RADIUS - SKIN
    assert world.balls[0, 0, BALL_VX] > 0.0 and world.balls[0, 0, BALL_X] > 0.03 + RADIUS


def crowded_classic():
    """The classic table with 63 pins in its upper field."""
    data = yaml.safe_load((builtin_tables_dir() / "classic.yaml").read_text())
    for i in range(9):
        for j in range(7):
            center = [0.07 + 0.05 * i, 0.40 + 0.07 * j + 0.02 * (i % 2)]
            data["posts"].append(
                {"name": f"pin{i}_{j}", "center": center, "radius": 0.004, "material": "rubber"}
            )
    return table_from_dict(data)


def sweep_everything(world: World) -> None:
    """Give every env of ``world`` a zone of infinite radius: a candidate set of every element,
    for good (``physics.near``), as the kernel was before it had candidate sets."""
    scratch = world.scratch
    for env in range(world.n_envs):
        gather_near(0.0, 0.0, math.inf, world.tables.geometry_of(env), scratch.near[env, 0],
                    scratch.near_ends[env, 0], scratch.near_zone[env, 0])  # fmt: skip


def traces(table, n_frames: int, place) -> list:
    """The balls and contact logs of 64 envs on ``table``, frame by frame, with candidate sets
    and with every element swept; ``place(world, env, rng)`` puts each env's ball in play."""
    runs = []
    for brute in (False, True):
        world = World(table, n_envs=64)
        rng = np.random.default_rng(0)
        for env in range(64):
            place(world, env, rng)
        if brute:
            sweep_everything(world)
        trace = []
        for _ in range(n_frames):
            world.step(rng.integers(0, 2, size=(64, 2)).astype(bool))
            trace.append((world.balls.tobytes(), world.state.contacts.tobytes()))
        runs.append(trace)
    return runs


@pytest.mark.slow  # minutes without the JIT
@pytest.mark.parametrize("table", ["classic", "classic_v1", "crowded"])
def test_the_candidate_sets_find_bitwise_the_contacts_of_sweeping_everything(table):
    table = crowded_classic() if table == "crowded" else load_table(table)
    launched, thrown = (
        traces(table, 400, lambda world, env, rng: world.launch(env, 2.2 + env * 0.015)),
        traces(table, 120, throw_anywhere),
    )
    assert launched[0] == launched[1]
    assert thrown[0] == thrown[1]


@pytest.mark.slow  # minutes without the JIT
def test_candidate_sets_keep_the_cuts_of_turning_flippers():
    """A turning flipper's sweep runs out of slices (a cut) for a fast enough ball wherever its
    path is, more readily with a thin skin: sets must not drop those sweeps."""
    data = yaml.safe_load((builtin_tables_dir() / "classic.yaml").read_text())
    data["simulation"].update(skin=1e-8, substeps=1)
    for flipper in data["flippers"]:
        flipper.update(stroke_time=0.005, return_time=0.005)
    runs = traces(table_from_dict(data), 60, throw_anywhere)
    assert runs[0] == runs[1]


def throw_anywhere(world: World, env: int, rng: np.random.Generator) -> None:
    """Env ``env``'s ball at a random place of the playfield, at up to 20 m/s in any
    direction (some start inside walls: the kernel pushes them out)."""
    table = world.table_of(env)
    speed, heading = rng.uniform(0.0, 20.0), rng.uniform(0.0, 2.0 * math.pi)
    position = (rng.uniform(0.05, table.width - 0.05), rng.uniform(0.05, table.height - 0.05))
    world.place_ball(env, position, (speed * math.cos(heading), speed * math.sin(heading)))


def test_a_long_compile_says_so_and_a_short_one_says_nothing(monkeypatch):
    """compiled_entry's notice: printed once the block has run ``after`` seconds, never for a
    block that ends before (a load from numba's cache)."""
    import sys
    import time

    from pinball_env.sim.world import notice_if_slow

    said: list[str] = []

    class Stream:
        def write(self, text: str) -> None:
            said.append(text)

        def flush(self) -> None:
            pass

    monkeypatch.setattr(sys, "stderr", Stream())
    with notice_if_slow("compiling", after=0.01):
        deadline = time.monotonic() + 30
        while not said and time.monotonic() < deadline:
            time.sleep(0.01)
    with notice_if_slow("loaded", after=30):
        pass
    time.sleep(0.05)
    assert "".join(said) == "compiling\n"
