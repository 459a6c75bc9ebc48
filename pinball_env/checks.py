"""The checks of option values, written once: each raises a ValueError that names the option,
says what it takes and shows what it got."""

import math
import numbers
from collections.abc import Sequence

import numpy as np


def is_int(value: object) -> bool:
    """An integer (Python's or NumPy's), not a bool."""
    return isinstance(value, (int, np.integer)) and not isinstance(value, (bool, np.bool_))


def is_real(value: object) -> bool:
    """A real number (an int or a float, Python's or NumPy's), not a bool."""
    return isinstance(value, numbers.Real) and not isinstance(value, (bool, np.bool_))


def integer(name: str, value: object, low: int | None = None, high: int | None = None) -> int:
    """``value`` as an int, if it is an integer in [low, high] (either bound may be None)."""
    below = low is not None and value < low
    if not is_int(value) or below or (high is not None and value > high):
        raise ValueError(f"{name} must be an integer {_range(low, high)}, got {value!r}")
    return int(value)


def optional_integer(name: str, value: object, low: int | None = None) -> int | None:
    """None, or an integer >= ``low``."""
    if value is None:
        return None
    if not is_int(value) or (low is not None and value < low):
        raise ValueError(f"{name} must be None or an integer {_range(low, None)}, got {value!r}")
    return int(value)


def finite(name: str, value: object) -> float:
    """``value`` as a float, if it is a finite real number."""
    if not is_real(value) or not math.isfinite(value):
        raise ValueError(f"{name} must be a finite number, got {value!r}")
    return float(value)


def fraction(name: str, value: object) -> float:
    """``value`` as a float, if it is a number in [0, 1)."""
    if not is_real(value) or not 0.0 <= value < 1.0:
        raise ValueError(f"{name} must be a number in [0, 1), got {value!r}")
    return float(value)


def flag(name: str, value: object) -> bool:
    """``value`` as a bool, if it is True or False (Python's or NumPy's)."""
    if not isinstance(value, (bool, np.bool_)):
        raise ValueError(f"{name} must be True or False, got {value!r}")
    return bool(value)


def choice(name: str, value: object, choices: Sequence[object]) -> None:
    """Nothing, if ``value`` is one of ``choices``."""
    if value not in choices:
        raise ValueError(f"{name} must be one of {', '.join(map(repr, choices))}, got {value!r}")


def _range(low: int | None, high: int | None) -> str:
    if low is not None and high is not None:
        return f"from {low} to {high}"
    if low is not None:
        return f">= {low}"
    return f"<= {high}" if high is not None else ""
