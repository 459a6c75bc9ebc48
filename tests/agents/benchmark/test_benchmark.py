"""python -m agents.benchmark (--tiny): jobs, resumes, the table; scoring a recording on the
protocol."""

import csv
import dataclasses
import json
import shutil
import time
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest
import yaml

import agents.train
from agents.benchmark import cli, jobs, methods, results, shipping
from agents.benchmark.curves import curves_table, learning_curve
from agents.config import ConfigError, load_config
from agents.evaluate import main as evaluate_main
from agents.policy import load_policy
from agents.runs import MODEL_FILE, validation_rows
from pinball_env import protocol
from pinball_env.recording import (
    GameRecord,
    Recording,
    make_recorded_env,
    table_sha256,
    write_recording,
)

ROOT = Path(__file__).resolve().parents[3]

pytestmark = pytest.mark.filterwarnings("ignore::DeprecationWarning")


@pytest.fixture(scope="module")
def tiny(tmp_path_factory) -> tuple[Path, dict]:
    out = tmp_path_factory.mktemp("bench")
    table = cli.main(["--tiny", "--out", str(out), "--methods", "random-v0", "ppo-v0",
                            "--seeds", "0", "1", "--parallel", "2"])  # fmt: skip
    return out, table


def test_the_table_holds_every_run_and_the_protocols_metrics(tiny):
    out, table = tiny
    assert set(table["methods"]) == {"random-v0", "ppo-v0"}
    ppo = table["methods"]["ppo-v0"]
    assert [run["seed"] for run in ppo["runs"]] == [0, 1]
    assert ppo["games"] == 2 * methods.TINY_EPISODES and ppo["env_id"] == "Pinball-v0"
    for run in ppo["runs"]:
        assert run["frames"] >= methods.TINY_FRAMES  # trained to the budget, no further
        assert run["frames"] < methods.TINY_FRAMES + 2 * 64 * 61  # (the rollout it stopped in)
        assert (out / run["run"] / MODEL_FILE).is_file()
        summary = json.loads((out / run["run"] / "protocol_eval" / "summary.json").read_text())
        assert summary["seeds"] == [100_000, 100_000 + methods.TINY_EPISODES - 1]
        assert summary["protocol"]["score_mean"] == run["score_mean"]
    pooled = np.concatenate([run["scores"] for run in ppo["runs"]])
    assert ppo["score_mean"] == pooled.mean() and ppo["score_iqm"] == protocol.iqm(pooled)
    assert (
        table["reference_measured"]["Pinball-v0"]["random"]
        == (table["methods"]["random-v0"]["score_mean"])
    )
    saved = json.loads((out / "benchmark.json").read_text())
    assert saved["methods"]["ppo-v0"]["score_mean"] == ppo["score_mean"]
    assert saved["methods"]["ppo-v0"]["training_frames"] == methods.TINY_FRAMES
    assert saved["methods"]["random-v0"]["training_frames"] is None
    assert saved["protocol"]["repeat_action_probability"] == 0.25
    with open(out / "benchmark.csv") as file:
        rows = {row["method"]: row for row in csv.DictReader(file)}
    assert float(rows["ppo-v0"]["score_iqm"]) == pytest.approx(ppo["score_iqm"], abs=1e-3)
    with open(out / "runs.csv") as file:
        assert len(list(csv.DictReader(file))) == 3  # two PPO runs, one random
    for picture in ("scores.png", "profiles.png", "curves.png"):
        assert (out / picture).stat().st_size > 10_000
    for run in saved["methods"]["ppo-v0"]["runs"]:  # each validation: its frames, mean, IQM
        rows = validation_rows(out / run["run"])
        assert run["validations"] == [[r["frames"], r["score_mean"], r["score_iqm"]] for r in rows]
        # (the tiny runs skip validation: none recorded, none claimed)
        assert run["validation"] == (max(r["score_mean"] for r in rows) if rows else None)


def test_a_learning_curve_is_the_mean_normalised_iqm_over_the_runs_at_each_validation():
    reference = protocol.REFERENCE_SCORES["Pinball-v0"]
    span = reference["heuristic"] - reference["random"]

    def at(normalised):
        return reference["random"] + normalised * span

    runs = [  # frames, mean, IQM; the third run recorded no IQM (an older run): no curve
        {"validations": [[100, 0.0, at(0.2)], [200, 0.0, at(0.6)]]},
        {
            "validations": [
                [110, 0.0, at(0.4)],
                [210, 0.0, at(1.0)],
                [300, 0.0, at(1.2)],
            ]
        },
        {"validations": [[100, 0.0, None]]},
    ]
    curve = learning_curve({"env_id": "Pinball-v0", "runs": runs})
    assert [(frames, runs) for frames, *_, runs in curve] == [(105.0, 2), (205.0, 2), (300.0, 1)]
    for (_, value, low, high, _), expected in zip(curve, (0.3, 0.8, 1.2), strict=True):
        assert value == pytest.approx(expected)
        assert low <= value <= high
    assert curve[0][2] == pytest.approx(0.2) and curve[0][3] == pytest.approx(0.4)  # the seeds'
    assert curve[2][2] == curve[2][3] == pytest.approx(1.2)  # one run: no spread
    assert "| m | Pinball-v0 | 0.0M | 2 | 0.30 [" in curves_table(
        {"m": {"env_id": "Pinball-v0", "runs": runs}}
    )


def test_a_distilled_method_is_distilled_from_the_planner_and_counts_its_frames(tmp_path):
    # dagger-v3: agents.distill, not agents.train; its frames are its games' and the planner's
    # look-ahead's (distill.csv's), under the budget's ceiling (tiny: the first iteration only);
    # its model played the protocol's games as a trained one (load_policy).
    argv = ["--tiny", "--out", str(tmp_path), "--methods", "dagger-v3", "--seeds", "0"]
    table = cli.main(argv)
    (run,) = table["methods"]["dagger-v3"]["runs"]
    folder = tmp_path / run["run"]
    with open(folder / "distill.csv") as file:
        iterations = list(csv.DictReader(file))
    assert len(iterations) == 1  # of 2: the second would pass the budget, as the first did
    assert (
        run["frames"] == sum(int(row["frames"]) for row in iterations) > int(iterations[0]["steps"])
    )  # (the planner's branches in it)
    assert run["steps"] == sum(int(row["steps"]) for row in iterations)
    assert run["validations"] == [[r["frames"], r["score_mean"], r["score_iqm"]]
                                  for r in validation_rows(folder)]  # fmt: skip
    settings = jobs.JobSettings(tmp_path, methods.TINY_EPISODES, tiny=True)
    config = jobs.job_config("dagger-v3", 0, settings)
    assert config.total_frames == methods.TINY_FRAMES and config.seed == 0
    assert run["config_digest"] == methods.config_digest(config)
    assert jobs.job_done("dagger-v3", 0, settings)
    assert cli.main(argv)["methods"]["dagger-v3"]["runs"][0]["scores"] == run["scores"]  # (done)
    # A run of another distillation config in its folder is refused, as a trained run's.
    with pytest.raises(ConfigError, match=r"another config than dagger-v3 seed 0 .*seed: 0, not 1"):
        jobs.job_run("dagger-v3", 0, settings, dataclasses.replace(config, seed=1))
    # One stopped before its model is distilled anew (it does not go on), to the same run.
    (folder / MODEL_FILE).unlink()
    again = cli.main(argv)["methods"]["dagger-v3"]["runs"][0]
    assert again["scores"] == run["scores"] and again["run"] != run["run"]
    assert not folder.exists()


def test_a_method_on_the_long_budget_trains_its_config_ten_times_as_long(tmp_path):
    settings = jobs.JobSettings(tmp_path)
    short = jobs.job_config("ppo-scale-v2", 3, settings)
    long = jobs.job_config("ppo-scale-v2-200m", 3, settings)
    assert methods.METHODS["ppo-scale-v2-200m"].config == methods.METHODS["ppo-scale-v2"].config
    assert (short.total_frames, long.total_frames) == protocol.TRAINING_BUDGETS
    assert long.total_frames == protocol.LONG_TRAINING_FRAMES == 200_000_000
    for key in methods.SCALED_BY_BUDGET:  # the schedules and validations spread as far
        assert getattr(long, key) == 10 * getattr(short, key), key
    # What trains is otherwise the same config: its digest differs only by those keys.
    scaled = {key: getattr(short, key) for key in ("total_frames", *methods.SCALED_BY_BUDGET)}
    assert dataclasses.replace(long, **scaled) == short
    with pytest.raises(ValueError, match="not a budget of the protocol"):
        methods.Method("Pinball-v2", "ppo_scale_v2.yaml", frames=50_000_000)


def test_finished_jobs_are_reused_and_a_partial_run_goes_on(tiny):
    out, table = tiny
    run = out / table["methods"]["ppo-v0"]["runs"][1]["run"]
    first_model = (out / table["methods"]["ppo-v0"]["runs"][0]["run"] / MODEL_FILE).stat()
    # The second run lost its model and evaluation (stopped before the end): it goes on from
    # its last checkpoint; the finished first run is left alone.
    (run / MODEL_FILE).unlink()
    for path in (run / "protocol_eval").iterdir():
        path.unlink()
    again = cli.main(["--tiny", "--out", str(out), "--methods", "random-v0", "ppo-v0",
                            "--seeds", "0", "1"])  # fmt: skip
    assert (run / MODEL_FILE).is_file() and (run / "progress_0.csv").is_file()
    first = out / table["methods"]["ppo-v0"]["runs"][0]["run"] / MODEL_FILE
    assert first.stat().st_mtime_ns == first_model.st_mtime_ns
    assert again["methods"]["ppo-v0"]["runs"][0] == table["methods"]["ppo-v0"]["runs"][0]
    # Fewer games: the evaluations are played again, the training is not.
    fewer = cli.main(["--tiny", "--out", str(out), "--methods", "ppo-v0", "--seeds", "0",
                            "--episodes", "2"])  # fmt: skip
    assert fewer["methods"]["ppo-v0"]["games"] == 2
    assert first.stat().st_mtime_ns == first_model.st_mtime_ns


def test_a_stopped_jobs_minutes_count_in_its_run(tiny, monkeypatch):
    out, _ = tiny
    settings = jobs.JobSettings(out, episodes=methods.TINY_EPISODES, tiny=True)
    record = jobs.job_folder(settings, "ppo-v0", 1) / jobs.JOB_FILE
    (jobs.job_run("ppo-v0", 1, settings) / MODEL_FILE).unlink()
    before = json.loads(record.read_text())["train_seconds"]
    real_train = agents.train.train

    def stopped(*args, **kwargs):  # a training that ran a while, then was stopped
        time.sleep(0.2)
        raise KeyboardInterrupt

    monkeypatch.setattr(agents.train, "train", stopped)
    with pytest.raises(KeyboardInterrupt):
        jobs.run_job("ppo-v0", 1, settings)
    after_stop = json.loads(record.read_text())["train_seconds"]
    assert after_stop >= before + 0.19  # (rounded to a thousandth)

    def slow(*args, **kwargs):  # the real training, which takes a while (a tiny one may not)
        time.sleep(0.2)
        return real_train(*args, **kwargs)

    monkeypatch.setattr(agents.train, "train", slow)
    jobs.run_job("ppo-v0", 1, settings)  # goes on from its checkpoint: its minutes add up
    assert json.loads(record.read_text())["train_seconds"] >= after_stop + 0.19
    assert (jobs.job_run("ppo-v0", 1, settings) / MODEL_FILE).is_file()


def test_a_run_stopped_before_its_first_checkpoint_starts_again(tiny):
    out, _ = tiny
    settings = jobs.JobSettings(out, episodes=2, tiny=True)
    run = jobs.job_run("ppo-v0", 0, settings)
    shutil.rmtree(run / "checkpoints")  # as if killed in its warm start
    (run / MODEL_FILE).unlink()
    jobs.run_job("ppo-v0", 0, settings)
    again = jobs.job_run("ppo-v0", 0, settings)
    assert (again / MODEL_FILE).is_file() and not (again / "progress_0.csv").exists()


def test_runs_of_an_earlier_benchmark_are_merged_not_trained_again(tiny, tmp_path):
    out, _ = tiny
    names = ["--methods", "random-v0", "ppo-v0", "--seeds", "0", "1"]
    # (the fixture's runs evaluated on its games again, whichever tests ran before)
    earlier = cli.main(["--tiny", "--out", str(out), *names])
    published = tmp_path / "published.json"
    shutil.copyfile(out / "benchmark.json", published)
    here = tmp_path / "here"
    shutil.copytree(out / "ppo-v0" / "seed1", here / "ppo-v0" / "seed1")  # one run here
    table = cli.main(["--tiny", "--out", str(here), *names, "--merge", str(published)])
    assert sorted(p.name for p in here.iterdir() if p.is_dir()) == ["ppo-v0"]  # none played
    assert sorted(p.name for p in (here / "ppo-v0").iterdir()) == ["seed1"]  # none trained
    for name in ("random-v0", "ppo-v0"):
        ours, theirs = table["methods"][name], earlier["methods"][name]
        assert [run["scores"] for run in ours["runs"]] == [run["scores"] for run in theirs["runs"]]
        assert ours["score_iqm_ci95"] == theirs["score_iqm_ci95"]
    seed0, seed1 = table["methods"]["ppo-v0"]["runs"]
    assert seed0["from"] == str(published) and "from" not in seed1  # a run here comes first
    assert table["methods"]["random-v0"]["runs"][0]["from"] == str(published)
    assert seed0["commit"] == earlier["methods"]["ppo-v0"]["runs"][0]["commit"]


def test_an_earlier_benchmark_of_another_protocol_or_config_is_refused(tiny, tmp_path):
    out, _ = tiny
    cli.main(["--tiny", "--out", str(out), "--methods", "ppo-v0", "--seeds", "0"])
    table = json.loads((out / "benchmark.json").read_text())
    settings, path = jobs.JobSettings(tmp_path, episodes=2, tiny=True), tmp_path / "b.json"
    path.write_text(json.dumps(table))
    with pytest.raises(ConfigError, match=r"another protocol .*eval_seeds: \[100000, 100002\]"):
        results.merged_runs([path], ["ppo-v0"], settings)
    settings = jobs.JobSettings(tmp_path, methods.TINY_EPISODES, tiny=True)
    assert len(results.merged_runs([path], ["ppo-v0"], settings)["ppo-v0"]) == 1
    table["methods"]["ppo-v0"]["runs"][0]["config_digest"] = "0" * 16  # its config since changed
    path.write_text(json.dumps(table))
    with pytest.raises(ConfigError, match="ppo-v0 seed 0 was trained by another config"):
        results.merged_runs([path], ["ppo-v0"], settings)
    assert results.merged_runs([path], ["random-v0"], settings) == {}  # (not asked for)
    path.write_text("[1, 2]")
    with pytest.raises(ConfigError, match=r"not a benchmark\.json"):
        results.merged_runs([path], ["ppo-v0"], settings)


PUBLISHED = Path(__file__).resolve().parents[3] / "docs" / "benchmark.json"
# Runs of methods that have fewer seeds than a row needs: kept to be merged, not published.
PARTIAL = PUBLISHED.with_name("benchmark-partial.json")


@pytest.mark.parametrize("path", [PUBLISHED, PARTIAL], ids=["published", "partial"])
def test_the_published_results_are_of_the_protocol_and_configs_of_today(path, tmp_path):
    published = json.loads(path.read_text())
    # Refused if the protocol or a method's config has changed since its runs were trained.
    merged = results.merged_runs([path], list(published["methods"]),
                                   jobs.JobSettings(tmp_path))  # fmt: skip
    assert merged.keys() == published["methods"].keys()
    for name, result in published["methods"].items():
        runs = result["runs"]
        assert [run["scores"] for run in merged[name]] == [run["scores"] for run in runs]
        assert all(len(run["scores"]) == len(protocol.EVAL_SEEDS) for run in runs)
        method = methods.METHODS[name]
        assert method.trained or path == PUBLISHED  # (a baseline's one run is a whole row)
        if method.trained:
            assert all(run["commit"] for run in runs)
            assert len(runs) >= 3 or path == PARTIAL
            for run in runs:  # trained to the budget; distilled under it (a ceiling)
                assert (
                    run["frames"] <= method.frames
                    if method.distilled
                    else (run["frames"] >= 0.99 * method.frames)
                )
        # Its metrics are those of its scores.
        metrics = protocol.aggregate([run["scores"] for run in runs], result["env_id"])
        assert metrics.pop("runs") == len(runs)
        assert {key: result[key] for key in metrics} == json.loads(json.dumps(metrics))


def test_the_partial_runs_are_not_published_ones():
    published = json.loads(PUBLISHED.read_text())["methods"]
    for name, result in json.loads(PARTIAL.read_text())["methods"].items():
        seeds = {run["seed"] for run in published.get(name, {}).get("runs", [])}
        assert not seeds & {run["seed"] for run in result["runs"]}, name


def test_tiny_runs_do_not_ship():
    with pytest.raises(SystemExit):
        cli.main(["--tiny", "--out", "/nonexistent", "--methods", "ppo-v0", "--table-only",
                        "--ship", "ppo-v0"])  # fmt: skip


def test_the_run_best_in_validation_ships_under_the_name_given(tiny, tmp_path, monkeypatch):
    out = tmp_path / "bench"
    shutil.copytree(tiny[0], out)
    # (both runs evaluated on the same games, whichever tests ran before)
    cli.main(["--tiny", "--out", str(out), "--methods", "ppo-v0", "--seeds", "0", "1",
                    "--episodes", "2"])  # fmt: skip
    settings = jobs.JobSettings(out, episodes=2, tiny=True)
    monkeypatch.setattr(protocol, "TRAINING_SEEDS", (0, 1))  # (two tiny runs stand for five)
    for seed, validated in ((0, 900.0), (1, 400.0)):  # seed 0 validated better
        run = jobs.job_run("ppo-v0", seed, settings)
        (run / "validation.csv").write_text(f"steps,frames,score_mean\n64,3000,{validated}\n")
    into = tmp_path / "pretrained"
    model = shipping.ship("ppo-v0", [0, 1], settings, "best-v0", into)
    card = json.loads((into / "best-v0.json").read_text())
    chosen = jobs.job_run("ppo-v0", 0, settings)
    assert model == into / "best-v0.zip"
    assert model.read_bytes() == (chosen / MODEL_FILE).read_bytes()
    assert card["name"] == "best-v0" and card["method"] == "ppo-v0" and card["seed"] == 0
    assert card["chosen_by"] == "the best validation score of 2 seeds (900)"
    with open(chosen / "protocol_eval" / "episodes.csv") as file:
        scores = [int(row["score"]) for row in csv.DictReader(file)]
    assert card["check_games"]["scores"] == scores[: shipping.CHECK_GAMES]
    assert card["load"] == 'agents.policy.load_policy("pretrained:best-v0")'
    assert load_policy(str(model)).env_id == "Pinball-v0"  # the zip carries its config
    # Runs published elsewhere count in the choice; the chosen one ships from a run here.
    results.aggregate_table(["ppo-v0"], [0, 1], settings)
    here = jobs.JobSettings(tmp_path / "here", episodes=2, tiny=True)
    shutil.copytree(out / "ppo-v0" / "seed1", here.out / "ppo-v0" / "seed1")
    merged = results.merged_runs([out / "benchmark.json"], ["ppo-v0"], here)
    with pytest.raises(ConfigError, match=r"best run, seed 0 .*\(900\).*\(--seeds 0\)"):
        shipping.ship("ppo-v0", [0, 1], here, "best-v0", into, merged)
    # ... or, asked to, the best of the runs here, the card saying what was better.
    shipping.ship("ppo-v0", [0, 1], here, "best-v0", into, merged, from_out=True)
    card = json.loads((into / "best-v0.json").read_text())
    assert card["seed"] == 1 and card["chosen_by"] == (
        "the best validation score of the 1 of 2 seeds whose models are here (400; "
        "seed 0's model, 900, was not kept)"
    )
    run = jobs.job_run("ppo-v0", 1, here)
    (run / "validation.csv").write_text("steps,frames,score_mean\n64,3000,1000\n")
    shipping.ship("ppo-v0", [0, 1], here, "best-v0", into, merged)
    card = json.loads((into / "best-v0.json").read_text())
    assert card["seed"] == 1 and card["chosen_by"].endswith("of 2 seeds (1000)")
    # A method with a seed short of the runs asked for does not ship.
    monkeypatch.setattr(protocol, "TRAINING_SEEDS", (0, 1, 2))
    with pytest.raises(ConfigError, match=r"ships the best of at least 3 runs .* 2 are done"):
        shipping.ship("ppo-v0", [0, 1, 2], settings, "best-v0", into)


@pytest.mark.parametrize(
    ("text", "error"),
    [("random-v0", "'random-v0' is not a trained method"), ("nope=x", "'nope' is not a trained"),
     ("ppo-v0=a b", "the name 'a b' is not letters")],
)  # fmt: skip
def test_a_bad_ship_is_refused_with_what_is_wrong(text, error):
    with pytest.raises(ConfigError, match=error):
        shipping.parse_ship(text)
    assert shipping.parse_ship("ppo-finetune-v1=ppo-v1") == ("ppo-finetune-v1", "ppo-v1")
    assert shipping.parse_ship("ppo-v0") == ("ppo-v0", "ppo-v0")


def test_a_run_trained_with_another_config_is_refused(tiny, tmp_path):
    out, _ = tiny
    run = jobs.job_run("ppo-v0", 0, jobs.JobSettings(out, tiny=True))
    copy = tmp_path / "ppo-v0" / "seed0" / run.name
    copy.mkdir(parents=True)
    text = (run / "config.yaml").read_text().replace("total_frames: 3000", "total_frames: 4000")
    (copy / "config.yaml").write_text(text)
    settings = jobs.JobSettings(tmp_path, tiny=True)
    with pytest.raises(ConfigError, match=r"than ppo-v0 seed 0 .*total_frames: 4000"):
        jobs.job_run("ppo-v0", 0, settings)
    # Its notes reworded since: the same training.
    data = yaml.safe_load((run / "config.yaml").read_text())
    data["notes"] = f"Reworded. {data['notes']}"
    (copy / "config.yaml").write_text(yaml.safe_dump(data))
    assert jobs.job_run("ppo-v0", 0, settings) == copy


def protocol_recording(path: Path, options: dict, seeds: list[int]) -> list[int]:
    """Write a play-tool recording of random play of Pinball-v0 with ``options``."""
    env = make_recorded_env(options, 7200, "Pinball-v0")
    rng = np.random.default_rng(0)
    games = []
    for seed in seeds:
        env.reset(seed=seed)
        actions, done = [], False
        while not done:
            actions.append(int(rng.integers(4)))
            _, _, terminated, truncated, info = env.step(actions[-1])
            done = terminated or truncated
        end = "game over" if terminated else "time limit"
        games.append(GameRecord(seed, "".join(map(str, actions)), info["score"],
                                info["frames"], end))  # fmt: skip
    recording = Recording("Pinball-v0", {"table": "classic", **options}, 7200,
                          table_sha256(env.unwrapped.table), tuple(games))  # fmt: skip
    write_recording(path, recording)
    return [game.score for game in games]


def test_a_recording_is_scored_on_the_protocol(tmp_path):
    path = tmp_path / "human.json"
    scores = protocol_recording(path, {"repeat_action_probability": 0.25}, [7, 8])
    summary = evaluate_main(["--recording", str(path), "--out", str(tmp_path / "eval")])
    assert summary["scores"] == scores
    metrics = summary["protocol"]
    assert metrics["score_mean"] == np.mean(scores)
    assert metrics["normalized_mean"] == pytest.approx(
        float(np.mean(protocol.normalized(scores, "Pinball-v0")))
    )
    assert json.loads((tmp_path / "eval" / "summary.json").read_text())["scores"] == scores


def test_a_recording_off_the_protocol_is_refused(tmp_path, capsys):
    path = tmp_path / "plain.json"
    protocol_recording(path, {}, [7])
    with pytest.raises(SystemExit):
        evaluate_main(["--recording", str(path)])
    assert "repeat_action_probability=0.0 (the protocol's: 0.25)" in capsys.readouterr().err
    protocol_recording(path, {"repeat_action_probability": 0.25, "balls": 1}, [7])
    with pytest.raises(SystemExit):
        evaluate_main(["--recording", str(path)])
    assert "balls=1" in capsys.readouterr().err


def test_the_protocol_evaluation_plays_sticky_held_out_games(tmp_path):
    summary = evaluate_main(["--policy", "heuristic", "--env", "Pinball-v1", "--protocol",
                             "--episodes", "2", "--out", str(tmp_path)])  # fmt: skip
    assert summary["seeds"] == [100_000, 100_001]
    with open(tmp_path / "episodes.csv") as file:
        scores = [int(row["score"]) for row in csv.DictReader(file)]
    # The same games by hand: the env with the protocol's options, the heuristic playing.
    from pinball_env.players import HeuristicPolicy

    for seed, score in zip((100_000, 100_001), scores, strict=True):
        env = gym.make("Pinball-v1", **protocol.protocol_options("Pinball-v1"))
        player = HeuristicPolicy(env.unwrapped.table)
        _, info = env.reset(seed=seed)
        done = False
        while not done:
            _, _, terminated, truncated, info = env.step(player(info))
            done = terminated or truncated
        assert info["score"] == score
    assert summary["protocol"]["score_mean"] == np.mean(scores)


def test_a_key_added_later_leaves_the_digest_of_configs_at_its_default():
    config = load_config(ROOT / "configs/agents/ppo_close_v1.yaml")
    assert set(methods.LATER_KEYS) <= set(config.to_dict())
    anchored = dataclasses.replace(config, kl_anchor_coef=1.0)
    assert "anchor_coef" not in methods.trained_by(config)
    assert "kl_anchor_coef" not in methods.trained_by(config)
    assert methods.config_digest(anchored) != methods.config_digest(config)


def test_the_benchmark_page_names_every_method():
    page = (PUBLISHED.parent / "benchmark.md").read_text()
    assert [name for name in methods.METHODS if f"`{name}`" not in page] == []


def test_the_planner_is_a_reference_row_with_its_seconds_a_game(tmp_path):
    table = cli.main(["--tiny", "--out", str(tmp_path), "--methods", "search-v2",
                      "--episodes", "1"])  # fmt: skip
    result = table["methods"]["search-v2"]
    assert result["baseline"] == "search" and result["training_frames"] is None
    (run,) = result["runs"]
    assert len(run["scores"]) == 1 and run["play_seconds"] > 0
    row = (tmp_path / "benchmark.md").read_text().splitlines()[-1]
    assert row.startswith("| search-v2 |") and "none: looks ahead in the simulator" in row
    assert row.rstrip(" |").endswith("s a game")
