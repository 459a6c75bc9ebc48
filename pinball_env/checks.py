"""The checks of option values, written once: each raises a ValueError in the one format of an
option's error, ``NAME must be WHAT, got VALUE`` (:func:`must_be`).

What counts as an integer, a real number, a flag or a finite number is the table's
(:mod:`pinball_env.table.fields`): an option and a table field take the same values. The table
phrases its own errors with the file and the element's path (``TableError``); a config names the
file and the key in ``NAME`` (``"run.yaml: env.num_envs:"``).
"""

from collections.abc import Sequence
from typing import NoReturn

from pinball_env.table.fields import Real, is_finite, is_flag, is_int, is_real

__all__ = [
    "choice",
    "finite",
    "flag",
    "fraction",
    "integer",
    "is_finite",
    "is_flag",
    "is_int",
    "is_real",
    "must_be",
    "optional_integer",
]


def must_be(name: str, what: str, value: object) -> NoReturn:
    """Raise the ValueError ``NAME must be WHAT, got VALUE``."""
    raise ValueError(f"{name} must be {what}, got {value!r}")


def integer(name: str, value: object, low: int | None = None, high: int | None = None) -> int:
    """``value`` as an int, if it is an integer in [low, high] (either bound may be None)."""
    if not is_int(value) or not _within(value, low, high):
        must_be(name, f"an integer {_range(low, high)}".rstrip(), value)
    return int(value)


def optional_integer(name: str, value: object, low: int | None = None) -> int | None:
    """None, or an integer >= ``low``."""
    if value is None:
        return None
    if not is_int(value) or not _within(value, low, None):
        must_be(name, f"None or an integer {_range(low, None)}".rstrip(), value)
    return int(value)


def finite(name: str, value: object) -> float:
    """``value`` as a float, if it is a finite real number."""
    if not is_finite(value):
        must_be(name, "a finite number", value)
    return float(value)


def fraction(name: str, value: object) -> float:
    """``value`` as a float, if it is a number in [0, 1)."""
    if not is_real(value) or not 0.0 <= value < 1.0:
        must_be(name, "a number in [0, 1)", value)
    return float(value)


def flag(name: str, value: object) -> bool:
    """``value`` as a bool, if it is True or False (Python's or NumPy's)."""
    if not is_flag(value):
        must_be(name, "True or False", value)
    return bool(value)


def choice(name: str, value: object, choices: Sequence[object]) -> None:
    """Nothing, if ``value`` is one of ``choices``."""
    if value not in choices:
        must_be(name, f"one of {', '.join(map(repr, choices))}", value)


def _within(value: Real, low: int | None, high: int | None) -> bool:
    return bool((low is None or value >= low) and (high is None or value <= high))


def _range(low: int | None, high: int | None) -> str:
    if low is not None and high is not None:
        return f"from {low} to {high}"
    if low is not None:
        return f">= {low}"
    return f"<= {high}" if high is not None else ""
