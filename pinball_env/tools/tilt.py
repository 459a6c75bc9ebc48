"""How the tilt answers nudging: ``python -m pinball_env.tools.tilt``.

Plays the nudge patterns of the tilt's tests on each env (a plunged ball, seed 0, a shove every
``every`` frames: one way, or left and right in turn) and prints the time to the first warning
and to the tilt of each, then the heuristic's nudges, warnings and tilts over the protocol's
held-out games (``--games``; sticky actions), as a table and as JSON (``--json``)::

    python -m pinball_env.tools.tilt --envs Pinball-v1 Pinball-v2 --games 100 --json tilt.json
"""

import json
from pathlib import Path
from typing import Any

import gymnasium as gym

from pinball_env.envs import unwrapped_pinball
from pinball_env.game.actions import action_meanings
from pinball_env.players import HeuristicPolicy
from pinball_env.protocol import EVAL_SEEDS, GAME_OPTIONS, REPEAT_ACTION_PROBABILITY
from pinball_env.tools import command_parser

MEANINGS = action_meanings(cabinet=True)
PLUNGER = MEANINGS.index("PLUNGER")
NUDGES = {name: MEANINGS.index(name) for name in ("NUDGE_LEFT", "NUDGE_RIGHT", "NUDGE_UP")}
# The patterns: a name and the nudges taken in turn, each shoving every `every` frames.
PATTERNS: dict[str, list[int]] = {
    **{name: [action] for name, action in NUDGES.items()},
    "NUDGE_LEFT/RIGHT": [NUDGES["NUDGE_LEFT"], NUDGES["NUDGE_RIGHT"]],
}
# The shoves' spacings [frames]: the fastest the cabinet allows (0.25 s) to a bob's period.
EVERY = (15, 20, 30, 38)


def pattern_times(env_id: str, nudges: list[int], every: int, seconds: float) -> dict[str, Any]:
    """Play ``env_id`` from a plunged ball (seed 0), shoving with ``nudges[k % len(nudges)]``
    every ``every`` frames from frame 0 for ``seconds``: the times [s] of the first warning and
    of the tilt (None: none) and the warnings standing at the end."""
    env = gym.make(env_id)
    env.reset(seed=0)
    for _ in range(60):  # pull the plunger back ...
        env.step(PLUNGER)
    env.step(0)  # ... and let it go: the ball in play
    first_warning = tilt = None
    info: dict[str, Any] = {}
    for frame in range(round(seconds * 60)):
        action = nudges[(frame // every) % len(nudges)] if frame % every == 0 else 0
        _, _, terminated, _, info = env.step(action)
        if info["tilt_warnings"] and first_warning is None:
            first_warning = frame / 60
        if info["tilted"]:
            tilt = frame / 60
            break
        if terminated:
            break
    env.close()
    return {"warning": first_warning, "tilt": tilt, "warnings": int(info["tilt_warnings"])}


def heuristic_games(env_id: str, games: int) -> dict[str, Any]:
    """The heuristic on the first ``games`` of the protocol's held-out games of ``env_id``
    (sticky actions): its mean score, the nudges it pressed, the frames with a warning standing,
    the most warnings ever standing and the tilts."""
    env = gym.make(env_id, **GAME_OPTIONS, repeat_action_probability=REPEAT_ACTION_PROBABILITY)
    policy = HeuristicPolicy(unwrapped_pinball(env).table)
    totals = {"games": 0, "score": 0.0, "nudges": 0, "warned_frames": 0, "most_warnings": 0,
              "tilts": 0}  # fmt: skip
    for seed in list(EVAL_SEEDS)[:games]:
        _, info = env.reset(seed=seed)
        policy.reset()
        done, tilted = False, False
        while not done:
            action = policy(info)
            totals["nudges"] += int(action) >> 3 > 0
            _, _, terminated, truncated, info = env.step(action)
            done = terminated or truncated
            totals["warned_frames"] += info["tilt_warnings"] > 0
            totals["most_warnings"] = max(totals["most_warnings"], int(info["tilt_warnings"]))
            totals["tilts"] += info["tilted"] and not tilted
            tilted = bool(info["tilted"])
        totals["games"] += 1
        totals["score"] += info["score"]
    env.close()
    totals["score"] /= max(1, totals["games"])
    return totals


def main(argv: list[str] | None = None) -> dict[str, Any]:
    parser = command_parser("pinball_env.tools.tilt", __doc__)
    parser.add_argument("--envs", nargs="+", default=["Pinball-v1", "Pinball-v2"])
    parser.add_argument("--seconds", type=float, default=20.0, help="each pattern's length")
    parser.add_argument("--games", type=int, default=0, help="heuristic games (default: none)")
    parser.add_argument("--json", type=Path, help="write the results here too")
    args = parser.parse_args(argv)
    if args.seconds <= 0 or not 0 <= args.games <= len(EVAL_SEEDS):
        parser.error(f"--seconds must be > 0 and --games in [0, {len(EVAL_SEEDS)}]")
    results: dict[str, Any] = {}
    print(f"{'env':11} {'pattern':17} {'every':>5}  {'warning [s]':>11}  {'tilt [s]':>8}")
    for env_id in args.envs:
        rows = results.setdefault(env_id, {"patterns": []})["patterns"]
        for name, nudges in PATTERNS.items():
            for every in EVERY:
                times = pattern_times(env_id, nudges, every, args.seconds)
                rows.append({"pattern": name, "every": every, **times})
                warning, tilt = (
                    "-" if t is None else f"{t:.2f}" for t in (times["warning"], times["tilt"])
                )
                print(f"{env_id:11} {name:17} {every:5}  {warning:>11}  {tilt:>8}")
        if args.games:
            results[env_id]["heuristic"] = heuristic_games(env_id, args.games)
            print(f"{env_id} heuristic: {results[env_id]['heuristic']}")
    if args.json:
        args.json.write_text(json.dumps(results, indent=1))
        print(f"-> {args.json}")
    return results


if __name__ == "__main__":
    main()
