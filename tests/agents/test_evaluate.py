"""Evaluation (agents.evaluate): deterministic scores, refused seeds, baselines, videos, the
learning curve and watching the games."""

import csv
import json

import pytest

from agents import evaluate
from agents.policy import load_policy
from agents.runs import latest_checkpoint
from pinball_env.table import load_table
from tests.agents.tiny_runs import ROOT, strip_agent_entry, tiny_run


def test_evaluation_refuses_training_seeds_and_missing_statistics(tmp_path, capsys):
    run = tiny_run(ROOT / "configs/agents/ppo.yaml", tmp_path / "runs")  # trains on seeds 0-1
    with pytest.raises(SystemExit):
        evaluate.main(["--model", str(run), "--episodes", "2", "--seed", "1"])
    assert "seeds 1..2 overlap the training seeds 0..1" in capsys.readouterr().err
    # A zip saved before models carried their statistics, without the pickle beside it:
    strip_agent_entry(run / "model.zip")
    (run / "model_vecnormalize.pkl").unlink()
    with pytest.raises(SystemExit):
        evaluate.main(["--model", str(run), "--episodes", "1"])
    assert "VecNormalize statistics are missing" in capsys.readouterr().err


def test_evaluation_is_deterministic_for_a_model_and_seeds(tmp_path):
    run = tiny_run(ROOT / "configs/agents/ppo.yaml", tmp_path / "runs")
    for out in ("a", "b"):
        evaluate.main(["--model", str(run), "--episodes", "3", "--out", str(tmp_path / out)])
    assert (tmp_path / "a/episodes.csv").read_text() == (tmp_path / "b/episodes.csv").read_text()


def test_baselines_evaluate_with_video(tmp_path):
    summary = evaluate.main(
        ["--policy", "heuristic", "--env", "Pinball-v0", "--episodes", "2", "--out",
         str(tmp_path / "h"), "--video", str(tmp_path / "game.gif")]
    )  # fmt: skip
    assert summary["policy"] == "heuristic" and summary["episodes"] == 2
    assert (tmp_path / "game.gif").read_bytes()[:6] == b"GIF89a"
    with open(tmp_path / "h" / "episodes.csv") as file:
        length = int(next(csv.DictReader(file))["length"])  # the recorded game, seed 100000
    import imageio.v3 as iio

    # Every third frame of the game, and the first: the frames steps run on are in it too.
    assert len(iio.imread(tmp_path / "game.gif", index=None)) == -(-(length + 1) // 3)
    random = evaluate.main(
        ["--policy", "random", "--env", "Pinball-v0", "--episodes", "2", "--out",
         str(tmp_path / "r"), "--video", str(tmp_path / "game.mp4")]
    )  # fmt: skip
    assert json.loads((tmp_path / "r/summary.json").read_text()) == random
    assert (tmp_path / "game.mp4").read_bytes()[4:8] == b"ftyp"  # an MP4 container


def test_baselines_play_the_env_asked_for(tmp_path):
    """--env Pinball-v1: the heuristic plunges (every game's first ball waits on the plunger:
    the machine's 10 s wait would show in the length) and scores the skill shot's bonus."""
    summary = evaluate.main(
        ["--policy", "heuristic", "--env", "Pinball-v1", "--episodes", "2", "--out",
         str(tmp_path / "h")]
    )  # fmt: skip
    assert summary["score_mean"] > 3 * load_table("classic_v1").plunger.skill_shot.bonus
    with pytest.raises(SystemExit):  # Pinball-v1's table is its own
        evaluate.main(["--policy", "random", "--env", "Pinball-v1", "--table", "classic"])


def test_report_writes_the_comparison_curve_and_game(tmp_path, capsys):
    run = tiny_run(ROOT / "configs/agents/ppo.yaml", tmp_path / "runs", "env.num_envs=8",
                   "total_timesteps=8192", "hyperparams.n_steps=512")  # fmt: skip
    capsys.readouterr()
    report = evaluate.report(run, episodes=2)
    # Each long step says what it does before it starts, in order.
    said = [line for line in capsys.readouterr().out.splitlines() if line.startswith("report: ")]
    assert [line.split(" ")[1:3] for line in said] == [
        ["playing", "the"], ["playing", "the"], ["playing", "the"], ["recording", "the"],
        [str(run / "report.json") + ",", str(run / "learning_curve.png") + ","],
    ]  # fmt: skip
    assert "random" in said[0] and "heuristic" in said[1] and "model's 2 games" in said[2]
    assert set(report) == {"random", "heuristic", "model"}
    assert json.loads((run / "report.json").read_text()) == report
    assert (run / "learning_curve.png").read_bytes()[:4] == b"\x89PNG"
    with open(run / "eval" / "model" / "episodes.csv") as file:
        length = int(next(csv.DictReader(file))["length"])  # the recorded game
    import imageio.v3 as iio

    # Every third frame, those that steps run on while the ball is high (skip_above) too.
    assert len(iio.imread(run / "game.gif", index=None)) == -(-(length + 1) // 3)


def test_a_checkpoint_evaluates_and_a_curve_brings_its_baselines(tmp_path):
    longer = ["env.num_envs=8", "total_timesteps=8192", "hyperparams.n_steps=512"]
    run = tiny_run(ROOT / "configs/agents/ppo.yaml", tmp_path / "runs", *longer)
    _, checkpoint = latest_checkpoint(run)
    summary = evaluate.main(["--model", str(checkpoint), "--episodes", "1"])  # config: run's
    assert summary["episodes"] == 1 and (run / "checkpoints" / "eval" / "summary.json").is_file()
    evaluate.main(["--model", str(run), "--episodes", "1", "--curve", "--out", str(tmp_path / "e")])
    assert (tmp_path / "e/learning_curve.png").read_bytes()[:4] == b"\x89PNG"
    assert {p.name for p in (tmp_path / "e").iterdir()} >= {"random", "heuristic"}


def test_watching_shows_every_frame_of_the_evaluated_games(tmp_path, monkeypatch):
    import pygame

    from pinball_env.render import Window

    run = tiny_run(ROOT / "configs/agents/ppo.yaml", tmp_path / "runs")  # skip_above: long steps
    summary = evaluate.main(["--model", str(run), "--episodes", "2", "--out", str(tmp_path / "e")])
    with open(tmp_path / "e" / "episodes.csv") as file:
        rows = list(csv.DictReader(file))
    shown = []
    monkeypatch.setattr(Window, "show", lambda self, frame: shown.append(frame.shape))
    trained = load_policy(run)

    def player(venv, seed):
        return lambda obs, infos: trained.act(obs)

    watched = evaluate.watch_games(trained.config, trained.normalization, player, 100_000, 2)
    assert watched["scores"] == [int(row["score"]) for row in rows] and summary["episodes"] == 2
    assert len(shown) == sum(int(row["length"]) for row in rows)  # every frame, at real speed
    assert len(set(shown)) == 1
    # Closing the window stops.
    pygame.display.init()
    pygame.event.post(pygame.event.Event(pygame.QUIT))
    stopped = evaluate.watch_games(trained.config, trained.normalization, player, 100_000, 2)
    assert stopped["episodes"] == 0


def test_watch_without_a_display_stops_at_once_and_points_to_the_browser(monkeypatch, capsys):
    monkeypatch.setenv("SDL_VIDEODRIVER", "dummy")
    with pytest.raises(SystemExit) as stopped:
        evaluate.main(["--policy", "heuristic", "--watch", "--episodes", "1"])
    assert stopped.value.code == 2
    error = capsys.readouterr().err
    assert "no display was found" in error and "pinball_env.tools.serve" in error


@pytest.mark.parametrize(
    ("module", "entry"),
    [("agents.evaluate", None), ("agents.train", None), ("agents.generalization", None),
     ("agents.benchmark", "agents.benchmark.cli"), ("pinball_env.tools.play", None),
     ("pinball_env.tools.serve", None), ("pinball_env.tools.plot", None),
     ("pinball_env.tools.demo", None), ("pinball_env.tools.tilt", None),
     ("pinball_env.tools.crosscheck", "pinball_env.tools.crosscheck.cli"),
     ("benchmarks.speed", None), ("benchmarks.first_compile", None),
     ("benchmarks.promises", None), ("agents.distill", None), ("benchmarks.planner", None)],
)  # fmt: skip
def test_help_names_the_command_and_reads_as_plain_text(module, entry, capsys):
    import importlib

    with pytest.raises(SystemExit):
        importlib.import_module(entry or module).main(["--help"])
    text = capsys.readouterr().out
    assert text.startswith(f"usage: python -m {module}") and "``" not in text


def test_the_learning_curve_names_the_table_the_env_plays():
    from agents.config import config_from_dict
    from agents.report import played_table

    assert played_table(config_from_dict({"env": {"id": "Pinball-v2"}})) == "classic_v2"
    assert played_table(config_from_dict({"env": {"id": "Pinball-v3"}})) == "classic_v3"
    chosen = {"env": {"id": "Pinball-v0", "kwargs": {"table": "classic_v1"}}}
    assert played_table(config_from_dict(chosen)) == "classic_v1"


def test_the_planner_plays_as_a_reference_and_each_game_as_alone(tmp_path):
    """--policy search: each game of the evaluation's vector env is the game SearchPolicy plays
    on its own env of the same seed (the same look-ahead), with the protocol's sticky actions."""
    import gymnasium as gym

    from pinball_env.players import SearchPolicy

    summary = evaluate.main(
        ["--policy", "search", "--env", "Pinball-v2", "--episodes", "1", "--protocol", "--out",
         str(tmp_path / "s")]
    )  # fmt: skip
    with open(tmp_path / "s" / "episodes.csv") as file:
        scores = [int(row["score"]) for row in csv.DictReader(file)]
    alone = []
    for seed in (100_000,):
        env = gym.make("Pinball-v2", repeat_action_probability=0.25, max_frames=7200)
        player, (_, info) = SearchPolicy(env), env.reset(seed=seed)
        ended = False
        while not ended:
            _, _, terminated, truncated, info = env.step(player(info))
            ended = terminated or truncated
        alone.append(int(info["score"]))
    assert scores == alone and summary["policy"] == "search"
