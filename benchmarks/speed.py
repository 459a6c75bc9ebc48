"""Speed of the envs, the kernel, and references of this machine, in one run:
``python -m benchmarks.speed`` from the repository root (``--quick`` for a short run, ``--json
PATH``, ``--compare REV`` for the same figures of a git revision, measured alternately in the
same run, ``--only NAME ...`` for some of the measurements). A developer's tool of the
checkout, not shipped in the wheel: it trains with ``agents`` beside the package.

Measures, with uniformly random actions on the classic table (state observations unless said):

- ``Pinball-v0`` through ``gym.make``, on the swept kernel and on pymunk, and the swept one
  bare (``.unwrapped``: gym.make's wrappers measured apart);
- Gymnasium's ``SyncVectorEnv`` of 8 of each;
- the native vector env (``gym.make_vec``) at N = 1, 64, 1024 and 4096 envs with 1 and 2
  threads, and at N = 256 with 84x84 grayscale observations;
- the native vector env as agents train on it (``TRAINING_KWARGS``: frame skip 2, the step
  running on while the ball is high, shaping) at N = 32 and 128, 1 thread: each step is about
  15 frames of every env;
- ``Pinball-v1``'s (the whole cabinet) native vector env at N = 1024 with 1 and 2 threads, and
  with 2 threads the chain stable-baselines3 steps over it (``SB3VecEnv`` under
  ``VecNormalize``: ``v1_sb3chain1024_2thread``);
- ``Pinball-v2``'s and ``Pinball-v3``'s (multiball: classic_v3, a trough of three balls, a
  lock and a saucer) native vector envs at N = 1024 with 2 threads, and v3's rate over v2's;
- ``PinballProcgen-v0``'s native vector env at N = 1024 with 2 threads, each env on its own
  generated table (16 layouts, generated before the timing), with 16 rays in the observation;
- ``CartPole-v1`` through ``gym.make`` and ``gym.make_vec("CartPole-v1", num_envs=1024)``, as
  references of this machine;
- the kernel alone: microseconds per ball-frame, and nanoseconds per ball-element pair that a
  pass would sweep if it tested every solid element (as the kernel did before its candidate
  sets: the figure compares across versions);
- the several-ball kernel alone (``physics.multiball.step_multiworld`` on classic_v3, one
  thread): microseconds per env-frame with 1, 2 and 3 balls in play
  (``kernel_multiball_us_per_frame_1ball``, ``_2balls``, ``_3balls``; :func:`measure_multiball`),
  and ``ratio_kernel_3balls_to_1ball``, three balls over one on that kernel and table;
- table generation (``tablegen_ms_per_table``, ``tablegen_targets_ms_per_table``): milliseconds
  per generated table, drawn, validated and checked for playability (``generate_table`` called
  directly, no cache), the mean over 8 (``--quick``) or 32 seeds, without and with targets;
- stable-baselines3 training (``SB3_CONFIGS``): PPO with the shipped ``configs/agents/ppo.yaml``
  (``sb3_ppo``) and with the recipe at the env's speed, ``ppo_scale_v2.yaml``
  (``sb3_ppo_scale_v2``: 1024 envs of Pinball-v2), A2C and DQN with the v1 recipes
  (``sb3_a2c_v1``, ``sb3_dqn_v1``) and at the env's speed (``sb3_a2c_scale_v2``: 1024 envs;
  ``sb3_dqn_scale_v2``: 256 envs, a gradient step of 2048 per vector step), each with its env,
  its hyperparameters and its threads (no warm start, validation or checkpoints), 2
  (``--quick``) or 8 iterations (rollouts and updates; DQN: 128 vector steps) timed after an
  untimed one: ``PREFIX_env_steps_per_second``, and the shares of that
  wall time ``PREFIX_env_share`` (inside the VecEnv's ``step_async``, ``step_wait`` and
  ``reset``, ``VecNormalize`` included: the env as SB3 sees it) and ``PREFIX_learner_share``
  (the rest: the policy's forward passes in the rollouts, the buffer and its advantages,
  ``train()``'s epochs, SB3's bookkeeping);
- training that shares the machine: ``ppo_scale_v2.yaml``'s again while another CPU-bound
  process (a Python busy loop) runs beside it (``sb3_ppo_scale_v2_shared_env_steps_per_second``),
  and ``ratio_sb3_ppo_scale_v2_shared_to_alone`` (at least 0.5 is a fair share of 2 cores);
- start-up: import + make + first step with a warm numba cache, and with a cold one (compiling
  every kernel; skipped with ``--quick``), each in a fresh process;

and the ratios between them, as a table and a JSON line. A figure this version cannot measure
(no stable-baselines3, an env or option an older revision lacks) is null. Timings are
wall-clock on a shared machine: compare figures of one run, never across runs.

``--compare REV`` (:mod:`benchmarks.compare`) measures every figure for the checkout and for git
revision REV, each measurement in a fresh process running this module's code against that
tree's package, the two alternating measurement by measurement (``--repeats N``: N of each, the
median kept). The table gains REV's column and the ratio checkout / REV (above 1: the
checkout's rate is higher, or its time longer); the JSON gains ``"compare": {"rev", "sha",
"repeats", "figures", "ratios", "errors"}``. So that a copy of this file measures any tree, it
imports nothing of ``benchmarks/`` but for ``--compare``, and only what every revision's
``pinball_env`` has.
"""

import argparse
import importlib
import inspect
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
from typing import Any

import gymnasium as gym
import numpy as np

import pinball_env  # registers Pinball-v0
from pinball_env.physics import first_sensor
from pinball_env.table import load_table

try:
    from pinball_env.sim.world import World
except ImportError:  # a revision from before sim/ (--compare): World's home was pinball_env.world
    from pinball_env.world import World  # type: ignore[no-redef]

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
    ("v3_native1024_2thread", "v2_native1024_2thread"),
    ("v1_sb3chain1024_2thread", "v1_native1024_2thread"),
    ("single_swept", "cartpole_single"),
    ("single_swept", "single_swept_unwrapped"),
    ("single_swept", "single_pymunk"),
)

# The configs whose training rate is measured, relative to the tree that holds the package, by
# the prefix of their figures: the shipped default, and the recipe at the env's speed.
SB3_CONFIGS = {
    "sb3_ppo": Path("configs/agents/ppo.yaml"),
    "sb3_ppo_scale_v2": Path("configs/agents/ppo_scale_v2.yaml"),
    "sb3_a2c_v1": Path("configs/agents/a2c_v1.yaml"),
    "sb3_a2c_scale_v2": Path("configs/agents/a2c_scale_v2.yaml"),
    "sb3_dqn_v1": Path("configs/agents/dqn_v1.yaml"),
    "sb3_dqn_scale_v2": Path("configs/agents/dqn_scale_v2.yaml"),
}
SB3_FIGURES = ("env_steps_per_second", "env_share", "learner_share")
# The several-ball kernel's figures: balls in play, and the name of its figure.
MULTIBALL_FIGURES = {n: f"kernel_multiball_us_per_frame_{n}ball{'s' if n > 1 else ''}"
                     for n in (1, 2, 3)}  # fmt: skip
TABLEGEN_FIGURES = ("tablegen_ms_per_table", "tablegen_targets_ms_per_table")
# Generated tables' seeds start here (plus 1000 per --seed): seeds no test or config uses.
TABLEGEN_SEED = 7_000_000

Figures = dict[str, float | None]


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
    elements = first_sensor(world.geometry)  # the solid ones (a pass sweeps its set of them)
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


def measure_multiball(n_balls: int, n_envs: int, frames: int, seed: int) -> Figures:
    """Microseconds per env-frame of the several-ball kernel (``step_multiworld``, called
    directly, one thread) on classic_v3 with ``n_balls`` balls in play in each of ``n_envs``
    envs, under random flipping (each button held or not, drawn anew each frame).

    Each env's balls are launched from the plunger at the auto-plunger's speeds, one every 20
    frames, and played for 100 frames in all, untimed (compiling or loading the kernel too);
    then ``frames`` frames are timed, the kernel calls only. Between frames (untimed) a drained
    ball, or one at rest on the plunger (the first, as the world starts it, or one that rolled
    back), is launched as soon as no other ball lies within three radii of the plunger, so that
    the balls stay in play (none is captured: the saucer's and lock's captures are
    ``sim.World.step``'s, outside the kernel). Null where this version lacks the kernel or
    classic_v3."""
    name = MULTIBALL_FIGURES[n_balls]
    try:
        from pinball_env.physics.multiball import step_multiworld

        table = load_table("classic_v3")
    except (ImportError, ValueError, KeyError, FileNotFoundError, AttributeError):
        return {name: None}
    world = World(table, n_envs=n_envs)
    plunger = np.asarray(table.plunger.position)
    speeds = table.trough.auto_plunger.speed
    rng = np.random.default_rng(seed)
    args, balls, active = multiball_kernel_args(world)
    reach = 3.0 * world.settings.radius

    def frame() -> float:
        world.state.flipper_command[:] = rng.random(world.state.flipper_command.shape) < 0.5
        start = time.perf_counter()
        faults = step_multiworld(*args)
        seconds = time.perf_counter() - start
        if faults:
            raise FloatingPointError(f"{faults} env(s) with a non-finite ball state")
        return seconds

    def relaunch(balls_now: int) -> None:
        gaps = np.hypot(*(balls[..., :2] - plunger).transpose(2, 0, 1))  # (N, M)
        speed = np.hypot(balls[..., 2], balls[..., 3])
        waiting = active & (gaps <= reach) & (speed < 0.1)  # at rest on the plunger
        launched = set()  # one ball per env and frame
        for env, ball in zip(*np.nonzero((~active | waiting)[:, :balls_now]), strict=True):
            others = active[env] & ~waiting[env]
            if env not in launched and (gaps[env, others] > reach).all():
                world.launch(int(env), rng.uniform(*speeds), int(ball))
                launched.add(env)

    for warmup in range(100):
        relaunch(min(n_balls, warmup // 20 + 1))
        frame()
    seconds = 0.0
    for _ in range(frames):
        relaunch(n_balls)
        seconds += frame()
    return {name: 1e6 * seconds / (n_envs * frames)}


def multiball_kernel_args(world: World) -> tuple[tuple, np.ndarray, np.ndarray]:
    """``step_multiworld``'s arguments stepping every env of ``world``, and its balls (N, M, 5)
    and whether each is in play (N, M): the World's ball slots, or a revision's from before
    them (``World.multi``)."""
    moving, n_envs = np.ones(world.n_envs, dtype=np.bool_), world.n_envs
    if getattr(world, "multi", None) is not None:
        args = (world.geometry, world.settings, world.state, world.scratch, world.multi,
                world.mscratch, world.pair, moving, 0, n_envs)  # fmt: skip
        return args, world.multi.balls, world.multi.active
    args = (world.geometry, world.settings, world.state, world.scratch, world.pair, moving, 0,
            n_envs)  # fmt: skip
    return args, world.balls, world.active


def measure_tablegen(count: int, seed: int) -> Figures:
    """Milliseconds per generated table: ``pinball_env.procgen.generate_table`` called directly
    (every draw of the layout, its validation and the playability check on the kernel; no cache
    in between) on ``count`` distinct seeds, the mean; then the same seeds with ``targets=True``.
    One untimed table of another seed first (compiling or loading the kernels). Null where this
    version's generator lacks the table generation or its ``targets``."""
    try:
        from pinball_env.procgen import generate_table
    except ImportError:
        return dict.fromkeys(TABLEGEN_FIGURES)
    seeds = [TABLEGEN_SEED + 1000 * seed + i for i in range(count)]
    variants = [("tablegen_ms_per_table", {})]
    if "targets" in inspect.signature(generate_table).parameters:
        variants.append(("tablegen_targets_ms_per_table", {"targets": True}))
    result = dict.fromkeys(TABLEGEN_FIGURES)
    for name, kwargs in variants:
        generate_table(seeds[-1] + 1, **kwargs)  # outside the timing: the kernels' first calls
        start = time.perf_counter()
        for table_seed in seeds:
            generate_table(table_seed, **kwargs)
        result[name] = 1e3 * (time.perf_counter() - start) / count
    return result


def measure_shared(prefix: str, iterations: int) -> Figures:
    """:func:`measure_sb3` of ``prefix`` while another CPU-bound process runs beside it (a
    Python busy loop: a user's other job), as ``PREFIX_shared_env_steps_per_second``; the
    training alone is ``PREFIX_env_steps_per_second`` (``ratio_..._shared_to_alone``)."""
    competitor = subprocess.Popen([sys.executable, "-c", "while True: pass"])
    try:
        figures = measure_sb3(prefix, iterations)
    finally:
        competitor.kill()
        competitor.wait()
    rate = figures[f"{prefix}_env_steps_per_second"]
    return {f"{prefix}_shared_env_steps_per_second": rate}


def sb3_model(config_path: Path) -> tuple[Any, Any]:
    """The stable-baselines3 model of the config at ``config_path`` and its VecEnv, set up as
    ``agents.train`` does it (``load_config``, ``set_threads``: torch's threads are the
    config's; ``make_env``, training's chain; the algorithm with ``sb3_hyperparams``; no warm
    start, validation or checkpoints). ``agents`` is the tree's, beside its ``pinball_env``."""
    from agents import envs
    from agents.config import algorithm_class, load_config, sb3_hyperparams
    from agents.train import set_threads

    make_env = getattr(envs, "make_env_chain", None) or envs.make_env  # older revisions' name

    config = load_config(config_path)
    set_threads(config)
    # Training's chain: infos only where a game ended (older revisions filled every env's).
    quiet = {"step_infos": False} if "step_infos" in inspect.signature(make_env).parameters else {}
    venv = make_env(config, **quiet)
    model = algorithm_class(config.algo)(
        config.policy, venv, seed=config.seed, device=config.device, verbose=0,
        **sb3_hyperparams(config),
    )  # fmt: skip
    return model, venv


def measure_sb3(prefix: str, iterations: int) -> Figures:
    """stable-baselines3 training with the config ``SB3_CONFIGS[prefix]`` (beside the
    package, :func:`sb3_model`); one iteration (on-policy:
    a rollout and its update; off-policy: 128 vector steps and their gradient steps) untimed,
    after off-policy's ``learning_starts``, then ``iterations`` timed. Returns
    ``PREFIX_env_steps_per_second`` of the timed ``learn`` call (wall time),
    ``PREFIX_env_share`` of it inside the VecEnv's ``step_async``, ``step_wait`` and ``reset``
    (the whole chain SB3 steps, ``VecNormalize`` included), and the rest,
    ``PREFIX_learner_share``. Null without torch and stable-baselines3, or without the config
    (an older revision)."""
    names = [f"{prefix}_{figure}" for figure in SB3_FIGURES]
    root = Path(pinball_env.__file__).resolve().parent.parent  # the tree: configs/, agents/
    if not (root / SB3_CONFIGS[prefix]).is_file():
        return dict.fromkeys(names)
    # agents first, as agents.train imports it: it sets how torch's threads wait.
    importlib.import_module("agents")
    try:
        import stable_baselines3  # noqa: F401
        import torch  # noqa: F401
    except ImportError:
        return dict.fromkeys(names)
    model, venv = sb3_model(root / SB3_CONFIGS[prefix])
    if hasattr(model, "n_steps"):  # on-policy: an iteration is a rollout and its update
        rollout = model.n_steps * model.n_envs
        warmup = rollout
    else:  # off-policy: an iteration is 128 vector steps, each with its gradient steps
        rollout = 128 * model.train_freq.frequency * model.n_envs
        warmup = model.learning_starts + rollout  # learning starts in the timing's first step
    model.learn(warmup)  # outside the timing: the kernels' first calls, the first reset
    env = model.get_env()
    in_env = [0.0]

    def timed(call: Callable[..., Any]) -> Callable[..., Any]:
        def timed_call(*args: Any, **kwargs: Any) -> Any:
            start = time.perf_counter()
            try:
                return call(*args, **kwargs)
            finally:
                in_env[0] += time.perf_counter() - start

        return timed_call

    for name in ("step_async", "step_wait", "reset"):
        setattr(env, name, timed(getattr(env, name)))
    before = model.num_timesteps
    start = time.perf_counter()
    model.learn(iterations * rollout, reset_num_timesteps=False)
    seconds = time.perf_counter() - start
    venv.close()
    rate, share = (model.num_timesteps - before) / seconds, in_env[0] / seconds
    return dict(zip(names, (rate, share, 1.0 - share), strict=True))


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


def sb3_chain_steps_per_second(
    n: int, threads: int, env_id: str, steps: int, seed: int
) -> float | None:
    """Env-steps per second of the chain stable-baselines3 trains on: ``SB3VecEnv`` (infos
    only where a game ended, as in training) under ``SB3VecNormalize``, over ``env_id``'s native
    vector env of ``n`` envs on ``threads`` threads, under uniformly random actions; None
    without stable-baselines3."""
    try:
        from stable_baselines3.common.vec_env import VecNormalize

        from pinball_env.wrappers import sb3
    except ImportError:
        return None
    # The chain agents train on (an older revision's: SB3's own VecNormalize).
    normalize = getattr(sb3, "SB3VecNormalize", VecNormalize)
    venv = normalize(sb3.SB3VecEnv(gym.make_vec(env_id, num_envs=n, num_threads=threads)))
    rng = np.random.default_rng(seed)
    actions = [rng.integers(venv.action_space.n, size=n) for _ in range(min(steps, 100))]
    venv.seed(seed)
    venv.reset()
    venv.step(actions[0])  # compile (or load the cached kernels) outside the timing
    start = time.perf_counter()
    for i in range(steps):
        venv.step(actions[i % len(actions)])
    seconds = time.perf_counter() - start
    venv.close()
    return steps * n / seconds


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


def measurements(quick: bool, seed: int) -> list[tuple[str, Callable[[], float | None]]]:
    """Every steps-per-second figure's name and the call that measures it."""
    scale = 20 if quick else 1

    def steps(n: int) -> int:
        return max(n // scale, 4)

    def single(physics: str, unwrapped: bool = False) -> float:
        env = gym.make("Pinball-v0", physics=physics)  # gym.make's wrappers, or the bare env
        env = env.unwrapped if unwrapped else env
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

    figures: list[tuple[str, Callable[[], float | None]]] = [
        ("single_swept", lambda: single("swept")),
        ("single_swept_unwrapped", lambda: single("swept", unwrapped=True)),
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
    for version in ("v2", "v3"):  # v3: multiball (classic_v3: a trough of 3 balls, a lock)
        figures.append((f"{version}_native1024_2thread",
                        lambda v=version: native(1024, 2, env_id=f"Pinball-{v}")))  # fmt: skip
    # The same as stable-baselines3 steps it: SB3VecEnv and VecNormalize over it.
    figures.append(("v1_sb3chain1024_2thread", lambda: sb3_chain_steps_per_second(
        1024, 2, "Pinball-v1", steps(300), seed)))  # fmt: skip

    def procgen(n: int, threads: int) -> float:
        env = gym.make_vec("PinballProcgen-v0", num_envs=n, num_threads=threads, num_layouts=16,
                           rays=16)  # fmt: skip
        return steps_per_second(env, steps(max(300, 300_000 // max(n, 100))), seed)

    def cartpole(steps_: int, vector: bool) -> float:
        env = gym.make_vec("CartPole-v1", num_envs=1024) if vector else gym.make("CartPole-v1")
        return steps_per_second(env, steps(steps_), seed)

    figures += [
        ("procgen1024_16layouts_2thread", lambda: procgen(1024, 2)),
        ("native256_grayscale_2thread", lambda: native(256, 2, "grayscale")),
        ("cartpole_single", lambda: cartpole(20000, vector=False)),
        ("cartpole_vec1024", lambda: cartpole(1000, vector=True)),
    ]
    return figures


def groups(quick: bool, seed: int) -> list[tuple[str, Callable[[], Figures]]]:
    """Every measurement's name and the call that makes it, giving one figure or more: the
    units that ``run`` goes through and ``--compare`` alternates (``--worker NAME`` runs one)."""

    def rate(name: str, measure: Callable[[], float | None]) -> Callable[[], Figures]:
        return lambda: {f"{name}_steps_per_second": measure()}

    n_envs, frames = (256, 20) if quick else (1024, 300)
    found = [(name, rate(name, measure)) for name, measure in measurements(quick, seed)]
    found.append(("kernel", lambda: measure_kernel("classic", n_envs, frames, 10.0, seed)))
    for n, name in MULTIBALL_FIGURES.items():  # kernel_multiball_1ball, _2balls, _3balls
        group = f"kernel_multiball_{name.rsplit('_', 1)[1]}"
        found.append((group, lambda n=n: measure_multiball(n, n_envs, 3 * frames, seed)))
    found += [
        ("tablegen", lambda: measure_tablegen(8 if quick else 32, seed)),
        *[(prefix, lambda p=prefix: measure_sb3(p, 2 if quick else 8)) for prefix in SB3_CONFIGS],
        ("sb3_ppo_scale_v2_shared", lambda: measure_shared("sb3_ppo_scale_v2", 2 if quick else 8)),
        ("startup_warm", lambda: {"startup_warm_seconds": startup_seconds(cold=False)}),
    ]
    if not quick:
        found.append(("startup_cold", lambda: {"startup_cold_seconds": startup_seconds(cold=True)}))
    return found


def progress(done: int, total: int, name: str) -> None:
    """A progress bar on stderr."""
    filled = round(30 * done / total)
    print(f"\r[{'#' * filled}{'.' * (30 - filled)}] {done}/{total} {name:<30}", end="",
          file=sys.stderr, flush=True)  # fmt: skip


def divide(numerator: object, denominator: object) -> float | None:
    """``numerator / denominator``, or None where either is missing (or the denominator 0)."""
    if not isinstance(numerator, (int, float)) or not isinstance(denominator, (int, float)):
        return None
    if isinstance(numerator, bool) or isinstance(denominator, bool) or denominator == 0:
        return None
    return numerator / denominator


def finish(figures: Figures, quick: bool) -> dict:
    """The figures with ``RATIOS`` (null where a figure is), the machine and the budget."""
    result: dict[str, object] = dict(figures)
    rate = {key.removesuffix("_steps_per_second"): value for key, value in figures.items()}
    for numerator, denominator in RATIOS:
        result[f"ratio_{numerator}_to_{denominator}"] = divide(
            rate.get(numerator), rate.get(denominator)
        )
    result["ratio_sb3_ppo_scale_v2_shared_to_alone"] = divide(
        figures.get("sb3_ppo_scale_v2_shared_env_steps_per_second"),
        figures.get("sb3_ppo_scale_v2_env_steps_per_second"),
    )
    result["ratio_kernel_3balls_to_1ball"] = divide(
        figures.get(MULTIBALL_FIGURES[3]), figures.get(MULTIBALL_FIGURES[1])
    )
    result["machine"] = f"{platform.machine()}, {os.cpu_count()} cores"
    result["quick"] = quick
    return result


def selected(
    quick: bool, seed: int, only: list[str] | None
) -> list[tuple[str, Callable[[], Figures]]]:
    """The measurements of :func:`groups` named in ``only`` (all of them without it);
    ValueError naming the known ones for a name that is not one."""
    found = groups(quick, seed)
    if not only:
        return found
    names = [name for name, _ in found]
    unknown = [name for name in only if name not in names]
    if unknown:
        raise ValueError(f"no measurement {', '.join(unknown)} (there are: {', '.join(names)})")
    return [(name, measure) for name, measure in found if name in only]


def run(quick: bool = False, seed: int = 0, only: list[str] | None = None) -> dict:
    """All the figures (steps per second, seconds, ratios) as a dict, measured in this
    process (those of the measurements ``only`` names, with it)."""
    todo = selected(quick, seed, only)
    figures: Figures = {}
    for done, (name, measure) in enumerate(todo):
        progress(done, len(todo), name)
        figures.update(measure())
    progress(len(todo), len(todo), "done")
    print(file=sys.stderr)
    return finish(figures, quick)


def worker(name: str, quick: bool, seed: int, out: Path) -> dict:
    """Run the measurement ``name`` (of :func:`groups`) and write ``{"figures", "error",
    "package"}`` to ``out`` as JSON: what ``--compare`` runs in a fresh process per tree.
    An error (an API this tree's package lacks) is written, not raised: its figures are null."""
    try:
        figures, error = dict(groups(quick, seed))[name](), None
    except Exception as exc:
        figures, error = {}, f"{type(exc).__name__}: {exc}"
    report = {
        "figures": figures,
        "error": error,
        "package": str(Path(pinball_env.__file__).resolve().parent),
    }
    out.write_text(json.dumps(report))
    return report


def shown(value: object) -> str:
    """A figure as the table prints it."""
    if value is None:
        return "null"
    return f"{value:,.4g}" if isinstance(value, float) else str(value)


def table(result: dict) -> str:
    """The figures as lines of text: name and value, and with ``"compare"`` the revision's
    value and the ratio checkout / revision."""
    keys = [key for key in result if key != "compare"]
    width = max(map(len, keys))
    if "compare" not in result:
        return "\n".join(f"{key:<{width}}  {shown(result[key])}" for key in keys)
    other = result["compare"]
    rev, sha = other["rev"], other["sha"]
    label = rev if sha.startswith(rev) else f"{rev} ({sha[:7]})"
    column = max(len(label), 12)
    lines = [f"{'figure':<{width}}  {'checkout':>12}  {label:>{column}}  {'ratio':>7}"]
    for key in keys:
        if key in other["figures"]:
            lines.append(
                f"{key:<{width}}  {shown(result[key]):>12}  "
                f"{shown(other['figures'][key]):>{column}}  {shown(other['ratios'][key]):>7}"
            )
        else:
            lines.append(f"{key:<{width}}  {shown(result[key]):>12}")
    for side, failed in other["errors"].items():
        for name, error in failed.items():  # the first line (the JSON has the whole message)
            lines.append(f"{name} failed on {label if side == 'rev' else side}: "
                         f"{error.splitlines()[0][:120]}")  # fmt: skip
    return "\n".join(lines)


def parser() -> argparse.ArgumentParser:
    """The command line."""
    from pinball_env.tools import command_parser  # (here: older trees' packages lack it)

    parser = command_parser("benchmarks.speed", __doc__)
    parser.add_argument("--quick", action="store_true", help="short run (about 20x fewer steps)")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--json", type=Path, help="also write the figures to this file")
    parser.add_argument(
        "--compare", metavar="REV",
        help="also measure git revision REV, alternating with the checkout, and the ratios",
    )  # fmt: skip
    parser.add_argument(
        "--repeats", type=int, default=1,
        help="with --compare: measurements of each figure per tree (the median is kept)",
    )  # fmt: skip
    parser.add_argument(
        "--only", nargs="+", metavar="NAME",
        help="only these measurements (v1_sb3chain1024_2thread, sb3_ppo, kernel, "
        "kernel_multiball_3balls, v3_native1024_2thread, ...)",
    )  # fmt: skip
    parser.add_argument("--worker", metavar="NAME", help=argparse.SUPPRESS)
    parser.add_argument("--json-out", type=Path, help=argparse.SUPPRESS)
    return parser


def main(argv: list[str] | None = None) -> dict:
    command = parser()
    args = command.parse_args(argv)
    if args.repeats < 1:
        command.error("--repeats must be 1 or more")
    if args.worker is not None:
        if args.json_out is None:
            command.error("--worker needs --json-out")
        return worker(args.worker, args.quick, args.seed, args.json_out)
    try:
        selected(args.quick, args.seed, args.only)
    except ValueError as error:
        command.error(f"--only: {error}")
    if args.compare is not None:
        # Imported here: a worker (a copy of this file, run against another tree) never is one.
        from benchmarks.compare import RevisionError, compare

        try:
            result = compare(args.compare, args.quick, args.seed, args.repeats, args.only)
        except RevisionError as error:
            command.error(f"--compare {error}")
    else:
        result = run(args.quick, args.seed, args.only)
    print(table(result))
    print(json.dumps(result))
    if args.json:
        args.json.parent.mkdir(parents=True, exist_ok=True)
        args.json.write_text(json.dumps(result, indent=2) + "\n")
    return result


if __name__ == "__main__":
    main()
