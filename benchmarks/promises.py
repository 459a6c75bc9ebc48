"""The times the README promises, measured: its quick start's two commands, each run as written
(without its ``pip install``, which depends on the network) from the repository root, timed
wall-clock, and the quick start's three scores read from the report it writes. The figures
behind the minutes the README and the getting-started page give.

    python -m benchmarks.promises [--only train|tests] [--cold] [--json FILE]

The training writes its run folder into a temporary folder (``--runs``), not ``runs/``.
``--cold`` runs on an empty numba cache (``NUMBA_CACHE_DIR``, a new temporary folder): what a
fresh machine pays once, the kernels' compile included. Run it alone on the machine: the
tests and the training each use every core.
"""

import json
import os
import shlex
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).parent.parent
COMMANDS = ("train", "tests")


def quick_start_commands(readme: Path = ROOT / "README.md") -> dict[str, list[str]]:
    """The README's quick start: its two commands after their ``pip install ... &&``, as
    argument lists (``train``: the first, ``tests``: the second)."""
    section = readme.read_text().split("## Quick start", 1)[1]
    block = section.split("```bash", 1)[1].split("```", 1)[0]
    commands = [line.split("&&", 1)[1] for line in block.splitlines() if "&&" in line]
    if len(commands) != 2:
        raise ValueError(f"{readme}: expected two 'pip install ... && COMMAND' lines")
    return dict(zip(COMMANDS, (shlex.split(command) for command in commands), strict=True))


def timed(argv: list[str], env: dict[str, str]) -> float:
    """Runs ``argv`` from the repository root (its output to this terminal) and returns its
    wall-clock seconds; a command that fails stops the measurement."""
    start = time.perf_counter()
    subprocess.run(argv, cwd=ROOT, env=env, check=True)
    return time.perf_counter() - start


def reported_scores(runs: Path) -> dict[str, float]:
    """The mean scores of the report the training wrote under ``runs``."""
    (report,) = runs.glob("*/report.json")
    entries = json.loads(report.read_text()).items()
    return {name: round(entry["score_mean"]) for name, entry in entries
            if isinstance(entry, dict) and "score_mean" in entry}  # fmt: skip


def measure(which: tuple[str, ...] = COMMANDS, cold: bool = False) -> dict:
    """The seconds of each of the quick start's commands in ``which``, with the date, the
    Python, the machine's cores and the quick start's scores."""
    commands = quick_start_commands()
    result: dict = {
        "date": time.strftime("%Y-%m-%d"), "python": sys.version.split()[0],
        "cpus": os.cpu_count(), "numba_cache": "empty" if cold else "as found", "seconds": {},
    }  # fmt: skip
    with tempfile.TemporaryDirectory() as scratch:
        env = {**os.environ, "SDL_VIDEODRIVER": "dummy", "SDL_AUDIODRIVER": "dummy"}
        if cold:
            env["NUMBA_CACHE_DIR"] = str(Path(scratch, "numba"))
        for name in which:
            argv = [sys.executable if commands[name][0] == "python" else commands[name][0]]
            argv += commands[name][1:]
            if name == "train":
                argv += ["--runs", str(Path(scratch, "runs"))]
            print(f"promises: timing {shlex.join(argv)}", file=sys.stderr, flush=True)
            result["seconds"][name] = round(timed(argv, env), 1)
            if name == "train":
                result["scores"] = reported_scores(Path(scratch, "runs"))
    return result


def main(argv: list[str] | None = None) -> dict:
    from pinball_env.tools import command_parser

    command = command_parser("benchmarks.promises", __doc__)
    command.add_argument("--only", choices=COMMANDS, help="time one of the two commands")
    command.add_argument("--cold", action="store_true", help="on an empty numba cache")
    command.add_argument("--json", type=Path, help="also write the figures to this file")
    args = command.parse_args(argv)
    result = measure((args.only,) if args.only else COMMANDS, cold=args.cold)
    for name, seconds in result["seconds"].items():
        minutes, rest = divmod(seconds, 60)
        print(f"{name}: {int(minutes)} min {rest:.0f} s")
    print(json.dumps(result))
    if args.json:
        args.json.write_text(json.dumps(result, indent=2) + "\n")
    return result


if __name__ == "__main__":
    main()
