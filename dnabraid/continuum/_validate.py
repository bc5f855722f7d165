"""Argument checks shared by the continuum solvers: one behaviour, one wording.

Every check raises :class:`ValueError` whose message starts with the argument's name and
says what was expected and what came, e.g. ``"n must be an integer >= 1, got 2.5"``.

Real numbers are Python ``int``/``float``, numpy integer/floating scalars and 0-d numeric
arrays; ``bool`` (also ``numpy.bool_``), strings, ``None`` and sequences are refused even
where ``float()`` would accept them.
"""

from __future__ import annotations

import math
import numbers

import numpy as np

from ..errors import UserError

__all__ = ["check_finite", "check_n", "check_nonnegative", "check_positive"]



class InputError(UserError):
    """A bad argument of a continuum problem (the CLI reports it as a user error)."""


def _is_bool(value) -> bool:
    return isinstance(value, (bool, np.bool_))


def _real(name: str, value, expected: str) -> float:
    """``value`` as a float if it is a real number (not a bool), else ValueError."""
    if isinstance(value, np.ndarray) and value.ndim == 0 and value.dtype.kind in "iuf":
        value = value[()]
    if _is_bool(value) or not isinstance(value, numbers.Real):
        raise InputError(f"{name} must be {expected}, got {value!r}")
    return float(value)


def check_finite(name: str, value) -> float:
    """``value`` as a float; it must be a finite real number."""
    expected = "a finite number"
    v = _real(name, value, expected)
    if not math.isfinite(v):
        raise InputError(f"{name} must be {expected}, got {value!r}")
    return v


def check_positive(name: str, value) -> float:
    """``value`` as a float; it must be a finite real number > 0."""
    expected = "a positive finite number"
    v = _real(name, value, expected)
    if not (math.isfinite(v) and v > 0.0):
        raise InputError(f"{name} must be {expected}, got {value!r}")
    return v


def check_nonnegative(name: str, value) -> float:
    """``value`` as a float; it must be a finite real number >= 0."""
    expected = "a finite number >= 0"
    v = _real(name, value, expected)
    if not (math.isfinite(v) and v >= 0.0):
        raise InputError(f"{name} must be {expected}, got {value!r}")
    return v


def check_n(n, *, minimum: int = 1, name: str = "n", what: str = "") -> int:
    """``n`` as an int; it must be an integer ``>= minimum``.

    Python and numpy integers are accepted, and floats with an integral value (``3.0``);
    ``bool``, non-integral or non-finite floats, strings and values below ``minimum`` are
    refused. ``what`` (optional) says what ``n`` counts, for the message.
    """
    expected = f"an integer >= {minimum}" + (f" ({what})" if what else "")
    if isinstance(n, np.ndarray) and n.ndim == 0 and n.dtype.kind in "iuf":
        n = n[()]
    if _is_bool(n) or not isinstance(n, numbers.Real):
        raise InputError(f"{name} must be {expected}, got {n!r}")
    if isinstance(n, numbers.Integral):
        k = int(n)
    else:
        f = float(n)
        if not (math.isfinite(f) and f == math.floor(f)):
            raise InputError(f"{name} must be {expected}, got {n!r}")
        k = int(f)
    if k < minimum:
        raise InputError(f"{name} must be {expected}, got {n!r}")
    return k
