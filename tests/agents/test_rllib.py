"""Ray RLlib training: a real multi-node cluster on this machine (env runners on a worker node),
the command line end to end with resume and evaluation, config errors, atomic checkpoints."""

import csv
import json
import math
from pathlib import Path

import pytest

pytest.importorskip(
    "ray.rllib", reason="Ray RLlib is not installed: pip install -e '.[distributed]'"
)
import ray

from agents import evaluate, rllib
from agents.config import ConfigError, RllibConfig, load_config
from agents.policy import load_policy
from tests.agents.tiny_runs import readme_example, start_training, wait_for

ROOT = Path(__file__).resolve().parents[2]
CONFIG = ROOT / "configs" / "agents" / "rllib_ppo.yaml"
# One iteration is a few hundred env steps from a few games.
TINY = [
    "env.num_envs=4",
    "hyperparams.train_batch_size_per_learner=256",
    "hyperparams.minibatch_size=128",
    "hyperparams.num_epochs=1",
    "max_minutes=0",
]


@pytest.fixture
def no_ray():
    """Each test starts and stops its own Ray (a local instance or a cluster)."""
    ray.shutdown()
    yield
    ray.shutdown()


def test_env_runners_on_a_worker_node_sample_and_learn(no_ray):
    from ray.cluster_utils import Cluster

    def shipped_packages(runner) -> set[str]:  # (by value: tests/ is not on the nodes)
        """The packages an env runner can import from its job's runtime_env."""
        import sys

        folders = [Path(p) for p in sys.path if "runtime_resources" in p]
        return {name for name in ("agents", "pinball_env") for f in folders if (f / name).is_dir()}

    # The head node has no CPU to offer: the env runners can only be placed on the worker.
    cluster = Cluster(initialize_head=True, head_node_args={"num_cpus": 0})
    worker = cluster.add_node(num_cpus=2)
    try:
        cluster.wait_for_nodes()
        rllib.init_ray(cluster.address)  # joins it, shipping agents and pinball_env
        config = load_config(CONFIG, [*TINY, "env_runners=2"], kind=RllibConfig)
        algo = rllib.build(config)
        try:
            runners = algo.env_runner_group
            nodes = runners.foreach_env_runner(
                lambda runner: ray.get_runtime_context().get_node_id(), local_env_runner=False
            )
            assert nodes == [worker.node_id, worker.node_id]
            # Both packages came with the job (runtime_env), as a node without a checkout needs.
            shipped = runners.foreach_env_runner(shipped_packages, local_env_runner=False)
            assert shipped == [{"agents", "pinball_env"}] * 2
            kinds = runners.foreach_env_runner(
                lambda runner: type(runner.env.unwrapped).__name__, local_env_runner=False
            )
            assert kinds == ["PinballVectorEnv"] * 2  # each steps one native vector env
            result = algo.train()
        finally:
            algo.stop()
    finally:
        ray.shutdown()
        cluster.shutdown()
    sampled = result["env_runners"]["num_env_steps_sampled"]
    assert sampled >= 256  # the batch, from both runners' vector envs
    assert result["num_env_steps_sampled_lifetime"] == sampled
    learner = result["learners"]["default_policy"]
    assert learner["num_module_steps_trained"] > 0
    assert math.isfinite(learner["policy_loss"]) and math.isfinite(learner["vf_loss"])


def test_train_resume_and_evaluate_from_the_command_line(tmp_path, no_ray):
    runs = tmp_path / "runs"
    argv = ["--config", str(CONFIG), *TINY, "env_runners=1", "total_timesteps=500",
            "checkpoint_every=256", "--runs", str(runs), "--no-progress"]  # fmt: skip
    rllib.main(argv)
    (run,) = runs.iterdir()
    assert run.name.startswith("Pinball-v0_rllib-ppo_seed0_")
    assert load_config(run / "config.yaml", kind=RllibConfig).env_runners == 1
    meta = json.loads((run / "meta.json").read_text())
    assert meta["ray"] == ray.__version__ and meta["pinball_env"]
    assert list(run.glob("events.out.tfevents.*")), "TensorBoard logs"
    first = [steps for steps, _ in rllib.checkpoints_of(run)]
    assert first[-1] >= 500 and len(first) >= 2
    assert rllib.is_checkpoint(run) and rllib.is_checkpoint(
        run / "checkpoints" / f"step_{first[0]}"
    )

    # Resumed with a bigger budget: the step count goes on from the last checkpoint.
    with open(run / "progress.csv", "a") as file:  # as if logged after the last checkpoint
        file.write(f"{10**9}" + ",0" * 13 + "\n")
    ray.shutdown()
    with pytest.raises(SystemExit):  # what was learned stays as it was
        rllib.main(["--resume", str(run), "hyperparams.lr=0.1", "--no-progress"])
    rllib.main(["--resume", str(run), "total_timesteps=900", "--no-progress"])
    assert load_config(run / "config.yaml", kind=RllibConfig).total_timesteps == 900
    with open(run / "progress.csv") as file:
        steps = [int(row["time/total_timesteps"]) for row in csv.DictReader(file)]
    assert steps == sorted(set(steps)) and steps[-1] >= 900  # counted on, not from zero
    assert rllib.checkpoints_of(run)[-1][0] == steps[-1]

    # Evaluated like an SB3 model, with the same rollouts and metrics, deterministically.
    summaries = [
        evaluate.main(["--model", str(run), "--episodes", "2", "--out", str(tmp_path / f"e{i}")])
        for i in range(2)
    ]
    assert summaries[0]["episodes"] == 2 and summaries[0]["seeds"] == [100_000, 100_001]
    assert (tmp_path / "e0" / "episodes.csv").read_text() == (
        tmp_path / "e1" / "episodes.csv"
    ).read_text()
    # The docs' load_policy example plays the same games through load_policy.
    with open(tmp_path / "e0" / "episodes.csv") as file:
        expected = [int(row["score"]) for row in csv.DictReader(file)]
    assert [readme_example(run, 100_000 + game) for game in range(2)] == expected
    checkpoint = run / "checkpoints" / f"step_{first[0]}"
    video = tmp_path / "game.gif"
    summary = evaluate.main(["--model", str(checkpoint), "--episodes", "1", "--video", str(video)])
    assert summary["episodes"] == 1 and video.stat().st_size > 0


def test_the_policy_sees_observations_as_training_normalised_them(tmp_path, no_ray, monkeypatch):
    """The checkpoint's policy applies RLlib's MeanStdFilter with the trained statistics."""
    import pickle

    import numpy as np
    from ray.rllib.core.rl_module.rl_module import RLModule
    from ray.rllib.utils.filter import RunningStat

    runs = tmp_path / "runs"
    rllib.main(["--config", str(CONFIG), *TINY, "env_runners=0", "total_timesteps=200",
                "--runs", str(runs), "--no-progress"])  # fmt: skip
    (run,) = runs.iterdir()
    checkpoint, _ = rllib.load_checkpoint(run)
    assert (checkpoint / "config.yaml").is_file()  # a checkpoint copied alone loads
    seen = []
    load = RLModule.from_checkpoint

    def spied(path):  # the module, its inputs recorded
        module = load(path)
        forward = module.forward_inference
        module.forward_inference = lambda batch: seen.append(batch["obs"].numpy()) or forward(batch)
        return module

    monkeypatch.setattr(RLModule, "from_checkpoint", spied)
    obs = np.random.default_rng(0).normal(size=(3, 10)).astype(np.float32)
    policy = load_policy(run)
    actions = policy.act(policy.normalization(obs))
    assert actions.shape == (3,) and set(actions) <= {0, 1, 2, 3}
    state_file = checkpoint.joinpath(*rllib.FILTER_PATH) / "state.pkl"
    state = pickle.loads(state_file.read_bytes())[None]
    stat = RunningStat.from_state(state["running_stats"][0])
    assert stat.n >= 200  # the observations of the training games
    expected = np.clip((obs - stat.mean) / (stat.std + 1e-6), -10, 10)  # RLlib's SMALL_NUMBER
    np.testing.assert_allclose(seen[0], expected, rtol=1e-5)


def test_each_env_runner_plays_its_own_block_of_seeds():
    env = rllib.make_rllib_env(
        {"id": "Pinball-v0", "seed": 10, "num_envs": 4, "max_episode_steps": None}
    )
    assert type(env.unwrapped).__name__ == "PinballVectorEnv"  # the native vector env
    seen = []
    reset = env.env.reset
    env.env.reset = lambda seed=None, options=None: seen.append(seed) or reset(seed=seed)
    for runner in range(3):  # RLlib resets runner k with seed + k
        env.reset(seed=10 + runner)
    assert seen == [10, 14, 18]  # games 10-13, 14-17, 18-21: no stream shared


def test_a_checkpoint_write_killed_midway_leaves_no_checkpoint(tmp_path):
    class Dying:
        def save_to_path(self, path):
            Path(path).mkdir()
            (Path(path) / "algorithm_state.pkl").write_bytes(b"half")
            raise KeyboardInterrupt  # killed before the checkpoint was whole

    class Whole:
        def save_to_path(self, path):
            Path(path).mkdir()
            (Path(path) / rllib.RLLIB_CHECKPOINT_FILE).write_text("{}")

    folder = tmp_path / "checkpoints"
    folder.mkdir()
    config = RllibConfig()
    rllib.save_checkpoint(Whole(), folder / "step_100", config)
    with pytest.raises(KeyboardInterrupt):
        rllib.save_checkpoint(Dying(), folder / "step_200", config)
    assert [steps for steps, _ in rllib.checkpoints_of(tmp_path)] == [100]
    assert not (folder / "step_200").exists()
    rllib.save_checkpoint(Whole(), folder / "step_100", config)  # again over itself: whole
    assert [path.name for path in folder.iterdir() if not path.name.startswith(".")] == ["step_100"]


@pytest.mark.parametrize(
    ("overrides", "message"),
    [
        (["hyperparams.n_steps=128"], "hyperparams.n_steps: not an option of PPO"),
        (["model.fcnet_width=3"], "model.fcnet_width: not an option of DefaultModelConfig"),
        (["hyperparams.lr=.nan"], "hyperparams.lr: must be finite"),
        (["env_runners=-1"], "env_runners: must be an integer >= 0"),
        (["cpus_per_env_runner=0"], "cpus_per_env_runner: must be a number of CPUs > 0"),
        (["algo=dqn"], "algo: unknown algorithm 'dqn'"),
        (["env.kwargs.obs_type=grayscale"], "obs_type: RLlib runs train on state observations"),
        (["env.frame_stack=4"], "env.frame_stack: RLlib runs do not stack frames"),
        (["eval_seed=47"], r"eval_seed: 47 overlaps the training seeds 0..47"),
        (["env.kwargs.table=nowhere"], "env.kwargs: unknown table 'nowhere'"),
        (["policy=MlpPolicy"], r"a stable-baselines3 config.*agents\.train"),
    ],
)
def test_bad_rllib_configs_are_rejected_naming_the_key(overrides, message):
    with pytest.raises(ConfigError, match=message):
        load_config(CONFIG, overrides, kind=RllibConfig)


def test_the_command_line_fails_clearly_before_training(tmp_path, capsys):
    runs = tmp_path / "runs"
    for argv, message in (
        (["--resume", str(tmp_path / "nothing")], "not a run folder"),
        (["--config", str(CONFIG), "env_runners=x"], "env_runners: must be an integer"),
        (["--config", str(ROOT / "configs/agents/ppo.yaml")], "a stable-baselines3 config"),
        ([], "give --config"),
        (["--config", str(CONFIG), "--scaling", "-1"], "env runner counts must be >= 0"),
    ):
        with pytest.raises(SystemExit) as exit_:
            rllib.main([*argv, "--runs", str(runs)])
        assert exit_.value.code == 2
        assert message in capsys.readouterr().err
    assert not runs.exists()
    assert not ray.is_initialized()  # nothing was started


def test_more_env_runners_than_cpus_is_an_error_not_a_hang(tmp_path, no_ray, capsys):
    rllib.init_ray(num_cpus=2)
    with pytest.raises(SystemExit):
        rllib.main(["--config", str(CONFIG), *TINY, "env_runners=3", "--runs", str(tmp_path)])
    assert (
        "env_runners: 3 x cpus_per_env_runner 1 needs 3 CPUs, Ray has 2" in capsys.readouterr().err
    )
    assert not any(tmp_path.iterdir())  # no run folder left behind


def test_an_rllib_config_given_to_the_sb3_trainer_says_where_it_belongs():
    with pytest.raises(ConfigError, match=r"an RLlib config.*agents\.rllib"):
        load_config(CONFIG)


def test_scaling_measures_each_runner_count(tmp_path, no_ray):
    rllib.init_ray(num_cpus=2)
    config = load_config(CONFIG, TINY, kind=RllibConfig)
    rows = rllib.scaling(config, [0, 1, 4], iterations=1, out=tmp_path / "scaling.json")
    assert [row["env_runners"] for row in rows] == [0, 1, 4]
    assert [row["cpus_per_runner"] for row in rows] == [1, 1, 0.5]  # 4 runners share 2 CPUs
    assert all(row["steps"] >= 256 and row["sampled_steps_per_s"] > 0 for row in rows)
    saved = json.loads((tmp_path / "scaling.json").read_text())
    assert saved["rows"] == rows


def test_a_signal_saves_a_checkpoint_and_says_how_to_resume(tmp_path):
    import signal

    runs = tmp_path / "runs"
    budget = ["env_runners=0", "total_timesteps=100000000", "checkpoint_every=0"]
    process = start_training(runs, *TINY, *budget, module="agents.rllib", config=CONFIG)
    wait_for(lambda: any(runs.glob("*/progress.csv")), process)  # an iteration is done
    process.send_signal(signal.SIGINT)
    _, err = process.communicate(timeout=180)
    assert process.returncode == 128 + signal.SIGINT, err
    (run,) = runs.iterdir()
    steps, checkpoint = rllib.checkpoints_of(run)[-1]
    assert steps > 0 and (checkpoint / "config.yaml").is_file()
    assert f"resume with: python -m agents.rllib --resume {run}" in err
    assert "Traceback" not in err


def test_the_benchmark_sends_each_job_to_a_worker_node_and_gathers_its_folder(tmp_path, no_ray):
    from ray.cluster_utils import Cluster

    from agents.benchmark.cli import main as benchmark_main
    from agents.benchmark.jobs import JOB_FILE

    # The head node has no CPU: every job runs on the worker, in its scratch folder, and only
    # what comes back lands in OUT.
    cluster = Cluster(initialize_head=True, head_node_args={"num_cpus": 0})
    worker = cluster.add_node(num_cpus=2)
    try:
        cluster.wait_for_nodes()
        jobs = ["--methods", "random-v0", "ppo-v0", "--seeds", "0", "1"]
        table = benchmark_main(["--tiny", "--address", cluster.address, "--out", str(tmp_path),
                                *jobs])  # fmt: skip
    finally:
        ray.shutdown()
        cluster.shutdown()
    ppo = table["methods"]["ppo-v0"]
    assert [run["seed"] for run in ppo["runs"]] == [0, 1]
    for folder in (tmp_path / "ppo-v0" / "seed0", tmp_path / "ppo-v0" / "seed1",
                   tmp_path / "random-v0"):  # fmt: skip
        assert json.loads((folder / JOB_FILE).read_text())["node"] == worker.node_id
    for run in ppo["runs"]:
        assert (tmp_path / run["run"] / "model.zip").is_file()
        assert (tmp_path / run["run"] / "protocol_eval" / "episodes.csv").is_file()
    assert (tmp_path / "benchmark.json").is_file() and (tmp_path / "profiles.png").is_file()
