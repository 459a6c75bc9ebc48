"""The env versions, one record each: what the package registers (``pinball_env/__init__.py``),
what the benchmark protocol plays (:data:`pinball_env.protocol.PROTOCOL_ENV_IDS`), what the
play tool records (:data:`pinball_env.recording.RECORDABLE_ENV_IDS`) and what the docs list
(``docs/generate.py``) are all read from :data:`ENV_VERSIONS`.

A change that would change an env's game makes a new version (``docs/development.md``): a new
record here, on its own table.
"""

import dataclasses

from pinball_env.options import GENERATED


@dataclasses.dataclass(frozen=True)
class EnvVersion:
    """One registered env: ``gym.make(id)`` plays ``table``."""

    id: str
    """The Gymnasium id, ``NAME-vN``."""
    table: str
    """The table it plays unless told another: a built-in table's name, or ``"generated"``."""
    summary: str
    """What it is, in a line (the docs' table of the envs)."""
    history: str
    """What this version changed, its entry in the version history (Markdown)."""
    recordable: bool
    """Whether the play tool records and replays its games (``pinball_env.recording``)."""
    track: int | None
    """Its place among the benchmark protocol's envs, which its published tables follow: 0 the
    protocol's env, then its tracks; None outside the benchmark."""

    @property
    def name(self) -> str:
        """The id without its version: ``Pinball``, ``PinballProcgen``."""
        return self.id.rpartition("-v")[0]

    @property
    def version(self) -> int:
        return int(self.id.rpartition("-v")[2])


_VERSIONS = (
    EnvVersion(
        id="Pinball-v0",
        table="classic",
        summary="the two-button table: the flippers, a launch from the machine's plunger",
        history="the first release: swept collision against walls, posts and rotating flippers.",
        recordable=True,
        track=3,
    ),
    EnvVersion(
        id="Pinball-v1",
        table="classic_v1",
        summary="the whole cabinet (the player's plunger, the nudge and the tilt), rules and "
        "targets",
        history="the whole cabinet on `classic_v1` (the classic layout): the player's plunger "
        "and a skill shot, the nudge, the plumb-bob tilt; 32 actions. Then rules and targets on "
        "`classic_v1` (top lanes with lane change and the bonus multiplier, a drop bank, a "
        "spinner, a stand-up, a kickback, ball save; the observation's rule rows, 29 in all), "
        "which changed v1's games and scores.",
        recordable=True,
        track=2,
    ),
    EnvVersion(
        id="Pinball-v2",
        table="classic_v2",
        summary="v1's game with a tilt that any sustained nudging trips",
        history="v1's game with a tilt that any sustained nudging trips (`classic_v2`: the plumb "
        "bob's ring at 1 degree, `settle_time` 1 s): every nudge is a warning.",
        recordable=True,
        track=1,
    ),
    EnvVersion(
        id="Pinball-v3",
        table="classic_v3",
        summary="v2's game with multiball: a trough of three balls, a two-ball lock, a saucer, "
        "the jackpot lit during a multiball",
        history="v2's game with multiball (`classic_v3`: v2's table with a two-ball lock, a "
        "saucer, a trough of three balls and its auto-plunger, the jackpot lit only during a "
        "multiball); a row block per ball in the state observation, rays that see every ball "
        "and the standing drop targets.",
        recordable=True,
        track=0,
    ),
    EnvVersion(
        id="PinballProcgen-v0",
        table=GENERATED,
        summary="a generated table every game (`num_layouts`, `difficulty`, ...)",
        history="the first release: a generated table every game (`num_layouts`, "
        "`start_layout`, `difficulty`). Then the `targets` option, whose default leaves every "
        "game as it was.",
        recordable=False,
        track=None,
    ),
)
# Every env version by id, in the order they are registered and listed.
ENV_VERSIONS: dict[str, EnvVersion] = {version.id: version for version in _VERSIONS}


def benchmark_versions() -> tuple[EnvVersion, ...]:
    """The benchmark protocol's envs in its order (by ``track``): the protocol's env first."""
    tracked = [version for version in ENV_VERSIONS.values() if version.track is not None]
    return tuple(sorted(tracked, key=lambda version: version.track or 0))


def recordable_versions() -> tuple[EnvVersion, ...]:
    """The envs the play tool records, in the order they are registered."""
    return tuple(version for version in ENV_VERSIONS.values() if version.recordable)


def version_history() -> tuple[EnvVersion, ...]:
    """The versions as their history lists them: each env's name together, newest first."""
    return tuple(sorted(ENV_VERSIONS.values(), key=lambda v: (v.name, -v.version)))


def older_version_note(env_id: str) -> str | None:
    """One line saying that ``env_id`` is an older version of its env and why one may still
    use it (None for the newest, or an env not of this package), in the project's words
    beside Gymnasium's "out of date" notice."""
    version = ENV_VERSIONS.get(env_id)
    if version is None:
        return None
    newest = max((v for v in ENV_VERSIONS.values() if v.name == version.name),
                 key=lambda v: v.version)  # fmt: skip
    if newest is version:
        return None
    why = "" if version.track is None else ", a track of the benchmark"
    return (
        f"note: {env_id} is an older game than {newest.id}, kept bitwise for its scores and "
        f"agents{why} ({version.summary}); the benchmark's own env is {benchmark_versions()[0].id}"
    )


__all__ = [
    "ENV_VERSIONS",
    "EnvVersion",
    "benchmark_versions",
    "older_version_note",
    "recordable_versions",
    "version_history",
]
