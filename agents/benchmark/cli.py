"""python -m agents.benchmark: named methods x training seeds under the protocol (see
:mod:`agents.benchmark`)."""

import argparse
from pathlib import Path
from typing import Any

import agents.benchmark
from agents.benchmark.jobs import JobSettings, job_done, run_job, run_local, run_on_cluster
from agents.benchmark.methods import METHODS, TINY_EPISODES
from agents.benchmark.results import aggregate_table, merged_run, merged_runs
from agents.benchmark.shipping import parse_ship, ship
from agents.benchmark.tables import print_table
from agents.config import ConfigError
from pinball_env import protocol
from pinball_env.tools import command_parser


def main(argv: list[str] | None = None) -> dict[str, Any] | None:
    parser = command_parser("agents.benchmark", agents.benchmark.__doc__)
    parser.add_argument(
        "--methods", nargs="+", choices=list(METHODS), default=list(METHODS), metavar="METHOD",
        help=f"the rows (default: all): {', '.join(METHODS)}",
    )  # fmt: skip
    parser.add_argument("--seeds", nargs="+", type=int, default=list(protocol.TRAINING_SEEDS),
                        help="training seeds (default: the protocol's)")  # fmt: skip
    parser.add_argument("--out", type=Path, default=Path("runs/benchmark"), help="results")
    parser.add_argument("--episodes", type=int, help="held-out games per run (default: 100)")
    parser.add_argument("--parallel", type=int, default=1, help="local jobs at once")
    parser.add_argument("--address", help="a Ray cluster to run the jobs on (auto, HOST:PORT)")
    parser.add_argument("--tiny", action="store_true", help="tiny settings, for tests")
    parser.add_argument("--job", help=argparse.SUPPRESS)  # METHOD:SEED, one job (run_local's)
    parser.add_argument("--table-only", action="store_true", help="aggregate what is done")
    parser.add_argument("--merge", nargs="+", type=Path, default=[], metavar="BENCHMARK_JSON",
                        help="runs of earlier benchmarks that OUT lacks")  # fmt: skip
    parser.add_argument("--ship", nargs="+", default=[], metavar="METHOD[=NAME]",
                        help="make each method's best run a pretrained agent (NAME)")  # fmt: skip
    parser.add_argument("--ship-from-out", action="store_true",
                        help="--ship the best run in OUT, not of merged ones")  # fmt: skip
    args = parser.parse_args(argv)
    if args.episodes is None:
        args.episodes = TINY_EPISODES if args.tiny else len(protocol.EVAL_SEEDS)
    if args.parallel < 1 or not 1 <= args.episodes <= len(protocol.EVAL_SEEDS):
        parser.error("--parallel must be >= 1 and --episodes in 1..100")
    if any(seed < 0 for seed in args.seeds):
        parser.error("seeds must be >= 0")
    if args.ship and args.tiny:
        parser.error("--ship ships agents trained under the protocol, not --tiny ones")
    settings = JobSettings(args.out.resolve(), args.episodes, args.tiny)
    try:
        ships = [parse_ship(text) for text in args.ship]
        if args.job is not None:
            name, _, seed = args.job.partition(":")
            run_job(name, int(seed), settings)
            return None
        args.methods, args.seeds = list(dict.fromkeys(args.methods)), sorted(set(args.seeds))
        jobs = [(name, seed) for name in args.methods
                for seed in (args.seeds if METHODS[name].trained else [0])]  # fmt: skip
        merged = merged_runs(args.merge, args.methods, settings)
        todo = [job for job in jobs
                if not job_done(*job, settings) and merged_run(merged, *job) is None]  # fmt: skip
        if todo and not args.table_only:
            print(f"{len(jobs) - len(todo)} of {len(jobs)} jobs done already; running {len(todo)}")
            if args.address:
                run_on_cluster(todo, settings, args.address)
            else:
                run_local(todo, settings, args.parallel)
        table = aggregate_table(args.methods, args.seeds, settings, merged)
        for name, ship_as in ships:
            ship(name, args.seeds, settings, ship_as, merged=merged, from_out=args.ship_from_out)
    except ConfigError as error:
        parser.exit(2, f"error: {error}\n")
    print_table(table)
    print(f"-> {settings.out}/benchmark.json, benchmark.csv, runs.csv, scores.png, profiles.png")
    return table
