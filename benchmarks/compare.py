"""``--compare REV``: every figure of :mod:`benchmarks.speed` for the checkout and for git
revision REV, measured alternately in the same run.

REV is ``git archive``'d once into ``~/.cache/pinball-benchmark/SHA`` (its ``pinball_env``,
``agents`` and ``configs``); each measurement runs in a fresh process per tree: a copy of
``benchmarks/speed.py`` (the checkout's measuring code, which imports nothing of this folder)
with that tree first on ``PYTHONPATH``, so that ``pinball_env`` and ``agents`` are the tree's,
an old revision's too (one that still had ``pinball_env/tools/benchmark.py`` and no
``benchmarks/``). The two trees alternate measurement by measurement (``--repeats N``: N of
each, the median kept).
"""

import json
import os
import re
import shutil
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

from benchmarks import speed
from benchmarks.speed import Figures, divide, finish, progress, selected

# What --compare unpacks of a revision (those it has), and where.
ARCHIVED = ("pinball_env", "agents", "configs")
CACHE_ENV = "PINBALL_BENCHMARK_CACHE"  # overrides the cache folder

ANSI = re.compile(r"\x1b\[[0-9;]*m")  # the colours of numba's error messages


class RevisionError(ValueError):
    """``--compare``'s revision is not one of the checkout's repository."""


def git(repo: Path, *args: str) -> str:
    """The output of ``git -C repo ARGS``, stripped."""
    return subprocess.run(
        ["git", "-C", str(repo), *args], check=True, capture_output=True, text=True
    ).stdout.strip()


def cache_folder() -> Path:
    """Where ``--compare`` keeps unpacked revisions: ``$PINBALL_BENCHMARK_CACHE``, else
    ``~/.cache/pinball-benchmark`` (or under ``$XDG_CACHE_HOME``)."""
    if os.environ.get(CACHE_ENV):
        return Path(os.environ[CACHE_ENV])
    return Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "pinball-benchmark"


def unpack_revision(repo: Path, rev: str) -> tuple[str, Path]:
    """The full sha of ``rev`` and a folder holding its ``ARCHIVED`` paths (``git archive``),
    made once per sha under :func:`cache_folder` and reused."""
    try:
        sha = git(repo, "rev-parse", "--verify", f"{rev}^{{commit}}")
    except subprocess.CalledProcessError as error:
        raise RevisionError(f"{rev}: not a revision of {repo}: {error.stderr.strip()}") from None
    cache = cache_folder()
    tree = cache / sha
    if (tree / "pinball_env" / "__init__.py").is_file():
        return sha, tree
    cache.mkdir(parents=True, exist_ok=True)
    present = set(git(repo, "ls-tree", "--name-only", sha).split())
    archive = subprocess.run(
        ["git", "-C", str(repo), "archive", "--format=tar", sha,
         *[path for path in ARCHIVED if path in present]],
        check=True, capture_output=True,
    ).stdout  # fmt: skip
    partial = Path(tempfile.mkdtemp(prefix=f".{sha}-", dir=cache))
    subprocess.run(["tar", "-x", "-C", str(partial)], input=archive, check=True)
    try:
        partial.rename(tree)  # whole or not at all
    except OSError:  # another run unpacked it meanwhile
        shutil.rmtree(partial)
    return sha, tree


# A worker's start: without an editable install's import hooks, which would serve a module that
# the tree lacks (an old revision's) from the checkout, and mix the two.
WORKER_BOOT = (
    "import runpy, sys; "
    "sys.meta_path[:] = [f for f in sys.meta_path "
    "if not getattr(f, '__module__', '').startswith('__editable__')]; "
    "sys.path[:] = [p for p in sys.path if not p.startswith('__editable__')]; "
    "sys.argv = sys.argv[1:]; runpy.run_path(sys.argv[0], run_name='__main__')"
)


def run_worker(
    script: Path, tree: Path, name: str, quick: bool, seed: int
) -> tuple[Figures, str | None]:
    """Measure ``name`` in a fresh process: ``script`` (``speed.py``'s code) run with ``tree``
    first on ``PYTHONPATH`` and as the working folder, so that ``pinball_env`` (and ``agents``)
    are that tree's. Returns the figures and the error (None if none)."""
    environment = dict(os.environ)
    environment["PYTHONPATH"] = os.pathsep.join(
        filter(None, [str(tree), environment.get("PYTHONPATH")])
    )
    with tempfile.TemporaryDirectory() as folder:
        out = Path(folder) / "figures.json"
        command = [sys.executable, "-c", WORKER_BOOT, str(script), "--worker", name,
                   "--json-out", str(out), "--seed", str(seed),
                   *(["--quick"] if quick else [])]  # fmt: skip
        done = subprocess.run(command, cwd=tree, env=environment, capture_output=True, text=True)
        if done.returncode != 0 or not out.is_file():
            tail = (done.stderr.strip().splitlines() or ["no output"])[-1]
            return {}, f"exit status {done.returncode}: {tail}"
        report = json.loads(out.read_text())
    expected = (tree / "pinball_env").resolve()
    if Path(report["package"]) != expected:
        raise RuntimeError(f"{name}: the worker imported {report['package']}, not {expected}")
    return report["figures"], report["error"]


def median(values: list[float | None]) -> float | None:
    """The median of the values measured (None if none was)."""
    measured = [value for value in values if value is not None]
    return statistics.median(measured) if measured else None


def compare(
    rev: str, quick: bool = False, seed: int = 0, repeats: int = 1, only: list[str] | None = None
) -> dict:
    """Every figure for the checkout and for ``rev``, each measurement in a fresh process per
    tree, the two alternating (which goes first alternates too), ``repeats`` times each, the
    median kept: :func:`finish`'s dict of the checkout with ``"compare"`` added."""
    checkout = Path(__file__).resolve().parents[1]  # the repository that holds benchmarks/
    sha, tree = unpack_revision(checkout, rev)
    names = [name for name, _ in selected(quick, seed, only)]
    trees = {"checkout": checkout, "rev": tree}
    values: dict[str, dict[str, list[float | None]]] = {"checkout": {}, "rev": {}}
    keys: dict[str, None] = {}  # the figures in the order measured, either tree's
    errors: dict[str, dict[str, str]] = {"checkout": {}, "rev": {}}
    total = len(names) * repeats * 2
    with tempfile.TemporaryDirectory() as folder:
        script = Path(folder) / "pinball_benchmark.py"  # speed.py, whichever package it meets
        shutil.copyfile(speed.__file__, script)
        done = 0
        for repeat in range(repeats):
            for index, name in enumerate(names):
                order = ("checkout", "rev") if (index + repeat) % 2 == 0 else ("rev", "checkout")
                for side in order:
                    progress(done, total, f"{name} ({side})")
                    figures, error = run_worker(script, trees[side], name, quick, seed)
                    if error is not None:
                        errors[side][name] = ANSI.sub("", error).strip()
                    for key, value in figures.items():
                        keys[key] = None
                        values[side].setdefault(key, []).append(value)
                    done += 1
    progress(total, total, "done")
    print(file=sys.stderr)
    ours = finish({key: median(values["checkout"].get(key, [])) for key in keys}, quick)
    theirs = finish({key: median(values["rev"].get(key, [])) for key in keys}, quick)
    del theirs["machine"], theirs["quick"]
    ours["compare"] = {
        "rev": rev,
        "sha": sha,
        "repeats": repeats,
        "figures": theirs,
        "ratios": {key: divide(ours[key], theirs[key]) for key in theirs},
        "errors": errors,
    }
    return ours
