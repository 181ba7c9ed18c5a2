"""Checks of the arguments at the package's public boundaries: one home for all of them.

Each check returns the value in its checked form (a float, an int, a float array) or raises
``InvalidInputError`` with a message that names the argument, says what it got and what is
valid. The estimator's own input checks (``estimation/inputs.py``), the command line
(``cli/args.py``) and the other public functions use these.
"""

from __future__ import annotations

import math
from numbers import Integral, Real

import numpy as np

from comgrasp_pin.errors import InvalidInputError


def _range_text(low: float | None, high: float | None, low_open: bool, high_open: bool) -> str:
    parts = []
    if low is not None:
        parts.append(f"{'>' if low_open else '>='} {low}")
    if high is not None:
        parts.append(f"{'<' if high_open else '<='} {high}")
    return " and ".join(parts)


def number(
    value: object,
    name: str,
    low: float | None = None,
    high: float | None = None,
    low_open: bool = False,
    high_open: bool = False,
) -> float:
    """``value`` as a finite float within [low, high] (open ends where asked).

    Raises:
        InvalidInputError: not a real number (strings and bools are not), not finite, or out
            of range.
    """
    if isinstance(value, bool) or not isinstance(value, (Real, np.floating, np.integer)):
        raise InvalidInputError(f"{name} must be a real number, got {value!r}")
    x = float(value)
    if not math.isfinite(x):
        raise InvalidInputError(f"{name} must be finite, got {x}")
    too_low = low is not None and (x <= low if low_open else x < low)
    too_high = high is not None and (x >= high if high_open else x > high)
    if too_low or too_high:
        raise InvalidInputError(
            f"{name} must be {_range_text(low, high, low_open, high_open)}, got {x}"
        )
    return x


def integer(value: object, name: str, low: int | None = None, high: int | None = None) -> int:
    """``value`` as an int within [low, high].

    Raises:
        InvalidInputError: not an integer (floats, strings and bools are not) or out of range.
    """
    if isinstance(value, bool) or not isinstance(value, (Integral, np.integer)):
        raise InvalidInputError(f"{name} must be an integer, got {value!r}")
    k = int(value)
    if (low is not None and k < low) or (high is not None and k > high):
        limits = _range_text(low, high, False, False)
        raise InvalidInputError(f"{name} must be an integer {limits}, got {k}")
    return k


def optional_number(value: object, name: str, **limits) -> float | None:
    """None stays None; anything else goes through ``number``."""
    return None if value is None else number(value, name, **limits)


REAL_KINDS = "iuf"
"""NumPy dtype kinds taken as real numbers: signed and unsigned integers, floats. Complex
(its imaginary part would be dropped), boolean, string, object and time arrays are refused
rather than converted."""


def real_array(value: object, name: str) -> np.ndarray:
    """``value`` as a float array, refusing what is not real numbers.

    A float64 array is returned as it is (no copy); integers and other floats are converted.

    Raises:
        InvalidInputError: naming ``name``: complex, boolean, string, object or ragged input.
    """
    if type(value) is np.ndarray and value.dtype == np.float64:  # the usual case, fast
        return value
    try:
        a = np.asarray(value)
    except (TypeError, ValueError):
        raise InvalidInputError(f"{name} is not a numeric array (ragged?)") from None
    if a.dtype.kind not in REAL_KINDS:
        raise InvalidInputError(
            f"{name} is not a numeric array of real numbers (integers or floats), got dtype "
            f"{a.dtype}: complex, boolean, string and object values are not converted"
        )
    return a.astype(float, copy=False)


def finite_array(value: object, name: str, shape: tuple[int, ...]) -> np.ndarray:
    """``value`` as a float array of exactly ``shape``, every entry finite (a copy).

    Raises:
        InvalidInputError: not numeric, another shape, NaN or inf.
    """
    a = np.array(real_array(value, name), dtype=float)  # a copy
    if a.shape != shape:
        raise InvalidInputError(f"{name} must have shape {shape}, got {a.shape}")
    if not np.all(np.isfinite(a)):
        raise InvalidInputError(f"{name} must be finite, got {a}")
    return a


def choice(value: object, name: str, valid: tuple[str, ...]) -> str:
    """``value`` if it is one of ``valid``.

    Raises:
        InvalidInputError: naming the valid options.
    """
    if not isinstance(value, str) or value not in valid:
        raise InvalidInputError(f"{name} must be one of {valid}, got {value!r}")
    return value
