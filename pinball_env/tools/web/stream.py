"""What the page draws from: a table's geometry, sent once, and each frame's state, streamed.

The page draws the game itself on a canvas (``static/app.js``), as ``pinball_env.render`` draws a
frame: the static layer (walls, posts, sensors, targets' lines, saucers, locks) from
:func:`geometry`, then each frame's moving parts from :func:`frame_state`. Both are plain JSON
objects; lengths are in metres in the table frame (x right, y up the table), angles in radians.

A frame's state (one game's; a message carries a list of them, one per game shown)::

    {"frame": 812, "score": 1230, "balls_left": 2,
     "balls": [[0.3121, 0.5502]],         // ball centres [m]: the ball, then any more in play
     "flippers": [-0.4363, 0.4363],       // angles [rad], one per table.flippers entry
     "over": false,
     // a table with the cabinet:
     "pull": 0.0, "on_plunger": true,     // the plunger's pull [m]; the ball waiting on it
     "offset": [0.0, 0.0],                // the cabinet's offset [m] (drawn SHAKE_EXAGGERATION x)
     "warnings": 0, "tilted": false,
     // a table with targets or rules (one entry per element of the geometry's lists):
     "targets": [1, 1, 0], "spinners": [0.0], "kickbacks": [1], "lights": [0, 1],
     // a table with rules: "bonus", "multiplier"; with several balls: "trough"
    }

Positions are rounded to 10 micrometres and angles to 1e-4 rad (0.006 px and 0.007 px at the
render scale): a message stays a few hundred bytes.
"""

from typing import Any

import numpy as np

from pinball_env.envs import PinballEnv
from pinball_env.observation import targets_view
from pinball_env.render import colours
from pinball_env.render.raster import (
    LAMP_RADIUS,
    PIXELS_PER_METRE,
    PLUNGER_ROD_HALF_WIDTH,
    PLUNGER_TIP_FLOOR,
    PLUNGER_TIP_HALF_WIDTH,
    PLUNGER_TIP_REACH,
    SENSOR_HALF_WIDTH,
    SHAKE_EXAGGERATION,
    TARGET_HALF_WIDTH,
    WALL_HALF_WIDTH,
)
from pinball_env.table import Table
from pinball_env.table.kinds import Disc, Line, static_shapes

POSITION_DIGITS = 5  # [m] to 10 micrometres
ANGLE_DIGITS = 4  # [rad]

# The browser's names (KeyboardEvent.code) of the pygame keys the play tool declares
# (PinballEnv.FLIPPER_KEYS, CABINET_KEYS and the play tool's COMMAND_KEYS).
BROWSER_KEYS = {
    "K_LSHIFT": "ShiftLeft", "K_RSHIFT": "ShiftRight", "K_z": "KeyZ", "K_m": "KeyM",
    "K_LEFT": "ArrowLeft", "K_RIGHT": "ArrowRight", "K_DOWN": "ArrowDown", "K_RETURN": "Enter",
    "K_x": "KeyX", "K_n": "KeyN", "K_UP": "ArrowUp", "K_b": "KeyB", "K_p": "KeyP",
    "K_SPACE": "Space", "K_r": "KeyR", "K_ESCAPE": "Escape", "K_q": "KeyQ",
}  # fmt: skip
# The play tool's commands a page sends; "quit" is the page's to close.
PAGE_COMMANDS = ("pause", "restart")


def page_keys(button_names: tuple[str, ...], command_keys: dict[str, str]) -> dict[str, str]:
    """The page's key map, browser key -> button name (``button_names``: the game's buttons) or
    command (of ``command_keys``, the play tool's pygame key -> command), from the play tool's
    declarations."""
    declared = {**PinballEnv.FLIPPER_KEYS, **PinballEnv.CABINET_KEYS}
    keys = {BROWSER_KEYS[key]: button for button in button_names for key in declared[button]}
    for key, command in command_keys.items():
        if command in PAGE_COMMANDS:
            keys[BROWSER_KEYS[key]] = command
    return keys


def geometry(table: Table, pull_scale: float = 1.0) -> dict[str, Any]:
    """The table as the page draws it (sent once): its size, its static lines and discs with
    their kinds, the elements whose state is streamed (drop targets, spinners, kickbacks,
    lights, in the order of :func:`frame_state`'s lists), the flippers, the player's plunger
    (``pull_scale``: the renderer's scale of its drawn pull, ``Renderer.pull_scale``), and the
    colours and widths of ``pinball_env.render``."""
    shapes = list(static_shapes(table))  # as the renderer's static layer, in its order
    lines = [[*shape.segment, shape.style] for shape in shapes if isinstance(shape, Line)]
    discs = [
        [*shape.center, shape.radius, shape.style] for shape in shapes if isinstance(shape, Disc)
    ]
    lamps = [list(kickback.lamp) for kickback in table.kickbacks]
    if table.rules is not None:
        lamps += [list(light.at) for light in table.rules.lights]
    plunger = None
    if table.plunger is not None and table.plunger.manual:
        plunger = {
            "x": table.plunger.position[0], "y": table.plunger.position[1],
            "stroke": table.plunger.stroke, "pull_scale": pull_scale,
            "rod": PLUNGER_ROD_HALF_WIDTH, "bar": PLUNGER_TIP_HALF_WIDTH,
            "reach": PLUNGER_TIP_REACH * table.ball.radius, "floor": PLUNGER_TIP_FLOOR,
        }  # fmt: skip
    return {
        "name": table.name,
        "width": table.width,
        "height": table.height,
        "ball_radius": table.ball.radius,
        "lines": _rounded(lines),
        "discs": _rounded(discs),
        "drop_targets": _rounded([list(t.segment) for t in table.drop_target_list]),
        "spinners": _rounded([[*s.segment, s.radius] for s in table.spinners]),
        "lamps": _rounded(lamps),  # the kickbacks' lamps, then the rules' lights
        "kickbacks": len(table.kickbacks),
        "flippers": _rounded(
            [[*f.pivot, f.length, f.base_radius, f.tip_radius] for f in table.flippers]
        ),
        "plunger": plunger,
        "cabinet": table.has_cabinet,
        "rules": table.rules is not None,
        "multiball": table.n_balls > 1,
        "pixels_per_metre": PIXELS_PER_METRE,
        "shake": SHAKE_EXAGGERATION,
        "half_widths": {
            "wall": WALL_HALF_WIDTH,
            "sensor": SENSOR_HALF_WIDTH,
            "target": TARGET_HALF_WIDTH,
            "lamp": LAMP_RADIUS,
        },
        "colours": {
            name.lower(): list(value)
            for name, value in vars(colours).items()
            if name.isupper() and isinstance(value, tuple) and len(value) == 3
        },
    }


def frame_state(env: PinballEnv, over: bool = False) -> dict[str, Any]:
    """The state of ``env``'s game now (see the module doc): what ``PinballCore.frame`` draws,
    as numbers. ``over``: the game has ended (the page says so)."""
    game = env.game
    world = game.world
    table = world.table_of(0)
    balls = [game.state.game_ball[0, :2]]
    if game.multi is not None:  # every other ball on the table, as the frame draws them (the
        # game's ball is a copy of one of them, or stands for one queued in the lane)
        balls += [ball for ball in world.balls[0, world.active[0], :2]
                  if not np.array_equal(ball, balls[0])]  # fmt: skip
    info = game.info(0)
    state: dict[str, Any] = {
        "frame": int(info["frames"]),
        "score": int(game.score[0]),
        "balls_left": int(game.balls_left[0]),
        "balls": [_round(ball, POSITION_DIGITS) for ball in balls],
        "flippers": _round(world.state.flipper_angle[0], ANGLE_DIGITS),
        "over": bool(over),
    }
    if game.cabinet:
        state.update(
            pull=round(float(info["plunger_pull"]), POSITION_DIGITS),
            on_plunger=bool(info["ball_on_plunger"]),
            offset=_round(info["cabinet_offset"], POSITION_DIGITS),
            warnings=int(info["tilt_warnings"]),
            tilted=bool(info["tilted"]),
        )
    targets = targets_view(game, slice(0, 1), table)
    if targets is not None:
        state.update(
            targets=targets.targets_up[0].astype(int).tolist(),
            spinners=_round(targets.spinner_angles[0], ANGLE_DIGITS),
            kickbacks=targets.kickback_lit[0].astype(int).tolist(),
            lights=targets.lights[0].astype(int).tolist(),
        )
    if table.rules is not None:
        state.update(bonus=int(game.state.bonus[0]), multiplier=int(game.state.multiplier[0]))
    if game.multi is not None:
        state["trough"] = int(game.multi.in_trough(0).sum())
    return state


def _round(values: Any, digits: int) -> list[float]:
    return [round(float(v), digits) for v in np.asarray(values).ravel()]


def _rounded(rows: list[list[Any]]) -> list[list[Any]]:
    return [
        [round(float(v), POSITION_DIGITS) if not isinstance(v, str) else v for v in row]
        for row in rows
    ]
