"""What the agent sees: the observers of a game, each with its space and one ``observe`` for
every env at once (the single env is a batch of one).

- :class:`StateObserver`: ball x, y, vx, vy (on a table of several balls a block per ball slot,
  in slot order, with its flag: in play 1, held 0.5, in the trough 0); each flipper's angle
  above rest and angular velocity towards up; ball in play; balls left (in table units, or
  normalised to the table so that they mean the same on every table); the cabinet's and the
  rules' rows where the table has them, and optionally ray distances (``physics.rays``; with
  several balls they also see the other balls and the standing drop targets). Its
  :meth:`StateObserver.rows` declare every entry once (:class:`ObservationRow`: meaning,
  bounds, unit), from which the space's bounds and the documentation's tables are made;
- :class:`ImageObserver`: the table drawn as an RGB or grayscale picture.
"""

import functools
from collections.abc import Callable
from dataclasses import dataclass
from typing import TypedDict

import numpy as np
from gymnasium import spaces
from numba import njit

from pinball_env.game import Game
from pinball_env.physics.columns import (
    BALL_VX,
    BALL_VY,
    BALL_X,
    BALL_Y,
    CABINET_VX,
    CABINET_X,
    CABINET_Y,
    SPIN_ANGLE,
)
from pinball_env.physics.rays import RAY_RANGE, cast_all_rays
from pinball_env.render import Renderer, TargetsView
from pinball_env.sim.tables import flipper_numbers
from pinball_env.table import Table
from pinball_env.table.rules import RuleSet

# The state observation clips ball velocities to +-MAX_OBS_SPEED [m/s] so its bounds hold; a
# real ball rarely exceeds 10 m/s on a table (a full flip at the tip gives about 5 m/s).
MAX_OBS_SPEED = 20.0
# Renderers kept per table (a renderer holds its table's static layer).
CACHED_RENDERERS = 512
# The cabinet's rows clip its offset to +-MAX_OBS_CABINET_OFFSET [m] and its velocity to
# +-MAX_OBS_CABINET_SPEED [m/s]: a shove moves a real cabinet a few millimetres at a few dm/s.
MAX_OBS_CABINET_OFFSET = 0.02
MAX_OBS_CABINET_SPEED = 1.0
# The rules' rows give the bonus in thousands of points and counters as counts, clipped to these.
MAX_OBS_BONUS = 100.0
MAX_OBS_COUNT = 100.0
# The balls left row is clipped to the balls of a game plus this many: the rules' extra balls
# have no bound (a counter's rule fires again each time it reaches its count), a game's rarely
# more than one.
MAX_OBS_EXTRA_BALLS = 9


@dataclass(frozen=True)
class ObservationRow:
    """One entry of a state observation: what it is, its bounds (the space's float32 numbers)
    and its unit ("" for none)."""

    meaning: str
    low: float
    high: float
    unit: str


def flipper_names(table: Table) -> list[str]:
    """Each flipper as the observation's rows name it, in the table's order: by its button
    ("left flipper") where that is the only flipper on its button, else by its own name too."""
    buttons = [f.button for f in table.flippers]
    return [f"{f.button} flipper" if buttons.count(f.button) == 1
            else f"flipper {f.name} ({f.button} button)" for f in table.flippers]  # fmt: skip


# A row of StateObserver.rows before its bounds are made float32: meaning, low, high, unit.
_Row = tuple[str, float, float, str]


def _ball_rows(table: Table, norm: bool, ball_order: str = "slot") -> list[_Row]:
    """One ball: its block; several (a trough): a block per ball slot, in slot order (or, with
    ``ball_order`` ``"lowest"``, the lowest ball in play first), each with its flag
    (balls_observation)."""
    speed = MAX_OBS_SPEED
    n_balls = table.n_balls
    rows: list[_Row] = []
    for i in range(n_balls):
        ball = "ball" if n_balls == 1 else f"ball {i}"
        if n_balls > 1 and ball_order == "lowest":
            ball = f"ball {i} (by urgency: in play lowest first, then held, then the trough's)"
        rows += [
            (f"{ball} x", 0.0, 1.0 if norm else table.width, "table widths" if norm else "m"),
            (f"{ball} y (up the table)", 0.0, 1.0 if norm else table.height,
             "table heights" if norm else "m"),
            (f"{ball} vx (clipped to +-{speed:g})", -speed, speed, "m/s"),
            (f"{ball} vy (clipped to +-{speed:g})", -speed, speed, "m/s"),
        ]  # fmt: skip
        if n_balls > 1:
            rows.append((f"{ball} in play (1: on the table or the player's plunger), held in "
                         "a lock or saucer (0.5) or in the trough (0; x, y, vx, vy 0)", 0.0,
                         1.0, ""))  # fmt: skip
    return rows


def _flipper_rows(table: Table, norm: bool) -> list[_Row]:
    """Each flipper's angle above rest, then each one's angular velocity."""
    _, _, swing, top_speed = flipper_numbers(table)
    names = flipper_names(table)
    rows: list[_Row] = [(f"{name} angle above rest", 0.0, 1.0 if norm else top,
                         "swings" if norm else "rad")
                        for name, top in zip(names, swing, strict=True)]  # fmt: skip
    rows += [(f"{name} angular velocity, + going up", -1.0 if norm else -top,
              1.0 if norm else top, "top speeds" if norm else "rad/s")
             for name, top in zip(names, top_speed, strict=True)]  # fmt: skip
    return rows


def _cabinet_rows(table: Table, norm: bool) -> list[_Row]:
    """The plunger, the cabinet's offset and velocity, the tilt (cabinet_observation)."""
    plunger, tilt = table.plunger, table.tilt
    assert plunger is not None and plunger.stroke is not None and tilt is not None
    offset, cabinet_speed = MAX_OBS_CABINET_OFFSET, MAX_OBS_CABINET_SPEED
    return [
        ("plunger pull", 0.0, 1.0 if norm else plunger.stroke,
         "strokes" if norm else "m"),
        ("ball waiting on the plunger (1) or not (0)", 0.0, 1.0, ""),
        (f"cabinet offset x (clipped to +-{offset:g})", -offset, offset, "m"),
        (f"cabinet offset y, up the table (clipped to +-{offset:g})", -offset, offset, "m"),
        (f"cabinet velocity x (clipped to +-{cabinet_speed:g})", -cabinet_speed,
         cabinet_speed, "m/s"),
        (f"cabinet velocity y (clipped to +-{cabinet_speed:g})", -cabinet_speed,
         cabinet_speed, "m/s"),
        # The touches of the frame that tilts all count: up to one a substep past the last
        # warning allowed.
        ("tilt warnings standing (past the allowed ones: tilted)", 0.0,
         float(tilt.warnings + table.simulation.substeps), ""),
        ("tilted (1) or not (0)", 0.0, 1.0, ""),
    ]  # fmt: skip


def _rule_rows(table: Table, rules: RuleSet) -> list[_Row]:
    """Lights, drop targets, kickbacks, timers, counters, multiplier, bonus (rule_observation)."""
    count = f"(clipped to {MAX_OBS_COUNT:g})"
    rows: list[_Row] = [(f"light {x.name} lit (1) or not (0)", 0.0, 1.0, "") for x in rules.lights]
    rows += [(f"drop target {x.name} up (1) or down (0)", 0.0, 1.0, "")
             for x in table.drop_target_list]  # fmt: skip
    rows += [(f"kickback {x.name} lit (1) or not (0)", 0.0, 1.0, "")
             for x in table.kickbacks]  # fmt: skip
    rows += [(f"timer {x.name}: share of its {x.time:g} s left", 0.0, 1.0, "")
             for x in rules.timers]  # fmt: skip
    rows += [(f"counter {x} {count}", 0.0, MAX_OBS_COUNT, "") for x in rules.counters]
    rows += [
        ("bonus multiplier", 1.0, float(rules.max_multiplier), "x"),
        (f"end-of-ball bonus, in thousands (clipped to {MAX_OBS_BONUS:g})", 0.0,
         MAX_OBS_BONUS, "1000 points"),
    ]  # fmt: skip
    return rows


def _ray_rows(rays: int, sees_balls: bool) -> list[_Row]:
    """The ray distances, evenly round the circle from +x (as ray_directions)."""
    sees = ", seeing other balls and standing drop targets" if sees_balls else ""
    return [(f"ray {k} distance (direction {360.0 * k / rays:.4g} deg from +x{sees})", 0.0, 1.0,
             f"{RAY_RANGE:g} m") for k in range(rays)]  # fmt: skip


class _CabinetView(TypedDict, total=False):
    """The cabinet's arguments of ``Renderer.frames`` (none for a table without a cabinet)."""

    plunger_pull: np.ndarray
    on_plunger: np.ndarray
    cabinet_offset: np.ndarray


class StateObserver:
    """The state observation of every env of ``game`` (see ``PinballEnv``'s Observation Space).

    ``normalised``: positions in table widths and heights, flipper angles in swings and angular
    velocities in top speeds, so that the bounds are the same on every table (generated
    tables); else in metres and radians, within the bounds of ``game.table``. ``rays``: that
    many ray distances after the state, in ``RAY_RANGE`` (0-1), from the game's ball to the
    walls, posts and flippers; on a table of several balls also to the other balls (in play
    or held) and the standing drop targets (``physics.rays.cast_all_rays``).
    """

    def __init__(
        self, game: Game, normalised: bool = False, rays: int = 0, ball_order: str = "slot"
    ) -> None:
        self.game = game
        self.normalised = normalised
        self.rays = rays
        self.ball_order = ball_order
        low, high = self.bounds()
        self.space = spaces.Box(low, high, dtype=np.float32)
        self._ray_distances = np.zeros((game.n_envs, rays), dtype=np.float32)
        n = game.n_envs
        self._sees_nothing = (np.zeros((n, 0, 5)), np.zeros((n, 0), dtype=bool), 0.0,
                              np.zeros((n, 0), dtype=bool))  # fmt: skip

    def rows(self) -> tuple[ObservationRow, ...]:
        """One env's observation, entry by entry in order: what each is, its bounds and unit.
        The one declaration of the bounds (:meth:`bounds` reads them from here), so that the
        documentation's table of them is the space itself."""
        table, norm = self.game.table, self.normalised
        rows = [
            *_ball_rows(table, norm, self.ball_order),
            *_flipper_rows(table, norm),
            ("ball in play (1) or game over (0)", 0.0, 1.0, ""),
            (
                f"balls left, the one in play included (clipped to the game's balls + "
                f"{MAX_OBS_EXTRA_BALLS}: extra balls)",
                0.0,
                float(self.game.balls_per_game + MAX_OBS_EXTRA_BALLS),
                "",
            ),
        ]
        if self.game.cabinet:  # as cabinet_observation
            rows += _cabinet_rows(table, norm)
        if table.rules is not None:  # as rule_observation
            rows += _rule_rows(table, table.rules)
        # Several balls: the rays also see the other balls and the standing drop targets.
        rows += _ray_rows(self.rays, sees_balls=bool(self.game.multi))
        # The bounds as the float32 space holds them, so that a row is exactly the space's.
        return tuple(
            ObservationRow(meaning, float(np.float32(low)), float(np.float32(high)), unit)
            for meaning, low, high, unit in rows
        )

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """Lower and upper bounds of one env's observation (float32, one entry per feature):
        :meth:`rows`'."""
        rows = self.rows()
        low = np.array([row.low for row in rows], dtype=np.float32)
        high = np.array([row.high for row in rows], dtype=np.float32)
        return low, high

    def observe(self) -> np.ndarray:
        """(n_envs, features) float32."""
        world, tables = self.game.world, self.game.world.tables
        state = world.state
        game = self.game.state
        obs = state_observation(
            game.game_ball, state.flipper_angle, state.flipper_omega, self.game.in_play,
            np.minimum(game.balls_left, self.game.balls_per_game + MAX_OBS_EXTRA_BALLS),
            tables.flipper_rest, tables.flipper_up_sign,
        )  # fmt: skip
        if self.normalised:
            n = tables.flipper_swing.shape[1]
            obs[:, 0] /= tables.width
            obs[:, 1] /= tables.height
            obs[:, 4 : 4 + n] /= tables.flipper_swing
            obs[:, 4 + n : 4 + 2 * n] /= tables.flipper_top_speed
        if self.game.multi is not None:
            block = balls_observation(self.game, self.ball_order)
            if self.normalised:
                block[:, 0::5] /= tables.width
                block[:, 1::5] /= tables.height
            obs = np.concatenate([block, obs[:, 4:]], axis=1)
        if self.game.cabinet:
            plunger = self.game.table.plunger
            assert plunger is not None and plunger.stroke is not None  # (the cabinet's)
            stroke = plunger.stroke if self.normalised else 1.0
            cabinet = cabinet_observation(
                game.plunger_pull / stroke, game.on_plunger, state.cabinet, game.tilt_warnings,
                state.tilted,
            )  # fmt: skip
            obs = np.concatenate([obs, cabinet], axis=1)
        if self.game.table.rules is not None:
            obs = np.concatenate([obs, self.rule_observation()], axis=1)
        if self.rays:
            world.threads.run(
                cast_all_rays, world.n_envs, game.game_ball, tables.geometries(),
                state.flipper_angle, self.rays, state.hits.shape[1], self._ray_distances,
                *self._rays_see(),
            )  # fmt: skip
            obs = np.concatenate([obs, self._ray_distances], axis=1)
        return obs

    def _rays_see(self) -> tuple:
        """What the rays see besides the walls, posts and flippers: on a table of several balls
        every ball slot (in play or held) and the standing drop targets; on a table of one ball
        nothing (no columns)."""
        world = self.game.world
        if self.game.multi is None:
            return self._sees_nothing
        return world.balls, world.active, self.game.table.ball.radius, world.state.targets_up

    def rule_counts(self) -> tuple[int, ...]:
        """How many rows each part of the rules' rows has: lights, drop targets, kickbacks,
        timers, counters, and 2 (multiplier, bonus)."""
        table = self.game.table
        rules = table.rules
        assert rules is not None  # (a table with rules)
        return (len(rules.lights), len(table.drop_target_list), len(table.kickbacks),
                len(rules.timers), len(rules.counters), 2)  # fmt: skip

    def rule_observation(self) -> np.ndarray:
        """The rules' rows of every env, float32: each light (1 lit), drop target (1 up) and
        kickback (1 lit), each timer's share of its time left, each counter (clipped to
        MAX_OBS_COUNT), the bonus multiplier and the bonus in thousands of points (clipped to
        MAX_OBS_BONUS)."""
        game, world = self.game.state, self.game.world.state
        n_timers = len(self.game.book.timer_frames)
        return np.concatenate(
            [
                game.lights,
                world.targets_up[:, : len(self.game.table.drop_target_list)],
                world.kickback_lit[:, : len(self.game.table.kickbacks)],
                game.timers / self.game.book.timer_frames.reshape(1, n_timers),
                np.minimum(game.counters, MAX_OBS_COUNT),
                game.multiplier[:, None],
                np.minimum(game.bonus / 1000.0, MAX_OBS_BONUS)[:, None],
            ],
            axis=1,
            dtype=np.float32,
        )


class TableRenderers:
    """A renderer per table, made once by ``make(table)`` (a renderer rasterises its table's
    static layer when made), at most CACHED_RENDERERS kept."""

    def __init__(self, make: Callable[[Table], Renderer]) -> None:
        self.make = make
        self._renderers: dict[int, tuple[Table, Renderer]] = {}  # id(table) -> its renderer

    def __call__(self, table: Table) -> Renderer:
        kept = self._renderers.get(id(table))
        if kept is None or kept[0] is not table:
            if len(self._renderers) >= CACHED_RENDERERS:
                self._renderers.clear()
            kept = self._renderers[id(table)] = (table, self.make(table))
        return kept[1]


class ImageObserver:
    """The picture of every env's table (its own, where envs differ), ``image_size`` (height,
    width) pixels, RGB or (``grayscale``) luma."""

    def __init__(self, game: Game, image_size: tuple[int, int], grayscale: bool = False) -> None:
        self.game = game
        self.grayscale = grayscale
        height, width = image_size
        self.space = spaces.Box(0, 255, (height, width, 1 if grayscale else 3), dtype=np.uint8)
        self.renderers = TableRenderers(functools.partial(Renderer, width=width, height=height))

    def observe(self) -> np.ndarray:
        """(n_envs, height, width, channels) uint8."""
        world = self.game.world
        state = world.state
        if not world.tables.varied:
            return self.renderers(world.table).frames(
                self.game.state.game_ball, self.game.in_play, state.flipper_angle,
                grayscale=self.grayscale,
                threads=world.threads, targets=targets_view(self.game, slice(None)),
                **self._cabinet(slice(None)), **self._other_balls(),
            )  # fmt: skip
        frames = []
        for env in range(world.n_envs):
            one = slice(env, env + 1)
            renderer = self.renderers(world.table_of(env))
            frames.append(renderer.frames(
                self.game.state.game_ball[one], self.game.in_play[one], state.flipper_angle[one],
                grayscale=self.grayscale,
                targets=targets_view(self.game, one, world.table_of(env)),
                **self._cabinet(one),
            ))  # fmt: skip
        return np.concatenate(frames)

    def _other_balls(self) -> dict[str, np.ndarray]:
        """Several balls: every ball on the table (in play or held), drawn besides the game's
        ball (which waits on the plunger, where it does); nothing for a table of one ball."""
        if self.game.multi is None:
            return {}
        world = self.game.world
        return {"other_balls": world.balls, "other_visible": world.active}

    def _cabinet(self, envs: slice) -> _CabinetView:
        """The cabinet as the picture shows it (true scale): the plunger pulled back, a ball
        waiting on it, the cabinet's offset; nothing for a table without a cabinet."""
        if not self.game.cabinet:
            return {}
        game, cabinet = self.game.state, self.game.world.state.cabinet
        return {
            "plunger_pull": game.plunger_pull[envs],
            "on_plunger": game.on_plunger[envs],
            "cabinet_offset": cabinet[envs, CABINET_X : CABINET_Y + 1],
        }


Observer = StateObserver | ImageObserver


def targets_view(game: Game, envs: slice, table: Table | None = None) -> TargetsView | None:
    """What the pictures of ``envs``, which play ``table`` (by default the game's), show of its
    targets and rules (None for a table with neither); the rows may be wider than the table
    needs (see ``World.set_table``)."""
    table = table or game.table
    if not (table.has_targets or table.rules is not None):
        return None
    state = game.world.state
    counts = (len(table.drop_target_list), len(table.spinners), len(table.kickbacks))
    return TargetsView(
        targets_up=state.targets_up[envs, : counts[0]],
        spinner_angles=state.spinners[envs, : counts[1], SPIN_ANGLE],
        kickback_lit=state.kickback_lit[envs, : counts[2]],
        lights=game.state.lights[envs],
    )


def make_observer(
    game: Game,
    obs_type: str,
    image_size: tuple[int, int],
    normalised: bool,
    rays: int,
    ball_order: str = "slot",
) -> Observer:
    """The observer of ``obs_type`` (``"state"``, ``"rgb"`` or ``"grayscale"``)."""
    if obs_type == "state":
        return StateObserver(game, normalised, rays, ball_order)
    return ImageObserver(game, image_size, grayscale=obs_type == "grayscale")


def balls_observation(game: Game, ball_order: str = "slot") -> np.ndarray:
    """(n_envs, 5 M) float32: every ball slot of a game of several balls, in slot order (or,
    ``ball_order`` ``"lowest"``, the balls in play lowest first, then the held ones lowest
    first, then the trough's, each group in slot order at equal heights): x, y, vx, vy (clipped
    to +-MAX_OBS_SPEED) and its flag: 1 in play (on the table, or waiting on the player's
    plunger), 0.5 held in a lock or saucer, 0 in the trough (x, y, vx, vy 0)."""
    world, state = game.world, game.state
    balls = world.balls
    n, m = balls.shape[:2]
    flag = np.where(world.active, np.where(world.held, 0.5, 1.0), 0.0)
    slot = state.ball_slot
    waiting = np.flatnonzero(state.on_plunger & (slot >= 0))
    flag[waiting, slot[waiting]] = 1.0
    block = np.zeros((n, m, 5), dtype=np.float32)
    block[..., 0] = balls[..., BALL_X]
    block[..., 1] = balls[..., BALL_Y]
    block[..., 2] = np.clip(balls[..., BALL_VX], -MAX_OBS_SPEED, MAX_OBS_SPEED)
    block[..., 3] = np.clip(balls[..., BALL_VY], -MAX_OBS_SPEED, MAX_OBS_SPEED)
    block[..., :4] = np.where((flag > 0.0)[..., None], block[..., :4], 0.0)  # no -0.0
    block[..., 4] = flag
    if ball_order == "lowest":
        rank = np.where(flag == 1.0, 0, np.where(flag == 0.5, 1, 2))
        order = np.lexsort((block[..., 1], rank), axis=-1)  # by rank, then height
        block = np.take_along_axis(block, order[..., None], axis=1)
    return block.reshape(n, 5 * m)


@njit(cache=True)
def state_observation(balls, flipper_angle, flipper_omega, active, balls_left, rest, up_sign):
    """The state observation of every env in table units, float32. Compiled: the single env
    pays it every step."""
    n_envs, n_flippers = flipper_angle.shape
    obs = np.empty((n_envs, 6 + 2 * n_flippers), dtype=np.float32)
    for env in range(n_envs):
        obs[env, 0] = balls[env, BALL_X]
        obs[env, 1] = balls[env, BALL_Y]
        obs[env, 2] = min(max(balls[env, BALL_VX], -MAX_OBS_SPEED), MAX_OBS_SPEED)
        obs[env, 3] = min(max(balls[env, BALL_VY], -MAX_OBS_SPEED), MAX_OBS_SPEED)
        for j in range(n_flippers):
            # The angle above rest (the kernel stops it exactly) and the speed towards up.
            obs[env, 4 + j] = (flipper_angle[env, j] - rest[env, j]) * up_sign[env, j]
            obs[env, 4 + n_flippers + j] = flipper_omega[env, j] * up_sign[env, j]
        obs[env, 4 + 2 * n_flippers] = active[env]
        obs[env, 5 + 2 * n_flippers] = balls_left[env]
    return obs


@njit(cache=True)
def cabinet_observation(pull, on_plunger, cabinet, warnings, tilted):
    """The cabinet's rows of the state observation of every env, float32: the plunger's pull,
    the ball waiting on it, the cabinet's offset and velocity (clipped), the tilt warnings and
    the tilt."""
    obs = np.empty((pull.shape[0], 8), dtype=np.float32)
    for env in range(pull.shape[0]):
        obs[env, 0] = pull[env]
        obs[env, 1] = on_plunger[env]
        for i in range(2):
            offset = cabinet[env, CABINET_X + i]
            speed = cabinet[env, CABINET_VX + i]
            obs[env, 2 + i] = min(max(offset, -MAX_OBS_CABINET_OFFSET), MAX_OBS_CABINET_OFFSET)
            obs[env, 4 + i] = min(max(speed, -MAX_OBS_CABINET_SPEED), MAX_OBS_CABINET_SPEED)
        obs[env, 6] = warnings[env]
        obs[env, 7] = tilted[env]
    return obs


__all__ = [
    "MAX_OBS_BONUS",
    "MAX_OBS_CABINET_OFFSET",
    "MAX_OBS_CABINET_SPEED",
    "MAX_OBS_COUNT",
    "MAX_OBS_SPEED",
    "ImageObserver",
    "ObservationRow",
    "Observer",
    "StateObserver",
    "TableRenderers",
    "cabinet_observation",
    "flipper_names",
    "make_observer",
    "state_observation",
    "targets_view",
]
