"""Table files: a table read from a YAML file (strictly: a key repeated in a mapping is an
error, and the file's size is bounded) and written to one. Tables by name (the built-in ones,
files, the generated ones) are in :mod:`~pinball_env.table.names`.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

import yaml

from pinball_env.table.fields import TableError, clipped
from pinball_env.table.model import Table
from pinball_env.table.schema import table_from_dict
from pinball_env.table.serialise import table_to_dict

SUFFIXES = (".yaml", ".yml")
# Largest table file read [bytes]: the classic table is 8 KB.
MAX_TABLE_BYTES = 1 << 20


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


def read_table(path: Path) -> Table:
    """The table in the YAML file at ``path`` (an existing file), validated; every problem a
    :class:`TableError` that names the file."""
    source = str(path)
    try:
        size = path.stat().st_size
        if size > MAX_TABLE_BYTES:
            raise TableError(
                f"{source}: {size} bytes, a table file may have at most {MAX_TABLE_BYTES}"
            )
        data = yaml.load(path.read_text(encoding="utf-8"), Loader=_StrictLoader)
    except yaml.YAMLError as exc:
        raise TableError(f"{source}: invalid YAML: {clipped(str(exc))}") from exc
    except (OSError, UnicodeDecodeError) as exc:
        raise TableError(f"{source}: cannot read the file: {clipped(str(exc))}") from exc
    except RecursionError:
        raise TableError(f"{source}: invalid YAML: nested too deeply") from None
    try:
        return table_from_dict(data, source)
    except RecursionError:
        raise TableError(f"{source}: a value is nested too deeply") from None


def dump_table(table: Table, path: str | os.PathLike[str]) -> Path:
    """Write ``table`` as a YAML file that :func:`~pinball_env.table.names.load_table` reads
    back as the same table."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    text = yaml.safe_dump(table_to_dict(table), sort_keys=False, default_flow_style=None)
    path.write_text(text, encoding="utf-8")
    return path
