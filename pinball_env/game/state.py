"""The game's state: everything that changes during play, for every env, in one record.

:class:`GameState` is to the game what ``physics.State`` is to the kernel (and holds it, as
``world``): :func:`make_game_state` allocates it once, :func:`clear_game` starts an env's game
over in it, and :func:`copy_state` / :func:`copy_state_into` snapshot and restore it as one
object. What does not change during play (every env's table) is the World's ``tables`` record.
"""

from typing import Any, NamedTuple

import numpy as np

from pinball_env.game.actions import CABINET_BUTTONS
from pinball_env.game.rulebook import RuleBook
from pinball_env.physics import State
from pinball_env.table.rules import RuleSet


class BallHolders(NamedTuple):
    """What holds each ball slot (the World's saucers and locks, see ``sim.world``), held here
    so that a snapshot has it too. The balls themselves are the kernel's (``world.balls``)."""

    holder: np.ndarray  # (N, M) int64: the element holding it (-1: none)
    slot: np.ndarray  # (N, M) int64: its slot in a lock
    held_time: np.ndarray  # (N, M) float64: how long it has been held [s]
    released_from: np.ndarray  # (N, M) int64: the element it last left


def ball_holders(world: Any) -> BallHolders:
    """``world``'s holder arrays as a :class:`BallHolders`: the arrays themselves, not copies."""
    return BallHolders(world.holder, world.slot, world.held_time, world.released_from)


class GameState(NamedTuple):
    """Everything that changes during play, for every env (the first axis)."""

    world: State  # the kernel's arrays: the ball slots, flippers, contacts, hits
    # The game's ball: the ball the rules play (the drain, the plunger, the ball search, the
    # tilt). On a table of one ball, views of its slot (world.balls[:, 0], world.active[:, 0]);
    # on a table of several, game.multiball's (the first in play, ball_slot).
    game_ball: np.ndarray  # (N, 5) float64
    game_ball_active: np.ndarray  # (N,) bool
    balls_left: np.ndarray  # (N,) int64: balls still to play, the one in play included
    score: np.ndarray  # (N,) int64: points scored in the current game
    drain_height: np.ndarray  # (N,) float64: where the last drained ball crossed the drain [m]
    points: np.ndarray  # (N,) int64: points of the last step
    drained: np.ndarray  # (N,) bool: a ball drained in the last step
    anchor: np.ndarray  # (N, 2) float64: where the ball was when it last moved a radius [m]
    still_frames: np.ndarray  # (N,) int64: frames since then (see BALL_SEARCH_TIME)
    frames: np.ndarray  # (N,) int64: frames played in the current game
    # The cabinet (tables with one): the tilt itself is the kernel's (world.tilted).
    plunger_pull: np.ndarray  # (N,) float64: how far the plunger is pulled back [m]
    on_plunger: np.ndarray  # (N,) bool: the ball in play waits on the plunger
    nudge_wait: np.ndarray  # (N,) int64: frames until the next nudge can shove the cabinet
    tilt_warnings: np.ndarray  # (N,) int64: warnings standing
    warning_age: np.ndarray  # (N,) int64: frames since the last warning
    skill_left: np.ndarray  # (N,) int64: frames the skill shot stays lit (0: dark)
    lane_frames: np.ndarray  # (N,) int64: frames the ball has stayed in the shooter lane
    # The rules (tables with them, see ``game.rulebook``; the targets' state is the kernel's).
    lights: np.ndarray  # (N, L) bool
    counters: np.ndarray  # (N, C) int64
    timers: np.ndarray  # (N, Tm) int64: frames each timer still runs (0: stopped)
    bonus: np.ndarray  # (N,) int64: the end-of-ball bonus so far [points]
    multiplier: np.ndarray  # (N,) int64: the bonus multiplier (1 to max_multiplier)
    save_frames: np.ndarray  # (N,) int64: frames the ball save lasts (-1: from the launch, 0: off)
    rule_points: np.ndarray  # (N,) int64: points the rules scored in this game
    rule_events: np.ndarray  # (N, R + 2) int64: rules fired in the last step (RuleSet.event_names)
    lights_were_on: np.ndarray  # (N, R) bool: a lights_on rule's lights were all lit
    flippers_before: np.ndarray  # (N, F) bool: the flipper commands of the last frame
    # The flipper commands and cabinet buttons the last frame pressed (with sticky actions,
    # repeat_action_probability, the next frame may press them again).
    pressed: np.ndarray  # (N, F + 4) bool
    # Several balls (a trough of more than one, see ``game.multiball``).
    holders: BallHolders  # what holds each ball slot (the World's saucers and locks)
    ball_slot: np.ndarray  # (N,) int64: the slot of the game's ball (-1: none)
    pending_balls: np.ndarray  # (N,) int64: balls the auto-plunger is still to launch
    multiball: np.ndarray  # (N,) bool: two or more balls are in play
    multiball_save: np.ndarray  # (N,) int64: frames the multiball's ball save still runs
    multiball_events: np.ndarray  # (N, 2) int64: the frame's multiball starts and ends
    multiballs: np.ndarray  # (N,) int64: multiballs started in the current game
    lock_release: np.ndarray  # (N, K) bool: the rules released lock k in the frame
    # The ball search of every ball slot (game.multiball): where each ball last moved a radius
    # from, and frames since (the game's ball's own clock is ``anchor``/``still_frames``).
    ball_anchor: np.ndarray  # (N, M, 2) float64 [m]
    ball_still: np.ndarray  # (N, M) int64


def make_game_state(
    world: State,
    book: RuleBook,
    rule_set: RuleSet,
    n_flippers: int,
    holders: BallHolders,
    several: bool,
    n_locks: int = 0,
) -> GameState:
    """A :class:`GameState` around the kernel's ``world`` arrays (as many envs), every game at
    its start but for the balls (none left: :func:`clear_game` deals them).

    Args:
        world: the kernel's state of every env (the World's ``state``).
        book: the table's rules compiled (``game.rulebook``): its rules and timers.
        rule_set: the table's rules as data (an empty ``RuleSet`` without): its lights, counters.
        n_flippers: the table's flippers.
        holders: the World's holder arrays (``ball_holders(world)``).
        several: the table has several balls (``game.multiball``): the game's ball is an array
            of its own, else slot 0.
        n_locks: the table's locks.
    """
    n_envs, n_balls = world.active.shape
    if several:
        game_ball = np.zeros((n_envs, world.balls.shape[2]))
        game_ball_active = np.zeros(n_envs, dtype=bool)
    else:
        game_ball, game_ball_active = world.balls[:, 0], world.active[:, 0]
    shapes = _zero_shapes(world, book, rule_set, n_flippers, n_locks, n_balls if several else 0)
    zeros = {
        name: np.zeros((n_envs, *shape), dtype=dtype) for name, (shape, dtype) in shapes.items()
    }
    return GameState(
        world=world,
        game_ball=game_ball,
        game_ball_active=game_ball_active,
        multiplier=np.ones(n_envs, dtype=np.int64),
        holders=holders,
        ball_slot=np.full(n_envs, -1, dtype=np.int64),
        **zeros,
    )


def _zero_shapes(
    world: State, book: RuleBook, rule_set: RuleSet, n_flippers: int, n_locks: int, n_slots: int
) -> dict[str, tuple[tuple[int, ...], type]]:
    """The shape past the env axis and the dtype of each field of :class:`GameState` that
    starts at zero."""
    n_rules = len(book.trigger_kind)
    count, real, flag = np.int64, np.float64, np.bool_
    return {
        "balls_left": ((), count),
        "score": ((), count),
        "drain_height": ((), real),
        "points": ((), count),
        "drained": ((), flag),
        "anchor": ((2,), real),
        "still_frames": ((), count),
        "frames": ((), count),
        "plunger_pull": ((), real),
        "on_plunger": ((), flag),
        "nudge_wait": ((), count),
        "tilt_warnings": ((), count),
        "warning_age": ((), count),
        "skill_left": ((), count),
        "lane_frames": ((), count),
        "lights": ((len(rule_set.lights),), flag),
        "counters": ((len(rule_set.counters),), count),
        "timers": ((len(book.timer_frames),), count),
        "bonus": ((), count),
        "save_frames": ((), count),
        "rule_points": ((), count),
        "rule_events": ((n_rules + 2,), count),
        "lights_were_on": ((n_rules,), flag),
        "flippers_before": ((n_flippers,), flag),
        "pressed": ((world.flipper_command.shape[1] + len(CABINET_BUTTONS),), flag),
        "pending_balls": ((), count),
        "multiball": ((), flag),
        "multiball_save": ((), count),
        "multiball_events": ((2,), count),
        "multiballs": ((), count),
        "lock_release": ((n_locks,), flag),
        "ball_anchor": ((n_slots, 2), real),
        "ball_still": ((n_slots,), count),
    }


def clear_game(
    state: GameState, env: int, balls: int, lights: list[bool] | None, cabinet: bool
) -> None:
    """Start env ``env``'s game over in ``state``: ``balls`` to play, no score, no events of the
    last game; the rules' state (where ``lights``, the lights lit at the start, is given: a
    table with rules or ball save) and the cabinet's (where ``cabinet``) at their start. The
    ball and the flippers are the World's to place."""
    state.world.hits[env] = 0  # the reset's info shows no events of the last game
    state.world.contact_count[env] = 0
    state.balls_left[env] = balls
    state.score[env] = 0
    state.points[env] = 0
    state.drained[env] = False
    state.frames[env] = 0
    state.pressed[env] = False
    for array in (state.pending_balls, state.multiball, state.multiball_save,
                  state.multiball_events, state.multiballs, state.lock_release,
                  state.ball_anchor, state.ball_still):  # fmt: skip
        array[env] = 0
    state.ball_slot[env] = -1
    if lights is not None:
        state.lights[env] = lights
        for array in (state.counters, state.timers, state.bonus, state.rule_points,
                      state.rule_events, state.lights_were_on):  # fmt: skip
            array[env] = 0
        state.multiplier[env] = 1
        state.save_frames[env] = -1
        state.flippers_before[env] = False
    if cabinet:
        state.world.cabinet[env] = 0.0
        state.world.tilted[env] = False
        for array in (state.nudge_wait, state.tilt_warnings, state.warning_age,
                      state.skill_left, state.lane_frames):  # fmt: skip
            array[env] = 0


def copy_state(record: tuple) -> Any:
    """A deep copy of a record of arrays (and nested records)."""
    return type(record)(*(copy_state(v) if isinstance(v, tuple) else v.copy() for v in record))


def copy_state_into(source: tuple, target: tuple) -> None:
    """Copy every array of record ``source`` into the same array of record ``target``."""
    for src, dst in zip(source, target, strict=True):
        if isinstance(dst, tuple):
            copy_state_into(src, dst)
        else:
            np.copyto(dst, src)
