"""A pinball table for reinforcement learning, moved by swept (continuous) collision.

Importing the package registers ``Pinball-v0`` (the classic table, or any other),
``Pinball-v1`` (the whole cabinet: the player's plunger, the nudge and the tilt, on
``classic_v1``), ``Pinball-v2`` (v1's game with a tilt that any sustained nudging trips, on
``classic_v2``: the protocol's env) and ``PinballProcgen-v0`` (a generated table each game,
the table source ``"generated"``) with Gymnasium::

    import gymnasium as gym
    import pinball_env  # noqa: F401

    env = gym.make("Pinball-v0", table="classic", obs_type="state")
    envs = gym.make_vec("Pinball-v0", num_envs=1024)  # the native vector env, PinballVectorEnv
    env = gym.make("PinballProcgen-v0", num_layouts=16, start_layout=0, difficulty="easy")
"""

from gymnasium.envs.registration import register

# Generated tables' names ("procgen:SEED", "procgen-hard:SEED") resolve wherever a table name
# is taken: the generator registers them with the table package when imported.
import pinball_env.procgen  # noqa: F401
from pinball_env.options import GENERATED, MAX_EPISODE_STEPS

__version__ = "0.1.0"

# The entry points: the classes' one home, pinball_env.envs.
register(
    id="Pinball-v0",
    entry_point="pinball_env.envs:PinballEnv",
    vector_entry_point="pinball_env.envs:PinballVectorEnv",
    max_episode_steps=MAX_EPISODE_STEPS,
)

# The whole cabinet: the classic layout with the player's plunger, the nudge and the tilt, and
# the full action set (32 discrete actions).
register(
    id="Pinball-v1",
    entry_point="pinball_env.envs:PinballEnv",
    vector_entry_point="pinball_env.envs:PinballVectorEnv",
    max_episode_steps=MAX_EPISODE_STEPS,
    kwargs={"table": "classic_v1"},
)

# Pinball-v1's game with a tilt that any sustained nudging trips (v1's ignores one-way nudging):
# the protocol's env.
register(
    id="Pinball-v2",
    entry_point="pinball_env.envs:PinballEnv",
    vector_entry_point="pinball_env.envs:PinballVectorEnv",
    max_episode_steps=MAX_EPISODE_STEPS,
    kwargs={"table": "classic_v2"},
)

# The same envs on a generated table each game (the table source "generated").
register(
    id="PinballProcgen-v0",
    entry_point="pinball_env.envs:PinballEnv",
    vector_entry_point="pinball_env.envs:PinballVectorEnv",
    max_episode_steps=MAX_EPISODE_STEPS,
    kwargs={"table": GENERATED},
)
