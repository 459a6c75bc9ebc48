"""Fork-safety: envs used in processes started after the parent has played (its table prefetch
and stepping threads running), by Gymnasium's AsyncVectorEnv (fork, forkserver, spawn),
stable-baselines3's SubprocVecEnv (fork), and a forked child that goes on with the parent's own
env objects. Each scenario runs in a subprocess with a time limit, so that a hang (a thread
pool inherited without its threads) is a failure, not a stuck test run."""

import os
import signal
import subprocess
import sys
import textwrap

import pytest

# Long enough for a spawned child to import the package and generate a few tables on a slow,
# busy machine; a hang runs into it.
TIME_LIMIT = 300  # [s]

# The parent plays a PinballProcgen-v0 game first: its Layouts' prefetch thread is started and
# generating the table of the next game, as after any procgen game.
PARENT = """
import multiprocessing, sys
import gymnasium as gym, numpy as np
import pinball_env  # noqa: F401

parent = gym.make("PinballProcgen-v0", num_layouts=0, start_layout=100)
parent.reset(seed=0)
for _ in range(30):
    parent.step(1)
"""

SCENARIOS = {
    # The second reset (no seed) plays the layouts drawn ahead at the first: their tables come
    # from each child's prefetch thread (the parent's, inherited by a fork, would never run).
    "async": """
envs = gym.make_vec("PinballProcgen-v0", num_envs=2, vectorization_mode="async",
                    vector_kwargs={"context": sys.argv[2]}, num_layouts=0, start_layout=100)
envs.reset(seed=1)
envs.step(np.zeros(2, dtype=np.int64))
obs, infos = envs.reset()
envs.step(np.ones(2, dtype=np.int64))
envs.close()
print("layouts", infos["layout"].tolist())
""",
    "sb3_subproc_fork": """
from stable_baselines3.common.vec_env import SubprocVecEnv

def make():
    return gym.make("PinballProcgen-v0", num_layouts=0, start_layout=100)

envs = SubprocVecEnv([make, make], start_method="fork")
envs.seed(1)
envs.reset()
envs.step(np.zeros(2, dtype=np.int64))
envs.reset()
envs.step(np.ones(2, dtype=np.int64))
print("layouts", envs.get_attr("layout"))
envs.close()
""",
    # A forked child that goes on with the parent's own objects: the procgen env (its next
    # table pending in the parent's thread) and a vector env stepped on two threads. The child
    # plays exactly the games the parent plays next.
    "copied_envs": """
vector = gym.make_vec("Pinball-v0", num_envs=64, num_threads=2)
vector.reset(seed=0)
vector.step(np.zeros(64, dtype=np.int64))

def go_on():
    obs, info = parent.reset()
    trace = [obs.tobytes(), info["layout"]]
    for _ in range(20):
        trace.append(parent.step(2)[0].tobytes())
    for _ in range(20):
        trace.append(vector.step(np.ones(64, dtype=np.int64))[0].tobytes())
    return trace

def child(connection):
    connection.send(go_on())

receive, send = multiprocessing.get_context("fork").Pipe(duplex=False)
process = multiprocessing.get_context("fork").Process(target=child, args=(send,))
process.start()
in_child = receive.recv()
process.join()
assert in_child == go_on(), "the forked child played other games"
print("same games, layout", in_child[1])
""",
}


def run_scenario(name: str, *args: str) -> str:
    """The scenario's output; a failure if it fails or has not ended in TIME_LIMIT (then it is
    killed with the processes it started: it runs in a process group of its own)."""
    code = textwrap.dedent(PARENT) + textwrap.dedent(SCENARIOS[name])
    env = {**os.environ, "SDL_VIDEODRIVER": "dummy", "SDL_AUDIODRIVER": "dummy"}
    process = subprocess.Popen(
        [sys.executable, "-c", code, name, *args], stdout=subprocess.PIPE,
        stderr=subprocess.PIPE, text=True, env=env, start_new_session=True,
    )  # fmt: skip
    try:
        out, err = process.communicate(timeout=TIME_LIMIT)
    except subprocess.TimeoutExpired:
        os.killpg(process.pid, signal.SIGKILL)
        _, err = process.communicate()
        pytest.fail(f"{name} {args}: no result in {TIME_LIMIT} s (a hang)\n{err[-3000:]}")
    assert process.returncode == 0, err[-3000:]
    return out


@pytest.mark.parametrize("context", ["fork", "forkserver", "spawn"])
def test_async_vector_env_after_a_procgen_game(context):
    out = run_scenario("async", context)
    assert out.startswith("layouts ")


def test_sb3_subproc_vec_env_with_fork_after_a_procgen_game():
    pytest.importorskip("stable_baselines3")
    out = run_scenario("sb3_subproc_fork")
    assert out.startswith("layouts ")


def test_a_forked_child_goes_on_with_the_parents_envs():
    out = run_scenario("copied_envs")
    assert out.startswith("same games")
