"""The recording format: the games of a play session, each a seed and its actions, in one JSON
file that replays them bitwise. The play tool writes it (``python -m pinball_env.tools.play
--record FILE``) and replays it (``--replay FILE``); ``python -m agents.evaluate --recording
FILE`` scores it on the benchmark protocol::

    from pinball_env.recording import load_recording, replay

    scores = replay(load_recording("my_games.json"))  # every game checked as recorded

A file holds every game of a session, in order: a game ends at game over, at the time limit, at
a restart or when the play tool's window is closed, and the file is rewritten as each game ends
(a game with no step is not kept)::


    {
      "format": "pinball-env-recording",  "version": 1,   // 2 with the cabinet (below)
      "package_version": "0.1.0",          // pinball_env.__version__
      "env_id": "Pinball-v0",              // or "Pinball-v1", "-v2", "-v3"
      "options": {"table": "classic"},     // every gym.make option passed
      "max_episode_steps": 7200,           // the TimeLimit of the env played
      "table_sha256": "...",               // the table played (a table file may change)
      "games": [
        {"seed": 5, "actions": "0011130...", "score": 1230, "frames": 2410,
         "end": "game over"}               // or "time limit", "restart", "quit"
      ]
    }

``actions`` holds one character per step, the discrete action. Format version 1 (a table without
a cabinet, written as before the cabinet): a digit 0-3 (0 none, 1 left, 2 right, 3 both).
Version 2 (a table with the cabinet, 32 actions): the action in base 32, ``0``-``9`` then
``a``-``v`` (10-31); the first four are version 1's. :func:`load_recording` refuses, naming the
problem, a file that is not such a recording (bad JSON, a missing or unknown key, a wrong type,
an action that is not a character of its version), one of another format version or package
version, and :func:`replay` one whose table is not the recorded one or has fewer actions; a
replay that does not end as recorded (the same score, frames and end) raises
:class:`RecordingError`, so a recording is never taken for a different game.
"""

import dataclasses
import json
import os
import re
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any, Protocol, runtime_checkable

import gymnasium as gym

from pinball_env import __version__  # importing the package registers the envs
from pinball_env.table import Table, table_sha256
from pinball_env.versions import ENV_VERSIONS, recordable_versions

# The envs whose games may be recorded (and replayed), the play tool's default first.
RECORDABLE_ENV_IDS = tuple(version.id for version in recordable_versions())
FORMAT = "pinball-env-recording"
# Format versions, by their actions: 1, digits 0-3 (a table without a cabinet); 2, base-32
# characters 0-9a-v (the cabinet's 32 actions). A recording is written in the first that holds
# its env's actions, so that Pinball-v0's stay as before.
FORMAT_VERSIONS = (1, 2)
FORMAT_VERSION = FORMAT_VERSIONS[-1]  # the newest
ACTION_CHARACTERS = {1: "0123", 2: "0123456789abcdefghijklmnopqrstuv"}
ENDS = ("game over", "time limit", "restart", "quit")
# Options a recording cannot carry, which the play tool fixes: it renders itself, and its
# actions are discrete.
RECORDING_FIXED_OPTIONS = ("render_mode", "action_type")

# Called before each step of a replay with the env and the game's name ("game 1 (seed 5)"):
# a viewer shows the frame, may wait (a pause) and may raise to stop the replay.
Viewer = Callable[[gym.Env, str], None]


class RecordingError(ValueError):
    """A recording that cannot be replayed, or a replay that did not end as recorded."""


@dataclasses.dataclass(frozen=True)
class GameRecord:
    """One game of a recording: its seed, one action character per step (see the module
    doc), and how it ended."""

    seed: int
    actions: str
    score: int
    frames: int
    end: str


@dataclasses.dataclass(frozen=True)
class Recording:
    """The games of one play session and the env they were played on (see the module doc)."""

    env_id: str
    options: dict[str, Any]
    max_episode_steps: int | None
    table_sha256: str
    games: tuple[GameRecord, ...] = ()
    package_version: str = __version__
    version: int = 1  # the format version (FORMAT_VERSIONS)

    def to_json(self) -> dict[str, Any]:
        return {
            "format": FORMAT,
            "version": self.version,
            "package_version": self.package_version,
            "env_id": self.env_id,
            "options": self.options,
            "max_episode_steps": self.max_episode_steps,
            "table_sha256": self.table_sha256,
            "games": [dataclasses.asdict(game) for game in self.games],
        }


def encode_action(action: int, version: int) -> str:
    """The character of a discrete action in a recording of format ``version``."""
    return ACTION_CHARACTERS[version][action]


def decode_recorded_actions(actions: str) -> list[int]:
    """The discrete actions of a recording's ``actions`` string (any format version)."""
    return [int(character, 32) for character in actions]


def format_version(n_actions: int) -> int:
    """The format version that a recording of an env with ``n_actions`` actions is written in:
    the first whose characters hold them all."""
    for version in FORMAT_VERSIONS:
        if n_actions <= len(ACTION_CHARACTERS[version]):
            return version
    raise ValueError(f"no recording format holds {n_actions} actions")


def default_table(env_id: str) -> str:
    """The table ``env_id`` plays unless told another (``classic``, ``classic_v1``)."""
    return ENV_VERSIONS[env_id].table


def make_recorded_env(
    options: Mapping[str, Any],
    max_episode_steps: int | None = None,
    env_id: str = RECORDABLE_ENV_IDS[0],
) -> gym.Env:
    """The env a recording is played on: ``gym.make(env_id, **options)``, rendering frames."""
    for key in RECORDING_FIXED_OPTIONS:
        if key in options:
            raise ValueError(f"the play tool sets {key} itself; do not pass it as an option")
    kwargs: dict[str, Any] = (
        {} if max_episode_steps is None else {"max_episode_steps": max_episode_steps}
    )
    return gym.make(env_id, render_mode="rgb_array", **kwargs, **options)


def write_recording(path: str | os.PathLike[str], recording: Recording) -> None:
    """Write ``recording`` as JSON, atomically (a crash leaves the previous file whole)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    temporary = path.with_name(path.name + ".tmp")
    temporary.write_text(json.dumps(recording.to_json(), indent=2) + "\n", encoding="utf-8")
    os.replace(temporary, path)


def load_recording(path: str | os.PathLike[str]) -> Recording:
    """Read and check a recording (:func:`parse_recording`); RecordingError says what is wrong."""
    try:
        data = json.loads(Path(path).read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError) as error:
        raise RecordingError(f"{path}: cannot read the recording: {error}") from None
    except json.JSONDecodeError as error:
        raise RecordingError(f"{path}: not a JSON recording: {error}") from None
    return parse_recording(data, str(path))


def parse_recording(data: Any, source: str = "recording") -> Recording:
    """The :class:`Recording` of a decoded JSON document, after checking every key and type."""

    def fail(problem: str) -> RecordingError:
        return RecordingError(f"{source}: {problem}")

    if not isinstance(data, dict):
        raise fail(f"expected a JSON object, got {type(data).__name__}")
    if data.get("format") != FORMAT:
        raise fail(f"not a pinball recording (format {data.get('format')!r}, expected {FORMAT!r})")
    version = data.get("version")
    if isinstance(version, bool) or version not in FORMAT_VERSIONS:
        readable = " and ".join(map(str, FORMAT_VERSIONS))
        raise fail(
            f"recording format version {version!r}; this pinball-env reads versions {readable}"
        )
    top = _fields(data, {
        "format": str, "version": int, "package_version": str, "env_id": str, "options": dict,
        "max_episode_steps": (int, type(None)), "table_sha256": str, "games": list,
    }, fail, "")  # fmt: skip
    if top["package_version"] != __version__:
        raise fail(
            f"recorded with pinball-env {top['package_version']}, this is {__version__}: a game "
            "can differ between versions, so it is not replayed"
        )
    if top["env_id"] not in RECORDABLE_ENV_IDS:
        known = ", ".join(map(repr, RECORDABLE_ENV_IDS[:-1])) + f" or {RECORDABLE_ENV_IDS[-1]!r}"
        raise fail(f"env_id {top['env_id']!r}: only {known} games are recorded")
    options = top["options"]
    for key in RECORDING_FIXED_OPTIONS:
        if key in options:
            raise fail(f"options.{key} is set by the play tool, it cannot be recorded")
    steps = top["max_episode_steps"]
    if steps is not None and steps < 1:
        raise fail(f"max_episode_steps must be None or >= 1, got {steps}")
    if not re.fullmatch(r"[0-9a-f]{64}", top["table_sha256"]):
        raise fail("table_sha256 must be 64 lowercase hex digits")
    if not top["games"]:
        raise fail("games is empty: the recording holds no game")
    return Recording(
        env_id=top["env_id"],
        options=options,
        max_episode_steps=steps,
        table_sha256=top["table_sha256"],
        games=tuple(
            _parse_game(raw, index, version, fail) for index, raw in enumerate(top["games"])
        ),
        package_version=top["package_version"],
        version=version,
    )


def _parse_game(
    raw: Any, index: int, version: int, fail: Callable[[str], RecordingError]
) -> GameRecord:
    """The :class:`GameRecord` of ``games[index]`` of a recording of format ``version``, after
    checking it."""
    where = f"games[{index}]."
    if not isinstance(raw, dict):
        raise fail(f"games[{index}] must be an object, got {type(raw).__name__}")
    game = _fields(
        raw, {"seed": int, "actions": str, "score": int, "frames": int, "end": str}, fail, where
    )
    for key in ("seed", "score", "frames"):
        if game[key] < 0:
            raise fail(f"{where}{key} must be >= 0, got {game[key]}")
    characters = ACTION_CHARACTERS[version]
    bad = re.search(f"[^{re.escape(characters)}]", game["actions"])
    if bad is not None:
        kind = "digit 0-3" if version == 1 else "character 0-9 or a-v"
        raise fail(
            f"{where}actions: {bad.group()!r} at step {bad.start()} is not an action "
            f"(one {kind} per step, format version {version})"
        )
    if not game["actions"]:
        raise fail(f"{where}actions is empty")
    if game["end"] not in ENDS:
        raise fail(f"{where}end must be one of {ENDS}, got {game['end']!r}")
    return GameRecord(**game)


def _fields(
    raw: dict[str, Any],
    types: dict[str, type | tuple[type, ...]],
    fail: Callable[[str], RecordingError],
    where: str,
) -> dict[str, Any]:
    """``raw`` with exactly the keys of ``types``, each of its type (a bool is not an int)."""
    unknown = sorted(set(raw) - set(types))
    if unknown:
        raise fail(f"unknown key {where}{unknown[0]}")
    for key, kind in types.items():
        if key not in raw:
            raise fail(f"missing key {where}{key}")
        value = raw[key]
        if isinstance(value, bool) or not isinstance(value, kind):
            expected = kind.__name__ if isinstance(kind, type) else "an int or null"
            raise fail(f"{where}{key} must be {expected}, got {json.dumps(value)[:40]}")
    return raw


def replay(recording: Recording, viewer: Viewer | None = None) -> list[int]:
    """Play every game of ``recording`` again and return their scores, checking that each ends
    as recorded (the score, the frames, and game over / time limit / unfinished); raises
    RecordingError if the table or any game differs. ``viewer``: called before each step (the
    play tool's window shows the replay through it)."""
    try:
        env = make_recorded_env(recording.options, recording.max_episode_steps, recording.env_id)
    except (TypeError, ValueError, OSError) as error:
        raise RecordingError(f"the recording's options do not make a game: {error}") from None
    try:
        _check_table(recording, env)
        return [_replay_game(env, game, n, viewer) for n, game in enumerate(recording.games)]
    finally:
        env.close()


@runtime_checkable
class _PlaysATable(Protocol):
    """An env that says which table it plays (``PinballEnv.table``)."""

    @property
    def table(self) -> Table: ...


def played_table(env: gym.Env) -> Table:
    """The table that ``env``, a Pinball env under its wrappers, plays."""
    core = env.unwrapped
    if not isinstance(core, _PlaysATable):
        raise RecordingError(f"{type(core).__name__} is not a Pinball env: it plays no table")
    return core.table


def action_count(env: gym.Env) -> int:
    """How many actions ``env`` takes: a recorded env's are discrete (``FIXED_OPTIONS``)."""
    space = env.action_space
    if not isinstance(space, gym.spaces.Discrete):
        raise RecordingError(f"recordings hold discrete actions, not those of {space}")
    return int(space.n)


def _check_table(recording: Recording, env: gym.Env) -> None:
    """RecordingError unless ``env`` plays the recorded table with every recorded action."""
    table = recording.options.get("table", default_table(recording.env_id))
    if table_sha256(played_table(env)) != recording.table_sha256:
        raise RecordingError(
            f"the table {table!r} is not the recorded one (its file has changed since): not "
            "replayed"
        )
    n_actions = action_count(env)
    for index, game in enumerate(recording.games):
        for step, action in enumerate(decode_recorded_actions(game.actions)):
            if action >= n_actions:
                raise RecordingError(
                    f"games[{index}].actions: {game.actions[step]!r} at step {step} is "
                    f"action {action}, but the table {table!r} has {n_actions} actions: not "
                    "replayed"
                )


def _replay_game(env: gym.Env, game: GameRecord, index: int, viewer: Viewer | None) -> int:
    """Play ``game`` (the ``index``-th) again on ``env``; its score, or RecordingError unless it
    ends as recorded."""
    name = f"game {index + 1} (seed {game.seed})"
    _, info = env.reset(seed=game.seed)
    actions = decode_recorded_actions(game.actions)
    ended: str | None = None
    for step, action in enumerate(actions):
        if viewer is not None:
            viewer(env, name)
        if ended is not None:
            raise RecordingError(
                f"{name}: the replay ended ({ended}) at step {step} of {len(actions)}; the "
                "recording is of a different game"
            )
        _, _, terminated, truncated, info = env.step(action)
        ended = "game over" if terminated else "time limit" if truncated else None
    expected_end = game.end if game.end in ("game over", "time limit") else None
    got = (info["score"], info["frames"], ended)
    want = (game.score, game.frames, expected_end)
    if got != want:
        raise RecordingError(
            f"{name}: the replay scored {got[0]} in {got[1]} frames ({got[2] or 'unfinished'}), "
            f"the recording says {want[0]} in {want[1]} ({want[2] or 'unfinished'})"
        )
    return int(info["score"])
