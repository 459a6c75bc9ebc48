"""What both env shells are made of: :class:`PinballCore` owns the game of N envs, its table
source, its observer and its frames, and starts new games; ``PinballEnv`` (N = 1) and
``PinballVectorEnv`` (N) add only Gymnasium's API around it.
"""

import functools
from collections.abc import Callable, Mapping, Sequence
from typing import Any

import numpy as np
from gymnasium import spaces

from pinball_env.envs.layouts import Layouts, frame_size
from pinball_env.game import Game
from pinball_env.observation import (
    ObservationRow,
    StateObserver,
    TableRenderers,
    make_observer,
    targets_view,
)
from pinball_env.options import PinballOptions
from pinball_env.render import (
    SHAKE_EXAGGERATION,
    FrameRenderer,
    Renderer,
    render_size,
    scoreboard,
)
from pinball_env.table import Table, load_any_table


class PinballCore:
    """``n_envs`` games played by ``options``: on the table ``options.table``, or, with
    ``table="generated"``, each game on a layout its env draws (:class:`Layouts`).

    Attributes:
        options: the :class:`PinballOptions`.
        game: the rules and physics of every env.
        layouts: the generated-table source (None for a fixed table).
        layout: (n_envs,) int64, each env's layout (None for a fixed table).
        observer: the observation of every env (``observer.space`` is one env's).
        action_space: one env's.
        steps_per_second: steps at real speed.
    """

    def __init__(self, options: PinballOptions, n_envs: int = 1, num_threads: int = 1) -> None:
        self.options = options
        self.layouts: Layouts | None = None
        self.layout: np.ndarray | None = None
        if options.generated:
            self.layouts = Layouts(
                options.num_layouts, options.start_layout, options.difficulty, options.targets
            )
            table = self.layouts.table(self.layouts.seeds.start)
            self.layout = np.full(n_envs, self.layouts.seeds.start, dtype=np.int64)
        elif isinstance(options.table, Table):
            table = options.table
        else:
            table = load_any_table(options.table)
        threads = num_threads if options.physics == "swept" else 1
        self.game = Game(table, n_envs, options, threads)
        self.observer = make_observer(
            self.game,
            options.obs_type,
            image_shape(options),
            options.generated,
            options.rays,
            options.ball_order,
        )
        if options.action_type == "discrete":
            self.action_space: spaces.Space = spaces.Discrete(len(self.game.discrete_buttons))
        else:
            self.action_space = spaces.MultiBinary(len(self.game.button_names))
        self.steps_per_second = table.simulation.frame_rate / options.frame_skip
        # The frames render() shows: of one size for every layout of generated tables.
        make: Callable[[Table], Renderer]
        if options.generated:
            width, height = frame_size(options.difficulty)
            make = functools.partial(FrameRenderer, width=width, height=height)
        else:
            make = full_size_renderer
        self.frame_renderers = TableRenderers(make)

    @property
    def n_envs(self) -> int:
        return self.game.n_envs

    @property
    def render_fps(self) -> int:
        """``metadata["render_fps"]``: the steps per second rounded to an int, at least 1 (as
        ``gymnasium.utils.play`` requires; windows keep the exact rate)."""
        return max(1, round(self.steps_per_second))

    def seeded(self, envs: Sequence[int]) -> None:
        """A reset seeded ``envs``' generators: the layouts drawn ahead from the generators
        they had are dropped (the others' stay, as a single env that is not reset keeps its
        own)."""
        if self.layouts is not None:
            self.layouts.forget(None if len(envs) == self.n_envs else envs)

    def new_games(
        self,
        envs: Sequence[int] | np.ndarray,
        rngs: Sequence[np.random.Generator],
        options: Mapping[str, Any] | None = None,
    ) -> None:
        """Start new games in ``envs`` (each drawing from its ``rngs`` entry). ``options``: the
        reset options (``ball_position``, ``ball_velocity``; for generated tables ``layout``,
        one for all or a sequence of one per env)."""
        options = dict(options or {})
        tables: dict[int, tuple[int, Table]] = {}
        if self.layouts is not None:
            tables = self._layout_tables(envs, rngs, options.pop("layout", None))
        for env in envs:
            env = int(env)
            if env in tables:
                layout, table = tables[env]
                if table is not self.game.world.table_of(env):
                    self.game.set_table(env, table)
                assert self.layout is not None  # (tables: generated ones)
                self.layout[env] = layout
            self.game.new_game(env, rngs[env], options)

    def _layout_tables(
        self, envs: Sequence[int] | np.ndarray, rngs: Sequence[np.random.Generator], chosen: Any
    ) -> dict[int, tuple[int, Table]]:
        """Each env's next layout and its table. Every env's layout first (each drawn from the
        env's own generator, before its game's launch, as one env at a time would), so that
        their tables are generated together."""
        assert self.layouts is not None  # (generated tables)
        if isinstance(chosen, (Sequence, np.ndarray)) and not isinstance(chosen, str):
            if len(chosen) != self.n_envs:
                raise ValueError(
                    f"a list of layouts needs one per env ({self.n_envs}), got {len(chosen)}"
                )
        else:
            chosen = [chosen] * self.n_envs
        layouts = {int(env): self.layouts.pick(int(env), rngs[env], chosen[env]) for env in envs}
        tables = self.layouts.tables(layouts.values())
        return {env: (layout, tables[layout]) for env, layout in layouts.items()}

    def observe(self) -> np.ndarray:
        """Every env's observation, (n_envs, ...)."""
        return self.observer.observe()

    def info(self, env: int) -> dict[str, Any]:
        """Env ``env``'s info (the single env's): the game's, and the layout it plays."""
        info = self.game.info(env)
        if self.layout is not None:
            info["layout"] = int(self.layout[env])
        return info

    def infos(self) -> dict[str, np.ndarray]:
        """Every env's info as arrays (the vector env's): the game's, and the layouts."""
        infos = self.game.infos()
        if self.layout is not None:
            infos["layout"] = self.layout.copy()
        return infos

    def frame(self, env: int) -> np.ndarray:
        """The frame ``render()`` shows of env ``env``: its playfield (the ball where it
        drained once the game is over) and a scoreboard beside it. With the cabinet: the
        plunger pulled back (the ball waiting on it with it), the playfield moved by the
        cabinet's shake (SHAKE_EXAGGERATION times), and the tilt warnings or TILT on the
        scoreboard."""
        game, world = self.game, self.game.world
        table = world.table_of(env)
        renderer = self.frame_renderers(table)
        ball, angles = tuple(game.state.game_ball[env, :2]), world.state.flipper_angle[env]
        targets = targets_view(game, slice(env, env + 1), table)
        rules: dict[str, Any] = {}
        if table.rules is not None:
            rules = {"bonus": game.state.bonus[env], "multiplier": game.state.multiplier[env]}
        others: dict[str, Any] = {}
        if game.multi is not None:  # every ball on the table; the trough's count
            on_table = world.active[env]
            others = {"other_balls": world.balls[env, on_table, :2]}
            rules["trough"] = int(game.multi.in_trough(env).sum())
        if not game.cabinet:
            playfield = renderer.frame(ball, angles, targets=targets, **others)
            board = scoreboard(playfield.shape[0], game.score[env], game.balls_left[env],
                               **rules)  # fmt: skip
            return np.concatenate([playfield, board], axis=1)
        info = game.info(env)  # "tilted" holds a tilt of the last step that ended at once
        assert table.tilt is not None  # (game.cabinet)
        playfield = renderer.frame(
            ball,
            angles,
            plunger_pull=info["plunger_pull"],
            on_plunger=info["ball_on_plunger"],
            cabinet_offset=tuple(SHAKE_EXAGGERATION * info["cabinet_offset"]),
            targets=targets,
            **others,
        )
        board = scoreboard(
            playfield.shape[0],
            info["score"],
            info["balls_left"],
            tilt_warnings=info["tilt_warnings"],
            allowed_warnings=table.tilt.warnings,
            tilted=info["tilted"],
            **rules,
        )
        return np.concatenate([playfield, board], axis=1)

    def close(self) -> None:
        """Stop the threads (the envs' and the table generators')."""
        if self.layouts is not None:
            self.layouts.close()
        self.game.world.threads.close()


class CoreAttributes:
    """The attributes both env shells read from their :class:`PinballCore` (``self.core``)."""

    core: PinballCore

    @property
    def game(self) -> Game:
        """The rules and physics of every env."""
        return self.core.game

    @property
    def layouts(self) -> Layouts | None:
        """The generated-table source (``table="generated"``), else None."""
        return self.core.layouts

    @property
    def obs_type(self) -> str:
        return self.core.options.obs_type

    @property
    def action_type(self) -> str:
        return self.core.options.action_type

    @property
    def image_size(self) -> tuple[int, int]:
        return image_shape(self.core.options)

    @property
    def rays(self) -> int:
        return self.core.options.rays

    @property
    def observation_rows(self) -> tuple[ObservationRow, ...]:
        """One env's state observation, entry by entry (``StateObserver.rows``): what each is,
        its bounds (the observation space's) and unit. An AttributeError for image
        observations, whose entries are pixels."""
        observer = self.core.observer
        if not isinstance(observer, StateObserver):
            raise AttributeError(
                f"observation_rows describes the state observation; this env's obs_type is "
                f"{self.obs_type!r} (pixels): make it with obs_type='state'"
            )
        return observer.rows()

    @property
    def reward_scale(self) -> float:
        """Reward per point (the game's)."""
        return self.game.reward_scale

    @property
    def height_shaping(self) -> float:
        """Weight of the height shaping term (the game's)."""
        return self.game.height_shaping


def image_shape(options: PinballOptions) -> tuple[int, int]:
    """``options.image_size`` as (height, width): its check makes an int a square's pair."""
    size = options.image_size
    assert isinstance(size, tuple)
    return size


def full_size_renderer(table: Table) -> Renderer:
    """The renderer of ``table``'s frames at the render scale (``render_size``)."""
    return Renderer(table, *render_size(table))
