"""The kernels also run as plain Python (NUMBA_DISABLE_JIT=1), and agree with the compiled path."""

import os
import subprocess
import sys
from pathlib import Path

import numpy as np

from pinball_env.sim.world import World
from pinball_env.table import load_table

ROOT = Path(__file__).resolve().parents[2]

TRACE_SCRIPT = """
import sys
import numpy as np
from pinball_env.table import load_table
from pinball_env.sim.world import World
world = World(load_table("box"), n_envs=3)
world.place_ball(1, (0.1, 0.95), (4.0, -2.5))
world.place_ball(2, (0.4, 0.3), (-30.0, 41.0))
for _ in range(240):
    world.step()
np.save(sys.argv[1], world.balls)
"""


def test_kernel_tests_pass_without_jit():
    env = {**os.environ, "NUMBA_DISABLE_JIT": "1"}
    result = subprocess.run(
        [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", "-m", "not slow",
         "tests/physics/test_sweep.py", "tests/sim/test_world.py",
         "tests/physics/test_flipper.py", "tests/sim/test_classic.py"],
        cwd=ROOT, env=env, capture_output=True, text=True, timeout=600,
    )  # fmt: skip
    assert result.returncode == 0, result.stdout[-3000:] + result.stderr[-3000:]


def test_pure_python_world_step_is_bitwise_the_compiled_one(tmp_path):
    out = tmp_path / "balls.npy"
    env = {**os.environ, "NUMBA_DISABLE_JIT": "1"}
    subprocess.run(
        [sys.executable, "-c", TRACE_SCRIPT, str(out)], cwd=ROOT, env=env, check=True, timeout=600
    )
    world = World(load_table("box"), n_envs=3)
    world.place_ball(1, (0.1, 0.95), (4.0, -2.5))
    world.place_ball(2, (0.4, 0.3), (-30.0, 41.0))
    for _ in range(240):
        world.step()
    np.testing.assert_array_equal(np.load(out), world.balls)


DROP_TARGET_SCRIPT = """
import sys
import numpy as np
from pinball_env.table import load_table
from pinball_env.sim.world import World
world = World(load_table("classic_v1"), n_envs=2)
world.place_ball(1, (0.30, 0.765), (2.0, 0.0))  # at drop_1, from the left
hits = 0
for _ in range(30):
    world.step()
    hits += int(world.state.hits[1].sum())
np.save(sys.argv[1], np.append(world.balls.ravel(), hits))
"""


def test_a_drop_target_contact_plays_as_plain_python_as_compiled(tmp_path):
    # A drop target's element id comes after the flippers': its contact once read a flipper row
    # past the end (an IndexError as plain Python, another env's memory compiled).
    out = tmp_path / "trace.npy"
    env = {**os.environ, "NUMBA_DISABLE_JIT": "1"}
    subprocess.run([sys.executable, "-c", DROP_TARGET_SCRIPT, str(out)], cwd=ROOT, env=env,
                   check=True, timeout=600)  # fmt: skip
    world = World(load_table("classic_v1"), n_envs=2)
    world.place_ball(1, (0.30, 0.765), (2.0, 0.0))
    hits = 0
    for _ in range(30):
        world.step()
        hits += int(world.state.hits[1].sum())
    assert hits >= 1 and not world.state.targets_up[1].all()  # drop_1 was hit and fell
    np.testing.assert_array_equal(np.load(out), np.append(world.balls.ravel(), hits))
