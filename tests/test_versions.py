"""The env versions' records (``pinball_env.versions``): what Gymnasium registers, what the
protocol plays, what the play tool records and what ``PinballEnv``'s docstring says are theirs."""

import re

import gymnasium as gym
import pytest

from pinball_env import protocol, recording
from pinball_env.envs import PinballEnv
from pinball_env.options import GENERATED, MAX_EPISODE_STEPS, PinballOptions
from pinball_env.table import Table, load_table
from pinball_env.versions import (
    ENV_VERSIONS,
    benchmark_versions,
    recordable_versions,
    version_history,
)


def test_the_registered_envs_are_the_records():
    registered = {env_id for env_id in gym.registry if env_id.startswith("Pinball")}
    assert registered == set(ENV_VERSIONS)
    for env_id, version in ENV_VERSIONS.items():
        spec = gym.spec(env_id)
        assert version.id == env_id and re.fullmatch(r"\w+-v\d+", env_id)
        assert spec.kwargs.get("table", PinballOptions.table) == version.table
        assert spec.max_episode_steps == MAX_EPISODE_STEPS
        assert spec.entry_point == "pinball_env.envs:PinballEnv"
        assert spec.vector_entry_point == "pinball_env.envs:PinballVectorEnv"
    # Pinball-v0's spec passes no table, as it always did (the options' default).
    assert gym.spec("Pinball-v0").kwargs == {}


def test_the_protocol_and_the_recordings_read_the_records():
    assert tuple(v.id for v in benchmark_versions()) == protocol.PROTOCOL_ENV_IDS
    # The order of the published tables: the protocol's env, then its tracks.
    assert protocol.PROTOCOL_ENV_IDS == ("Pinball-v3", "Pinball-v2", "Pinball-v1", "Pinball-v0")
    assert [v.track for v in benchmark_versions()] == list(range(len(protocol.PROTOCOL_ENV_IDS)))
    assert set(protocol.REFERENCE_SCORES) == set(protocol.PROTOCOL_ENV_IDS)
    assert tuple(v.id for v in recordable_versions()) == recording.RECORDABLE_ENV_IDS
    assert recording.RECORDABLE_ENV_IDS == ("Pinball-v0", "Pinball-v1", "Pinball-v2", "Pinball-v3")
    for env_id in recording.RECORDABLE_ENV_IDS:
        assert recording.default_table(env_id) == ENV_VERSIONS[env_id].table


@pytest.mark.parametrize("env_id", list(ENV_VERSIONS))
def test_each_records_table_loads(env_id):
    version = ENV_VERSIONS[env_id]
    if version.table == GENERATED:
        assert PinballOptions(table=version.table).generated
        env = gym.make(env_id, num_layouts=1)
        env.reset(seed=0)
        assert isinstance(env.unwrapped.table, Table)
        env.close()
    else:
        assert load_table(version.table).name == version.table


def _plain(text: str) -> str:
    """``text`` with its whitespace runs as one space and reST's double backticks as Markdown's
    single ones."""
    return " ".join(text.replace("``", "`").split())


def test_pinball_env_s_version_history_is_the_records():
    docstring = PinballEnv.__doc__ or ""
    history = _plain(docstring.partition("## Version History")[2])
    entries = [f"- {v.id}: {_plain(v.history)}" for v in version_history()]
    positions = [history.find(entry) for entry in entries]
    missing = [entry for entry, at in zip(entries, positions, strict=True) if at < 0]
    assert not missing, f"PinballEnv's Version History lacks (write it as the records): {missing}"
    assert positions == sorted(positions), "the history lists each env's versions newest first"
    assert len(re.findall(r"- \w+-v\d+:", history)) == len(entries)


def test_an_older_version_says_what_it_is_and_which_env_is_the_benchmarks():
    from pinball_env.versions import older_version_note

    note = older_version_note("Pinball-v2")
    assert note is not None and note.startswith("note: Pinball-v2 is an older game than Pinball-v3")
    assert ENV_VERSIONS["Pinball-v2"].summary in note and note.endswith("env is Pinball-v3")
    assert older_version_note("Pinball-v3") is None  # the newest
    assert older_version_note("PinballProcgen-v0") is None  # its only version
    assert older_version_note("CartPole-v1") is None
