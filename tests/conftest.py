"""Test settings shared by every test file."""

from hypothesis import settings

# Deterministic property tests: the same examples on every run and every machine, and no
# example database carried between runs.
settings.register_profile("deterministic", derandomize=True, database=None, deadline=None)
settings.load_profile("deterministic")
