"""Errors of :mod:`robot.analysis` and the argument checks that raise them.

Every bad argument raises :class:`AnalysisError` (a :class:`robot.errors.RobotError`
and a :class:`ValueError`) with a message naming the parameter, its value and the
valid range, e.g. ``period=-1.0 must be positive (valid range (0, inf))``.
"""

from __future__ import annotations

import math

import numpy as np

from robot.errors import RobotError


class AnalysisError(RobotError, ValueError):
    """An analysis got an invalid argument (shape, range, time grid) or could not proceed."""


class UnknownAnalysisError(AnalysisError, KeyError):
    """No analysis is registered under the requested name."""

    def __str__(self) -> str:  # KeyError would quote the message
        return str(self.args[0]) if self.args else ""


def require_finite(name: str, value: float) -> float:
    """``float(value)``; AnalysisError unless it is a finite real number."""
    try:
        x = float(value)
    except (TypeError, ValueError):
        raise AnalysisError(f"{name}={value!r} must be a real number") from None
    if not math.isfinite(x):
        raise AnalysisError(f"{name}={value!r} must be finite")
    return x


def require_positive(name: str, value: float) -> float:
    """``float(value)``; AnalysisError unless ``0 < value < inf``."""
    x = require_finite(name, value)
    if not x > 0.0:
        raise AnalysisError(f"{name}={value!r} must be positive (valid range (0, inf))")
    return x


def require_non_negative(name: str, value: float) -> float:
    """``float(value)``; AnalysisError unless ``0 <= value < inf``."""
    x = require_finite(name, value)
    if not x >= 0.0:
        raise AnalysisError(f"{name}={value!r} must be non-negative (valid range [0, inf))")
    return x


def require_count(name: str, value: int, minimum: int = 1) -> int:
    """``int(value)``; AnalysisError unless it is an integer ``>= minimum``."""
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
        raise AnalysisError(f"{name}={value!r} must be an integer (valid range [{minimum}, inf))")
    if value < minimum:
        raise AnalysisError(f"{name}={value!r} is outside the valid range [{minimum}, inf)")
    return int(value)


def require_array(name: str, value, ndim: int | tuple[int, ...], *, length: int | None = None) -> np.ndarray:
    """``value`` as a finite float64 array with ``ndim`` dimensions (and first axis ``length``)."""
    try:
        a = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError):
        raise AnalysisError(f"{name} must be an array of real numbers, got {type(value).__name__}") from None
    allowed = (ndim,) if isinstance(ndim, int) else ndim
    if a.ndim not in allowed:
        what = "be one-dimensional (n,)" if allowed == (1,) else f"have {' or '.join(map(str, allowed))} dimension(s)"
        raise AnalysisError(f"{name} must {what}, got shape {a.shape}")
    if length is not None and a.shape[0] != length:
        raise AnalysisError(f"{name} has {a.shape[0]} rows but the time grid has {length} points")
    if not np.all(np.isfinite(a)):
        bad = int(np.flatnonzero(~np.isfinite(a.reshape(a.shape[0], -1)).any(axis=1))[0]) if a.ndim else 0
        raise AnalysisError(f"{name} has a non-finite value (first at row {bad})")
    return a
