"""The rules over a batch of envs: N games in one Game are N single games, bitwise; snapshots."""

import copy
import pickle

import numpy as np
import pytest

from pinball_env.game import DISCRETE_BUTTONS, MAX_RUN_ON_FRAMES, Game, discrete_action
from pinball_env.observation import StateObserver
from pinball_env.table import BUTTONS, load_table

CLASSIC = load_table("classic")
SEEDS = [3, 14, 15, 92, 65]


def random_actions(action_type: str, n_envs: int, steps: int, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    if action_type == "discrete":
        return rng.integers(0, len(DISCRETE_BUTTONS), size=(steps, n_envs))
    return rng.integers(0, 2, size=(steps, n_envs, len(BUTTONS)))


def play(game: Game, rngs: list[np.random.Generator], actions: np.ndarray) -> list[tuple]:
    """Every step's observation, reward, game over and info, each env's game restarted when over."""
    trace = []
    for step_actions in actions:
        reward, over = game.step(step_actions, rngs)
        trace.append((StateObserver(game).observe(), reward.copy(), over.copy(), game.infos()))
        for env in np.flatnonzero(over):
            game.new_game(env, rngs[env])
    return trace


@pytest.mark.parametrize("action_type", ["discrete", "multibinary"])
def test_a_batch_of_games_is_bitwise_the_single_games(action_type):
    kwargs = {"action_type": action_type, "height_shaping": 0.5, "balls": 1}
    n, steps = len(SEEDS), 1500
    actions = random_actions(action_type, n, steps, seed=7)
    batch = Game(CLASSIC, n_envs=n, **kwargs)
    rngs = [np.random.default_rng(seed) for seed in SEEDS]
    for env in range(n):
        batch.new_game(env, rngs[env])
    batch_trace = play(batch, rngs, actions)
    drained = 0
    for env, seed in enumerate(SEEDS):
        single = Game(CLASSIC, n_envs=1, **kwargs)
        rng = np.random.default_rng(seed)
        single.new_game(0, rng)
        single_trace = play(single, [rng], actions[:, env : env + 1])
        for (obs, reward, over, info), (obs1, reward1, over1, info1) in zip(
            batch_trace, single_trace, strict=True
        ):
            assert obs[env].tobytes() == obs1[0].tobytes()
            assert reward[env].tobytes() == reward1[0].tobytes()
            assert over[env] == over1[0]
            for key, value in info.items():
                assert value[env].tobytes() == info1[key][0].tobytes(), key
            drained += int(info1["drained"][0])
    assert drained >= n  # the games drained balls and started again: the launches are covered


def test_snapshot_and_restore_replay_a_game_exactly():
    game = Game(CLASSIC, n_envs=2)
    rngs = [np.random.default_rng(seed) for seed in (1, 2)]
    for env in range(2):
        game.new_game(env, rngs[env])
    actions = random_actions("discrete", 2, 900, seed=0)
    play(game, rngs, actions[:300])
    snapshot = game.snapshot()
    saved_rngs = copy.deepcopy(rngs)
    first = play(game, rngs, actions[300:])
    game.restore(snapshot)
    second = play(game, saved_rngs, actions[300:])
    for (obs, reward, _, info), (obs2, reward2, _, info2) in zip(first, second, strict=True):
        assert obs.tobytes() == obs2.tobytes()
        assert reward.tobytes() == reward2.tobytes()
        assert info["score"].tobytes() == info2["score"].tobytes()
    # The snapshot is a copy: playing on did not change it.
    assert snapshot.world.balls.tobytes() != game.world.balls.tobytes()


def test_restore_writes_into_the_arrays_the_kernel_uses():
    game = Game(CLASSIC, n_envs=1)
    game.new_game(0, np.random.default_rng(0))
    balls = game.world.state.balls
    game.restore(game.snapshot())
    assert game.world.state.balls is balls and game.state.world is game.world.state
    # On a table of one ball the game's ball is the World's slot 0, also after a pickle.
    for one in (game, pickle.loads(pickle.dumps(game))):
        assert np.shares_memory(one.state.game_ball, one.world.balls)
        one.world.place_ball(0, (0.2, 0.3))
        assert one.state.game_ball[0, 0] == 0.2 and one.state.game_ball_active[0]


@pytest.mark.parametrize(
    ("action_type", "actions"),
    [
        ("discrete", np.array([4, 0])),
        ("discrete", np.array([-1, 0])),
        ("discrete", np.array([0.5, 1.0])),
        ("discrete", np.array([1, 2, 3])),
        ("multibinary", np.array([[2, 0], [0, 0]])),
        ("multibinary", np.array([1, 0])),
    ],
)
def test_bad_actions_are_rejected_with_the_expected_form(action_type, actions):
    game = Game(CLASSIC, n_envs=2, action_type=action_type)
    with pytest.raises(ValueError, match=rf"invalid actions: expected .*{action_type}"):
        game.buttons(actions)


def test_discrete_actions_are_the_buttons_as_bits():
    for action, buttons in enumerate(DISCRETE_BUTTONS):
        assert discrete_action(buttons) == action
    assert DISCRETE_BUTTONS[1].tolist() == [True, False]  # left
    assert DISCRETE_BUTTONS[2].tolist() == [False, True]  # right


def test_a_step_of_k_frames_is_k_frames_with_the_action_held():
    kwargs = {"height_shaping": 0.5, "drain_penalty": 2.0, "balls": 2}
    n, k, steps = len(SEEDS), 4, 600
    actions = random_actions("discrete", n, steps, seed=11)
    skipping = Game(CLASSIC, n_envs=n, frame_skip=k, **kwargs)
    framing = Game(CLASSIC, n_envs=n, **kwargs)
    rngs = {game: [np.random.default_rng(seed) for seed in SEEDS] for game in (skipping, framing)}
    for game in (skipping, framing):
        for env in range(n):
            game.new_game(env, rngs[game][env])
    ended = np.zeros(n, dtype=bool)
    games_over = 0
    for step_actions in actions:
        reward, over = skipping.step(step_actions, rngs[skipping])
        total = np.zeros(n)
        points = np.zeros(n, dtype=np.int64)
        drained = np.zeros(n, dtype=bool)
        for _ in range(k):  # frame by frame, an env whose game is over stays as it is
            frame_reward, frame_over = framing.step(step_actions, rngs[framing], ended.copy())
            total += frame_reward
            points += np.where(ended, 0, framing.state.points)
            drained |= ~ended & framing.state.drained
            ended |= frame_over
        assert reward.tobytes() == total.tobytes()
        assert (skipping.state.points == points).all()
        assert (skipping.state.drained == drained).all()
        assert (over == ended).all()
        observed = [StateObserver(game).observe().tobytes() for game in (skipping, framing)]
        assert observed[0] == observed[1]
        for env in np.flatnonzero(over):
            games_over += 1
            for game in (skipping, framing):
                game.new_game(env, rngs[game][env])
        ended[:] = False
    assert games_over > 0  # games ended inside a step


def test_skip_above_runs_on_with_the_buttons_released_while_the_ball_is_high():
    # A game with skip_above is, frame by frame, the game that holds the action for the step's
    # frames, then releases the buttons while the ball is above the line (at most
    # MAX_RUN_ON_FRAMES frames); it is asked again only with the ball low, or after that many.
    n, k, line = len(SEEDS), 2, 0.3
    skipping = Game(CLASSIC, n_envs=n, frame_skip=k, skip_above=line, drain_penalty=1.0)
    framing = Game(CLASSIC, n_envs=n, drain_penalty=1.0)
    rngs = {game: [np.random.default_rng(seed) for seed in SEEDS] for game in (skipping, framing)}
    for game in (skipping, framing):
        for env in range(n):
            game.new_game(env, rngs[game][env])
    high_asks = lengths = 0
    for step_actions in random_actions("discrete", n, 500, seed=3):
        reward, over = skipping.step(step_actions, rngs[skipping])
        total = np.zeros(n)
        ended = np.zeros(n, dtype=bool)
        frames = np.zeros(n, dtype=np.int64)
        for frame in range(k + MAX_RUN_ON_FRAMES):
            high = framing.world.balls[:, 0, 1] > line * CLASSIC.height
            going = ~ended & ((frame < k) | (high & framing.world.active[:, 0]))
            if not going.any():
                break
            actions = np.where(frame < k, step_actions, 0)
            frame_reward, frame_over = framing.step(actions, rngs[framing], ~going)
            total += frame_reward
            frames += going
            ended |= frame_over
        assert reward.tobytes() == total.tobytes()
        observed = [StateObserver(game).observe().tobytes() for game in (skipping, framing)]
        assert observed[0] == observed[1]
        assert (skipping.state.frames == framing.state.frames).all()
        high = skipping.world.balls[:, 0, 1] > line * CLASSIC.height
        asked_high = high & skipping.world.active[:, 0] & ~over
        assert (frames[asked_high] == k + MAX_RUN_ON_FRAMES).all()  # only after the most
        high_asks += int(asked_high.sum())
        lengths += int(frames.sum())
        for env in np.flatnonzero(over):
            for game in (skipping, framing):
                game.new_game(env, rngs[game][env])
    assert lengths > 3 * k * 500 * n  # steps ran on for many frames
    assert 0 < high_asks < 0.1 * 500 * n


def test_skip_above_balls_all_plays_a_one_ball_game_as_first():
    # On a table of one ball every free ball in play is the game's ball: the same game.
    n = len(SEEDS)
    games = [Game(CLASSIC, n_envs=n, skip_above=0.3, skip_above_balls=watched)
             for watched in ("first", "all")]  # fmt: skip
    rngs = [[np.random.default_rng(seed) for seed in SEEDS] for _ in games]
    for game, game_rngs in zip(games, rngs, strict=True):
        for env in range(n):
            game.new_game(env, game_rngs[env])
    for actions in random_actions("discrete", n, 300, seed=8):
        results = [
            game.step(actions, game_rngs) for game, game_rngs in zip(games, rngs, strict=True)
        ]
        assert results[0][0].tobytes() == results[1][0].tobytes()
        assert games[0].world.balls.tobytes() == games[1].world.balls.tobytes()
        assert (games[0].state.frames == games[1].state.frames).all()


@pytest.mark.parametrize("num_threads", [1, 2])
@pytest.mark.parametrize("framed_by", ["backend", "on_frame"])
def test_the_compiled_step_loop_plays_the_frame_by_frame_loop_bitwise(num_threads, framed_by):
    # The swept kernel's envs play their steps in one compiled loop; other physics backends,
    # or a recorder's on_frame hook, go frame by frame with the same rules. Both ways, on the
    # swept physics, are one game: launches after drains, a ball search (env 0's ball rests on
    # the plunger), the time limit.
    kwargs = {"frame_skip": 2, "skip_above": 0.26, "height_shaping": 1.0, "drain_penalty": 5.0,
              "max_frames": 1500, "balls": 2}  # fmt: skip
    n = len(SEEDS)
    compiled = Game(CLASSIC, n_envs=n, num_threads=num_threads, **kwargs)
    framing = Game(CLASSIC, n_envs=n, **kwargs)
    hooked = []  # the game's frame count of each env at each call of on_frame
    if framed_by == "backend":
        framing.world.swept_kernel = False  # as the pymunk backend's world
    else:
        framing.on_frame = lambda: hooked.append(framing.state.frames.copy())
    rngs = {game: [np.random.default_rng(seed) for seed in SEEDS] for game in (compiled, framing)}
    for game in (compiled, framing):
        game.new_game(0, rngs[game][0], {"ball_velocity": [0.0, 0.0]})
        for env in range(1, n):
            game.new_game(env, rngs[game][env])
    traces = {game: play(game, rngs[game], random_actions("discrete", n, 900, seed=5))
              for game in (compiled, framing)}  # fmt: skip
    drained = 0
    for step, (ours, theirs) in enumerate(zip(traces[compiled], traces[framing], strict=True)):
        (obs, reward, over, info), (obs1, reward1, over1, info1) = ours, theirs
        assert obs.tobytes() == obs1.tobytes(), step
        assert reward.tobytes() == reward1.tobytes(), step
        assert (over == over1).all()
        for key, value in info.items():
            assert value.tobytes() == info1[key].tobytes(), (step, key)
        drained += int(info["drained"].sum())
    assert drained > n  # launches after drains
    # Env 0's ball first left the plunger by the ball search, ten seconds in, no ball lost.
    heights = [obs[0, 1] for obs, *_ in traces[compiled]]
    first = next(step for step in range(1, len(heights)) if heights[step] > heights[0] + 0.1)
    info = traces[compiled][first][3]
    assert info["balls_left"][0] == 2 and info["frames"][0] >= compiled.ball_search_frames
    if framed_by == "on_frame":  # once per frame: each step, as often as its longest env's
        played, before = 0, np.zeros(n, dtype=np.int64)
        for _, _, over, info in traces[framing]:
            played += int((info["frames"] - before).max())
            before = np.where(over, 0, info["frames"])
        assert len(hooked) == played > 900


def test_a_game_runs_out_of_time_at_max_frames_exactly():
    for frame_skip, skip_above in ((1, 0.0), (3, 0.0), (2, 0.4)):
        game = Game(CLASSIC, n_envs=2, frame_skip=frame_skip, skip_above=skip_above,
                    max_frames=500)  # fmt: skip
        rngs = [np.random.default_rng(s) for s in (0, 1)]
        for env in range(2):
            game.new_game(env, rngs[env])
        while not game.out_of_time().all():
            assert not game.out_of_time().any() or (game.state.frames == 500).any()
            game.step(np.array([1, 2]), rngs)
        assert (game.state.frames == 500).all()
        assert game.infos()["frames"].tolist() == [500, 500]


def test_a_drained_ball_costs_the_drain_penalty():
    game = Game(CLASSIC, n_envs=1, drain_penalty=1.5, reward_scale=0.0)
    rng = np.random.default_rng(0)
    game.new_game(0, rng)
    rewards = []
    for _ in range(7200):
        reward, over = game.step(np.array([0]), [rng])
        rewards.append((reward[0], game.state.drained[0]))
        if over[0]:
            break
    assert {reward for reward, drained in rewards if drained} == {-1.5}
    assert {reward for reward, drained in rewards if not drained} == {0.0}
    assert sum(drained for _, drained in rewards) == 3


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"frame_skip": 0}, "frame_skip must be an integer from 1 to 60"),
        ({"frame_skip": 2.5}, "frame_skip must be an integer from 1 to 60"),
        ({"drain_penalty": float("nan")}, "drain_penalty must be a finite number"),
        ({"skip_above": 1.0}, r"skip_above must be a number in \[0, 1\)"),
        ({"skip_above": -0.1}, r"skip_above must be a number in \[0, 1\)"),
        ({"max_frames": 0}, "max_frames must be None or an integer >= 1"),
        ({"max_frames": 10.0}, "max_frames must be None or an integer >= 1"),
    ],
)
def test_bad_step_options_are_rejected(kwargs, message):
    with pytest.raises(ValueError, match=message):
        Game(CLASSIC, **kwargs)


def test_a_game_plays_on_bitwise_when_an_env_gets_its_own_table():
    # The compiled loop runs on the one table until set_table gives an env its own (the
    # per-env path, which procgen uses): with an equal table the games are bitwise the same.
    games = [Game(CLASSIC, n_envs=2, frame_skip=2, skip_above=0.26) for _ in range(2)]
    rngs = [[np.random.default_rng(seed) for seed in (4, 5)] for _ in games]
    actions = random_actions("discrete", 2, 400, seed=9)
    for game, game_rngs in zip(games, rngs, strict=True):
        for env in range(2):
            game.new_game(env, game_rngs[env])
        play(game, game_rngs, actions[:200])
    games[0].set_table(1, load_table("classic"))  # its own (equal) table object
    for game, game_rngs in zip(games, rngs, strict=True):
        game.new_game(1, game_rngs[1])
    traces = [play(game, r, actions[200:]) for game, r in zip(games, rngs, strict=True)]
    for ours, theirs in zip(*traces, strict=True):
        assert ours[0].tobytes() == theirs[0].tobytes()
        assert ours[1].tobytes() == theirs[1].tobytes()
