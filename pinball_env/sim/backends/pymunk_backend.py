"""The same table built in pymunk (Chipmunk2D), behind the World interface, for cross-checks.

``PymunkWorld`` is a :class:`~pinball_env.sim.world.World` whose frame is simulated by pymunk
instead of the swept kernel: one ``pymunk.Space`` per env, built from the same validated table.

- walls are static ``Segment`` shapes, posts and bumpers static ``Circle`` shapes; a one-sided
  wall ignores a ball whose centre is behind it (pymunk has no one-sided segments);
- the ball is a dynamic circle with the moment of inertia of a solid sphere, 2/5 m r^2, so its
  spin matches ours;
- flippers are kinematic bodies made of the base circle, the tip circle and the quadrilateral
  between their tangent points, driven by exactly the same angle schedule as the kernel's
  (the kernel's own :func:`~pinball_env.physics.contact.flipper_motion` and
  :func:`~pinball_env.physics.contact.flipper_end`): in each substep the body turns at
  the angular velocity that takes it from the kernel's start angle to its end angle;
- materials map to ``elasticity`` (restitution) and ``friction``: the ball's own are 1, and
  pymunk multiplies the two shapes' values; kickers add their kick along the contact normal once
  per new contact, and what counts as a hit is the kernel's rule (``is_hit``);
- gravity, frame rate and substeps are the table's; sensors and the drain are the kernel's own
  crossing test and bookkeeping (``record_crossings``) on the ball centre's path over each
  substep;
- the cabinet (a table with one) is the kernel's own: each substep advances it by
  :func:`~pinball_env.physics.cabinet.cabinet_substep`, and the ball, simulated relative to the
  cabinet as in the kernel, feels its acceleration ``-dv / h`` beside gravity (the space's
  gravity for that substep: the ball is the space's only dynamic body); a tilted machine's
  kickers are dead (``state.tilted``), as in the kernel;
- targets (a table with them) are the kernel's too: a drop target is a static segment that
  stops being processed once it has fallen (``state.targets_up``), dropping at the end of the
  substep that hit it; spinner and kickback lines are the kernel's crossing tests on the ball
  centre's path over each substep (a lit kickback puts the ball at its line at the kick
  velocity), and the frame ends with the kernel's ``update_targets`` (spinners turn, banks
  rise).

Several balls (a table whose trough holds several, see ``World.n_balls``): each ball slot is a
dynamic circle of its own, and pymunk collides the balls itself (it finds their overlaps after
they happen, as with every other contact), at the ball-ball material's restitution and friction
(``table.pack_ball_pair``: set on each ball-ball arbiter, since pymunk would multiply the balls'
own values); a held ball (``World.held``: a saucer, a lock) is a kinematic body at rest,
immovable to the others, and dynamic again when released. The sensors, kickbacks and the drain
are crossed by each ball's own move; banks rise when no ball in play is near them. The saucers
and locks themselves are ``World``'s (the end of each frame, either backend).

What pymunk does not have, and the cross-check measures: continuous collision (it finds overlaps
after they happen, so a fast ball can pass through a thin wall or a flipper within one substep),
and the inelastic resting-contact threshold (it relies on its slop and bias instead).

The state arrays (``self.state``) stay the single source of truth: each frame writes them into
the pymunk bodies, steps the spaces, and reads the bodies back. So everything built on World
(``Game``, ``PinballEnv(physics="pymunk")``) runs on pymunk unchanged.
"""

import math
from typing import TYPE_CHECKING, Any

import numpy as np

from pinball_env.extras import require
from pinball_env.physics import capsule_face_normal, first_circle, first_flipper
from pinball_env.physics.cabinet import cabinet_substep
from pinball_env.physics.columns import (
    BALL_SPIN,
    BALL_VX,
    BALL_VY,
    BALL_X,
    BALL_Y,
    BOB_TOUCHES,
    KICKBACK_VX,
    KICKBACK_VY,
    PROP_FRICTION,
    PROP_KICK,
    PROP_RESTITUTION,
)
from pinball_env.physics.contact import flipper_end, flipper_motion, is_hit
from pinball_env.physics.data import first_drop_target, first_kickback, log_contact
from pinball_env.physics.targets import (
    count_kickbacks,
    kickback_crossing,
    record_crossings,
    sensor_crossing,
    spin_spinner,
    update_targets,
)
from pinball_env.sim.world import World
from pinball_env.table import Table

if TYPE_CHECKING:  # the module require() returns, for its types
    import pymunk
else:
    pymunk = require("pymunk")

# Chipmunk's defaults assume pixels; in metres they would let the ball sink 10 cm into a wall.
COLLISION_SLOP = 1e-4  # [m] overlap allowed before the position correction acts
SOLVER_ITERATIONS = 20  # more than the default 10: stacked contacts (cradles) settle better
BALL_COLLISION_TYPE = 1


class PymunkWorld(World):
    """``n_envs`` games on one table, each simulated by its own pymunk space."""

    swept_kernel = False

    def __init__(self, table: Table, n_envs: int = 1) -> None:
        self._spaces: list[_EnvSpace] = []
        super().__init__(table, n_envs)
        self._spaces = [_EnvSpace(self, env) for env in range(n_envs)]

    def _advance(self, envs: np.ndarray | None = None) -> int:
        for env, env_space in enumerate(self._spaces):
            if envs is None or envs[env]:
                env_space.advance_frame()
        return int((~np.isfinite(self.state.balls).all(axis=(1, 2))).sum())

    def __getstate__(self) -> dict[str, Any]:
        # Spaces hold callbacks into this object; they are rebuilt from the state arrays.
        state = super().__getstate__()
        state["_spaces"] = []
        return state

    def __setstate__(self, state: dict[str, Any]) -> None:
        self.__dict__.update(state)
        self._spaces = [_EnvSpace(self, env) for env in range(self.n_envs)]


class _EnvSpace:
    """The pymunk space of one env, and the bookkeeping that mirrors the kernel's outputs."""

    def __init__(self, world: PymunkWorld, env: int) -> None:
        self.world = world
        self.env = env
        table, geometry = world.table, world.geometry
        space = pymunk.Space()
        space.gravity = table.gravity_vector
        space.collision_slop = COLLISION_SLOP
        space.iterations = SOLVER_ITERATIONS
        self.space = space
        self.time = 0.0  # seconds since the start of the frame, for the contact log
        self.pending_kicks: list[tuple[Any, float, float, float]] = []
        self.kick_scale = 1.0  # 0 while the machine is tilted (its kickers dead)
        self.pending_drops: list[int] = []  # drop targets hit in the substep under way

        static = space.static_body
        shape: pymunk.Shape
        for element, (x0, y0, x1, y1) in enumerate(geometry.segments):
            shape = pymunk.Segment(static, (x0, y0), (x1, y1), 0.0)
            self._add_element(shape, element, geometry.segment_props[element])
            shape.one_sided = bool(geometry.segment_one_sided[element])
            shape.blocking_normal = (-(y1 - y0), x1 - x0)  # rot+90(P1 - P0)
            shape.anchor = (x0, y0)
        for j, (x, y, radius) in enumerate(geometry.circles):
            shape = pymunk.Circle(static, radius, offset=(x, y))
            self._add_element(shape, first_circle(geometry) + j, geometry.circle_props[j])
        for j, (x0, y0, x1, y1) in enumerate(geometry.drop_targets):
            shape = pymunk.Segment(static, (x0, y0), (x1, y1), 0.0)
            self._add_element(shape, first_drop_target(geometry) + j, geometry.drop_target_props[j])
            shape.drop_target = j
        self.flipper_bodies = []
        for j, flipper in enumerate(table.flippers):
            body = pymunk.Body(body_type=pymunk.Body.KINEMATIC)
            body.position = flipper.pivot
            space.add(body)
            for shape in _flipper_shapes(body, flipper.length, flipper.base_radius,
                                         flipper.tip_radius):  # fmt: skip
                self._add_element(shape, first_flipper(geometry) + j, geometry.flipper_props[j])
            self.flipper_bodies.append(body)

        mass = table.ball.mass
        radius = table.ball.radius
        self.mass, self.moment = mass, 0.4 * mass * radius * radius  # a solid sphere
        self.balls: list[pymunk.Body] = []
        self.ball_shapes: list[pymunk.Shape] = []
        for i in range(world.n_balls):
            body = pymunk.Body(self.mass, self.moment)
            shape = pymunk.Circle(body, radius)
            shape.elasticity = 1.0  # pymunk multiplies: the surface's value is the result
            shape.friction = 1.0
            shape.collision_type = BALL_COLLISION_TYPE
            shape.ball = i
            self.balls.append(body)
            self.ball_shapes.append(shape)
        self.in_space = [False] * world.n_balls
        pair = table.pack_ball_pair()
        self.pair = float(pair[PROP_RESTITUTION]), float(pair[PROP_FRICTION])
        space.on_collision(BALL_COLLISION_TYPE, None, begin=self._begin, pre_solve=self._pre_solve)

    # The first ball's (the state's ``ball`` slot 0), for code written for one ball.
    @property
    def ball(self) -> "pymunk.Body":
        return self.balls[0]

    def _add_element(self, shape: "pymunk.Shape", element: int, props: np.ndarray) -> None:
        shape.elasticity = float(props[PROP_RESTITUTION])
        shape.friction = float(props[PROP_FRICTION])
        shape.kick = float(props[PROP_KICK])
        shape.element = element
        shape.one_sided = False
        shape.drop_target = -1  # else the index of the drop target it is
        self.space.add(shape)

    # --- collision callbacks ------------------------------------------------------------------

    def _other(self, arbiter: "pymunk.Arbiter") -> tuple["pymunk.Shape", float, float]:
        """The shape the ball touches and the contact normal pointing towards the ball."""
        _, other = arbiter.shapes
        nx, ny = arbiter.normal  # from the first shape (the ball) to the second
        return other, -nx, -ny

    def _pair(self, arbiter: "pymunk.Arbiter") -> bool:
        """Whether the contact is between two balls; if so it takes the ball-ball material."""
        if getattr(arbiter.shapes[1], "ball", None) is None:
            return False
        arbiter.restitution, arbiter.friction = self.pair
        return True

    def _pre_solve(self, arbiter: "pymunk.Arbiter", space: "pymunk.Space", data: Any) -> None:
        if self._pair(arbiter):
            return
        other, _, _ = self._other(arbiter)
        ball = arbiter.shapes[0].body
        assert ball is not None  # (a ball's shape has its body)
        if other.drop_target >= 0 and not self.world.state.targets_up[self.env, other.drop_target]:
            arbiter.process_collision = False  # fallen: no contact
        elif other.one_sided:
            # Behind a one-sided segment (the side its normal does not point to): pass through.
            cx, cy = ball.position
            ax, ay = other.anchor
            if (cx - ax) * other.blocking_normal[0] + (cy - ay) * other.blocking_normal[1] < 0.0:
                arbiter.process_collision = False

    def _begin(self, arbiter: "pymunk.Arbiter", space: "pymunk.Space", data: Any) -> None:
        if self._pair(arbiter):
            return  # ball-ball contacts are not logged (no element id), as in the kernel
        other, nx, ny = self._other(arbiter)
        ball = arbiter.shapes[0].body
        assert ball is not None and other.body is not None  # (shapes in the space have bodies)
        if other.one_sided or other.drop_target >= 0:
            self._pre_solve(arbiter, space, data)
            if not arbiter.process_collision:
                return
        points = arbiter.contact_point_set.points
        contact = points[0].point_a if points else ball.position
        surface = other.body.velocity_at_world_point(contact)
        vx, vy = ball.velocity
        speed = max(-((vx - surface.x) * nx + (vy - surface.y) * ny), 0.0)
        state = self.world.state
        kick = self.kick_scale * other.kick
        log_contact(state, self.env, other.element, self.time, speed)
        if is_hit(speed, kick, self.world.settings.resting_speed):
            state.hits[self.env, other.element] += 1
            if other.drop_target >= 0:
                self.pending_drops.append(other.drop_target)
        if kick > 0.0:
            self.pending_kicks.append((ball, kick, nx, ny))

    # --- one frame ----------------------------------------------------------------------------

    def advance_frame(self) -> None:
        world, env = self.world, self.env
        state, settings, geometry = world.state, world.settings, world.geometry
        h = settings.dt / settings.substeps
        state.contact_count[env] = 0
        state.hits[env, :] = 0
        cabinet = world.tables.geometry_of(env).cabinet
        if cabinet.shape[0] > 0:
            state.cabinet[env, BOB_TOUCHES] = 0.0
        self.kick_scale = 0.0 if state.tilted[env] else 1.0
        gravity_x, gravity_y = settings.gravity_x, settings.gravity_y
        self._sync_ball_in()
        angle, omega = state.flipper_angle[env], state.flipper_omega[env]
        flippers, commands = geometry.flippers, state.flipper_command[env]
        for k in range(settings.substeps):
            self.time = k * h
            if cabinet.shape[0] > 0:
                # The kernel's cabinet, whether or not a ball is in play; relative to it the
                # ball feels its acceleration, opposite, beside gravity (a frame force).
                dvx, dvy = cabinet_substep(state.cabinet[env], cabinet[0], h)
                self.space.gravity = (gravity_x - dvx / h, gravity_y - dvy / h)
            # The kernel's flipper schedule, never held (pymunk has no wedge rule).
            for j, body in enumerate(self.flipper_bodies):
                start = angle[j]
                target, turn, stop = flipper_motion(flippers[j], start, commands[j])
                angle[j], omega[j] = flipper_end(start, target, turn, stop, False, h, h)
                body.angle = start
                body.angular_velocity = (angle[j] - start) / h
            before = [body.position for body in self.balls]
            space_before = list(self.in_space)
            self.space.step(h)
            for j, body in enumerate(self.flipper_bodies):
                body.angle = angle[j]  # exactly the kernel's angle
            for ball, kick, nx, ny in self.pending_kicks:
                ball.velocity += (kick * nx, kick * ny)
            self.pending_kicks.clear()
            for j in self.pending_drops:  # they fall at the end of the substep, as the kernel's
                state.targets_up[env, j] = False
            self.pending_drops.clear()
            for i in range(world.n_balls):
                if space_before[i] and self.balls[i].body_type == pymunk.Body.DYNAMIC:
                    self._cross_sensors(i, before[i])
        self._sync_ball_out()
        if world.table.has_targets:
            update_targets(geometry, state, env, state.balls[env], state.active[env],
                           world.table.ball.radius, settings.dt)  # fmt: skip

    def _cross_sensors(self, i: int, before: "pymunk.Vec2d") -> None:
        """The kernel's sensor bookkeeping on ball ``i``'s move over the substep just stepped;
        a drained ball leaves the space where it crossed the drain."""
        world, env = self.world, self.env
        geometry, state = world.geometry, world.state
        body = self.balls[i]
        after = body.position
        dx, dy = after.x - before.x, after.y - before.y
        h = world.settings.dt / world.settings.substeps
        vx, vy = dx / h, dy / h  # the move's mean velocity
        kicked, u = -1, math.inf
        if geometry.kickbacks.shape[0] > 0:
            lit = state.kickback_lit[env]
            kicked, u = kickback_crossing(before.x, before.y, vx, vy, h, geometry.kickbacks, lit)
            if kicked >= 0:  # the move ends at the line, whence the ball leaves at the kick
                dx, dy = dx * u, dy * u
            count_kickbacks(
                state,
                env,
                before.x,
                before.y,
                vx,
                vy,
                h * min(u, 1.0),
                geometry.kickbacks,
                lit,
                first_kickback(geometry),
                self.time + h,
            )
        for j in range(geometry.spinners.shape[0]):
            crossing = sensor_crossing(before.x, before.y, dx, dy, geometry.spinners[j])
            if crossing < math.inf:
                spin_spinner(geometry.spinners[j], state.spinners[env, j], vx, vy,
                             self.time + crossing * h)  # fmt: skip
        if kicked >= 0:
            kick = geometry.kickbacks[kicked]
            state.hits[env, first_kickback(geometry) + kicked] += 1
            log_contact(state, env, first_kickback(geometry) + kicked, self.time + u * h, 0.0)
            state.kickback_lit[env, kicked] = False
            body.position = (before.x + dx, before.y + dy)
            body.velocity = (kick[KICKBACK_VX], kick[KICKBACK_VY])
            body.angular_velocity = 0.0
        drain = record_crossings(
            world.state, env, world.geometry, before.x, before.y, dx, dy, self.time, h,
            world.scratch.crossings[env],
        )  # fmt: skip
        if drain < math.inf:
            body.position = (before.x + drain * dx, before.y + drain * dy)
            world.active[env, i] = False
            self._remove_ball(i)

    def _sync_ball_in(self) -> None:
        """Write the state arrays into the ball bodies (they may have been set from outside):
        a ball out of play leaves the space, a held one is a kinematic body at rest."""
        world, env = self.world, self.env
        states, active, held = world.balls[env], world.active[env], world.held[env]
        for i, body in enumerate(self.balls):
            if not active[i]:
                self._remove_ball(i)
                continue
            kind = pymunk.Body.KINEMATIC if held[i] else pymunk.Body.DYNAMIC
            if body.body_type != kind:
                body.body_type = kind
                if kind == pymunk.Body.DYNAMIC:  # pymunk zeroes them on a change of type
                    body.mass, body.moment = self.mass, self.moment
            ball = states[i]
            body.position = (ball[BALL_X], ball[BALL_Y])
            body.velocity = (ball[BALL_VX], ball[BALL_VY])
            body.angular_velocity = ball[BALL_SPIN]
            if not self.in_space[i]:
                self.space.add(body, self.ball_shapes[i])
                self.in_space[i] = True

    def _sync_ball_out(self) -> None:
        world, env = self.world, self.env
        for i, body in enumerate(self.balls):
            if world.held[env, i]:
                continue  # exactly where it is held
            ball = world.balls[env, i]
            ball[BALL_X], ball[BALL_Y] = body.position
            ball[BALL_VX], ball[BALL_VY] = body.velocity
            ball[BALL_SPIN] = body.angular_velocity

    def _remove_ball(self, i: int) -> None:
        if self.in_space[i]:
            self.space.remove(self.balls[i], self.ball_shapes[i])
            self.in_space[i] = False


def _flipper_shapes(
    body: "pymunk.Body", length: float, base_radius: float, tip_radius: float
) -> list["pymunk.Shape"]:
    """The tapered capsule as pymunk shapes in the body frame (pivot at the origin, tip on +x):
    both circles and the quadrilateral between their common tangent points."""
    face_x, face_y = capsule_face_normal(length, base_radius, tip_radius)
    quad = [
        (base_radius * face_x, base_radius * face_y),
        (length + tip_radius * face_x, tip_radius * face_y),
        (length + tip_radius * face_x, -tip_radius * face_y),
        (base_radius * face_x, -base_radius * face_y),
    ]
    return [
        pymunk.Circle(body, base_radius),
        pymunk.Circle(body, tip_radius, offset=(length, 0.0)),
        pymunk.Poly(body, quad),
    ]
