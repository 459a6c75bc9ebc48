"""The game in a browser: ``python -m pinball_env.tools.serve``, then open http://localhost:8000.

A local web server (the ``web`` extra: Starlette on uvicorn) whose page draws the game on a
canvas from the table's geometry (sent once) and the state of every frame (streamed over a
WebSocket at the game's frame rate, 60 per second; ``pinball_env.tools.web``). Nothing to
install on the viewer's side; from a machine without a screen, forward the port::

    ssh -L 8000:localhost:8000 trainer   # then, there: python -m pinball_env.tools.serve

Modes (each page its own session, stepped on the server at real speed):

- play (the default): ``[--env ID] [--table NAME] [--seed S] [--protocol] [--record FILE]``, as
  the play tool: its keys (Left Shift / Z / Left arrow, Right Shift / M / Right arrow, Down /
  Enter the plunger, X / N / Up / B the nudges, P / Space pause, R restart) or the page's touch
  buttons; with ``--record`` every page's ended games are written to FILE in the play tool's
  format (``pinball_env.recording``), which ``python -m agents.evaluate --recording FILE``
  scores on the protocol;
- watch: ``--watch heuristic [--games N]`` (the scripted player, N games side by side), or
  ``--model RUN_OR_ZIP`` (or ``pretrained:NAME``) a trained agent, on the env it was trained on:
  loaded once, from that path only, by the installed agent loader (:func:`agent_loader`: the
  repository's ``agents``, which are not in the wheel, so from a checkout);
- replay: ``--replay FILE``: a recording, checked first (another version's, or one that does not
  replay as recorded, is refused), on a timeline: play, pause, step, scrub, speed.

Safe by default: it listens on 127.0.0.1 unless ``--host`` says otherwise, serves its page and
the state only, takes WebSockets from its own page only (the Origin is checked), at most
``--max-viewers`` pages at once; each page's send queue holds one frame (a slow page skips
frames) and a few other messages; a malformed message from a page gets an error back.
"""

import argparse
import asyncio
import contextlib
import html
import importlib.metadata
import ipaddress
import json
import os
import socket
import sys
from collections import deque
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, Any
from urllib.parse import urlsplit

import gymnasium as gym

from pinball_env.envs import unwrapped_pinball
from pinball_env.extras import MissingDependency, require
from pinball_env.players import HeuristicPolicy
from pinball_env.protocol import PROTOCOL_ENV_IDS, REPEAT_ACTION_PROBABILITY
from pinball_env.recording import (
    RECORDABLE_ENV_IDS,
    RecordingError,
    default_table,
    load_recording,
    make_recorded_env,
)
from pinball_env.tools import command_parser
from pinball_env.tools.web.sessions import (
    MAX_MESSAGE_BYTES,
    Message,
    PlaySession,
    Recorder,
    ReplayIndex,
    ReplaySession,
    Session,
    WatchedPlayer,
    WatchSession,
    error,
)

if TYPE_CHECKING:  # the web extra is optional: imported where used (make_app)
    from starlette.applications import Starlette
    from starlette.websockets import WebSocket

HOST = "127.0.0.1"  # this machine only; --host 0.0.0.0 opens it to the network
# What a page on this machine calls it (the Host header's name; an IPv6 address in brackets).
LOCAL_NAMES = ("localhost", "127.0.0.1", "[::1]")
# The page may not be framed by another site's (clickjacking).
PAGE_HEADERS = {"X-Frame-Options": "DENY", "Content-Security-Policy": "frame-ancestors 'none'"}
PORT = 8000
MAX_VIEWERS = 8  # pages at once: each has its own game
MAX_QUEUED = 32  # messages other than frames waiting for a slow page (the oldest dropped)
MAX_LATE_FRAMES = 6  # a tick this late skips ahead rather than stepping to catch up
STATIC = Path(__file__).resolve().parent / "web" / "static"
WATCHERS = ("heuristic",)  # the players --watch names
# The entry point group of --model's loader: a function of the path given that returns a maker
# of the agent's games (a WatchedPlayer each) and the env id they are of. The package never
# imports the agents; the repository's agents/ registers theirs (pyproject.toml).
AGENT_LOADERS = "pinball_env.agent_loaders"

SessionFactory = Callable[[], Session]


class Outbox:
    """A page's send queue: the newest frame (a frame not yet sent when the next comes is
    dropped) and at most ``limit`` other messages."""

    def __init__(self, limit: int = MAX_QUEUED) -> None:
        self.frame: Message | None = None
        self.others: deque[Message] = deque(maxlen=limit)
        self.ready = asyncio.Event()
        self.dropped = 0  # frames never sent

    def put(self, message: Message) -> None:
        if message["type"] == "frame":
            self.dropped += self.frame is not None
            self.frame = message
        else:
            self.others.append(message)
        self.ready.set()

    async def get(self) -> Message:
        while not (self.others or self.frame):
            self.ready.clear()
            await self.ready.wait()
        if self.others:
            return self.others.popleft()
        frame, self.frame = self.frame, None
        assert frame is not None  # the wait above ends on a message
        return frame


def encode(message: Message) -> str:
    """A message as the page receives it: compact JSON."""
    return json.dumps(message, separators=(",", ":"))


def make_app(
    factory: SessionFactory,
    max_viewers: int = MAX_VIEWERS,
    title: str = "Pinball",
    hosts: tuple[str, ...] | None = LOCAL_NAMES,
) -> "Starlette":
    """The ASGI app: the page (``/``), its files (``/static``) and each page's WebSocket
    (``/ws``), whose session ``factory()`` makes. ``hosts``: the names a request may call the
    server by (the Host header; None: any), so that another site's name pointed at this
    machine (DNS rebinding) reaches nothing."""
    require("starlette", "websockets")  # MissingDependency names the web extra
    from starlette.applications import Starlette
    from starlette.middleware import Middleware
    from starlette.middleware.trustedhost import TrustedHostMiddleware
    from starlette.responses import HTMLResponse
    from starlette.routing import Mount, Route, WebSocketRoute
    from starlette.staticfiles import StaticFiles
    from starlette.websockets import WebSocket, WebSocketDisconnect

    page = (STATIC / "index.html").read_text(encoding="utf-8")
    page = page.replace("{{title}}", html.escape(title))
    viewers: set[Any] = set()

    async def index(request: Any) -> HTMLResponse:
        return HTMLResponse(page, headers=PAGE_HEADERS)

    async def game_socket(websocket: WebSocket) -> None:
        if not await admitted(websocket, viewers, max_viewers):
            return
        viewers.add(websocket)
        session = None
        try:
            try:  # (off the event loop: the other pages play on meanwhile)
                session = await asyncio.to_thread(factory)
            except Exception as failure:  # the page says why, the server log has the rest
                await websocket.send_text(encode(error(f"no game could start: {failure}")))
                raise
            await play_session(websocket, session, WebSocketDisconnect)
        finally:
            viewers.discard(websocket)
            if session is not None:
                session.close()

    trusted = [] if hosts is None else [Middleware(TrustedHostMiddleware, allowed_hosts=hosts)]
    app = Starlette(
        routes=[
            Route("/", index),
            Mount("/static", StaticFiles(directory=STATIC), name="static"),
            WebSocketRoute("/ws", game_socket),
        ],
        middleware=trusted,
    )
    app.state.viewers = viewers
    return app


async def admitted(websocket: "WebSocket", viewers: set[Any], max_viewers: int) -> bool:
    """Whether a page's WebSocket may play: not when another site's page opened it (closed
    unaccepted) or when ``max_viewers`` pages already play (accepted to be told so, closed)."""
    origin = websocket.headers.get("origin")
    if origin is not None and urlsplit(origin).netloc != websocket.headers.get("host"):
        await websocket.close(code=1008, reason="another site's page")
        return False
    await websocket.accept()
    if len(viewers) >= max_viewers:
        await websocket.send_text(encode(error(f"full: {max_viewers} pages at most")))
        await websocket.close(code=1013)
        return False
    return True


async def play_session(
    websocket: "WebSocket", session: Session, disconnect: type[Exception]
) -> None:
    """Run ``session`` for one page: its hello, then a tick every frame at real speed, the
    page's messages applied as they come, each sent through an :class:`Outbox`. The page gone
    (``disconnect``) ends it quietly; any other failure (a session's bug) is raised."""
    outbox = Outbox()
    for message in session.hello():
        outbox.put(message)

    async def send() -> None:
        while True:
            text = encode(await outbox.get())
            try:
                await websocket.send_text(text)
            except RuntimeError as gone:  # Starlette's send to a page that has gone
                raise disconnect(1006) from gone

    async def receive() -> None:
        while True:
            message = await websocket.receive()
            if message["type"] == "websocket.disconnect":
                raise disconnect(message.get("code", 1000))
            if message.get("text") is None:  # the page sends text (JSON), never binary
                outbox.put(error("binary message refused: the page's messages are JSON text"))
                continue
            for reply in session.receive(message["text"]):
                outbox.put(reply)

    async def tick() -> None:
        loop = asyncio.get_running_loop()
        period = 1.0 / session.fps
        deadline = loop.time()
        while True:
            for message in session.tick():
                outbox.put(message)
            deadline += period
            late = loop.time() - deadline
            if late > MAX_LATE_FRAMES * period:  # fell behind (a slow machine): no burst
                deadline = loop.time()
            await asyncio.sleep(max(0.0, deadline - loop.time()))

    tasks = [asyncio.create_task(job()) for job in (send, receive, tick)]
    try:
        done, _ = await asyncio.wait(tasks, return_when=asyncio.FIRST_COMPLETED)
        for task in done:  # a page gone ends the session; anything else is a bug to show
            failure = task.exception()
            if failure is not None and not isinstance(failure, disconnect):
                raise failure
    finally:
        for task in tasks:
            task.cancel()
        for task in tasks:
            with contextlib.suppress(asyncio.CancelledError, Exception):
                await task


# --- the command line -------------------------------------------------------------------------


def parser() -> argparse.ArgumentParser:
    """The command line's arguments."""
    parser = command_parser("pinball_env.tools.serve", __doc__)
    parser.add_argument("--host", default=HOST, help=f"address to listen on (default {HOST})")
    parser.add_argument("--port", type=int, default=PORT, help=f"port (default {PORT})")
    parser.add_argument(
        "--max-viewers", type=int, default=MAX_VIEWERS,
        help=f"pages at once, each its own game (default {MAX_VIEWERS})",
    )  # fmt: skip
    parser.add_argument(
        "--env", choices=RECORDABLE_ENV_IDS, help=f"the env (default {PROTOCOL_ENV_IDS[0]})"
    )
    parser.add_argument("--table", help="table name or YAML path (default: the env's own)")
    parser.add_argument(
        "--seed", type=int, help="seed of the first game (default: random in play, 0 in watch)"
    )
    parser.add_argument(
        "--protocol", action="store_true", help="the benchmark protocol's game (sticky actions)"
    )
    parser.add_argument("--games", type=int, help="watch: games side by side (default 1)")
    modes = parser.add_mutually_exclusive_group()
    modes.add_argument("--record", type=Path, help="play: write the games played to this file")
    modes.add_argument("--replay", type=Path, help="replay a recording on a timeline")
    modes.add_argument("--watch", choices=WATCHERS, help="watch a scripted player play")
    modes.add_argument(
        "--model", help="watch a trained agent: a run folder, a model zip or pretrained:NAME"
    )
    return parser


def check_args(command: argparse.ArgumentParser, args: argparse.Namespace) -> None:
    """Refuse the combinations that make no sense, before anything runs."""
    if args.seed is not None and args.seed < 0:
        command.error(f"--seed must be >= 0, got {args.seed}")
    if not 1 <= args.max_viewers <= 1000:
        command.error(f"--max-viewers must be from 1 to 1000, got {args.max_viewers}")
    if args.games is not None and not 1 <= args.games <= 16:
        command.error(f"--games must be from 1 to 16, got {args.games}")
    if args.games is not None and args.watch is None and args.model is None:
        command.error("--games is for watching (--watch, --model): a page plays one game")
    if args.protocol and args.table:
        command.error("--protocol plays the env's own table")
    if args.replay is not None and (
        args.env or args.table or args.seed is not None or args.protocol
    ):
        command.error("--replay takes the env, the table and the seeds from the recording")
    if args.model is not None and (args.env or args.table or args.protocol):
        command.error("--model plays the agent's own game: no --env, --table or --protocol")
    env_id = default_env_id(args)
    if args.protocol and env_id not in PROTOCOL_ENV_IDS:
        command.error(f"--protocol plays {', '.join(PROTOCOL_ENV_IDS)}, not {env_id}")
    if args.record is not None:
        problem = unwritable(args.record)
        if problem:
            command.error(f"--record {args.record}: {problem}")


def unwritable(path: Path) -> str | None:
    """Why the recording cannot be written to ``path`` (None: it can), checked at the start so
    that a game is not lost at its end. Its folder is made, as the play tool's is (the file is
    written through a temporary file beside it, :func:`~pinball_env.recording.write_recording`,
    so the folder must take new files)."""
    folder = path.parent
    if path.is_dir():
        return "is a folder"
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as error:
        return f"cannot make its folder {folder} ({error.strerror or error})"
    if not os.access(folder, os.W_OK | os.X_OK):
        return f"the folder {folder} is not writable"
    return None


def default_env_id(args: argparse.Namespace) -> str:
    """The env of the command line's game: ``--env``, else the protocol's."""
    return args.env or PROTOCOL_ENV_IDS[0]


def env_options(args: argparse.Namespace) -> tuple[str, dict[str, Any]]:
    """The env id and ``gym.make`` options of the command line's game."""
    env_id = default_env_id(args)
    options: dict[str, Any] = {"table": args.table or default_table(env_id)}
    if args.protocol:
        options["repeat_action_probability"] = REPEAT_ACTION_PROBABILITY
    return env_id, options


def session_factory(args: argparse.Namespace) -> tuple[SessionFactory, str]:
    """What each page gets (play, watch or replay) and the page's title; SystemExit for a
    recording that cannot be replayed."""
    if args.replay is not None:
        try:
            index = ReplayIndex(load_recording(args.replay))
        except RecordingError as refused:
            raise SystemExit(f"refused: {refused}") from None
        return (lambda: ReplaySession(index)), f"Pinball replay: {args.replay.name}"
    seed = args.seed or 0
    games = args.games or 1
    if args.model is not None:
        player, env_id = agent_loader()(args.model)

        def agent() -> Session:
            return WatchSession([player() for _ in range(games)], seed, args.model)

        return agent, f"Pinball: {args.model} on {env_id}"
    env_id, options = env_options(args)
    if args.watch is not None:

        def heuristic() -> WatchedPlayer:
            env = gym.make(env_id, **options)
            policy = HeuristicPolicy(unwrapped_pinball(env).table)
            return WatchedPlayer(env, lambda obs, info: policy(info), policy.reset)

        def watch() -> Session:
            return WatchSession([heuristic() for _ in range(games)], seed, args.watch)

        return watch, f"Pinball: {args.watch} on {env_id}"
    recorder = None
    if args.record is not None:
        probe = make_recorded_env(options, env_id=env_id)
        recorder = Recorder(args.record, probe, env_id, options)
        probe.close()
    return (lambda: PlaySession(env_id, options, args.seed, recorder)), f"Pinball: {env_id}"


def agent_loader() -> Callable[[str], tuple[Callable[[], WatchedPlayer], str]]:
    """The installed loader of ``--model`` (the entry point of :data:`AGENT_LOADERS`); SystemExit
    saying what to do where there is none or it cannot be imported (a wheel without the
    repository's agents)."""
    found = sorted(importlib.metadata.entry_points(group=AGENT_LOADERS), key=lambda e: e.name)
    if not found:
        raise SystemExit(
            f"--model needs an agent loader (entry point group {AGENT_LOADERS}): the "
            "repository's agents provide one; install its checkout (pip install -e .)"
        )
    try:
        return found[0].load()
    except ImportError as error:
        raise SystemExit(
            f"--model: the agent loader {found[0].value} cannot be imported ({error}); run from "
            "the repository's checkout, where agents/ is"
        ) from None


def allowed_hosts(host: str) -> tuple[str, ...] | None:
    """The Host names a server listening on ``host`` answers: this machine's own names (and
    ``host``) when it listens on a loopback address or ``localhost`` only, any name when it is
    opened to the network (``--host``)."""
    try:
        loopback = host == "localhost" or ipaddress.ip_address(host).is_loopback
    except ValueError:  # a name other than localhost
        loopback = False
    if not loopback:
        return None
    own = f"[{host}]" if ":" in host else host
    return tuple(dict.fromkeys((*LOCAL_NAMES, own)))


def require_web() -> None:
    """SystemExit naming the web extra if a part of it is missing: checked before a
    recording is replayed, a model loaded or a game made."""
    try:
        require("starlette", "uvicorn", "websockets")
    except MissingDependency as error:
        raise SystemExit(str(error)) from None


def server_config(app: "Starlette", log_level: str = "warning", **kwargs: Any) -> Any:
    """uvicorn's settings of the server: a page's WebSocket messages longer than the sessions
    take are refused by the WebSocket layer itself (closed, 1009), before they are read
    whole."""
    uvicorn = require("uvicorn")
    return uvicorn.Config(app, log_level=log_level, ws_max_size=MAX_MESSAGE_BYTES, **kwargs)


def listening_socket(host: str, port: int) -> socket.socket:
    """The server's socket, bound to ``host``:``port``; SystemExit saying so where it cannot
    be (a port in use, an address not of this machine), before anything is served."""
    family = socket.AF_INET6 if ":" in host else socket.AF_INET
    try:
        return socket.create_server((host, port), family=family)
    except OSError as failure:
        raise SystemExit(
            f"cannot serve on {host} port {port}: {failure.strerror or failure} "
            "(another server there? --port chooses another)"
        ) from None


def run(app: "Starlette", host: str, port: int) -> None:
    """Serve ``app`` until interrupted (uvicorn), once its socket is bound."""
    uvicorn = require("uvicorn")
    listening = listening_socket(host, port)
    shown = f"[{host}]" if ":" in host else host
    print(f"serving on http://{shown}:{port}/ (Ctrl+C stops)", file=sys.stderr)
    uvicorn.Server(server_config(app)).run(sockets=[listening])


def unrecorded(args: argparse.Namespace) -> argparse.Namespace:
    """``args`` without ``--record``."""
    return argparse.Namespace(**{**vars(args), "record": None})


def prepare(factory: SessionFactory) -> None:
    """A page's game made and played a frame before the server answers: its kernels compiled
    (the first time on a machine and Python: minutes, which the line says) or loaded from
    numba's cache, so that no page waits on a compile and no compile holds up the pages."""
    print("preparing the game: its kernels compile the first time on a machine (one to three "
          "minutes), then load from numba's cache", file=sys.stderr, flush=True)  # fmt: skip
    session = factory()
    try:
        session.tick()
    finally:
        session.close()


def main(argv: list[str] | None = None) -> None:
    command = parser()
    args = command.parse_args(argv)
    check_args(command, args)
    require_web()
    factory, title = session_factory(args)
    # (a game played on a page with --record is recorded: the one prepared is not)
    prepare(factory if args.record is None else session_factory(unrecorded(args))[0])
    run(make_app(factory, args.max_viewers, title, allowed_hosts(args.host)), args.host, args.port)


if __name__ == "__main__":
    main()
