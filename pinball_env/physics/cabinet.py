"""The cabinet and its plumb bob: what a nudge does to the table, and what tilts it.

The cabinet stands on its legs like a mass on a spring with a damper (Visual Pinball X models the
table the same way, ``u'' = -k u - c u'``, in ``PhysicsEngine``): a nudge is an impulse ``J`` on
the cabinet's mass ``M``, after which the legs pull it back, ``M a = -k u - c u'``. The walls,
posts and flippers move with the cabinet, so the kernel simulates the ball *relative to the
cabinet*: there the ball feels the cabinet's acceleration, opposite, beside gravity (a frame
force), and is swept exactly as before; nothing about a nudge can push it through a surface.

The plumb bob is a pendulum of length ``L`` hanging in the cabinet (VPX's ``PlumbHandler``), its
angle from vertical a small 2-vector ``theta`` (towards +x and +y) driven by the cabinet's
acceleration: ``theta'' = -(g / L) theta - d theta' - a / L``. Around it hangs the tilt ring: a
bob that swings out to the ring's angle touches it (one touch counted, however long it stays
there, until it swings clear again) and bounces back off it with the ring's restitution.

Both advance with the kernel's substeps by semi-implicit Euler, the integrator of the ball, so
that a ball in free flight changes velocity by exactly the cabinet's change, opposite.
"""

import math

from numba import njit

from pinball_env.physics.columns import (
    BOB_DAMPING,
    BOB_GRAVITY,
    BOB_LENGTH,
    BOB_ON_RING,
    BOB_RESTITUTION,
    BOB_RING,
    BOB_TOUCHES,
    BOB_VX,
    BOB_VY,
    BOB_X,
    BOB_Y,
    CABINET_DAMPING,
    CABINET_MASS,
    CABINET_SHOVE_X,
    CABINET_SHOVE_Y,
    CABINET_STIFFNESS,
    CABINET_VX,
    CABINET_VY,
    CABINET_X,
    CABINET_Y,
)

# A bob that has touched the ring counts as clear of it (ready to count the next touch) once it
# is back inside this fraction of the ring's angle: a bob resting against the ring under a steady
# push is one touch, not one per substep.
RING_CLEAR = 0.9


@njit(cache=True)
def cabinet_frame(cabinet, constants, h, velocity_changes):
    """Advance one env's cabinet and plumb bob by a frame of ``len(velocity_changes)``
    substeps ``h`` (:func:`cabinet_substep` each), the cabinet's velocity change in each into
    ``velocity_changes`` (substeps, 2). The cabinet moves whatever the ball does, so the kernel
    integrates its frame before the ball's substeps (a call inside their loop, even one not
    taken, slowed every ball-frame by a tenth)."""
    cabinet[BOB_TOUCHES] = 0.0
    for k in range(velocity_changes.shape[0]):
        velocity_changes[k, 0], velocity_changes[k, 1] = cabinet_substep(cabinet, constants, h)


@njit(cache=True)
def cabinet_substep(cabinet, constants, h):
    """Advance one env's cabinet and plumb bob (``cabinet``, a row of the state's cabinet
    array, in place) by a substep ``h`` [s], applying and clearing the pending shove.

    Returns ``(dvx, dvy)``, the cabinet's velocity change over the substep [m/s]: a ball that
    moves with no contact changes velocity relative to the cabinet by exactly ``-dv`` (beside
    gravity)."""
    mass = constants[CABINET_MASS]
    stiffness = constants[CABINET_STIFFNESS]
    damping = constants[CABINET_DAMPING]
    dvx = (cabinet[CABINET_SHOVE_X] - (stiffness * cabinet[CABINET_X]
                                       + damping * cabinet[CABINET_VX]) * h) / mass  # fmt: skip
    dvy = (cabinet[CABINET_SHOVE_Y] - (stiffness * cabinet[CABINET_Y]
                                       + damping * cabinet[CABINET_VY]) * h) / mass  # fmt: skip
    cabinet[CABINET_SHOVE_X] = 0.0
    cabinet[CABINET_SHOVE_Y] = 0.0
    cabinet[CABINET_VX] += dvx
    cabinet[CABINET_VY] += dvy
    cabinet[CABINET_X] += cabinet[CABINET_VX] * h
    cabinet[CABINET_Y] += cabinet[CABINET_VY] * h
    swing_bob(cabinet, constants, dvx / h, dvy / h, h)
    return dvx, dvy


@njit(cache=True)
def swing_bob(cabinet, constants, ax, ay, h):
    """Advance the plumb bob by ``h`` while the cabinet accelerates at (ax, ay) [m/s^2]; count a
    touch of the ring in ``cabinet[BOB_TOUCHES]`` and bounce the bob off it."""
    length = constants[BOB_LENGTH]
    stiffness = constants[BOB_GRAVITY] / length
    damping = constants[BOB_DAMPING]
    ring = constants[BOB_RING]
    cabinet[BOB_VX] += (-stiffness * cabinet[BOB_X] - damping * cabinet[BOB_VX] - ax / length) * h
    cabinet[BOB_VY] += (-stiffness * cabinet[BOB_Y] - damping * cabinet[BOB_VY] - ay / length) * h
    cabinet[BOB_X] += cabinet[BOB_VX] * h
    cabinet[BOB_Y] += cabinet[BOB_VY] * h
    # Well inside the clear angle (as the squares tell, with a margin for rounding), the bob
    # is off the ring: no need of hypot's exact angle, which is slow.
    clear = RING_CLEAR * ring * (1.0 - 1e-9)
    if cabinet[BOB_X] * cabinet[BOB_X] + cabinet[BOB_Y] * cabinet[BOB_Y] < clear * clear:
        cabinet[BOB_ON_RING] = 0.0
        return
    angle = math.hypot(cabinet[BOB_X], cabinet[BOB_Y])
    if angle >= ring:
        # The ring stops the bob at its angle: back onto it, the outward swing reflected.
        nx = cabinet[BOB_X] / angle
        ny = cabinet[BOB_Y] / angle
        cabinet[BOB_X] = nx * ring
        cabinet[BOB_Y] = ny * ring
        outward = cabinet[BOB_VX] * nx + cabinet[BOB_VY] * ny
        if outward > 0.0:
            bounce = (1.0 + constants[BOB_RESTITUTION]) * outward
            cabinet[BOB_VX] -= bounce * nx
            cabinet[BOB_VY] -= bounce * ny
        if cabinet[BOB_ON_RING] == 0.0:
            cabinet[BOB_TOUCHES] += 1.0
            cabinet[BOB_ON_RING] = 1.0
    elif angle < RING_CLEAR * ring:
        cabinet[BOB_ON_RING] = 0.0
