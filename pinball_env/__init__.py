"""A pinball table for reinforcement learning, moved by swept (continuous) collision.

Importing the package registers ``Pinball-v0`` with Gymnasium::

    import gymnasium as gym
    import pinball_env  # noqa: F401

    env = gym.make("Pinball-v0", table="classic", obs_type="state")
    envs = gym.make_vec("Pinball-v0", num_envs=1024)  # the native vector env, PinballVectorEnv
"""

from gymnasium.envs.registration import register

__version__ = "0.1.0"

# Two minutes of play at 60 frames per second.
MAX_EPISODE_STEPS = 7200

register(
    id="Pinball-v0",
    entry_point="pinball_env.env:PinballEnv",
    vector_entry_point="pinball_env.vector_env:PinballVectorEnv",
    max_episode_steps=MAX_EPISODE_STEPS,
)
