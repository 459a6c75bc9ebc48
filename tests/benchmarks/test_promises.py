import json

import pytest

from benchmarks.promises import quick_start_commands, reported_scores


def test_the_readme_quick_starts_two_commands_are_read_as_written():
    commands = quick_start_commands()
    assert commands["train"][:3] == ["python", "-m", "agents.train"]
    assert "--report" in commands["train"]
    assert commands["tests"][0] == "pytest"


def test_a_readme_without_two_commands_is_refused(tmp_path):
    readme = tmp_path / "README.md"
    readme.write_text("# x\n\n## Quick start\n\n```bash\npip install -e . && pytest\n```\n")
    with pytest.raises(ValueError, match="expected two"):
        quick_start_commands(readme)


def test_the_scores_come_from_the_runs_report(tmp_path):
    run = tmp_path / "Pinball-v3_ppo_seed0_TIME"
    run.mkdir()
    report = {"random": {"score_mean": 12.4}, "model": {"score_mean": 64888.2}, "commit": "x"}
    (run / "report.json").write_text(json.dumps(report))
    assert reported_scores(tmp_path) == {"random": 12, "model": 64888}
