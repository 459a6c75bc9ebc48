"""Pinball tables as validated data.

- ``parts.py``: the table's parts (frozen dataclasses: its elements and sections);
- ``kinds.py``: the element kinds' registry (key, class, fields, element ids, drawing), which
  the parsing, the writing back, the element ids, the renderer and the web page read;
- ``model.py``: ``Table``, the validated table, and ``Table.pack()``, the kernel's arrays;
- ``rules.py``: the rules as data (``RuleSet``: lights, counters, timers, triggers, effects);
- ``schema.py``: ``table_from_dict``, the table schema's top level, over its parts:
  ``fields.py`` (the kinds of value and ``TableError``), ``elements.py``, ``cabinet.py``,
  ``rules_schema.py`` (the ``rules`` section) and ``geometry.py`` (the checks that tie places
  together, ``check_ball_state``); ``serialise.py``: ``table_to_dict``;
- ``files.py``: a table file read and written (``dump_table``), and how a file derived from a
  ``base`` is laid over it (``merge_description``);
- ``names.py``: tables by name: the built-in tables (``tables/*.yaml``, package data), files
  (``load_table``; ``table_description``, a file's description with its ``base`` resolved) and
  generated tables (``load_any_table``; generators such as
  ``pinball_env.procgen`` register their names' prefixes with ``register_generator``);
- ``reachable.py``: the free space a ball from the plunger can get to (checks reset positions).
- ``reference.py``: the reference of the table files (``schema_fields``, ``rule_keys``,
  ``schema_limits``), read from the schema's declarations for the documentation.
"""

from pinball_env.table.fields import MAX_BALL_SPEED, TableError
from pinball_env.table.files import dump_table
from pinball_env.table.geometry import check_ball_state
from pinball_env.table.model import Table
from pinball_env.table.names import (
    TABLES_DIR,
    TEST_TABLES,
    available_tables,
    builtin_tables_dir,
    generated_prefixes,
    load_any_table,
    load_table,
    register_generator,
    table_description,
)
from pinball_env.table.parts import (
    BUTTONS,
    Ball,
    Cabinet,
    Flipper,
    Material,
    Plunger,
    Post,
    Sensor,
    Simulation,
    SkillShot,
    Tilt,
    Wall,
    enclosure,
)
from pinball_env.table.schema import table_from_dict
from pinball_env.table.serialise import table_sha256, table_to_dict

__all__ = [
    "BUTTONS",
    "MAX_BALL_SPEED",
    "TABLES_DIR",
    "TEST_TABLES",
    "Ball",
    "Cabinet",
    "Flipper",
    "Material",
    "Plunger",
    "Post",
    "Sensor",
    "Simulation",
    "SkillShot",
    "Table",
    "TableError",
    "Tilt",
    "Wall",
    "available_tables",
    "builtin_tables_dir",
    "check_ball_state",
    "dump_table",
    "enclosure",
    "generated_prefixes",
    "load_any_table",
    "load_table",
    "register_generator",
    "table_description",
    "table_from_dict",
    "table_sha256",
    "table_to_dict",
]
