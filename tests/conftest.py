"""Test settings shared by every test file."""

import re

from hypothesis import settings

# Deterministic property tests: the same examples on every run and every machine, and no
# example database carried between runs.
settings.register_profile("deterministic", derandomize=True, database=None, deadline=None)
settings.load_profile("deterministic")


def pytest_configure(config):
    # Gymnasium tells every gym.make of an older version (Pinball-v0 beside Pinball-v3, as
    # CartPole-v0 beside -v1) that a newer one exists; the older versions stay for continuity,
    # so the notice is no news in the tests. Which are older is read from the version records.
    from pinball_env.versions import ENV_VERSIONS

    newest: dict[str, int] = {}
    for version in ENV_VERSIONS.values():
        newest[version.name] = max(newest.get(version.name, 0), version.version)
    for version in ENV_VERSIONS.values():
        if version.version < newest[version.name]:
            message = re.escape(f"{version.id} is out of date")
            config.addinivalue_line("filterwarnings", f"ignore:.*{message}:DeprecationWarning")
