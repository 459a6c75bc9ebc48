"""Ball-ball contact: the swept test between two moving balls and the impulsive response.

The first brick of multiball: scalar kernels in the style of ``sweep.py``, not yet
called by the world step.

Sweep. Two balls whose centres move from ``a`` to ``a + da`` and from ``b`` to ``b + db`` over
one sweep, ``A(t) = a + da t`` and ``B(t) = b + db t`` with ``t`` in [0, 1], touch when
``|A(t) - B(t)| = reach`` (the sum of their radii). In their relative motion
``M(t) = (a - b) + (da - db) t`` this is the lecture's problem (CS230 lecture 17b) for a point
against a circle of radius ``reach`` at rest at the origin, which ``sweep.sweep_point`` solves:
the smaller root of ``|m + d t|^2 = reach^2``, with the same start-overlap rule as every sweep.

Response. Two balls of equal mass (solid spheres, I = 2/5 m r^2, of equal radius ``r``) meet
along the unit normal n from b to a. With ``wa``, ``wb`` their inverse masses in units of 1/m
(1, or 0 for a ball held fixed in a lock or saucer), the normal impulse per unit mass is
``jn = -(1 + e) vn / (wa + wb)`` on the relative normal velocity ``vn = (va - vb).n < 0``; a
gets ``+wa jn n`` and b ``-wb jn n``, so momentum is conserved (when neither is fixed) and the
relative normal velocity after is ``-e vn``. Friction mirrors ``contact.respond``: a Coulomb
impulse, at most ``friction jn``, that drives the slip of the contact points towards zero.
"""

from numba import njit

from pinball_env.physics.contact import ROLLING_SHARE
from pinball_env.physics.sweep import sweep_point


@njit(cache=True)
def sweep_ball_ball(ax, ay, adx, ady, bx, by, bdx, bdy, reach):
    """First contact of two balls whose centres move from a by ad and from b by bd.

    ``reach`` is the sum of their radii. Returns ``(t, nx, ny)``: ``t`` in [0, 1] the fraction
    of the sweep at first contact and n the unit normal from b's centre towards a's at that
    moment; ``t = inf`` (n zero) when they do not touch during the sweep.

    In the relative motion, ``m = a - b`` moving by ``d = ad - bd``, it is the ray ``m + d t``
    against a circle of radius ``reach`` around the origin: ``sweep.sweep_point``, the smaller
    root of ``(d.d) t^2 + 2 (m.d) t + (m.m - reach^2) = 0``. Cases, as there:

    - Start overlap (``|m| <= reach``): a contact at t = 0 with n = m / |m| where the balls
      approach (``m.d < 0``), none where they separate or keep their distance (``m.d >= 0``).
    - Coincident centres (``m.m = 0`` in floating point, so also centres closer than about
      1e-154, whose squares underflow): n = -d / |d|, against the relative motion of a, so the
      response pushes them apart the way they came; no contact without relative motion.
    - No relative motion (``d = 0``): no contact, overlapping or not (their distance never
      shrinks; an overlap left over is for the world step to settle).

    Swapping a and b gives bitwise the same t and the opposite normal: the relative position
    and motion only change sign, which is exact in floating point.
    """
    # m = a - b is formed inside sweep_point (as c - p), d here.
    return sweep_point(ax, ay, adx - bdx, ady - bdy, reach, bx, by)


@njit(cache=True)
def respond_ball_ball(avx, avy, aspin, bvx, bvy, bspin, nx, ny, r, restitution, friction,
                      a_fixed, b_fixed):  # fmt: skip
    """Velocities and spins of two equal balls (radius ``r``) after a contact along the unit
    normal n from b to a, with ``restitution`` and ``friction`` (Coulomb) of the pair.

    A ball held fixed (``a_fixed``, ``b_fixed``: in a lock or saucer) is of infinite mass: it
    keeps its velocity and spin, and the other bounces off it as off a post moving with it
    (bitwise ``contact.respond`` against a surface at rest, for a fixed ball at rest). Returns
    ``(avx, avy, aspin, bvx, bvy, bspin)``; unchanged where the balls do not approach along n
    (``(va - vb).n >= 0``) or both are fixed.

    Normal: ``jn = -(1 + e) vn / (wa + wb)`` per unit mass (module docstring). Tangent
    ``t = rot+90(n)``: the contact point, at ``-r n`` from a and ``+r n`` from b, slips at
    ``s = (va - vb).t - r (spin_a + spin_b)`` (spin counter-clockwise). A tangential impulse
    ``jt`` (``-jt t`` on a, ``+jt t`` on b, per unit mass) turns each free ball by
    ``2.5 jt / r`` (torque r jt, I = 2/5 m r^2) and so changes the slip by
    ``-3.5 (wa + wb) jt``: ``jt = min(2/7 |s| / (wa + wb), friction jn)`` with the sign of s
    stops the slip or removes what Coulomb allows. The impulses are equal and opposite at one
    point, so linear and angular momentum are conserved when neither ball is fixed, and
    friction never adds energy.
    """
    wa = 0.0 if a_fixed else 1.0
    wb = 0.0 if b_fixed else 1.0
    w = wa + wb
    rvx = avx - bvx
    rvy = avy - bvy
    vn = rvx * nx + rvy * ny
    if vn >= 0.0 or w == 0.0:
        return avx, avy, aspin, bvx, bvy, bspin
    jn = -(1.0 + restitution) * vn / w  # normal impulse per unit mass
    # The same order of operations as contact.respond, so that a ball against a fixed ball at rest
    # is bitwise a ball against a post (multiplying by w, wa or wb = 1 is exact).
    avx += wa * jn * nx
    avy += wa * jn * ny
    bvx -= wb * jn * nx
    bvy -= wb * jn * ny
    tx = -ny
    ty = nx
    slip = rvx * tx + rvy * ty - r * (aspin + bspin)
    jt = min(ROLLING_SHARE * abs(slip) / w, friction * jn)
    if slip < 0.0:
        jt = -jt
    avx -= wa * jt * tx
    avy -= wa * jt * ty
    bvx += wb * jt * tx
    bvy += wb * jt * ty
    aspin += wa * 2.5 * jt / r
    bspin += wb * 2.5 * jt / r
    return avx, avy, aspin, bvx, bvy, bspin
