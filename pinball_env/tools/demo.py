"""Watch the scripted heuristic play: ``python -m pinball_env.tools.demo``.

Opens a pygame window (the ``render`` extra) and plays games of ``Pinball-v0`` with
:class:`~pinball_env.players.HeuristicPolicy`, printing each game's score. Without a display
(or with ``--headless``) it plays off-screen and saves the last frame as a PNG (matplotlib, the
``plot`` extra). What it needs is checked before a game is played.
"""

import os
import sys
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np

from pinball_env import MAX_EPISODE_STEPS  # importing the package registers Pinball-v0
from pinball_env.envs import unwrapped_pinball
from pinball_env.extras import MissingDependency, require
from pinball_env.players import HeuristicPolicy
from pinball_env.tools import command_parser


def has_display() -> bool:
    """Whether a window can be shown (a desktop session, or an explicit SDL video driver)."""
    if os.environ.get("SDL_VIDEODRIVER"):
        return os.environ["SDL_VIDEODRIVER"] != "dummy"
    if sys.platform.startswith("linux"):
        return bool(os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY"))
    return True


def save_png(frame: np.ndarray, path: Path) -> None:
    """Write an (H, W, 3) uint8 frame to PNG (needs matplotlib, the ``plot`` extra)."""
    require("matplotlib").use("Agg")
    import matplotlib.pyplot as plt

    path.parent.mkdir(parents=True, exist_ok=True)
    plt.imsave(path, frame)


def play(
    table: str = "classic",
    episodes: int = 1,
    seed: int = 0,
    max_steps: int = MAX_EPISODE_STEPS,
    headless: bool = False,
    snapshot: Path | None = None,
) -> list[int]:
    """Play ``episodes`` games with the heuristic; returns their scores."""
    render_mode = "rgb_array" if headless else "human"
    env = gym.make("Pinball-v0", table=table, render_mode=render_mode, max_episode_steps=max_steps)
    policy = HeuristicPolicy(unwrapped_pinball(env).table)
    scores = []
    for episode in range(episodes):
        _, info = env.reset(seed=seed + episode)
        policy.reset()
        steps, done = 0, False
        while not done:
            _, _, terminated, truncated, info = env.step(policy(info))
            steps += 1
            done = terminated or truncated
        scores.append(info["score"])
        end = "game over" if terminated else "time limit"
        print(f"game {episode + 1}: score {info['score']:6d} after {steps} steps ({end})")
    if snapshot is not None and headless:
        frame: Any = env.render()
        assert isinstance(frame, np.ndarray)  # (render_mode="rgb_array")
        save_png(frame, snapshot)
        print(f"wrote {snapshot}")
    env.close()
    return scores


def main(argv: list[str] | None = None) -> list[int]:
    parser = command_parser("pinball_env.tools.demo", __doc__)
    parser.add_argument("--table", default="classic", help="table name or YAML path")
    parser.add_argument("--episodes", type=int, default=1, help="games to play")
    parser.add_argument("--seed", type=int, default=0, help="seed of the first game")
    parser.add_argument(
        "--max-steps", type=int, default=MAX_EPISODE_STEPS, help="time limit per game"
    )
    parser.add_argument("--headless", action="store_true", help="play without a window")
    parser.add_argument(
        "--snapshot", type=Path, default=Path("outputs/demo.png"),
        help="headless: PNG of the last frame",
    )  # fmt: skip
    args = parser.parse_args(argv)
    headless = args.headless or not has_display()
    if headless and not args.headless:
        print("no display found: playing headless")
    try:  # before a game is played, not after it
        require("matplotlib" if headless else "pygame")
    except MissingDependency as error:
        parser.exit(1, f"error: {error}\n")
    return play(args.table, args.episodes, args.seed, args.max_steps, headless, args.snapshot)


if __name__ == "__main__":
    main()
