"""``PinballProcgen-v0``: every game on a table generated from a seed, as Procgen's levels.

The single env (:class:`PinballProcgenEnv`) and the native vector env
(:class:`PinballProcgenVectorEnv`, each env on its own table, all stepped in one kernel call) are
the Pinball-v0 envs with a layout drawn at every reset and observations that keep their meaning
from one table to the next.

Tables are made by the env (its :class:`Layouts`): the table of each env's next game generated in
the background while this one is played, those a reset needs at once on several threads.
"""

import functools
import math
import os
import sys
import time
from collections.abc import Iterable, Mapping, Sequence
from concurrent.futures import Future, ThreadPoolExecutor, as_completed
from typing import Any

import numpy as np
from gymnasium import spaces
from numba import njit

from pinball_env.env import PinballEnv, obs_renderer, render_frame
from pinball_env.game import check_choice
from pinball_env.physics.columns import (
    BALL_X,
    BALL_Y,
    FLIPPER_BASE_RADIUS,
    FLIPPER_LENGTH,
    FLIPPER_PIVOT_X,
    FLIPPER_PIVOT_Y,
    FLIPPER_TIP_RADIUS,
)
from pinball_env.procgen import DIFFICULTIES, MAX_SEED, RANGES, generate_table
from pinball_env.render import PIXELS_PER_METRE, FrameRenderer, Renderer
from pinball_env.table import Table
from pinball_env.vector_env import EnvAttribute, PinballVectorEnv

# Seeds an unlimited env (num_layouts=0) draws from: [start_layout, start_layout + this).
UNLIMITED_LAYOUTS = 2**31
# Generated tables kept in memory (a table is about 50 KB; generating one takes 0.1-0.2 s).
CACHED_TABLES = 512
# Threads that generate the tables a reset needs at once (the playability check's simulation
# releases the GIL, so they share the cores).
GENERATION_THREADS = min(os.cpu_count() or 1, 8)
# Tables that take longer than this to make show their progress on stderr [s], every so often [s].
PROGRESS_AFTER = 2.0
PROGRESS_EVERY = 1.0
# Rays see this far [m]; a ray that meets nothing reads 1.
RAY_RANGE = 0.5
MAX_RAYS = 64


@functools.lru_cache(maxsize=CACHED_TABLES)
def layout_table(seed: int, difficulty: str) -> Table:
    """The generated table of a layout (``generate_table``, cached)."""
    return generate_table(seed, difficulty)


def frame_size(difficulty: str) -> tuple[int, int]:
    """(width, height) in pixels of the playfield of every rendered frame of ``difficulty``'s
    tables (the scoreboard is beside it): the largest table the generator draws (``RANGES``)
    at the render scale, rounded up to even numbers (as video encoders need); each table is
    fitted into it (``FrameRenderer``)."""
    ranges = RANGES[difficulty]
    size = (ranges.width[1], ranges.width[1] * ranges.aspect[1])  # [m]
    width, height = (2 * math.ceil(round(metres * PIXELS_PER_METRE) / 2) for metres in size)
    return width, height


class Layouts:
    """The layouts an env plays, seeds ``[start, start + count)`` (``count`` 0: unlimited), and
    the making of their tables, which belongs to the env: the table of each env's next game is
    generated on a thread in the background while this one is played, and tables needed at
    once (a reset's) on ``GENERATION_THREADS`` threads. Fork-safe: a forked child has none of
    its parent's threads, so it forgets the work pending there and starts its own threads.
    Which layouts are drawn does not depend on any of this."""

    def __init__(self, count: int, start: int, difficulty: str) -> None:
        for name, value in (("num_layouts", count), ("start_layout", start)):
            if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < 0:
                raise ValueError(f"{name} must be an integer >= 0, got {value!r}")
        check_choice("difficulty", difficulty, DIFFICULTIES)
        self.count = int(count)
        self.start = int(start)
        self.difficulty = difficulty
        self._upcoming: dict[int, int] = {}  # env -> the layout of its next game
        self._to_prefetch: list[int] = []  # upcoming layouts not yet sent to the prefetcher
        self._pending: dict[int, Future[Table]] = {}  # layout -> its table, being generated
        self._prefetcher: ThreadPoolExecutor | None = None  # one thread, beside the training
        self._generators: ThreadPoolExecutor | None = None  # for the tables needed now
        self._pid = os.getpid()  # the process whose threads the executors have
        if self.start + (self.count or UNLIMITED_LAYOUTS) - 1 > MAX_SEED:
            raise ValueError(f"layouts beyond seed {MAX_SEED}: lower start_layout")

    def draw(self, rng: np.random.Generator) -> int:
        """A layout drawn uniformly from the env's."""
        return self.start + int(rng.integers(self.count or UNLIMITED_LAYOUTS))

    def check(self, layout: object) -> int:
        """``layout`` (a reset option) if it is one of the env's; a ValueError if not."""
        end = self.start + (self.count or UNLIMITED_LAYOUTS)
        valid = isinstance(layout, (int, np.integer)) and not isinstance(layout, bool)
        if not valid or not self.start <= layout < end:
            raise ValueError(f"layout must be an integer in [{self.start}, {end}), got {layout!r}")
        return int(layout)

    def pick(self, env: int, rng: np.random.Generator, chosen: object = None) -> int:
        """The layout of env ``env``'s next game: ``chosen`` (checked), or the one drawn for it
        at its last game. Then the one after is drawn; the next :meth:`tables` has it generated
        in the background while this game is played (unlimited layouts would wait for each
        table otherwise)."""
        if chosen is not None:
            return self.check(chosen)
        layout = self._upcoming.pop(env, None)
        if layout is None:
            layout = self.draw(rng)
        self._upcoming[env] = upcoming = self.draw(rng)
        self._to_prefetch.append(upcoming)
        return layout

    def forget(self, envs: Iterable[int] | None = None) -> None:
        """Drop the layouts drawn ahead for ``envs`` (default: all), whose random generators
        were seeded again."""
        if envs is not None:
            for env in envs:
                self._upcoming.pop(int(env), None)
            return
        self._upcoming.clear()
        self._to_prefetch.clear()
        self._pending.clear()  # their tables still land in the cache

    def table(self, layout: int) -> Table:
        """The table of ``layout`` (see :meth:`tables`)."""
        return self.tables([layout])[layout]

    def tables(self, layouts: Iterable[int]) -> dict[int, Table]:
        """The tables of ``layouts``, by layout: cached, awaited where the background thread has
        begun them, or generated now, on threads if more than one (with progress on stderr
        when that takes a while). Then the layouts drawn ahead by :meth:`pick` are sent to the
        background thread."""
        self._in_this_process()
        futures: dict[int, Future[Table]] = {}
        missing = []
        for layout in dict.fromkeys(layouts):
            future = self._pending.pop(layout, None)
            if future is not None and not future.cancel():  # begun (or done): wait for it
                futures[layout] = future
            else:
                missing.append(layout)
        tables = {}
        if len(missing) == 1:
            tables[missing[0]] = layout_table(missing[0], self.difficulty)
        elif missing:
            if self._generators is None:
                self._generators = ThreadPoolExecutor(
                    GENERATION_THREADS, thread_name_prefix="pinball-tables"
                )
            for layout in missing:
                futures[layout] = self._generators.submit(layout_table, layout, self.difficulty)
        tables.update(self._wait(futures))
        self._prefetch()
        return tables

    def close(self) -> None:
        """Stop the threads (their work is dropped; a later use starts new ones)."""
        self._in_this_process()
        for executor in (self._prefetcher, self._generators):
            if executor is not None:
                executor.shutdown(wait=False, cancel_futures=True)
        self._prefetcher = self._generators = None
        self._pending.clear()

    def _wait(self, futures: dict[int, Future[Table]]) -> dict[int, Table]:
        """The futures' tables, once all are done; their progress on stderr after
        PROGRESS_AFTER seconds, every PROGRESS_EVERY seconds and at the end."""
        start = shown = time.monotonic()
        for done, _ in enumerate(as_completed(futures.values()), 1):
            now = time.monotonic()
            last = done == len(futures)
            if now - start >= PROGRESS_AFTER and (last or now - shown >= PROGRESS_EVERY):
                shown = now
                line = f"generating {len(futures)} {self.difficulty} tables: {done}/{len(futures)}"
                tty = sys.stderr.isatty()  # a terminal's line is rewritten, a log gets lines
                end = "\n" if last or not tty else ""
                print(f"\r{line}" if tty else line, end=end, file=sys.stderr, flush=True)
        return {layout: future.result() for layout, future in futures.items()}

    def _prefetch(self) -> None:
        """Send the layouts drawn ahead to the background thread."""
        for layout in self._to_prefetch:
            if layout not in self._pending and len(self._pending) < CACHED_TABLES:
                if self._prefetcher is None:
                    self._prefetcher = ThreadPoolExecutor(1, thread_name_prefix="pinball-layouts")
                self._pending[layout] = self._prefetcher.submit(
                    layout_table, layout, self.difficulty
                )
        self._to_prefetch.clear()

    def _in_this_process(self) -> None:
        """In a forked child: forget the parent's executors and futures (their threads are not
        in this process: the futures would never finish, the executors never work)."""
        if self._pid != os.getpid():
            self._pid = os.getpid()
            self._prefetcher = self._generators = None
            self._pending = {}

    def __getstate__(self) -> dict[str, Any]:
        # A copy starts its own threads, and generates again what was pending here.
        return {**self.__dict__, "_pending": {}, "_prefetcher": None, "_generators": None}


def state_space(game: Any, rays: int) -> spaces.Box:
    """The normalised state observation's space, with ``rays`` ray distances after it."""
    low, high = game.observation_bounds(normalised=True)
    low = np.concatenate([low, np.zeros(rays, dtype=np.float32)])
    high = np.concatenate([high, np.ones(rays, dtype=np.float32)])
    return spaces.Box(low, high, dtype=np.float32)


def check_rays(rays: object, obs_type: str) -> int:
    if isinstance(rays, bool) or not isinstance(rays, (int, np.integer)):
        raise ValueError(f"rays must be an integer, got {rays!r}")
    if not 0 <= rays <= MAX_RAYS:
        raise ValueError(f"rays must be in [0, {MAX_RAYS}], got {rays}")
    if rays and obs_type != "state":
        raise ValueError(f"rays are part of the state observation, not of obs_type={obs_type!r}")
    return int(rays)


@njit(cache=True)
def cast_rays(x, y, n_rays, geometry, flipper_angles, out):
    """Distances from (x, y) along ``n_rays`` directions (0 = +x, evenly round the circle) to
    the first wall, post or flipper (its capsule: base and tip circles and the two sides),
    in RAY_RANGE (1: nothing within it), written to ``out``."""
    segments, circles, flippers = geometry.segments, geometry.circles, geometry.flippers
    for k in range(n_rays):
        a = 2.0 * math.pi * k / n_rays
        dx, dy = math.cos(a), math.sin(a)
        best = RAY_RANGE
        for j in range(segments.shape[0]):
            x0, y0, x1, y1 = segments[j, 0], segments[j, 1], segments[j, 2], segments[j, 3]
            best = min(best, _ray_segment(x, y, dx, dy, x0, y0, x1, y1))
        for j in range(circles.shape[0]):
            best = min(best, _ray_circle(x, y, dx, dy, circles[j, 0], circles[j, 1],
                                         circles[j, 2]))  # fmt: skip
        for j in range(flippers.shape[0]):
            px, py = flippers[j, FLIPPER_PIVOT_X], flippers[j, FLIPPER_PIVOT_Y]
            length = flippers[j, FLIPPER_LENGTH]
            rb, rt = flippers[j, FLIPPER_BASE_RADIUS], flippers[j, FLIPPER_TIP_RADIUS]
            ux, uy = math.cos(flipper_angles[j]), math.sin(flipper_angles[j])
            tx, ty = px + length * ux, py + length * uy
            best = min(best, _ray_circle(x, y, dx, dy, px, py, rb))
            best = min(best, _ray_circle(x, y, dx, dy, tx, ty, rt))
            for side in (-1.0, 1.0):  # the sides, as lines between the circles' edges
                nx, ny = -side * uy, side * ux
                side_hit = _ray_segment(
                    x, y, dx, dy, px + nx * rb, py + ny * rb, tx + nx * rt, ty + ny * rt
                )
                best = min(best, side_hit)
        out[k] = best / RAY_RANGE


@njit(cache=True, inline="always")
def _ray_segment(x, y, dx, dy, x0, y0, x1, y1):
    """Distance along the ray (x, y) + t (dx, dy), unit direction, to the segment (inf: none)."""
    ex, ey = x1 - x0, y1 - y0
    denominator = dx * ey - dy * ex
    if denominator == 0.0:
        return math.inf
    t = ((x0 - x) * ey - (y0 - y) * ex) / denominator
    s = ((x0 - x) * dy - (y0 - y) * dx) / denominator
    return t if t >= 0.0 and 0.0 <= s <= 1.0 else math.inf


@njit(cache=True, inline="always")
def _ray_circle(x, y, dx, dy, cx, cy, r):
    """Distance along the ray to the circle (0 from inside it, inf: none)."""
    fx, fy = x - cx, y - cy
    c = fx * fx + fy * fy - r * r
    if c <= 0.0:
        return 0.0
    b = fx * dx + fy * dy
    disc = b * b - c
    if b > 0.0 or disc < 0.0:
        return math.inf
    return -b - math.sqrt(disc)


class PinballProcgenEnv(PinballEnv):
    """``Pinball-v0`` on generated tables: each reset draws a layout, a table generated from a
    seed (``pinball_env.procgen.generate_table``), so an agent can be trained on some layouts
    and tested on others, as in Procgen.

    ## Layouts

    Layouts are the seeds ``[start_layout, start_layout + num_layouts)`` (``num_layouts=0``:
    unlimited, ``[start_layout, start_layout + 2**31)``); each reset draws one uniformly with
    the env's random generator (``reset(seed=...)`` fixes the sequence), or plays the one given
    as ``reset(options={"layout": seed})``. ``difficulty``: ``"easy"`` or ``"hard"`` tables.
    ``info["layout"]`` is the layout of the game.

    ## Observation Space

    ``obs_type="state"``: the state of ``Pinball-v0`` normalised to the table, so that it means
    the same on every layout: ball x and y in table widths and heights (0-1), vx and vy [m/s]
    (clipped to +-20), each flipper's angle above rest in swings (0-1) and angular velocity in
    top speeds (-1..1), ball in play, balls left. With ``rays=K``, K more entries: the
    distances from the ball's centre to the first wall, post or flipper along K directions
    evenly round the circle (the first along +x, counter-clockwise), in 0.5 m (1: nothing
    that near), so that a state policy can see the layout. ``"rgb"`` and ``"grayscale"``: the
    pictures of ``Pinball-v0``, of each game's own table.

    ## Rendering

    ``render_mode="rgb_array"`` frames (and the ``"human"`` window) have one size for every
    layout of a difficulty, so that video recorders and windows take them: the playfield part
    is :func:`frame_size` (360 x 792 pixels), each table fitted into it with its aspect kept
    and centred (background colour around it), the scoreboard beside it: (792, 470, 3) uint8.

    ## Arguments

    ```python
    gym.make("PinballProcgen-v0", num_layouts=0, start_layout=0, difficulty="easy", rays=0,
             obs_type="state", action_type="discrete", balls=3, reward_scale=0.01,
             height_shaping=0.0, drain_penalty=0.0, frame_skip=1, skip_above=0.0,
             max_frames=None, image_size=(84, 84), render_mode=None)
    ```

    The rest is ``Pinball-v0``'s (actions, rewards, episode end, infos; see ``PinballEnv``).
    """

    def __init__(
        self,
        num_layouts: int = 0,
        start_layout: int = 0,
        difficulty: str = "easy",
        rays: int = 0,
        obs_type: str = "state",
        action_type: str = "discrete",
        balls: int = 3,
        reward_scale: float = 0.01,
        height_shaping: float = 0.0,
        drain_penalty: float = 0.0,
        frame_skip: int = 1,
        skip_above: float = 0.0,
        max_frames: int | None = None,
        image_size: int | tuple[int, int] = (84, 84),
        render_mode: str | None = None,
    ) -> None:
        self.layouts = Layouts(num_layouts, start_layout, difficulty)
        self.rays = check_rays(rays, obs_type)
        self.layout = self.layouts.start
        super().__init__(
            table=self.layouts.table(self.layout), obs_type=obs_type, action_type=action_type,
            balls=balls, reward_scale=reward_scale, height_shaping=height_shaping,
            drain_penalty=drain_penalty, frame_skip=frame_skip, skip_above=skip_above,
            max_frames=max_frames, image_size=image_size, render_mode=render_mode,
        )  # fmt: skip
        if obs_type == "state":
            self.observation_space = state_space(self.game, self.rays)
        self._rays = np.zeros((1, self.rays), dtype=np.float32)

    def render(self) -> np.ndarray | None:
        if self.render_mode is not None and self._frame_renderer is None:
            # PinballEnv.render draws with it: this table in the frame of every layout's size.
            self._frame_renderer = FrameRenderer(self.table, *frame_size(self.layouts.difficulty))
        return super().render()

    def close(self) -> None:
        self.layouts.close()
        super().close()

    def reset(
        self, *, seed: int | None = None, options: Mapping[str, Any] | None = None
    ) -> tuple[np.ndarray, dict[str, Any]]:
        if seed is not None:
            self.layouts.forget()
        return super().reset(seed=seed, options=options)

    def _new_game(self, options: Mapping[str, Any] | None) -> None:
        options = dict(options or {})
        layout = self.layouts.pick(0, self.np_random, options.pop("layout", None))
        table = self.layouts.table(layout)
        if table is not self.table:
            self.game.set_table(0, table)
            self.table, self.layout = table, layout
            self._obs_renderer = obs_renderer(table, self.obs_type, self.image_size)
            self._frame_renderer = None  # made for the new table when next rendered
        self.game.new_game(0, self.np_random, options)

    def _info(self) -> dict[str, Any]:
        return {**self.game.info(0), "layout": self.layout}

    def _observe(self) -> np.ndarray:
        if self._obs_renderer is not None:
            return super()._observe()
        state = self.game.observe(normalised=True)
        if self.rays:
            observe_rays(self.game.world, self.rays, self._rays)
            state = np.concatenate([state, self._rays], axis=1)
        return state[0]


def observe_rays(world: Any, n_rays: int, out: np.ndarray) -> np.ndarray:
    """The ray distances (see PinballProcgenEnv) of every env of ``world`` into ``out``, in
    one compiled call (shared by the world's threads)."""
    args = (world.balls, world.geometries(), world.state.flipper_angle, n_rays, out)
    world.threads.run(_cast_all_rays, world.n_envs, *args)
    return out


@njit(cache=True, nogil=True)
def _cast_all_rays(balls, geometries, angles, n_rays, out, start, stop):
    """:func:`cast_rays` for envs ``start`` to ``stop``, env i on ``geometries[i]``."""
    for env in range(start, stop):
        cast_rays(balls[env, BALL_X], balls[env, BALL_Y], n_rays, geometries[env], angles[env],
                  out[env])  # fmt: skip


class PinballProcgenVectorEnv(PinballVectorEnv):
    """``num_envs`` games of ``PinballProcgen-v0``, each on its own table, stepped in one
    kernel call (``World.set_table``); see ``PinballProcgenEnv`` and ``PinballVectorEnv``.

    ``reset(options={"layout": L})`` plays layout ``L`` in every env reset, or
    ``{"layout": [L0, L1, ...]}`` one per env (for evaluations on chosen layouts); later games
    draw their layouts. ``infos["layout"]`` is each env's layout, and so is
    ``get_attr("layout")``, with the per-env attributes of ``PinballVectorEnv`` (``table`` each
    env's own). The tables a reset needs are generated on several threads (a line on stderr
    shows the progress when that takes more than two seconds); the layouts drawn do not depend
    on it. Frames (``render()``) are those of the single env, of one size for every layout.

    ```python
    gym.make_vec("PinballProcgen-v0", num_envs=64, num_layouts=0, start_layout=0,
                 difficulty="easy", rays=0, ...)  # and PinballVectorEnv's other arguments
    ```
    """

    def __init__(
        self,
        num_envs: int = 1,
        num_layouts: int = 0,
        start_layout: int = 0,
        difficulty: str = "easy",
        rays: int = 0,
        obs_type: str = "state",
        action_type: str = "discrete",
        balls: int = 3,
        reward_scale: float = 0.01,
        height_shaping: float = 0.0,
        drain_penalty: float = 0.0,
        frame_skip: int = 1,
        skip_above: float = 0.0,
        max_frames: int | None = None,
        image_size: int | tuple[int, int] = (84, 84),
        render_mode: str | None = None,
        max_episode_steps: int | None = 7200,
        num_threads: int | None = None,
        autoreset_mode: Any = "NextStep",
    ) -> None:
        self.layouts = Layouts(num_layouts, start_layout, difficulty)
        self.rays = check_rays(rays, obs_type)
        super().__init__(
            num_envs=num_envs, table=self.layouts.table(self.layouts.start), obs_type=obs_type,
            action_type=action_type, balls=balls, reward_scale=reward_scale,
            height_shaping=height_shaping, drain_penalty=drain_penalty, frame_skip=frame_skip,
            skip_above=skip_above, max_frames=max_frames, image_size=image_size,
            render_mode=render_mode, max_episode_steps=max_episode_steps,
            num_threads=num_threads, autoreset_mode=autoreset_mode,
        )  # fmt: skip
        self.layout = np.full(self.num_envs, self.layouts.start, dtype=np.int64)
        if obs_type == "state":
            self.single_observation_space = state_space(self.game, self.rays)
            self.observation_space = spaces.Box(
                np.tile(self.single_observation_space.low, (self.num_envs, 1)),
                np.tile(self.single_observation_space.high, (self.num_envs, 1)),
                dtype=np.float32,
            )
        self._rays = np.zeros((self.num_envs, self.rays), dtype=np.float32)
        self._renderers: dict[tuple[int, bool], Renderer] = {}

    def env_attributes(self) -> dict[str, EnvAttribute]:
        layout = EnvAttribute(lambda env: int(self.layout[env]))
        return {**super().env_attributes(), "layout": layout}

    def close_extras(self, **kwargs: Any) -> None:
        if hasattr(self, "layouts"):
            self.layouts.close()
        super().close_extras(**kwargs)

    def _seeded(self, envs: Sequence[int]) -> None:
        # Their layouts drawn ahead came from the generators they had (the others' stay, as
        # a single env that is not reset keeps its own).
        self.layouts.forget(None if len(envs) == self.num_envs else envs)

    def _new_games(self, envs: Sequence[int], options: Mapping[str, Any] | None = None) -> None:
        options = dict(options or {})
        chosen = options.pop("layout", None)
        if isinstance(chosen, (Sequence, np.ndarray)) and not isinstance(chosen, str):
            if len(chosen) != self.num_envs:
                raise ValueError(
                    f"a list of layouts needs one per env ({self.num_envs}), got {len(chosen)}"
                )
        else:
            chosen = [chosen] * self.num_envs
        # Every env's layout first (each drawn from the env's own generator, before its game's
        # launch, as one env at a time would), so that their tables are generated together.
        layouts = {int(env): self.layouts.pick(int(env), self._rngs[env], chosen[env])
                   for env in envs}  # fmt: skip
        tables = self.layouts.tables(layouts.values())
        for env, layout in layouts.items():
            table = tables[layout]
            if table is not self.game.world.table_of(env):
                self.game.set_table(env, table)
            self.layout[env] = layout
            self.game.new_game(env, self._rngs[env], options)

    def _observe(self) -> np.ndarray:
        if self.obs_type != "state":
            world = self.game.world
            frames = []
            for env in range(self.num_envs):
                renderer = self._renderer(int(self.layout[env]), world.table_of(env))
                frames.append(renderer.frames(
                    world.balls[env : env + 1], world.active[env : env + 1],
                    world.state.flipper_angle[env : env + 1],
                    grayscale=self.obs_type == "grayscale",
                ))  # fmt: skip
            return np.concatenate(frames)
        state = self.game.observe(normalised=True)
        if self.rays:
            state = np.concatenate(
                [state, observe_rays(self.game.world, self.rays, self._rays)], axis=1
            )
        return state

    def _renderer(self, layout: int, table: Table, frame: bool = False) -> Renderer:
        """The observation renderer of a layout (or its full-size frame renderer), made once:
        a renderer rasterises its table's static layer when made."""
        key = (layout, frame)
        renderer = self._renderers.get(key)
        if renderer is None:
            if len(self._renderers) >= CACHED_TABLES:
                self._renderers.clear()
            if frame:  # one frame size for every layout
                renderer = FrameRenderer(table, *frame_size(self.layouts.difficulty))
            else:
                renderer = obs_renderer(table, self.obs_type, self.image_size)
            self._renderers[key] = renderer
        return renderer

    def _infos(self, envs: np.ndarray | None = None) -> dict[str, Any]:
        infos = super()._infos(envs)
        infos["layout"] = self.layout.copy()
        infos["_layout"] = infos["_score"]
        return infos

    def _render_env(self, env: int) -> np.ndarray | None:
        """Env ``env``'s frame, of its own table in the frame of every layout's size."""
        if self.render_mode is None:
            return None
        renderer = self._renderer(int(self.layout[env]), self.game.world.table_of(env), True)
        return render_frame(renderer, self.game, env)


__all__ = [
    "RAY_RANGE",
    "Layouts",
    "PinballProcgenEnv",
    "PinballProcgenVectorEnv",
    "cast_rays",
    "frame_size",
    "layout_table",
    "observe_rays",
]
