"""The games behind a page, stepped one frame per tick (the server ticks at the game's frame
rate): :class:`PlaySession` (a person plays from the page's buttons), :class:`WatchSession`
(players play, several games side by side) and :class:`ReplaySession` (a recording on a
timeline). A session knows nothing of the web: it takes the page's messages (JSON text,
:meth:`Session.receive`) and returns the messages to send (dicts), so that tests drive it
without a server.

Messages to the page (``type``): ``hello`` (first: the mode, the env, the tables' geometry once,
the key map), ``frame`` (each tick: ``games``, one :func:`~pinball_env.tools.web.stream.frame_state`
per game shown), ``timeline`` (a replay's game: its score at every frame), ``saved`` (a game was
added to the recording) and ``error`` (a message refused: what was wrong).

Messages from the page::

    {"type": "buttons", "held": ["left", "plunger"]}     # play: the buttons held now
    {"type": "command", "command": "pause"}              # or "restart" (play, watch)
    {"type": "play"} / {"type": "pause"}                 # replay
    {"type": "step", "frames": 1}                        # replay: this many frames on (or back)
    {"type": "seek", "frame": 1200}                      # replay: to this frame

A replay's seeks and steps are done at the next tick, the latest only (a page sending many
costs one seek's work a tick, at most :data:`SNAPSHOT_EVERY` steps).
    {"type": "speed", "speed": 4}                        # replay: frames per tick, 1/16 to 16
    {"type": "game", "game": 1}                          # replay: the recording's game (from 0)
"""

import dataclasses
import json
import secrets
from collections import deque
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np

from pinball_env.envs import PinballEnv, unwrapped_pinball
from pinball_env.game import GameState
from pinball_env.recording import (
    GameRecord,
    Recording,
    action_count,
    decode_recorded_actions,
    encode_action,
    format_version,
    make_recorded_env,
    played_table,
    replay,
    table_sha256,
    write_recording,
)
from pinball_env.tools.play import COMMAND_KEYS, held_action
from pinball_env.tools.web.stream import frame_state, geometry, page_keys

MAX_MESSAGE_BYTES = 4096  # a page's messages are a few dozen bytes; larger ones are refused
GAME_ENDINGS = ("game over", "time limit")  # a recorded game's ends that ended the game itself
MAX_SPEED = 16.0  # a replay's frames per tick, at most (and 1 / MAX_SPEED at least)
MAX_STEP = 3600  # frames a replay's step moves at most (a minute)
SNAPSHOT_EVERY = 300  # [frames] a replay keeps a snapshot this often (5 s), to scrub from
OVER_HOLD = 120  # [ticks] a watched game's end stays on the page (2 s) before the next game

Message = dict[str, Any]
# The fields of each message a page may send, by type, and the types of their values.
MESSAGES: dict[str, dict[str, type | tuple[type, ...]]] = {
    "buttons": {"held": list},
    "command": {"command": str},
    "play": {},
    "pause": {},
    "step": {"frames": int},
    "seek": {"frame": int},
    "speed": {"speed": (int, float)},
    "game": {"game": int},
}


class MessageError(ValueError):
    """A page's message that is not one its session takes: the reply's error says why."""


def parse_message(text: str | bytes, accepted: Sequence[str]) -> Message:
    """The page's message ``text`` as a dict, checked against :data:`MESSAGES` (its type one of
    ``accepted``); MessageError says what is wrong."""
    if len(text) > MAX_MESSAGE_BYTES:
        raise MessageError(f"message of {len(text)} bytes; at most {MAX_MESSAGE_BYTES}")
    try:
        message = json.loads(text)
    except (json.JSONDecodeError, UnicodeDecodeError) as error:
        raise MessageError(f"not JSON: {error}") from None
    except RecursionError:  # "[[[[...": deeper than the parser's stack, still under the size cap
        raise MessageError("JSON nested too deeply") from None
    if not isinstance(message, dict):
        raise MessageError(f"expected a JSON object, got {type(message).__name__}")
    kind = message.get("type")
    if not isinstance(kind, str) or kind not in accepted:
        raise MessageError(f"unknown message type {kind!r}; this page takes {', '.join(accepted)}")
    fields = MESSAGES[kind]
    for key, value in message.items():
        if key == "type":
            continue
        if key not in fields:
            raise MessageError(f"{kind} message: unknown key {key!r}")
        if isinstance(value, bool) or not isinstance(value, fields[key]):
            raise MessageError(f"{kind} message: {key} has the wrong type ({json.dumps(value)})")
    missing = sorted(set(fields) - set(message))
    if missing:
        raise MessageError(f"{kind} message: missing key {missing[0]!r}")
    return message


def error(text: str) -> Message:
    return {"type": "error", "message": text}


class Session:
    """A page's games. :meth:`hello`'s messages are sent first, then :meth:`tick`'s every
    frame; :meth:`receive` takes the page's messages (replies: errors)."""

    accepted: tuple[str, ...] = ()
    fps: float  # ticks per second at real speed (from the table's frame rate, _frame_rate)

    def hello(self) -> list[Message]:
        """The first messages: ``hello`` (the mode, the env, the geometry, the keys), then
        any the mode needs."""
        raise NotImplementedError

    def tick(self) -> list[Message]:
        raise NotImplementedError

    def handle(self, message: Message) -> list[Message]:
        raise NotImplementedError

    def receive(self, text: str | bytes) -> list[Message]:
        """Apply the page's message ``text``; the replies (an error for a malformed one)."""
        try:
            return self.handle(parse_message(text, self.accepted))
        except MessageError as refused:
            return [error(str(refused))]

    def close(self) -> None:
        """End the session (a page closed)."""


def _frame_rate(core: PinballEnv, every_frame: bool = False) -> float:
    """Ticks per second at real speed: the table's frame rate, over the env's frame skip where a
    tick is one step (play, replay) rather than one frame (watch, ``every_frame``)."""
    rate = core.game.table.simulation.frame_rate
    return rate if every_frame else rate / core.options.frame_skip


def _table_geometry(env: PinballEnv) -> dict[str, Any]:
    """The geometry of ``env``'s table, with its renderer's scale of the plunger's pull."""
    table = env.game.world.table_of(0)
    return geometry(table, env.core.frame_renderers(table).pull_scale)


# --- play -----------------------------------------------------------------------------------


class Recorder:
    """The recording of a server's played games (``--record FILE``), in the play tool's format:
    every page's ended games, in order, the file rewritten as each ends."""

    def __init__(self, path: str | Path, env: gym.Env, env_id: str, options: Mapping) -> None:
        self.path = Path(path)
        self.recording = Recording(
            env_id=env_id,
            options=dict(options),
            max_episode_steps=env.spec.max_episode_steps if env.spec else None,
            table_sha256=table_sha256(played_table(env)),
            version=format_version(action_count(env)),
        )

    def add(self, game: GameRecord) -> None:
        games = (*self.recording.games, game)
        self.recording = dataclasses.replace(self.recording, games=games)
        write_recording(self.path, self.recording)


class PlaySession(Session):
    """A person's games on ``env_id`` with ``options`` (``gym.make``'s): the page's buttons held
    make each step's action (the play tool's, :func:`~pinball_env.tools.play.held_action`),
    one step per tick; pause, restart (a new game, the next seed). ``seed``: the first game's
    (None: a random one). Ended games (game over, time limit, restart, the page closed) go to
    ``recorder`` when given."""

    accepted = ("buttons", "command")

    def __init__(
        self,
        env_id: str,
        options: Mapping[str, Any] | None = None,
        seed: int | None = None,
        recorder: Recorder | None = None,
    ) -> None:
        options = dict(options or {})
        if recorder is not None:
            recorded = recorder.recording
            if (recorded.env_id, recorded.options) != (env_id, options):
                raise ValueError(
                    f"the recorder records {recorded.env_id} with {recorded.options}, not "
                    f"{env_id} with {options}: one recording holds games of one game"
                )
        self.env_id = env_id
        self.env = make_recorded_env(options, env_id=env_id)
        self.core = unwrapped_pinball(self.env)
        self.fps = _frame_rate(self.core)
        self.names = self.core.game.button_names
        self.nudges = self.core.options.nudge_actions
        self.recorder = recorder
        self.version = format_version(action_count(self.env))
        self.held: set[str] = set()
        self.paused = False
        self._new_game(secrets.randbelow(1_000_000) if seed is None else seed)

    def _new_game(self, seed: int) -> None:
        self.seed = seed
        self.actions: list[int] = []
        self.over = False
        self.paused = False
        _, self.info = self.env.reset(seed=seed)

    def _end_game(self, end: str) -> list[Message]:
        if self.over or not self.actions:
            return []  # already recorded, or nothing played
        self.over = True
        if self.recorder is None:
            return []
        self.recorder.add(
            GameRecord(
                seed=self.seed,
                actions="".join(encode_action(a, self.version) for a in self.actions),
                score=int(self.info["score"]),
                frames=int(self.info["frames"]),
                end=end,
            )
        )
        games = len(self.recorder.recording.games)
        return [{"type": "saved", "path": self.recorder.path.name, "games": games}]  # no folder

    @property
    def action(self) -> int:
        pressed = np.array([name in self.held for name in self.names])
        return held_action(pressed, self.names, self.nudges)

    def hello(self) -> list[Message]:
        return [{
            "type": "hello", "mode": "play", "env_id": self.env_id, "fps": self.fps,
            "tables": [_table_geometry(self.core)], "buttons": list(self.names),
            "keys": page_keys(self.names, COMMAND_KEYS), "record": self.recorder is not None,
        }]  # fmt: skip

    def tick(self) -> list[Message]:
        replies: list[Message] = []
        if not (self.paused or self.over):
            action = self.action
            _, _, terminated, truncated, self.info = self.env.step(action)
            self.actions.append(action)
            if terminated or truncated:
                replies += self._end_game("game over" if terminated else "time limit")
        frame: Message = {"type": "frame", "games": [frame_state(self.core, self.over)]}
        frame["paused"] = self.paused
        return [frame, *replies]

    def handle(self, message: Message) -> list[Message]:
        if message["type"] == "buttons":
            held = message["held"]
            unknown = [name for name in held if name not in self.names]
            if unknown:
                raise MessageError(
                    f"buttons message: {unknown[0]!r} is not a button of {self.env_id} "
                    f"({', '.join(self.names)})"
                )
            self.held = set(held)
            return []
        command = message["command"]
        if command == "pause":
            self.paused = not self.paused and not self.over
        elif command == "restart":
            ended = self._end_game("restart")
            self._new_game(self.seed + 1)
            return ended
        else:
            raise MessageError(f"command {command!r}: a player's are pause and restart")
        return []

    def close(self) -> None:
        self._end_game("quit")
        self.env.close()


# --- watch ----------------------------------------------------------------------------------


@dataclasses.dataclass
class WatchedPlayer:
    """A player and its game: ``env`` (a ``gym.make`` env, wrappers and all) and ``act(obs,
    info)``, its action; ``reset()`` (when given) before each game."""

    env: gym.Env
    act: Callable[[Any, dict[str, Any]], Any]
    reset: Callable[[], None] | None = None


class _Watched:
    """One watched game: its player, its frames not yet shown, its state."""

    def __init__(self, player: WatchedPlayer) -> None:
        self.player = player
        self.core = unwrapped_pinball(player.env)
        self.frames: deque[dict[str, Any]] = deque()
        options = self.core.options
        # A step of several frames (frame skip, skip_above): each frame shown, as a video has.
        self.every_frame = options.frame_skip > 1 or options.skip_above > 0
        if self.every_frame:
            self.core.game.on_frame = self._on_frame
        self.over = 0  # ticks the ended game has been shown; 0 while playing

    def _on_frame(self) -> None:
        state = frame_state(self.core)
        state["frame"] += 1  # the frame just played: the game counts it (and its points) after
        self.frames.append(state)

    def new_game(self, seed: int) -> None:
        self.seed = seed
        self.obs, self.info = self.player.env.reset(seed=seed)
        if self.player.reset is not None:
            self.player.reset()
        self.over = 0
        self.frames.clear()
        self.last = frame_state(self.core)

    def next_frame(self) -> dict[str, Any]:
        if not self.frames and not self.over:
            action = self.player.act(self.obs, self.info)
            self.obs, _, terminated, truncated, self.info = self.player.env.step(action)
            if self.every_frame and self.frames:  # the step's last frame, its points counted
                self.frames[-1] = frame_state(self.core)
            else:
                self.frames.append(frame_state(self.core))
            if terminated or truncated:
                self.over = 1
        if self.frames:
            self.last = self.frames.popleft()
        return self.last


class WatchSession(Session):
    """``players`` playing, their games side by side, one frame per tick (every frame of a
    step of several frames). Game ``i`` starts on seed ``seed + i``, and each new game on the
    next seed not yet played; an ended game stays on the page 2 seconds. ``name``: the
    player's, shown on the page. Pause and restart (every game anew, on the next seeds)."""

    accepted = ("command",)

    def __init__(
        self, players: Sequence[WatchedPlayer], seed: int = 0, name: str = "player"
    ) -> None:
        if not players:
            raise ValueError("a watch session needs at least one player")
        self.games = [_Watched(player) for player in players]
        self.name = name
        self.fps = _frame_rate(self.games[0].core, every_frame=True)
        self.paused = False
        self.next_seed = seed
        for game in self.games:
            self._start(game)

    def _start(self, game: _Watched) -> None:
        game.new_game(self.next_seed)
        self.next_seed += 1

    def hello(self) -> list[Message]:
        first = self.games[0]
        spec = first.player.env.spec
        assert spec is not None  # (a gym.make env, as WatchedPlayer says)
        return [{
            "type": "hello", "mode": "watch", "env_id": spec.id, "fps": self.fps,
            "tables": [_table_geometry(game.core) for game in self.games], "player": self.name,
            "keys": page_keys((), COMMAND_KEYS),
        }]  # fmt: skip

    def tick(self) -> list[Message]:
        states = []
        for game in self.games:
            if not self.paused:
                if game.over >= OVER_HOLD:
                    self._start(game)
                elif game.over:
                    game.over += 1
                game.next_frame()
            states.append({**game.last, "over": bool(game.over), "seed": game.seed})
        return [{"type": "frame", "games": states, "paused": self.paused}]

    def handle(self, message: Message) -> list[Message]:
        command = message["command"]
        if command == "pause":
            self.paused = not self.paused
        elif command == "restart":
            for game in self.games:
                self._start(game)
        else:
            raise MessageError(f"command {command!r}: a watcher's are pause and restart")
        return []

    def close(self) -> None:
        for game in self.games:
            game.player.env.close()


# --- replay ---------------------------------------------------------------------------------


@dataclasses.dataclass(frozen=True)
class Snapshot:
    """A replayed game at ``frame``: its state and its env's random stream."""

    frame: int
    state: GameState
    rng: Mapping[str, Any]  # (bit_generator.state)


class ReplayIndex:
    """A recording, replayed once and checked (:func:`pinball_env.recording.replay`: a
    RecordingError if any game differs from the recording, or if it is of another version or
    table), with each game's score at every frame and snapshots every ``every`` frames for the
    timeline. Shared by every page that replays it."""

    def __init__(self, recording: Recording, every: int = SNAPSHOT_EVERY) -> None:
        if every < 1:
            raise ValueError(f"snapshots every {every} frames: must be at least 1")
        self.recording = recording
        self.every = every
        self.actions = [decode_recorded_actions(game.actions) for game in recording.games]
        self.scores: list[list[int]] = [[] for _ in recording.games]
        self.snapshots: list[list[Snapshot]] = [[] for _ in recording.games]
        starts = np.cumsum([0, *map(len, self.actions)])
        count = 0

        def viewer(env: gym.Env, name: str) -> None:  # before each step of each game
            nonlocal count
            game = int(np.searchsorted(starts, count, side="right")) - 1
            frame = int(count - starts[game])
            count += 1
            core = unwrapped_pinball(env)
            self.scores[game].append(int(core.game.score[0]))
            if frame % every == 0:
                rng = core.np_random.bit_generator.state
                self.snapshots[game].append(Snapshot(frame, core.game.snapshot(), rng))

        finals = replay(recording, viewer)
        for game, score in enumerate(finals):
            self.scores[game].append(int(score))


class ReplaySession(Session):
    """A recording's games on a timeline (``index``: the recording, checked): play, pause, step
    a frame (or back), seek, speed, the game. Every frame is the recorded game's, bitwise: the
    game is stepped on from the start or from a snapshot of it."""

    accepted = ("command", "play", "pause", "step", "seek", "speed", "game")

    def __init__(self, index: ReplayIndex) -> None:
        self.index = index
        recording = index.recording
        self.env = make_recorded_env(
            recording.options, recording.max_episode_steps, recording.env_id
        )
        self.core = unwrapped_pinball(self.env)
        self.fps = _frame_rate(self.core)
        self.playing = False
        self.speed = 1.0
        self._credit = 0.0  # frames owed by a speed below 1
        self._select(0)

    def _select(self, game: int) -> None:
        games = self.index.recording.games
        if not 0 <= game < len(games):
            raise MessageError(f"game {game}: the recording has games 0 to {len(games) - 1}")
        self.game = game
        self.actions = self.index.actions[game]
        self.env.reset(seed=games[game].seed)
        self.frame = 0
        self.wanted: int | None = None  # the frame a seek or step asked for, done at the tick

    def _goto(self, frame: int) -> None:
        """Step to ``frame`` (clipped to the game): on from here, or from the last snapshot
        before it."""
        frame = min(max(frame, 0), len(self.actions))
        if frame < self.frame or frame - self.frame > self.index.every:
            snapshots = self.index.snapshots[self.game]
            # The game's end has no snapshot of its own (a game of 24 x 300 frames has 24).
            snapshot = snapshots[min(frame // self.index.every, len(snapshots) - 1)]
            self.core.game.restore(snapshot.state)
            self.core.np_random.bit_generator.state = snapshot.rng
            # The TimeLimit wrapper's count is not set back (a private attribute): a replay
            # never steps past the recorded game, so its truncation is never reached or read.
            self.frame = snapshot.frame
        while self.frame < frame:
            self.env.step(self.actions[self.frame])
            self.frame += 1

    def hello(self) -> list[Message]:
        recording = self.index.recording
        return [{
            "type": "hello", "mode": "replay", "env_id": recording.env_id, "fps": self.fps,
            "tables": [_table_geometry(self.core)],
            "games": [
                {"seed": g.seed, "frames": g.frames, "score": g.score, "end": g.end}
                for g in recording.games
            ],
        }, self._timeline()]  # fmt: skip

    def _timeline(self) -> Message:
        record = self.index.recording.games[self.game]
        return {
            "type": "timeline", "game": self.game, "seed": record.seed,
            "frames": len(self.actions), "score": record.score, "end": record.end,
            "scores": self.index.scores[self.game],
        }  # fmt: skip

    @property
    def _position(self) -> int:
        """The frame the page has asked for: a seek or step not yet done, or the frame shown."""
        return self.frame if self.wanted is None else self.wanted

    def _want(self, frame: int) -> None:
        self.wanted = min(max(frame, 0), len(self.actions))

    def tick(self) -> list[Message]:
        if self.wanted is not None:  # the latest seek or step only: one seek's work a tick
            self._goto(self.wanted)
            self.wanted = None
        if self.playing:
            self._credit += self.speed
            frames = int(self._credit)
            self._credit -= frames
            self._goto(self.frame + frames)
            if self.frame >= len(self.actions):
                self.playing = False
        # GAME OVER at the end of a game that ended (not one the player restarted or left).
        ended = self.index.recording.games[self.game].end in GAME_ENDINGS
        state = frame_state(self.core, ended and self.frame >= len(self.actions))
        timeline = {"game": self.game, "frame": self.frame, "frames": len(self.actions),
                    "playing": self.playing, "speed": self.speed}  # fmt: skip
        return [{"type": "frame", "games": [state], "replay": timeline}]

    def handle(self, message: Message) -> list[Message]:
        kind = message["type"]
        if kind == "play" or (kind == "command" and message["command"] == "pause"):
            self.playing = not self.playing if kind == "command" else True
            if self._position >= len(self.actions) and self.playing:
                self._want(0)  # played to the end: from the start again
        elif kind == "command":
            raise MessageError(f"command {message['command']!r}: a replay's is pause")
        elif kind == "pause":
            self.playing = False
        elif kind == "step":
            frames = message["frames"]
            if abs(frames) > MAX_STEP:
                raise MessageError(f"step of {frames} frames: at most {MAX_STEP} either way")
            self.playing = False
            self._want(self._position + frames)
        elif kind == "seek":
            self._want(message["frame"])
        elif kind == "speed":
            speed = float(message["speed"])
            if not 1 / MAX_SPEED <= speed <= MAX_SPEED:
                raise MessageError(f"speed {speed}: from 1/{MAX_SPEED:g} to {MAX_SPEED:g}")
            self.speed = speed
        else:  # game
            self._select(message["game"])
            self.playing = False
            return [self._timeline()]
        return []

    def close(self) -> None:
        self.env.close()
