"""Table files: a table read from a YAML file (strictly: a key repeated in a mapping is an
error, and the file's size is bounded) and written to one (a whole file). A file may give a
``base`` (a table) and only what differs from it: :func:`merge_description` lays it over the
base's. Tables by name (the built-in ones, files, the generated ones) and the resolution of a
file's base are in :mod:`~pinball_env.table.names`.
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import yaml

from pinball_env.table.fields import TableError, Where, clipped
from pinball_env.table.model import Table
from pinball_env.table.schema import table_from_dict
from pinball_env.table.serialise import table_to_dict

SUFFIXES = (".yaml", ".yml")
# Largest table file read [bytes]: the classic table is 8 KB.
MAX_TABLE_BYTES = 1 << 20
# Most values merged along a file's bases (the classic tables merge a few hundred).
MAX_MERGED_VALUES = 100_000


class _StrictLoader(yaml.SafeLoader):
    """Safe YAML loader that rejects a key repeated in one mapping (instead of keeping the last)."""

    def construct_mapping(self, node: yaml.MappingNode, deep: bool = False) -> dict[Any, Any]:
        self.flatten_mapping(node)  # resolve YAML merge keys ("<<") first
        seen: list[Any] = []
        for key_node, _ in node.value:
            key = self.construct_object(key_node, deep=deep)
            if key in seen:
                raise yaml.constructor.ConstructorError(
                    None, None, f"duplicate key {key!r}", key_node.start_mark
                )
            seen.append(key)
        return super().construct_mapping(node, deep=deep)


def read_yaml(path: Path) -> Any:
    """The YAML in the file at ``path`` (an existing file), read strictly; every problem a
    :class:`TableError` that names the file."""
    source = str(path)
    try:
        size = path.stat().st_size
        if size > MAX_TABLE_BYTES:
            raise TableError(
                f"{source}: {size} bytes, a table file may have at most {MAX_TABLE_BYTES}"
            )
        return yaml.load(path.read_text(encoding="utf-8"), Loader=_StrictLoader)
    except yaml.YAMLError as exc:
        raise TableError(f"{source}: invalid YAML: {clipped(str(exc))}") from exc
    except (OSError, UnicodeDecodeError) as exc:
        raise TableError(f"{source}: cannot read the file: {clipped(str(exc))}") from exc
    except RecursionError:
        raise TableError(f"{source}: invalid YAML: nested too deeply") from None


def build_table(description: Any, source: str) -> Table:
    """The table a file's ``description`` (its base resolved) gives, validated."""
    try:
        return table_from_dict(description, source)
    except RecursionError:
        raise TableError(f"{source}: a value is nested too deeply") from None


def merge_description(base: Any, change: Any, loc: Where, budget: list[int] | None = None) -> Any:
    """A derived file's value ``change`` (at ``loc``) laid over its base's value ``base``, as
    JSON Merge Patch (RFC 7386) lays a patch, but strict: two mappings merge key by key (a key
    the change lacks keeps the base's value, a key it sets to null is removed, any other key is
    merged in turn); any other value, a list included, replaces the base's. (A list of elements
    is ordered, and their ids follow its order: a version restates a list it changes.) Nothing
    is modified; ``budget`` bounds the work (YAML aliases can make a small file a huge tree)."""
    budget = [MAX_MERGED_VALUES] if budget is None else budget
    budget[0] -= 1
    if budget[0] < 0:
        loc.fail(f"more than {MAX_MERGED_VALUES} values to merge with the base")
    if not isinstance(base, Mapping) or not isinstance(change, Mapping):
        return change
    merged = dict(base)
    for key, value in change.items():
        if value is None and key not in merged:
            loc.key(str(key)).fail("null removes a key of the base, which has none here")
        if value is None:
            del merged[key]
        elif key in merged:
            merged[key] = merge_description(merged[key], value, loc.key(str(key)), budget)
        else:
            merged[key] = value
    return merged


def dump_table(table: Table, path: str | os.PathLike[str]) -> Path:
    """Write ``table`` as a YAML file that :func:`~pinball_env.table.names.load_table` reads
    back as the same table: a whole file, whatever base the table was read with."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    text = yaml.safe_dump(table_to_dict(table), sort_keys=False, default_flow_style=None)
    path.write_text(text, encoding="utf-8")
    return path
