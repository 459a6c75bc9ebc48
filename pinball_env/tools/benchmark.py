"""Speed of the batched world step and of the env: ``python -m pinball_env.tools.benchmark``.

Steps a batch of balls with random launches on a table and prints a table of figures plus a JSON
line (``--json PATH`` also writes it to a file). The headline figure is the time per ball-element
sweep test: every pass of the contact loop sweeps one ball against every wall, post and flipper.
It also times ``Pinball-v0`` itself (one env, random actions), with state and with image
observations. Timings are wall-clock on a shared machine: compare figures measured in one run.
"""

import argparse
import json
import math
import platform
import time
from pathlib import Path

import numpy as np

from pinball_env.physics import first_sensor
from pinball_env.table import load_table
from pinball_env.world import World


def random_launches(world: World, rng: np.random.Generator, max_speed: float) -> None:
    """Put every ball of ``world`` at the table's start with a random velocity."""
    for env in range(world.n_envs):
        speed = rng.uniform(0.0, max_speed)
        heading = rng.uniform(0.0, 2.0 * math.pi)
        world.place_ball(
            env, world.table.ball.start, (speed * math.cos(heading), speed * math.sin(heading))
        )


def measure(table: str, n_envs: int, frames: int, max_speed: float, seed: int) -> dict:
    """Time ``frames`` world steps of ``n_envs`` balls; returns the figures as a dict."""
    world = World(load_table(table), n_envs=n_envs)
    rng = np.random.default_rng(seed)
    random_launches(world, rng, max_speed)
    world.step()  # compile (or load the cached kernel) outside the timing
    random_launches(world, rng, max_speed)
    elements = first_sensor(world.geometry)  # the solid ones, that every pass sweeps against
    substeps = world.table.simulation.substeps
    contacts = 0
    ball_frames = 0  # frames of balls in play: a drained ball costs (almost) nothing
    start = time.perf_counter()
    for _ in range(frames):
        ball_frames += int(world.active.sum())
        world.step()
        contacts += int(world.state.contact_count.sum())
    seconds = time.perf_counter() - start
    # One pass per substep plus one more after each contact (the sweep of the remaining time).
    passes = ball_frames * substeps + contacts
    tests = passes * elements
    return {
        "table": table,
        "n_envs": n_envs,
        "frames": frames,
        "elements": elements,
        "substeps": substeps,
        "contacts_per_ball_frame": contacts / ball_frames,
        "seconds": seconds,
        "ball_frames_per_second": ball_frames / seconds,
        "us_per_ball_frame": 1e6 * seconds / ball_frames,
        "ns_per_ball_element_test": 1e9 * seconds / tests,
    }


def measure_env(table: str, obs_type: str, steps: int, seed: int) -> float:
    """Steps per second of one ``Pinball-v0`` env on ``table`` with random actions."""
    import gymnasium as gym

    import pinball_env  # noqa: F401  (registers Pinball-v0)

    env = gym.make("Pinball-v0", table=table, obs_type=obs_type)
    env.reset(seed=seed)
    actions = np.random.default_rng(seed).integers(0, 4, size=steps)
    env.step(0)  # compile outside the timing
    start = time.perf_counter()
    for action in actions:
        _, _, terminated, truncated, _ = env.step(int(action))
        if terminated or truncated:
            env.reset()
    return steps / (time.perf_counter() - start)


def main(argv: list[str] | None = None) -> dict:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--table", default="classic", help="table name or YAML path")
    parser.add_argument("--envs", type=int, default=1024, help="balls stepped together")
    parser.add_argument("--frames", type=int, default=600, help="frames timed")
    parser.add_argument("--max-speed", type=float, default=10.0, help="launch speeds [m/s]")
    parser.add_argument("--env-steps", type=int, default=5000, help="Pinball-v0 steps timed")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--json", type=Path, help="also write the figures to this file")
    args = parser.parse_args(argv)
    result = measure(args.table, args.envs, args.frames, args.max_speed, args.seed)
    table = load_table(args.table)
    if table.plunger is not None and table.flippers:  # a playable table: time the env too
        for obs_type in ("state", "rgb"):
            steps_per_second = measure_env(args.table, obs_type, args.env_steps, args.seed)
            result[f"env_{obs_type}_steps_per_second"] = steps_per_second
    result["machine"] = platform.processor() or platform.machine()
    width = max(map(len, result))
    for key, value in result.items():
        shown = f"{value:.4g}" if isinstance(value, float) else value
        print(f"{key:<{width}}  {shown}")
    print(json.dumps(result))
    if args.json:
        args.json.parent.mkdir(parents=True, exist_ok=True)
        args.json.write_text(json.dumps(result, indent=2) + "\n")
    return result


if __name__ == "__main__":
    main()
