"""Speed of the envs, the kernel, and references of this machine, in one run:
``python -m pinball_env.tools.benchmark`` (``--quick`` for a short run, ``--json PATH``).

Measures, with uniformly random actions on the classic table (state observations unless said):

- ``Pinball-v0`` through ``gym.make``, on the swept kernel and on pymunk;
- Gymnasium's ``SyncVectorEnv`` of 8 of each;
- the native vector env (``gym.make_vec``) at N = 1, 64, 1024 and 4096 envs with 1 and 2
  threads, and at N = 256 with 84x84 grayscale observations;
- the native vector env as agents train on it (``TRAINING_KWARGS``: frame skip 2, the step
  running on while the ball is high, shaping) at N = 32 and 128, 1 thread: each step is about
  15 frames of every env;
- ``Pinball-v1``'s (the whole cabinet) native vector env at N = 1024 with 1 and 2 threads;
- ``PinballProcgen-v0``'s native vector env at N = 1024 with 2 threads, each env on its own
  generated table (16 layouts, generated before the timing), with 16 rays in the observation;
- ``CartPole-v1`` through ``gym.make`` and ``gym.make_vec("CartPole-v1", num_envs=1024)``, as
  references of this machine;
- the kernel alone: microseconds per ball-frame and nanoseconds per ball-element sweep test;
- start-up: import + make + first step with a warm numba cache, and with a cold one (compiling
  every kernel; skipped with ``--quick``), each in a fresh process;

and the ratios between them, as a table and a JSON line. Timings are wall-clock on a shared
machine: compare figures of one run, never across runs.
"""

import argparse
import json
import math
import os
import platform
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

import gymnasium as gym
import numpy as np

import pinball_env  # noqa: F401  (registers Pinball-v0)
from pinball_env.physics import first_sensor
from pinball_env.sim.world import World
from pinball_env.table import load_table

STARTUP = (
    "import time; start = time.perf_counter(); import gymnasium as gym, pinball_env; "
    "env = gym.make('Pinball-v0'); env.reset(seed=0); env.step(0); "
    "print(time.perf_counter() - start)"
)


# A training env: configs/agents/ppo.yaml's until it went to frame skip 1, kept as it was so
# that the training figures compare across versions.
TRAINING_KWARGS = {"frame_skip": 2, "skip_above": 0.26, "drain_penalty": 5.0, "height_shaping": 1.0}

# The ratios reported, numerator and denominator (the targets among them).
RATIOS = (
    ("native1024_2thread", "sync8_pymunk"),
    ("native1024_2thread", "sync8_swept"),
    ("native1024_2thread", "native1024_1thread"),
    ("native1024_2thread", "cartpole_vec1024"),
    ("procgen1024_16layouts_2thread", "native1024_2thread"),
    ("v1_native1024_2thread", "native1024_2thread"),
    ("single_swept", "cartpole_single"),
    ("single_swept", "single_pymunk"),
)


def random_launches(world: World, rng: np.random.Generator, max_speed: float) -> None:
    """Put every ball of ``world`` at the table's start with a random velocity."""
    for env in range(world.n_envs):
        speed = rng.uniform(0.0, max_speed)
        heading = rng.uniform(0.0, 2.0 * math.pi)
        world.place_ball(
            env, world.table.ball.start, (speed * math.cos(heading), speed * math.sin(heading))
        )


def measure_kernel(table: str, n_envs: int, frames: int, max_speed: float, seed: int) -> dict:
    """Time ``frames`` world steps of ``n_envs`` balls, one thread; returns the figures."""
    world = World(load_table(table), n_envs=n_envs)
    rng = np.random.default_rng(seed)
    random_launches(world, rng, max_speed)
    world.step()  # compile (or load the cached kernel) outside the timing
    random_launches(world, rng, max_speed)
    elements = first_sensor(world.geometry)  # the solid ones, that every pass sweeps against
    substeps = world.table.simulation.substeps
    contacts = ball_frames = 0  # frames of balls in play: a drained ball costs (almost) nothing
    start = time.perf_counter()
    for _ in range(frames):
        ball_frames += int(world.active.sum())
        world.step()
        contacts += int(world.state.contact_count.sum())
    seconds = time.perf_counter() - start
    # One pass per substep plus one more after each contact (the sweep of the remaining time).
    tests = (ball_frames * substeps + contacts) * elements
    return {
        "kernel_elements": elements,
        "kernel_contacts_per_ball_frame": contacts / ball_frames,
        "kernel_us_per_ball_frame": 1e6 * seconds / ball_frames,
        "kernel_ns_per_ball_element_test": 1e9 * seconds / tests,
    }


def steps_per_second(env: gym.Env | gym.vector.VectorEnv, steps: int, seed: int) -> float:
    """Env-steps per second of ``env`` under uniformly random actions (a vector env's steps
    count once per env). Single envs are reset when their episode ends."""
    vector = isinstance(env, gym.vector.VectorEnv)
    env.action_space.seed(seed)
    actions = [env.action_space.sample() for _ in range(min(steps, 1000))]
    env.reset(seed=seed)
    env.step(actions[0])  # compile (or load the cached kernels) outside the timing
    start = time.perf_counter()
    for i in range(steps):
        _, _, terminated, truncated, _ = env.step(actions[i % len(actions)])
        if not vector and (terminated or truncated):
            env.reset()
    seconds = time.perf_counter() - start
    return steps * (env.num_envs if vector else 1) / seconds


def startup_seconds(cold: bool) -> float:
    """Import + make + first step in a fresh process, with a warm numba cache (this run's) or
    a cold one (an empty cache folder: every kernel compiles)."""
    environment = dict(os.environ)
    with tempfile.TemporaryDirectory() as cache:
        if cold:
            environment["NUMBA_CACHE_DIR"] = cache
        else:  # warm the cache this process uses, then time a fresh one
            subprocess.run([sys.executable, "-c", STARTUP], env=environment, check=True,
                           capture_output=True)  # fmt: skip
        result = subprocess.run(
            [sys.executable, "-c", STARTUP], env=environment, check=True, capture_output=True,
            text=True,
        )  # fmt: skip
    return float(result.stdout.strip().splitlines()[-1])


def measurements(quick: bool, seed: int) -> list[tuple[str, Callable[[], float]]]:
    """Every figure's name and the call that measures it."""
    scale = 20 if quick else 1

    def steps(n: int) -> int:
        return max(n // scale, 4)

    def single(physics: str) -> float:
        env = gym.make("Pinball-v0", physics=physics)
        return steps_per_second(env, steps(5000 if physics == "swept" else 1000), seed)

    def sync(physics: str) -> float:
        env = gym.vector.SyncVectorEnv(
            [lambda: gym.make("Pinball-v0", physics=physics) for _ in range(8)]
        )
        return steps_per_second(env, steps(1000 if physics == "swept" else 200), seed)

    def native(
        n: int, threads: int, obs_type: str = "state", env_id: str = "Pinball-v0", **kwargs: float
    ) -> float:
        env = gym.make_vec(env_id, num_envs=n, num_threads=threads, obs_type=obs_type,
                           **kwargs)  # fmt: skip
        return steps_per_second(env, steps(max(300, 300_000 // max(n, 100))), seed)

    figures: list[tuple[str, Callable[[], float]]] = [
        ("single_swept", lambda: single("swept")),
        ("single_pymunk", lambda: single("pymunk")),
        ("sync8_swept", lambda: sync("swept")),
        ("sync8_pymunk", lambda: sync("pymunk")),
    ]
    for n in (1, 64, 1024, 4096):
        for threads in (1, 2):
            figures.append((f"native{n}_{threads}thread", lambda n=n, t=threads: native(n, t)))
    for n in (32, 128):
        figures.append((f"training{n}_1thread", lambda n=n: native(n, 1, **TRAINING_KWARGS)))
    for threads in (1, 2):  # the whole cabinet: plunger, nudges (random ones tilt), the bob
        figures.append((f"v1_native1024_{threads}thread",
                        lambda t=threads: native(1024, t, env_id="Pinball-v1")))  # fmt: skip
    cartpole = gym.make("CartPole-v1")
    cartpoles = gym.make_vec("CartPole-v1", num_envs=1024)

    def procgen(n: int, threads: int) -> float:
        env = gym.make_vec("PinballProcgen-v0", num_envs=n, num_threads=threads, num_layouts=16,
                           rays=16)  # fmt: skip
        return steps_per_second(env, steps(max(300, 300_000 // max(n, 100))), seed)

    figures += [
        ("procgen1024_16layouts_2thread", lambda: procgen(1024, 2)),
        ("native256_grayscale_2thread", lambda: native(256, 2, "grayscale")),
        ("cartpole_single", lambda: steps_per_second(cartpole, steps(20000), seed)),
        ("cartpole_vec1024", lambda: steps_per_second(cartpoles, steps(1000), seed)),
    ]
    return figures


def progress(done: int, total: int, name: str) -> None:
    """A progress bar on stderr."""
    filled = round(30 * done / total)
    print(f"\r[{'#' * filled}{'.' * (30 - filled)}] {done}/{total} {name:<30}", end="",
          file=sys.stderr, flush=True)  # fmt: skip


def run(quick: bool = False, seed: int = 0) -> dict:
    """All the figures (steps per second, seconds, ratios) as a dict."""
    figures = measurements(quick, seed)
    total = len(figures) + 3 - int(quick)
    result: dict[str, object] = {}
    for done, (name, measure) in enumerate(figures):
        progress(done, total, name)
        result[f"{name}_steps_per_second"] = measure()
    progress(len(figures), total, "kernel")
    n_envs, frames = (256, 20) if quick else (1024, 300)
    result.update(measure_kernel("classic", n_envs, frames, 10.0, seed))
    progress(len(figures) + 1, total, "start-up, warm cache")
    result["startup_warm_seconds"] = startup_seconds(cold=False)
    if not quick:
        progress(len(figures) + 2, total, "start-up, cold cache")
        result["startup_cold_seconds"] = startup_seconds(cold=True)
    progress(total, total, "done")
    print(file=sys.stderr)
    rate = {key.removesuffix("_steps_per_second"): value for key, value in result.items()}
    for numerator, denominator in RATIOS:
        result[f"ratio_{numerator}_to_{denominator}"] = rate[numerator] / rate[denominator]
    result["machine"] = f"{platform.machine()}, {os.cpu_count()} cores"
    result["quick"] = quick
    return result


def main(argv: list[str] | None = None) -> dict:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="short run (about 20x fewer steps)")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--json", type=Path, help="also write the figures to this file")
    args = parser.parse_args(argv)
    result = run(args.quick, args.seed)
    width = max(map(len, result))
    for key, value in result.items():
        shown = f"{value:,.4g}" if isinstance(value, float) else value
        print(f"{key:<{width}}  {shown}")
    print(json.dumps(result))
    if args.json:
        args.json.parent.mkdir(parents=True, exist_ok=True)
        args.json.write_text(json.dumps(result, indent=2) + "\n")
    return result


if __name__ == "__main__":
    main()
