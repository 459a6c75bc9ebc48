"""Drawing a layout from a seed's random stream, element by element: the cabinet and its arch,
the shooter lane, the flippers, the outlanes, inlanes and slingshots, the upper deflectors, the
top rollover lanes, the pop bumpers, the rubber posts, the deflector walls and the plunger; on
request, then, a drop bank and a spinner.

:func:`draw_layout` returns a table description (as ``load_table`` reads from YAML); the caller
validates it and checks that it plays. Each step draws from the same ``rng`` in a fixed order, so
a seed always gives the same layout. The drop bank and the spinner are drawn after the rest, from
a stream of their own, so that the rest of a layout is the same with them or without them.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from pinball_env.physics import point_segment_distance
from pinball_env.procgen.obstacles import Obstacles, mm, point
from pinball_env.procgen.ranges import Ranges

BALL_RADIUS = 0.0135  # the standard 27 mm ball
MARGIN = 0.005  # the cabinet's walls, in from the playfield's edges [m]
LANE_WIDTH = 0.037  # inside width of the shooter lane [m]
DRAIN_Y = 0.03  # height of the drain line [m]
# Gap kept between a placed element and any other: a ball and 6 mm [m].
CLEARANCE = 2.0 * BALL_RADIUS + 0.006
# Flippers' circles at the pivot and the tip [m].
FLIPPER_BASE_RADIUS = 0.0116
FLIPPER_TIP_RADIUS = 0.007
# Tries at a random free place for a bumper, post or deflector before giving up on the layout.
PLACE_TRIES = 200

MATERIALS = {
    "wall": {"restitution": 0.3, "friction": 0.3},
    "rubber": {"restitution": 0.85, "friction": 0.5},
    "flipper": {"restitution": 0.8, "friction": 0.4},
    "bumper": {"restitution": 0.9, "friction": 0.3},
    "metal": {"restitution": 0.3, "friction": 0.2},
}
# The material of drop targets' faces, in a layout's materials only when it has targets.
TARGET_MATERIAL = {"restitution": 0.5, "friction": 0.3}
# A drop bank: its targets (count, inclusive), each target's length [m], the gap between two
# targets [m], the points per target and the time the bank takes to rise again [s].
BANK_TARGETS = (2, 4)
DROP_LENGTH = (0.03, 0.04)
DROP_GAP = 0.01
DROP_SCORE = 100
BANK_RESET_TIME = 1.0
# A spinner: its width across the path [m], and as classic_v1's: its flap's radius [m], its
# damping [1/s] and friction [rad/s^2], its points per revolution.
SPINNER_WIDTH = (0.05, 0.07)
SPINNER = {"radius": 0.015, "damping": 0.5, "friction": 20.0, "score": 10}


class LayoutError(Exception):
    """A drawn layout that cannot be built (an element found no free place)."""


@dataclass
class Layout:
    """A layout being drawn: its random stream, its size, and the elements placed so far."""

    rng: np.random.Generator
    ranges: Ranges
    width: float
    height: float
    walls: list[dict] = field(default_factory=list)
    posts: list[dict] = field(default_factory=list)
    sensors: list[dict] = field(default_factory=list)
    flippers: list[dict] = field(default_factory=list)
    obstacles: Obstacles = field(default_factory=Obstacles)

    @property
    def left(self) -> float:
        """The cabinet's left side [m]."""
        return MARGIN

    @property
    def right(self) -> float:
        """The cabinet's right side [m]."""
        return self.width - MARGIN

    @property
    def lane_x(self) -> float:
        """The shooter lane's inner wall [m]."""
        return self.right - LANE_WIDTH

    @property
    def centre(self) -> float:
        """Of the playfield proper, between the cabinet and the lane [m]."""
        return (self.left + self.lane_x) / 2.0

    @property
    def plunger(self) -> list[float]:
        """Where the plunger holds the ball (the ball's start), at the shooter lane's foot."""
        return point(self.lane_x + LANE_WIDTH / 2.0, 0.04)

    @property
    def arch_radius(self) -> float:
        return (self.right - self.left) / 2.0

    @property
    def arch_x(self) -> float:
        return self.width / 2.0

    @property
    def arch_y(self) -> float:
        """The height of the arch's centre [m]."""
        return self.height - MARGIN - self.arch_radius

    def uniform(self, low: float, high: float) -> float:
        return self.rng.uniform(low, high)

    def mirror(self, x: float) -> float:
        """``x`` mirrored about the playfield's centre line."""
        return self.left + self.lane_x - x

    def place_wall(self, wall: dict) -> None:
        """Add a wall drawn after the fixed parts, and keep the next elements clear of it."""
        self.walls.append(wall)
        self.obstacles.add_wall(wall["points"])


def draw_layout(
    rng: np.random.Generator,
    ranges: Ranges,
    name: str,
    targets: np.random.Generator | None = None,
) -> dict:
    """A table description (as ``load_table`` reads from YAML) drawn with ``rng``; the caller
    validates it and checks that it plays. With ``targets`` (a random stream of their own) a
    drop bank and a spinner are drawn from it after the rest (:func:`_draw_targets`), which is
    then what it is without them."""
    width = mm(rng.uniform(*ranges.width))
    height = mm(width * rng.uniform(*ranges.aspect))
    slope = rng.uniform(*ranges.slope)
    layout = Layout(rng, ranges, width, height)
    _draw_cabinet(layout)
    pivot_x, pivot_y, reach = _draw_flippers(layout)
    sling_top = _draw_outlanes(layout, pivot_x, pivot_y)
    drain = [point(layout.left, DRAIN_Y), point(layout.lane_x, DRAIN_Y)]
    layout.sensors.append({"name": "drain", "points": drain, "drain": True})
    _gather_obstacles(layout, reach)
    field_low = sling_top + 0.08  # placed elements stay above the slingshots
    _draw_upper_deflectors(layout, field_low)
    _draw_top_lanes(layout)
    _draw_bumpers_and_posts(layout, field_low)
    _draw_deflectors(layout, field_low)
    description = _description(layout, name, slope)
    if targets is not None:
        aim = (layout.centre, pivot_y + reach)  # above the flippers' tips
        description.update(_draw_targets(layout, targets, field_low, aim))
    return description


def _draw_cabinet(layout: Layout) -> None:
    """The outline (the cabinet's sides, its floor and the top arch), the shooter lane's wall
    and the one-way gate at its top."""
    left, right, lane_x = layout.left, layout.right, layout.lane_x
    arch_x, arch_y, arch_radius = layout.arch_x, layout.arch_y, layout.arch_radius
    arc = [
        point(arch_x + arch_radius * math.cos(a), arch_y + arch_radius * math.sin(a))
        for a in np.linspace(0.0, math.pi, 25)
    ]
    outline = [point(left, left), point(right, left), *arc[:-1], point(left, arch_y)]
    gate_y = arch_y - 0.02
    layout.walls += [
        {"name": "outline", "points": outline, "closed": True, "material": "wall"},
        {"name": "lane_wall", "points": [point(lane_x, left), point(lane_x, gate_y)],
         "material": "wall"},
        {"name": "gate", "points": [point(lane_x, gate_y), point(right, gate_y + 0.04)],
         "material": "metal", "one_sided": True},
    ]  # fmt: skip


def _draw_flippers(layout: Layout) -> tuple[float, float, float]:
    """Flippers, mirror images about the centre line, with a gap between their tips at rest.
    Returns the left pivot (x, y) and the reach of a flipper's swing."""
    ranges, uniform = layout.ranges, layout.uniform
    length = uniform(*ranges.flipper_length)
    rest = -uniform(*ranges.rest_angle)
    swing = uniform(*ranges.swing)
    gap = uniform(*ranges.flipper_gap)
    tip_radius = FLIPPER_TIP_RADIUS
    pivot_y = uniform(0.10, 0.14)
    pivot_x = layout.centre - (gap / 2.0 + tip_radius + length * math.cos(math.radians(rest)))
    stroke = uniform(0.022, 0.028)
    layout.flippers += [
        {"name": f"{side}_flipper", "pivot": point(x, pivot_y), "length": mm(length),
         "base_radius": FLIPPER_BASE_RADIUS, "tip_radius": tip_radius, "rest_angle": round(a, 3),
         "up_angle": round(a + sign * swing, 3), "stroke_time": round(stroke, 4),
         "return_time": 0.04, "material": "flipper", "button": side}
        for side, x, a, sign in (
            ("left", pivot_x, rest, 1.0), ("right", layout.mirror(pivot_x), 180.0 - rest, -1.0)
        )
    ]  # fmt: skip
    return pivot_x, pivot_y, length + tip_radius


def _draw_outlanes(layout: Layout, pivot_x: float, pivot_y: float) -> float:
    """Outlane guides: a wire between outlane and inlane, then an incline down to just above the
    flipper's base; a slingshot above each inlane; rollovers across the four lanes. Returns the
    slingshots' top."""
    ranges, uniform, left = layout.ranges, layout.uniform, layout.left
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
    for side, m in (("left", lambda x: x), ("right", layout.mirror)):
        layout.walls.append({"name": f"{side}_outlane_guide", "material": "metal", "points": [
            point(m(wire_x), incline_y + 0.11), point(m(wire_x), incline_y),
            point(m(end_x), end_y)]})  # fmt: skip
        body = [point(m(sling_x + sling_width), incline_y - 0.005),
                point(m(sling_x), incline_y + 0.03), point(m(sling_x), sling_top)]  # fmt: skip
        layout.walls.append({"name": f"{side}_sling_body", "points": body, "material": "rubber"})
        layout.walls.append({"name": f"{side}_slingshot", "points": [body[2], body[0]],
                             "material": "rubber", "kick": kick, "score": 10})  # fmt: skip
        guide_post = point(m(wire_x), incline_y + 0.116)
        layout.posts.append({"name": f"{side}_guide_post", "center": guide_post,
                             "radius": 0.006, "material": "rubber"})  # fmt: skip
        lanes = ((f"{side}_outlane", left, wire_x), (f"{side}_inlane", wire_x, sling_x))
        for lane, x0, x1 in lanes:
            rollover = [point(m(x0), rollover_y), point(m(x1), rollover_y)]
            layout.sensors.append({"name": lane, "points": rollover, "score": 10})
    return sling_top


def _gather_obstacles(layout: Layout, reach: float) -> None:
    """The fixed parts drawn so far as obstacles; each flipper's whole swing, roughly, as a
    disc of radius ``reach`` around its pivot."""
    obstacles = layout.obstacles
    for wall in layout.walls:
        obstacles.add_wall(wall["points"], wall.get("closed", False))
    for post in layout.posts:
        obstacles.add_circle(post["center"], post["radius"])
    for flipper in layout.flippers:
        obstacles.add_circle(flipper["pivot"], reach)


def _draw_upper_deflectors(layout: Layout, field_low: float) -> None:
    """Upper deflectors: rubber ramps off the side walls that throw a ball rolling down a wall
    (the plunger shot comes round the arch and down the left one) towards the centre instead
    of into the outlane. The left one always; the right one by chance."""
    uniform = layout.uniform
    dx, dy = uniform(0.07, 0.1), uniform(0.05, 0.08)
    y = max(uniform(0.5, 0.6) * layout.height, field_low + 0.05 + dy + uniform(0.0, 0.05))
    if y > layout.arch_y - 0.1:
        raise LayoutError("no room for the upper deflectors below the arch")
    right_too = layout.rng.random() < layout.ranges.upper_deflectors
    sides = (("left", layout.left, 1.0), ("right", layout.lane_x, -1.0))
    for side, x, sign in sides[: 1 + right_too]:
        points = [point(x, y), point(x + sign * dx, y - dy)]
        layout.place_wall({"name": f"{side}_deflector", "points": points, "material": "rubber"})


def _draw_top_lanes(layout: Layout) -> None:
    """Rollover lanes under the arch: guides hanging from just below it, a rollover in each."""
    n_lanes = int(layout.rng.choice(layout.ranges.top_lanes))
    if not n_lanes:
        return
    arch_x, arch_y = layout.arch_x, layout.arch_y
    spacing = layout.uniform(0.042, 0.05)
    guides = []
    for i in range(n_lanes + 1):
        x = arch_x + (i - n_lanes / 2.0) * spacing
        inner = layout.arch_radius - CLEARANCE - 0.002  # the arch's chords sag 0.5 mm at most
        top = arch_y + math.sqrt(inner**2 - (x - arch_x) ** 2)
        guides.append((x, top, top - 0.05))
    for i, (x, top, bottom) in enumerate(guides):
        points = [point(x, top), point(x, bottom)]
        if i in (0, n_lanes) and layout.obstacles.segment_gap((*points[0], *points[1])) < CLEARANCE:
            raise LayoutError("the top lanes do not fit under the arch")
        layout.place_wall({"name": f"lane_guide_{i}", "points": points, "material": "metal"})
    for i in range(n_lanes):
        (x0, t0, b0), (x1, t1, b1) = guides[i], guides[i + 1]
        y = (max(b0, b1) + min(t0, t1)) / 2.0
        layout.sensors.append({"name": f"top_lane_{i}", "score": 50,
                               "points": [point(x0, y), point(x1, y)]})  # fmt: skip


def _place_circle(layout: Layout, radius: float, low: float) -> list[float]:
    """A random free centre for a circle of ``radius`` above ``low``, below the arch; the circle
    is added to the obstacles."""
    left, lane_x = layout.left, layout.lane_x
    arch_x, arch_y, arch_radius = layout.arch_x, layout.arch_y, layout.arch_radius
    for _ in range(PLACE_TRIES):
        x = layout.uniform(left + radius + CLEARANCE, lane_x - radius - CLEARANCE)
        y = layout.uniform(low, arch_y + 0.6 * arch_radius)
        inside = math.hypot(x - arch_x, y - arch_y) <= arch_radius - radius - CLEARANCE
        if (y <= arch_y or inside) and layout.obstacles.circle_gap(x, y, radius) >= CLEARANCE:
            center = point(x, y)
            layout.obstacles.add_circle(center, radius)
            return center
    raise LayoutError("no free place left for a post or bumper")


def _draw_bumpers_and_posts(layout: Layout, field_low: float) -> None:
    """Pop bumpers in the upper half of the field, then small rubber posts anywhere above the
    slingshots."""
    rng, ranges, uniform = layout.rng, layout.ranges, layout.uniform
    bumper_low = max(0.45 * layout.height, field_low + 0.1)
    for i in range(rng.integers(ranges.bumpers[0], ranges.bumpers[1] + 1)):
        radius = mm(uniform(0.025, 0.032))
        center = _place_circle(layout, radius, bumper_low)
        layout.posts.append({"name": f"bumper_{i}", "center": center,
                             "radius": radius, "material": "bumper",
                             "kick": round(uniform(1.2, 1.6), 3), "score": 100})  # fmt: skip
    for i in range(rng.integers(ranges.posts[0], ranges.posts[1] + 1)):
        radius = mm(uniform(0.006, 0.01))
        center = _place_circle(layout, radius, field_low)
        layout.posts.append({"name": f"post_{i}", "center": center,
                             "radius": radius, "material": "rubber", "score": 10})  # fmt: skip


def _draw_deflectors(layout: Layout, field_low: float) -> None:
    """Short deflector walls at random free places above the slingshots, some one-way."""
    rng, ranges = layout.rng, layout.ranges
    for i in range(rng.integers(ranges.deflectors[0], ranges.deflectors[1] + 1)):
        points = _free_deflector(layout, field_low)
        one_way = bool(rng.random() < 0.25)
        layout.place_wall(
            {
                "name": f"deflector_{i}",
                "points": points,
                "material": str(rng.choice(["rubber", "metal"])),
                "one_sided": one_way,
            }
        )


def _free_deflector(layout: Layout, field_low: float) -> list[list[float]]:
    """The ends of a deflector at a random free place between ``field_low`` and the arch."""
    uniform = layout.uniform
    for _ in range(PLACE_TRIES):
        half = uniform(0.02, 0.04)
        angle = uniform(0.0, math.pi)
        x = uniform(layout.left + CLEARANCE + half, layout.lane_x - CLEARANCE - half)
        y = uniform(field_low, layout.arch_y)
        dx, dy = half * math.cos(angle), half * math.sin(angle)
        points = [point(x - dx, y - dy), point(x + dx, y + dy)]
        if layout.obstacles.segment_gap((*points[0], *points[1])) >= CLEARANCE:
            return points
    raise LayoutError("no free place left for a deflector")


def _draw_targets(
    layout: Layout,
    rng: np.random.Generator,
    field_low: float,
    aim: tuple[float, float],
) -> dict:
    """A drop bank (2-4 targets in a line, a gap between each two) and a spinner across an open
    path, each at a random free place between ``field_low`` and the arch, facing ``aim`` (the
    middle of the flippers) and clear of everything drawn (and of the ball's start) by
    ``CLEARANCE``; drawn from ``rng`` alone. Returns the description's entries they add."""
    start = layout.plunger
    count = int(rng.integers(BANK_TARGETS[0], BANK_TARGETS[1] + 1))
    length = rng.uniform(*DROP_LENGTH)
    span = count * length + (count - 1) * DROP_GAP
    centre, along = _free_line(layout, rng, span / 2.0, field_low, aim, start, "a drop bank")
    targets = []
    for i in range(count):
        offset = -span / 2.0 + i * (length + DROP_GAP)
        ends = [_along(centre, along, offset), _along(centre, along, offset + length)]
        targets.append({"name": f"drop_{i}", "points": ends, "score": DROP_SCORE})
        layout.obstacles.add_wall(ends)
    bank = {"name": "drop_bank", "material": "target", "reset_time": BANK_RESET_TIME,
            "targets": targets}  # fmt: skip
    width = rng.uniform(*SPINNER_WIDTH)
    centre, along = _free_line(layout, rng, width / 2.0, field_low, aim, start, "a spinner")
    ends = [_along(centre, along, -width / 2.0), _along(centre, along, width / 2.0)]
    layout.obstacles.add_wall(ends)
    return {
        "materials": {**MATERIALS, "target": TARGET_MATERIAL},
        "drop_targets": [bank],
        "spinners": [{"name": "spinner", "points": ends, **SPINNER}],
    }


def _along(centre: tuple[float, float], along: tuple[float, float], offset: float) -> list[float]:
    """The point ``offset`` from ``centre`` in the direction ``along``, rounded."""
    return point(centre[0] + offset * along[0], centre[1] + offset * along[1])


def _free_line(
    layout: Layout,
    rng: np.random.Generator,
    half: float,
    low: float,
    aim: tuple[float, float],
    start: list[float],
    what: str,
) -> tuple[tuple[float, float], tuple[float, float]]:
    """The centre of a line ``2 * half`` long at a random free place between ``low`` and the
    arch, and its direction: square to the way to ``aim``, so that it faces it."""
    left, lane_x = layout.left, layout.lane_x
    arch_x, arch_y, arch_radius = layout.arch_x, layout.arch_y, layout.arch_radius
    for _ in range(PLACE_TRIES):
        x = rng.uniform(left + CLEARANCE + half, lane_x - CLEARANCE - half)
        y = rng.uniform(low, arch_y + 0.6 * arch_radius)
        if y > arch_y and math.hypot(x - arch_x, y - arch_y) > arch_radius - CLEARANCE:
            continue
        to_aim = math.hypot(aim[0] - x, aim[1] - y)
        along = ((aim[1] - y) / to_aim, (x - aim[0]) / to_aim)
        ends = (*_along((x, y), along, -half), *_along((x, y), along, half))
        clear = layout.obstacles.segment_gap(ends) >= CLEARANCE
        if clear and point_segment_distance(*start, *ends) >= BALL_RADIUS + CLEARANCE:
            return (x, y), along
    raise LayoutError(f"no free place left for {what}")


def _description(layout: Layout, name: str, slope: float) -> dict:
    """The table description of the drawn elements, with the ball and the plunger: launch
    speeds scaled from the classic table's by the climb to the top."""
    climb = math.sqrt(layout.height * math.sin(math.radians(slope)))
    scale = climb / math.sqrt(1.07 * math.sin(math.radians(6.5)))
    plunger = layout.plunger
    return {
        "name": name,
        "playfield": {"width": layout.width, "height": layout.height},
        "slope_deg": round(slope, 3),
        "gravity": 9.81,
        "ball": {"radius": BALL_RADIUS, "mass": 0.08, "start": plunger, "velocity": [0.0, 0.0]},
        "materials": MATERIALS,
        "walls": layout.walls,
        "posts": layout.posts,
        "flippers": layout.flippers,
        "sensors": layout.sensors,
        "plunger": {"position": plunger, "speed": [round(2.2 * scale, 3), round(3.2 * scale, 3)]},
    }
