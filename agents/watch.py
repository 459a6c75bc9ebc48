"""Games shown: a game recorded as a video (MP4 or GIF, every frame) and games played in a window
at real speed; each with a player ``make_policy(venv, seed)`` (``agents.rollouts.Player``'s
``policy``) through the env chain of a config."""

import math
from collections.abc import Callable
from pathlib import Path
from typing import Any

from agents.config import AnyConfig
from agents.envs import make_env_chain
from agents.gif import GifWriter
from agents.policy import ObsNormalization
from agents.rollouts import VecPolicy


def record_video(
    config: AnyConfig, stats: ObsNormalization | None,
    make_policy: Callable[[Any, int], VecPolicy], seed: int, path: Path,
) -> None:  # fmt: skip
    """The game on ``seed`` as a video (MP4, or GIF by the suffix), the scoreboard in view;
    ``make_policy(venv, seed)`` gives the player."""
    import imageio.v2 as imageio

    venv = make_env_chain(config, num_envs=1, seed=seed, frozen=stats, render=True)
    act = make_policy(venv, seed)
    game = venv.get_attr("game")[0]
    fps = game.table.simulation.frame_rate  # every frame is recorded, those a step runs on too
    stride = max(1, round(fps / 20)) if path.suffix.lower() == ".gif" else 1  # small GIFs
    path.parent.mkdir(parents=True, exist_ok=True)
    writer: Any
    if path.suffix.lower() == ".gif":
        writer = GifWriter(path, duration_ms=1000 * stride / fps)
    else:
        writer = imageio.get_writer(path, fps=fps, macro_block_size=1)
    obs = venv.reset()
    infos = list(venv.unwrapped.reset_infos)  # the wrappers keep none
    frames = 0

    def record() -> None:  # every frame, those a step runs on (frame skip, skip_above) too
        nonlocal frames
        if frames % stride == 0:
            writer.append_data(venv.get_images()[0])
        frames += 1

    with writer:  # frames are written as they come: a whole game would not fit in memory
        record()
        game.on_frame = record
        while True:
            obs, _, dones, infos = venv.step(act(obs, infos))
            if dones[0]:
                break
    venv.close()
    print(f"video: {path} ({math.ceil(frames / stride)} frames)")


def watch_games(
    config: AnyConfig, stats: ObsNormalization | None,
    make_policy: Callable[[Any, int], VecPolicy], first: int, episodes: int,
    fps: float | None = None,
) -> dict[str, Any]:  # fmt: skip
    """Play the games on seeds ``first..first + episodes - 1`` in a pygame window at real
    speed (or ``fps`` frames per second): every frame, those a step runs on included, at the
    table's frame rate. Closing the window or Ctrl-C stops."""
    from pinball_env.render import Window

    venv = make_env_chain(config, num_envs=1, seed=first, frozen=stats, render=True)
    act = make_policy(venv, first)
    game = venv.get_attr("game")[0]
    window = None
    closed = False

    def show() -> None:  # after each frame's physics
        nonlocal window, closed
        frame = venv.get_images()[0]
        if window is None:
            rate = fps or game.table.simulation.frame_rate
            window = Window((frame.shape[1], frame.shape[0]), rate, f"Pinball: {config.label}")
        window.show(frame)
        closed = closed or window.quit_requested()

    scores = []
    game.on_frame = show
    try:
        for episode in range(episodes):
            venv.seed(first + episode)
            obs = venv.reset()
            infos = list(venv.unwrapped.reset_infos)  # the wrappers keep none
            done = False
            while not (done or closed):
                obs, _, dones, infos = venv.step(act(obs, infos))
                done = bool(dones[0])
            if closed:
                break
            scores.append(int(infos[0]["score"]))
            print(f"game {episode + 1} (seed {first + episode}): score {scores[-1]}")
    except KeyboardInterrupt:
        pass
    finally:
        if window is not None:
            window.close()
        venv.close()
    return {"episodes": len(scores), "scores": scores}
