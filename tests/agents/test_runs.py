"""Run folders (agents.runs): atomic checkpoints, the statistics saved first, the progress bar."""

import pytest

from agents.config import load_config
from agents.runs import atomic_write, save_model
from tests.agents.tiny_runs import ROOT


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


def test_the_training_bar_ends_where_the_frame_budget_stops_it():
    # 1000 steps asked, a budget of 600 frames: at 100 steps and 200 frames (2 a step), the
    # bar's end is the 300th step, so it ends at 100% where the budget stops the training.
    from agents.runs import ProgressBar

    config = load_config(ROOT / "configs/agents/ppo.yaml",
                         ["total_timesteps=1000", "total_frames=600"])  # fmt: skip
    bar = ProgressBar(config, 0, deadline=float("inf"), show=True, frames=0)
    bar.update(100, force=True, frames=200)
    assert bar.bar.total == 300 and bar.bar.desc.startswith("stops at total_frames")
    bar.update(300, force=True, frames=600)
    assert bar.bar.n == bar.bar.total == 300
    bar.close()


def test_the_training_bar_shows_its_last_step_however_soon_it_closes(monkeypatch):
    # The bar redraws at most twice a second; the training's last steps come sooner than that
    # after the update before them, and closing shows them: a run the budget stopped ends at 100%.
    from agents.runs import ProgressBar

    clock = [1000.0]
    monkeypatch.setattr("agents.runs.time.monotonic", lambda: clock[0])
    config = load_config(ROOT / "configs/agents/ppo.yaml",
                         ["total_timesteps=1000", "total_frames=600"])  # fmt: skip
    bar = ProgressBar(config, 0, deadline=float("inf"), show=True, frames=0)
    clock[0] = 1001.0
    bar.update(100, frames=200)
    clock[0] = 1001.1
    bar.update(280, frames=560)  # (too soon: not drawn)
    assert bar.bar.n == 100
    clock[0] = 1001.2
    bar.close(302, frames=604)
    assert bar.bar.n == bar.bar.total == 302


def test_news_of_a_training_is_written_above_its_bar(capsys):
    from agents.runs import say

    say("validation at 10 steps")
    assert capsys.readouterr().out == "validation at 10 steps\n"
