"""What the envs report after a step: the per-step infos of a :class:`~pinball_env.game.Game`,
of every env as arrays (:func:`batch_infos`) or of one env as Python numbers
(:func:`env_info`), and the range of each of their numbers (:func:`info_ranges`)."""

import math
from typing import TYPE_CHECKING, Any

import numpy as np

from pinball_env.physics.columns import BALL_VX, BALL_VY, BALL_X, BALL_Y, CABINET_X, CABINET_Y

if TYPE_CHECKING:
    from pinball_env.game.game import Game


def element_events(game: "Game", env: int) -> dict[str, int]:
    """The scoring elements env ``env`` hit in the last step: name -> hits."""
    hits = game.world.state.hits[env]
    names = game.world.table_of(env).element_names
    return {names[i]: int(hits[i]) for i in game.world.tables.scoring[env] if hits[i]}


def batch_infos(game: "Game") -> dict[str, np.ndarray]:
    """The per-step info of every env as arrays (first axis the env): ``ball_position`` [m],
    ``ball_velocity`` [m/s], ``score``, ``balls_left``, ``points`` (this step), ``drained`` (a
    ball drained this step) and ``frames`` (played in this game); the cabinet's, the rules' and
    the several balls' (:func:`_balls_infos`) entries on tables with them. With several balls
    ``ball_position`` and ``ball_velocity`` are the game's ball's, the first in play."""
    state, balls = game.state, game.state.game_ball
    return {
        "ball_position": balls[:, [BALL_X, BALL_Y]],
        "ball_velocity": balls[:, [BALL_VX, BALL_VY]],
        "score": state.score.copy(),
        "balls_left": state.balls_left.copy(),
        "points": state.points.copy(),
        "drained": state.drained.copy(),
        "frames": state.frames.copy(),
        **_cabinet_infos(game, slice(None)),
        **_rule_infos(game, slice(None)),
        **_balls_infos(game, slice(None)),
    }


def env_info(game: "Game", env: int) -> dict[str, Any]:
    """The per-step info of env ``env``: that of :func:`batch_infos` as Python numbers (the
    ball's position and velocity as float64 arrays), plus ``events`` (:func:`element_events`)."""
    state, ball = game.state, game.state.game_ball[env]
    return {
        "ball_position": ball[[BALL_X, BALL_Y]],
        "ball_velocity": ball[[BALL_VX, BALL_VY]],
        "score": int(state.score[env]),
        "balls_left": int(state.balls_left[env]),
        "events": element_events(game, env),
        "points": int(state.points[env]),
        "drained": bool(state.drained[env]),
        "frames": int(state.frames[env]),
        **{
            key: value if isinstance(value, np.ndarray) else value.item()
            for key, value in _cabinet_infos(game, env).items()
        },
        **_rule_info(game, env),
        **{
            key: value if isinstance(value, np.ndarray) else value.item()
            for key, value in _balls_infos(game, env).items()
        },
    }


def _rule_infos(game: "Game", envs: int | slice) -> dict[str, Any]:
    """The rules' entries of the infos (none for a table without rules or ball save):
    ``rule_events`` (the step's rules fired, ball saves and bonuses, counts in the order of
    ``game.event_names``), ``bonus``, ``bonus_multiplier`` and ``rule_score`` (points the rules
    scored in this game: modes, awards and end-of-ball bonuses)."""
    if not game.book.active:
        return {}
    state = game.state
    return {
        "rule_events": state.rule_events[envs].copy(),
        "bonus": state.bonus[envs].copy(),
        "bonus_multiplier": state.multiplier[envs].copy(),
        "rule_score": state.rule_points[envs].copy(),
    }


def _rule_info(game: "Game", env: int) -> dict[str, Any]:
    """:func:`_rule_infos` of one env, ``rule_events`` as name -> times this step."""
    info = {key: value.item() for key, value in _rule_infos(game, env).items()
            if key != "rule_events"}  # fmt: skip
    if info:
        counts = game.state.rule_events[env]
        info["rule_events"] = {
            name: int(n) for name, n in zip(game.event_names, counts, strict=False) if n
        }
    return info


def _balls_infos(game: "Game", envs: int | slice) -> dict[str, Any]:
    """The several balls' entries (none for a table of one ball): ``ball_positions`` (M, 2)
    [m] and ``ball_velocities`` (M, 2) [m/s] of every ball slot, ``balls_in_play`` (M,) bool
    (on the table and not held in a lock), ``balls_locked`` (held in locks), ``multiball`` (two
    or more balls in play) and ``multiballs`` (started in this game)."""
    if game.multi is None:
        return {}
    world, state = game.world, game.state
    states = world.balls[envs]
    locked = game.multi.locked(slice(None))
    return {
        "ball_positions": states[..., [BALL_X, BALL_Y]],
        "ball_velocities": states[..., [BALL_VX, BALL_VY]],
        "balls_in_play": (world.active & ~locked)[envs],
        "balls_locked": locked[envs].sum(axis=-1),
        "multiball": state.multiball[envs].copy(),
        "multiballs": state.multiballs[envs].copy(),
    }


def _cabinet_infos(game: "Game", envs: int | slice) -> dict[str, Any]:
    """The cabinet's entries of the infos (none for a table without a cabinet)."""
    if not game.cabinet:
        return {}
    state, world, progress = game.state, game.world.state, game.progress
    return {
        "tilt_warnings": state.tilt_warnings[envs].copy(),
        "tilted": world.tilted[envs] | progress.tilt[envs],
        "ball_on_plunger": state.on_plunger[envs].copy(),
        "plunger_pull": state.plunger_pull[envs].copy(),
        "cabinet_offset": world.cabinet[envs, CABINET_X : CABINET_Y + 1].copy(),
        "skill_shot": progress.skill_shot[envs].copy(),
    }


# The ranges of the infos' numbers (info_ranges): a count or a score is an integer from 0 up.
_COUNT = (0.0, math.inf)


def info_ranges(
    game: "Game", env: int = 0, max_frames: int | None = None
) -> dict[str, tuple[Any, Any]]:
    """The documented range [low, high] of every number of the infos of env ``env`` of ``game``
    (each entry of an array entry in it; a pair of (x, y) for positions), for every play: the
    ball's position on its table (the ball slots' too, wherever they lie), the
    counts from 0, the tilt warnings up to the allowed ones plus the touches of the frame that
    tilts (one a substep), the plunger's pull up to its stroke, the bonus multiplier from 1 to
    its most, the frames up to ``max_frames`` (the game's time, where it has one). Velocities and
    the cabinet's offset are only finite (the ball's speed has no bound the game keeps). Flags
    are 0 or 1; ``events`` and ``rule_events`` of the single env are name -> count."""
    table = game.world.table_of(env)
    frames = (0.0, math.inf if max_frames is None else float(max_frames))
    finite = (-math.inf, math.inf)
    ranges = {
        "ball_position": ((0.0, 0.0), (table.width, table.height)),
        "ball_velocity": finite,
        "score": _COUNT, "balls_left": _COUNT, "points": _COUNT, "drained": (0.0, 1.0),
        "frames": frames,
    }  # fmt: skip
    if game.cabinet:
        assert table.tilt is not None and table.plunger is not None  # (the cabinet's)
        warnings = table.tilt.warnings + table.simulation.substeps
        ranges.update({
            "tilt_warnings": (0.0, float(warnings)), "tilted": (0.0, 1.0),
            "ball_on_plunger": (0.0, 1.0), "plunger_pull": (0.0, float(table.plunger.stroke or 0)),
            "cabinet_offset": finite, "skill_shot": (0.0, 1.0),
        })  # fmt: skip
    if game.book.active:
        ranges.update({"rule_events": _COUNT, "bonus": _COUNT, "rule_score": _COUNT,
                       "bonus_multiplier": (1.0, float(game.book.max_multiplier))})  # fmt: skip
    if game.multi is not None:
        ranges.update({
            "ball_positions": ranges["ball_position"], "ball_velocities": finite,
            "balls_in_play": (0.0, 1.0), "balls_locked": (0.0, float(game.world.n_balls)),
            "multiball": (0.0, 1.0), "multiballs": _COUNT,
        })  # fmt: skip
    return ranges
