"""Optional dependencies: one declaration each (pinball_env.extras), the extras of
pyproject.toml that install them, and a missing one named in one line before anything runs."""

import sys
from pathlib import Path

import pytest

from pinball_env.extras import OPTIONAL, MissingDependency, missing_message, require
from pinball_env.tools import demo

tomllib = pytest.importorskip("tomllib")  # Python >= 3.11
ROOT = Path(__file__).resolve().parent.parent
EXTRAS = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["optional-dependencies"]


@pytest.mark.parametrize("module", sorted(OPTIONAL))
def test_each_optional_dependency_is_in_the_extra_its_message_names(module):
    package, extra = OPTIONAL[module]
    requirements = " ".join(EXTRAS[extra]).lower()
    for name in package.strip('"').split():
        assert name.split("[")[0].lower() in requirements, (module, extra)
    message = missing_message(module)
    assert "\n" not in message
    # An installed package (pip install NAME) and a checkout (the extra) both get a command.
    assert f"pip install {package}" in message and f'pip install -e ".[{extra}]"' in message


def test_the_dev_extra_is_everything_but_ray():
    (everything,) = [r for r in EXTRAS["dev"] if r.startswith("pinball-env[")]
    assert set(everything.removeprefix("pinball-env[").rstrip("]").split(",")) == set(EXTRAS) - {
        "dev", "distributed"
    }  # fmt: skip
    assert any("moviepy" in r for r in EXTRAS["train"])  # videos both ways: imageio, moviepy


def test_a_missing_dependency_is_one_line_naming_its_extra(monkeypatch):
    monkeypatch.setitem(sys.modules, "pymunk", None)  # as if not installed
    with pytest.raises(MissingDependency, match=r"pymunk is missing: .*\[crosscheck\]") as error:
        require("pymunk")
    assert isinstance(error.value, ImportError)


def test_the_demo_checks_what_it_needs_before_playing(monkeypatch, capsys):
    monkeypatch.setitem(sys.modules, "matplotlib", None)
    with pytest.raises(SystemExit) as exit_:
        demo.main(["--headless"])
    assert exit_.value.code == 1
    out, err = capsys.readouterr()
    assert "game 1" not in out  # no game was played
    assert err.strip() == f"error: {missing_message('matplotlib')}"
