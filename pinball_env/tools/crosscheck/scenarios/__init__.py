"""The cross-check's scenarios and tolerances: the same shots on our swept kernel and on pymunk
(the same validated table object, built by ``pinball_env.sim.backends.make_world``), each row
with both engines' results against the analytic answer, and the checks of a row against the
tolerances. The tests take them as their oracle; :mod:`.cli` runs them all into a report.

The package's modules: :mod:`.shots` (the scenario table, a shot on each engine, its comparison
with the analytic answer, the tolerances), :mod:`.contacts` (walls, posts, flippers, the free run,
tunnelling), :mod:`.cabinet` (nudges, the plunger), :mod:`.targets` (drop targets, spinners) and
:mod:`.balls` (several balls); every name is here too, where the tests and the command line
take them.

Scenarios: single-wall bounces over a grid of angles and speeds; segment-end (corner) hits;
post hits; a ball falling on a resting flipper; a swinging flipper hit; a free run on the classic
table; and a tunnelling sweep (pass-through fraction against speed, for a thin wall, a resting
flipper and a swinging flipper). The cabinet (classic_v1's): bumper hits on a tilted machine;
nudges on a ball in free flight, and on one resting on or rolling along a wall or lying in a
flipper's cradle; plunger launches up the shooter lane. Several balls (a trough of two): ball-ball
shots (head-on, onto a resting ball, oblique at 45 degrees; restitution 1 and 0.5) and two balls
cradled together on a raised flipper. Needs pymunk (the ``crosscheck`` extra).

Tolerances, fixed from how the engines work (not tuned to the results):

- contact time: ours is exact up to float rounding; pymunk finds an overlap at the end of the
  substep in which it happens, so its contact time is late by up to one substep (1/600 s);
- velocities after a bounce: both apply v_n' = -e v_n and Coulomb friction to the same contact,
  so they agree to 1% of the incoming speed plus 1 mm/s where pymunk sees the contact before the
  ball has moved more than its slop into the wall, i.e. at low speed (<= 4 m/s: under half a ball
  radius per substep);
- a ball falling from rest: Chipmunk integrates positions before velocities, which under a
  constant force is the same path one substep later, so its landing may be up to two substeps
  late (DROP_TIME_TOLERANCE);
- flipper contacts: pymunk's kinematic flipper turns at the kernel's angular velocity, but it
  resolves the contact after the flipper has already swept into the ball, one substep late at
  worst; the hit speeds agree to 10% (a substep of a 40 rad/s flipper is 0.07 rad);
- free run: the trajectories are chaotic (every bounce off a curved post amplifies a difference),
  so they are compared by how long they stay within 1 mm and 1 cm of each other, not by a bound;
- the cabinet is the kernel's own function on both engines, so it moves bitwise the same; a ball
  in free flight adds its velocity change, opposite, in the same substeps: both agree with it to
  rounding (ROUNDING). A nudge along a wall: both apply the same Coulomb friction with the normal
  impulse of the substep's gravity, so they agree to rounding. A nudge into a surface differs by
  design (see :func:`nudge_contact`): by ``e (J/M + g h)`` on a wall exactly, and in a cradle by
  at most its largest restitution times that approach, plus what the settling left;
- plunger launches: each engine's path is the analytic parabola of launch speed ``v -/+ g h / 2``
  (the integration order), so the apex is within half a substep's travel at the launch speed,
  ``v h / 2`` (plus ``g h^2 / 8``), of the analytic one, the engines ``v h`` apart; the time to
  the gate within half a substep, h / 2 (the paths are ``g h t / 2`` off, which the ball covers in
  under h / 2 while it is faster than the speed it has lost);
- ball-ball shots (:func:`pair_tolerance`): ours is exact (the swept time of impact of two
  moving circles, then the equal-mass impulse); pymunk resolves the pair up to a substep late,
  after the balls have moved into each other, so its line of centres is turned by up to
  ``atan(w h sin(angle) / 2r)`` and the exchanged velocity with it, and the contact its paths
  imply is late by up to ``h (1 + 1 / e)`` (the delay, then the overlap its slow position
  correction leaves, closed at ``e`` times the speed); head-on, it agrees to the wall bounces'
  tolerance. Two cradled balls: at rest touching, ours a skin apart at most and never closer
  than 2r, pymunk's overlapping by up to its slop.
"""

from pinball_env.tools.crosscheck.scenarios.balls import (
    PAIR_RESTITUTIONS,
    PAIR_SHOTS,
    PAIR_SPEEDS,
    PAIR_TIME,
    ball_ball_hits,
    pair_agrees,
    pair_expected,
    pair_tolerance,
    two_balls_cradled,
    with_balls,
)
from pinball_env.tools.crosscheck.scenarios.cabinet import (
    NUDGE_SITUATIONS,
    nudge,
    nudge_agrees,
    nudge_contact,
    nudge_free_flight,
    plunger_agrees,
    plunger_launches,
)
from pinball_env.tools.crosscheck.scenarios.contacts import (
    corner_hits,
    flipper_drop,
    flipper_swing,
    free_run,
    post_hits,
    tunnelling,
    wall_bounces,
)
from pinball_env.tools.crosscheck.scenarios.shots import (
    CABINET_TABLE,
    DROP_TIME_TOLERANCE,
    ENGINES,
    FLIPPER,
    FLIPPER_SPEED_TOLERANCE,
    FRAME_RATE,
    HIT_TIME,
    LEFT_BUTTON,
    LOW_SPEED,
    RADIUS,
    ROUNDING,
    SUBSTEP,
    SUBSTEPS,
    TIME_TOLERANCE,
    VELOCITY_TOLERANCE,
    Shot,
    agrees,
    classic_left_flipper,
    compare,
    reflect,
    scenario_table,
    shoot,
)
from pinball_env.tools.crosscheck.scenarios.targets import spinner_turns, target_hits

__all__ = [
    "CABINET_TABLE",
    "DROP_TIME_TOLERANCE",
    "ENGINES",
    "FLIPPER",
    "FLIPPER_SPEED_TOLERANCE",
    "FRAME_RATE",
    "HIT_TIME",
    "LEFT_BUTTON",
    "LOW_SPEED",
    "NUDGE_SITUATIONS",
    "PAIR_RESTITUTIONS",
    "PAIR_SHOTS",
    "PAIR_SPEEDS",
    "PAIR_TIME",
    "RADIUS",
    "ROUNDING",
    "SUBSTEP",
    "SUBSTEPS",
    "TIME_TOLERANCE",
    "VELOCITY_TOLERANCE",
    "Shot",
    "agrees",
    "ball_ball_hits",
    "classic_left_flipper",
    "compare",
    "corner_hits",
    "flipper_drop",
    "flipper_swing",
    "free_run",
    "nudge",
    "nudge_agrees",
    "nudge_contact",
    "nudge_free_flight",
    "pair_agrees",
    "pair_expected",
    "pair_tolerance",
    "plunger_agrees",
    "plunger_launches",
    "post_hits",
    "reflect",
    "scenario_table",
    "shoot",
    "spinner_turns",
    "target_hits",
    "tunnelling",
    "two_balls_cradled",
    "wall_bounces",
    "with_balls",
]
