"""Playing by hand: the keyboard map (PinballEnv.get_keys_to_action), gymnasium.utils.play on
Pinball-v0 and Pinball-v1, and the play tool (pinball_env.tools.play): keys (the cabinet's too),
pause, restart, quit, recordings and their replays, driven headless by events posted to
pygame's queue."""

import os

# SDL's dummy drivers, before pygame is first imported: no display or sound card needed.
os.environ["SDL_VIDEODRIVER"] = "dummy"
os.environ["SDL_AUDIODRIVER"] = "dummy"

import copy
import itertools
import json
import subprocess
import sys
import warnings
from collections.abc import Callable
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.error import DependencyNotInstalled

import pinball_env
from pinball_env.recording import (
    GameRecord,
    RecordingError,
    decode_recorded_actions,
    load_recording,
    parse_recording,
    table_sha256,
    write_recording,
)
from pinball_env.table import load_table
from pinball_env.tools import play

pygame = pytest.importorskip("pygame")

LEFT_KEYS = (pygame.K_LSHIFT, pygame.K_z, pygame.K_LEFT)
RIGHT_KEYS = (pygame.K_RSHIFT, pygame.K_m, pygame.K_RIGHT)
PLUNGER_KEYS = (pygame.K_DOWN, pygame.K_RETURN)
NUDGE_KEYS = ((pygame.K_x,), (pygame.K_n,), (pygame.K_UP, pygame.K_b))  # left, right, up
CABINET_KEYS = (*PLUNGER_KEYS, *(key for keys in NUDGE_KEYS for key in keys))
LEFT, RIGHT = 4, 5  # the flipper angles' indices in the state observation


def down(key: int) -> Any:
    return pygame.event.Event(pygame.KEYDOWN, key=key)


def up(key: int) -> Any:
    return pygame.event.Event(pygame.KEYUP, key=key)


def scripted(script: dict[int, list[Any]]) -> Callable[[], list[Any]]:
    """An event source that posts the events of its n-th call (frame) to pygame's queue, then
    reads the queue, as the play loop's default source does."""
    calls = itertools.count()

    def source() -> list[Any]:
        for event in script.get(next(calls), []):
            pygame.event.post(event)
        return pygame.event.get()

    return source


@pytest.fixture
def loop():
    session = play.PlayLoop(
        {"balls": 1}, seed=3, fps=0, env_id="Pinball-v0"
    )  # fps 0: no waiting between frames
    yield session
    session.close()


# --- the key map and render_fps -------------------------------------------------------------


def test_keys_to_action_maps_every_combination_of_the_flipper_keys():
    env = gym.make("Pinball-v0")
    mapping = env.unwrapped.get_keys_to_action()
    keys = LEFT_KEYS + RIGHT_KEYS
    combinations = [
        c for n in range(1, len(keys) + 1) for c in itertools.combinations(sorted(keys), n)
    ]
    assert sorted(mapping) == sorted(combinations)  # sorted tuples, every non-empty set
    for combination, action in mapping.items():
        left = any(key in LEFT_KEYS for key in combination)
        right = any(key in RIGHT_KEYS for key in combination)
        assert action == left + 2 * right, combination
    assert mapping[(pygame.K_z,)] == mapping[(pygame.K_LSHIFT,)] == 1
    assert mapping[(pygame.K_m,)] == mapping[(pygame.K_RSHIFT,)] == 2
    assert mapping[tuple(sorted((pygame.K_LSHIFT, pygame.K_RSHIFT)))] == 3
    assert mapping[tuple(sorted((pygame.K_z, pygame.K_m)))] == 3


def test_keys_to_action_gives_button_arrays_for_multibinary():
    env = gym.make("Pinball-v0", action_type="multibinary")
    mapping = env.unwrapped.get_keys_to_action()
    assert len(mapping) == 2 ** len(LEFT_KEYS + RIGHT_KEYS) - 1
    assert mapping[(pygame.K_z,)].tolist() == [1, 0]
    assert mapping[(pygame.K_RSHIFT,)].tolist() == [0, 1]
    assert mapping[tuple(sorted((pygame.K_LSHIFT, pygame.K_m)))].tolist() == [1, 1]
    assert all(action in env.action_space for action in mapping.values())


@pytest.mark.parametrize(("frame_skip", "fps"), [(1, 60), (4, 15), (7, 9), (60, 1)])
def test_render_fps_is_an_int(frame_skip, fps):
    env = gym.make("Pinball-v0", frame_skip=frame_skip)
    assert type(env.metadata["render_fps"]) is int and env.metadata["render_fps"] == fps
    assert env.unwrapped.steps_per_second == pytest.approx(60 / frame_skip)  # windows' rate


def test_render_fps_of_the_procgen_env_is_an_int():
    env = gym.make("PinballProcgen-v0", num_layouts=1, frame_skip=7)
    assert type(env.metadata["render_fps"]) is int and env.metadata["render_fps"] == 9


@pytest.mark.parametrize("action_type", ["discrete", "multibinary"])
def test_gymnasium_play_works_with_no_key_map(action_type):
    with warnings.catch_warnings():  # it warns at import when matplotlib cannot use Tk
        warnings.simplefilter("ignore")
        from gymnasium.utils.play import play as gymnasium_play

    actions: list[int] = []
    quit_event = pygame.event.Event(pygame.QUIT)
    events = {0: down(pygame.K_LSHIFT), 5: down(pygame.K_m), 10: up(pygame.K_LSHIFT)}

    def callback(obs_t, obs_tp1, action, reward, terminated, truncated, info):
        buttons = np.asarray(action).tolist()  # (left, right), or the Discrete(4) action
        actions.append(buttons[0] + 2 * buttons[1] if action_type == "multibinary" else buttons)
        step = len(actions) - 1
        if step in events or step >= 15:  # QUIT ends play (and a loop that missed one)
            pygame.event.post(events.get(step, quit_event))

    env = gym.make("Pinball-v0", render_mode="rgb_array", action_type=action_type)
    noop = np.array([0, 0], dtype=np.int8) if action_type == "multibinary" else 0
    gymnasium_play(env, callback=callback, seed=0, noop=noop)
    # Each event acts from the next step on: left, then both, then right alone.
    assert actions == [0] + [1] * 5 + [3] * 5 + [2] * 5


# --- the play loop --------------------------------------------------------------------------


def test_holding_a_flipper_key_raises_that_flipper(loop):
    top = loop.env.observation_space.high[LEFT]
    loop.run(scripted({0: [down(pygame.K_LSHIFT)]}), max_frames=10)
    assert loop.actions == [1] * 10
    assert loop.observation[LEFT] == pytest.approx(top) and loop.observation[RIGHT] == 0.0
    # Left released, right held (by M): the left falls back to rest, the right goes up.
    loop.run(scripted({0: [up(pygame.K_LSHIFT), down(pygame.K_m)]}), max_frames=10)
    assert loop.actions == [1] * 10 + [2] * 10
    assert loop.observation[LEFT] == 0.0 and loop.observation[RIGHT] == pytest.approx(top)
    loop.run(scripted({0: [down(pygame.K_z)]}), max_frames=3)  # Z and M: both
    assert loop.actions[-3:] == [3, 3, 3]


def test_losing_the_window_focus_releases_the_keys(loop):
    focus_lost = pygame.event.Event(pygame.WINDOWFOCUSLOST)
    loop.run(scripted({0: [down(pygame.K_RSHIFT)], 3: [focus_lost]}), max_frames=6)
    assert loop.actions == [2, 2, 2, 0, 0, 0]


def test_pause_stops_the_game_and_resumes_it(loop):
    loop.run(scripted({5: [down(pygame.K_p)]}), max_frames=20)
    assert loop.paused and loop.info["frames"] == 5 and loop.frames_shown == 20
    assert len(loop.actions) == 5
    loop.run(scripted({0: [down(pygame.K_SPACE)]}), max_frames=5)  # Space resumes too
    assert not loop.paused and loop.info["frames"] == 10


def test_restart_starts_a_new_game_with_the_next_seed(loop):
    loop.run(scripted({0: [down(pygame.K_z)], 8: [down(pygame.K_r)]}), max_frames=12)
    assert [(g.seed, g.frames, g.end) for g in loop.games] == [(3, 8, "restart")]
    assert loop.seed == 4 and loop.info["frames"] == 4
    assert loop.actions == [1] * 4  # the key is still held in the new game


@pytest.mark.parametrize("event", ["q", "escape", "close"])
def test_quit_keys_and_closing_the_window_end_the_loop(loop, event):
    quit_event = {
        "q": down(pygame.K_q),
        "escape": down(pygame.K_ESCAPE),
        "close": pygame.event.Event(pygame.QUIT),
    }[event]
    loop.run(scripted({4: [quit_event]}), max_frames=100)
    assert not loop.running and loop.frames_shown == 4
    loop.run(max_frames=10)  # a loop that quit plays no more
    assert loop.frames_shown == 4


def play_until_over(session: play.PlayLoop, source: Callable[[], list[Any]] | None = None) -> None:
    """Run ``session`` until its game is over (a few frames more at most), or fail."""
    for _ in range(100):
        if session.over:
            return
        session.run(source, max_frames=20)
    raise AssertionError("the game did not end in 2000 frames")


def test_a_game_over_waits_for_a_new_game(loop):
    play_until_over(loop)  # no flipper: the one ball drains
    (game,) = loop.games
    assert game.end == "game over" and loop.over and loop.frames_shown > game.frames
    assert len(game.actions) == game.frames and set(game.actions) == {"0"}
    loop.run(scripted({0: [down(pygame.K_p)]}), max_frames=2)  # no pause once it is over
    assert not loop.paused and loop.info["frames"] == game.frames


# --- recordings -----------------------------------------------------------------------------


@pytest.fixture(scope="module")
def recorded(tmp_path_factory) -> tuple[Path, tuple[GameRecord, ...]]:
    """A recording of two games: one to game over with both flippers worked, then a restart,
    one that the player quits."""
    path = tmp_path_factory.mktemp("play") / "games.json"
    session = play.PlayLoop({"balls": 1}, seed=3, record=path, fps=0, env_id="Pinball-v0")
    script = {
        0: [down(pygame.K_LSHIFT)],
        30: [up(pygame.K_LSHIFT)],
        60: [down(pygame.K_RSHIFT), down(pygame.K_z)],
        70: [up(pygame.K_z)],
        90: [up(pygame.K_RSHIFT)],
    }
    play_until_over(session, scripted(script))
    session.run(scripted({0: [down(pygame.K_r)], 1: [down(pygame.K_m)]}), max_frames=40)
    session.close()  # ends the second game
    return path, session.games


def test_a_recording_holds_the_games_and_the_env(recorded):
    path, games = recorded
    data = json.loads(path.read_text())
    assert data["format"] == "pinball-env-recording" and data["version"] == 1
    assert data["package_version"] == pinball_env.__version__
    assert data["env_id"] == "Pinball-v0" and data["options"] == {"table": "classic", "balls": 1}
    assert data["max_episode_steps"] == pinball_env.MAX_EPISODE_STEPS
    assert [(g["seed"], g["end"]) for g in data["games"]] == [(3, "game over"), (4, "quit")]
    first = data["games"][0]["actions"]
    assert first[:30] == "1" * 30 and first[60:70] == "3" * 10 and first[70:90] == "2" * 20
    assert data["games"][1]["actions"] == "0" + "2" * 39
    assert load_recording(path).games == games


def test_replay_gives_the_recorded_scores(recorded, capsys):
    path, games = recorded
    recording = load_recording(path)
    assert play.replay(recording) == [game.score for game in games]
    assert play.main(["--replay", str(path), "--headless"]) == [game.score for game in games]
    assert "as recorded" in capsys.readouterr().out


def test_replay_in_a_window_and_stopping_it(recorded):
    path, games = recorded
    recording = load_recording(path)
    assert play.replay(recording, window=True, fps=0) == [game.score for game in games]
    with pytest.raises(play.ReplayStopped, match="game 1"):
        play.replay(recording, window=True, fps=0, events=scripted({3: [down(pygame.K_q)]}))


def test_the_tool_runs_as_a_module(recorded):
    path, games = recorded
    out = subprocess.run(
        [sys.executable, "-m", "pinball_env.tools.play", "--replay", str(path), "--headless"],
        capture_output=True, text=True, check=True,
    )  # fmt: skip
    assert f"seed 3: score {games[0].score} in {games[0].frames} frames" in out.stdout


def edited(recorded, edit: Callable[[dict[str, Any]], None]) -> dict[str, Any]:
    data = copy.deepcopy(json.loads(recorded[0].read_text()))
    edit(data)
    return data


def _set(*path_and_value: Any) -> Callable[[dict[str, Any]], None]:
    *path, value = path_and_value

    def edit(data: dict[str, Any]) -> None:
        for key in path[:-1]:
            data = data[key]
        data[path[-1]] = value

    return edit


def _delete(key: str) -> Callable[[dict[str, Any]], None]:
    return lambda data: data.pop(key)


@pytest.mark.parametrize(
    ("edit", "message"),
    [
        (_set("version", 3), r"format version 3; this pinball-env reads versions 1 and 2"),
        (_set("version", True), r"format version True; this pinball-env reads versions"),
        (_set("format", "other"), r"not a pinball recording \(format 'other'"),
        (_set("package_version", "0.0.1"), r"recorded with pinball-env 0\.0\.1, this is"),
        (_delete("games"), r"missing key games"),
        (_set("extra", 1), r"unknown key extra"),
        (_set("games", 0, "seed", "3"), r"games\[0\]\.seed must be int"),
        (_set("games", 0, "score", True), r"games\[0\]\.score must be int, got true"),
        (_set("games", 1, "actions", "0124"), r"games\[1\]\.actions: '4' at step 3"),
        (_set("games", 1, "actions", "01-1"), r"'-' at step 2 is not an action"),
        (_set("games", 1, "actions", "01a"), r"'a' at step 2 is not an action \(one digit 0-3"),
        (_set("games", 0, "end", "tilt"), r"games\[0\]\.end must be one of"),
        (_set("games", 0, "frames", -1), r"games\[0\]\.frames must be >= 0"),
        (_set("games", []), r"holds no game"),
        (_set("options", "render_mode", "human"), r"options\.render_mode is set by the play"),
        (
            _set("env_id", "CartPole-v1"),
            r"only 'Pinball-v0', 'Pinball-v1', 'Pinball-v2' or 'Pinball-v3' games",
        ),
        (_set("table_sha256", "abc"), r"table_sha256 must be 64"),
    ],
)
def test_a_bad_recording_is_refused_naming_the_problem(recorded, tmp_path, edit, message):
    path = tmp_path / "bad.json"
    path.write_text(json.dumps(edited(recorded, edit)))
    with pytest.raises(RecordingError, match=message):
        load_recording(path)
    with pytest.raises(SystemExit, match="refused: .*" + message):
        play.main(["--replay", str(path), "--headless"])


@pytest.mark.parametrize(
    ("text", "message"),
    [("{not json", "not a JSON recording"), ("[1, 2]", "expected a JSON object, got list")],
)
def test_a_file_that_is_not_a_recording_is_refused(tmp_path, text, message):
    path = tmp_path / "bad.json"
    path.write_text(text)
    with pytest.raises(RecordingError, match=message):
        load_recording(path)


@pytest.mark.parametrize(
    ("edit", "message"),
    [
        (_set("games", 0, "score", 1), r"game 1 \(seed 3\): the replay scored \d+ .* says 1 in"),
        (_set("games", 0, "seed", 4), r"game 1 \(seed 4\): the replay"),
        (_set("games", 1, "end", "game over"), r"\(unfinished\), the recording says .*game over"),
        (_set("table_sha256", "0" * 64), r"is not the recorded one"),
        (_set("options", "balls", 0), r"options do not make a game"),
    ],
)
def test_a_replay_that_differs_from_its_recording_is_refused(recorded, edit, message):
    recording = parse_recording(edited(recorded, edit))
    with pytest.raises(RecordingError, match=message):
        play.replay(recording)


def test_a_replay_that_ends_before_its_actions_is_refused(recorded):
    # Steps after the game over: the recording cannot be of this game.
    data = edited(recorded, lambda d: d["games"][0].update(actions=d["games"][0]["actions"] + "0"))
    with pytest.raises(RecordingError, match=r"the replay ended \(game over\) at step"):
        play.replay(parse_recording(data))


def test_a_written_recording_loads_back_equal(tmp_path, recorded):
    recording = load_recording(recorded[0])
    write_recording(tmp_path / "sub" / "copy.json", recording)
    assert load_recording(tmp_path / "sub" / "copy.json") == recording


# --- without pygame -------------------------------------------------------------------------


def test_without_pygame_play_stops_with_the_install_line(monkeypatch):
    monkeypatch.setitem(sys.modules, "pygame", None)  # makes `import pygame` fail
    with pytest.raises(SystemExit) as stopped:
        play.main(["--seed", "1"])
    line = str(stopped.value)
    assert (
        "\n" not in line and "pip install pygame" in line and 'pip install -e ".[render]"' in line
    )
    with pytest.raises(DependencyNotInstalled, match="pip install pygame"):
        play.PlayLoop()
    with pytest.raises(DependencyNotInstalled, match="pip install pygame"):
        gym.make("Pinball-v0").unwrapped.get_keys_to_action()


def test_a_headless_replay_needs_no_pygame(recorded, monkeypatch):
    path, games = recorded
    monkeypatch.setitem(sys.modules, "pygame", None)
    assert play.main(["--replay", str(path), "--headless"]) == [game.score for game in games]


def test_an_action_string_is_the_digits_of_the_discrete_actions(recorded):
    # The recording's digits are Discrete(4) actions: replaying them by hand scores the same.
    _, games = recorded
    env = gym.make("Pinball-v0", balls=1)
    env.reset(seed=games[0].seed)
    for digit in games[0].actions:
        _, _, terminated, _, info = env.step(int(digit))
    assert terminated and info["score"] == games[0].score


def test_playing_without_a_display_says_so():
    with pytest.raises(SystemExit, match="no display found: playing needs a window"):
        play.main(["--table", "classic"])
    with pytest.raises(SystemExit):  # argparse: --headless is for --replay
        play.main(["--headless"])


# --- the cabinet (Pinball-v1) ---------------------------------------------------------------


def cabinet_action(keys: tuple[int, ...]) -> int:
    """The discrete action of a set of keys: their buttons, the first nudge held winning."""
    held = set(keys)
    nudge = next((n + 1 for n, nudge_keys in enumerate(NUDGE_KEYS) if held & set(nudge_keys)), 0)
    left, right = bool(held & set(LEFT_KEYS)), bool(held & set(RIGHT_KEYS))
    return left + 2 * right + 4 * bool(held & set(PLUNGER_KEYS)) + 8 * nudge


def test_keys_to_action_maps_the_cabinet_keys():
    mapping = gym.make("Pinball-v1").unwrapped.get_keys_to_action()
    keys = sorted(LEFT_KEYS + RIGHT_KEYS + CABINET_KEYS)
    flipper_keys = set(LEFT_KEYS + RIGHT_KEYS)
    # Every set of flipper keys, and every set of at most 4 keys with a cabinet key.
    expected = {
        c
        for n in range(1, len(keys) + 1)
        for c in itertools.combinations(keys, n)
        if n <= 4 or set(c) <= flipper_keys
    }
    assert set(mapping) == expected and len(mapping) == 800
    for combination, action in mapping.items():
        assert action == cabinet_action(combination), combination
    assert mapping[(pygame.K_DOWN,)] == mapping[(pygame.K_RETURN,)] == 4  # PLUNGER
    assert mapping[(pygame.K_x,)] == 8 and mapping[(pygame.K_n,)] == 16  # NUDGE_LEFT, _RIGHT
    assert mapping[(pygame.K_UP,)] == mapping[(pygame.K_b,)] == 24  # NUDGE_UP
    both = tuple(sorted((pygame.K_z, pygame.K_m, pygame.K_DOWN, pygame.K_x)))
    assert mapping[both] == 15  # BOTH_FLIPPERS_PLUNGER_NUDGE_LEFT
    # Two nudges: the first of left, right, up.
    assert mapping[tuple(sorted((pygame.K_n, pygame.K_b)))] == 16
    assert mapping[tuple(sorted((pygame.K_x, pygame.K_n, pygame.K_UP)))] == 8


def test_keys_to_action_of_the_cabinet_gives_button_arrays_for_multibinary():
    env = gym.make("Pinball-v1", action_type="multibinary")
    mapping = env.unwrapped.get_keys_to_action()
    assert len(mapping) == 800
    assert mapping[(pygame.K_RETURN,)].tolist() == [0, 0, 1, 0, 0, 0]
    assert mapping[tuple(sorted((pygame.K_z, pygame.K_b)))].tolist() == [1, 0, 0, 0, 0, 1]
    # Every nudge held is pressed (the env sums their directions: left and right cancel).
    assert mapping[tuple(sorted((pygame.K_x, pygame.K_n)))].tolist() == [0, 0, 0, 1, 1, 0]
    assert all(action in env.action_space for action in mapping.values())


def test_gymnasium_play_works_on_the_cabinet():
    with warnings.catch_warnings():  # it warns at import when matplotlib cannot use Tk
        warnings.simplefilter("ignore")
        from gymnasium.utils.play import play as gymnasium_play

    actions: list[int] = []
    quit_event = pygame.event.Event(pygame.QUIT)
    events = {0: down(pygame.K_DOWN), 5: down(pygame.K_x), 10: up(pygame.K_DOWN)}

    def callback(obs_t, obs_tp1, action, reward, terminated, truncated, info):
        actions.append(int(action))
        step = len(actions) - 1
        if step in events or step >= 15:
            pygame.event.post(events.get(step, quit_event))

    gymnasium_play(gym.make("Pinball-v1", render_mode="rgb_array"), callback=callback, seed=0)
    # The plunger, then the plunger and a nudge left, then the nudge alone.
    assert actions == [0] + [4] * 5 + [12] * 5 + [8] * 5


@pytest.fixture
def cabinet_loop():
    session = play.PlayLoop({"balls": 1}, seed=3, fps=0, env_id="Pinball-v1")
    yield session
    session.close()


def test_the_plunger_keys_pull_the_plunger_and_fire_the_ball(cabinet_loop):
    game = cabinet_loop.env.unwrapped.game
    assert cabinet_loop.options == {"table": "classic_v1", "balls": 1}
    cabinet_loop.run(scripted({0: [down(pygame.K_DOWN)]}), max_frames=30)
    assert cabinet_loop.actions == [4] * 30
    assert game.state.on_plunger[0] and game.state.plunger_pull[0] > 0.0
    cabinet_loop.run(scripted({0: [up(pygame.K_DOWN)]}), max_frames=2)
    assert not game.state.on_plunger[0] and game.world.state.active[0, 0]
    assert (
        cabinet_loop.info["ball_position"][1] > cabinet_loop.env.unwrapped.table.plunger.position[1]
    )


def test_the_nudge_keys_and_the_first_nudge_wins(cabinet_loop):
    script = {
        0: [down(pygame.K_b)],
        2: [down(pygame.K_n)],
        4: [down(pygame.K_x)],
        6: [up(pygame.K_x), up(pygame.K_n)],
        8: [down(pygame.K_RETURN), down(pygame.K_z)],
    }
    cabinet_loop.run(scripted(script), max_frames=10)
    assert cabinet_loop.actions == [24, 24, 16, 16, 8, 8, 24, 24, 29, 29]
    assert cabinet_loop.info["cabinet_offset"][1] != 0.0  # nudged up the table


@pytest.mark.parametrize("env_id", ["Pinball-v0", "Pinball-v1"])
def test_the_play_loop_acts_as_the_key_map_and_on_any_number_of_keys(env_id):
    session = play.PlayLoop({"balls": 1}, seed=3, fps=0, env_id=env_id)
    try:
        for keys, action in session.keys_to_action.items():
            session.held = set(keys)
            assert session.action == action, keys
        session.held = set()
        assert session.action == 0
        if env_id == "Pinball-v1":  # more keys than the map holds: still their buttons
            session.held = {pygame.K_LSHIFT, pygame.K_z, pygame.K_RSHIFT, pygame.K_DOWN, pygame.K_n}
            assert session.action == 1 + 2 + 4 + 16
            session.held = set(LEFT_KEYS + RIGHT_KEYS + CABINET_KEYS)
            assert session.action == 1 + 2 + 4 + 8
    finally:
        session.close()


def test_the_play_tool_plays_only_pinball_envs():
    with pytest.raises(
        ValueError,
        match="plays Pinball-v0, Pinball-v1, Pinball-v2 or Pinball-v3, not 'CartPole-v1'",
    ):
        play.PlayLoop(env_id="CartPole-v1")


@pytest.fixture(scope="module")
def cabinet_recorded(tmp_path_factory) -> tuple[Path, tuple[GameRecord, ...]]:
    """A recording of two Pinball-v1 games: a plunge, nudges and flips, a restart, then one that
    the player quits."""
    path = tmp_path_factory.mktemp("play") / "cabinet.json"
    session = play.PlayLoop({"balls": 1}, seed=5, record=path, fps=0, env_id="Pinball-v1")
    script = {
        0: [down(pygame.K_DOWN)],
        50: [up(pygame.K_DOWN)],
        60: [down(pygame.K_x)],
        62: [up(pygame.K_x)],
        70: [down(pygame.K_RETURN), down(pygame.K_b)],
        75: [up(pygame.K_RETURN), up(pygame.K_b)],
        90: [down(pygame.K_z), down(pygame.K_m)],
        120: [up(pygame.K_z), up(pygame.K_m)],
        150: [down(pygame.K_r)],
        151: [down(pygame.K_n)],
    }
    session.run(scripted(script), max_frames=180)
    session.close()
    return path, session.games


def test_a_cabinet_recording_holds_the_actions_in_base_32(cabinet_recorded):
    path, games = cabinet_recorded
    data = json.loads(path.read_text())
    assert data["version"] == 2 and data["env_id"] == "Pinball-v1"
    assert data["options"] == {"table": "classic_v1", "balls": 1}
    assert [(g["seed"], g["end"]) for g in data["games"]] == [(5, "restart"), (6, "quit")]
    first = data["games"][0]["actions"]
    # PLUNGER (4), NUDGE_LEFT (8), PLUNGER_NUDGE_UP (28: "s"), BOTH_FLIPPERS (3).
    assert first[:50] == "4" * 50 and first[60:62] == "88" and first[70:75] == "s" * 5
    assert first[90:120] == "3" * 30 and len(first) == 150
    assert data["games"][1]["actions"] == "0" + "g" * 29  # NUDGE_RIGHT (16) held
    assert decode_recorded_actions("0s3g") == [0, 28, 3, 16]
    assert load_recording(path).games == games


def test_a_cabinet_recording_replays(cabinet_recorded, capsys):
    path, games = cabinet_recorded
    recording = load_recording(path)
    assert play.replay(recording) == [game.score for game in games]
    assert play.replay(recording, window=True, fps=0) == [game.score for game in games]
    assert play.main(["--replay", str(path), "--headless"]) == [game.score for game in games]
    assert "as recorded" in capsys.readouterr().out
    write_recording(path.with_name("copy.json"), recording)
    assert path.with_name("copy.json").read_text() == path.read_text()


def test_a_pinball_v3_game_is_played_recorded_and_replayed(tmp_path):
    """Pinball-v3 (multiball's table): a game is played in the window, recorded and replayed to
    its score."""
    path = tmp_path / "v3.json"
    session = play.PlayLoop({"balls": 1}, seed=4, record=path, fps=0, env_id="Pinball-v3")
    script = {0: [down(pygame.K_DOWN)], 40: [up(pygame.K_DOWN)], 200: [down(pygame.K_z)],
              260: [up(pygame.K_z)]}  # fmt: skip
    session.run(scripted(script), max_frames=400)
    session.close()
    data = json.loads(path.read_text())
    assert data["env_id"] == "Pinball-v3" and data["options"]["table"] == "classic_v3"
    assert play.replay(load_recording(path)) == [game.score for game in session.games]


def test_a_cabinet_recording_on_a_table_without_the_cabinet_is_refused(cabinet_recorded):
    def to_classic(data: dict[str, Any]) -> None:
        data["env_id"], data["options"]["table"] = "Pinball-v0", "classic"
        data["table_sha256"] = table_sha256(load_table("classic"))

    recording = parse_recording(edited(cabinet_recorded, to_classic))
    with pytest.raises(RecordingError, match=r"'4' at step 0 is action 4, but the table "):
        play.replay(recording)


# Written by the play tool of commit 601e8ae, before the cabinet (one game, balls=2, seed 11:
# left held 60 frames, both 60, right 60, then none until the game was over).
RECORDING_BEFORE_THE_CABINET = {
    "format": "pinball-env-recording",
    "version": 1,
    "package_version": pinball_env.__version__,
    "env_id": "Pinball-v0",
    "options": {"table": "classic", "balls": 2},
    "max_episode_steps": 7200,
    "table_sha256": "d241a4f7604a7adb10b96da539dfa50377cb221d0342f99e51d526fed9d7fb4a",
    "games": [
        {
            "seed": 11,
            "actions": "1" * 60 + "3" * 60 + "2" * 60 + "0" * 251,
            "score": 530,
            "frames": 431,
            "end": "game over",
        }
    ],
}


def test_a_recording_from_before_the_cabinet_replays_and_writes_back_the_same(tmp_path):
    text = json.dumps(RECORDING_BEFORE_THE_CABINET, indent=2) + "\n"  # as that tool wrote it
    (tmp_path / "old.json").write_text(text)
    recording = load_recording(tmp_path / "old.json")
    assert recording.version == 1 and play.replay(recording) == [530]
    write_recording(tmp_path / "again.json", recording)
    assert (tmp_path / "again.json").read_text() == text


def test_the_command_line_plays_pinball_v1_and_the_protocols_v3(tmp_path, monkeypatch, capsys):
    monkeypatch.setattr(play, "has_display", lambda: True)  # SDL's dummy driver shows it
    monkeypatch.setattr(play.PlayLoop, "run", lambda loop: play.PlayLoop.tick(loop))
    scores = play.main(["--env", "Pinball-v1", "--seed", "2", "--record", str(tmp_path / "r.json")])
    data = json.loads((tmp_path / "r.json").read_text())
    assert scores == [0] and data["env_id"] == "Pinball-v1" and data["version"] == 2
    assert data["options"] == {"table": "classic_v1"} and data["games"][0]["seed"] == 2
    out = capsys.readouterr().out
    assert "plunger: down / return" in out and "nudge up: up / b" in out
    # Pinball-v0's keys as before.
    play.main(["--env", "Pinball-v0", "--seed", "2", "--record", str(tmp_path / "v0.json")])
    data = json.loads((tmp_path / "v0.json").read_text())
    assert data["env_id"] == "Pinball-v0" and data["options"] == {"table": "classic"}
    assert data["version"] == 1 and "plunger" not in capsys.readouterr().out
    # The protocol's env by default (without its sticky actions: those are --protocol's).
    play.main(["--seed", "2", "--record", str(tmp_path / "v3.json")])
    data = json.loads((tmp_path / "v3.json").read_text())
    assert data["env_id"] == "Pinball-v3" and data["options"] == {"table": "classic_v3"}
    with pytest.raises(SystemExit):  # argparse: the recording says which env
        play.main(["--replay", str(tmp_path / "r.json"), "--env", "Pinball-v1"])
    with pytest.raises(SystemExit):  # argparse: no such env
        play.main(["--env", "Pinball-v9"])
    # --protocol plays the protocol's env, Pinball-v3, with its sticky actions.
    play.main(["--protocol", "--seed", "3", "--record", str(tmp_path / "p.json")])
    data = json.loads((tmp_path / "p.json").read_text())
    assert data["env_id"] == "Pinball-v3" and data["options"]["table"] == "classic_v3"
    assert data["options"]["repeat_action_probability"] == 0.25
