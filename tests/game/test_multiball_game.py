"""The game of several balls on classic_v3: the trough and drains (a ball is lost only
when the last ball in play drains), locks, the multiball's start and end, its ball save, the
jackpot lit only during a multiball, and random play that keeps every ball sound."""

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from pinball_env.game import Game
from pinball_env.physics.columns import BALL_VX, BALL_VY, BALL_X, BALL_Y
from pinball_env.table import load_table

TABLE = load_table("classic_v3")
NOOP = np.array([0])
LOCK = TABLE.locks[0]
SAUCER = TABLE.saucers[0]


def new_game(position=(0.25, 0.5), velocity=(0.0, 0.0), seed=0):
    game = Game(TABLE, 1)
    rng = np.random.default_rng(seed)
    game.new_game(0, rng, {"ball_position": position, "ball_velocity": velocity})
    return game, rng


def in_play(game):
    return int((game.world.ball_active[0] & ~locked(game)).sum())


def locked(game):
    world = game.world
    return world.ball_held[0] & np.isin(world.holder[0], world.lock_ids)


def lights(game):
    names = [light.name for light in TABLE.rules.lights]
    return {name for name, lit in zip(names, game.state.lights[0], strict=True) if lit}


def events(game):
    names = game.event_names
    return {names[i] for i in np.flatnonzero(game.state.rule_events[0])}


def step_until(game, rng, done, limit=2000):
    for _ in range(limit):
        game.step(NOOP, [rng])
        if done():
            return
    raise AssertionError("never happened")


def start_multiball(game, rng):
    """Lock two balls: the second lock starts the multiball."""
    step_until(game, rng, lambda: locked(game).sum() == 1 and in_play(game) == 1)
    assert game.state.balls_left[0] == 3  # a ball was served
    free = np.flatnonzero(game.world.ball_active[0] & ~game.world.ball_held[0])
    game.world.place_ball(0, LOCK.slots[1], (0.0, 0.0), ball=int(free[0]))
    step_until(game, rng, lambda: game.state.multiball[0])


def test_a_ball_drains_back_to_the_trough_and_is_lost_only_when_the_last_drains():
    game, rng = new_game()
    game.state.pending_balls[0] = 2  # as add_balls: the auto-plunger launches two more
    step_until(game, rng, lambda: in_play(game) == 3)
    assert game.state.multiball[0] and game.state.multiballs[0] == 1
    assert game.state.pending_balls[0] == 0
    seen = []
    for _ in range(20000):
        before = in_play(game)
        game.step(NOOP, [rng])
        seen.append(in_play(game))
        if before > 0 and in_play(game) == 0:
            break
        if game.state.balls_left[0] == 3 and in_play(game) < before:
            assert not game.state.drained[0]  # a ball back in the trough, none lost
    # The last ball drained: the ball is lost, the next served onto the plunger.
    assert 1 in seen
    assert game.state.balls_left[0] == 2 and game.state.drained[0]
    assert game.state.on_plunger[0] and not game.state.multiball[0]
    assert game.world.ball_active[0].sum() == 0  # every ball back (the next on the plunger)


def test_the_auto_plunger_launches_one_ball_at_a_time_from_the_trough():
    game, rng = new_game()
    game.state.pending_balls[0] = 5  # more than the trough holds: the rest are dropped
    launched = []
    for _ in range(200):
        game.step(NOOP, [rng])
        launched.append(int(game.world.ball_active[0].sum()))
    assert max(np.diff(launched)) <= 1  # one a frame at most
    assert max(launched) == 3 and game.state.pending_balls[0] == 0


def test_a_locked_ball_is_not_lost_and_the_second_lock_starts_a_multiball():
    game, rng = new_game(LOCK.slots[0])
    game.step(NOOP, [rng])
    assert locked(game).sum() == 1 and game.state.score[0] == LOCK.score
    assert "lock 1" in events(game) and lights(game) == {"lock_1_lit"}
    assert game.state.balls_left[0] == 3 and game.in_play[0]  # a ball served, none lost
    start_multiball(game, rng)
    assert in_play(game) == 3 and not locked(game).any()  # the lock let both go, plus one
    assert game.state.multiballs[0] == 1 and "jackpot_lit" in lights(game)
    assert not {"lock_1_lit", "lock_2_lit"} & lights(game)
    # The multiball ends with one ball left in play: the jackpot goes out.
    step_until(game, rng, lambda: not game.state.multiball[0], limit=20000)
    assert in_play(game) <= 1 and "jackpot out" in events(game)
    assert "jackpot_lit" not in lights(game)
    assert game.state.balls_left[0] == 3 or game.state.balls_left[0] == 2


def test_a_ball_that_drains_during_the_multiballs_ball_save_is_launched_again():
    game, rng = new_game(LOCK.slots[0])
    start_multiball(game, rng)
    assert game.state.multiball_save[0] > 0
    step_until(game, rng, lambda: in_play(game) == 3)
    ball = int(np.flatnonzero(game.world.ball_active[0])[0])
    game.world.place_ball(0, (0.25, 0.034), (0.0, -2.0), ball=ball)  # drains this frame
    game.step(NOOP, [rng])
    assert game.state.pending_balls[0] == 1 or in_play(game) == 3
    step_until(game, rng, lambda: in_play(game) == 3 and game.state.pending_balls[0] == 0)
    assert game.state.balls_left[0] == 3
    # After the save, a drain is a ball back to the trough.
    game.state.multiball_save[0] = 0
    ball = int(np.flatnonzero(game.world.ball_active[0])[0])
    game.world.place_ball(0, (0.25, 0.034), (0.0, -2.0), ball=ball)
    game.step(NOOP, [rng])
    assert in_play(game) == 2 and game.state.pending_balls[0] == 0


def test_the_jackpot_scores_only_while_lit():
    game, rng = new_game(SAUCER.center)
    game.step(NOOP, [rng])
    assert game.state.points[0] == SAUCER.score and "jackpot" not in events(game)
    game, rng = new_game(LOCK.slots[0])
    start_multiball(game, rng)
    ball = int(np.flatnonzero(game.world.ball_active[0] & ~game.world.ball_held[0])[0])
    game.world.place_ball(0, SAUCER.center, (0.0, 0.0), ball=ball)
    game.step(NOOP, [rng])
    assert "jackpot" in events(game)
    assert game.state.points[0] >= SAUCER.score + 5000


def test_the_game_ball_is_the_first_in_play_and_a_snapshot_restores_every_ball():
    game, rng = new_game()
    game.state.pending_balls[0] = 2
    step_until(game, rng, lambda: in_play(game) == 3)
    first = int(np.flatnonzero(game.world.ball_active[0])[0])
    assert game.state.ball_slot[0] == first
    assert np.array_equal(game.world.state.balls[0], game.world.ball_states[0, first])
    snapshot = game.snapshot()
    rng_state = rng.bit_generator.state
    trace = []
    for _ in range(100):
        game.step(NOOP, [rng])
        trace.append(game.world.ball_states.copy())
    game.restore(snapshot)
    rng.bit_generator.state = rng_state
    for expected in trace:
        game.step(NOOP, [rng])
        assert np.array_equal(game.world.ball_states, expected)


@settings(max_examples=4)
@given(seed=st.integers(0, 2**16))
def test_random_play_keeps_every_ball_sound(seed):
    """Random buttons (nudges and the plunger included) with three balls in play for 1500
    steps: no two balls overlap beyond the skin, none leaves the table, the state is finite."""
    game, rng = new_game(seed=seed)
    game.state.pending_balls[0] = 2
    r, skin = TABLE.ball.radius, TABLE.simulation.skin
    actions = np.random.default_rng(seed).integers(0, len(game.discrete_buttons), 1500)
    for action in actions:
        game.step(np.array([action]), [rng])
        if game.state.balls_left[0] == 0:
            game.new_game(0, rng)
            game.state.pending_balls[0] = 2
        balls = game.world.ball_states[0]
        assert np.isfinite(balls).all()
        active = np.flatnonzero(game.world.ball_active[0])
        xy = balls[active][:, [BALL_X, BALL_Y]]
        assert ((xy >= 0.0) & (xy <= (TABLE.width, TABLE.height))).all()
        for i in range(len(active)):
            for j in range(i):
                assert np.hypot(*(xy[i] - xy[j])) >= 2 * r - skin - 1e-9
        assert (np.abs(balls[active][:, [BALL_VX, BALL_VY]]) < 100.0).all()
