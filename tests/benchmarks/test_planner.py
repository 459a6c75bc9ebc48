"""benchmarks.planner: the protocol's games, the heuristic beside the planner's settings, the
figures written."""

import json
from pathlib import Path

from benchmarks import planner

PUBLISHED = Path(__file__).resolve().parents[2] / "docs" / "benchmark.json"


def test_it_plays_the_protocols_games_and_writes_its_figures(tmp_path):
    result = planner.main(["--games", "2", "--ladder", "h15", "--json", str(tmp_path / "p.json"),
                           "--figure", str(tmp_path / "p.png")])  # fmt: skip
    # The heuristic's games are the protocol's: the published heuristic-v3 row's first two.
    published = json.loads(PUBLISHED.read_text())["methods"]["heuristic-v3"]["runs"][0]
    assert result["heuristic"]["scores"] == published["scores"][:2]
    row = result["ladder"]["h15"]
    assert (
        len(row["scores"]) == 2 and row["settings"]["horizon"] == 15 and not row["settings"]["aims"]
    )
    assert row["branch_steps_per_game"] > 0 and row["decisions_per_game"] > 0
    assert json.loads((tmp_path / "p.json").read_text())["ladder"]["h15"]["scores"] == row["scores"]
    assert (tmp_path / "p.png").stat().st_size > 0
