"""Exceptions of :mod:`clearance_contact` and the checks that raise them.

Every invalid physical parameter raises :class:`ContactParameterError` with a
message that names the parameter, its value and the valid range, e.g.::

    restitution=1.2 is outside the valid range (0, 1]

The ``require_*`` helpers are used by every constructor of the package (and by
the revolute joint), so that all messages share one format.
"""

from __future__ import annotations

import math

__all__ = [
    "ContactError",
    "ContactParameterError",
    "require_finite",
    "require_positive",
    "require_non_negative",
    "require_in_range",
]


class ContactError(Exception):
    """Base class of every error raised by :mod:`clearance_contact`."""


class ContactParameterError(ContactError, ValueError):
    """A contact parameter (geometry, material, force law) is invalid.

    Subclass of :class:`ValueError` so that generic callers can catch it too.
    """


def require_finite(name: str, value: float) -> float:
    """Return ``float(value)``; raise if it is not a finite real number."""
    try:
        x = float(value)
    except (TypeError, ValueError):
        raise ContactParameterError(f"{name}={value!r} must be a real number") from None
    if not math.isfinite(x):
        raise ContactParameterError(f"{name}={value!r} must be finite")
    return x


def require_positive(name: str, value: float) -> float:
    """Return ``float(value)``; raise unless ``0 < value < inf``."""
    x = require_finite(name, value)
    if not x > 0.0:
        raise ContactParameterError(f"{name}={value!r} must be positive (valid range (0, inf))")
    return x


def require_non_negative(name: str, value: float) -> float:
    """Return ``float(value)``; raise unless ``0 <= value < inf``."""
    x = require_finite(name, value)
    if not x >= 0.0:
        raise ContactParameterError(f"{name}={value!r} must be non-negative (valid range [0, inf))")
    return x


def require_in_range(
    name: str,
    value: float,
    low: float,
    high: float,
    *,
    low_inclusive: bool = True,
    high_inclusive: bool = True,
) -> float:
    """Return ``float(value)``; raise unless it lies in the interval [low, high].

    ``low_inclusive`` / ``high_inclusive`` select closed or open ends; the message
    prints the interval in the usual notation, e.g. ``(0, 1]``.
    """
    x = require_finite(name, value)
    above = x >= low if low_inclusive else x > low
    below = x <= high if high_inclusive else x < high
    if not (above and below):
        interval = f"{'[' if low_inclusive else '('}{low:g}, {high:g}{']' if high_inclusive else ')'}"
        raise ContactParameterError(f"{name}={value!r} is outside the valid range {interval}")
    return x
