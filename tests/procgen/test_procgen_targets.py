"""Generated tables with targets (``targets=True``, ``"procgen+targets:SEED"``): a drop bank and a
spinner drawn onto the layout from a stream of their own; the tables without them unchanged."""

import hashlib
import itertools
import json
import math

import gymnasium as gym
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import pinball_env  # noqa: F401  (registers the envs)
from pinball_env import procgen
from pinball_env.options import PinballOptions
from pinball_env.physics import point_segment_distance
from pinball_env.procgen import (
    CLEARANCE,
    generate,
    generate_table,
    load_any_table,
    parse_name,
    playability,
    table_name,
)
from pinball_env.procgen.obstacles import segment_distance
from pinball_env.table import TableError, table_from_dict, table_to_dict

# sha256 of json.dumps(table_to_dict(generate_table(seed, difficulty)), sort_keys=True), computed
# with the generator before targets existed: tables without targets must stay bitwise these
# (published scores depend on them).
BEFORE_TARGETS = {
    ("easy", 0): "fc69777da7bc37770a2abc7cc4472d4489632916c49f5c96e19823914fe1c230",
    ("easy", 1): "74dc0e1ef47685ef8c05510e0f1fff32efe85b908cc0b802e512de98535615e6",
    ("easy", 2): "0dbe69976f7964d3fc35ab25fe18881630864515d43a3986a5ec2c03d476c135",
    ("easy", 3): "b625a879e1b10bb972dde0e66c794aaa4a80bf20d14b872642f84c041b4c6d61",
    ("easy", 4): "cf4bf3408caaee43a0f89d5272d33fa7e87ce89ee03d4b66a889c7ca44164fcd",
    ("easy", 5): "96492f1b2148384b9e2fb646223a17a82b5e309f9a1f13aa36dd12575fb5967a",
    ("hard", 0): "5b89218eafdf89096d6470aa0df0862ab68e8f05acaac17a2353146ebb077469",
    ("hard", 1): "d3fd55ae0b2e7b79e28a713fb5cecefe4082984ade79956de9b73d4e895e66db",
    ("hard", 2): "8450f31cee8eba285a06998343d08598c9a8e8c44a9b3966cb93b0b7c29d4a97",
    ("hard", 3): "b327201fef602b31fbbf63187e9108e18f42493d80b0b7c696294dbc9e487b74",
    ("hard", 4): "36cc5bac44e2a0579b70d27bee3e1da792e139ad1f97ef4ba06ab299e74a1240",
    ("hard", 5): "558875163a55c15c3931fb7f494e975724d66a9009a27080edb9b228088a593d",
}
# Draws each of those took (seed 5 easy: its first layout was rejected).
BEFORE_DRAWS = {("easy", 5): 2}
CASES = sorted(BEFORE_TARGETS)


def digest(table) -> str:
    return hashlib.sha256(json.dumps(table_to_dict(table), sort_keys=True).encode()).hexdigest()


@pytest.fixture(scope="module")
def generated():
    """``generate`` of every case, without and with targets (each made once here)."""
    return {
        (difficulty, seed, targets): generate(seed, difficulty, targets)
        for difficulty, seed in CASES
        for targets in (False, True)
    }


@pytest.mark.parametrize(("difficulty", "seed"), CASES)
def test_tables_without_targets_are_bitwise_what_they_were(generated, difficulty, seed):
    made = generated[difficulty, seed, False]
    assert digest(made.table) == BEFORE_TARGETS[difficulty, seed]
    assert made.draws == BEFORE_DRAWS.get((difficulty, seed), 1)
    assert not made.targets and not made.table.has_targets
    assert "target" not in [m.name for m in made.table.materials]
    assert generate_table(seed, difficulty, targets=False) == made.table


@pytest.mark.parametrize(("difficulty", "seed"), CASES)
def test_a_table_with_targets_is_its_layout_plus_a_bank_and_a_spinner(generated, difficulty, seed):
    plain, made = generated[difficulty, seed, False], generated[difficulty, seed, True]
    table = made.table
    assert made.targets and table.name == table_name(seed, difficulty, True)
    assert table.name == f"procgen{'-hard' if difficulty == 'hard' else ''}+targets:{seed}"
    # Drawn after the rest from a stream of their own: the rest is the plain table's layout
    # (where the same draw was kept, as for all of these seeds).
    assert made.draws == plain.draws
    rest = table_to_dict(table)
    assert len(rest.pop("drop_targets")) == len(rest.pop("spinners")) == 1
    assert rest["materials"].pop("target") == {"restitution": 0.5, "friction": 0.3}
    base = table_to_dict(plain.table)
    assert "drop_targets" not in base and "spinners" not in base
    rest["name"] = base["name"]
    assert rest == base
    # The same seed gives the same table.
    assert digest(generate_table(seed, difficulty, True)) == digest(table)


@pytest.mark.parametrize(("difficulty", "seed"), CASES)
def test_the_bank_and_the_spinner_have_their_sizes_and_keep_clear(generated, difficulty, seed):
    table = generated[difficulty, seed, True].table
    assert table_from_dict(table_to_dict(table), table.source) == table
    (bank,) = table.drop_targets
    (spinner,) = table.spinners
    assert 2 <= len(bank.targets) <= 4 and bank.material == "target"
    assert all(t.score > 0 for t in bank.targets) and spinner.score > 0
    segments = [np.array(t.points, dtype=float) for t in bank.targets]
    direction = segments[0][1] - segments[0][0]
    direction /= np.linalg.norm(direction)
    for i, ends in enumerate(segments):
        assert 0.03 - 1e-4 <= np.linalg.norm(ends[1] - ends[0]) <= 0.04 + 1e-4
        for end in ends:  # in a line
            offset = end - segments[0][0]
            assert abs(offset[0] * direction[1] - offset[1] * direction[0]) < 1e-4
        if i:
            assert np.linalg.norm(ends[0] - segments[i - 1][1]) == pytest.approx(0.01, abs=1e-4)
    # Facing the flippers: the bank's line square to the way from its middle to the point
    # between them, a flipper's reach above their pivots.
    middle = (segments[0][0] + segments[-1][1]) / 2.0
    left = table.flippers[0]
    aim = np.array([table.flippers[0].pivot[0] + table.flippers[1].pivot[0], 0.0]) / 2.0
    aim[1] = left.pivot[1] + left.length + left.tip_radius
    assert abs((aim - middle) @ direction) < 1e-3 * np.linalg.norm(aim - middle)
    width = math.dist(*spinner.points)
    assert 0.05 - 1e-4 <= width <= 0.07 + 1e-4
    # Clear of everything else (and of each other) by CLEARANCE: a ball and a margin.
    lines = [("bank", (*segments[0][0], *segments[-1][1])), ("spinner", spinner.segment)]
    reach = {f.name: f.length + f.tip_radius for f in table.flippers}
    for name, line in lines:
        gaps = [segment_distance(line, s) for w in table.walls for s in w.segments()]
        gaps += [point_segment_distance(*p.center, *line) - p.radius for p in table.posts]
        gaps += [point_segment_distance(*f.pivot, *line) - reach[f.name] for f in table.flippers]
        gaps.append(point_segment_distance(*table.ball.start, *line) - table.ball.radius)
        assert min(gaps) >= CLEARANCE - 1e-4, name
        assert min(line[1], line[3]) > left.pivot[1] + 0.2  # up in the playfield
    assert segment_distance(*(line for _, line in lines)) >= CLEARANCE - 1e-4


@pytest.mark.parametrize(("difficulty", "seed"), [("easy", 0), ("hard", 3)])
def test_tables_with_targets_play(generated, difficulty, seed):
    table = generated[difficulty, seed, True].table
    assert playability(table, np.random.default_rng(seed + 1)) is None


@settings(max_examples=8)
@given(seed=st.integers(0, 2**40), difficulty=st.sampled_from(procgen.DIFFICULTIES))
def test_tables_with_targets_validate_round_trip_and_play(seed, difficulty):
    table = generate_table(seed, difficulty, True)
    assert table_from_dict(table_to_dict(table), table.source) == table
    assert len(table.drop_targets) == len(table.spinners) == 1
    # Playable for balls dropped at other random places than the generator's own check.
    assert playability(table, np.random.default_rng(seed + 1)) is None


def _with_bank(table, targets):
    data = table_to_dict(table)
    data["materials"]["target"] = {"restitution": 0.5, "friction": 0.3}
    data["drop_targets"] = [{
        "name": "blocker", "material": "target", "reset_time": 1.0,
        "targets": [{"name": f"b{i}", "points": p, "score": 100} for i, p in enumerate(targets)],
    }]  # fmt: skip
    return table_from_dict(data)


def test_a_bank_across_the_launch_path_or_the_drain_is_rejected():
    # A ball knocks a drop target down, so the balls rolled on the kernel get past a bank
    # standing across the drain; the check finds the way blocked with the targets standing.
    table = generate_table(4)
    assert playability(table, np.random.default_rng(0)) is None
    lane_x = next(w for w in table.walls if w.name == "lane_wall").points[0][0]
    right = table.width - procgen.MARGIN
    lane = _with_bank(table, [[[lane_x + 0.0005, 0.3], [right - 0.0005, 0.3]]])
    problem = playability(lane, np.random.default_rng(0))
    assert problem == "the drop targets block the plunger's launch path"
    xs = np.linspace(procgen.MARGIN + 0.0005, lane_x - 0.0005, 13)
    across = [[[float(a), 0.045], [float(b) - 0.0005, 0.045]] for a, b in itertools.pairwise(xs)]
    drain = _with_bank(table, across)
    problem = playability(drain, np.random.default_rng(0))
    assert problem == "the drop targets keep the ball from the drain"


def test_names_with_targets():
    assert parse_name("procgen+targets:5") == (5, "easy", True)
    assert parse_name("procgen-hard+targets:7") == (7, "hard", True)
    assert parse_name("procgen-hard:7") == (7, "hard", False)
    assert table_name(7, "hard", targets=True) == "procgen-hard+targets:7"
    assert load_any_table("procgen-hard+targets:3") == generate_table(3, "hard", True)
    with pytest.raises(TableError, match="seed of a generated table"):
        load_any_table("procgen+targets:x")
    with pytest.raises(TableError, match="no generator of tables is registered"):
        load_any_table("procgen+target:1")
    with pytest.raises(TypeError, match="targets must be True or False"):
        generate_table(0, "easy", targets=1)  # type: ignore[arg-type]


def test_the_targets_option():
    assert PinballOptions().targets is False
    assert PinballOptions(table="generated", targets=np.True_).targets is True
    with pytest.raises(ValueError, match="targets must be True or False, got 1"):
        PinballOptions(table="generated", targets=1)
    with pytest.raises(ValueError, match="targets: options of generated tables"):
        PinballOptions(targets=True)


def _play(env, steps, seed=0):
    """``steps`` random steps (a single env reset where a game ends; a vector env resets its
    own)."""
    env.action_space.seed(seed)
    for _ in range(steps):
        _, _, terminated, truncated, _ = env.step(env.action_space.sample())
        if not isinstance(terminated, np.ndarray) and (terminated or truncated):
            env.reset()


def test_the_procgen_env_plays_tables_with_targets():
    env = gym.make("PinballProcgen-v0", targets=True, num_layouts=4)
    plain = gym.make("PinballProcgen-v0", num_layouts=4)
    obs, info = env.reset(seed=0)
    assert obs.shape == plain.reset(seed=0)[0].shape == env.observation_space.shape
    table = env.unwrapped.table
    assert table.name == f"procgen+targets:{info['layout']}" and table.has_targets
    assert table == generate_table(int(info["layout"]), "easy", True)
    _play(env, 300)
    assert env.unwrapped.table.drop_targets and env.unwrapped.table.spinners


def test_the_vector_env_plays_tables_with_different_target_counts():
    vector = gym.make_vec("PinballProcgen-v0", num_envs=4, targets=True, num_layouts=20)
    vector.reset(seed=0, options={"layout": [0, 1, 2, 3]})
    world = vector.unwrapped.game.world
    tables = [world.table_of(env) for env in range(4)]
    counts = [len(t.drop_target_list) for t in tables]
    assert len(set(counts)) > 1, counts  # the world widened its rows for the largest bank
    assert world.state.targets_up.shape[1] >= max(counts)
    assert all(t.spinners for t in tables)
    _play(vector, 300)


def test_the_vector_env_with_targets_is_bitwise_n_single_envs():
    n, seed = 4, 0
    kwargs = {"num_layouts": 6, "targets": True, "balls": 1, "max_episode_steps": 200}
    vector = gym.make_vec("PinballProcgen-v0", num_envs=n, **kwargs)
    singles = [gym.make("PinballProcgen-v0", **kwargs) for _ in range(n)]
    obs, infos = vector.reset(seed=seed)
    for env, single in enumerate(singles):
        obs1, info1 = single.reset(seed=seed + env)
        assert obs[env].tobytes() == obs1.tobytes() and infos["layout"][env] == info1["layout"]
    counts = {len(vector.unwrapped.game.world.table_of(e).drop_target_list) for e in range(n)}
    assert len(counts) > 1, counts
    ended = np.zeros(n, dtype=bool)
    vector.action_space.seed(1)
    for _ in range(300):
        actions = vector.action_space.sample()
        obs, reward, terminated, truncated, infos = vector.step(actions)
        for env, single in enumerate(singles):
            if ended[env]:
                obs1, info1 = single.reset()
                reward1, terminated1, truncated1 = 0.0, False, False
            else:
                obs1, reward1, terminated1, truncated1, info1 = single.step(actions[env])
            assert obs[env].tobytes() == obs1.tobytes()
            assert (reward[env], terminated[env], truncated[env]) == (
                reward1, terminated1, truncated1,
            )  # fmt: skip
            assert infos["score"][env] == info1["score"]
        ended = terminated | truncated
