"""How long a new user's first game takes: for each env, a fresh process on an empty numba
cache (``NUMBA_CACHE_DIR``, a new temporary folder: what a fresh machine has) makes the env,
resets it and plays its first step, which compiles the step loop, then a second process on the
same cache plays again (what every later run pays). The figures behind the compile times the
getting-started page gives.

    python -m benchmarks.first_compile [--envs Pinball-v2 Pinball-v3] [--json FILE]

The envs are timed in turn, each on its own empty cache, so each figure is that env's whole
compile (the kernels the envs share are compiled again for each).
"""

import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

PHASES = ("import", "make", "reset", "first step")


def first_game_seconds(env_id: str) -> dict[str, float]:
    """The seconds this process takes to import the package, make ``env_id``, reset it and
    play its first step (a compile where numba's cache is empty)."""
    start = time.perf_counter()
    import gymnasium as gym

    import pinball_env  # noqa: F401  (registers the envs)

    seconds = {"import": time.perf_counter() - start}
    start = time.perf_counter()
    env = gym.make(env_id)
    seconds["make"] = time.perf_counter() - start
    start = time.perf_counter()
    env.reset(seed=0)
    seconds["reset"] = time.perf_counter() - start
    start = time.perf_counter()
    env.step(env.action_space.sample())
    seconds["first step"] = time.perf_counter() - start
    env.close()
    return seconds


def timed_process(env_id: str, cache: Path) -> dict[str, float]:
    """:func:`first_game_seconds` in a new process whose numba cache is ``cache``."""
    code = (
        "import json, sys; from benchmarks.first_compile import first_game_seconds; "
        f"print(json.dumps(first_game_seconds({env_id!r})))"
    )
    done = subprocess.run(
        [sys.executable, "-c", code], env={**os.environ, "NUMBA_CACHE_DIR": str(cache)},
        capture_output=True, text=True, check=True, cwd=Path(__file__).parent.parent,
    )  # fmt: skip
    return json.loads(done.stdout.strip().splitlines()[-1])


def measure(env_ids: list[str]) -> dict:
    """Each env's phases on an empty cache (``cold``) and again on the cache it left
    (``warm``), with the date, the Python and the machine's cores."""
    result: dict = {
        "date": time.strftime("%Y-%m-%d"), "python": sys.version.split()[0],
        "cpus": os.cpu_count(), "envs": {},
    }  # fmt: skip
    for env_id in env_ids:
        with tempfile.TemporaryDirectory() as cache:
            cold = timed_process(env_id, Path(cache))
            warm = timed_process(env_id, Path(cache))
        result["envs"][env_id] = {"cold": cold, "warm": warm}
        print(f"{env_id}: first step {cold['first step']:.0f} s on an empty cache, "
              f"{warm['first step']:.1f} s from it", file=sys.stderr, flush=True)  # fmt: skip
    return result


def table(result: dict) -> str:
    """The figures as text: a row per env and cache, a column per phase, in seconds."""
    lines = [f"{'env':<20} {'cache':<6} " + " ".join(f"{phase:>11}" for phase in PHASES)]
    for env_id, runs in result["envs"].items():
        for cache, seconds in runs.items():
            cells = " ".join(f"{seconds[phase]:>11.1f}" for phase in PHASES)
            lines.append(f"{env_id:<20} {cache:<6} {cells}")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> dict:
    from pinball_env.tools import command_parser  # (not at the top: the timed import is first)

    command = command_parser("benchmarks.first_compile", __doc__)
    command.add_argument("--envs", nargs="+", default=["Pinball-v2", "Pinball-v3"])
    command.add_argument("--json", type=Path, help="also write the figures to this file")
    args = command.parse_args(argv)
    result = measure(args.envs)
    print(table(result))
    print(json.dumps(result))
    if args.json:
        args.json.write_text(json.dumps(result, indent=2) + "\n")
    return result


if __name__ == "__main__":
    main()
