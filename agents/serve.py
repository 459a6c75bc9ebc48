"""A trained agent playing in the browser: ``python -m agents.serve --model RUN_OR_ZIP``.

    python -m agents.serve --model pretrained:ppo-gentle-v1 --games 3   # then http://localhost:8000

The page of ``python -m pinball_env.tools.serve`` (its options: ``--host``, ``--port``,
``--max-viewers``, ``--seed``, ``--games``) in watch mode, the player the agent saved at
``--model`` (what :func:`agents.policy.load_policy` takes: a run folder, a model or checkpoint
zip, an RLlib checkpoint, ``pretrained:NAME``), loaded once, from that path only, before the
server starts. Each page gets ``--games`` games side by side, on seeds ``--seed`` on, played
through the env chain the agent was trained on, every frame shown at real speed. The agent's
own env and table are played: ``--env``, ``--table``, ``--protocol``, ``--record``, ``--replay``
and ``--watch`` are the tool's other modes. (The command lives here, not in the tool, because
the package never imports ``agents``.)
"""

from typing import Any

from agents.config import ConfigError
from agents.policy import Policy, load_policy
from pinball_env.tools import serve
from pinball_env.tools.web.sessions import WatchedPlayer, WatchSession


def agent_player(policy: Policy) -> WatchedPlayer:
    """A game of ``policy``'s env chain, played by it (greedy)."""
    return WatchedPlayer(policy.make_env(), lambda obs, info: policy.act(obs))


def main(argv: list[str] | None = None) -> None:
    command = serve.parser()
    command.description = __doc__.splitlines()[0]
    command.add_argument(
        "--model", required=True, help="the agent: run folder, zip, pretrained:NAME"
    )
    args = command.parse_args(argv)
    serve.check_args(command, args)
    others = [f"--{name}" for name in ("env", "table", "protocol", "record", "replay", "watch")
              if getattr(args, name) not in (None, False)]  # fmt: skip
    if others:
        command.error(f"--model plays the agent's own game: no {others[0]}")
    serve.require_web()
    try:
        policy = load_policy(args.model)
    except (ConfigError, ValueError, OSError) as error:
        raise SystemExit(f"cannot load the agent {args.model}: {error}") from None
    name = str(args.model)
    seed = args.seed or 0

    def watch() -> Any:
        return WatchSession([agent_player(policy) for _ in range(args.games)], seed, name)

    title = f"Pinball: {name} on {policy.env_id}"
    app = serve.make_app(watch, args.max_viewers, title, serve.allowed_hosts(args.host))
    serve.run(app, args.host, args.port)


if __name__ == "__main__":
    main()
