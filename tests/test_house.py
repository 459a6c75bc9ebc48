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
            if node.module == "pinball_env":  # from pinball_env import checks: the submodule
                modules.update(f"pinball_env.{alias.name}" for alias in node.names)
            else:
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


# What each floor may import from the package (besides itself), bottom up: the arrows run
# agents -> wrappers/envs -> observation/game -> sim -> table/procgen -> physics, with the
# declarations every floor may use (checks, extras, protocol, versions) beside them, the
# scripted players and the recording format over the game, and the tools on top of it all.
# "__init__" is the package itself (its version, its registration of the envs).
BELOW_TOOLS = {
    "physics": (),
    "checks.py": ("table",),  # the kinds of value are the table's (table/fields.py)
    "extras.py": (),
    "version.py": (),  # the package's version
    "protocol.py": ("options", "versions"),  # its game is options' GAME_FRAMES
    "table": ("physics",),
    "sim": ("physics", "table", "extras"),
    "procgen": ("physics", "table", "sim"),  # its playability check plays balls on a World
    "render": ("physics", "table", "sim", "extras"),
    "options.py": ("checks", "table", "procgen", "sim"),
    "versions.py": ("options",),  # a generated table's source is options' GENERATED
    "game": ("physics", "table", "sim", "options", "checks"),
    "observation.py": ("physics", "table", "sim", "game", "render"),
    "envs": ("physics", "table", "sim", "procgen", "game", "options", "checks", "observation",
             "render", "version"),  # (a saved game carries the package's version)
    "__init__.py": ("options", "procgen", "versions", "version"),
    "wrappers": ("envs", "extras"),
    "players": ("physics", "table", "sim", "game"),
    "heuristic.py": ("players",),  # the documented import path of the heuristic
    "recording.py": ("__init__", "table", "versions"),
}  # fmt: skip
FLOORS = {**BELOW_TOOLS, "tools": ("__init__", *(f.removesuffix(".py") for f in BELOW_TOOLS))}


def floor_files(floor: str) -> list[Path]:
    path = PACKAGE / floor
    return [path] if path.suffix == ".py" else sorted(path.rglob("*.py"))


def test_every_module_of_the_package_is_on_a_floor():
    placed = {path for floor in FLOORS for path in floor_files(floor)}
    assert placed == set(PACKAGE.rglob("*.py")), sorted(
        str(path.relative_to(PACKAGE)) for path in set(PACKAGE.rglob("*.py")) - placed
    )


def package_module(module: str) -> str:
    """``pinball_env.X`` for a module of the package's floor X, ``pinball_env`` for the package
    itself (``from pinball_env import __version__``: a name, not a module)."""
    parts = module.split(".")
    if len(parts) > 1 and any((PACKAGE / parts[1]).with_suffix(s).exists() for s in (".py", "")):
        return ".".join(parts[:2])
    return "pinball_env"


@pytest.mark.parametrize("floor", sorted(FLOORS))
def test_each_floor_imports_only_from_below_it(floor):
    own = floor.removesuffix(".py")
    allowed = {
        "pinball_env" if name == "__init__" else f"pinball_env.{name}"
        for name in (own, *FLOORS[floor])
    }
    for path in floor_files(floor):
        for module in imported_modules(path):
            assert module.split(".")[0] != "agents", f"{path.relative_to(PACKAGE)} imports agents"
            if module.startswith("pinball_env.") or module == "pinball_env":
                top = package_module(module)
                assert top in allowed, f"{path.relative_to(PACKAGE)} imports {module}"


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


AGENTS = Path(__file__).resolve().parent.parent / "agents"
# The commands on top of agents/: nothing below them imports them.
AGENT_COMMANDS = {"train", "rllib", "distill", "evaluate", "generalization", "benchmark"}


def agent_imports(path: Path) -> set[str]:
    """The modules of ``agents`` that ``path`` imports, at module level or inside a function."""
    found = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Import):
            names = [alias.name for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            assert node.level == 0, f"{path.name}: a relative import hides where it points"
            names = [node.module]
            if node.module == "agents":  # from agents import train: the module agents.train
                names = [f"agents.{alias.name}" for alias in node.names]
        else:
            continue
        found.update(name.split(".")[1] for name in names if name.startswith("agents."))
    return found


def test_the_agents_modules_import_one_way():
    graph: dict[str, set[str]] = {}  # a module, or a package's modules as one (benchmark/)
    for path in AGENTS.rglob("*.py"):
        module = path.relative_to(AGENTS).parts[0].removesuffix(".py")
        graph.setdefault(module, set()).update(agent_imports(path) - {module})
    assert {"train", "rllib", "evaluate", "generalization", "policy", "config"} <= set(graph)
    for module, imports in graph.items():
        assert imports <= set(graph), f"agents.{module} imports a module agents lacks: {imports}"
        if module not in AGENT_COMMANDS:
            below = imports & AGENT_COMMANDS
            assert not below, f"agents.{module} imports the command(s) {sorted(below)} above it"
    # No cycle: take off, again and again, the modules that import none of those left.
    left = dict(graph)
    while left:
        leaves = [module for module, imports in left.items() if not imports & set(left)]
        assert leaves, f"an import cycle among agents.{{{', '.join(sorted(left))}}}"
        for module in leaves:
            del left[module]


# --- sizes -----------------------------------------------------------------------------------

MAX_FUNCTION_LINES = 60  # def line to last line
MAX_MODULE_LINES = 600
# The compiled hot loops, each one function by design: numba counts a reference to every array
# a compiled function receives (or takes out of a record), so helpers taking arrays in the pass
# loop cost more than the physics. Each says so in its source (see below).
HOT_LOOPS = {
    "pinball_env/physics/step.py::step_ball",
    "pinball_env/physics/multiball.py::step_balls",
    "pinball_env/game/play.py::play_step",
}


def functions_of(path: Path) -> dict[str, ast.FunctionDef | ast.AsyncFunctionDef]:
    """Every function of a module by ``path::qualified.name`` (methods ``Class.method``, nested
    ones ``outer.inner``); of two with one name (a conditional def), the longer."""
    module = path.relative_to(PACKAGE.parent).as_posix()
    found: dict[str, ast.FunctionDef | ast.AsyncFunctionDef] = {}

    def visit(node: ast.AST, prefix: str) -> None:
        for child in ast.iter_child_nodes(node):
            if isinstance(child, ast.FunctionDef | ast.AsyncFunctionDef | ast.ClassDef):
                name = f"{prefix}{child.name}"
                if not isinstance(child, ast.ClassDef):
                    key = f"{module}::{name}"
                    if key not in found or length(child) > length(found[key]):
                        found[key] = child
                visit(child, f"{name}.")
            else:
                visit(child, prefix)

    visit(ast.parse(path.read_text(encoding="utf-8")), "")
    return found


def length(node: ast.AST) -> int:
    return node.end_lineno - node.lineno + 1


def sizes() -> dict[str, tuple[int, int]]:
    """Each module and function of the package by name: its length in lines, and its limit."""
    found = {}
    for path in sorted(PACKAGE.rglob("*.py")):
        lines = len(path.read_text(encoding="utf-8").splitlines())
        found[path.relative_to(PACKAGE.parent).as_posix()] = (lines, MAX_MODULE_LINES)
        found.update(
            (name, (length(node), MAX_FUNCTION_LINES)) for name, node in functions_of(path).items()
        )
    return found


def test_no_function_or_module_is_over_its_limit():
    over = {
        name: f"{name}: {length} lines (limit {limit})"
        for name, (length, limit) in sizes().items()
        if length > limit and name not in HOT_LOOPS
    }
    assert not over, "over the house limits:\n" + "\n".join(sorted(over.values()))


@pytest.mark.parametrize("name", sorted(HOT_LOOPS))
def test_each_hot_loop_says_why_it_is_one_function(name):
    path = PACKAGE.parent / name.split("::")[0]
    node = functions_of(path)[name]
    first = min([node.lineno, *(d.lineno for d in node.decorator_list)])
    lines = path.read_text(encoding="utf-8").splitlines()
    comments = []  # the comment lines right above the decorators
    while first - 2 - len(comments) >= 0 and lines[first - 2 - len(comments)].startswith("#"):
        comments.append(lines[first - 2 - len(comments)])
    said = " ".join(" ".join([*comments, ast.get_docstring(node) or ""]).split())
    assert "numba counts a reference" in said, (
        f"{name}: say why it is one function (numba counts a reference to every array ...)"
    )
