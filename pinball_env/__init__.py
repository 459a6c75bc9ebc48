"""A pinball table for reinforcement learning, moved by swept (continuous) collision.

Importing the package registers with Gymnasium the env versions of ``pinball_env.versions``
(``ENV_VERSIONS``, one record each: its id, its table, what it is): ``Pinball-v0`` (the
flippers) to ``Pinball-v3`` (the whole cabinet with multiball, the protocol's env), each on its
own table, and ``PinballProcgen-v0`` (a generated table each game)::

    import gymnasium as gym
    import pinball_env  # noqa: F401

    env = gym.make("Pinball-v0", table="classic", obs_type="state")
    envs = gym.make_vec("Pinball-v0", num_envs=1024)  # the native vector env, PinballVectorEnv
    env = gym.make("PinballProcgen-v0", num_layouts=16, start_layout=0, difficulty="easy")

The package, bottom up (imports run one way: ``tests/test_house.py``): ``physics`` (the numba
kernels), ``table`` (tables as validated data), ``procgen`` (generated tables), ``sim`` (the
World of N envs, the pymunk backend), ``game`` (the rules over N envs), ``options``,
``versions`` (the env versions), ``observation``, ``envs`` (the Gymnasium shells), ``wrappers``
(stable-baselines3), ``render``, ``players`` (the scripted baselines), ``recording`` (the play
tool's recordings), ``protocol`` (the benchmark protocol) and ``tools`` (``python -m
pinball_env.tools.NAME``). The documentation's pages: ``docs/`` (``python -m mkdocs serve``).
"""

from gymnasium.envs.registration import register

# Generated tables' names ("procgen:SEED", "procgen-hard:SEED") resolve wherever a table name
# is taken: the generator registers them with the table package when imported.
import pinball_env.procgen  # noqa: F401
from pinball_env.options import MAX_EPISODE_STEPS, PinballOptions
from pinball_env.version import __version__ as __version__
from pinball_env.versions import ENV_VERSIONS

# Every version has the same entry points (the classes' one home, pinball_env.envs) and the
# game's two minutes as its time limit. The default table is left to the options' default, as
# Pinball-v0 always was, so that its spec stays what it was.
for _version in ENV_VERSIONS.values():
    register(
        id=_version.id,
        entry_point="pinball_env.envs:PinballEnv",
        vector_entry_point="pinball_env.envs:PinballVectorEnv",
        max_episode_steps=MAX_EPISODE_STEPS,
        kwargs={} if _version.table == PinballOptions.table else {"table": _version.table},
    )
del _version
