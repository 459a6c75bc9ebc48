"""The step parameters: the numbers the compiled step loop (``game.play``) plays by, made from
the game's options and its tables (:func:`make_step_parameters`)."""

from typing import Any, NamedTuple

import numpy as np

from pinball_env.game.rulebook import RuleBook
from pinball_env.options import PinballOptions
from pinball_env.sim.world import World
from pinball_env.table import Table

# Ball search: a ball in play that has not moved a ball radius in this long [s] (resting in the
# shooter lane, say, or held in a flipper's cradle) is served again from the plunger, as a real
# machine's ball search and auto-plunger would; no ball is lost. So every game can end. With
# several balls every ball in play is watched (game.multiball).
BALL_SEARCH_TIME = 10.0
# Most frames one step runs on with the buttons released while the ball is high (skip_above),
# after its frame_skip frames: then the agent is asked again, wherever the ball is.
MAX_RUN_ON_FRAMES = 60


class StepParameters(NamedTuple):
    """What the compiled step loop plays by (see ``Game``); arrays are per env."""

    reward_scale: float
    drain_penalty: float
    height_shaping: float
    bonus_shaping: float  # share of the end-of-ball bonus rewarded as it is earned
    heights: np.ndarray  # (N,) float64: table heights [m]
    skip_heights: np.ndarray  # (N,) float64: skip_above in metres
    frame_skip: int
    skip_frames: int  # most frames run on while the ball is high (0: skip_above is off)
    skip_all_balls: bool  # skip_above watches every free ball in play, not the game's alone
    repeat_probability: float  # sticky actions: a frame repeats the last one's buttons (0: off)
    max_frames: int  # frames a game lasts (-1: no limit)
    search_frames: int  # still frames before a ball search
    radius: float  # the ball's [m]
    scores: np.ndarray  # (N, elements) int64: points per element id
    # The cabinet (tables with one; see ``Game`` and ``physics.cabinet``).
    cabinet: bool  # the table has the player's plunger, the nudge and the tilt
    plunger_x: float  # ball centre on the plunger [m]
    plunger_y: float
    stroke: float  # the plunger's pull back [m]
    pull_step: float  # its pull in a frame [m]
    nudge_impulse: float  # [N s]
    nudge_frames: int  # shortest time between two shoves [frames]
    warnings: int  # ring touches that warn; the next tilts
    warning_frames: int  # a warning is forgotten after this long without another [frames]
    settle_frames: int  # touches this soon after a warning are that warning [frames] (0: none)
    skill_sensors: np.ndarray  # (N,) int64: element id of the skill-shot rollover (-1: none)
    skill_bonus: int  # [points]
    skill_frames: int  # how long the skill shot stays lit after a plunge [frames]
    book: RuleBook  # the table's rules and ball save (``game.rulebook``)


def ball_search_frames(table: Table) -> int:
    """Frames a ball stays still before the ball search serves it again (BALL_SEARCH_TIME)."""
    return round(BALL_SEARCH_TIME * table.simulation.frame_rate)


def make_step_parameters(
    options: PinballOptions, table: Table, world: World, book: RuleBook
) -> StepParameters:
    """The step parameters of a game of ``options`` on ``world``'s tables (``table`` the game's
    first, whose ball and cabinet are every env's), its rules compiled in ``book``."""
    return StepParameters(
        reward_scale=options.reward_scale,
        drain_penalty=options.drain_penalty,
        height_shaping=options.height_shaping,
        bonus_shaping=options.bonus_shaping if book.active else 0.0,
        heights=world.tables.height,
        skip_heights=options.skip_above * world.tables.height,
        frame_skip=options.frame_skip,
        skip_frames=MAX_RUN_ON_FRAMES if options.skip_above else 0,
        skip_all_balls=options.skip_above_balls == "all",
        repeat_probability=options.repeat_action_probability,
        max_frames=-1 if options.max_frames is None else options.max_frames,
        search_frames=ball_search_frames(table),
        radius=table.ball.radius,
        scores=world.tables.scores,
        **_cabinet_parameters(table, world),
        book=book,
    )


def _cabinet_parameters(table: Table, world: World) -> dict[str, Any]:
    """The cabinet's step parameters (all zero for a table without a cabinet)."""
    rate = table.simulation.frame_rate
    plunger, cabinet, tilt = table.plunger, table.cabinet, table.tilt
    skill_sensors = np.full(world.n_envs, -1, dtype=np.int64)
    if not table.has_cabinet:
        return dict(cabinet=False, plunger_x=0.0, plunger_y=0.0, stroke=0.0, pull_step=0.0,
                    nudge_impulse=0.0, nudge_frames=0, warnings=0, warning_frames=0,
                    settle_frames=0, skill_sensors=skill_sensors, skill_bonus=0,
                    skill_frames=0)  # fmt: skip
    assert plunger is not None and cabinet is not None and tilt is not None  # (the whole cabinet)
    assert plunger.stroke is not None and plunger.pull_time is not None  # (the player's plunger)
    skill = plunger.skill_shot
    for env in range(world.n_envs):
        names = world.table_of(env).element_names
        if skill is not None and skill.sensor in names:
            skill_sensors[env] = names.index(skill.sensor)
    return dict(
        cabinet=True,
        plunger_x=float(plunger.position[0]),
        plunger_y=float(plunger.position[1]),
        stroke=plunger.stroke,
        pull_step=plunger.stroke / (plunger.pull_time * rate),
        nudge_impulse=cabinet.nudge_impulse,
        nudge_frames=max(1, round(cabinet.nudge_interval * rate)),
        warnings=tilt.warnings,
        warning_frames=max(1, round(tilt.warning_time * rate)),
        settle_frames=round(tilt.settle_time * rate),
        skill_sensors=skill_sensors,
        skill_bonus=0 if skill is None else skill.bonus,
        skill_frames=0 if skill is None else max(1, round(skill.time * rate)),
    )
