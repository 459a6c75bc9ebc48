"""The game of several balls on classic_v3: the trough and drains (a ball is lost only
when the last ball in play drains), locks, the multiball's start and end, its ball save, the
jackpot lit only during a multiball, and random play that keeps every ball sound."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pinball_env.game import Game
from pinball_env.game.parameters import MAX_RUN_ON_FRAMES
from pinball_env.physics.columns import BALL_VX, BALL_VY, BALL_X, BALL_Y
from pinball_env.procgen import generate_table
from pinball_env.table import load_table, table_from_dict, table_to_dict
from pinball_env.table.reachable import CELL

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
    return int((game.world.active[0] & ~locked(game)).sum())


def locked(game):
    world = game.world
    return world.held[0] & np.isin(world.holder[0], world.lock_ids)


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
    free = np.flatnonzero(game.world.active[0] & ~game.world.held[0])
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
    assert game.world.active[0].sum() == 0  # every ball back (the next on the plunger)


def test_the_auto_plunger_launches_one_ball_at_a_time_from_the_trough():
    game, rng = new_game()
    game.state.pending_balls[0] = 5  # more than the trough holds: the rest are dropped
    launched = []
    for _ in range(200):
        game.step(NOOP, [rng])
        launched.append(int(game.world.active[0].sum()))
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
    ball = int(np.flatnonzero(game.world.active[0])[0])
    game.world.place_ball(0, (0.25, 0.034), (0.0, -2.0), ball=ball)  # drains this frame
    game.step(NOOP, [rng])
    assert game.state.pending_balls[0] == 1 or in_play(game) == 3
    step_until(game, rng, lambda: in_play(game) == 3 and game.state.pending_balls[0] == 0)
    assert game.state.balls_left[0] == 3
    # After the save, a drain is a ball back to the trough.
    game.state.multiball_save[0] = 0
    ball = int(np.flatnonzero(game.world.active[0])[0])
    game.world.place_ball(0, (0.25, 0.034), (0.0, -2.0), ball=ball)
    game.step(NOOP, [rng])
    assert in_play(game) == 2 and game.state.pending_balls[0] == 0


def test_the_jackpot_scores_only_while_lit():
    game, rng = new_game(SAUCER.center)
    game.step(NOOP, [rng])
    assert game.state.points[0] == SAUCER.score and "jackpot" not in events(game)
    game, rng = new_game(LOCK.slots[0])
    start_multiball(game, rng)
    ball = int(np.flatnonzero(game.world.active[0] & ~game.world.held[0])[0])
    game.world.place_ball(0, SAUCER.center, (0.0, 0.0), ball=ball)
    game.step(NOOP, [rng])
    assert "jackpot" in events(game)
    assert game.state.points[0] >= SAUCER.score + 5000


def test_the_game_ball_is_the_first_in_play_and_a_snapshot_restores_every_ball():
    game, rng = new_game()
    game.state.pending_balls[0] = 2
    step_until(game, rng, lambda: in_play(game) == 3)
    first = int(np.flatnonzero(game.world.active[0])[0])
    assert game.state.ball_slot[0] == first
    assert np.array_equal(game.state.game_ball[0], game.world.balls[0, first])
    snapshot = game.snapshot()
    rng_state = rng.bit_generator.state
    trace = []
    for _ in range(100):
        game.step(NOOP, [rng])
        trace.append(game.world.balls.copy())
    game.restore(snapshot)
    rng.bit_generator.state = rng_state
    for expected in trace:
        game.step(NOOP, [rng])
        assert np.array_equal(game.world.balls, expected)


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
        balls = game.world.balls[0]
        assert np.isfinite(balls).all()
        active = np.flatnonzero(game.world.active[0])
        xy = balls[active][:, [BALL_X, BALL_Y]]
        assert ((xy >= 0.0) & (xy <= (TABLE.width, TABLE.height))).all()
        for i in range(len(active)):
            for j in range(i):
                assert np.hypot(*(xy[i] - xy[j])) >= 2 * r - skin - 1e-9
        assert (np.abs(balls[active][:, [BALL_VX, BALL_VY]]) < 100.0).all()


def with_a_lock(table):
    """``table`` (a generated one) with a trough of three balls and a two-slot lock where a ball
    in play can get to, clear of every element: the first place in its upper half, scanned
    from the top left, whose slots have a free disc of two ball radii around each."""
    data = table_to_dict(table)
    data["materials"] = {**data["materials"], "steel": {"restitution": 0.95, "friction": 0.1}}
    data["ball"] = {**data["ball"], "material": "steel"}
    data["trough"] = {"balls": 3, "auto_plunger": {"speed": [2.5, 3.0]}}
    free, r = table.free_space, table.ball.radius
    angles = np.linspace(0.0, 2.0 * np.pi, 16, endpoint=False)
    ring = 2.0 * r * np.stack([np.cos(angles), np.sin(angles)], axis=1)

    def clear(x, y):
        cells = np.round((np.array([x, y]) + ring) / CELL).astype(int)
        inside = (cells >= 0).all() and (cells < free.shape[::-1]).all()
        return inside and free[cells[:, 1], cells[:, 0]].all()

    for y in np.arange(0.85, 0.5, -0.01) * table.height:
        for x in np.arange(0.1, 0.9, 0.02) * table.width:
            if clear(x, y) and clear(x, y - 3.0 * r):
                slots = [[float(x), float(y)], [float(x), float(y - 3.0 * r)]]
                data["locks"] = [{"name": "lock", "slots": slots, "capture_speed": 1.0,
                                  "kick": [0.3, -0.5], "score": 100}]  # fmt: skip
                return table_from_dict(data, f"<{table.name} with a lock>")
    raise AssertionError(f"no place for a lock on {table.name}")


@settings(max_examples=4, deadline=None)
@given(seed=st.integers(0, 200))
def test_random_play_on_generated_tables_with_a_lock_keeps_every_ball_sound(seed):
    """A generated table (with targets) given a trough of three balls and a lock: random
    flipping with two extra balls queued whenever no multiball runs, 1200 steps
    (the lock takes balls in most of them): the balls stay sound (no overlap beyond the skin,
    on the table, finite)."""
    table = with_a_lock(generate_table(seed, "easy", True))
    game = Game(table, 1)
    rng = np.random.default_rng(seed)
    game.new_game(0, rng)
    r, skin = table.ball.radius, table.simulation.skin
    actions = np.random.default_rng(seed).integers(0, len(game.discrete_buttons), 1200)
    for action in actions:
        if game.state.balls_left[0] == 0:
            game.new_game(0, rng)
        if game.state.pending_balls[0] == 0 and not game.state.multiball[0]:
            game.state.pending_balls[0] = 2
        game.step(np.array([action]), [rng])
        balls = game.world.balls[0]
        assert np.isfinite(balls).all()
        active = np.flatnonzero(game.world.active[0])
        xy = balls[active][:, [BALL_X, BALL_Y]]
        assert ((xy >= 0.0) & (xy <= (table.width, table.height))).all()
        for i in range(len(active)):
            for j in range(i):
                assert np.hypot(*(xy[i] - xy[j])) >= 2 * r - skin - 1e-9


# --- the ball search and the tilt watch every ball -----------------------------------------

# Balls put back at these places (at rest) before each frame: MOVING's by turns, 5 cm apart (the
# ball moves a radius every frame), STUCK's the same (it never moves a radius).
MOVING = ((0.25, 0.9), (0.25, 0.95))
STUCK = ((0.15, 0.6),)


def two_balls_in_play(seed=0):
    """Slot 0 (the game's ball) and slot 1 in play, nothing queued."""
    game, rng = new_game(MOVING[0], seed=seed)
    game.world.place_ball(0, STUCK[0], ball=1)
    game.multi.sync(0)
    assert game.state.ball_slot[0] == 0 and in_play(game) == 2
    return game, rng


def play_pinned(game, rng, pins, until, limit):
    """Step, each ball of ``pins`` (slot -> places) put back at its places by turns, at rest,
    before each frame while it is in play, until ``until()``; returns the frames played."""
    world = game.world
    for frame in range(limit):
        if until():
            return frame
        for ball, places in pins.items():
            if world.active[0, ball] and not world.held[0, ball]:
                world.place_ball(0, places[frame % len(places)], ball=ball)
        game.step(NOOP, [rng])
    raise AssertionError("never happened")


def test_a_stuck_ball_that_is_not_the_games_ball_goes_back_to_the_trough_and_is_served_again():
    game, rng = two_balls_in_play()
    search = game.multi.search_frames
    pins = {0: MOVING, 1: STUCK}
    frames = play_pinned(game, rng, pins, lambda: not game.world.active[0, 1], 2 * search)
    assert search <= frames <= search + 2
    assert game.state.balls_left[0] == 3 and game.world.active[0, 0]  # none lost
    assert game.state.pending_balls[0] == 1  # served again: queued for the auto-plunger
    assert not game.state.multiball_events[0, 1]  # two balls still count: no multiball end
    game.step(NOOP, [rng])  # the auto-plunger launches it up the shooter lane
    assert in_play(game) == 2 and game.state.pending_balls[0] == 0
    launched = game.world.balls[0, 1]
    assert launched[BALL_X] == TABLE.plunger.position[0] and launched[BALL_VY] > 0.0


def test_a_stuck_ball_that_becomes_the_games_ball_keeps_its_clock():
    """Ball 1 lies still while ball 0 plays; ball 0 leaves play halfway: the game's ball is
    now ball 1, and the loop's ball search serves it again when its whole wait is up."""
    game, rng = two_balls_in_play()
    search = game.multi.search_frames
    half = search // 2
    pins = {0: MOVING, 1: STUCK}
    start = game.state.frames[0]
    play_pinned(game, rng, pins, lambda: game.state.frames[0] - start >= half, search)
    game.world.active[0, 0] = False  # ball 0 goes back to the trough (as if drained)
    game.state.multiball_save[0] = 0
    pins = {1: STUCK}
    served = lambda: game.world.balls[0, 1, BALL_X] == TABLE.plunger.position[0]  # noqa: E731
    play_pinned(game, rng, pins, served, search)
    assert search <= game.state.frames[0] - start <= search + 3  # not half + search
    assert game.state.ball_slot[0] == 1 and game.state.balls_left[0] == 3


def test_a_tilt_gives_up_every_ball_in_play_loses_the_ball_once_and_keeps_the_locked_ball():
    game, rng = new_game(LOCK.slots[0])
    step_until(game, rng, lambda: locked(game).sum() == 1 and in_play(game) == 1)
    game.state.pending_balls[0] = 1  # a second ball in play: a multiball (its ball save runs)
    step_until(game, rng, lambda: in_play(game) == 2)
    assert game.state.multiball[0]
    game.state.world.tilted[0] = True  # the machine tilts (as the plumb bob's warnings would)
    balls_left, held = [], [1]
    for _ in range(20000):
        game.step(NOOP, [rng])
        balls_left.append(int(game.state.balls_left[0]))
        held.append(int(locked(game).sum()))
        assert held[-1] >= held[-2]  # none let go from the lock (it may take one more)
        if balls_left[-1] < 3:
            break
        # Tilted: no ball is served or saved.
        assert game.state.pending_balls[0] == 0 and game.state.multiball_save[0] == 0
    # Lost once, when the last ball in play was gone; the locked balls stay locked.
    assert balls_left[-1] == 2 and balls_left.count(2) == 1
    assert in_play(game) == 0 and locked(game).sum() == held[-1] >= 1
    assert game.state.on_plunger[0] and not game.state.world.tilted[0]  # the next ball waits
    game.step(NOOP, [rng])
    assert game.state.balls_left[0] == 2 and locked(game).sum() == held[-1]


def test_tilted_a_ball_that_lies_still_is_given_up_and_not_served_again():
    game, rng = two_balls_in_play()
    game.state.multiball_save[0] = 0
    game.state.world.tilted[0] = True
    search = game.multi.search_frames
    # The other ball lies still: given up (back to the trough), nothing queued.
    pins = {0: MOVING, 1: STUCK}
    frames = play_pinned(game, rng, pins, lambda: not game.world.active[0, 1], 2 * search)
    assert search <= frames <= search + 2
    assert game.state.pending_balls[0] == 0 and game.state.balls_left[0] == 3
    # The game's ball lies still too: given up where it lies, and the ball is lost, once.
    pins = {0: STUCK}
    play_pinned(game, rng, pins, lambda: game.state.balls_left[0] < 3, 2 * search)
    assert game.state.balls_left[0] == 2 and game.world.active[0].sum() == 0


def test_tilted_the_games_ball_lying_still_is_given_up_while_another_plays_on():
    game, rng = two_balls_in_play()
    game.state.multiball_save[0] = 0
    game.state.world.tilted[0] = True
    search = game.multi.search_frames
    pins = {0: STUCK, 1: ((0.3, 0.9), (0.3, 0.95))}
    frames = play_pinned(game, rng, pins, lambda: not game.world.active[0, 0], 2 * search)
    assert search <= frames <= search + 2
    # Ball 1 plays on as the game's ball; no ball lost, none queued.
    assert game.state.ball_slot[0] == 1 and game.state.game_ball_active[0]
    assert game.state.balls_left[0] == 3 and game.state.pending_balls[0] == 0


@pytest.mark.parametrize("watched", ["first", "all"])
def test_skip_above_balls_all_hands_back_while_any_ball_in_play_is_low(watched):
    # A step runs on past its frame only while the watched balls are above the line: "first"
    # watches the game's ball (the first in play), "all" every free ball in play too, so only
    # "all" hands back for another ball low while the game's ball is high.
    line = 0.45 * TABLE.height
    game = Game(TABLE, 1, skip_above=0.45, skip_above_balls=watched)
    rng = np.random.default_rng(4)
    game.new_game(0, rng, {"ball_position": (0.25, 0.5)})
    state, world = game.state, game.world
    for_another = 0
    for step, action in enumerate(np.random.default_rng(5).integers(0, 2, size=3000)):
        if step % 300 == 0:
            state.pending_balls[0] = 2  # a multiball's balls (as add_balls queues them)
        before = state.frames[0]
        _, over = game.step(np.array([action]), [rng])
        if over[0]:
            break
        if not 1 < state.frames[0] - before < 1 + MAX_RUN_ON_FRAMES:
            continue  # it did not run on, or ran on as long as it may
        free = world.active[0] & ~world.held[0]
        any_low = (world.balls[0, free, BALL_Y] <= line).any()
        game_ball_low = not state.game_ball_active[0] or state.game_ball[0, BALL_Y] <= line
        assert game_ball_low or (watched == "all" and any_low)
        for_another += not game_ball_low
    assert (for_another > 0) == (watched == "all")
