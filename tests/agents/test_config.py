"""Configs (agents.config): bad keys and files refused by name, bases laid under variants,
schedules, and the rl_zoo3 hyperparameters."""

import csv
import dataclasses
import sys

import numpy as np
import pytest
import yaml
from stable_baselines3 import PPO

from agents.config import ConfigError, load_config, sb3_hyperparams, schedule
from tests.agents.tiny_runs import CONFIGS_DIR, ROOT, tiny_run


@pytest.mark.parametrize(
    ("overrides", "message"),
    [
        (["algo=sac"], "algo: unknown algorithm 'sac'"),
        (["policy=LstmPolicy"], "policy: unknown policy 'LstmPolicy'"),
        (["policy=CnnPolicy"], "CnnPolicy does not fit obs_type 'state'"),
        (["algo=recurrent_ppo"], "recurrent_ppo takes MlpLstmPolicy, and only it does"),
        (["policy=MlpLstmPolicy"], "recurrent_ppo takes MlpLstmPolicy, and only it does"),
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
        (
            ["hyperparams.learning_rate=lin_x"],
            "learning_rate: a schedule is lin_X or cos_X",
        ),
        (
            ["hyperparams.clip_range=lin_-0.2"],
            "clip_range: a schedule is lin_X or cos_X",
        ),
        (["hyperparams.ent_coef=cos_0"], "ent_coef: a schedule is lin_X or cos_X with X > 0"),
        (
            ["algo=dqn", "hyperparams={ent_coef: lin_0.01}"],
            "ent_coef: not an option of DQN",
        ),
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


def test_a_cosine_schedule_falls_from_its_start_to_zero_along_a_half_cosine():
    function = schedule("cos_0.02")
    assert function(1.0) == 0.02 and function(0.0) == 0.0
    assert function(0.5) == pytest.approx(0.01)
    left = np.linspace(1.0, 0.0, 11)
    assert (np.diff([function(x) for x in left]) < 0).all()


def test_the_entropy_schedule_is_the_coefficient_each_update_reads(tmp_path, monkeypatch):
    # stable-baselines3 has no entropy schedule; EntropySchedule sets model.ent_coef once a
    # rollout is collected, and PPO's train() reads it: record what each update saw.
    seen = []
    train = PPO.train

    def recording_train(self):
        seen.append((self.num_timesteps, self.ent_coef))
        train(self)

    monkeypatch.setattr(PPO, "train", recording_train)
    run = tiny_run(ROOT / "configs/agents/ppo.yaml", tmp_path / "runs",
                   "hyperparams.ent_coef=lin_0.05", "total_timesteps=640")  # fmt: skip
    assert len(seen) >= 3
    for steps, coefficient in seen:
        assert coefficient == pytest.approx(0.05 * (1.0 - steps / 640))
    with open(run / "progress.csv") as f:
        logged = [float(row["train/ent_coef"]) for row in csv.DictReader(f)
                  if row.get("train/ent_coef")]  # fmt: skip
    assert logged == pytest.approx([coefficient for _, coefficient in seen])


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


def test_a_config_reads_unchecked_without_its_libraries(monkeypatch):
    # The docs' table of configs reads every config, RLlib's too, where Ray is not installed:
    # unchecked, only its keys are; checked, the missing library is named.
    from agents.config import RllibConfig

    monkeypatch.setitem(sys.modules, "ray", None)  # as if not installed
    path = CONFIGS_DIR / "rllib_ppo.yaml"
    config = load_config(path, kind=RllibConfig, check=False)
    assert config.env_runners == 2 and config.env.id == "Pinball-v0"
    with pytest.raises(ConfigError, match="ray is missing"):
        load_config(path, kind=RllibConfig)
    with pytest.raises(ConfigError, match="unknown key"):
        load_config(path, ["no_such_key=1"], kind=RllibConfig, check=False)
