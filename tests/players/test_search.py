"""The planner (``players.search.SearchPolicy``): it looks ahead without touching the game it
plays (its state or its random stream), plays the heuristic's action where there is nothing
to choose, chooses the best branch, and refuses bad settings."""

import gymnasium as gym
import numpy as np
import pytest

from pinball_env.players import HeuristicPolicy, SearchPolicy, SearchSettings, VectorSearch
from pinball_env.players.search import Plan, Planner

SMALL = SearchSettings(horizon=6, holds=(2,))


def test_bad_settings_are_refused():
    for bad, message in (({"horizon": 0}, "horizon"), ({"holds": (9,), "horizon": 5}, "holds"),
                         ({"low": 1.5}, "low"), ({"decide_every": 0}, "decide_every"),
                         ({"decide": "often"}, "decide")):  # fmt: skip
        with pytest.raises(ValueError, match=message):
            SearchSettings(**bad)
    for bad, message in (({"aims": (0.0,)}, "aims"), ({"aims": (1.2,)}, "aims"),
                         ({"holds": (), "aims": ()}, "holds or aims")):  # fmt: skip
        with pytest.raises(ValueError, match=message):
            SearchSettings(**bad)


def test_the_plans_are_the_heuristic_its_other_aims_and_each_action_held():
    plans = SearchSettings(holds=(2, 8), aims=(0.3, 0.7)).candidates
    assert plans[0] == Plan() and [p.aim for p in plans[1:3]] == [0.3, 0.7]
    assert [(p.action, p.hold) for p in plans[3:]] == [(a, h) for h in (2, 8) for a in range(4)]
    assert len(SearchSettings(holds=(), aims=(0.4,)).candidates) == 2


def test_the_chosen_plan_plays_until_the_next_decision_and_its_aim_stays(monkeypatch):
    # Every 4 steps (a ball always low) a plan is chosen: here both flippers held 2 steps, then
    # the heuristic with aim 0.9, which stays the heuristic's aim until a new game.
    env = gym.make("Pinball-v3")
    settings = SearchSettings(horizon=4, holds=(2,), decide="steps", decide_every=4)
    player = SearchPolicy(env, settings)
    monkeypatch.setattr(player, "_search", lambda info: Plan(3, 2, 0.9))
    monkeypatch.setattr(player, "_low", lambda info: True)
    heuristic = HeuristicPolicy(env.unwrapped.table)
    heuristic.aim = 0.9
    _, info = env.reset(seed=5)
    for step in range(9):
        action = player(info)
        expected = int(heuristic(info))
        assert action == (3 if step % 4 < 2 else expected), step
        info = env.step(action)[4]
    assert player.heuristic.aim == 0.9
    player.reset()
    assert player.heuristic.aim == HeuristicPolicy(env.unwrapped.table).aim


@pytest.mark.parametrize("env_id", ["Pinball-v3", "Pinball-v0"])
def test_the_look_ahead_leaves_the_game_and_its_stream_as_they_are(env_id):
    # The game played with the planner is the game played with the actions it chose: its
    # look-ahead changes nothing of the env (state or stream) between two steps.
    env = gym.make(env_id, repeat_action_probability=0.25)
    replay = gym.make(env_id, repeat_action_probability=0.25)
    player = SearchPolicy(env, SMALL)
    _, info = env.reset(seed=100_000)
    replay.reset(seed=100_000)
    for _ in range(1500):
        stream = env.unwrapped.np_random.bit_generator.state
        action = player(info)
        assert env.unwrapped.np_random.bit_generator.state == stream
        assert action in range(env.action_space.n)
        obs, _, terminated, truncated, info = env.step(action)
        assert (replay.step(action)[0] == obs).all()
        if terminated or truncated:
            break
    assert player.decisions > 0 and player.branch_steps > 0
    assert player.branch_frames == player.branch_steps  # (one frame a step: no skips)
    player.close()


@pytest.mark.parametrize("skip_above", [0.0, 0.45])
def test_the_branch_frames_count_the_frames_each_step_plays(skip_above):
    # What a distillation's budget counts: every frame its branches play (2 a step at frame
    # skip 2; more with skip_above, whose steps run on while no ball is low).
    env = gym.make("Pinball-v3", frame_skip=2, skip_above=skip_above)
    player = SearchPolicy(env, SearchSettings(horizon=30, holds=(2,)))
    _, info = env.reset(seed=5)
    for _ in range(400):
        info = env.step(player(info))[-1]
    assert player.branch_steps > 0
    if skip_above:
        assert player.branch_frames > 2 * player.branch_steps
    else:
        assert player.branch_frames == 2 * player.branch_steps
    player.close()


def test_where_no_ball_is_low_it_plays_the_heuristics_action():
    env = gym.make("Pinball-v3")
    player = SearchPolicy(env, SearchSettings(horizon=4, holds=(1,), low=0.0))  # never low
    heuristic = HeuristicPolicy(env.unwrapped.table)
    _, info = env.reset(seed=3)
    for _ in range(300):
        action = player(info)
        assert action == heuristic(info)
        info = env.step(action)[4]
    assert player.decisions == 0


def test_the_chosen_action_is_the_first_of_the_best_branch():
    # Scored by hand: each candidate's branch played out from the saved game (a flipper action
    # held for the whole horizon, or the heuristic throughout), its points less the drain cost
    # of its lost balls; the planner plays the first action of the best (the heuristic's first).
    env = gym.make("Pinball-v3")
    settings = SearchSettings(horizon=10, holds=(10,), drain_cost=1e6)
    player = SearchPolicy(env, settings)
    _, info = env.reset(seed=11)
    for _ in range(3000):  # on to a flip: the first moment to choose
        if player._low(info) and player.heuristic.starts_flip(info):
            break
        info = env.step(player(info))[4]
    assert player.decisions == 0
    state = env.unwrapped.clone_state()
    scripted = player.heuristic.fork()
    chosen = player(info)
    values = []
    for action, _, _ in settings.candidates:
        branch = gym.make("Pinball-v3")
        branch.reset(seed=0)
        _, start = branch.unwrapped.restore_state(state)
        script, seen = scripted.fork(), info
        for _ in range(settings.horizon):
            seen = branch.step(action if action >= 0 else int(script(seen)))[4]
        values.append(seen["score"] - start["score"]
                      - 1e6 * (start["balls_left"] - seen["balls_left"]))  # fmt: skip
    best = settings.candidates[int(np.argmax(values))][0]
    assert chosen == (int(scripted.fork()(info)) if best < 0 else best)
    assert player.decisions == 1


def test_it_decides_where_the_heuristic_begins_a_flip_and_only_there(monkeypatch):
    # Deciding on flips: a decision at each step (a ball low) where the heuristic would send a
    # resting flipper up, none elsewhere; the heuristic's own state is left as it was.
    env = gym.make("Pinball-v3")
    player = SearchPolicy(env, SearchSettings(horizon=2, holds=(1,)))
    chosen: list[int] = []
    monkeypatch.setattr(player, "_search", lambda info: chosen.append(step) or Plan())
    heuristic = HeuristicPolicy(env.unwrapped.table)
    _, info = env.reset(seed=7)
    flips = []
    for step in range(1500):
        if player._low(info) and heuristic.starts_flip(info):
            flips.append(step)
        action = player(info)
        assert action == heuristic(info)
        info = env.step(action)[4]
    assert len(flips) > 3 and chosen == flips


def test_starts_flip_says_whether_a_resting_flipper_goes_up_and_changes_nothing():
    env = gym.make("Pinball-v3")
    heuristic = HeuristicPolicy(env.unwrapped.table)
    _, info = env.reset(seed=7)
    said = []
    for _ in range(1500):
        before = list(heuristic._held)
        starts = heuristic.starts_flip(info)
        assert heuristic._held == before
        action = heuristic(info)
        went_up = [was == 0 < now for was, now in zip(before, heuristic._held, strict=True)]
        assert starts == any(went_up)
        said.append(starts)
        info = env.step(action)[4]
    assert any(said) and not all(said)


@pytest.mark.parametrize("env_id", ["Pinball-v3", "Pinball-v2"])
def test_the_vector_search_plays_each_env_as_the_single_envs_planner(env_id):
    # Each env of a native vector env, played by VectorSearch, gets the actions SearchPolicy
    # chooses on a single env of the same seed: the same game, the same look-ahead.
    seeds = [100_000, 100_001]
    venv = gym.make_vec(env_id, num_envs=2, vectorization_mode="vector_entry_point",
                        repeat_action_probability=0.25)  # fmt: skip
    search = VectorSearch(venv, SMALL)
    _, infos = venv.reset(seed=seeds)
    singles = [gym.make(env_id, repeat_action_probability=0.25) for _ in seeds]
    players = [SearchPolicy(env, SMALL) for env in singles]
    single_infos = [env.reset(seed=seed)[1] for env, seed in zip(singles, seeds, strict=True)]
    for _ in range(3000):
        if search.planner.decisions >= 4:  # (a few decisions: enough)
            break
        actions = search([{key: value[env] for key, value in infos.items()} for env in range(2)])
        assert actions.tolist() == [p(i) for p, i in zip(players, single_infos, strict=True)]
        _, _, terminated, truncated, infos = venv.step(actions)
        single_infos = [env.step(int(a))[4] for env, a in zip(singles, actions, strict=True)]
        assert not (terminated | truncated).any()
    assert search.planner.decisions == sum(p.decisions for p in players) > 0
    search.close()


def test_the_vector_search_refuses_generated_tables():
    venv = gym.make_vec("PinballProcgen-v0", num_envs=1, vectorization_mode="vector_entry_point")
    with pytest.raises(ValueError, match="fixed table"):
        VectorSearch(venv)


def test_the_branches_draw_the_same_from_the_same_game_in_any_planner():
    # The branches draw (here the plunger's launch, 56 frames into the game) from a stream
    # seeded by the game's frame, not from their env's own: two planners, each with branch
    # envs of their own, play every branch to the same end.
    env = gym.make("Pinball-v3")
    _, info = env.reset(seed=3)
    state, table = env.unwrapped.clone_state(), env.unwrapped.table
    kwargs = env.unwrapped.options.to_kwargs()
    ends = []
    for _ in range(2):
        planner = Planner("Pinball-v3", kwargs, table, SearchSettings(horizon=120, holds=(2,)))
        planner.best(state, info, HeuristicPolicy(table))
        ends.append(planner.branches.step(np.zeros(len(planner.plans), dtype=np.int64))[0])
        planner.close()
    assert (ends[0] == ends[1]).all()
