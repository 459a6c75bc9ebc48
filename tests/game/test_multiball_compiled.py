"""The compiled passes of the several balls (``game.multiball.after_frames``,
``sim.world.play_holders``) against the per-env Python they replaced, kept here as the
reference: on states played and then stirred at random (drains, tilts, ball saves, stuck balls,
balls dropped at the saucer and the lock's slots), both leave every array the same."""

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from pinball_env.game import Game
from pinball_env.game.state import copy_state, copy_state_into
from pinball_env.physics.columns import BALL_VX, BALL_VY, BALL_X, BALL_Y
from pinball_env.table import load_table

TABLE = load_table("classic_v3")
N_ENVS = 16


def reference_after_frame(multi, envs):
    """``Multiball.after_frame`` as the per-env Python of its first version."""
    state, world = multi.state, multi.world
    for env in envs:
        state.multiball_events[env] = 0
        tilted = bool(state.world.tilted[env])
        if tilted:
            state.pending_balls[env] = 0
            state.multiball_save[env] = 0
            state.lock_release[env] = False
        drained = multi._was_active[env] & ~world.active[env]
        n_drained = int(drained.sum())
        if n_drained and state.multiball_save[env] > 0:
            state.pending_balls[env] += n_drained
        if state.multiball_save[env] > 0:
            state.multiball_save[env] -= 1
        game_ball, stuck = int(multi._watching[env]), 0
        for ball in range(multi.n_balls):  # the ball search
            in_play = bool(multi.playing(env)[ball])
            if ball == game_ball:
                continue
            xy = world.balls[env, ball, [BALL_X, BALL_Y]]
            gap = xy - state.ball_anchor[env, ball]
            if not in_play or world.held[env, ball] or gap @ gap > multi.radius2:
                state.ball_anchor[env, ball] = xy
                state.ball_still[env, ball] = 0
            else:
                state.ball_still[env, ball] += 1
                if state.ball_still[env, ball] >= multi.search_frames:
                    world.active[env, ball] = False
                    state.ball_still[env, ball] = 0
                    stuck += 1
        if stuck and not tilted:
            state.pending_balls[env] += stuck
        if (
            tilted
            and game_ball >= 0
            and multi.playing(env).sum() > 1
            and not world.held[env, game_ball]
            and state.still_frames[env] >= multi.search_frames
        ):
            world.active[env, game_ball] = False
        in_play = int(multi.playing(env).sum()) + int(state.pending_balls[env])
        took = world.state.hits[env, multi.lock_ids].sum() > 0
        if took and in_play == 0 and not (n_drained or state.on_plunger[env] or tilted):
            if multi.in_trough(env).any():
                state.pending_balls[env] += 1
            else:
                state.lock_release[env] = True
            in_play = 1
        if not state.multiball[env] and in_play >= 2:
            state.multiball[env] = True
            state.multiball_events[env, 0] = 1
            state.multiballs[env] += 1
        elif state.multiball[env] and in_play <= 1:
            state.multiball[env] = False
            state.multiball_events[env, 1] = 1
        multi.sync(env, drained)  # sync_ball: its own Python is its docstring's


def reference_play_holders(world, stepped):
    """``World._play_holders`` as the table-wide NumPy and per-env Python of its first version."""
    table, r, dt = world.table, world.settings.radius, world.settings.dt
    states, active, held = world.balls, world.active, world.held
    xy = states[..., [BALL_X, BALL_Y]]
    speed = np.hypot(states[..., BALL_VX], states[..., BALL_VY])
    free = active & ~held & stepped[:, None]

    def capture(env, ball, element, position, slot):
        hit_speed = float(np.hypot(*states[env, ball, [BALL_VX, BALL_VY]]))
        world.hold_ball(env, ball, position)
        world.holder[env, ball], world.slot[env, ball] = element, slot
        world.state.hits[env, element] += 1
        count = world.state.contact_count[env]
        if count < world.state.contacts.shape[1]:
            world.state.contacts[env, count] = (element, dt, hit_speed)
        world.state.contact_count[env] = count + 1
        free[env, ball] = False

    def fits(env, ball, position):  # no other ball on the table within two radii of the place
        others = world.active[env].copy()
        others[ball] = False
        return not (
            np.hypot(*(states[env, others][:, [BALL_X, BALL_Y]] - position).T) < 2 * r
        ).any()

    for s, saucer in enumerate(table.saucers):
        element = int(world.saucer_ids[s])
        mine = (world.holder == element) & stepped[:, None]
        world.held_time[mine] += dt
        due = mine & (world.held_time >= saucer.hold_time - 1e-9)
        for env, ball in zip(*np.nonzero(due), strict=True):
            world.release_ball(int(env), int(ball), saucer.kick)
            world.released_from[env, ball] = element
        near = np.hypot(*(xy - saucer.center).transpose(2, 0, 1)) <= saucer.radius
        world.released_from[(world.released_from == element) & ~near] = -1
        catch = free & near & (speed < saucer.capture_speed) & (world.released_from != element)
        for env in np.flatnonzero(catch.any(axis=1)):
            first = int(np.flatnonzero(catch[env])[0])
            if not (world.holder[env] == element).any() and fits(env, first, saucer.center):
                capture(int(env), first, element, saucer.center, 0)
    for k, lock in enumerate(table.locks):
        element, reach = int(world.lock_ids[k]), lock.capture_radius(r)
        slots = np.asarray(lock.slots)
        gaps = np.hypot(*(xy[:, :, None, :] - slots).transpose(3, 0, 1, 2))
        world.released_from[(world.released_from == element) & (gaps.min(axis=2) > reach)] = -1
        catch = free & (speed < lock.capture_speed) & (world.released_from != element)
        for env in np.flatnonzero(catch.any(axis=1)):
            taken = set(world.slot[env, world.holder[env] == element].tolist())
            for ball in np.flatnonzero(catch[env]):
                slot = next((j for j in range(len(slots)) if j not in taken), -1)
                if slot < 0 or gaps[env, ball, slot] > reach:
                    continue
                if fits(env, ball, lock.slots[slot]):
                    capture(int(env), int(ball), element, lock.slots[slot], slot)
                    taken.add(slot)


def arrays(record, prefix=""):
    """Every array of a record of arrays (nested records flattened), by name."""
    out = {}
    for name, value in zip(record._fields, record, strict=True):
        if isinstance(value, tuple):
            out.update(arrays(value, f"{prefix}{name}."))
        else:
            out[prefix + name] = value
    return out


def assert_same(left, right):
    for name, value in left.items():
        np.testing.assert_array_equal(value, right[name], err_msg=name)


def stir(game, rng):
    """Put the envs of ``game`` in states that random play rarely reaches: balls drained,
    stuck, dropped slowly at the saucer and the lock's slots, tilts and ball saves."""
    state, world = game.state, game.world
    n, m = world.active.shape
    spots = [TABLE.saucers[0].center, *TABLE.locks[0].slots]
    for env in range(n):
        for ball in range(m):
            if rng.random() < 0.2 and not world.held[env, ball]:
                x, y = spots[rng.integers(len(spots))]
                jitter = rng.normal(0.0, 0.01, 2)
                speed = rng.uniform(0.0, 1.5, 2)
                world.place_ball(env, (x + jitter[0], y + jitter[1]), tuple(speed), ball=ball)
            if rng.random() < 0.1:
                world.active[env, ball] = False  # drained
            if rng.random() < 0.1:
                state.ball_still[env, ball] = game.ball_search_frames - 1
        state.world.tilted[env] = rng.random() < 0.15
        if rng.random() < 0.2:
            state.multiball_save[env] = rng.integers(1, 3)
        if rng.random() < 0.2:
            state.still_frames[env] = game.ball_search_frames
        if rng.random() < 0.2:
            state.world.hits[env, world.lock_ids] = 1


@settings(max_examples=3, deadline=None)
@given(seed=st.integers(0, 2**16))
def test_the_compiled_passes_match_the_python_they_replaced(seed):
    game = Game(TABLE, N_ENVS)
    rngs = [np.random.default_rng([seed, env]) for env in range(N_ENVS)]
    for env in range(N_ENVS):
        game.new_game(env, rngs[env])
    stir_rng = np.random.default_rng(seed)
    world, multi = game.world, game.multi
    compiled_holders, compiled_after = world._play_holders, multi.after_frame
    memory = (multi._proxy, multi._proxy_active, multi._was_active, multi._watching)
    checked = []

    def both(compiled, reference, stepped):
        """Run ``compiled`` and ``reference`` on the same state; go on from the compiled one's."""
        stir(game, stir_rng)
        before, kept = copy_state(game.state), [array.copy() for array in memory]
        reference(stepped)
        expected = {name: array.copy() for name, array in arrays(game.state).items()}
        expected.update({str(i): array.copy() for i, array in enumerate(memory)})
        copy_state_into(before, game.state)
        for array, copy in zip(memory, kept, strict=True):
            array[...] = copy
        compiled(stepped)
        got = arrays(game.state) | {str(i): array for i, array in enumerate(memory)}
        assert_same(expected, got)
        checked.append(stepped.sum())

    def holders(envs):
        stepped = np.ones(N_ENVS, bool) if envs is None else envs
        both(compiled_holders, lambda mask: reference_play_holders(world, mask), stepped)

    def after(envs):
        both(compiled_after, lambda mask: reference_after_frame(multi, np.flatnonzero(mask)), envs)

    world._play_holders, multi.after_frame = holders, after
    game.on_frame = lambda: None  # each frame's physics in Python: World.step and the passes
    for _ in range(60):
        game.step(stir_rng.integers(0, 3, N_ENVS), rngs)
    assert game.state.multiballs.sum() > 0 and world.state.hits[:, world.lock_ids].sum() > 0
    assert sum(checked) > 0


def test_the_loops_own_frames_play_as_the_frames_handed_to_python():
    """Pinball-v3's frames played in the compiled step loop (``multiball_passes``, env by env)
    and handed to Python one at a time (``on_frame`` set: ``World.step`` and the all-env passes)
    give bitwise the same games, multiballs, locks and serves included."""
    games = [Game(TABLE, N_ENVS) for _ in range(2)]
    games[1].on_frame = lambda: None
    rngs = [[np.random.default_rng([7, env]) for env in range(N_ENVS)] for _ in games]
    stirs = [np.random.default_rng(7) for _ in games]  # the same stirring of both
    for game, streams in zip(games, rngs, strict=True):
        for env in range(N_ENVS):
            game.new_game(env, streams[env])
    actions = np.random.default_rng(7)
    for step in range(120):
        step_actions = actions.integers(0, 32, N_ENVS)
        for game, streams, stir_rng in zip(games, rngs, stirs, strict=True):
            if step % 4 == 0:
                stir(game, stir_rng)  # states random play rarely reaches: multiballs, locks
            game.step(step_actions, streams)
            for env in np.flatnonzero(game.state.balls_left == 0):
                game.new_game(env, streams[env])
        assert_same(arrays(games[1].state), arrays(games[0].state))
    assert games[0].state.multiballs.sum() > 0
