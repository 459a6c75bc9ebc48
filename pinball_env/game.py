"""The rules of a pinball game over a batch of tables: balls per game, scoring, launches, drains,
and the state observation. The single env is a batch of one; a vector env (to come) can
run N with the same code.

Everything here is vectorised over the env axis; the physics is the World's kernel.
"""

import numpy as np

from pinball_env.backends import make_world
from pinball_env.physics.layout import BALL_VX, BALL_VY, BALL_X, BALL_Y, FLIPPER_REST_ANGLE
from pinball_env.table import Table, enclosure
from pinball_env.world import LEFT, RIGHT

# The state observation clips ball velocities to +-MAX_OBS_SPEED [m/s] so its bounds hold; a
# real ball rarely exceeds 10 m/s on a table (a full flip at the tip gives about 5 m/s).
MAX_OBS_SPEED = 20.0

# Discrete actions -> (left button, right button).
DISCRETE_BUTTONS = np.array([[False, False], [True, False], [False, True], [True, True]])


class Game:
    """``n_envs`` games on one table.

    Attributes:
        world: the physics (balls, flippers) of every env.
        balls_left: (n_envs,) balls still to play, the one in play included.
        score: (n_envs,) points scored in the current game.
    """

    def __init__(self, table: Table, n_envs: int, balls: int, physics: str = "swept") -> None:
        if table.plunger is None:
            raise ValueError(f"table {table.name!r} has no plunger: a game needs one to launch")
        if not table.flippers:
            raise ValueError(f"table {table.name!r} has no flippers: there is nothing to play")
        if enclosure(table.walls) is None:
            raise ValueError(f"table {table.name!r} has no closed outline wall to keep the ball in")
        if not any(sensor.drain for sensor in table.sensors):
            raise ValueError(f"table {table.name!r} has no drain sensor: a game could never end")
        if balls < 1:
            raise ValueError(f"balls must be >= 1, got {balls}")
        self.table = table
        self.balls = balls
        self.world = make_world(table, n_envs, physics)
        self.balls_left = np.zeros(n_envs, dtype=np.int64)
        self.score = np.zeros(n_envs, dtype=np.int64)
        # Height [m] at which each env's last drained ball crossed the drain.
        self.drain_height = np.zeros(n_envs)
        flippers = self.world.packed.flippers
        self._rest = flippers[:, FLIPPER_REST_ANGLE]
        # +1 for a flipper whose upstroke turns counter-clockwise, -1 for clockwise.
        up = np.radians([f.up_angle for f in table.flippers])
        self._up_sign = np.sign(up - self._rest)
        self._swing = np.abs(up - self._rest)
        self._max_omega = np.array([max(f.up_speed, f.down_speed) for f in table.flippers])
        self._scoring = np.flatnonzero(self.world.packed.element_scores)

    @property
    def n_envs(self) -> int:
        return self.world.n_envs

    def new_game(self, env: int, rng: np.random.Generator) -> None:
        """Start a new game in env ``env``: flippers at rest, score 0, the first ball launched."""
        self.world.rest_flippers(env)
        self.balls_left[env] = self.balls
        self.score[env] = 0
        self.launch(env, rng)

    def launch(self, env: int, rng: np.random.Generator) -> None:
        """Fire env ``env``'s next ball off the plunger at a speed drawn from the table's range."""
        low, high = self.table.plunger.speed
        self.world.launch(env, float(rng.uniform(low, high)))

    def step(self, buttons: np.ndarray, rngs: list[np.random.Generator]) -> tuple[np.ndarray, ...]:
        """One frame with the given (n_envs, 2) buttons. A drained ball is replaced by the next
        one off the plunger; the game ends when the last ball drains.

        Returns ``(points, drained, game_over)``, each (n_envs,).
        """
        self.world.step(buttons)
        points = self.world.frame_points()
        self.score += points
        drained = self.balls_left > 0
        drained &= ~self.world.state.active
        self.drain_height[drained] = self.world.balls[drained, BALL_Y]
        self.balls_left -= drained
        for env in np.flatnonzero(drained & (self.balls_left > 0)):
            self.launch(env, rngs[env])
        game_over = self.balls_left == 0
        return points, drained, game_over

    def events(self, env: int) -> dict[str, int]:
        """The scoring elements env ``env`` hit in the last frame: name -> hits."""
        hits = self.world.state.hits[env]
        names = self.world.packed.element_names
        return {names[i]: int(hits[i]) for i in self._scoring if hits[i]}

    # --- the state observation -------------------------------------------------------------

    def observation_bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """Lower and upper bounds of :meth:`observe` (float32, one entry per feature)."""
        n_flippers = len(self._rest)
        low = np.concatenate(
            [[0.0, 0.0, -MAX_OBS_SPEED, -MAX_OBS_SPEED], np.zeros(n_flippers),
             -self._max_omega, [0.0, 0.0]]
        )  # fmt: skip
        high = np.concatenate(
            [[self.table.width, self.table.height, MAX_OBS_SPEED, MAX_OBS_SPEED], self._swing,
             self._max_omega, [1.0, float(self.balls)]]
        )  # fmt: skip
        return low.astype(np.float32), high.astype(np.float32)

    def observe(self) -> np.ndarray:
        """(n_envs, 4 + 2F + 2) float32: ball x, y, vx, vy; each flipper's angle above rest and
        angular velocity towards up; ball in play; balls left. See PinballEnv's docstring."""
        state = self.world.state
        balls = state.balls
        lift = (state.flipper_angle - self._rest) * self._up_sign  # the kernel stops it exactly
        velocity = np.clip(balls[:, [BALL_VX, BALL_VY]], -MAX_OBS_SPEED, MAX_OBS_SPEED)
        obs = np.concatenate(
            [balls[:, [BALL_X, BALL_Y]], velocity, lift, state.flipper_omega * self._up_sign,
             state.active[:, None], self.balls_left[:, None]],
            axis=1,
        )  # fmt: skip
        return obs.astype(np.float32)

    def ball_info(self, env: int) -> dict[str, np.ndarray]:
        """Ball position [m] and velocity [m/s] of env ``env`` in table coordinates."""
        ball = self.world.state.balls[env]
        return {
            "ball_position": ball[[BALL_X, BALL_Y]].copy(),
            "ball_velocity": ball[[BALL_VX, BALL_VY]].copy(),
        }


__all__ = ["DISCRETE_BUTTONS", "LEFT", "MAX_OBS_SPEED", "RIGHT", "Game"]
