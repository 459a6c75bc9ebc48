"""Generated tables: validation, YAML round trip, determinism, playability, names, gallery."""

import dataclasses
import hashlib
import importlib
import inspect
import json
import math
import pickle
import subprocess
import sys
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pinball_env import procgen
from pinball_env.physics import first_flipper, point_segment_distance
from pinball_env.physics.columns import BALL_X, BALL_Y, CONTACT_ELEMENT
from pinball_env.procgen import (
    generate,
    generate_table,
    load_any_table,
    parse_name,
    playability,
    table_name,
)
from pinball_env.procgen.obstacles import segment_distance
from pinball_env.sim.world import World
from pinball_env.table import TableError, dump_table, load_table, table_from_dict, table_to_dict

# The playability check's module (the package's ``playability`` is its function).
checks = importlib.import_module("pinball_env.procgen.playability")

seeds = st.integers(0, 2**40)
difficulties = st.sampled_from(procgen.DIFFICULTIES)


def fingerprint(seed: int, difficulty: str) -> str:
    text = json.dumps(table_to_dict(generate_table(seed, difficulty)), sort_keys=True)
    return hashlib.sha256(text.encode()).hexdigest()


@settings(max_examples=40)
@given(seed=seeds, difficulty=difficulties)
def test_generated_tables_validate_round_trip_and_play(seed, difficulty, tmp_path_factory):
    table = generate_table(seed, difficulty)
    assert table.name == table_name(seed, difficulty)
    assert table_from_dict(table_to_dict(table), table.source) == table
    path = dump_table(table, tmp_path_factory.mktemp("yaml") / "table.yaml")
    again = load_table(path)
    assert dataclasses.replace(again, source=table.source) == table
    # Playable for balls dropped at other random places than the generator's own check.
    assert playability(table, np.random.default_rng(seed + 1)) is None
    assert len(table.flippers) == 2 and table.plunger is not None


@settings(max_examples=20)
@given(seed=seeds, difficulty=difficulties)
def test_generated_tables_keep_their_proportions(seed, difficulty):
    table = generate_table(seed, difficulty)
    ranges = procgen.RANGES[difficulty]
    assert ranges.width[0] - 1e-5 <= table.width <= ranges.width[1] + 1e-5
    assert 1.8 <= table.height / table.width <= 2.25
    assert ranges.slope[0] - 1e-3 <= table.slope_deg <= ranges.slope[1] + 1e-3
    bumpers = [p for p in table.posts if p.name.startswith("bumper_")]
    assert ranges.bumpers[0] <= len(bumpers) <= ranges.bumpers[1]
    for bumper in bumpers:  # within the playfield, clear of every wall by a ball and more
        for wall in table.walls:
            for x0, y0, x1, y1 in wall.segments():
                gap = _segment_gap(bumper.center, (x0, y0, x1, y1)) - bumper.radius
                assert gap >= procgen.CLEARANCE - 1e-4, (bumper.name, wall.name)


def _segment_gap(point, segment):
    x, y = point
    x0, y0, x1, y1 = segment
    dx, dy = x1 - x0, y1 - y0
    t = min(max(((x - x0) * dx + (y - y0) * dy) / (dx * dx + dy * dy), 0.0), 1.0)
    return math.hypot(x - x0 - t * dx, y - y0 - t * dy)


def test_a_seed_gives_the_same_table_in_another_process():
    # The same fingerprint, by its source (a test module is not imported).
    code = (
        "import hashlib, json\n"
        "from pinball_env.procgen import generate_table\n"
        "from pinball_env.table import table_to_dict\n"
        + inspect.getsource(fingerprint)
        + "print(json.dumps([fingerprint(s, d) for s in (0, 7, 123456789) "
        "for d in ('easy', 'hard')]))"
    )
    result = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True,
        cwd=Path(__file__).resolve().parents[2],
    )  # fmt: skip
    theirs = json.loads(result.stdout)
    assert theirs == [fingerprint(s, d) for s in (0, 7, 123456789) for d in ("easy", "hard")]
    assert len(set(theirs)) == len(theirs)  # and different seeds differ


def test_a_rejected_draw_is_redrawn_from_a_derived_seed():
    # Seeds whose first draw fails a check: the table comes from a later draw, and the first
    # draw's layout really does fail.
    found = [g for g in (generate(s) for s in range(40)) if g.draws > 1]
    assert found, "some of 40 seeds should need a second draw"
    kept = found[0]
    assert len(kept.rejected) == kept.draws - 1
    rng = np.random.default_rng([kept.seed, 0, 0])
    try:
        first = table_from_dict(procgen.draw_layout(rng, procgen.RANGES["easy"], "x"))
    except (TableError, procgen.LayoutError):
        return
    assert playability(first, rng) is not None


def _trapped(table):
    """``table`` with a V of walls, open upwards, put in the most open place of the upper
    field: a pocket that holds a ball."""
    data = table_to_dict(table)
    obstacles = procgen._Obstacles()
    for wall in table.walls:
        obstacles.add_wall([list(p) for p in wall.points], wall.closed)
    for post in table.posts:
        obstacles.add_circle(list(post.center), post.radius)
    spots = [(x, y) for x in np.linspace(0.05, table.width - 0.1, 30)
             for y in np.linspace(0.45 * table.height, 0.8 * table.height, 30)]  # fmt: skip
    x, y = max(spots, key=lambda p: obstacles.circle_gap(*p, 0.0))
    assert obstacles.circle_gap(x, y, 0.0) > 0.06
    data["walls"].append(
        {"name": "trap", "points": [[x - 0.04, y + 0.04], [x, y], [x + 0.04, y + 0.04]],
         "material": "wall"}
    )  # fmt: skip
    return table_from_dict(data)


def test_playability_finds_a_pocket_that_holds_a_ball():
    table = generate_table(3)
    problem = playability(_trapped(table), np.random.default_rng(0), drops=400)
    assert problem is not None and "rests at" in problem, problem
    assert playability(table, np.random.default_rng(0), drops=400) is None


def test_playability_finds_a_plunger_too_weak_to_enter_the_field():
    data = table_to_dict(generate_table(4))
    data["plunger"]["speed"] = [0.5, 0.6]
    problem = playability(table_from_dict(data), np.random.default_rng(0))
    assert problem == "a plunger shot does not enter the playfield"


def _roll_frame_by_frame(table, starts, lane_x):
    """The check's roll as first written: every ball stepped together, frame by frame, in a
    World of one env per ball, stopping at the first ball at rest."""
    n, radius = len(starts.balls), table.ball.radius
    world = World(table, n)
    for env, (position, velocity) in enumerate(starts.balls):
        world.place_ball(env, position, velocity)
    flippers = first_flipper(world.geometry) + np.arange(len(table.flippers))
    entered, touched = np.zeros(n, dtype=bool), np.zeros(n, dtype=bool)
    anchor = world.balls[:, 0, [BALL_X, BALL_Y]].copy()
    still = np.zeros(n, dtype=np.int64)
    frame_rate = table.simulation.frame_rate
    for _ in range(round(checks.DRAIN_TIME * frame_rate)):
        world.step()
        active = world.active[:, 0]
        if not active.any():
            break
        position = world.balls[:, 0, [BALL_X, BALL_Y]]
        entered |= active & (position[:, 0] < lane_x - radius)
        for env in np.flatnonzero(active):
            ids = world.state.contacts[env, : world.state.contact_count[env], CONTACT_ELEMENT]
            touched[env] |= np.isin(ids, flippers).any()
        moved = np.hypot(*(position - anchor).T) >= radius
        anchor[moved] = position[moved]
        still = np.where(moved | ~active, 0, still + 1)
        if (still >= round(checks.REST_TIME * frame_rate)).any():
            env = int(np.argmax(still))
            if env < starts.launches and not entered[env]:
                return "a plunger shot does not enter the playfield"
            return f"a ball rests at ({position[env, 0]:.3f}, {position[env, 1]:.3f})"
    if world.active.any():
        x, y = starts.balls[int(np.argmax(world.active))][0]
        return f"a ball from ({x:.3f}, {y:.3f}) has not drained in {checks.DRAIN_TIME:g} s"
    return entered, touched


@pytest.mark.parametrize(("drain_time", "rest_time"), [(60.0, 10.0), (1.5, 10.0), (60.0, 0.4)])
def test_the_check_rolls_each_ball_as_when_all_were_stepped_together(
    drain_time, rest_time, monkeypatch
):
    # The compiled roll takes the balls one by one to their ends; its verdict, and which balls
    # entered the playfield and touched a flipper, are those of stepping every ball together
    # frame by frame. Short times make balls that have not drained, or that rest.
    weak = table_to_dict(generate_table(4))
    weak["plunger"]["speed"] = [0.5, 1.5]
    tables = [generate_table(3), _trapped(generate_table(3)), table_from_dict(weak)]
    tables.append(generate_table(2, targets=True))
    monkeypatch.setattr(checks, "DRAIN_TIME", drain_time)
    monkeypatch.setattr(checks, "REST_TIME", rest_time)
    verdicts = set()
    for table in tables:
        lane_x = min(s[0] for s in checks._lane_walls(table))
        space = table.free_space
        starts = checks._starts(table, np.random.default_rng(0), 24, lane_x, space)
        expected = _roll_frame_by_frame(table, starts, lane_x)
        outcome = checks._roll(table, starts, lane_x)
        if isinstance(expected, str):
            assert outcome == expected
        else:
            assert not isinstance(outcome, str), outcome
            np.testing.assert_array_equal(outcome[0], expected[0])
            np.testing.assert_array_equal(outcome[1], expected[1])
        verdicts.add(expected if isinstance(expected, str) else None)
    assert verdicts - {None}, "some table should fail the check"


def test_obstacles_segment_gap_is_the_smallest_gap():
    rng = np.random.default_rng(0)
    obstacles = procgen.Obstacles()
    for _ in range(12):  # the gaps follow the obstacles as they are added
        obstacles.add_wall(rng.uniform(0.0, 0.5, (3, 2)).tolist(), closed=bool(rng.random() < 0.5))
        obstacles.add_circle(rng.uniform(0.0, 0.5, 2).tolist(), float(rng.uniform(0.005, 0.03)))
        segment = tuple(rng.uniform(0.0, 0.5, 4).tolist())
        gaps = [segment_distance(segment, s) for s in obstacles.segments]
        gaps += [point_segment_distance(x, y, *segment) - r for x, y, r in obstacles.circles]
        assert obstacles.segment_gap(segment) == min(gaps)
    assert procgen.Obstacles().segment_gap((0.0, 0.0, 1.0, 1.0)) == math.inf


def test_tables_by_name():
    assert load_any_table("procgen:12") == generate_table(12)
    assert load_any_table("procgen-hard:12") == generate_table(12, "hard")
    assert load_any_table("classic") == load_table("classic")
    assert parse_name("procgen-hard:5") == (5, "hard", False)
    assert parse_name("classic") is None
    env = gym.make("Pinball-v0", table="procgen-hard:2")
    env.reset(seed=0)
    for _ in range(50):
        env.step(env.action_space.sample())
    assert env.unwrapped.table.name == "procgen-hard:2"


@pytest.mark.parametrize("name", ["procgen:", "procgen:-1", "procgen:x", "procgen:1.5",
                                  f"procgen:{2**63}", "procgen-hard:0x10"])  # fmt: skip
def test_a_bad_generated_table_name_is_a_clear_error(name):
    with pytest.raises(TableError, match="seed of a generated table"):
        load_any_table(name)


def test_generate_rejects_bad_arguments():
    with pytest.raises(ValueError, match="difficulty"):
        generate_table(0, "medium")
    with pytest.raises(ValueError, match="seed"):
        generate_table(-1)
    with pytest.raises(TypeError, match="seed"):
        generate_table(1.0)  # type: ignore[arg-type]


@pytest.mark.parametrize("difficulty", procgen.DIFFICULTIES)
def test_random_play_never_lets_the_ball_out(difficulty):
    for seed in range(3):
        table = generate_table(seed, difficulty)
        outline = np.array(table.outline.points)
        env = gym.make("Pinball-v0", table=table_name(seed, difficulty))
        env.reset(seed=seed)
        env.action_space.seed(seed)
        for _ in range(1500):
            _, _, terminated, truncated, info = env.step(env.action_space.sample())
            assert _inside(info["ball_position"], outline)
            if terminated or truncated:
                env.reset()


def _inside(point, polygon) -> bool:
    """Even-odd rule."""
    x, y = point
    inside = False
    for (x0, y0), (x1, y1) in zip(polygon, np.roll(polygon, -1, axis=0), strict=True):
        if (y0 > y) != (y1 > y) and x < x0 + (y - y0) * (x1 - x0) / (y1 - y0):
            inside = not inside
    return inside


def test_the_gallery_draws_generated_tables(tmp_path):
    pytest.importorskip("matplotlib")
    from pinball_env.tools import plot

    out = plot.main(["--gallery", "--difficulty", "hard", "--seeds", "3", "4",
                     "--out", str(tmp_path / "gallery.png")])  # fmt: skip
    assert out.stat().st_size > 10_000
    with pytest.raises(SystemExit):
        plot.main(["--gallery", "--seeds", "0", "0"])


def test_a_world_of_different_tables_steps_each_env_as_its_own_world():
    tables = [load_table("classic")]
    tables += [generate_table(s, d) for s in range(3) for d in procgen.DIFFICULTIES]
    n = len(tables)
    world = World(tables[0], n, num_threads=2)
    for env, table in enumerate(tables[1:], 1):
        world.set_table(env, table)
    assert world.state.hits.shape[1] == max(len(t.element_scores) for t in tables)
    singles = [World(table) for table in tables]
    rng = np.random.default_rng(0)
    for frame in range(1200):
        for env, single in enumerate(singles):
            if not single.active[0, 0]:  # relaunch drained balls, the same in both
                speed = rng.uniform(*tables[env].plunger.speed)
                single.launch(0, speed)
                world.launch(env, speed)
        buttons = rng.random((n, 2)) < 0.3
        world.step(buttons)
        points = world.frame_points()
        for env, single in enumerate(singles):
            single.step(buttons[env : env + 1])
            assert np.array_equal(single.balls[0, 0], world.balls[env, 0]), (frame, env)
            assert np.array_equal(single.state.flipper_angle[0], world.state.flipper_angle[env])
            assert single.frame_points()[0] == points[env]
            assert single.frame_contacts(0) == world.frame_contacts(env)
    copy = pickle.loads(pickle.dumps(world))
    world.step(buttons)
    copy.step(buttons)
    assert np.array_equal(copy.balls, world.balls)
    assert copy.table_of(3) == world.table_of(3) == tables[3]


def test_a_world_takes_only_tables_with_the_same_flipper_buttons():
    world = World(load_table("classic"), 2)
    data = table_to_dict(generate_table(0))
    data["flippers"] = data["flippers"][:1]
    with pytest.raises(ValueError, match="buttons"):
        world.set_table(1, table_from_dict(data))
