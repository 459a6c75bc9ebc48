"""Pure numerical kernels (numba): swept collision and the batched world step.

Nothing here imports from Gymnasium, YAML or rendering code; everything works on floats and
arrays, and runs as plain Python with ``NUMBA_DISABLE_JIT=1``.
"""

from pinball_env.physics.sweep import (
    sweep_circle,
    sweep_circle_circle,
    sweep_circle_segment,
    sweep_point,
    sweep_segment,
)
from pinball_env.physics.world import earliest_contact, respond, step_balls

__all__ = [
    "earliest_contact",
    "respond",
    "step_balls",
    "sweep_circle",
    "sweep_circle_circle",
    "sweep_circle_segment",
    "sweep_point",
    "sweep_segment",
]
