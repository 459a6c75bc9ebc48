"""Pure numerical kernels (numba): swept collision and the batched world step.

Nothing here imports from Gymnasium, YAML or rendering code; everything works on floats and
arrays, and runs as plain Python with ``NUMBA_DISABLE_JIT=1``.
"""

from pinball_env.physics.flipper import capsule_distance, sweep_capsule, sweep_flipper
from pinball_env.physics.sweep import (
    sweep_circle,
    sweep_circle_circle,
    sweep_circle_segment,
    sweep_point,
    sweep_segment,
)
from pinball_env.physics.world import Geometry, Settings, State, respond, step_world

__all__ = [
    "Geometry",
    "Settings",
    "State",
    "capsule_distance",
    "respond",
    "step_world",
    "sweep_capsule",
    "sweep_circle",
    "sweep_circle_circle",
    "sweep_circle_segment",
    "sweep_flipper",
    "sweep_point",
    "sweep_segment",
]
