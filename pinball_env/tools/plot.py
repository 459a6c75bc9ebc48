"""Plot a table, and optionally a ball's path on it, to PNG: ``python -m pinball_env.tools.plot``.

Examples::

    python -m pinball_env.tools.plot box --out outputs/box.png
    python -m pinball_env.tools.plot box --trace 600 --velocity 2.5 1.0 --out outputs/trace.png
    python -m pinball_env.tools.plot procgen:7 --out outputs/procgen7.png
    python -m pinball_env.tools.plot --gallery --difficulty hard --seeds 0 12 --out gallery.png
    python -m pinball_env.tools.plot classic_v1 --cabinet --out docs/cabinet.png
    python -m pinball_env.tools.plot classic_v1 --rules --out docs/rules.png
    python -m pinball_env.tools.plot classic_v3 --multiball --out docs/multiball.png
    python -m pinball_env.tools.plot --tilt classic_v1 classic_v2 --out docs/tilt.png

Needs matplotlib (the ``plot`` extra).
"""

import argparse
import math
from collections.abc import Callable
from pathlib import Path

import numpy as np

from pinball_env.extras import require
from pinball_env.physics import capsule_face_normal
from pinball_env.physics.columns import BOB_X, BOB_Y
from pinball_env.procgen import DIFFICULTIES, generate_table, load_any_table
from pinball_env.sim.world import World
from pinball_env.table import Flipper, Table
from pinball_env.tools import command_parser

WALL_COLOUR = "#1d3557"
ONE_SIDED_COLOUR = "#e76f51"
KICKER_COLOUR = "#e63946"
POST_COLOUR = "#2a9d8f"
FLIPPER_COLOUR = "#f4a261"
SENSOR_COLOUR = "#8d99ae"


def flipper_outline(flipper: Flipper, angle_deg: float, arc_points: int = 12) -> np.ndarray:
    """Outline of a flipper at ``angle_deg`` as a closed polygon, (n, 2) world points."""
    rb, rt, length = flipper.base_radius, flipper.tip_radius, flipper.length
    # The tangent faces' outward normals make angle +-phi with the flipper axis.
    phi = math.acos(capsule_face_normal(length, rb, rt)[0])
    tip = np.linspace(-phi, phi, arc_points)  # tip arc, around the front
    base = np.linspace(phi, 2 * math.pi - phi, arc_points)  # base arc, around the back
    local = np.vstack(
        [
            np.column_stack([length + rt * np.cos(tip), rt * np.sin(tip)]),
            np.column_stack([rb * np.cos(base), rb * np.sin(base)]),
        ]
    )
    a = math.radians(angle_deg)
    rotation = np.array([[math.cos(a), -math.sin(a)], [math.sin(a), math.cos(a)]])
    return local @ rotation.T + np.asarray(flipper.pivot)


def _pyplot():
    matplotlib = require("matplotlib")
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def draw_table(ax, table: Table, labels: bool = True) -> None:
    """Draw walls (one-sided ones with an arrow on their blocking side, kickers in red), posts,
    flippers (at rest, and faintly raised), sensors (dashed) and the ball start."""
    from matplotlib.patches import Circle, Polygon

    for wall in table.walls:
        colour = WALL_COLOUR
        if wall.one_sided:
            colour = ONE_SIDED_COLOUR
        elif wall.kick > 0:
            colour = KICKER_COLOUR
        for x0, y0, x1, y1 in wall.segments():
            ax.plot([x0, x1], [y0, y1], color=colour, lw=2, solid_capstyle="round")
            if wall.one_sided:
                # The normal rot+90(P1 - P0) points to the side the segment blocks.
                length = math.hypot(x1 - x0, y1 - y0)
                nx, ny = -(y1 - y0) / length, (x1 - x0) / length
                mx, my = (x0 + x1) / 2, (y0 + y1) / 2
                arrow = 2 * table.ball.radius
                ax.annotate(
                    "", (mx + nx * arrow, my + ny * arrow), (mx, my),
                    arrowprops={"arrowstyle": "->", "color": colour},
                )  # fmt: skip
    for post in table.posts:
        colour = KICKER_COLOUR if post.kick > 0 else POST_COLOUR
        ax.add_patch(Circle(post.center, post.radius, color=colour, alpha=0.85))
    for flipper in table.flippers:
        raised = flipper_outline(flipper, flipper.up_angle)
        ax.add_patch(Polygon(raised, color=FLIPPER_COLOUR, alpha=0.3, lw=0))
        ax.add_patch(Polygon(flipper_outline(flipper, flipper.rest_angle), color=FLIPPER_COLOUR))
    for sensor in table.sensors:
        (x0, y0), (x1, y1) = sensor.points
        ax.plot([x0, x1], [y0, y1], color=SENSOR_COLOUR, lw=1.5, ls="--")
    ax.add_patch(Circle(table.ball.start, table.ball.radius, fill=False, ls="--", color="grey"))
    ax.set_xlim(0, table.width)
    ax.set_ylim(0, table.height)
    ax.set_aspect("equal")
    if labels:
        ax.set_xlabel("x [m]")
        ax.set_ylabel("y [m] (up the table)")
        ax.set_title(
            f"{table.name}: {table.width:g} m x {table.height:g} m, slope {table.slope_deg:g} deg"
        )
    else:
        ax.set_axis_off()
        ax.set_title(f"{table.name}\n{table.width:.2f} x {table.height:.2f} m, "
                     f"{table.slope_deg:.1f} deg", fontsize=8)  # fmt: skip


def draw_path(ax, path: np.ndarray, frame_rate: float) -> None:
    """Draw a ball path (n, 2) coloured by time."""
    times = np.arange(len(path)) / frame_rate
    points = ax.scatter(path[:, 0], path[:, 1], c=times, s=3, cmap="viridis", zorder=3)
    ax.figure.colorbar(points, ax=ax, label="time [s]", shrink=0.6)


def plot_table(
    table: Table,
    out: Path,
    trace_frames: int = 0,
    velocity: tuple[float, float] | None = None,
) -> Path:
    """Write a PNG of ``table``, with the path of a ball over ``trace_frames`` frames if > 0."""
    plt = _pyplot()
    aspect = table.height / table.width
    fig, ax = plt.subplots(figsize=(4.2, 4.2 * aspect * 0.9 + 0.6))
    draw_table(ax, table)
    if trace_frames > 0:
        world = World(table)
        world.place_ball(0, table.ball.start, velocity or table.ball.velocity)
        path = np.vstack([world.balls[0, 0, :2], world.trace(trace_frames)])
        draw_path(ax, path, table.simulation.frame_rate)
    fig.tight_layout()
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=110, bbox_inches="tight")
    plt.close(fig)
    return out


def plot_gallery(tables: list[Table], out: Path, columns: int = 6) -> Path:
    """Write a PNG of ``tables`` side by side, ``columns`` to a row, all drawn to one scale."""
    plt = _pyplot()
    rows = math.ceil(len(tables) / columns)
    width = max(t.width for t in tables)
    height = max(t.height for t in tables)
    size = 2.0  # inches per table's width
    fig, axes = plt.subplots(
        rows, columns, figsize=(size * columns, size * rows * height / width + 0.4 * rows),
        squeeze=False,
    )  # fmt: skip
    for ax in axes.flat:
        ax.set_axis_off()
    for ax, table in zip(axes.flat, tables, strict=False):
        draw_table(ax, table, labels=False)
        ax.set_xlim(0, width)
        ax.set_ylim(0, height)
    fig.tight_layout()
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=90, bbox_inches="tight")
    plt.close(fig)
    return out


def plot_rules(table: Table, out: Path, seed: int = 0) -> Path:
    """Write a PNG of a heuristic game on ``table`` (one with rules): the table as the renderer
    draws it where the most of its lamps and fallen targets show, and the score over the game,
    the points of the rules (modes, awards, end-of-ball bonuses) apart from the hits'."""
    if table.rules is None:
        raise ValueError(f"table {table.name!r} has no rules")
    from pinball_env.envs import PinballEnv  # the envs import the plot's floor, not back
    from pinball_env.players import HeuristicPolicy

    plt = _pyplot()
    env = PinballEnv(table=table, render_mode="rgb_array")
    policy = HeuristicPolicy(table)
    _, info = env.reset(seed=seed)
    rate = table.simulation.frame_rate
    times, scores, rule_scores, multipliers = [], [], [], []
    best, frame = -1, None
    done = False
    while not done:
        _, _, terminated, truncated, info = env.step(policy(info))
        done = terminated or truncated
        times.append(info["frames"] / rate)
        scores.append(info["score"])
        rule_scores.append(info["rule_score"])
        multipliers.append(info["bonus_multiplier"])
        world = env.game.world.state
        shown = env.game.state.lights[0].sum() + (~world.targets_up[0]).sum()
        shown += world.kickback_lit[0].sum() + info["bonus_multiplier"]
        if shown > best and env.game.state.game_ball_active[0]:
            best, frame = shown, env.render()
    fig = plt.figure(figsize=(10, 6.2))
    grid = fig.add_gridspec(1, 2, width_ratios=(1, 1.5))
    ax = fig.add_subplot(grid[0, 0])
    ax.imshow(frame)
    ax.set_axis_off()
    ax.set_title("lamps lit, targets down, the bonus and its multiplier", fontsize=9)
    ax = fig.add_subplot(grid[0, 1])
    points, rule_points = np.array(scores), np.array(rule_scores)
    ax.plot(times, points, color="#1d3557", label="score")
    ax.plot(times, points - rule_points, color="#2a9d8f", label="from hits")
    ax.plot(times, rule_points, color="#e76f51", label="from the rules (modes, awards, bonus)")
    ax.set_xlabel("time [s]")
    ax.set_ylabel("points")
    ax.legend(fontsize=8, loc="upper left")
    twin = ax.twinx()
    twin.step(times, multipliers, color="#f4a261", lw=0.8, where="post", alpha=0.7)
    twin.set_ylabel("bonus multiplier", color="#f4a261")
    twin.set_ylim(0.5, table.rules.max_multiplier + 0.5)
    ax.set_title(f"the heuristic's game (seed {seed}): {points[-1]} points, "
                 f"{rule_points[-1]} from the rules", fontsize=9)  # fmt: skip
    fig.tight_layout()
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=90, bbox_inches="tight")
    plt.close(fig)
    env.close()
    return out


# plot_multiball: the seeds it tries for a game with a multiball, how long into a stretch of
# the most balls in play it takes the frame (the balls out of the shooter lane by then), and
# how long it plays on after the first multiball ends (the heuristic's games last many minutes).
MULTIBALL_TRIES = 10
MULTIBALL_SETTLE_FRAMES = 45
MULTIBALL_TAIL_FRAMES = 600


def multiball_game(
    table: Table, seed: int, max_frames: int | None = None
) -> tuple[dict[str, np.ndarray], np.ndarray]:
    """A heuristic game on ``table`` (seed ``seed``) up to ``MULTIBALL_TAIL_FRAMES`` steps
    after its first multiball ends (or its end; at most ``max_frames`` steps): the time, score,
    balls in play and locked, and whether a multiball runs, step by step; and the frame as the
    renderer draws it with the most balls in play (``MULTIBALL_SETTLE_FRAMES`` into the first
    stretch of that many where it lasts: the balls out of the shooter lane)."""
    from pinball_env.envs import PinballEnv  # the envs import the plot's floor, not back
    from pinball_env.players import HeuristicPolicy

    env = PinballEnv(table=table, render_mode="rgb_array")
    policy = HeuristicPolicy(table)
    _, info = env.reset(seed=seed)
    rate = table.simulation.frame_rate
    trace: dict[str, list] = {"time": [], "score": [], "in_play": [], "locked": [],
                              "multiball": []}  # fmt: skip
    best, since, frame = -1, 0, env.render()
    done, seen, tail = False, False, -1  # tail: the steps since the first multiball ended
    while not done and tail < MULTIBALL_TAIL_FRAMES:
        if max_frames is not None and len(trace["time"]) >= max_frames:
            break
        _, _, terminated, truncated, info = env.step(policy(info))
        done = terminated or truncated
        in_play = int(np.sum(info["balls_in_play"]))
        for key, value in (("time", info["frames"] / rate), ("score", info["score"]),
                           ("in_play", in_play), ("locked", info["balls_locked"]),
                           ("multiball", info["multiball"])):  # fmt: skip
            trace[key].append(value)
        seen = seen or info["multiball"]
        if tail >= 0 or (seen and not info["multiball"]):
            tail += 1
        since = since + 1 if in_play == best else 0
        if in_play > best or (in_play == best and since == MULTIBALL_SETTLE_FRAMES):
            best, frame = in_play, env.render()
    env.close()
    assert frame is not None  # (the first step's, with at least 0 > -1 balls in play)
    return {key: np.array(values) for key, values in trace.items()}, frame


def plot_multiball(
    table: Table, out: Path, seed: int = 0, max_frames: int | None = None,
    tries: int = MULTIBALL_TRIES,
) -> Path:  # fmt: skip
    """Write a PNG of a heuristic game on ``table`` (one with a trough of several balls) that
    starts a multiball (the first of seeds ``seed`` to ``seed + tries - 1`` that does; the last
    one tried otherwise), until a while after its first multiball (:func:`multiball_game`): the
    frame with the most balls in play (the lock, the saucer, every ball, as the renderer draws
    them), and the score over the game with the balls in play and the multiballs marked.
    ``max_frames`` caps each game's steps (for tests)."""
    if table.n_balls < 2:
        raise ValueError(f"table {table.name!r} has one ball: no multiball")
    plt = _pyplot()
    for game_seed in range(seed, seed + tries):
        trace, frame = multiball_game(table, game_seed, max_frames)
        if trace["multiball"].any():
            break
    times, multiball = trace["time"], trace["multiball"]
    fig = plt.figure(figsize=(10, 6.2))
    grid = fig.add_gridspec(1, 2, width_ratios=(1, 1.5))
    ax = fig.add_subplot(grid[0, 0])
    ax.imshow(frame)
    ax.set_axis_off()
    ax.set_title(f"{trace['in_play'].max(initial=0)} balls in play", fontsize=9)
    ax = fig.add_subplot(grid[0, 1])
    starts = np.flatnonzero(np.diff(np.concatenate([[False], multiball, [False]]).astype(int)))
    for k, (first, last) in enumerate(zip(starts[::2], starts[1::2], strict=True)):
        ax.axvspan(times[first], times[min(last, len(times) - 1)], color="#e76f51", alpha=0.2,
                   lw=0, label="multiball" if k == 0 else None)  # fmt: skip
    ax.plot(times, trace["score"], color="#1d3557", label="score")
    ax.set_xlabel("time [s]")
    ax.set_ylabel("points")
    twin = ax.twinx()
    twin.step(times, trace["in_play"], color="#2a9d8f", lw=0.8, where="post", alpha=0.8)
    twin.step(times, trace["locked"], color="#f4a261", lw=0.8, where="post", alpha=0.8, ls="--")
    twin.set_ylabel("balls in play (green), locked (orange)")
    twin.set_ylim(-0.2, table.n_balls + 0.5)
    ax.legend(fontsize=8, loc="upper left")
    score = int(trace["score"][-1]) if len(times) else 0
    ax.set_title(f"the heuristic's game on {table.name} (seed {game_seed}), its first "
                 f"{times[-1]:.0f} s: {score} points", fontsize=9)  # fmt: skip
    fig.tight_layout()
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=80, bbox_inches="tight")
    plt.close(fig)
    return out


def plot_cabinet(table: Table, out: Path) -> Path:
    """Write a PNG of the cabinet at work on ``table`` (one with a cabinet): the skill shot's
    plunge beside a whole stroke, one nudge (the cabinet's offset and the ball's velocity
    relative to the table), and the plumb bob under nudges left and right in a rhythm, with
    its ring, the warnings and the tilt."""
    plunger = table.plunger
    if not table.has_cabinet or plunger is None or plunger.pull_time is None:
        raise ValueError(f"table {table.name!r} has no cabinet")
    if plunger.skill_shot is None:
        raise ValueError(f"table {table.name!r} has no skill shot")
    from pinball_env.envs import PinballEnv  # the envs import the plot's floor, not back

    plt = _pyplot()
    fig = plt.figure(figsize=(10, 6.2))
    grid = fig.add_gridspec(2, 2, width_ratios=(1, 1.6))
    ax = fig.add_subplot(grid[:, 0])
    draw_table(ax, table, labels=False)
    rate = table.simulation.frame_rate
    pull_frames = round(plunger.pull_time * rate)
    for frames, colour in ((pull_frames - 4, "#2a9d8f"), (pull_frames, "#e76f51")):
        env = PinballEnv(table=table)
        env.reset(seed=0)
        path, speed = [], 0.0
        for step in range(frames + round(plunger.skill_shot.time * rate)):
            _, _, _, _, info = env.step(4 if step < frames else 0)
            path.append(info["ball_position"])
            if step == frames:  # the launch, one frame of gravity ago
                speed = info["ball_velocity"][1] - table.gravity_vector[1] / rate
        ax.plot(
            *np.array(path).T, color=colour, lw=1.2, label=f"pull {frames} frames: {speed:.2f} m/s"
        )
    ax.legend(loc="lower left", fontsize=7)
    ax.set_title("the plunger: the skill shot and a whole stroke", fontsize=9)
    draw_nudge(fig.add_subplot(grid[0, 1]), table)
    ax = fig.add_subplot(grid[1, 1])
    draw_bob(ax, table, bob_trace(table, lambda step: 8 if (step // 15) % 2 == 0 else 16, 150))
    ax.set_title("nudges left and right every 0.25 s: warnings, then the tilt", fontsize=9)
    fig.tight_layout()
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=90, bbox_inches="tight")
    plt.close(fig)
    return out


def draw_nudge(ax, table: Table) -> None:
    """Draw one NUDGE_LEFT on a ball in free flight on ``ax``: the cabinet's offset and the
    ball's velocity relative to the table."""
    from pinball_env.envs import PinballEnv  # the envs import the plot's floor, not back

    env = PinballEnv(table=table)
    # A ball in free flight in the middle of the table.
    env.reset(seed=0, options={"ball_position": [0.24, 0.42], "ball_velocity": [0.0, 0.3]})
    game, rate = env.game, table.simulation.frame_rate
    times, offsets, relative = [], [], []
    velocity0 = game.state.game_ball[0, 2]
    for step in range(24):
        env.step(8 if step == 5 else 0)  # one nudge left
        times.append(step / rate)
        offsets.append(1000 * game.world.state.cabinet[0, 0])
        relative.append(game.state.game_ball[0, 2] - velocity0)
    ax.plot(times, offsets, color="#1d3557", label="cabinet offset x [mm]")
    ax.plot(times, np.array(relative) * 10, color="#e63946",
            label="ball vx relative to the table x10 [m/s]")  # fmt: skip
    ax.axhline(0, color="#8d99ae", lw=0.5)
    ax.legend(fontsize=7)
    ax.set_title("one NUDGE_LEFT on a ball in free flight: the table moves left under it, "
                 "and back", fontsize=9)  # fmt: skip


# The nudges of the tilt's patterns by discrete action (see ``game.actions``).
NUDGE_LEFT, NUDGE_RIGHT = 8, 16
# The patterns of plot_tilt: the discrete action at each step, over TILT_FRAMES.
TILT_PATTERNS = {
    "NUDGE_LEFT every 15 frames (0.25 s)": lambda step: NUDGE_LEFT if step % 15 == 0 else 0,
    "NUDGE_LEFT and NUDGE_RIGHT in turn every 15 frames": lambda step: (
        0 if step % 15 else NUDGE_LEFT if step % 30 == 0 else NUDGE_RIGHT
    ),
}
TILT_FRAMES = 240


def bob_trace(table: Table, action: Callable[[int], int], frames: int) -> dict[str, np.ndarray]:
    """The plumb bob's angle from vertical [deg], the warnings standing and the tilt, frame by
    frame, of a game on ``table`` (one with a cabinet, seed 0) whose step ``k`` takes discrete
    action ``action(k)``."""
    from pinball_env.envs import PinballEnv  # the envs import the plot's floor, not back

    env = PinballEnv(table=table)
    env.reset(seed=0)
    trace: dict[str, list[float]] = {"time": [], "angle": [], "warnings": [], "tilted": []}
    for step in range(frames):
        _, _, _, _, info = env.step(action(step))
        bob = env.game.world.state.cabinet[0]
        trace["time"].append(step / table.simulation.frame_rate)
        trace["angle"].append(math.degrees(math.hypot(bob[BOB_X], bob[BOB_Y])))
        trace["warnings"].append(info["tilt_warnings"])
        trace["tilted"].append(info["tilted"])
    return {key: np.array(values) for key, values in trace.items()}


def draw_bob(ax, table: Table, trace: dict[str, np.ndarray]) -> None:
    """Draw a :func:`bob_trace` on ``ax``: the bob's angle, its ring, the warnings, the tilts."""
    times, tilts = trace["time"], trace["tilted"]
    assert table.tilt is not None  # (a table with a cabinet)
    ring = table.tilt.ring_angle
    ax.plot(times, trace["angle"], color="#1d3557", label="plumb bob's angle [deg]")
    ax.axhline(ring, color="#e63946", ls="--", lw=0.8, label="the ring")
    ax.step(times, trace["warnings"], color="#f4a261", where="post", label="warnings")
    for t, tilted, before in zip(times, tilts, [False, *tilts], strict=False):
        if tilted and not before:  # a tilt: the ball lost, the next one served
            ax.axvline(t, color="#e63946", lw=2, alpha=0.5)
            ax.text(t, ring * 1.05, " TILT", color="#e63946", fontsize=8)
    ax.set_xlabel("time [s]")
    ax.legend(fontsize=7, loc="upper left")


def plot_tilt(tables: list[Table], out: Path) -> Path:
    """Write a PNG of the plumb bob of each of ``tables`` (with a cabinet; a row each) under
    :data:`TILT_PATTERNS` (a column each), from a ball waiting on the plunger: its angle, its
    ring, the warnings and the tilt."""
    for table in tables:
        if not table.has_cabinet:
            raise ValueError(f"table {table.name!r} has no cabinet")
    plt = _pyplot()
    fig, axes = plt.subplots(
        len(tables), len(TILT_PATTERNS), figsize=(11, 3.2 * len(tables)), squeeze=False
    )
    for row, table in zip(axes, tables, strict=True):
        for ax, (name, action) in zip(row, TILT_PATTERNS.items(), strict=True):
            draw_bob(ax, table, bob_trace(table, action, TILT_FRAMES))
            ax.set_title(f"{table.name}: {name}", fontsize=9)
    fig.tight_layout()
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=90, bbox_inches="tight")
    plt.close(fig)
    return out


def _parser() -> argparse.ArgumentParser:
    parser = command_parser("pinball_env.tools.plot", __doc__)
    parser.add_argument("table", nargs="?", default="box", help="table name or YAML path")
    parser.add_argument("--out", type=Path, default=Path("outputs/table.png"))
    parser.add_argument(
        "--trace", type=int, default=0, metavar="FRAMES", help="simulate the ball for FRAMES"
    )
    parser.add_argument(
        "--velocity", type=float, nargs=2, metavar=("VX", "VY"), help="launch velocity [m/s]"
    )
    parser.add_argument(
        "--gallery", action="store_true", help="draw a grid of generated tables instead"
    )
    parser.add_argument(
        "--cabinet", action="store_true", help="the plunger, a nudge and the tilt at work"
    )
    parser.add_argument(
        "--tilt", nargs="+", metavar="TABLE",
        help="the plumb bob of these tables (with a cabinet) under one-way and alternating nudges",
    )  # fmt: skip
    parser.add_argument(
        "--rules", action="store_true", help="a heuristic game: the rules' lights and score"
    )
    parser.add_argument(
        "--multiball", action="store_true",
        help="a heuristic game with a multiball: its most balls in play and the score",
    )  # fmt: skip
    parser.add_argument(
        "--difficulty", choices=DIFFICULTIES, default="easy", help="of the gallery's tables"
    )
    parser.add_argument(
        "--seeds", type=int, nargs=2, default=(0, 12), metavar=("FIRST", "COUNT"),
        help="the gallery's tables: COUNT seeds from FIRST (default: 0 12)",
    )  # fmt: skip
    return parser


def main(argv: list[str] | None = None) -> Path:
    parser = _parser()
    args = parser.parse_args(argv)
    if args.gallery and (args.seeds[0] < 0 or args.seeds[1] < 1):
        parser.error(
            f"--seeds needs FIRST >= 0 and COUNT >= 1, got {args.seeds[0]} {args.seeds[1]}"
        )
    out = _plot(args)
    print(f"wrote {out}")
    return out


def _plot(args: argparse.Namespace) -> Path:
    """The picture the arguments ask for (one kind, the first given of those below)."""
    if args.gallery:
        first, count = args.seeds
        tables = [generate_table(s, args.difficulty) for s in range(first, first + count)]
        return plot_gallery(tables, args.out, columns=min(count, 6))
    if args.rules:
        return plot_rules(load_any_table(args.table), args.out)
    if args.multiball:
        return plot_multiball(load_any_table(args.table), args.out)
    if args.tilt:
        return plot_tilt([load_any_table(name) for name in args.tilt], args.out)
    if args.cabinet:
        return plot_cabinet(load_any_table(args.table), args.out)
    velocity = tuple(args.velocity) if args.velocity else None
    return plot_table(load_any_table(args.table), args.out, args.trace, velocity)


if __name__ == "__main__":
    main()
