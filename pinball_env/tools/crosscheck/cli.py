"""Cross-check our swept physics against pymunk: ``python -m pinball_env.tools.crosscheck``.

Runs every scenario of :mod:`.scenarios` on both engines and writes a report to ``--out``
(default ``outputs/crosscheck``): a table on the terminal (:mod:`.report`), ``crosscheck.json``
and ``crosscheck.png`` (:mod:`.plots`). Needs the ``crosscheck`` extra (pymunk, matplotlib).
"""

import json
from pathlib import Path
from typing import Any

from pinball_env.tools import command_parser
from pinball_env.tools.crosscheck.plots import plot
from pinball_env.tools.crosscheck.report import headline_figures, print_report
from pinball_env.tools.crosscheck.scenarios import (
    DROP_TIME_TOLERANCE,
    FLIPPER_SPEED_TOLERANCE,
    LOW_SPEED,
    ROUNDING,
    SUBSTEP,
    TIME_TOLERANCE,
    VELOCITY_TOLERANCE,
    ball_ball_hits,
    corner_hits,
    flipper_drop,
    flipper_swing,
    free_run,
    nudge_contact,
    nudge_free_flight,
    plunger_launches,
    post_hits,
    spinner_turns,
    target_hits,
    tunnelling,
    two_balls_cradled,
    wall_bounces,
)


def run(out: Path, trials: int = 100, free_frames: int = 600) -> dict[str, Any]:
    """Run every scenario, print the report, and write crosscheck.json and crosscheck.png."""
    angles = [15.0, 30.0, 45.0, 60.0, 75.0, 90.0]
    report: dict[str, Any] = {
        "tolerances": {
            "low_speed_m_per_s": LOW_SPEED,
            "contact_time_s": TIME_TOLERANCE,
            "drop_contact_time_s": DROP_TIME_TOLERANCE,
            "velocity_relative": VELOCITY_TOLERANCE[0],
            "velocity_absolute_m_per_s": VELOCITY_TOLERANCE[1],
            "flipper_relative": FLIPPER_SPEED_TOLERANCE,
            "rounding": ROUNDING,
            "plunger_gate_time_s": SUBSTEP / 2.0,
        },
        "wall_bounces": wall_bounces([0.5, 1.0, 2.0, 4.0, 8.0, 16.0, 32.0], angles),
        "corner_hits": corner_hits([0.2, 0.4, 0.6, 0.8, 0.95]),
        "post_hits": post_hits([0.0, 0.3, 0.6, 0.9]),
        "bumper_hits": post_hits([0.0, 0.3, 0.6, 0.9], restitution=0.9, kick=1.5),
        "flipper_drop": flipper_drop([0.01, 0.03, 0.1]),
        "flipper_swing": flipper_swing([0.02, 0.035, 0.05, 0.06]),
        "free_run": free_run(free_frames),
        "tunnelling": tunnelling([1.0, 3.0, 10.0, 20.0, 30.0, 50.0, 100.0, 300.0, 1000.0], trials),
        "tilted_bumper_hits": post_hits(
            [0.0, 0.3, 0.6, 0.9], restitution=0.9, kick=1.5, tilted=True
        ),
        "nudge_free_flight": nudge_free_flight(),
        "nudge_contact": nudge_contact(),
        "plunger": plunger_launches([0.1, 0.2, 0.25, 0.5, 0.75, 1.0]),
        "drop_target": target_hits([0.5, 1.0, 2.0, 4.0]),
        "spinner": spinner_turns([0.5, 1.0, 2.0, 4.0]),
        "ball_ball": ball_ball_hits(),
        "two_balls_cradled": two_balls_cradled(),
    }
    report["summary"] = headline_figures(report)
    print_report(report)
    out.mkdir(parents=True, exist_ok=True)
    (out / "crosscheck.json").write_text(json.dumps(report, indent=1) + "\n")
    plot(report, out / "crosscheck.png")
    print(f"\nwrote {out / 'crosscheck.json'} and {out / 'crosscheck.png'}")
    return report


def main(argv: list[str] | None = None) -> dict[str, Any]:
    parser = command_parser("pinball_env.tools.crosscheck", __doc__)
    parser.add_argument("--out", type=Path, default=Path("outputs/crosscheck"))
    parser.add_argument("--trials", type=int, default=100, help="aimed shots per speed")
    parser.add_argument("--frames", type=int, default=600, help="frames of the free run")
    args = parser.parse_args(argv)
    return run(args.out, args.trials, args.frames)


if __name__ == "__main__":
    main()
