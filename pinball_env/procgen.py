"""Generated tables: endless playable layouts, each drawn from a seed.

``generate_table(seed, difficulty)`` draws a table in the proportions of real machines (Procgen's
idea, for pinball): playfield size and slope, the top arch, the shooter lane and its gate, the
flippers, outlanes and inlanes, slingshots, and a varying number and placement of pop bumpers,
rubber posts, deflector walls (some one-way), upper deflectors and top rollover lanes. The same
seed gives the same table on any machine (NumPy's ``SeedSequence`` and ``PCG64`` are specified,
and every length is rounded to 0.01 mm).

A drawn layout is kept only if it passes ``load_table``'s validation and :func:`playability`:

- the plunger shot enters the playfield at every launch speed, and at a third of them or more
  it comes down to a flipper (not straight down an outlane);
- a ball rolling down each inlane reaches its flipper, and a fair share of the balls dropped
  anywhere in the playfield touch a flipper on the way down;
- with the flippers at rest, every ball from random reachable places, sent across between the
  slingshots, or launched, drains within ``DRAIN_TIME``: no pocket holds a ball, and no pair of
  kickers keeps one bouncing for ever.

Placed elements keep ``CLEARANCE`` (a ball and a margin) from every other element, so nothing
overlaps and every gap lets a ball through. A layout that fails is redrawn from the next derived
seed (``SeedSequence([seed, difficulty, draw])``); :func:`generate` says how many draws it took
and why each was rejected. ``"easy"`` tables are forgiving (long flippers, a narrow centre gap,
narrow outlanes, upper deflectors); ``"hard"`` ones are not.

Tables by name: ``"procgen:SEED"`` and ``"procgen-hard:SEED"`` wherever a table name is taken
(the envs, the plot tool, training configs: :func:`load_any_table`).
"""

from __future__ import annotations

import itertools
import math
import os
import re
from dataclasses import dataclass

import numpy as np

from pinball_env.physics import first_flipper, point_segment_distance
from pinball_env.physics.columns import BALL_X, BALL_Y, CONTACT_ELEMENT
from pinball_env.table import Table, TableError, load_table, table_from_dict

DIFFICULTIES = ("easy", "hard")
PREFIXES = {"easy": "procgen", "hard": "procgen-hard"}
NAME_PATTERN = re.compile(r"(procgen|procgen-hard):(.*)")
MAX_SEED = 2**63 - 1
# Draws tried before giving up on a seed (none has needed more than a handful).
MAX_DRAWS = 100

BALL_RADIUS = 0.0135  # the standard 27 mm ball
MARGIN = 0.005  # the cabinet's walls, in from the playfield's edges [m]
LANE_WIDTH = 0.037  # inside width of the shooter lane [m]
DRAIN_Y = 0.03  # height of the drain line [m]
# Gap kept between a placed element and any other: a ball and 6 mm [m].
CLEARANCE = 2.0 * BALL_RADIUS + 0.006
# With the flippers at rest, every ball must drain within this [s].
DRAIN_TIME = 60.0
# A ball that moves less than its radius in this long is resting [s] (as the game's ball search).
REST_TIME = 10.0
# Balls dropped at random reachable places in the playability check, and the share of them
# that must touch a flipper on the way down.
DROPS = 48
MIN_FLIPPER_SHARE = 0.25
# Plunger shots tried (launch speeds spread over the plunger's range), and the share of them
# that must come down to a flipper before draining (not straight down an outlane).
LAUNCHES = 9
MIN_LAUNCH_SHARE = 1 / 3
# Balls sent across between the slingshots: heights from the kickers' bottoms to above their
# tops, and speeds [m/s] either way.
SLING_HEIGHTS = 16
SLING_SPEEDS = (-1.2, -0.8, -0.5, -0.3, 0.3, 0.5, 0.8, 1.2)

MATERIALS = {
    "wall": {"restitution": 0.3, "friction": 0.3},
    "rubber": {"restitution": 0.85, "friction": 0.5},
    "flipper": {"restitution": 0.8, "friction": 0.4},
    "bumper": {"restitution": 0.9, "friction": 0.3},
    "metal": {"restitution": 0.3, "friction": 0.2},
}


@dataclass(frozen=True)
class Ranges:
    """What a difficulty draws from: (low, high) ranges, uniform; counts inclusive."""

    width: tuple[float, float]  # playfield width, shooter lane included [m]
    aspect: tuple[float, float]  # height / width
    slope: tuple[float, float]  # [deg]
    flipper_length: tuple[float, float]  # pivot to tip centre [m]
    flipper_gap: tuple[float, float]  # between the flipper tips at rest, surface to surface [m]
    rest_angle: tuple[float, float]  # below horizontal [deg]
    swing: tuple[float, float]  # [deg]
    outlane: tuple[float, float]  # outlane width [m]
    upper_deflectors: float  # chance of a right upper deflector (the left is always there)
    slingshot_kick: tuple[float, float]  # [m/s]
    bumpers: tuple[int, int]
    posts: tuple[int, int]
    deflectors: tuple[int, int]
    top_lanes: tuple[int, ...]  # lane counts to choose from (0: none)


RANGES = {
    "easy": Ranges(
        width=(0.46, 0.60), aspect=(1.85, 2.2), slope=(6.0, 6.75), flipper_length=(0.066, 0.08),
        flipper_gap=(0.034, 0.042), rest_angle=(22.0, 28.0), swing=(48.0, 55.0),
        outlane=(0.035, 0.040), upper_deflectors=0.8, slingshot_kick=(1.0, 1.3), bumpers=(2, 5),
        posts=(0, 2), deflectors=(0, 1), top_lanes=(0, 2, 3),
    ),
    "hard": Ranges(
        width=(0.46, 0.60), aspect=(1.85, 2.2), slope=(6.5, 7.5), flipper_length=(0.056, 0.07),
        flipper_gap=(0.042, 0.052), rest_angle=(25.0, 32.0), swing=(45.0, 52.0),
        outlane=(0.038, 0.048), upper_deflectors=0.3, slingshot_kick=(1.2, 1.6), bumpers=(1, 4),
        posts=(0, 3), deflectors=(0, 3), top_lanes=(0, 2, 3, 4),
    ),
}  # fmt: skip


@dataclass(frozen=True)
class Generated:
    """A generated table and how it was found."""

    table: Table
    seed: int
    difficulty: str
    draws: int  # layouts drawn, the kept one included
    rejected: tuple[str, ...]  # why each earlier draw was rejected


def table_name(seed: int, difficulty: str = "easy") -> str:
    """The name of a generated table: ``"procgen:SEED"`` or ``"procgen-hard:SEED"``."""
    return f"{PREFIXES[_check_difficulty(difficulty)]}:{seed}"


def parse_name(name: str) -> tuple[int, str] | None:
    """``(seed, difficulty)`` for a generated table's name, None for any other name; a
    ``procgen`` name with a bad seed is a ``TableError``."""
    match = NAME_PATTERN.fullmatch(name)
    if match is None:
        return None
    prefix, seed = match.groups()
    if not re.fullmatch(r"\d{1,19}", seed) or int(seed) > MAX_SEED:
        raise TableError(
            f"{name!r}: the seed of a generated table is an integer from 0 to {MAX_SEED}, "
            f"got {seed!r}"
        )
    difficulty = next(d for d, p in PREFIXES.items() if p == prefix)
    return int(seed), difficulty


def load_any_table(name_or_path: str | os.PathLike[str]) -> Table:
    """``load_table``, and the generated tables by name (``"procgen:SEED"``,
    ``"procgen-hard:SEED"``): what the envs, the plot tool and the training configs take."""
    generated = parse_name(name_or_path) if isinstance(name_or_path, str) else None
    if generated is not None:
        return generate_table(*generated)
    return load_table(name_or_path)


def generate_table(seed: int, difficulty: str = "easy") -> Table:
    """The playable table drawn from ``seed`` (see the module's docstring)."""
    return generate(seed, difficulty).table


def generate(seed: int, difficulty: str = "easy") -> Generated:
    """:func:`generate_table`, with the number of draws it took and the rejections."""
    _check_difficulty(difficulty)
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)):
        raise TypeError(f"seed must be an integer, got {type(seed).__name__}")
    if not 0 <= seed <= MAX_SEED:
        raise ValueError(f"seed must be from 0 to {MAX_SEED}, got {seed}")
    seed = int(seed)
    name = table_name(seed, difficulty)
    rejected: list[str] = []
    for draw in range(MAX_DRAWS):
        rng = np.random.default_rng([seed, DIFFICULTIES.index(difficulty), draw])
        try:
            table = table_from_dict(draw_layout(rng, RANGES[difficulty], name), f"<{name}>")
        except (TableError, LayoutError) as exc:
            rejected.append(f"draw {draw}: {exc}")
            continue
        problem = playability(table, rng)
        if problem is None:
            return Generated(table, seed, difficulty, draw + 1, tuple(rejected))
        rejected.append(f"draw {draw}: {problem}")
    raise RuntimeError(f"{name}: no playable layout in {MAX_DRAWS} draws: {rejected[-3:]}")


class LayoutError(Exception):
    """A drawn layout that cannot be built (an element found no free place)."""


def _check_difficulty(difficulty: str) -> str:
    if difficulty not in DIFFICULTIES:
        raise ValueError(f"difficulty must be one of {DIFFICULTIES}, got {difficulty!r}")
    return difficulty


# --- drawing a layout ---------------------------------------------------------------------------


def _mm(value: float) -> float:
    """A length rounded to 0.01 mm, so that files are short and the same on every machine."""
    return round(float(value), 5)


def _point(x: float, y: float) -> list[float]:
    return [_mm(x), _mm(y)]


class _Obstacles:
    """The segments and circles placed so far, for the clearance of the next element."""

    def __init__(self) -> None:
        self.segments: list[tuple[float, float, float, float]] = []
        self.circles: list[tuple[float, float, float]] = []

    def add_wall(self, points: list[list[float]], closed: bool = False) -> None:
        ends = points + points[:1] if closed else points
        for (x0, y0), (x1, y1) in itertools.pairwise(ends):
            self.segments.append((x0, y0, x1, y1))

    def add_circle(self, center: list[float], radius: float) -> None:
        self.circles.append((*center, radius))

    def circle_gap(self, x: float, y: float, radius: float) -> float:
        """The smallest gap between a circle and everything placed."""
        gaps = [point_segment_distance(x, y, *s) - radius for s in self.segments]
        gaps += [math.hypot(x - cx, y - cy) - radius - r for cx, cy, r in self.circles]
        return min(gaps, default=math.inf)

    def segment_gap(self, segment: tuple[float, float, float, float]) -> float:
        """The smallest gap between a segment and everything placed."""
        gaps = [_segment_distance(segment, s) for s in self.segments]
        gaps += [point_segment_distance(cx, cy, *segment) - r for cx, cy, r in self.circles]
        return min(gaps, default=math.inf)


def _segment_distance(a: tuple[float, ...], b: tuple[float, ...]) -> float:
    """Distance between two segments (0 if they cross)."""
    ax0, ay0, ax1, ay1 = a
    bx0, by0, bx1, by1 = b

    def side(px: float, py: float, qx: float, qy: float, rx: float, ry: float) -> float:
        return (qx - px) * (ry - py) - (qy - py) * (rx - px)

    d1, d2 = side(ax0, ay0, ax1, ay1, bx0, by0), side(ax0, ay0, ax1, ay1, bx1, by1)
    d3, d4 = side(bx0, by0, bx1, by1, ax0, ay0), side(bx0, by0, bx1, by1, ax1, ay1)
    if d1 * d2 < 0.0 and d3 * d4 < 0.0:
        return 0.0
    return min(
        point_segment_distance(ax0, ay0, *b), point_segment_distance(ax1, ay1, *b),
        point_segment_distance(bx0, by0, *a), point_segment_distance(bx1, by1, *a),
    )  # fmt: skip


def draw_layout(rng: np.random.Generator, ranges: Ranges, name: str) -> dict:
    """A table description (as ``load_table`` reads from YAML) drawn with ``rng``; the caller
    validates it and checks that it plays."""
    uniform = rng.uniform
    width = _mm(uniform(*ranges.width))
    height = _mm(width * uniform(*ranges.aspect))
    slope = uniform(*ranges.slope)
    left, right = MARGIN, width - MARGIN  # the cabinet's sides
    lane_x = right - LANE_WIDTH  # the shooter lane's inner wall
    centre = (left + lane_x) / 2.0  # of the playfield proper, between the cabinet and the lane

    def mirror(x: float) -> float:
        return left + lane_x - x

    arch_radius = (right - left) / 2.0
    arch_x, arch_y = width / 2.0, height - MARGIN - arch_radius
    arc = [
        _point(arch_x + arch_radius * math.cos(a), arch_y + arch_radius * math.sin(a))
        for a in np.linspace(0.0, math.pi, 25)
    ]
    outline = [_point(left, left), _point(right, left), *arc[:-1], _point(left, arch_y)]
    gate_y = arch_y - 0.02
    walls: list[dict] = [
        {"name": "outline", "points": outline, "closed": True, "material": "wall"},
        {"name": "lane_wall", "points": [_point(lane_x, left), _point(lane_x, gate_y)],
         "material": "wall"},
        {"name": "gate", "points": [_point(lane_x, gate_y), _point(right, gate_y + 0.04)],
         "material": "metal", "one_sided": True},
    ]  # fmt: skip
    posts: list[dict] = []
    sensors: list[dict] = []

    # Flippers, mirror images about the centre line, with a gap between their tips at rest.
    length = uniform(*ranges.flipper_length)
    rest = -uniform(*ranges.rest_angle)
    swing = uniform(*ranges.swing)
    gap = uniform(*ranges.flipper_gap)
    base_radius, tip_radius = 0.0116, 0.007
    pivot_y = uniform(0.10, 0.14)
    pivot_x = centre - (gap / 2.0 + tip_radius + length * math.cos(math.radians(rest)))
    stroke = uniform(0.022, 0.028)
    flippers = [
        {"name": f"{side}_flipper", "pivot": _point(x, pivot_y), "length": _mm(length),
         "base_radius": base_radius, "tip_radius": tip_radius, "rest_angle": round(a, 3),
         "up_angle": round(a + sign * swing, 3), "stroke_time": round(stroke, 4),
         "return_time": 0.04, "material": "flipper", "button": side}
        for side, x, a, sign in (
            ("left", pivot_x, rest, 1.0), ("right", mirror(pivot_x), 180.0 - rest, -1.0)
        )
    ]  # fmt: skip

    # Outlane guides: a wire between outlane and inlane, then an incline down to just above the
    # flipper's base; a slingshot above each inlane; rollovers across the four lanes.
    wire_x = left + uniform(*ranges.outlane)
    end_x, end_y = pivot_x - 0.011, pivot_y + 0.025
    incline_y = end_y + 0.79 * (end_x - wire_x)
    sling_x = wire_x + uniform(0.038, 0.044)
    sling_width = min(0.05, end_x - sling_x)
    if sling_width < 0.02:
        raise LayoutError("no room for the slingshots between the inlanes and the flippers")
    kick = round(uniform(*ranges.slingshot_kick), 3)
    rollover_y = incline_y + 0.06
    sling_top = incline_y + 0.13
    for side, m in (("left", lambda x: x), ("right", mirror)):
        walls.append({"name": f"{side}_outlane_guide", "material": "metal", "points": [
            _point(m(wire_x), incline_y + 0.11), _point(m(wire_x), incline_y),
            _point(m(end_x), end_y)]})  # fmt: skip
        body = [_point(m(sling_x + sling_width), incline_y - 0.005),
                _point(m(sling_x), incline_y + 0.03), _point(m(sling_x), sling_top)]  # fmt: skip
        walls.append({"name": f"{side}_sling_body", "points": body, "material": "rubber"})
        walls.append({"name": f"{side}_slingshot", "points": [body[2], body[0]],
                      "material": "rubber", "kick": kick, "score": 10})  # fmt: skip
        posts.append({"name": f"{side}_guide_post", "center": _point(m(wire_x), incline_y + 0.116),
                      "radius": 0.006, "material": "rubber"})  # fmt: skip
        lanes = ((f"{side}_outlane", left, wire_x), (f"{side}_inlane", wire_x, sling_x))
        for lane, x0, x1 in lanes:
            sensors.append(
                {
                    "name": lane,
                    "points": [_point(m(x0), rollover_y), _point(m(x1), rollover_y)],
                    "score": 10,
                }
            )
    sensors.append({"name": "drain", "points": [_point(left, DRAIN_Y), _point(lane_x, DRAIN_Y)],
                    "drain": True})  # fmt: skip

    obstacles = _Obstacles()
    for wall in walls:
        obstacles.add_wall(wall["points"], wall.get("closed", False))
    for post in posts:
        obstacles.add_circle(post["center"], post["radius"])
    for flipper in flippers:  # the whole swing, roughly: a disc around each pivot
        obstacles.add_circle(flipper["pivot"], length + tip_radius)
    field_low = sling_top + 0.08  # placed elements stay above the slingshots

    # Upper deflectors: rubber ramps off the side walls that throw a ball rolling down a wall
    # (the plunger shot comes round the arch and down the left one) towards the centre instead
    # of into the outlane. The left one always; the right one by chance.
    dx, dy = uniform(0.07, 0.1), uniform(0.05, 0.08)
    y = max(uniform(0.5, 0.6) * height, field_low + 0.05 + dy + uniform(0.0, 0.05))
    if y > arch_y - 0.1:
        raise LayoutError("no room for the upper deflectors below the arch")
    right_too = rng.random() < ranges.upper_deflectors
    for side, x, sign in (("left", left, 1.0), ("right", lane_x, -1.0))[: 1 + right_too]:
        points = [_point(x, y), _point(x + sign * dx, y - dy)]
        walls.append({"name": f"{side}_deflector", "points": points, "material": "rubber"})
        obstacles.add_wall(points)

    # Rollover lanes under the arch: guides hanging from just below it, a rollover in each lane.
    n_lanes = int(rng.choice(ranges.top_lanes))
    if n_lanes:
        spacing = uniform(0.042, 0.05)
        guides = []
        for i in range(n_lanes + 1):
            x = arch_x + (i - n_lanes / 2.0) * spacing
            inner = arch_radius - CLEARANCE - 0.002  # the arch's chords sag 0.5 mm at most
            top = arch_y + math.sqrt(inner**2 - (x - arch_x) ** 2)
            guides.append((x, top, top - 0.05))
        for i, (x, top, bottom) in enumerate(guides):
            points = [_point(x, top), _point(x, bottom)]
            if i in (0, n_lanes) and obstacles.segment_gap((*points[0], *points[1])) < CLEARANCE:
                raise LayoutError("the top lanes do not fit under the arch")
            walls.append({"name": f"lane_guide_{i}", "points": points, "material": "metal"})
            obstacles.add_wall(points)
        for i in range(n_lanes):
            (x0, t0, b0), (x1, t1, b1) = guides[i], guides[i + 1]
            y = (max(b0, b1) + min(t0, t1)) / 2.0
            sensors.append({"name": f"top_lane_{i}", "score": 50,
                            "points": [_point(x0, y), _point(x1, y)]})  # fmt: skip

    def place_circle(radius: float, low: float) -> list[float]:
        for _ in range(200):
            x = uniform(left + radius + CLEARANCE, lane_x - radius - CLEARANCE)
            y = uniform(low, arch_y + 0.6 * arch_radius)
            inside = math.hypot(x - arch_x, y - arch_y) <= arch_radius - radius - CLEARANCE
            if (y <= arch_y or inside) and obstacles.circle_gap(x, y, radius) >= CLEARANCE:
                center = _point(x, y)
                obstacles.add_circle(center, radius)
                return center
        raise LayoutError("no free place left for a post or bumper")

    bumper_low = max(0.45 * height, field_low + 0.1)
    for i in range(rng.integers(ranges.bumpers[0], ranges.bumpers[1] + 1)):
        radius = _mm(uniform(0.025, 0.032))
        posts.append({"name": f"bumper_{i}", "center": place_circle(radius, bumper_low),
                      "radius": radius, "material": "bumper",
                      "kick": round(uniform(1.2, 1.6), 3), "score": 100})  # fmt: skip
    for i in range(rng.integers(ranges.posts[0], ranges.posts[1] + 1)):
        radius = _mm(uniform(0.006, 0.01))
        posts.append({"name": f"post_{i}", "center": place_circle(radius, field_low),
                      "radius": radius, "material": "rubber", "score": 10})  # fmt: skip
    for i in range(rng.integers(ranges.deflectors[0], ranges.deflectors[1] + 1)):
        for _ in range(200):
            half = uniform(0.02, 0.04)
            angle = uniform(0.0, math.pi)
            x = uniform(left + CLEARANCE + half, lane_x - CLEARANCE - half)
            y = uniform(field_low, arch_y)
            dx, dy = half * math.cos(angle), half * math.sin(angle)
            points = [_point(x - dx, y - dy), _point(x + dx, y + dy)]
            if obstacles.segment_gap((*points[0], *points[1])) >= CLEARANCE:
                break
        else:
            raise LayoutError("no free place left for a deflector")
        one_way = bool(rng.random() < 0.25)
        walls.append(
            {
                "name": f"deflector_{i}",
                "points": points,
                "material": str(rng.choice(["rubber", "metal"])),
                "one_sided": one_way,
            }
        )
        obstacles.add_wall(points)

    # The plunger: launch speeds scaled from the classic table's by the climb to the top.
    climb = math.sqrt(height * math.sin(math.radians(slope)))
    scale = climb / math.sqrt(1.07 * math.sin(math.radians(6.5)))
    plunger = _point(lane_x + LANE_WIDTH / 2.0, 0.04)
    return {
        "name": name,
        "playfield": {"width": width, "height": height},
        "slope_deg": round(slope, 3),
        "gravity": 9.81,
        "ball": {"radius": BALL_RADIUS, "mass": 0.08, "start": plunger, "velocity": [0.0, 0.0]},
        "materials": MATERIALS,
        "walls": walls,
        "posts": posts,
        "flippers": flippers,
        "sensors": sensors,
        "plunger": {"position": plunger, "speed": [round(2.2 * scale, 3), round(3.2 * scale, 3)]},
    }


# --- playability --------------------------------------------------------------------------------


def playability(table: Table, rng: np.random.Generator, drops: int = DROPS) -> str | None:
    """What keeps ``table`` from being played (None: nothing): the checks of the module's
    docstring, run on the swept kernel with ``drops`` balls at places drawn from ``rng``."""
    from pinball_env.world import World  # the world imports the table package, as this does

    plunger = table.plunger
    radius = table.ball.radius
    lane_x = min(s[0] for s in _lane_walls(table))
    speeds = np.linspace(plunger.speed[0], plunger.speed[1], LAUNCHES)
    inlanes = [s for s in table.sensors if s.name.endswith("_inlane")]
    starts = [(plunger.position, (0.0, float(v))) for v in speeds]
    starts += [(((s.points[0][0] + s.points[1][0]) / 2.0, s.points[0][1]), (0.0, 0.0))
               for s in inlanes]  # fmt: skip
    n_fixed = len(starts)
    # Balls sent across between the slingshots, where kicks that balance gravity could keep
    # one bouncing from side to side for ever.
    slings = [w for w in table.walls if w.name.endswith("_slingshot")]
    if slings:
        low = max(min(p[1] for p in w.points) for w in slings)
        high = min(max(p[1] for p in w.points) for w in slings) + 2.0 * radius
        middle = sum(p[0] for w in slings for p in w.points) / (2 * len(slings))
        for height in np.linspace(low, high, SLING_HEIGHTS):
            for speed in SLING_SPEEDS:
                starts.append(((middle, float(height)), (speed, 0.0)))
    n_checked = len(starts)
    cells = np.argwhere(table.free_space)  # (row, column) of reachable 1 mm cells
    x = (cells[:, 1] + 0.5) * 0.001
    y = (cells[:, 0] + 0.5) * 0.001
    cells = cells[(x < lane_x - radius) & (y > DRAIN_Y + radius)]
    picks = cells[rng.choice(len(cells), drops, replace=len(cells) < drops)]
    for row, column in picks:
        speed, heading = rng.uniform(0.0, 1.5), rng.uniform(0.0, 2.0 * math.pi)
        start = ((column + 0.5) * 0.001, (row + 0.5) * 0.001)
        starts.append((start, (speed * math.cos(heading), speed * math.sin(heading))))

    world = World(table, len(starts))
    for env, (position, velocity) in enumerate(starts):
        world.place_ball(env, position, velocity)
    flippers = first_flipper(world.geometry) + np.arange(len(table.flippers))
    entered = np.zeros(len(starts), dtype=bool)
    touched = np.zeros(len(starts), dtype=bool)
    anchor = world.balls[:, [BALL_X, BALL_Y]].copy()
    still = np.zeros(len(starts), dtype=np.int64)
    frame_rate = table.simulation.frame_rate
    rest_frames = round(REST_TIME * frame_rate)
    for _ in range(round(DRAIN_TIME * frame_rate)):
        world.step()
        active = world.active
        if not active.any():
            break
        position = world.balls[:, [BALL_X, BALL_Y]]
        entered |= active & (position[:, 0] < lane_x - radius)
        state = world.state
        for env in np.flatnonzero(active & ~touched & (state.contact_count > 0)):
            count = min(state.contact_count[env], state.contacts.shape[1])
            ids = state.contacts[env, :count, CONTACT_ELEMENT]
            touched[env] = np.isin(ids, flippers).any()
        moved = np.hypot(*(position - anchor).T) >= radius
        anchor[moved] = position[moved]
        still = np.where(moved | ~active, 0, still + 1)
        if (still >= rest_frames).any():
            env = int(np.argmax(still))
            if env < len(speeds) and not entered[env]:
                return "a plunger shot does not enter the playfield"
            return f"a ball rests at ({position[env, 0]:.3f}, {position[env, 1]:.3f})"
    if world.active.any():
        env = int(np.argmax(world.active))
        x, y = starts[env][0]
        return f"a ball from ({x:.3f}, {y:.3f}) has not drained in {DRAIN_TIME:g} s"
    if not entered[: len(speeds)].all():
        return "a plunger shot does not enter the playfield"
    if touched[: len(speeds)].mean() < MIN_LAUNCH_SHARE:
        return f"only {touched[: len(speeds)].mean():.0%} of plunger shots reach a flipper"
    if not touched[len(speeds) : n_fixed].all():
        return "a ball rolling down an inlane misses its flipper"
    share = touched[n_checked:].mean()
    if share < MIN_FLIPPER_SHARE:
        return f"only {share:.0%} of dropped balls touch a flipper"
    return None


def _lane_walls(table: Table) -> list[tuple[float, float, float, float]]:
    """The shooter lane's inner wall as segments."""
    return [s for w in table.walls if w.name == "lane_wall" for s in w.segments()]


__all__ = [
    "CLEARANCE",
    "DIFFICULTIES",
    "RANGES",
    "Generated",
    "LayoutError",
    "Ranges",
    "draw_layout",
    "generate",
    "generate_table",
    "load_any_table",
    "parse_name",
    "playability",
    "table_name",
]
