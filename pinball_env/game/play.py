"""The compiled step loop: every frame of a step, the physics and the rules, in one call.

:func:`play_frames` (:func:`play_frames_per_env` where envs play their own tables) runs, per
env, the frames of a step one after another: the World's kernel
(``step_ball``) for the physics and the rules written out beside it. It hands a step back to
Python only where Python must act (a launch, which draws from the env's random stream; a
physics backend other than the swept kernel), and takes it up again where it stopped
(:class:`StepProgress`). ``Game.step`` drives it; ``params`` is what it plays by, the
``StepParameters`` of ``game.parameters``.
"""

import math
from typing import NamedTuple

import numpy as np
from numba import njit

from pinball_env.game.multiball_passes import before_physics, multiball_frame
from pinball_env.game.rulebook import end_of_ball, run_rules
from pinball_env.physics import first_flipper
from pinball_env.physics.columns import (
    BALL_VY,
    BALL_X,
    BALL_Y,
    BOB_TOUCHES,
    CABINET_SHOVE_X,
    CABINET_SHOVE_Y,
)
from pinball_env.physics.step import step_ball


class StepProgress(NamedTuple):
    """Where each env is in the current step: the compiled loop hands it back to Python and
    takes it up again where it stopped.

    Why the hand-back stays: numba takes NumPy ``Generator`` objects (a typed list of them too)
    and draws bitwise what NumPy draws (checked on ``uniform``), so the loop could launch balls
    itself; but the pymunk backend and the ``on_frame`` hook need each frame's physics handed to
    Python anyway, so the stages serve them whatever launches do, and the envs' generators are
    Python objects that users replace (``reset(seed=...)``, ``set_attr("np_random", ...)``), which
    a typed list would have to follow. A launch comes back once a ball, which costs nothing that
    a benchmark sees.
    """

    stage: np.ndarray  # (N,) int64: what comes next (NEW_STEP ... STEP_DONE)
    frames: np.ndarray  # (N,) int64: frames played in this step
    reward: np.ndarray  # (N,) float64: summed over the step's frames
    points: np.ndarray  # (N,) int64: summed over the step's frames
    drained: np.ndarray  # (N,) bool: a ball drained in the step
    height_before: np.ndarray  # (N,) float64: the ball's height when the frame began [m]
    bonus_before: np.ndarray  # (N,) int64: the bonus times the multiplier when it began
    frame_points: np.ndarray  # (N,) int64: points of the frame under way
    frame_drained: np.ndarray  # (N,) bool: the frame under way drained a ball
    launch: np.ndarray  # (N,) bool: waits for a ball off the plunger before it goes on
    serve: np.ndarray  # (N,) bool: waits for the auto-plunger's launch of a queued ball
    plunge: np.ndarray  # (N,) bool: ... fired by the player's plunger (else by the machine)
    finite: np.ndarray  # (N,) bool: the ball state stayed finite
    skill_shot: np.ndarray  # (N,) bool: the skill shot was made in the step
    tilt: np.ndarray  # (N,) bool: the machine tilted in the step
    # (N, frame_skip + skip_frames) float64: the step's draws of the sticky actions, uniform in
    # [0, 1) from each env's stream, one per frame (no columns without sticky actions)
    repeat_draws: np.ndarray


# A step's stages, per env: its start, then per frame: the next frame chosen (or the step
# ended), its physics, its points and drains, the ball search, its reward (a launch may come
# between the last three).
NEW_STEP, NEXT_FRAME, PHYSICS, AFTER_PHYSICS, SEARCH, CLOSE_FRAME, STEP_DONE = range(7)


@njit(cache=True, nogil=True, _nrt=False)  # type: ignore[call-overload]  # _nrt: not in the stubs
def play_frames(
    geometries, settings, state, scratch, progress, params, commands, cabinet_buttons, swept,
    memory, several, start, stop,
):  # fmt: skip
    """:func:`play_step` with every env on one table (``geometries`` and ``settings`` tuples of
    one entry), compiled without reference counting (``_nrt=False``): numba counts a
    reference, atomically, for every array a compiled function receives or takes out of a
    record, which cost the step more than its physics (2.2 against 1.2 us per ball-frame on
    the classic table, measured). This loop allocates nothing, so it needs none."""
    play_step(geometries, settings, state, scratch, progress, params, commands, cabinet_buttons,
              swept, memory, several, start, stop)  # fmt: skip


@njit(cache=True, nogil=True)
def play_frames_per_env(
    geometries, settings, state, scratch, progress, params, commands, cabinet_buttons, swept,
    memory, several, start, stop,
):  # fmt: skip
    """:func:`play_step` with each env on its own table (typed lists of ``geometries`` and
    ``settings``, one entry per env), which take numba's reference counting."""
    play_step(geometries, settings, state, scratch, progress, params, commands, cabinet_buttons,
              swept, memory, several, start, stop)  # fmt: skip


# The one function here over 60 lines, by design, as ``step_ball``: every frame of a step in one
# compiled body, each record's arrays taken out once per call rather than once per helper and
# frame (about 1.7x faster a frame of the plain env, measured; see the docstring's end).
@njit(cache=True, inline="always")
def play_step(
    geometries, settings, state, scratch, progress, params, commands, cabinet_buttons, swept,
    memory, several, start, stop,
):  # fmt: skip
    """Take the step of envs ``start`` to ``stop`` on from where each is (``progress.stage``),
    each env's frames one after another, to its end (STEP_DONE), or to where it needs a launch
    (``progress.launch``, and ``progress.plunge`` for the player's plunger; Python draws it from
    the env's stream), or, unless ``swept``, the physics of a frame (PHYSICS; Python runs the
    world's backend). With ``swept`` the physics is the swept kernel's: :func:`step_ball` on
    ``geometries[env]`` and ``settings[env]`` (or their only entries, see ``World.tables``); or,
    on a table of several balls (``several``, the ``MultiballParameters`` of
    ``game.multiball_passes``, with ``memory`` the Multiball's; None for one ball, which
    compiles that branch out), the passes before the physics (which hand the env back to
    Python, ``progress.serve``, where the auto-plunger's launch is due: a draw from the env's
    stream) and ``multiball_frame`` (the several-ball kernel, the saucers and locks, the drains,
    the ball search of the other balls, the multiball's start and end). A ball state that is
    no longer finite ends the env's step (``progress.finite``).

    A frame: the flipper commands (the action's for the first ``frame_skip`` frames, then
    released while the ball is above ``skip_heights``; with sticky actions, the last frame's
    buttons again where the frame's draw is below ``params.repeat_probability``), the physics,
    the points scored, a drained ball (the next one is launched), the ball search
    (BALL_SEARCH_TIME), the frame's reward. Envs are independent: threads may share the range.

    With the cabinet (``params.cabinet``; ``cabinet_buttons`` (N, 4): plunger, nudge left,
    right, up) a frame also pulls the plunger while its button is held and fires a ball
    waiting on it when let go, shoves the cabinet for a nudge (at most once per
    ``nudge_frames``), scores the skill shot, counts the plumb bob's touches of its ring as
    warnings and tilts the machine past the allowed ones (flippers and kickers dead, no
    points, the ball lost), serves the next ball onto the plunger to wait for the player, and
    catches a ball that falls back down the shooter lane onto the plunger.

    Written out in one body, as ``step_ball``: numba counts a reference for every array taken
    out of a record, and taking them out once per call instead of once per helper and frame
    makes a frame of the plain env about 1.7x faster.
    """
    world = state.world
    balls, active, hits = state.game_ball, state.game_ball_active, world.hits
    flipper_command = world.flipper_command
    score, balls_left, drain_height = state.score, state.balls_left, state.drain_height
    anchor, still_frames, game_frames = state.anchor, state.still_frames, state.frames
    stage, frames, total = progress.stage, progress.frames, progress.reward
    points, drained = progress.points, progress.drained
    height_before = progress.height_before
    frame_points, frame_drained = progress.frame_points, progress.frame_drained
    launch, finite, plunge = progress.launch, progress.finite, progress.plunge
    cabinet, tilted, skill_shot, tilt = (
        world.cabinet,
        world.tilted,
        progress.skill_shot,
        progress.tilt,
    )
    pull, on_plunger, nudge_wait = state.plunger_pull, state.on_plunger, state.nudge_wait
    warnings, warning_age, skill_left = state.tilt_warnings, state.warning_age, state.skill_left
    lane_frames = state.lane_frames
    scores, heights, skip_heights = params.scores, params.heights, params.skip_heights
    r2 = params.radius * params.radius
    per_env = len(geometries) > 1  # else every env plays the one table
    geometry, setting = geometries[0], settings[0]
    flipper_id = first_flipper(geometry)
    for env in range(start, stop):
        if per_env:
            geometry, setting = geometries[env], settings[env]
            flipper_id = first_flipper(geometry)
        while not launch[env]:
            now = stage[env]
            if now == NEW_STEP:
                frames[env] = points[env] = 0
                total[env] = 0.0
                drained[env] = False
                finite[env] = True
                skill_shot[env] = tilt[env] = False
                if params.book.active:
                    state.rule_events[env, :] = 0
                stage[env] = NEXT_FRAME
            elif now == NEXT_FRAME:
                k = frames[env]
                held = k < params.frame_skip
                high = active[env] and balls[env, BALL_Y] > skip_heights[env]
                if high and params.skip_all_balls:  # and every other free ball in play
                    high = all_above(world.balls, world.active, world.held, env,
                                     skip_heights[env])  # fmt: skip
                if (
                    (params.max_frames >= 0 and game_frames[env] >= params.max_frames)
                    or (k > 0 and balls_left[env] == 0)  # the game ended in the step
                    or not (held or (high and k < params.frame_skip + params.skip_frames))
                ):
                    stage[env] = STEP_DONE
                    continue
                # The buttons the frame presses (state.pressed): the action's (released after
                # its frames), or with sticky actions, where the frame's draw says so, the last
                # frame's again (ALE's).
                n_flippers = flipper_command.shape[1]
                repeat = params.repeat_probability
                if not (repeat > 0.0 and progress.repeat_draws[env, k] < repeat):
                    for j in range(n_flippers):
                        state.pressed[env, j] = held and commands[env, j]
                    for j in range(cabinet_buttons.shape[1]):
                        state.pressed[env, n_flippers + j] = held and cabinet_buttons[env, j]
                for j in range(n_flippers):
                    flipper_command[env, j] = state.pressed[env, j] and not tilted[env]
                if params.cabinet:
                    cab = n_flippers  # the cabinet's buttons follow the flippers'
                    plunger, left = state.pressed[env, cab], state.pressed[env, cab + 1]
                    right, up = state.pressed[env, cab + 2], state.pressed[env, cab + 3]
                    # The plunger: pulled back while its button is held, fired when let go.
                    if plunger:
                        pull[env] = min(pull[env] + params.pull_step, params.stroke)
                    elif pull[env] > 0.0:
                        if on_plunger[env]:  # Python fires it: the scatter is a random draw
                            plunge[env] = launch[env] = True
                        else:
                            pull[env] = 0.0
                    # The nudge: a shove along the pressed directions, once per nudge_frames.
                    if nudge_wait[env] > 0:
                        nudge_wait[env] -= 1
                    if nudge_wait[env] == 0:
                        dx = (1.0 if right else 0.0) - (1.0 if left else 0.0)
                        dy = 1.0 if up else 0.0
                        length = math.sqrt(dx * dx + dy * dy)
                        if length > 0.0:
                            cabinet[env, CABINET_SHOVE_X] = params.nudge_impulse * dx / length
                            cabinet[env, CABINET_SHOVE_Y] = params.nudge_impulse * dy / length
                            nudge_wait[env] = params.nudge_frames
                height_before[env] = balls[env, BALL_Y]
                if params.bonus_shaping:
                    progress.bonus_before[env] = state.bonus[env] * state.multiplier[env]
                stage[env] = PHYSICS
            elif now == PHYSICS:
                if not swept:
                    break
                if several is not None:  # a game of several balls (None: compiled out)
                    if before_physics(state, memory, several, env):
                        progress.serve[env] = True  # Python draws the auto-plunger's launch
                        break
                    ok = multiball_frame(geometry, setting, state, scratch, memory, several, env)
                else:
                    ok = step_ball(geometry, setting, world, scratch, env, flipper_id)
                if not ok:
                    finite[env] = False
                    stage[env] = STEP_DONE
                else:
                    stage[env] = AFTER_PHYSICS
            elif now == AFTER_PHYSICS:  # points and drains; a launch for the next ball
                scored = 0
                for element in range(hits.shape[1]):
                    scored += hits[env, element] * scores[env, element]
                if params.cabinet:
                    scored = cabinet_rules(
                        env, scored, params, hits, cabinet, tilted, active, on_plunger,
                        warnings, warning_age, skill_left, skill_shot, tilt, still_frames,
                    )  # fmt: skip
                gone = balls_left[env] > 0 and not active[env] and not on_plunger[env]
                saved = False
                if params.book.active:
                    # The rules (a tilted machine plays none), the ball save, the bonus.
                    if not tilted[env]:
                        scored += run_rules(env, params.book, state, scores[env])
                        if state.save_frames[env] > 0:
                            state.save_frames[env] -= 1
                    if gone:
                        award = end_of_ball(env, params.book, state, tilted[env])
                        saved = award < 0
                        gone = not saved
                        scored += max(award, 0)
                score[env] += scored
                if gone:
                    drain_height[env] = balls[env, BALL_Y]
                    balls_left[env] -= 1
                frame_points[env] = scored
                frame_drained[env] = gone
                launch[env] = (gone and balls_left[env] > 0) or saved
                if params.cabinet:
                    ball = balls[env]
                    caught = (
                        active[env]
                        and abs(ball[BALL_X] - params.plunger_x) < params.radius
                        and ball[BALL_Y] <= params.plunger_y
                        and ball[BALL_VY] <= 0.0
                    )
                    if launch[env] or caught:
                        # The next ball, or one fallen back down the shooter lane, waits on the
                        # plunger for the player.
                        put_ball(ball, params.plunger_x, params.plunger_y)
                        active[env] = False
                        on_plunger[env] = True
                        skill_left[env] = 0
                    if launch[env]:  # a new ball: the tilt is over
                        launch[env] = False
                        tilted[env] = False
                        warnings[env] = warning_age[env] = 0
                stage[env] = SEARCH
            elif now == SEARCH:  # a ball that has not moved a radius for long is served again
                dx = balls[env, BALL_X] - anchor[env, 0]
                dy = balls[env, BALL_Y] - anchor[env, 1]
                if (not active[env] and not on_plunger[env]) or dx * dx + dy * dy > r2:
                    anchor[env, 0] = balls[env, BALL_X]
                    anchor[env, 1] = balls[env, BALL_Y]
                    still_frames[env] = 0
                else:  # (a tilted ball is given up instead, see cabinet_rules)
                    still_frames[env] += 1
                    launch[env] = still_frames[env] >= params.search_frames and not tilted[env]
                if params.cabinet:
                    # A ball that stays in the shooter lane (plunged too softly, it falls back
                    # onto the plunger) is fired by the machine once it has been there as long.
                    in_lane = abs(balls[env, BALL_X] - params.plunger_x) < params.radius
                    lane_frames[env] = lane_frames[env] + 1 if in_lane else 0
                    if on_plunger[env]:
                        launch[env] = lane_frames[env] >= params.search_frames and not tilted[env]
                stage[env] = CLOSE_FRAME
            elif now == CLOSE_FRAME:  # the frame's reward
                gone = frame_drained[env]
                reward = frame_points[env] * params.reward_scale
                if params.drain_penalty:
                    reward -= params.drain_penalty * gone
                if params.bonus_shaping:
                    # The bonus's reward as it is earned; where it is scored (or lost), the
                    # pending bonus falls to 0 and its share is taken back.
                    pending = state.bonus[env] * state.multiplier[env] - progress.bonus_before[env]
                    reward += params.bonus_shaping * params.reward_scale * pending
                if params.height_shaping:
                    # A drained ball's last height is where it crossed the drain, not the next's.
                    after = drain_height[env] if gone else balls[env, BALL_Y]
                    reward += params.height_shaping * (after - height_before[env]) / heights[env]
                game_frames[env] += 1
                frames[env] += 1
                total[env] += reward
                points[env] += frame_points[env]
                drained[env] |= gone
                stage[env] = NEXT_FRAME
            else:
                break


@njit(cache=True, inline="always")
def all_above(balls, active, held, env, height):
    """Whether every free ball in play of env ``env`` (``balls`` (N, M, 5), ``active``,
    ``held`` (N, M)) is above ``height`` [m]."""
    for ball in range(balls.shape[1]):
        if active[env, ball] and not held[env, ball] and balls[env, ball, BALL_Y] <= height:
            return False
    return True


@njit(cache=True)
def put_ball(ball, x, y):
    """Put ``ball`` (a row of the balls array) at rest at (x, y)."""
    ball[:] = 0.0
    ball[BALL_X] = x
    ball[BALL_Y] = y


@njit(cache=True)
def cabinet_rules(
    env, scored, params, hits, cabinet, tilted, active, on_plunger, warnings, warning_age,
    skill_left, skill_shot, tilt, still_frames,
):  # fmt: skip
    """The cabinet's rules after env ``env``'s frame of physics, which scored ``scored``:
    returns the frame's points. The skill shot scores its bonus if its rollover is crossed
    while lit; each touch of the ring by the plumb bob is a warning (forgotten after
    ``warning_frames`` without another; touches within ``settle_frames`` of a warning are that
    warning), and one more than ``params.warnings`` tilts the
    machine. A tilted machine scores nothing; its ball is lost if it waits on the plunger,
    or given up where it lies once it has lain still as long as the ball search waits
    (``tilt``: the machine tilted in this step)."""
    if skill_left[env] > 0:
        skill_left[env] -= 1
        sensor = params.skill_sensors[env]
        if sensor >= 0 and hits[env, sensor] > 0:
            scored += params.skill_bonus
            skill_left[env] = 0
            skill_shot[env] = True
    touches = 0 if tilted[env] else int(cabinet[env, BOB_TOUCHES])  # a tilted machine is deaf
    if touches > 0 and warnings[env] > 0 and warning_age[env] < params.settle_frames:
        touches = 0  # the bob still swinging from the shove that warned: the same warning
    if touches > 0:
        warnings[env] += touches
        warning_age[env] = 0
        if warnings[env] > params.warnings and not tilted[env]:
            tilted[env] = tilt[env] = True
    elif warnings[env] > 0:
        warning_age[env] += 1
        if warning_age[env] >= params.warning_frames:
            warnings[env] -= 1
            warning_age[env] = 0
    if tilted[env]:
        skill_shot[env] = False
        on_plunger[env] = False
        if still_frames[env] >= params.search_frames:
            active[env] = False
        return 0
    return scored


def new_progress(n_envs: int, repeat_draws: int = 0) -> StepProgress:
    """A zeroed :class:`StepProgress` for ``n_envs`` envs (``repeat_draws``: draws of the
    sticky actions per step)."""
    return StepProgress(
        stage=np.zeros(n_envs, dtype=np.int64),
        frames=np.zeros(n_envs, dtype=np.int64),
        reward=np.zeros(n_envs),
        points=np.zeros(n_envs, dtype=np.int64),
        drained=np.zeros(n_envs, dtype=bool),
        height_before=np.zeros(n_envs),
        bonus_before=np.zeros(n_envs, dtype=np.int64),
        frame_points=np.zeros(n_envs, dtype=np.int64),
        frame_drained=np.zeros(n_envs, dtype=bool),
        launch=np.zeros(n_envs, dtype=bool),
        serve=np.zeros(n_envs, dtype=bool),
        plunge=np.zeros(n_envs, dtype=bool),
        finite=np.ones(n_envs, dtype=bool),
        skill_shot=np.zeros(n_envs, dtype=bool),
        tilt=np.zeros(n_envs, dtype=bool),
        repeat_draws=np.zeros((n_envs, repeat_draws)),
    )
