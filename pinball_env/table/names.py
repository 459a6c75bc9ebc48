"""Tables by name: the built-in tables shipped with the package, table files by path (a file's
``base`` resolved: :func:`table_description`), and the generated tables.

The built-in tables are package data in ``pinball_env/table/tables/`` (``classic.yaml``, the
default, its versions ``classic_v1.yaml`` to ``classic_v3.yaml``, each written as the one before
plus what changed, and ``box.yaml``), found through :mod:`importlib.resources` so that they work
from a wheel as well as from a checkout. Generated tables are named ``PREFIX:...``; the package that
makes them registers a function per prefix (:func:`register_generator`: ``pinball_env.procgen``
registers ``procgen`` and ``procgen-hard``, each also with ``+targets``, when imported, as
importing ``pinball_env`` does), so that :func:`load_any_table` takes their names while this
package imports no generator.
"""

from __future__ import annotations

import os
import re
from collections.abc import Callable, Mapping
from importlib import resources
from pathlib import Path
from typing import Any

from pinball_env.table.fields import TableError, Where, clipped, describe
from pinball_env.table.files import SUFFIXES, build_table, merge_description, read_yaml
from pinball_env.table.model import Table


def builtin_tables_dir() -> Path:
    """The folder of the built-in table files (inside the installed package)."""
    return Path(str(resources.files("pinball_env.table") / "tables"))


# The folder of the built-in tables, as a constant for scripts (``TABLES_DIR / "classic.yaml"``).
TABLES_DIR = builtin_tables_dir()
# Built-in tables that are physics test rigs, not games: they load, but have no plunger,
# flippers or drain, so no env plays them.
TEST_TABLES = ("box",)
TABLE_KINDS = ("game", "test", "all")


def available_tables(kind: str = "game") -> list[str]:
    """Names of the built-in tables: those a game is played on (``"game"``, the default), the
    physics test rigs (``"test"``: :data:`TEST_TABLES`), or ``"all"``."""
    if kind not in TABLE_KINDS:
        raise ValueError(f"kind must be one of {', '.join(TABLE_KINDS)}, got {kind!r}")
    folder = builtin_tables_dir()
    names = (
        sorted(p.stem for p in folder.iterdir() if p.suffix in SUFFIXES) if folder.is_dir() else []
    )
    if kind == "all":
        return names
    return [name for name in names if (name in TEST_TABLES) == (kind == "test")]


def load_table(name_or_path: str | os.PathLike[str]) -> Table:
    """Load a table from a .yaml/.yml path, or a built-in one by bare name (``"classic"``).
    (:func:`load_any_table` also takes generated tables' names.)"""
    if not isinstance(name_or_path, (str, os.PathLike)):
        raise TypeError(f"a table is a name or a path, got {type(name_or_path).__name__}")
    path = _table_file(name_or_path)
    return build_table(table_description(path), str(path))


def table_description(name_or_path: str | os.PathLike[str]) -> Any:
    """The description a table file gives (a built-in table's bare name, or a path), with its
    ``base`` resolved: a file that names a ``base`` (a built-in table's bare name, or a path,
    relative to the file's folder) gives its base's description (resolved the same way) with
    the file's other keys laid over it (:func:`~pinball_env.table.files.merge_description`).
    An unknown base, or a ring of bases, is a :class:`TableError` naming the file and its key."""
    return _description(_table_file(name_or_path), ())


def _description(path: Path, derived: tuple[Path, ...]) -> Any:
    """The description of the file at ``path``, which the files ``derived`` (in order) are
    derived from."""
    data = read_yaml(path)
    if not isinstance(data, Mapping) or "base" not in data:
        return data
    loc = Where(str(path)).key("base")
    name = data["base"]
    if not isinstance(name, str) or not name:
        loc.fail(f"expected a table's name or path, got {describe(name)}")
    given = Path(name)
    builtin = given.suffix not in SUFFIXES and len(given.parts) == 1
    try:
        base = _table_file(name if builtin else path.parent / given)
    except TableError as error:
        loc.fail(str(error))
    chain = (*derived, path.resolve())
    if base.resolve() in chain:
        ring = " -> ".join(p.name for p in (*chain[chain.index(base.resolve()) :], base))
        loc.fail(f"a ring of bases: {ring}")
    change = {key: value for key, value in data.items() if key != "base"}
    try:
        return merge_description(_description(base, chain), change, Where(str(path)))
    except RecursionError:
        raise TableError(f"{path}: a value is nested too deeply to merge") from None


def _table_file(name_or_path: str | os.PathLike[str]) -> Path:
    """The file of a built-in table's bare name, or the path given, if it is a file."""
    path = Path(name_or_path)
    shown = clipped(str(name_or_path), 120)
    try:
        if path.suffix not in SUFFIXES and len(path.parts) == 1:
            candidates = [builtin_tables_dir() / f"{path.name}{suffix}" for suffix in SUFFIXES]
            builtin = next((p for p in candidates if p.is_file()), None)
            if builtin is None:
                available = ", ".join(available_tables()) or "none"
                rigs = ", ".join(available_tables("test"))
                raise TableError(
                    f"unknown table {shown!r} (available: {available}; test rigs: {rigs})"
                )
            path = builtin
        found = path.is_file()
    except OSError as exc:  # a name too long for the file system, say
        raise TableError(f"{shown}: cannot read the file: {clipped(str(exc), 120)}") from None
    if not found:
        raise TableError(f"{clipped(str(path), 120)}: table file not found")
    return path


# A generated table's name: a prefix, a colon, and what the prefix's generator reads.
GENERATED_NAME = re.compile(r"([A-Za-z][\w+-]*):(.*)", re.DOTALL)
# Generated tables by prefix: the function that makes the table of a name (see the docstring).
_GENERATORS: dict[str, Callable[[str], Table]] = {}


def register_generator(prefix: str, make: Callable[[str], Table]) -> None:
    """Let :func:`load_any_table` take the names ``"PREFIX:..."``: ``make(name)`` returns the
    table of such a name (or raises ``TableError``). Registering a prefix again replaces it."""
    if not GENERATED_NAME.fullmatch(f"{prefix}:"):
        raise ValueError(f"a generated table's prefix is a letter then letters, digits, _, - "
                         f"or +, got {prefix!r}")  # fmt: skip
    _GENERATORS[prefix] = make


def generated_prefixes() -> tuple[str, ...]:
    """The prefixes of generated tables' names that :func:`load_any_table` takes now."""
    return tuple(sorted(_GENERATORS))


def load_any_table(name_or_path: str | os.PathLike[str]) -> Table:
    """:func:`load_table`, and the generated tables by name (``"procgen:SEED"``,
    ``"procgen-hard:SEED"``, any registered prefix): what the envs, the plot tool and the
    training configs take. A name ``PREFIX:...`` whose prefix no generator registered (not a
    path to a file) is a ``TableError`` naming those that are."""
    if isinstance(name_or_path, str) and (match := GENERATED_NAME.fullmatch(name_or_path)):
        make = _GENERATORS.get(match[1])
        if make is not None:
            return make(name_or_path)
        path = Path(name_or_path)
        if path.suffix not in SUFFIXES and len(path.parts) == 1:
            registered = ", ".join(generated_prefixes()) or "none"
            raise TableError(
                f"unknown table {clipped(name_or_path, 120)!r}: no generator of tables is "
                f"registered for the prefix {match[1]!r} (registered: {registered})"
            )
    return load_table(name_or_path)
