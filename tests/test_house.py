"""The house rules: imports run one way (physics at the bottom), and the package imports no agent
library, and none of its tools, when it is imported."""

import ast
import subprocess
import sys
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parent.parent / "pinball_env"


def imported_modules(path: Path) -> set[str]:
    modules = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Import):
            modules.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom):
            assert node.level == 0, f"{path.name}: a relative import hides where it points"
            modules.add(node.module)
    return modules


@pytest.mark.parametrize("path", sorted((PACKAGE / "physics").glob("*.py")), ids=lambda p: p.name)
def test_physics_imports_nothing_from_above_it(path):
    for module in imported_modules(path):
        if module.startswith("pinball_env"):
            assert module.startswith("pinball_env.physics"), module
        assert module.split(".")[0] not in {"gymnasium", "yaml", "pygame", "pymunk"}, module


@pytest.mark.parametrize("path", sorted((PACKAGE / "table").glob("*.py")), ids=lambda p: p.name)
def test_the_table_imports_only_physics_and_itself(path):
    for module in imported_modules(path):
        if module.startswith("pinball_env"):
            assert module.startswith(("pinball_env.physics", "pinball_env.table")), module


def test_importing_the_package_loads_no_agent_library_and_no_tool():
    code = (
        "import sys, gymnasium as gym, pinball_env, pinball_env.wrappers; "
        "gym.make('Pinball-v0').reset(seed=0); gym.make_vec('Pinball-v0', num_envs=2); "
        "heavy = {'torch', 'stable_baselines3', 'pymunk', 'pygame', 'matplotlib', 'ray'}; "
        "print(sorted(m for m in sys.modules if m.split('.')[0] in heavy "
        "or m.startswith('pinball_env.tools')))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"
