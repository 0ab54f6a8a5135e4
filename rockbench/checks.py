"""Strict checks of scenario values, shared by the scenario classes and the file reader.

A string, boolean, list or table is never coerced into a number (``width = true`` or
``width = "0.5"`` is an error, not 1 m or 0.5 m), and every message is one line that names
the field and says what was expected and what was found.
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Collection, Mapping
from typing import Any

import numpy as np

from rockbench.errors import ScenarioError

__all__ = ["describe", "is_number", "number", "integer", "text", "table", "no_unknown",
           "number_array", "length", "coordinate", "MAX_LENGTH"]

#: Largest length accepted (m): no structure that rocks as a rigid body is larger (the
#: tallest masonry structures stand about 150 m), and a 1 m block typed in millimetres
#: lands above it.
MAX_LENGTH = 500.0


def describe(value: Any) -> str:
    """A short one-line description of a value for error messages."""
    if isinstance(value, bool):
        return f"{str(value).lower()} (a boolean)"
    if isinstance(value, str):
        r = repr(value)
        return f"{r if len(r) <= 40 else r[:36] + '...' + r[0]} (a string)"
    if isinstance(value, Mapping):
        return "a table"
    if isinstance(value, (list, tuple)):
        return f"a list of {len(value)} item{'s' if len(value) != 1 else ''}"
    if isinstance(value, numbers.Integral):
        n = int(value)
        return str(n) if abs(n) < 10**20 else "an integer of 20 digits or more"
    if isinstance(value, numbers.Real):
        return repr(float(value))
    return f"a {type(value).__name__}"


def is_number(value: Any) -> bool:
    """True for a real number (int, float, NumPy scalar), False for booleans and all else."""
    t = type(value)
    if t is float or t is int:  # the common case, without the ABC check
        return True
    return isinstance(value, numbers.Real) and not isinstance(value, (bool, np.bool_))


def _float(value: Any) -> float:
    """``value`` as a float, NaN if it is not a number or overflows one."""
    if type(value) is float:
        return value
    if not is_number(value):
        return math.nan
    try:
        return float(value)
    except OverflowError:
        return math.nan


def number(value: Any, what: str, *, low: float | None = None, strict: bool = True,
           high: float | None = None, unit: str = "") -> float:
    """A finite real number, optionally in a range, as a float.

    Parameters
    ----------
    value : Any
        The value to check.
    what : str
        Name of the field for the message (e.g. ``"block width"``).
    low, high : float, optional
        Bounds; ``low`` is exclusive when ``strict``, ``high`` inclusive.
    strict : bool
        Whether ``low`` itself is excluded.
    unit : str
        Unit shown in the message.

    Raises
    ------
    ScenarioError
        Not a number (booleans included), not finite, or out of range.
    """
    v = _float(value)
    ok = math.isfinite(v) and (low is None or (v > low if strict else v >= low)) and (
        high is None or v <= high)
    if not ok:
        rng = ""
        if low is not None:
            rng += f" {'>' if strict else '>='} {low:g}"
        if high is not None:
            rng += f"{' and' if low is not None else ''} <= {high:g}"
        raise ScenarioError(f"{what} must be a finite number{rng}{f' ({unit})' if unit else ''}, "
                            f"got {describe(value)}")
    return v


def length(value: Any, what: str, *, low: float = 0.0, strict: bool = True) -> float:
    """A size in metres, above ``low`` and at most :data:`MAX_LENGTH`.

    Raises
    ------
    ScenarioError
        Not a number, not finite, not above ``low``, or larger than any rigid structure.
    """
    v = number(value, what, low=low, strict=strict, unit="m")
    if v > MAX_LENGTH:
        raise ScenarioError(f"{what} must be at most {MAX_LENGTH:g} m (lengths are in metres; "
                            f"no structure that rocks as a rigid body is larger), got "
                            f"{describe(value)}")
    return v


def coordinate(value: Any, what: str) -> float:
    """A position in metres, within :data:`MAX_LENGTH` of the origin.

    Raises
    ------
    ScenarioError
        Not a number, not finite, or farther than any rigid structure reaches.
    """
    v = number(value, what, unit="m")
    if abs(v) > MAX_LENGTH:
        raise ScenarioError(f"{what} must be within {MAX_LENGTH:g} m of the origin (lengths "
                            f"are in metres), got {describe(value)}")
    return v


def integer(value: Any, what: str, *, low: int = 1) -> Any:
    """An integral number ≥ ``low`` (``2`` or ``2.0``), returned unchanged."""
    v = _float(value)
    if not (math.isfinite(v) and v.is_integer() and v >= low):
        raise ScenarioError(f"{what} must be an integer >= {low}, got {describe(value)}")
    return value


def text(value: Any, what: str) -> str:
    """A string, kept as is."""
    if not isinstance(value, str):
        raise ScenarioError(f"{what} must be a string, got {describe(value)}")
    return value


def table(value: Any, what: str) -> dict[str, Any]:
    """A TOML table (mapping), as a dict copy."""
    if not isinstance(value, Mapping):
        raise ScenarioError(f"{what} must be a table, got {describe(value)}")
    return dict(value)


def no_unknown(data: Mapping[str, Any], allowed: Collection[str], where: str) -> None:
    """Refuse keys of ``data`` outside ``allowed``, listing the allowed ones."""
    unknown = sorted(set(data) - set(allowed))
    if unknown:
        raise ScenarioError(
            f"unknown key{'s' if len(unknown) > 1 else ''} {', '.join(map(repr, unknown))} in "
            f"{where}; allowed: {', '.join(sorted(allowed)) or '(none)'}"
        )


def number_array(value: Any, what: str) -> np.ndarray:
    """A one-dimensional array of real numbers (finiteness is the caller's check)."""
    if isinstance(value, np.ndarray) and value.dtype.kind in "iuf":
        return np.asarray(value, float).reshape(-1)
    if not isinstance(value, (list, tuple, np.ndarray)):
        raise ScenarioError(f"{what} must be a list of numbers, got {describe(value)}")
    for i, v in enumerate(value):
        if not is_number(v):
            raise ScenarioError(f"{what} must be a list of numbers; item {i + 1} is "
                                f"{describe(v)}")
    with np.errstate(over="ignore"):
        return np.asarray([_float(v) for v in value], float).reshape(-1)
