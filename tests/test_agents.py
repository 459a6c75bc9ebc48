"""Training and evaluation from configs: smoke runs of every shipped config, resume, atomic
checkpoints, config errors, deterministic evaluation, and rl-zoo3's hyperparameters."""

import csv
import dataclasses
import itertools
import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import yaml

from agents import evaluate, train
from agents.config import ConfigError, load_config, sb3_hyperparams
from agents.envs import make_env_chain
from agents.imitation import discounted_returns, imitate, teacher_games
from agents.policy import load_policy
from agents.runs import atomic_write, latest_checkpoint, save_model
from pinball_env.table import load_table

ROOT = Path(__file__).resolve().parent.parent
CONFIGS_DIR = ROOT / "configs" / "agents"
# The stable-baselines3 configs (rllib_*.yaml are RLlib's: tests/test_rllib.py).
CONFIGS = sorted(p for p in (ROOT / "configs" / "agents").glob("*.yaml") if "rllib" not in p.name)
# Tiny budgets: a few hundred steps, a couple of envs.
TINY = {
    "ppo": ["hyperparams.n_steps=64", "hyperparams.batch_size=64"],
    "a2c": ["hyperparams.n_steps=8"],
    "dqn": ["hyperparams.learning_starts=64", "hyperparams.buffer_size=1000"],
}


def tiny_overrides(config: Path) -> list[str]:
    loaded = load_config(config)  # (over its base, if it has one)
    warm = ["imitation_steps=64"] if loaded.imitation_steps else []
    validation = ["validate_episodes=2"] if loaded.validate_every else []
    return ["total_timesteps=256", "env.num_envs=2", "checkpoint_every=128", *TINY[loaded.algo],
            *warm, *validation]  # fmt: skip


def tiny_run(config: Path, runs: Path, *extra: str) -> Path:
    overrides = [*tiny_overrides(config), *extra]
    train.main(["--config", str(config), *overrides, "--runs", str(runs), "--no-progress"])
    (run,) = runs.iterdir()
    return run


@pytest.mark.parametrize("config", CONFIGS, ids=lambda path: path.stem)
def test_every_shipped_config_trains_and_evaluates(config, tmp_path):
    run = tiny_run(config, tmp_path / "runs")
    assert load_config(run / "config.yaml") == load_config(config, tiny_overrides(config))
    meta = json.loads((run / "meta.json").read_text())
    assert meta["pinball_env"] and meta["stable_baselines3"] and meta["torch"]
    assert (run / "model.zip").is_file()
    assert list(run.glob("events.out.tfevents.*")), "TensorBoard logs"
    assert latest_checkpoint(run)[0] >= 256
    summary = evaluate.main(["--model", str(run), "--episodes", "2"])
    assert summary["episodes"] == 2 and summary["seeds"] == [100_000, 100_001]
    with open(run / "eval" / "episodes.csv") as file:
        rows = list(csv.DictReader(file))
    for row in rows:  # whole games: every ball lost, or the two minutes played
        assert row["balls_lost"] == "3" or (row["truncated"] == "True" and row["length"] == "7200")


@pytest.mark.parametrize("config", ["ppo", "dqn"])
def test_a_run_killed_after_a_checkpoint_resumes_from_it(config, tmp_path):
    import pickle

    import stable_baselines3

    algorithm = getattr(stable_baselines3, config.upper())
    run = tiny_run(ROOT / f"configs/agents/{config}.yaml", tmp_path / "runs")
    # As if killed after the first checkpoint: the later ones and the model never written.
    (run / "model.zip").unlink()
    for path in (run / "checkpoints").glob("*"):
        if not path.name.startswith("step_128"):
            path.unlink()
    assert latest_checkpoint(run)[0] == 128
    logged = (run / "progress.csv").read_text()
    train.main(["--resume", str(run), "--no-progress"])
    model = algorithm.load(run / "model.zip")
    assert model.num_timesteps == 256
    assert latest_checkpoint(run)[0] == 256
    assert (run / "progress_0.csv").read_text() == logged  # the curve before the resume kept
    stats = run / "checkpoints/step_128_vecnormalize.pkl"
    if stats.exists():  # the normalisation went on from the checkpoint's statistics
        before = pickle.loads(stats.read_bytes()).obs_rms.count
        after = pickle.loads((run / "model_vecnormalize.pkl").read_bytes()).obs_rms.count
        assert after > before > 1
    if config == "dqn":  # no buffer in a checkpoint: it is refilled before learning again
        assert model.learning_starts == 128 + 64


def test_resume_needs_a_whole_checkpoint(tmp_path, capsys):
    run = tiny_run(ROOT / "configs/agents/ppo.yaml", tmp_path / "runs")
    (run / "checkpoints/step_256_vecnormalize.pkl").unlink()
    with pytest.raises(SystemExit):
        train.main(["--resume", str(run), "--no-progress"])
    assert "step_256.zip: its VecNormalize statistics are missing" in capsys.readouterr().err
    for path in (run / "checkpoints").glob("*"):
        path.unlink()
    with pytest.raises(SystemExit):
        train.main(["--resume", str(run), "--no-progress"])
    assert "no checkpoint to resume from" in capsys.readouterr().err


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


def strip_agent_entry(model: Path) -> None:
    """Rewrite a model zip without the config and statistics it carries (an older zip)."""
    import zipfile

    from agents.runs import AGENT_ENTRY

    with zipfile.ZipFile(model) as archive:
        entries = {name: archive.read(name) for name in archive.namelist() if name != AGENT_ENTRY}
    with zipfile.ZipFile(model, "w") as archive:
        for name, data in entries.items():
            archive.writestr(name, data)


def test_a_checkpoint_write_killed_midway_leaves_the_last_one_whole(tmp_path):
    folder = tmp_path / "checkpoints"
    atomic_write(folder / "step_100.zip", lambda file: file.write(b"complete"))

    def killed(file):
        file.write(b"half a checkp")
        raise KeyboardInterrupt  # the run dies in the middle of the write

    with pytest.raises(KeyboardInterrupt):
        atomic_write(folder / "step_200.zip", killed)
    assert [path.name for path in folder.iterdir()] == ["step_100.zip"]
    assert (folder / "step_100.zip").read_bytes() == b"complete"
    with pytest.raises(KeyboardInterrupt):
        atomic_write(folder / "step_100.zip", killed)  # nor is an old one overwritten by half
    assert (folder / "step_100.zip").read_bytes() == b"complete"


def test_save_model_writes_the_normalisation_statistics_first(tmp_path, monkeypatch):
    order = []
    monkeypatch.setattr("agents.runs.atomic_write", lambda path, write: order.append(path.name))

    class Model:
        def get_env(self):
            return type("VecNormalize", (), {"obs_rms": None, "norm_obs": False})()

        def save(self, file):
            pass

    save_model(Model(), tmp_path, "step_5", load_config(ROOT / "configs/agents/ppo.yaml"))
    assert order == ["step_5_vecnormalize.pkl", "step_5.zip"]


def test_evaluation_is_deterministic_for_a_model_and_seeds(tmp_path):
    run = tiny_run(ROOT / "configs/agents/ppo.yaml", tmp_path / "runs")
    for out in ("a", "b"):
        evaluate.main(["--model", str(run), "--episodes", "3", "--out", str(tmp_path / out)])
    assert (tmp_path / "a/episodes.csv").read_text() == (tmp_path / "b/episodes.csv").read_text()


def test_baselines_evaluate_with_video(tmp_path):
    summary = evaluate.main(
        ["--policy", "heuristic", "--episodes", "2", "--out", str(tmp_path / "h"),
         "--video", str(tmp_path / "game.gif")]
    )  # fmt: skip
    assert summary["policy"] == "heuristic" and summary["episodes"] == 2
    assert (tmp_path / "game.gif").read_bytes()[:6] == b"GIF89a"
    with open(tmp_path / "h" / "episodes.csv") as file:
        length = int(next(csv.DictReader(file))["length"])  # the recorded game, seed 100000
    import imageio.v3 as iio

    # Every third frame of the game, and the first: the frames steps run on are in it too.
    assert len(iio.imread(tmp_path / "game.gif", index=None)) == -(-(length + 1) // 3)
    random = evaluate.main(
        ["--policy", "random", "--episodes", "2", "--out", str(tmp_path / "r"),
         "--video", str(tmp_path / "game.mp4")]
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


def test_report_writes_the_comparison_curve_and_game(tmp_path):
    run = tiny_run(ROOT / "configs/agents/ppo.yaml", tmp_path / "runs", "env.num_envs=8",
                   "total_timesteps=8192", "hyperparams.n_steps=512")  # fmt: skip
    report = evaluate.report(run, episodes=2)
    assert set(report) == {"random", "heuristic", "model"}
    assert json.loads((run / "report.json").read_text()) == report
    assert (run / "learning_curve.png").read_bytes()[:4] == b"\x89PNG"
    with open(run / "eval" / "model" / "episodes.csv") as file:
        length = int(next(csv.DictReader(file))["length"])  # the recorded game
    import imageio.v3 as iio

    # Every third frame, those that steps run on while the ball is high (skip_above) too.
    assert len(iio.imread(run / "game.gif", index=None)) == -(-(length + 1) // 3)


@pytest.mark.parametrize(
    ("overrides", "message"),
    [
        (["algo=sac"], "algo: unknown algorithm 'sac'"),
        (["policy=LstmPolicy"], "policy: unknown policy 'LstmPolicy'"),
        (["policy=CnnPolicy"], "CnnPolicy does not fit obs_type 'state'"),
        (["totl_timesteps=5"], "unknown key 'totl_timesteps'"),
        (["env.kwargs.tabel=classic"], "env.kwargs.tabel: not a training option"),
        (["env.kwargs.table=nowhere"], "env.kwargs: unknown table 'nowhere'"),
        (["env.kwargs.render_mode=human"], "env.kwargs.render_mode: not a training option"),
        (["env.kwargs.frame_skip=0"], "frame_skip must be an integer from 1 to 60"),
        (["hyperparams.n_step=3"], "hyperparams.n_step: not an option of PPO"),
        (["total_timesteps=-1"], "total_timesteps: must be an integer >= 1"),
        (["eval_seed=3"], "eval_seed: 3 overlaps the training seeds"),
        (["env.id=CartPole-v9"], "env.id: 'CartPole-v9' is not a registered pinball env"),
        (["env.id=CartPole-v1"], "env.id: 'CartPole-v1' is not a registered pinball env"),
        (["device=toaster"], "device: not a torch device: 'toaster'"),
        (["seed"], "override 'seed' is not key=value"),
        (["max_minutes=-1"], "max_minutes: must be a number of minutes >= 0"),
        (["hyperparams.learning_rate=lin_x"], "learning_rate: a schedule is lin_X with X > 0"),
        (["hyperparams.clip_range=lin_-0.2"], "clip_range: a schedule is lin_X with X > 0"),
        (["imitation_steps=-5"], "imitation_steps: must be an integer >= 0"),
        (["imitation_epochs=0"], "imitation_epochs: must be an integer >= 1"),
        (["imitation_learning_rate=-1e-3"], "imitation_learning_rate: must be a positive number"),
        (["imitation_steps=100", "algo=dqn", "hyperparams={}"], "needs an actor-critic"),
        (["imitation_steps=100", "env.kwargs.action_type=multibinary"], "needs discrete actions"),
        (["imitation_steps=100", "env.frame_stack=2"], "needs state observations"),
        (["kl_anchor_coef=-1"], "kl_anchor_coef: must be a number >= 0"),
        (["kl_anchor_coef=nan", "imitation_steps=100"], "kl_anchor_coef: must be a number >= 0"),
        (["kl_anchor_coef=0.5", "imitation_steps=0"], "kl_anchor_coef: pulls towards a warm start"),
        (["anchor_coef=0.5", "imitation_steps=0"], "kl_anchor_coef: pulls towards"),  # (old name)
        (["anchor_coef=0.5", "kl_anchor_coef=0.5"], "anchor_coef is the old name of kl_anchor"),
        (["validate_every=-1"], "validate_every: must be an integer >= 0"),
        (["validate_every=9", "validate_episodes=0"], "validate_episodes: must be an integer >= 1"),
        (["validate_every=9", "validate_seed=31"], "validate_seed: 31 overlaps the training seeds"),
        (["validate_every=9", "validate_seed=99999"], "games 99999..100198 hold eval_seed 100000"),
    ],
)
def test_bad_configs_are_rejected_naming_the_key(overrides, message):
    with pytest.raises(ConfigError, match=message):
        load_config(ROOT / "configs/agents/ppo.yaml", overrides)


def test_linear_schedules_decay_to_zero_over_the_run(tmp_path):
    overrides = ["hyperparams.learning_rate=lin_1e-3", "hyperparams.clip_range=lin_0.2"]
    hyperparams = sb3_hyperparams(load_config(ROOT / "configs/agents/ppo.yaml", overrides))
    assert (
        hyperparams["learning_rate"](1.0) == 1e-3 and hyperparams["learning_rate"](0.25) == 2.5e-4
    )
    assert hyperparams["clip_range"](0.5) == 0.1 and hyperparams["gamma"] == 0.995
    run = tiny_run(
        ROOT / "configs/agents/ppo.yaml", tmp_path / "runs", *overrides, "total_timesteps=640"
    )
    with open(run / "progress.csv") as file:
        rates = [float(row["train/learning_rate"]) for row in csv.DictReader(file)
                 if row["train/learning_rate"]]  # fmt: skip
    assert rates == sorted(rates, reverse=True) and 0 < rates[-1] < rates[0] < 1e-3


@pytest.mark.parametrize(
    ("text", "message"),
    [("algo: [", "not valid YAML"), ("- ppo", "a config is a mapping"), (None, "cannot read")],
)
def test_bad_config_files_are_rejected(tmp_path, text, message):
    path = tmp_path / "config.yaml"
    if text is not None:
        path.write_text(text)
    with pytest.raises(ConfigError, match=message):
        load_config(path)


def test_a_config_is_laid_over_its_base(tmp_path):
    """``base``: mappings merge key by key through the chain, other values replace the base's,
    and the result is the config written out in full."""
    (tmp_path / "sub").mkdir()
    (tmp_path / "sub" / "mid.yaml").write_text(
        f"base: {ROOT / 'configs/agents/ppo.yaml'}\n"
        "total_timesteps: 5000\nenv: {kwargs: {drain_penalty: 9.0}}\n"
    )
    (tmp_path / "top.yaml").write_text(
        "base: sub/mid.yaml\nhyperparams: {policy_kwargs: {net_arch: [8]}, gamma: 0.9}\n"
    )
    written_out = load_config(
        ROOT / "configs/agents/ppo.yaml",
        ["total_timesteps=5000", "env.kwargs.drain_penalty=9.0",
         "hyperparams.policy_kwargs.net_arch=[8]", "hyperparams.gamma=0.9"],
    )  # fmt: skip
    assert load_config(tmp_path / "top.yaml") == written_out
    assert written_out.env.kwargs["skip_above"] == 0.26  # a merged mapping keeps the base's keys


def test_the_shipped_variants_are_their_base_and_their_changes():
    sticky = load_config(CONFIGS_DIR / "ppo_sticky_v1.yaml")
    changes = ["total_timesteps=9000000", "max_minutes=0", "total_frames=20000000",
               "env.kwargs.repeat_action_probability=0.25",
               "env.kwargs.drain_penalty=40.0"]  # fmt: skip
    base = load_config(CONFIGS_DIR / "ppo_v1.yaml", changes)
    assert sticky == dataclasses.replace(base, notes=sticky.notes)
    wide = load_config(CONFIGS_DIR / "ppo_wide_v1.yaml")
    changes = ["imitation_epochs=10", "hyperparams.policy_kwargs.net_arch=[256,256]"]
    base = load_config(CONFIGS_DIR / "ppo_sticky_v1.yaml", changes)
    assert wide == dataclasses.replace(base, notes=wide.notes)


@pytest.mark.parametrize(
    ("files", "message"),
    [
        ({"a.yaml": "base: 3"}, r"a\.yaml: base: must be the path of a config file, got 3"),
        ({"a.yaml": "base: nothing.yaml"}, r"nothing\.yaml: cannot read the config"),
        ({"a.yaml": "base: a.yaml"}, r"a\.yaml: base: a\.yaml makes a cycle"),
        ({"a.yaml": "base: b.yaml", "b.yaml": "base: a.yaml"}, r"b\.yaml: base: a\.yaml makes"),
        ({"a.yaml": "base: b.yaml", "b.yaml": "algo: ppo\nbogus: 1"}, "unknown key 'bogus'"),
    ],
)  # fmt: skip
def test_a_bad_base_is_rejected_naming_the_file(tmp_path, files, message):
    for name, text in files.items():
        (tmp_path / name).write_text(text)
    with pytest.raises(ConfigError, match=message):
        load_config(tmp_path / "a.yaml")


def test_the_command_line_fails_clearly_before_training(tmp_path, capsys):
    runs = tmp_path / "runs"
    for argv in (
        ["--resume", str(tmp_path / "nothing")],
        ["--config", str(ROOT / "configs/agents/ppo.yaml"), "hyperparams.n_steps=abc"],
        [],
    ):
        with pytest.raises(SystemExit) as exit_:
            train.main([*argv, "--runs", str(runs)])
        assert exit_.value.code == 2
    err = capsys.readouterr().err
    assert "not a run folder" in err and "PPO rejects them" in err and "give --config" in err
    assert not runs.exists() or not any(runs.iterdir())  # no run folder left behind
    with pytest.raises(SystemExit):
        evaluate.main(["--model", str(tmp_path / "nothing")])
    assert "nothing: no such file or folder" in capsys.readouterr().err


def test_rl_zoo3_hyperparameters_are_the_ppo_config():
    zoo = yaml.safe_load((ROOT / "configs/agents/rl_zoo3.yml").read_text())["Pinball-v0"]
    config = load_config(ROOT / "configs/agents/ppo.yaml")
    hyperparams = dict(config.hyperparams)
    assert zoo.pop("policy_kwargs") == "dict(net_arch={})".format(
        hyperparams.pop("policy_kwargs")["net_arch"]
    )
    assert zoo.pop("env_kwargs") == config.env.make_kwargs
    assert zoo.pop("policy") == config.policy
    assert zoo.pop("n_timesteps") == config.total_timesteps
    assert zoo.pop("n_envs") == config.env.num_envs
    assert zoo.pop("normalize") == config.env.normalize
    assert zoo == hyperparams


def test_rl_zoo3_trains_with_the_shipped_hyperparameters(tmp_path):
    command = [
        sys.executable, "-m", "rl_zoo3.train", "--algo", "ppo", "--env", "Pinball-v0",
        "--gym-packages", "pinball_env", "--conf-file", "configs/agents/rl_zoo3.yml",
        "-n", "256", "--log-folder", str(tmp_path), "--eval-freq", "-1", "--seed", "0",
    ]  # fmt: skip
    done = subprocess.run(command, cwd=ROOT, capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr[-2000:]
    assert "Normalization activated" in done.stdout and "frame_skip': 1" in done.stdout
    assert list(tmp_path.glob("ppo/Pinball-v0_*/Pinball-v0.zip"))


def test_training_stops_at_its_wall_clock_limit(tmp_path):
    run = tiny_run(ROOT / "configs/agents/ppo.yaml", tmp_path / "runs", "total_timesteps=10000000",
                   "max_minutes=0.0001")  # fmt: skip
    from stable_baselines3 import PPO

    steps = PPO.load(run / "model.zip").num_timesteps
    assert 0 < steps < 10_000_000  # stopped in the first rollout past the limit, and saved
    assert latest_checkpoint(run)[0] == steps  # a resume goes on from there


def test_a_checkpoint_evaluates_and_a_curve_brings_its_baselines(tmp_path):
    longer = ["env.num_envs=8", "total_timesteps=8192", "hyperparams.n_steps=512"]
    run = tiny_run(ROOT / "configs/agents/ppo.yaml", tmp_path / "runs", *longer)
    _, checkpoint = latest_checkpoint(run)
    summary = evaluate.main(["--model", str(checkpoint), "--episodes", "1"])  # config: run's
    assert summary["episodes"] == 1 and (run / "checkpoints" / "eval" / "summary.json").is_file()
    evaluate.main(["--model", str(run), "--episodes", "1", "--curve", "--out", str(tmp_path / "e")])
    assert (tmp_path / "e/learning_curve.png").read_bytes()[:4] == b"\x89PNG"
    assert {p.name for p in (tmp_path / "e").iterdir()} >= {"random", "heuristic"}


def test_validation_keeps_the_best_model_and_goes_on_after_a_resume(tmp_path, capsys):
    from stable_baselines3 import PPO

    games = ["validate_every=128", "validate_episodes=3"]
    run = tiny_run(ROOT / "configs/agents/ppo.yaml", tmp_path / "runs", *games)
    with open(run / "validation.csv") as file:
        rows = list(csv.DictReader(file))
    assert [int(row["steps"]) for row in rows] == [128, 256]  # the last one: the final model
    best = max(rows, key=lambda row: float(row["score_mean"]))
    assert (run / "model.zip").read_bytes() == (run / "best_model.zip").read_bytes()
    assert PPO.load(run / "model.zip").num_timesteps == int(best["steps"])
    assert f"at {best['steps']} steps" in capsys.readouterr().out
    # The model replays its validation games through its saved chain, to the same scores.
    trained = load_policy(run)
    venv = make_env_chain(trained.config, num_envs=3, seed=300_000, frozen=trained.normalization)
    replayed = evaluate.rollouts(
        venv, evaluate.model_policy(trained.model), [300_000, 300_001, 300_002]
    )
    assert np.mean([row["score"] for row in replayed]) == pytest.approx(
        float(best["score_mean"]), abs=0.01
    )
    # Those games chose the model: they are not evaluation games.
    with pytest.raises(SystemExit):
        evaluate.main(["--model", str(run), "--episodes", "5", "--seed", "299998"])
    assert "overlap the validation seeds 300000..300002" in capsys.readouterr().err
    # Killed after the first checkpoint and validation: the resume validates on.
    for path in [*run.glob("model*"), *(run / "checkpoints").glob("step_256*")]:
        path.unlink()
    (run / "validation.csv").write_text("".join((run / "validation.csv").open().readlines()[:2]))
    train.main(["--resume", str(run), "--no-progress"])
    with open(run / "validation.csv") as file:
        assert [row["steps"] for row in csv.DictReader(file)] == ["128", "256"]
    assert (run / "model.zip").is_file()


def test_report_games_that_validated_the_model_are_refused_before_training(tmp_path, capsys):
    runs = tmp_path / "runs"
    argv = [
        "--config",
        str(ROOT / "configs/agents/ppo.yaml"),
        "validate_every=128",
        "validate_seed=100100",
        "validate_episodes=100",
        "--runs",
        str(runs),
        "--report",
        "--episodes",
        "101",
    ]
    with pytest.raises(SystemExit):
        train.main(argv)  # fmt: skip
    assert "seeds 100000..100100 overlap the validation seeds 100100..100199" in (
        capsys.readouterr().err
    )
    assert not runs.exists()


def test_discounted_returns_restart_at_each_game_end():
    rewards = np.array([[1.0, 0.0], [2.0, 1.0], [4.0, 0.0]])
    dones = np.array([[False, True], [True, False], [False, False]])
    returns = discounted_returns(rewards, dones, gamma=0.5)
    assert returns[:, 0].tolist() == [2.0, 2.0, 4.0]  # 1 + 0.5 * 2, then a new game: 4
    assert returns[:, 1].tolist() == [0.0, 1.0, 0.0]


def test_the_warm_start_fits_the_heuristic_and_counts_in_the_budget(tmp_path):
    from stable_baselines3 import PPO

    config = load_config(ROOT / "configs/agents/ppo.yaml",
                         ["env.num_envs=8", "env.kwargs.frame_skip=1"])  # fmt: skip
    venv = make_env_chain(config)
    model = PPO("MlpPolicy", venv, seed=0, device="cpu", **sb3_hyperparams(config))
    fit = imitate(model, venv, steps=8000, epochs=5, seed=0)
    games = teacher_games(make_env_chain(config), 1000)
    majority = np.bincount(games["actions"].ravel()).max() / games["actions"].size
    assert fit["steps"] == 8000 and fit["frames"] > fit["steps"]  # skip_above runs frames on
    assert fit["accuracy"] > majority + 0.03  # more than always pressing the usual buttons
    assert venv.obs_rms.count > 8000  # VecNormalize learned from the heuristic's games
    # Through the command line: the fit is logged, and the learning goes on within the budget.
    run = tiny_run(ROOT / "configs/agents/ppo.yaml", tmp_path / "runs", "imitation_steps=512")
    with open(run / "progress.csv") as file:
        row = next(csv.DictReader(file))
    assert float(row["imitation/steps"]) == 512 and float(row["imitation/accuracy"]) > 0.5
    assert int(float(row["time/frames"])) > int(float(row["imitation/frames"]))


def test_the_warm_start_fits_at_its_own_learning_rate():
    from stable_baselines3 import PPO

    config = load_config(ROOT / "configs/agents/ppo.yaml", ["env.num_envs=4"])  # (512 a batch)
    moves = []
    for learning_rate in (None, 1e-30):  # the algorithm's 3e-4, and a rate that moves nothing
        venv = make_env_chain(config)
        model = PPO("MlpPolicy", venv, seed=0, device="cpu", **sb3_hyperparams(config))
        before = [p.detach().clone() for p in model.policy.parameters()]
        imitate(model, venv, steps=256, epochs=1, seed=0, learning_rate=learning_rate)
        after = [p.detach() for p in model.policy.parameters()]
        moves.append(max(float((p - q).abs().max()) for p, q in zip(after, before, strict=True)))
        assert model.policy.optimizer.param_groups[0]["lr"] == pytest.approx(3e-4)  # restored
    assert moves[0] > 1e-4 and moves[1] < 1e-20


def test_the_anchor_pulls_a_drifted_policy_back_to_its_warm_start():
    """KLAnchor: KL(warm start || policy) is 0 at the start, and each pull over a rollout's
    states lowers it; the warm start it keeps is a frozen copy."""
    import torch
    from stable_baselines3 import PPO

    from agents.imitation import KLAnchor

    config = load_config(ROOT / "configs/agents/ppo.yaml", ["env.num_envs=4"])
    venv = make_env_chain(config)
    model = PPO("MlpPolicy", venv, seed=0, device="cpu", **sb3_hyperparams(config))
    anchor = KLAnchor(model.policy, coef=1.0, batch_size=64, seed=0)
    frozen = [p.detach().clone() for p in anchor.reference.parameters()]
    venv.reset()
    actions = [np.array([venv.action_space.sample()] * 4) for _ in range(64)]
    rollout = np.stack([venv.step(action)[0] for action in actions])  # (steps, envs, features)
    anchor.remember(rollout)
    assert anchor.divergence(model.policy) == pytest.approx(0.0, abs=1e-6)
    with torch.no_grad():  # the drift: the action head's weights pushed at random
        for parameter in model.policy.action_net.parameters():
            parameter.add_(torch.randn_like(parameter))
    divergences = [anchor.divergence(model.policy)]
    for _ in range(5):
        anchor.remember(rollout)
        assert anchor.pull(model.policy) == pytest.approx(divergences[-1], rel=1e-5)
        divergences.append(anchor.divergence(model.policy, rollout.reshape(-1, rollout.shape[2])))
    assert divergences[0] > 0.05
    assert all(later < earlier for earlier, later in itertools.pairwise(divergences))
    assert divergences[-1] < divergences[0] / 2
    assert anchor.pull(model.policy) is None  # (the states are forgotten once pulled on)
    kept = zip(anchor.reference.parameters(), frozen, strict=True)
    assert all(torch.equal(now, before) for now, before in kept)


def test_a_warm_start_is_checkpointed_and_an_anchored_run_resumes_from_it(tmp_path, monkeypatch):
    """A finished warm start is checkpoint step_0 with its frames: a run killed after it goes on
    from there without fitting again, its frames counted on; with kl_anchor_coef, the pull's KL is
    logged and a resume takes the warm start from that checkpoint."""
    config = ROOT / "configs/agents/ppo.yaml"
    run = tiny_run(config, tmp_path / "runs", "imitation_steps=64", "kl_anchor_coef=1.0")
    assert (run / "checkpoints/step_0.zip").is_file()
    with open(run / "progress.csv") as file:
        rows = list(csv.DictReader(file))
    warm_frames = int(float(rows[0]["imitation/frames"]))
    kls = [float(row["anchor/kl"]) for row in rows if row.get("anchor/kl")]
    assert kls and all(np.isfinite(kl) and kl >= 0 for kl in kls)
    # The run as a kill right after its warm start leaves it: step_0 and the frames it played.
    for path in [*run.glob("model*"), *run.glob("progress*.csv"), run / "validation.csv"]:
        path.unlink(missing_ok=True)
    for path in (run / "checkpoints").glob("step_*"):
        if not path.name.startswith("step_0.") and not path.name.startswith("step_0_"):
            path.unlink()
    meta = json.loads((run / "meta.json").read_text())
    meta["trained"] = {"steps": 0, "frames": warm_frames}
    (run / "meta.json").write_text(json.dumps(meta))

    def no_second_fit(*args, **kwargs):
        raise AssertionError("the warm start was fitted again")

    monkeypatch.setattr("agents.train.imitate", no_second_fit)
    train.main(["--resume", str(run), "--no-progress"])
    assert latest_checkpoint(run)[0] >= 256
    with open(run / "progress.csv") as file:
        frames = [int(float(row["time/frames"])) for row in csv.DictReader(file)]
    assert frames[0] > warm_frames  # counted on from the warm start's
    # A resume past step 0 takes the warm start from its checkpoint, and needs it.
    train.main(["--resume", str(run), "total_timesteps=512", "--no-progress"])
    assert latest_checkpoint(run)[0] >= 512  # (model.zip is the best validated)
    for path in (run / "checkpoints").glob("step_0*"):
        path.unlink()
    with pytest.raises(ConfigError, match="kl_anchor_coef needs the warm start's checkpoint"):
        train.train(load_config(run / "config.yaml", ["total_timesteps=1024"]), run, resume=True)


def start_training(
    runs: Path,
    *overrides: str,
    module: str = "agents.train",
    config: Path = CONFIGS_DIR / "ppo.yaml",
) -> subprocess.Popen:
    """``python -m MODULE --config CONFIG`` with a budget it will not reach, in a process of its
    own (stdout and stderr piped)."""
    command = [sys.executable, "-m", module, "--config", str(config), *overrides,
               "--runs", str(runs), "--no-progress"]  # fmt: skip
    return subprocess.Popen(command, cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True)  # fmt: skip


def wait_for(condition, process: subprocess.Popen, seconds: float = 240.0) -> None:
    import time

    deadline = time.monotonic() + seconds
    while not condition():
        if process.poll() is not None:
            raise AssertionError(f"training ended early: {process.communicate()}")
        if time.monotonic() > deadline:
            process.kill()
            raise AssertionError("timed out waiting for the training")
        time.sleep(0.2)


def logged_rows(runs: Path) -> int:
    files = list(runs.glob("*/progress.csv"))
    return len(files[0].read_text().splitlines()) if files else -1


@pytest.mark.parametrize(("signal_name", "warm_start"), [("SIGINT", False), ("SIGTERM", True)])
def test_a_signal_saves_a_checkpoint_and_the_run_resumes_extended(
    tmp_path, signal_name, warm_start
):
    import signal
    import zipfile

    from stable_baselines3 import PPO

    from agents.runs import AGENT_ENTRY

    runs = tmp_path / "runs"
    budget = ["total_timesteps=100000000", "checkpoint_every=0", *TINY["ppo"], "env.num_envs=2"]
    warm = ["imitation_steps=100000000"] if warm_start else ["imitation_steps=0"]
    process = start_training(runs, *budget, *warm)
    # Learning has begun once a row is logged; the warm start, once the log file exists.
    wait_for(lambda: logged_rows(runs) >= (0 if warm_start else 2), process)
    process.send_signal(getattr(signal, signal_name))
    _, err = process.communicate(timeout=120)
    assert process.returncode == 128 + getattr(signal, signal_name), err
    (run,) = runs.iterdir()
    assert "Traceback" not in err
    if warm_start:  # nothing saved (test_a_run_stopped_in_its_warm_start_is_trained_again)
        assert latest_checkpoint(run) is None and "stopped in the warm start" in err
        assert f"--resume {run} (it starts the run again)" in err
        return
    steps, checkpoint = latest_checkpoint(run)
    assert steps >= 128
    assert f"checkpoint {checkpoint}" in err
    assert f"resume with: python -m agents.train --resume {run}" in err
    assert checkpoint.with_name(f"step_{steps}_vecnormalize.pkl").is_file()
    with zipfile.ZipFile(checkpoint) as archive:
        assert json.loads(archive.read(AGENT_ENTRY))["obs_normalization"]["var"]
    # The resume extends the run: a new budget, the same learning.
    train.main(["--resume", str(run), f"total_timesteps={steps + 256}", "--no-progress"])
    assert PPO.load(run / "model.zip").num_timesteps >= steps + 256
    assert load_config(run / "config.yaml").total_timesteps == steps + 256
    meta = json.loads((run / "meta.json").read_text())
    assert meta["resumes"][0]["overrides"] == [f"total_timesteps={steps + 256}"]


def test_a_run_stopped_in_its_warm_start_is_trained_again(tmp_path, monkeypatch, capsys):
    """A stop in the warm start saves no checkpoint (one would skip the rest of the warm start
    for good); the resume trains the run from the start: the run never stopped, bit for bit."""
    import pickle
    import signal

    import torch
    from stable_baselines3 import PPO

    from agents import imitation

    config, overrides = ROOT / "configs/agents/ppo.yaml", ["imitation_steps=64"]
    whole = tiny_run(config, tmp_path / "whole", *overrides)
    fits = []

    def stopped_in_the_fit(*args, **kwargs):
        fits.append(imitation.imitate(*args, **kwargs))
        if len(fits) == 1:
            signal.raise_signal(signal.SIGINT)  # (StopRequest's: the stop turns true)
        return fits[-1]

    monkeypatch.setattr("agents.train.imitate", stopped_in_the_fit)
    with pytest.raises(SystemExit) as exit_:
        tiny_run(config, tmp_path / "runs", *overrides)
    assert exit_.value.code == 128 + signal.SIGINT
    (run,) = (tmp_path / "runs").iterdir()
    assert latest_checkpoint(run) is None and not (run / "model.zip").exists()
    assert "stopped in the warm start, before learning: nothing saved" in capsys.readouterr().err
    train.main(["--resume", str(run), "--no-progress"])
    assert len(fits) == 2 and "training it again from the start" in capsys.readouterr().out
    trained, again = (PPO.load(path / "model.zip").policy.state_dict() for path in (whole, run))
    assert all(torch.equal(trained[key], again[key]) for key in trained)
    trained, again = (pickle.loads((path / "model_vecnormalize.pkl").read_bytes())
                      for path in (whole, run))  # fmt: skip
    for rms in ("obs_rms", "ret_rms"):
        for moment in ("mean", "var"):
            assert np.array_equal(getattr(getattr(trained, rms), moment),
                                  getattr(getattr(again, rms), moment))  # fmt: skip


def test_a_resume_refuses_keys_that_would_change_what_was_learned(tmp_path, capsys):
    run = tiny_run(ROOT / "configs/agents/ppo.yaml", tmp_path / "runs")
    before = (run / "config.yaml").read_text()
    for key in ("hyperparams.learning_rate=0.1", "env.kwargs.frame_skip=2", "seed=3"):
        with pytest.raises(SystemExit) as exit_:
            train.main(["--resume", str(run), key, "--no-progress"])
        assert exit_.value.code == 2
        name = key.partition("=")[0]
        assert f"--resume: {name!r} would change what the run learned" in capsys.readouterr().err
    assert (run / "config.yaml").read_text() == before
    with pytest.raises(SystemExit):
        train.main(["--resume", str(run), "max_minutes=-1", "--no-progress"])
    assert "max_minutes" in capsys.readouterr().err
    assert (run / "config.yaml").read_text() == before


def test_the_progress_bar_counts_down_to_max_minutes(monkeypatch):
    from agents.runs import ProgressBar

    clock = [1000.0]
    monkeypatch.setattr("agents.runs.time.monotonic", lambda: clock[0])
    config = load_config(ROOT / "configs/agents/ppo.yaml", ["max_minutes=1"])
    bar = ProgressBar(config, 0, deadline=1060.0, show=True)
    clock[0] = 1010.0
    bar.update(1000)  # 100 steps/s with 50 s left: the run will end at 6000 steps
    assert bar.bar.total == 6000 and bar.bar.desc.startswith("stops at max_minutes")
    clock[0] = 1020.0
    bar.update(2000)
    assert bar.bar.total == 6000
    unlimited = ProgressBar(
        load_config(ROOT / "configs/agents/ppo.yaml", ["max_minutes=0"]), 0, 0.0, True
    )
    clock[0] = 1030.0
    unlimited.update(1000)
    assert unlimited.bar.total == config.total_timesteps
    bar.close()
    unlimited.close()


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
