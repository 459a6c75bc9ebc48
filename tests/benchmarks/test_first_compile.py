import pytest

from benchmarks.first_compile import PHASES, first_game_seconds, table


@pytest.mark.filterwarnings("ignore::DeprecationWarning")
def test_a_first_game_is_timed_phase_by_phase_and_tabled():
    seconds = first_game_seconds("Pinball-v0")
    assert list(seconds) == list(PHASES) and all(value >= 0 for value in seconds.values())
    text = table({"envs": {"Pinball-v0": {"cold": seconds, "warm": seconds}}})
    lines = text.splitlines()
    assert len(lines) == 3 and lines[1].split()[:2] == ["Pinball-v0", "cold"]
    assert lines[1].split()[-1] == f"{seconds['first step']:.1f}"
