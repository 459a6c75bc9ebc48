"""Evaluation rollouts: whole games on fixed seeds that training never used.

    python -m agents.evaluate --model RUN_OR_ZIP --episodes 100 [--video game.mp4] [--curve]
    python -m agents.evaluate --policy heuristic --episodes 100
    python -m agents.evaluate --model RUN_OR_ZIP --watch [--episodes 3]

Each game is played to its end (the last ball drained, or the two-minute time limit), on seeds
``seed .. seed + episodes - 1`` (``--seed``, by default the config's ``eval_seed``, 100000). A
model plays through the env chain it was trained on (frame skip, frame stacking, frozen
``VecNormalize`` statistics), choosing its actions deterministically; ``random`` (uniform over
the actions, every frame) and ``heuristic`` (``pinball_env.heuristic.HeuristicPolicy``) play
frame by frame. Written to ``--out`` (default: ``RUN/eval`` for a run, ``evals/POLICY``):

- ``episodes.csv``: per game the seed, score, return (the env's reward, shaping included),
  length (frames), balls lost and whether the time limit truncated it;
- ``summary.json``: mean, std and 95% confidence interval of the score (normal approximation),
  mean return and length, share truncated;
- with ``--video PATH``: the first game as an MP4 or GIF (by the suffix), score on screen,
  every frame of it (every third in a GIF), those a step runs on included;
- with ``--curve`` (a run): ``learning_curve.png``, the training games' mean score against
  frames, with the random and heuristic baselines drawn in (from the run's report, or played
  on the same games, their results in ``OUT/random`` and ``OUT/heuristic``).

``--watch`` plays the games in a window instead, at real speed (every frame shown at the
table's frame rate), printing each score; close the window or press Ctrl-C to stop.

``report(run)`` (``python -m agents.train ... --report``) does all of it for a run and its two
baselines and writes ``report.json``. Models load through ``agents.policy.load_policy``: a run
folder, a model or checkpoint zip (copied alone, it carries its config and statistics), or an
RLlib run or checkpoint folder (``agents.rllib``), which plays the same games through its
checkpoint's RL module and observation filter. Models are pickles: load only models you trust.
"""

import argparse
import csv
import json
import math
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from agents.common import BASELINES, Policy, baseline_policy, make_env
from agents.config import (
    AnyConfig,
    ConfigError,
    TrainConfig,
    check_evaluation_seeds,
    config_from_dict,
    load_run_config,
)
from agents.policy import ObsNormalization, load_policy

# The baselines play frame by frame, on the model's table (or layouts) with the default rewards.
BASELINE_KWARGS = ("table", "balls", "num_layouts", "start_layout", "difficulty")


def baseline_config(name: str, config: AnyConfig | None = None) -> TrainConfig:
    """The config a baseline plays with: the env, table (or layouts) and balls of ``config``,
    one frame a step."""
    kwargs = {} if config is None else config.env.kwargs
    env = {"kwargs": {key: kwargs[key] for key in BASELINE_KWARGS if key in kwargs}}
    if config is not None:
        env["id"] = config.env.id
    seed = {} if config is None else {"eval_seed": config.eval_seed}
    return config_from_dict({"env": env, **seed}, f"<{name} baseline>")


def model_policy(model: Any) -> Policy:
    return lambda obs, infos: model.predict(obs, deterministic=True)[0]


def rollouts(
    venv: Any, policy: Policy, seeds: list[int], layouts: list[int] | None = None
) -> list[dict]:
    """One whole game per env of ``venv`` (whose env i was seeded with ``seeds[i]``), played by
    ``policy`` (on layout ``layouts[i]`` of PinballProcgen-v0); a row of metrics per game."""
    n = venv.num_envs
    if layouts is not None:
        venv.unwrapped.set_options({"layout": list(layouts)})
    obs = venv.reset()
    infos = list(venv.unwrapped.reset_infos)  # the wrappers keep none
    rows: list[dict | None] = [None] * n
    returns = np.zeros(n)
    balls = venv.get_attr("game")[0].balls_per_game
    while any(row is None for row in rows):
        obs, rewards, dones, infos = venv.step(policy(obs, infos))
        playing = np.array([row is None for row in rows])
        returns[playing] += rewards[playing]  # raw: an evaluation VecNormalize leaves them
        for env in np.flatnonzero(dones & playing):
            info = infos[env]
            rows[env] = {
                "seed": seeds[env],
                **({} if layouts is None else {"layout": int(info["layout"])}),
                "score": int(info["score"]),
                "return": round(float(returns[env]), 6),
                "length": int(info["frames"]),
                "balls_lost": int(balls - info["balls_left"]),
                "truncated": bool(info.get("TimeLimit.truncated", False)),
            }
    return rows  # type: ignore[return-value]


def summarize(rows: list[dict]) -> dict[str, Any]:
    """Mean, std and 95% confidence interval (normal approximation) of the score, and means."""
    scores = np.array([row["score"] for row in rows], dtype=np.float64)
    n = len(scores)
    std = float(scores.std(ddof=1)) if n > 1 else 0.0
    half = 1.96 * std / math.sqrt(n) if n > 1 else 0.0
    mean = float(scores.mean())
    return {
        "episodes": n,
        "score_mean": mean,
        "score_std": std,
        "score_ci95": [mean - half, mean + half],
        "return_mean": float(np.mean([row["return"] for row in rows])),
        "length_mean": float(np.mean([row["length"] for row in rows])),
        "truncated_share": float(np.mean([row["truncated"] for row in rows])),
    }


def evaluate(
    policy: str | None = None,
    model_path: Path | None = None,
    table: str | None = None,
    episodes: int = 100,
    seed: int | None = None,
    out: Path | None = None,
    video: Path | None = None,
    curve: bool = False,
    like: AnyConfig | None = None,
    watch: bool = False,
) -> dict[str, Any]:
    """Play ``episodes`` games with a model or a baseline, write the results into ``out``;
    returns the summary. A baseline plays on ``table``, or on the env (and layouts) of the
    config ``like``. With ``watch``, the games are shown in a window instead (nothing is
    written)."""
    if (policy is None) == (model_path is None):
        raise ConfigError("give a model or a policy (random or heuristic), not both")
    if episodes < 1:
        raise ConfigError(f"episodes must be >= 1, got {episodes}")
    if policy is not None:
        if policy not in BASELINES:
            raise ConfigError(f"unknown policy {policy!r} (known: {', '.join(BASELINES)})")
        if like is None:
            like = config_from_dict({"env": {"kwargs": {"table": table} if table else {}}})
        config = baseline_config(policy, like)
        stats, name = None, policy
        out = out or Path("evals") / policy

        def make_policy(venv: Any, seed: int) -> Policy:
            return baseline_policy(policy, venv, seed)

    else:
        import torch

        name = str(model_path)
        out = out or (model_path if model_path.is_dir() else model_path.parent) / "eval"
        trained = load_policy(model_path)
        config, stats = trained.config, trained.normalization
        torch.set_num_threads(config.torch_threads)

        def make_policy(venv: Any, seed: int) -> Policy:
            return lambda obs, infos: trained.act(obs)

    first = config.eval_seed if seed is None else seed
    if model_path is not None:
        check_evaluation_seeds(config, first, episodes)
    if watch:
        return watch_games(config, stats, make_policy, first, episodes)
    seeds = list(range(first, first + episodes))
    venv = make_env(config, num_envs=episodes, seed=first, frozen=stats)
    rows = rollouts(venv, make_policy(venv, first), seeds)
    venv.close()
    summary = {"policy": name, "seeds": [first, first + episodes - 1], **summarize(rows)}
    write_results(out, rows, summary)
    if video is not None:
        record_video(config, stats, make_policy, first, video)
    if curve and model_path is not None and model_path.is_dir():
        baselines = baselines_for(model_path) or {  # played now on the same games
            baseline: evaluate(
                policy=baseline, episodes=episodes, seed=first, out=out / baseline, like=config
            )["score_mean"]
            for baseline in BASELINES
        }  # fmt: skip
        plot_learning_curve(model_path, out / "learning_curve.png", baselines)
    print(
        f"{name}: score {summary['score_mean']:.0f} (95% CI {summary['score_ci95'][0]:.0f}-"
        f"{summary['score_ci95'][1]:.0f}) over {episodes} games, mean length "
        f"{summary['length_mean']:.0f} frames, {summary['truncated_share']:.0%} truncated "
        f"-> {out}"
    )
    return summary


def write_results(out: Path, rows: list[dict], summary: dict[str, Any]) -> None:
    out.mkdir(parents=True, exist_ok=True)
    with open(out / "episodes.csv", "w", newline="") as file:
        writer = csv.DictWriter(file, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    (out / "summary.json").write_text(json.dumps(summary, indent=1))


def record_video(
    config: AnyConfig, stats: ObsNormalization | None,
    make_policy: Callable[[Any, int], Policy], seed: int, path: Path,
) -> None:  # fmt: skip
    """The game on ``seed`` as a video (MP4, or GIF by the suffix), the scoreboard in view;
    ``make_policy(venv, seed)`` gives the player."""
    import imageio.v2 as imageio

    venv = make_env(config, num_envs=1, seed=seed, frozen=stats, render=True)
    act = make_policy(venv, seed)
    game = venv.get_attr("game")[0]
    fps = game.table.simulation.frame_rate  # every frame is recorded, those a step runs on too
    stride = max(1, round(fps / 20)) if path.suffix.lower() == ".gif" else 1  # small GIFs
    path.parent.mkdir(parents=True, exist_ok=True)
    if path.suffix.lower() == ".gif":
        writer = imageio.get_writer(path, duration=1000 * stride / fps, loop=0)
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
    make_policy: Callable[[Any, int], Policy], first: int, episodes: int,
    fps: float | None = None,
) -> dict[str, Any]:  # fmt: skip
    """Play the games on seeds ``first..first + episodes - 1`` in a pygame window at real
    speed (or ``fps`` frames per second): every frame, those a step runs on included, at the
    table's frame rate. Closing the window or Ctrl-C stops."""
    from pinball_env.render import Window

    venv = make_env(config, num_envs=1, seed=first, frozen=stats, render=True)
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


def baselines_for(run: Path) -> dict[str, float]:
    """The baselines' mean scores from a run's report, when it has one."""
    report = run / "report.json"
    if not report.is_file():
        return {}
    data = json.loads(report.read_text())
    return {name: data[name]["score_mean"] for name in BASELINES if name in data}


def plot_learning_curve(run: Path, out: Path, baselines: dict[str, float]) -> None:
    """The training games' mean score (``rollout/ep_score_mean``) against frames played, and
    the validation games' (``validation.csv``) when the run has them."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from agents.train import Validation, progress_rows

    config = load_run_config(run)
    rows = [row for row in progress_rows(run) if row.get("rollout/ep_score_mean")]
    if not rows:
        print(f"no learning curve: {run} has no finished training games logged yet")
        return
    skip = config.env.frame_skip  # runs from before time/frames was logged: steps x skip
    frames = [float(row.get("time/frames") or float(row["time/total_timesteps"]) * skip)
              for row in rows]  # fmt: skip
    scores = [float(row["rollout/ep_score_mean"]) for row in rows]
    fig, ax = plt.subplots(figsize=(6, 3.5), dpi=100)
    ax.plot(frames, scores, label=f"{config.algo.upper()} (training games, last 100)")
    checks = Validation(config, run)  # the run's validations, read back (none: no file)
    if checks.rows:
        ax.plot([row["frames"] for row in checks.rows],
                [row["score_mean"] for row in checks.rows], "o", markersize=4,
                label=f"validation games ({config.validate_episodes})")  # fmt: skip
        chosen = checks.best  # the run's model
        ax.plot(chosen["frames"], chosen["score_mean"], "*", color="black", markersize=11,
                label=f"the model (at {chosen['steps']:,} steps)")  # fmt: skip
    for (name, score), style in zip(baselines.items(), ("--", ":"), strict=False):
        ax.axhline(score, linestyle=style, color="grey", label=f"{name} (evaluation)")
    ax.set_xlabel("frames played (1/60 s each)")
    ax.set_ylabel("game score")
    ax.set_title(f"{config.env.id} on {config.env.kwargs.get('table', 'classic')}")
    ax.legend(loc="lower right", fontsize=8)
    ax.grid(alpha=0.3)
    fig.tight_layout()
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out)
    plt.close(fig)


def report(run: Path, episodes: int = 100) -> dict[str, Any]:
    """Evaluate a run's model and both baselines on the same seeds; write ``report.json``,
    ``learning_curve.png`` and ``game.gif`` into the run folder."""
    config = load_run_config(run)
    results = {}
    for name in BASELINES:
        out = run / "eval" / name
        results[name] = evaluate(
            policy=name, episodes=episodes, seed=config.eval_seed, out=out, like=config
        )
    results["model"] = evaluate(
        model_path=run, episodes=episodes, out=run / "eval" / "model", video=run / "game.gif"
    )
    (run / "report.json").write_text(json.dumps(results, indent=1))
    plot_learning_curve(run, run / "learning_curve.png", baselines_for(run))
    print(f"report: {run / 'report.json'}, {run / 'learning_curve.png'}, {run / 'game.gif'}")
    return results


def main(argv: list[str] | None = None) -> dict[str, Any]:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    who = parser.add_mutually_exclusive_group(required=True)
    who.add_argument("--model", type=Path, help="a run folder or model zip (or RLlib checkpoint)")
    who.add_argument("--policy", choices=BASELINES, help="a baseline")
    parser.add_argument("--table", help="the baselines' table (default: classic)")
    parser.add_argument("--episodes", type=int, default=100, help="games to play")
    parser.add_argument("--seed", type=int, help="first game's seed (default: eval_seed)")
    parser.add_argument("--out", type=Path, help="where to write the results")
    parser.add_argument("--video", type=Path, help="record the first game (.mp4 or .gif)")
    parser.add_argument("--curve", action="store_true", help="draw a run's learning curve")
    parser.add_argument("--watch", action="store_true", help="show the games in a window")
    args = parser.parse_args(argv)
    try:
        return evaluate(
            policy=args.policy, model_path=args.model, table=args.table, episodes=args.episodes,
            seed=args.seed, out=args.out, video=args.video, curve=args.curve, watch=args.watch,
        )  # fmt: skip
    except ConfigError as error:
        parser.exit(2, f"error: {error}\n")


if __name__ == "__main__":
    main()
