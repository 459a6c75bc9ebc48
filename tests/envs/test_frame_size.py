"""One frame size per env: procgen frames keep their size from layout to layout (the table fitted
and letterboxed), so Gymnasium's RecordVideo and HumanRendering (single and vector) and SB3's
VecVideoRecorder take them across episodes; Pinball-v0's frames are as they were."""

import math

import gymnasium as gym
import numpy as np
import pytest

import pinball_env  # noqa: F401  (registers the envs)
from pinball_env.envs import frame_size, layout_table
from pinball_env.render import (
    BACKGROUND,
    SCOREBOARD_WIDTH,
    FrameRenderer,
    Renderer,
    fit_size,
    render_size,
)
from pinball_env.table import load_table

# Three layouts whose tables differ in size (checked below), short episodes.
PROCGEN = {"num_layouts": 3, "start_layout": 0, "balls": 1, "max_episode_steps": 12}


def test_the_layouts_played_here_differ_in_size():
    sizes = {render_size(layout_table(layout, "easy")) for layout in range(3)}
    assert len(sizes) == 3  # without one frame size, their frames would differ


@pytest.mark.parametrize("difficulty", ["easy", "hard"])
def test_procgen_frames_have_one_size_with_the_table_fitted_in(difficulty):
    width, height = frame_size(difficulty)
    assert (width, height) == (360, 792)  # 0.60 m x 1.32 m, the largest table, at 600 px/m
    env = gym.make("PinballProcgen-v0", render_mode="rgb_array", difficulty=difficulty,
                   **PROCGEN)  # fmt: skip
    layouts = set()
    for seed in range(6):
        _, info = env.reset(seed=seed)
        layouts.add(info["layout"])
        frame = env.render()
        assert frame.shape == (height, width + SCOREBOARD_WIDTH, 3) and frame.dtype == np.uint8
        # The table as large as it fits, aspect kept, centred, the background around it.
        table = env.unwrapped.table
        inner_width, inner_height = fit_size(table, width, height)
        assert inner_width == width or inner_height == height
        assert inner_width / inner_height == pytest.approx(table.width / table.height, rel=0.01)
        top, left = (height - inner_height) // 2, (width - inner_width) // 2
        world = env.unwrapped.game.world
        alone = Renderer(table, inner_width, inner_height).frame(
            tuple(world.balls[0, 0, :2]), world.state.flipper_angle[0]
        )
        playfield = frame[:, :width]
        assert playfield[top : top + inner_height, left : left + inner_width].tobytes() == (
            alone.tobytes()
        )
        margins = np.ones((height, width), dtype=bool)
        margins[top : top + inner_height, left : left + inner_width] = False
        assert (playfield[margins] == BACKGROUND).all()
    assert len(layouts) > 1


def test_procgen_vector_frames_are_the_single_envs():
    vector = gym.make_vec("PinballProcgen-v0", num_envs=3, render_mode="rgb_array", **PROCGEN)
    singles = [gym.make("PinballProcgen-v0", render_mode="rgb_array", **PROCGEN) for _ in range(3)]
    vector.reset(seed=[0, 1, 2])
    for env, single in enumerate(singles):
        single.reset(seed=env)
    for _ in range(5):
        vector.step(np.array([1, 2, 3]))
        for env, single in enumerate(singles):
            single.step(env + 1)
    frames = vector.render()
    assert len({frame.shape for frame in frames}) == 1
    for frame, single in zip(frames, singles, strict=True):
        assert frame.tobytes() == single.render().tobytes()


def test_pinball_v0_frames_are_as_they_were():
    env = gym.make("Pinball-v0", render_mode="rgb_array")
    env.reset(seed=0)
    frame = env.render()
    table = env.unwrapped.table
    width, height = render_size(table)
    assert frame.shape == (642, 306 + SCOREBOARD_WIDTH, 3) == (height, width + SCOREBOARD_WIDTH, 3)
    world = env.unwrapped.game.world
    playfield = Renderer(table, width, height).frame(
        tuple(world.balls[0, 0, :2]), world.state.flipper_angle[0]
    )
    assert frame[:, :width].tobytes() == playfield.tobytes()


def test_a_frame_renderer_of_the_tables_own_size_is_its_renderer():
    table = load_table("classic")
    angles = [math.radians(f.rest_angle) for f in table.flippers]
    fitted = FrameRenderer(table, *render_size(table))
    plain = Renderer(table, *render_size(table))
    assert fitted.frame((0.2, 0.4), angles).tobytes() == plain.frame((0.2, 0.4), angles).tobytes()
    gray = fitted.grayscale(None, angles)
    assert gray.shape == (642, 306, 1) and gray.tobytes() == plain.grayscale(None, angles).tobytes()
    wide = FrameRenderer(table, 500, 642)  # room at the sides: letterboxed, 306 px wide
    assert (wide.left, wide.top) == (97, 0)
    frames = wide.frames(np.zeros((2, 2)), np.zeros(2, dtype=bool), np.array([angles] * 2), True)
    assert frames.shape == (2, 642, 500, 1)
    assert (
        frames[:, :, 97:403].tobytes()
        == plain.frames(
            np.zeros((2, 2)), np.zeros(2, dtype=bool), np.array([angles] * 2), True
        ).tobytes()
    )


def play(env, episodes: int) -> set[int]:
    """Random play over ``episodes`` episodes; the layouts they were on."""
    env.action_space.seed(0)
    layouts = set()
    for episode in range(episodes):
        _, info = env.reset(seed=episode)
        layouts.add(info["layout"])
        done = False
        while not done:
            *_, terminated, truncated, info = env.step(env.action_space.sample())
            done = terminated or truncated
    return layouts


def test_gymnasium_record_video_across_episodes_on_other_layouts(tmp_path):
    pytest.importorskip("moviepy")
    env = gym.make("PinballProcgen-v0", render_mode="rgb_array", **PROCGEN)
    # One video over four episodes (frames of several layouts), and one per episode.
    across = gym.wrappers.RecordVideo(env, str(tmp_path / "across"), step_trigger=lambda s: s == 0,
                                      video_length=45, disable_logger=True)  # fmt: skip
    assert len(play(across, 4)) > 1
    across.close()
    each = gym.wrappers.RecordVideo(
        gym.make("PinballProcgen-v0", render_mode="rgb_array", **PROCGEN),
        str(tmp_path / "each"), episode_trigger=lambda e: True, disable_logger=True,
    )  # fmt: skip
    play(each, 3)
    each.close()
    assert len(list((tmp_path / "across").glob("*.mp4"))) == 1
    assert len(list((tmp_path / "each").glob("*.mp4"))) == 3


def test_gymnasium_human_rendering_across_episodes(monkeypatch):
    pytest.importorskip("pygame")
    monkeypatch.setenv("SDL_VIDEODRIVER", "dummy")
    env = gym.wrappers.HumanRendering(
        gym.make("PinballProcgen-v0", render_mode="rgb_array", **PROCGEN)
    )
    assert len(play(env, 4)) > 1  # each frame the size of the first (HumanRendering asserts it)
    env.close()


def test_gymnasium_vector_record_video_and_human_rendering(tmp_path, monkeypatch):
    pytest.importorskip("moviepy")
    pytest.importorskip("cv2")  # the vector HumanRendering's
    monkeypatch.setenv("SDL_VIDEODRIVER", "dummy")
    for kind in ("vector_entry_point", "sync"):
        envs = gym.make_vec("PinballProcgen-v0", num_envs=2, vectorization_mode=kind,
                            render_mode="rgb_array", **PROCGEN)  # fmt: skip
        video = gym.wrappers.vector.RecordVideo(
            envs, str(tmp_path / kind), step_trigger=lambda s: s == 0, video_length=40
        )
        window = gym.wrappers.vector.HumanRendering(video)
        window.reset(seed=[1, 2])
        layouts = set()
        for _ in range(40):  # three episodes each, new layouts drawn (NEXT_STEP)
            *_, infos = window.step(np.array([1, 2]))
            layouts.update(infos["layout"].tolist())
        assert len(layouts) > 1
        window.close()
        assert len(list((tmp_path / kind).glob("*.mp4"))) == 1


def test_sb3_vec_video_recorder_on_procgen(tmp_path):
    pytest.importorskip("moviepy")
    from stable_baselines3.common.vec_env import VecVideoRecorder

    from pinball_env.wrappers import SB3VecEnv

    venv = SB3VecEnv(  # every env's infos every step: the test reads each one's layout
        gym.make_vec("PinballProcgen-v0", num_envs=2, render_mode="rgb_array", **PROCGEN),
        step_infos=True,
    )
    recorder = VecVideoRecorder(venv, str(tmp_path), record_video_trigger=lambda s: s == 0,
                                video_length=40)  # fmt: skip
    recorder.seed(0)
    recorder.reset()
    layouts = set()
    for _ in range(41):
        *_, infos = recorder.step(np.array([1, 2]))
        layouts.update(info["layout"] for info in infos)
    recorder.close()
    assert len(layouts) > 1
    assert len(list(tmp_path.glob("*.mp4"))) == 1
