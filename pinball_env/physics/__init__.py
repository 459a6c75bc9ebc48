"""Pure numerical kernels (numba): swept collision and the batched world step.

Nothing here imports from Gymnasium, YAML, rendering code or the rest of the package; everything
works on floats and arrays, and runs as plain Python with ``NUMBA_DISABLE_JIT=1``.

- ``sweep.py``: swept ball-segment and ball-circle tests, point-segment distance;
- ``flipper.py``: swept contact with a rotating flipper (a kinematic tapered capsule);
- ``balls.py``: ball-ball contact, the swept test of two moving balls and the impulsive response;
- ``multiball.py``: the frame step of several ball slots per env with ball-ball contact in one
  event loop (``step_balls``, ``step_multiworld``), and a helper to build and step such a world
  (``make_multiball``); the kernel of tables of several balls, saucers or locks (chosen once,
  when the World is built);
- ``step.py``: the world step over a batch of envs, split into named helpers;
- ``near.py``: the broad phase, each ball's candidate set of the elements it can reach soon;
- ``rays.py``: ray casts from the ball against walls, posts and flippers (the observation's rays);
- ``cabinet.py``: the cabinet (a mass-spring-damper that a nudge shoves) and its plumb bob;
- ``targets.py``: drop targets, spinners and kickbacks, and every crossing (sensors, the drain,
  spinner and kickback lines, the drop targets' sweep);
- ``data.py``: the kernel's data (``Geometry``, ``Settings``, ``State``: the ball slots,
  (N, M) per env, and the rest of the env's state; ``Scratch``) and their constructors
  ``make_state`` and ``make_scratch``;
- ``columns.py``: what each column of those arrays means.
"""

from pinball_env.physics.balls import respond_ball_ball, sweep_ball_ball
from pinball_env.physics.contact import deepest_overlap, respond
from pinball_env.physics.data import (
    CONTACT_CAPACITY,
    Geometry,
    Scratch,
    Settings,
    State,
    element_count,
    first_circle,
    first_flipper,
    first_sensor,
    make_scratch,
    make_state,
    segment_bounds,
)
from pinball_env.physics.flipper import (
    capsule_distance,
    capsule_face_normal,
    flipper_distance,
    flipper_reach,
    sweep_capsule,
    sweep_flipper,
)
from pinball_env.physics.step import step_tables, step_world
from pinball_env.physics.sweep import (
    point_segment_distance,
    sweep_circle,
    sweep_circle_circle,
    sweep_circle_segment,
    sweep_point,
    sweep_segment,
)

__all__ = [
    "CONTACT_CAPACITY",
    "Geometry",
    "Scratch",
    "Settings",
    "State",
    "capsule_distance",
    "capsule_face_normal",
    "deepest_overlap",
    "element_count",
    "first_circle",
    "first_flipper",
    "first_sensor",
    "flipper_distance",
    "flipper_reach",
    "make_scratch",
    "make_state",
    "point_segment_distance",
    "respond",
    "respond_ball_ball",
    "segment_bounds",
    "step_tables",
    "step_world",
    "sweep_ball_ball",
    "sweep_capsule",
    "sweep_circle",
    "sweep_circle_circle",
    "sweep_circle_segment",
    "sweep_flipper",
    "sweep_point",
    "sweep_segment",
]
