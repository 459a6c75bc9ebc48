"""Column meaning of the arrays the kernels share with the layers above.

Kept in one place so that the table packer, the kernels and the environment agree on what each
column means. Units are SI throughout: metres, seconds, radians.
"""

# Ball state, array of shape (n_envs, n_balls, BALL_STATE_SIZE), float64: a row per ball slot.
BALL_X = 0  # centre x [m], to the right
BALL_Y = 1  # centre y [m], up the playfield (towards the top of the table)
BALL_VX = 2  # velocity x [m/s]
BALL_VY = 3  # velocity y [m/s]
BALL_SPIN = 4  # angular velocity about the playfield normal [rad/s], counter-clockwise positive
BALL_STATE_SIZE = 5

# Surface properties of every element (segments, circles), array of shape (n, PROP_SIZE).
PROP_RESTITUTION = 0  # coefficient of restitution of the normal velocity [-]
PROP_FRICTION = 1  # Coulomb friction coefficient ball/surface [-]
PROP_KICK = 2  # speed added along the contact normal on every impact [m/s] (bumpers, slingshots)
PROP_SIZE = 3

# Segment geometry, array of shape (n_segments, 4): x0, y0, x1, y1 [m].
# Segment bounds (walls, drop targets), array of shape (n_segments, BOUND_SIZE), float64: what
# the sweeps' cheap tests read (``data.segment_bounds``).
BOUND_X = 0  # centre of the bounding circle [m]
BOUND_Y = 1
BOUND_RADIUS = 2  # its radius: half the length [m]
BOUND_NX = 3  # unit normal of the segment's line, rot+90(P1 - P0) (zero for a point)
BOUND_NY = 4
BOUND_OFFSET = 5  # the line's offset along it: n . P0 [m]
BOUND_SIZE = 6
# Circle geometry, array of shape (n_circles, 3): x, y, radius [m].
# Sensor geometry (rollovers, drain), array of shape (n_sensors, 4): x0, y0, x1, y1 [m]. The
# ball passes over sensors; a crossing of its centre is an event. Drains take the ball out of play.

# Flippers, array of shape (n_flippers, FLIPPER_SIZE), float64. A flipper is a tapered capsule: a
# base circle around the pivot and a tip circle ``length`` away along the flipper's angle, joined
# by their common tangents. Angles are counter-clockwise from +x [rad].
FLIPPER_PIVOT_X = 0  # [m]
FLIPPER_PIVOT_Y = 1  # [m]
FLIPPER_LENGTH = 2  # pivot to tip-circle centre [m]
FLIPPER_BASE_RADIUS = 3  # [m]
FLIPPER_TIP_RADIUS = 4  # [m]
FLIPPER_REST_ANGLE = 5  # angle when released, against the lower stop [rad]
FLIPPER_UP_ANGLE = 6  # angle when energised, against the upper stop [rad]
FLIPPER_UP_SPEED = 7  # angular speed of the upstroke [rad/s] (> 0)
FLIPPER_DOWN_SPEED = 8  # angular speed of the return [rad/s] (> 0)
FLIPPER_SIZE = 9

# Targets and their kin (tables with them; each array has 0 rows on a table without), after the
# sensors in the element ids: drop targets, spinners, kickbacks (see ``physics.targets``).
# Drop targets, array of shape (T, 4): x0, y0, x1, y1 [m], two-sided segments that stop the ball
# while up (State.targets_up) and drop when hit; Geometry.drop_target_bank gives each its bank.
# Spinners, array of shape (P, SPINNER_SIZE): a flap across a lane that the ball passes through.
SPINNER_X0 = 0  # the flap's line across the lane [m]
SPINNER_Y0 = 1
SPINNER_X1 = 2
SPINNER_Y1 = 3
SPINNER_RADIUS = 4  # flap radius [m]: a ball crossing at normal speed v spins it at v / radius
SPINNER_DAMPING = 5  # viscous decay of its spin [1/s]
SPINNER_FRICTION = 6  # its bearing's constant deceleration [rad/s^2]
SPINNER_SIZE = 7
# A spinner's state, array of shape (n_envs, P, SPIN_STATE_SIZE), float64.
SPIN_ANGLE = 0  # the flap's angle, wrapped to [0, 2 pi) [rad]
SPIN_OMEGA = 1  # its angular velocity [rad/s]
SPIN_STATE_SIZE = 2
# Kickbacks, array of shape (K, KICKBACK_SIZE): a line across an outlane; a ball crossing it
# against the kick while the kickback is lit (State.kickback_lit) leaves it at the kick velocity.
KICKBACK_X0 = 0  # [m]
KICKBACK_Y0 = 1
KICKBACK_X1 = 2
KICKBACK_Y1 = 3
KICKBACK_VX = 4  # the velocity a lit kickback gives the ball [m/s]
KICKBACK_VY = 5
KICKBACK_SIZE = 6

# Contact log, one row per contact, array of shape (n_envs, capacity, CONTACT_SIZE).
# Element ids are global: segments first, then circles, flippers, sensors, drop targets, spinners
# and kickbacks.
CONTACT_ELEMENT = 0  # global element id (stored as float, exact for any realistic count)
CONTACT_TIME = 1  # time of the contact since the start of the step [s]
CONTACT_SPEED = 2  # normal approach speed relative to the surface before the response [m/s]
CONTACT_SIZE = 3

# The cabinet's constants (tables with a cabinet), array of shape (1, CABINET_SIZE), float64; a
# table without one has (0, CABINET_SIZE). The cabinet is a mass-spring-damper on its legs, the
# plumb bob a pendulum hanging in it; see ``physics.cabinet``.
CABINET_MASS = 0  # [kg]
CABINET_STIFFNESS = 1  # [N/m]
CABINET_DAMPING = 2  # [N s/m]
BOB_LENGTH = 3  # pendulum length [m]
BOB_DAMPING = 4  # angular damping rate [1/s]
BOB_RING = 5  # the bob's angle from vertical where it touches the tilt ring [rad]
BOB_RESTITUTION = 6  # of the bob's bounce off the ring [-]
BOB_GRAVITY = 7  # g [m/s^2], which swings the bob back
CABINET_SIZE = 8

# The cabinet's state, array of shape (n_envs, CABINET_STATE_SIZE), float64: offset and velocity
# of the cabinet from where it stands (x to the right, y up the table), the shove a nudge gives it
# in the next substep, the plumb bob's angle from vertical (towards +x and +y) and angular
# velocity, and its touches of the ring.
CABINET_X = 0  # [m]
CABINET_Y = 1  # [m]
CABINET_VX = 2  # [m/s]
CABINET_VY = 3  # [m/s]
CABINET_SHOVE_X = 4  # impulse of the next substep [N s], cleared once applied
CABINET_SHOVE_Y = 5  # [N s]
BOB_X = 6  # [rad]
BOB_Y = 7  # [rad]
BOB_VX = 8  # [rad/s]
BOB_VY = 9  # [rad/s]
BOB_TOUCHES = 10  # touches of the ring in the last frame (a count, as a float)
BOB_ON_RING = 11  # 1 while the bob lies against the ring, 0 once it has swung clear
CABINET_STATE_SIZE = 12

# The several-ball kernel's work arrays (``physics.multiball``, ``data.Scratch``).
# A ball's cached earliest element contact, (N, M, EVENT_SIZE) float64 (``Scratch.events``).
EV_VALID = 0  # 1 while the ball keeps the path it was found for, 0: find it anew
EV_USED = 1  # the time to the contact (the whole time left where there is none) [s]
EV_REMAINING = 2  # the substep's time left when it was found [s]
EV_NX = 3  # the contact normal, from the surface towards the ball
EV_NY = 4
EV_SVX = 5  # the surface's velocity at the contact [m/s] (a swinging flipper's)
EV_SVY = 6
EV_ELEMENT = 7  # its element id (-1: none within the time left)
EV_CUT = 8  # 1 where a flipper sweep ran out of slices (the ball's substep ends there)
EVENT_SIZE = 9

# A ball's bookkeeping over one substep, (N, M, WORK_SIZE) float64 (``Scratch.work``; counts,
# ids and flags stored as floats, exact).
W_MOVING = 0  # 1 while the ball moves in this substep (in play, not held, not wedged)
W_X0 = 1  # where it started the substep [m]
W_Y0 = 2
W_STALLED = 3  # its events in a row that made no progress
W_LAST_REM = 4  # the substep's time left at its last event [s]
W_LAST = 5  # the last two different elements it touched (-1: none) and their normals
W_LAST_NX = 6
W_LAST_NY = 7
W_BEFORE = 8
W_BEFORE_NX = 9
W_BEFORE_NY = 10
W_PUSHERS = 11  # bit j: flipper j pushed into it in this substep
W_CHECK = 12  # 1: check its overlap at the substep's end (wedged, turning flipper, pair)
W_WEDGED = 13  # 1: it stopped before the substep's end (wedged, cut or the pass cap)
WORK_SIZE = 14
