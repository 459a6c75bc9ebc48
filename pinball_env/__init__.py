"""A pinball table for reinforcement learning, moved by swept (continuous) collision.

Importing the package registers ``Pinball-v0`` (the classic table, or any other),
``Pinball-v1`` (the whole cabinet: the player's plunger, the nudge and the tilt, on
``classic_v1``), ``Pinball-v2`` (v1's game with a tilt that any sustained nudging trips, on
``classic_v2``), ``Pinball-v3`` (v2's game with multiball, on ``classic_v3``: a trough of three
balls, a lock and a saucer; the protocol's env) and ``PinballProcgen-v0`` (a
generated table each game, the table source ``"generated"``) with Gymnasium::

    import gymnasium as gym
    import pinball_env  # noqa: F401

    env = gym.make("Pinball-v0", table="classic", obs_type="state")
    envs = gym.make_vec("Pinball-v0", num_envs=1024)  # the native vector env, PinballVectorEnv
    env = gym.make("PinballProcgen-v0", num_layouts=16, start_layout=0, difficulty="easy")

The package, bottom up (imports run one way: ``tests/test_house.py``): ``physics`` (the numba
kernels), ``table`` (tables as validated data), ``procgen`` (generated tables), ``sim`` (the
World of N envs, the pymunk backend), ``game`` (the rules over N envs), ``options``,
``observation``, ``envs`` (the Gymnasium shells), ``wrappers`` (stable-baselines3), ``render``,
``players`` (the scripted baselines), ``recording`` (the play tool's recordings), ``protocol``
(the benchmark protocol) and ``tools`` (``python -m pinball_env.tools.NAME``). The
documentation's pages: ``docs/`` (``python -m mkdocs serve``).
"""

from gymnasium.envs.registration import register

# Generated tables' names ("procgen:SEED", "procgen-hard:SEED") resolve wherever a table name
# is taken: the generator registers them with the table package when imported.
import pinball_env.procgen  # noqa: F401
from pinball_env.options import GENERATED, MAX_EPISODE_STEPS

__version__ = "0.1.0"

# The envs, each on its table, with what it is. Every one has the same entry points (the classes'
# one home, pinball_env.envs) and the game's two minutes as its time limit.
ENVS = {
    "Pinball-v0": "the two-button table: the flippers, a launch from the machine's plunger",
    "Pinball-v1": "the whole cabinet (the player's plunger, the nudge and the tilt), rules and "
    "targets",
    "Pinball-v2": "v1's game with a tilt that any sustained nudging trips: the benchmark's "
    "one-ball track",
    "Pinball-v3": "v2's game with multiball: a trough of three balls, a two-ball lock, a saucer, "
    "the jackpot lit during a multiball; the benchmark's env",
    "PinballProcgen-v0": "a generated table every game (`num_layouts`, `difficulty`, ...)",
}
TABLES = {"Pinball-v0": None, "Pinball-v1": "classic_v1", "Pinball-v2": "classic_v2",
          "Pinball-v3": "classic_v3", "PinballProcgen-v0": GENERATED}  # fmt: skip

for _id, _table in TABLES.items():
    register(
        id=_id,
        entry_point="pinball_env.envs:PinballEnv",
        vector_entry_point="pinball_env.envs:PinballVectorEnv",
        max_episode_steps=MAX_EPISODE_STEPS,
        kwargs={} if _table is None else {"table": _table},
    )
del _id, _table
