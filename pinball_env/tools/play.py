"""Play ``Pinball-v0`` to ``-v3`` on the keyboard: ``python -m pinball_env.tools.play``.

``python -m pinball_env.tools.play [--env ID] [--table NAME] [--seed S] [--record FILE]
[--protocol]`` opens
a pygame window (the ``render`` extra) and plays at real speed, one env step per frame (the
table's frame rate, 60 frames per second), with the score and the balls left on the scoreboard.
``--env Pinball-v1`` plays the whole cabinet (its table ``classic_v1``): the player's plunger,
the nudge and the tilt, whose warnings and TILT the scoreboard shows; ``--env Pinball-v2`` the
same with a tilt that any sustained nudging trips (``classic_v2``); ``--env Pinball-v3`` v2's
game with multiball (``classic_v3``: every ball, the lock and the trough drawn). ``--table``
plays another table on the env (default: the env's own). ``--protocol`` plays the benchmark
protocol's game (its env, ``Pinball-v3``, unless ``--env`` names another of it; sticky actions,
``pinball_env.protocol``): a recording of it is a human score that
``python -m agents.evaluate --recording FILE`` scores on the protocol. ``--replay FILE
[--headless]`` plays a recording back and checks that every game scores what was recorded.

Keys (``PinballEnv.FLIPPER_KEYS`` and ``CABINET_KEYS``, the map of ``get_keys_to_action``; the
cabinet's on a table that has one):

============================  ===========================================
Left Shift, Z, Left arrow     left flipper (held: up)
Right Shift, M, Right arrow   right flipper
Down arrow, Enter             plunger (held: pulled back; let go: fires)
X / N                         nudge left / right
Up arrow, B                   nudge up
P or Space                    pause / resume
R                             restart: a new game, with the next seed
Esc or Q, closing the window  quit
============================  ===========================================

Any number of keys can be held at once; with several nudge keys held, the first of left, right,
up nudges (a discrete action holds one nudge).

Recordings (``--record FILE``) hold every game of the session, in order, rewritten as each game
ends (a game ends at game over, at the time limit, at a restart (R) or when the window is
closed); their format, its checks and the headless replay are :mod:`pinball_env.recording`.
"""

import argparse
import dataclasses
import os
import secrets
from collections.abc import Callable, Iterable, Mapping, Sequence
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np

from pinball_env.envs import PinballEnv, unwrapped_pinball
from pinball_env.game import discrete_action
from pinball_env.protocol import PROTOCOL_ENV_IDS, REPEAT_ACTION_PROBABILITY
from pinball_env.recording import (
    RECORDABLE_ENV_IDS,
    GameRecord,
    Recording,
    RecordingError,
    action_count,
    default_table,
    encode_action,
    format_version,
    load_recording,
    make_recorded_env,
    table_sha256,
    write_recording,
)
from pinball_env.recording import replay as replay_recording
from pinball_env.render import BACKGROUND, SCOREBOARD_TEXT, SCOREBOARD_WIDTH, Window
from pinball_env.tools import command_parser
from pinball_env.tools.demo import has_display

ENV_ID = PROTOCOL_ENV_IDS[0]  # the env played by default: the benchmark's

BANNER_PAUSED = "PAUSED\nP: play on"
BANNER_OVER = "GAME OVER\nR: new game, Q: quit"

EventSource = Callable[[], Iterable[Any]]  # returns the pygame events of one frame


class ReplayStopped(Exception):
    """The viewer closed the window of a replay before its last game ended."""


def replay(
    recording: Recording,
    window: bool = False,
    fps: float | None = None,
    events: EventSource | None = None,
) -> list[int]:
    """:func:`pinball_env.recording.replay`, shown in a window with ``window``: at real speed,
    or ``fps`` (0 is as fast as it goes), where P or Space pauses and Esc, Q or closing the
    window raises ReplayStopped."""
    if not window:
        return replay_recording(recording)
    viewer = _ReplayViewer(fps, events)
    try:
        return replay_recording(recording, viewer)
    finally:
        viewer.close()


class _ReplayViewer:
    """The window of a replay (a :data:`pinball_env.recording.Viewer`): each step's frame, held
    while paused; opened at the first frame, so that a refused recording opens no window."""

    def __init__(self, fps: float | None, events: EventSource | None) -> None:
        self.fps = fps
        self.events = events
        self.screen: _Screen | None = None

    def __call__(self, env: gym.Env, name: str) -> None:
        if self.screen is None:
            self.screen = _Screen(env, self.fps, "Pinball replay")
        paused = False
        while True:
            for event in (self.events or self.screen.pygame.event.get)():
                command = self.screen.command(event)
                if command == "quit":
                    raise ReplayStopped(f"replay stopped in {name}")
                paused ^= command == "pause"
            self.screen.show(env, "PAUSED" if paused else None)
            if not paused:
                return

    def close(self) -> None:
        if self.screen is not None:
            self.screen.close()


# --- the window -----------------------------------------------------------------------------


class _Screen:
    """The window of a game: frames at real speed, a banner over the playfield, the controls."""

    def __init__(self, env: gym.Env, fps: float | None, title: str) -> None:
        self.pygame = Window.import_pygame()
        self.pygame.display.init()  # the event queue works from here; the window opens later
        self.fps = unwrapped_pinball(env).steps_per_second if fps is None else fps
        self.window: Window | None = None  # opened by the first frame, at its size
        self.title = title
        self._caption = title
        self.command_keys = {getattr(self.pygame, name): c for name, c in COMMAND_KEYS.items()}
        try:
            self.pygame.font.init()
            self.font: Any = self.pygame.font.Font(None, 34)
        except (ImportError, NotImplementedError, RuntimeError):  # pygame built without fonts
            self.font = None

    def command(self, event: Any) -> str | None:
        """The command of an event: "quit" (a quit key, or the window closed), "pause",
        "restart", or None."""
        if event.type == self.pygame.QUIT:
            return "quit"
        if event.type == self.pygame.KEYDOWN:
            return self.command_keys.get(event.key)
        return None

    def show(self, env: gym.Env, banner: str | None) -> None:
        frame: Any = env.render()
        assert isinstance(frame, np.ndarray)  # (render_mode="rgb_array")
        if banner is not None:
            frame = self._banner(frame, banner)
        caption = f"{self.title}: {banner}" if banner else self.title
        if self.window is None:
            self.window = Window((frame.shape[1], frame.shape[0]), self.fps, self.title)
        if caption != self._caption:  # the caption says it too, should the font be missing
            self.pygame.display.set_caption(caption)
            self._caption = caption
        self.window.show(frame)

    def _banner(self, frame: np.ndarray, text: str) -> np.ndarray:
        """``frame`` with the lines of ``text`` in a box at the middle of the playfield."""
        if self.font is None:
            return frame
        lines = [
            self.pygame.surfarray.array3d(
                self.font.render(line, True, SCOREBOARD_TEXT, BACKGROUND)
            ).swapaxes(0, 1)
            for line in text.split("\n")
        ]
        pad = 8  # [px] of background around the text
        height = sum(line.shape[0] for line in lines) + 2 * pad
        width = max(line.shape[1] for line in lines) + 2 * pad
        playfield = frame.shape[1] - SCOREBOARD_WIDTH
        top = max(0, (frame.shape[0] - height) // 2)
        frame = frame.copy()
        frame[top : top + height, max(0, (playfield - width) // 2) : (playfield + width) // 2] = (
            BACKGROUND
        )
        top += pad
        for line in lines:
            left = max(0, (playfield - line.shape[1]) // 2)
            area = frame[top : top + line.shape[0], left : left + line.shape[1]]
            area[...] = line[: area.shape[0], : area.shape[1]]
            top += line.shape[0]
        return frame

    def close(self) -> None:
        if self.window is not None:
            self.window.close()
        self.pygame.display.quit()


# The command keys (pygame key names, as PinballEnv.FLIPPER_KEYS: no pygame needed to declare).
COMMAND_KEYS = {
    "K_p": "pause", "K_SPACE": "pause", "K_r": "restart", "K_ESCAPE": "quit", "K_q": "quit",
}  # fmt: skip


# --- playing --------------------------------------------------------------------------------


def keys_help(pygame: Any, cabinet: bool = False) -> str:
    """The keys, as pygame names them, from their declarations (FLIPPER_KEYS, CABINET_KEYS on a
    table with the cabinet, COMMAND_KEYS)."""

    def names(keys: Iterable[str]) -> str:
        return " / ".join(pygame.key.name(getattr(pygame, key)) for key in keys)

    parts = [f"{button} flipper: {names(keys)}" for button, keys in PinballEnv.FLIPPER_KEYS.items()]
    if cabinet:
        for button, keys in PinballEnv.CABINET_KEYS.items():
            parts.append(f"{button.replace('_', ' ')}: {names(keys)}")
    for command in dict.fromkeys(COMMAND_KEYS.values()):
        parts.append(f"{command}: {names(k for k, c in COMMAND_KEYS.items() if c == command)}")
    return "keys: " + ", ".join(parts)


def held_action(pressed: np.ndarray, button_names: Sequence[str], nudges: bool = True) -> int:
    """The discrete action of the buttons held, ``pressed`` (a bool per ``button_names``, the
    game's), as ``get_keys_to_action`` maps keys: with several nudges held the first of left,
    right, up wins; without ``nudges`` (the env's ``nudge_actions`` off) none does. The play
    tool's keys and the browser page's buttons both go through here."""
    pressed = np.array(pressed, dtype=bool)
    held = [i for i, name in enumerate(button_names) if name.startswith("nudge") and pressed[i]]
    pressed[held[1:] if nudges else held] = False
    return discrete_action(pressed)


class PlayLoop:
    """A session of games on the keyboard in a pygame window (see the module doc).

    :meth:`run` plays frames until the player quits or ``max_frames`` frames were shown; it can
    be called again to go on. Each frame takes the frame's events (``events``, by default
    ``pygame.event.get``; tests post key events to the queue), then steps the game once unless
    it is paused or over, and shows the frame. Held button keys are tracked from KEYDOWN and
    KEYUP events (``pygame.key.get_pressed`` is not updated by every video driver); the action
    presses the buttons of every key held, however many (``get_keys_to_action``'s map stops at
    ``MAX_CABINET_KEYS`` keys with a cabinet key), the first nudge winning as in the map.
    :meth:`close` ends the game in play and writes the recording.

    ``options``: ``gym.make`` options of ``env_id`` (one of :data:`RECORDABLE_ENV_IDS`; ``table``
    defaults to the env's own, ``"classic"`` or ``"classic_v1"`` to ``"classic_v3"``; not
    ``render_mode`` or ``action_type``, which the tool sets); ``seed``: the first game's (None:
    a random one; each restart takes the next); ``record``: the recording's path; ``fps``:
    frames per second, None for real speed, 0 for no waiting (tests).
    """

    def __init__(
        self,
        options: Mapping[str, Any] | None = None,
        seed: int | None = None,
        record: str | os.PathLike[str] | None = None,
        fps: float | None = None,
        env_id: str = ENV_ID,
    ) -> None:
        if env_id not in RECORDABLE_ENV_IDS:
            known = ", ".join(RECORDABLE_ENV_IDS[:-1]) + f" or {RECORDABLE_ENV_IDS[-1]}"
            raise ValueError(f"the play tool plays {known}, not {env_id!r}")
        self.options = {"table": default_table(env_id), **(options or {})}
        self.env = make_recorded_env(self.options, env_id=env_id)
        self.screen = _Screen(self.env, fps, "Pinball")
        self._pygame = self.screen.pygame
        self.core = unwrapped_pinball(self.env)
        game = self.core.game
        self.keys_to_action = self.core.get_keys_to_action()
        # Each key's buttons, from its one-key entry: held keys press the union of theirs.
        self.key_buttons = {
            keys[0]: game.discrete_buttons[action]
            for keys, action in self.keys_to_action.items()
            if len(keys) == 1
        }
        self._no_buttons = np.zeros(len(game.button_names), dtype=bool)
        self.record = None if record is None else Path(record)
        self.recording = Recording(
            env_id=env_id,
            options=self.options,
            max_episode_steps=self.env.spec.max_episode_steps if self.env.spec else None,
            table_sha256=table_sha256(self.core.table),
            version=format_version(action_count(self.env)),
        )
        self.held: set[int] = set()
        self.paused = False
        self.running = True
        self.frames_shown = 0
        self._new_game(secrets.randbelow(1_000_000) if seed is None else seed)

    @property
    def games(self) -> tuple[GameRecord, ...]:
        """The games ended so far, in order."""
        return self.recording.games

    def _new_game(self, seed: int) -> None:
        self.seed = seed
        self.actions: list[int] = []
        self.over = False
        self.paused = False
        self.observation, self.info = self.env.reset(seed=seed)

    def _end_game(self, end: str) -> None:
        if self.over or not self.actions:
            return  # already recorded, or nothing played
        self.over = True
        game = GameRecord(
            seed=self.seed,
            actions="".join(encode_action(a, self.recording.version) for a in self.actions),
            score=int(self.info["score"]),
            frames=int(self.info["frames"]),
            end=end,
        )
        self.recording = dataclasses.replace(self.recording, games=(*self.games, game))
        summary = f"score {game.score} in {game.frames} frames ({end})"
        print(f"game {len(self.games)} (seed {game.seed}): {summary}")
        if self.record is not None:
            write_recording(self.record, self.recording)

    def handle(self, event: Any) -> None:
        """Apply one pygame event: a button key down or up, a command, or losing focus."""
        pygame = self._pygame
        if event.type in (pygame.KEYDOWN, pygame.KEYUP) and event.key in self.key_buttons:
            if event.type == pygame.KEYDOWN:
                self.held.add(event.key)
            else:
                self.held.discard(event.key)
        elif event.type == pygame.WINDOWFOCUSLOST:
            self.held.clear()  # the key-up of a key held then will never come
        else:
            command = self.screen.command(event)
            if command == "quit":
                self.running = False
            elif command == "pause" and not self.over:
                self.paused = not self.paused
            elif command == "restart":
                self._end_game("restart")
                self._new_game(self.seed + 1)

    @property
    def action(self) -> int:
        """The discrete action of the button keys held now (0 when none): their buttons, the
        first nudge held winning (as ``get_keys_to_action``)."""
        pressed = self._no_buttons.copy()
        for key in self.held:
            pressed |= self.key_buttons[key]
        return held_action(pressed, self.core.game.button_names)

    def tick(self) -> None:
        """One frame: a step of the game unless paused or over, then the picture."""
        if not (self.paused or self.over):
            action = self.action
            self.observation, _, terminated, truncated, self.info = self.env.step(action)
            self.actions.append(action)
            if terminated or truncated:
                self._end_game("game over" if terminated else "time limit")
        banner = BANNER_OVER if self.over else BANNER_PAUSED if self.paused else None
        self.screen.show(self.env, banner)
        self.frames_shown += 1

    def run(self, events: EventSource | None = None, max_frames: int | None = None) -> None:
        """Play until the player quits or ``max_frames`` more frames were shown."""
        source = events or self._pygame.event.get
        stop = None if max_frames is None else self.frames_shown + max_frames
        while self.running and (stop is None or self.frames_shown < stop):
            for event in source():
                self.handle(event)
            if self.running:
                self.tick()

    def close(self) -> None:
        """End the game in play ("quit") and close the window and the env."""
        self._end_game("quit")
        self.screen.close()
        self.env.close()


def parser() -> argparse.ArgumentParser:
    """The command line's arguments."""
    parser = command_parser("pinball_env.tools.play", __doc__)
    parser.add_argument(
        "--env",
        choices=RECORDABLE_ENV_IDS,
        help=f"the env to play (default {ENV_ID}, or with --protocol {PROTOCOL_ENV_IDS[0]}; "
        "Pinball-v1 to -v3: the plunger, nudge and tilt)",
    )
    parser.add_argument("--table", help="table name or YAML path (default: the env's own)")
    parser.add_argument("--seed", type=int, help="seed of the first game (default: random)")
    parser.add_argument(
        "--protocol", action="store_true", help="the benchmark protocol's game (sticky actions)"
    )
    modes = parser.add_mutually_exclusive_group()
    modes.add_argument("--record", type=Path, help="write the games played to this JSON file")
    modes.add_argument("--replay", type=Path, help="play a recording back and check its scores")
    parser.add_argument("--headless", action="store_true", help="replay without a window")
    return parser


def main(argv: list[str] | None = None) -> list[int]:
    """The command line; returns the scores of the games played or replayed."""
    command = parser()
    args = command.parse_args(argv)
    if args.seed is not None and args.seed < 0:
        command.error(f"--seed must be >= 0, got {args.seed}")
    if args.protocol and args.table:
        command.error("--protocol plays the env's own table")
    if args.replay is not None and (
        args.env or args.table or args.seed is not None or args.protocol
    ):
        command.error("--replay takes the env, the table and the seeds from the recording")
    if args.headless and args.replay is None:
        command.error("--headless is for --replay: playing needs a window")
    window = not args.headless and has_display()
    if window or args.replay is None:  # a headless replay needs no pygame
        try:  # checked before anything is played
            Window.import_pygame()
        except gym.error.DependencyNotInstalled as error:
            raise SystemExit(str(error)) from None
    if args.replay is not None:
        return replay_file(args.replay, window, args.headless)
    if not window:
        raise SystemExit(
            "no display found: playing needs a window (--replay FILE --headless replays without)"
        )
    env_id = args.env or (PROTOCOL_ENV_IDS[0] if args.protocol else ENV_ID)
    if args.protocol and env_id not in PROTOCOL_ENV_IDS:
        command.error(f"--protocol plays {', '.join(PROTOCOL_ENV_IDS)}, not {env_id}")
    return play(env_id, args.table, args.seed, args.record, args.protocol)


def replay_file(path: Path, window: bool, headless: bool) -> list[int]:
    """``--replay``: the recording at ``path`` played back (in a window with ``window``) and
    checked; its scores ([] when the viewer stopped it)."""
    try:
        recording = load_recording(path)
        if not window and not headless:
            print("no display found: replaying headless")
        scores = replay(recording, window=window)
    except RecordingError as error:
        raise SystemExit(f"refused: {error}") from None
    except ReplayStopped as stopped:
        print(stopped)
        return []
    for game, score in zip(recording.games, scores, strict=True):
        print(f"seed {game.seed}: score {score} in {game.frames} frames, as recorded")
    return scores


def play(
    env_id: str, table: str | None, seed: int | None, record: Path | None, protocol: bool
) -> list[int]:
    """A session on the keyboard (``--record``: written to that file); the games' scores."""
    options: dict[str, Any] = {} if table is None else {"table": table}
    if protocol:
        options["repeat_action_probability"] = REPEAT_ACTION_PROBABILITY
    loop = PlayLoop(options, seed, record, env_id=env_id)
    print(keys_help(Window.import_pygame(), loop.core.game.cabinet))
    try:
        loop.run()
    finally:
        loop.close()
    if record is not None and loop.games:
        print(f"wrote {record}")
    return [game.score for game in loop.games]


if __name__ == "__main__":
    main()
