"""Generic field parsing for table descriptions: where a value sits, and the kinds of value a
table file holds (mappings with known keys, lists, names, flags, numbers in a range, pairs,
points in the playfield), each with the one error format of a table; the declarations that
records are parsed by (:func:`record`, :func:`records`, :data:`POINT` and :func:`bound`), which
:mod:`pinball_env.table.reference` reads to document them.

The kinds themselves (:func:`is_int`, :func:`is_real`, :func:`is_flag`, :func:`is_finite`) are
pinball_env's one vocabulary: :mod:`pinball_env.checks` phrases the options' errors over them.

Every parser takes the value and its :class:`Where` and returns the parsed value, or raises
:class:`TableError` naming the source, the path of the element and the problem. Values from a
file are shown shortened (:func:`short`): aliases in YAML can make a small file hold a value whose
full repr is gigabytes.
"""

from __future__ import annotations

import math
import numbers
import reprlib
from collections.abc import Callable, Iterable, Mapping
from dataclasses import MISSING, dataclass, fields
from functools import partial
from typing import Any, NoReturn, TypeGuard

import numpy as np

# Fastest ball a table or a reset may set [m/s]: a real one rarely passes 10 m/s, and the flipper
# contact's work grows with the speed.
MAX_BALL_SPEED = 100.0

# Most points one hit (or one rule's effect) may score.
MAX_SCORE = 1_000_000

_SHORT = reprlib.Repr()
_SHORT.maxstring = _SHORT.maxother = 60
_SHORT.maxlist = _SHORT.maxtuple = _SHORT.maxdict = _SHORT.maxset = 4
_SHORT.maxlevel = 2
_SHORT.maxlong = 40


# What is_real accepts, as the type checker knows it (numbers.Real is not typed for arithmetic).
Real = float | np.integer[Any] | np.floating[Any]


class TableError(ValueError):
    """A table description is invalid or cannot be read."""


def is_int(value: object) -> TypeGuard[int | np.integer[Any]]:
    """An integer (Python's or NumPy's), not a bool."""
    return isinstance(value, numbers.Integral) and not isinstance(value, (bool, np.bool_))


def is_real(value: object) -> TypeGuard[Real]:
    """A real number (an int or a float, Python's or NumPy's), not a bool."""
    return isinstance(value, numbers.Real) and not isinstance(value, (bool, np.bool_))


def is_flag(value: object) -> TypeGuard[bool | np.bool_]:
    """True or False (Python's or NumPy's bool)."""
    return isinstance(value, (bool, np.bool_))


def is_finite(value: object) -> TypeGuard[Real]:
    """A real number that is finite as a float (an int too large for a float is not)."""
    try:
        return is_real(value) and math.isfinite(value)
    except OverflowError:
        return False


def short(value: object) -> str:
    """The repr of ``value`` shortened for a message (long strings, lists, dicts and ints cut)."""
    return _SHORT.repr(value)


def clipped(text: str, most: int = 300) -> str:
    """``text`` cut after ``most`` characters (an OS's or YAML's message, a path)."""
    return text if len(text) <= most else text[:most] + " ..."


@dataclass(frozen=True)
class Where:
    """Where a value sits: the source file and the element path, for error messages."""

    source: str
    path: str = ""

    def key(self, key: str) -> Where:
        key = key if len(key) <= 60 else short(key)
        return Where(self.source, f"{self.path}.{key}" if self.path else key)

    def index(self, i: int, name: object = None) -> Where:
        label = f"{self.path}[{i}]" + (f" {short(name)}" if isinstance(name, str) else "")
        return Where(self.source, label)

    def fail(self, problem: str) -> NoReturn:
        raise TableError(f"{self.source}: {self.path or 'top level'}: {problem}")


Parser = Callable[[Any, Where], Any]


def describe(value: object) -> str:
    """The type and a shortened repr of a value from a file: aliases in YAML can make a small
    file hold a value whose full repr is gigabytes."""
    return f"{type(value).__name__} {short(value)}"


def listing(names: Iterable[str], most: int = 12) -> str:
    """Names for a message, sorted, each shortened, at most ``most`` of them."""
    names = sorted(names)
    shown = [name if len(name) <= 40 else short(name) for name in names[:most]]
    return ", ".join(shown) + (f", ... ({len(names)} in all)" if len(names) > most else "")


def mapping(
    value: object, loc: Where, required: Iterable[str], optional: Iterable[str] = ()
) -> Mapping[str, Any]:
    """Check ``value`` is a mapping with all ``required`` keys and no unknown key."""
    if not isinstance(value, Mapping):
        loc.fail(f"expected a mapping, got {describe(value)}")
    required = list(required)
    allowed = sorted({*required, *optional})
    for key in value:
        if key not in allowed:
            loc.fail(f"unknown key {short(key)} (allowed: {', '.join(allowed)})")
    for key in required:
        if key not in value:
            loc.fail(f"missing required key {key!r}")
    return value


def list_of(value: object, loc: Where, min_len: int = 0, max_len: int | None = None) -> list[Any]:
    """A list (or tuple) of ``min_len`` to ``max_len`` items, as a list."""
    if not isinstance(value, (list, tuple)):
        loc.fail(f"expected a list, got {describe(value)}")
    if min_len == max_len and len(value) != min_len:
        loc.fail(f"expected exactly {min_len} items, got {len(value)}")
    if len(value) < min_len:
        loc.fail(f"expected at least {min_len} items, got {len(value)}")
    if max_len is not None and len(value) > max_len:
        loc.fail(f"expected at most {max_len} items, got {len(value)}")
    return list(value)


def string(value: object, loc: Where) -> str:
    """A non-empty string (a name)."""
    if not isinstance(value, str) or not value:
        loc.fail(f"expected a non-empty string, got {describe(value)}")
    return value


def choice(value: object, loc: Where, options: tuple[str, ...]) -> str:
    """One of ``options``."""
    if value not in options:
        loc.fail(f"expected one of {', '.join(map(repr, options))}, got {describe(value)}")
    return str(value)


def flag(value: object, loc: Where) -> bool:
    """True or false (Python's or NumPy's bool), as a bool."""
    if not is_flag(value):
        loc.fail(f"expected true or false, got {describe(value)}")
    return bool(value)


def number(
    value: object,
    loc: Where,
    low: float | None = None,
    high: float | None = None,
    *,
    open_low: bool = False,
    open_high: bool = False,
    integer: bool = False,
    unit: str = "",
) -> float | int:
    """A finite real (or, with ``integer``, an int) in the given interval. ``unit`` only
    documents the field (the table reference shows it); the messages keep their own wording."""
    if not is_real(value) or (integer and not is_int(value)):  # (an int is a real)
        hint = ""
        if isinstance(value, str) and _parses_as_float(value):
            hint = " (YAML reads exponents without a dot as text: write 1.0e-6, not 1e-6)"
        loc.fail(f"expected {'an integer' if integer else 'a number'}, got {describe(value)}{hint}")
    try:
        finite = math.isfinite(value)
    except OverflowError:  # an integer too large for a float
        loc.fail(f"{short(value)} is out of range (too large)")
    if not finite:
        loc.fail(f"expected a finite number, got {value!r}")
    too_low = low is not None and (value <= low if open_low else value < low)
    too_high = high is not None and (value >= high if open_high else value > high)
    if too_low or too_high:
        if high is None:
            interval = f"{'>' if open_low else '>='} {low:g}"
        else:
            interval = f"{'(' if open_low else '['}{low:g}, {high:g}{')' if open_high else ']'}"
        loc.fail(f"{short(value)} is out of range (must be {interval})")
    return int(value) if integer else float(value)


def _parses_as_float(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


def pair(value: object, loc: Where, item: Parser = number) -> tuple[Any, Any]:
    """An [x, y] pair of finite numbers (or of whatever ``item`` parses); a list, a tuple or a
    1-d numpy array (such as ``info["ball_position"]``)."""
    not_a_vector = isinstance(value, np.ndarray) and value.ndim != 1
    if not isinstance(value, (list, tuple, np.ndarray)) or not_a_vector or len(value) != 2:
        loc.fail(f"expected a pair [x, y], got {describe(value)}")
    return (item(value[0], loc.index(0)), item(value[1], loc.index(1)))


def velocity_pair(value: object, loc: Where) -> tuple[float, float]:
    """A finite [vx, vy] pair no faster than MAX_BALL_SPEED."""
    vx, vy = pair(value, loc)
    if math.hypot(vx, vy) > MAX_BALL_SPEED:
        loc.fail(
            f"speed {math.hypot(vx, vy):.10g} m/s is above {MAX_BALL_SPEED:g} m/s "
            "(no pinball moves that fast)"
        )
    return (vx, vy)


def in_playfield(value: object, loc: Where, width: float, height: float) -> tuple[float, float]:
    """An [x, y] pair inside the playfield (bounds included)."""
    x, y = pair(value, loc)
    if not (0.0 <= x <= width and 0.0 <= y <= height):
        loc.fail(f"point ({x:g}, {y:g}) is outside the playfield [0, {width:g}] x [0, {height:g}]")
    return (x, y)


def point_list(
    value: object, loc: Where, point: Parser, min_len: int, max_len: int | None = None
) -> tuple[tuple[float, float], ...]:
    """A list of points inside the playfield (``point``: :func:`in_playfield` bound to its size)."""
    items = list_of(value, loc, min_len, max_len)
    return tuple(point(p, loc.index(i)) for i, p in enumerate(items))


def name_list(
    value: object, loc: Where, min_len: int = 0, max_len: int | None = None
) -> tuple[str, ...]:
    """A list of ``min_len`` to ``max_len`` names."""
    items = list_of(value, loc, min_len, max_len)
    return tuple(string(item, loc.index(i)) for i, item in enumerate(items))


def record(
    cls: type, value: object, loc: Where, parsers: Mapping[str, Parser], **extra: Any
) -> Any:
    """Build dataclass ``cls`` from a mapping: one parser per key, defaults from ``cls``."""
    required = [f.name for f in fields(cls) if f.name in parsers and f.default is MISSING]
    raw = mapping(value, loc, required, parsers)
    return cls(**{key: parsers[key](raw[key], loc.key(key)) for key in raw}, **extra)


def records(
    cls: type,
    value: object,
    loc: Where,
    parsers: Mapping[str, Parser],
    min_len: int = 0,
    max_len: int | None = None,
) -> tuple[Any, ...]:
    """A list of ``min_len`` to ``max_len`` records ``cls``, each at its path ``[i] 'name'``."""
    items = list_of(value, loc, min_len, max_len)
    return tuple(
        record(cls, item, loc.index(i, name_of(item)), parsers) for i, item in enumerate(items)
    )


# Named as a constant: it is a marker in declarations, never called on a value.
def POINT(value: object, loc: Where) -> NoReturn:
    """A point in the playfield [m]: the marker a declaration puts where the table's ``point``
    parser goes, which :func:`bound` puts in at parse time (the playfield's size is only known
    then)."""
    raise AssertionError(f"{loc.path}: POINT was not bound to the table's point parser")


def bound(parsers: Mapping[str, Parser], point: Parser) -> dict[str, Parser]:
    """``parsers`` with :data:`POINT` replaced by ``point``, also where a partial holds it (as
    ``point=POINT`` or within nested ``parsers``)."""
    return {key: _bind(parser, point) for key, parser in parsers.items()}


def _bind(parser: Any, point: Parser) -> Any:
    if parser is POINT:
        return point
    if isinstance(parser, Mapping):
        return bound(parser, point)
    if isinstance(parser, partial):
        keywords = {key: _bind(value, point) for key, value in parser.keywords.items()}
        if any(keywords[key] is not value for key, value in parser.keywords.items()):
            return partial(parser.func, *parser.args, **keywords)
    return parser


def name_of(item: object) -> object:
    """The ``name`` of a list item, for the path of its errors (None while it is no mapping)."""
    return item.get("name") if isinstance(item, Mapping) else None


# Points one hit or one rule scores, at most MAX_SCORE.
score = partial(number, low=0, high=MAX_SCORE, integer=True)
