"""Exceptions of :mod:`clearance_contact` and the checks that raise them.

Every invalid physical parameter raises :class:`ContactParameterError` with a
message that names the parameter, its value and the valid range, e.g.::

    restitution=1.2 is outside the valid range (0, 1]

The ``require_*`` helpers are used by every constructor of the package (and by
the revolute joint), so that all messages share one format.
"""

from __future__ import annotations

import math
import numbers

import numpy as np

__all__ = [
    "ClearanceMechanismsError",
    "ContactError",
    "ContactParameterError",
    "real_number",
    "require_unregistered",
    "require_finite",
    "require_positive",
    "require_non_negative",
    "require_in_range",
    "state_array",
    "nonfinite_state_message",
]


class ClearanceMechanismsError(Exception):
    """Root of every error raised by this project (``clearance_contact`` and ``robot``).

    ``key`` and ``value``: the offending input (a parameter name or a scene key
    path, and its value) when the error is about one, else ``None``; the message
    names them too. ``robot`` re-exports this class as ``robot.Error``.
    """

    def __init__(self, message: str = "", *, key: str | None = None, value=None):
        super().__init__(message)
        self.key = key
        self.value = value


class ContactError(ClearanceMechanismsError):
    """Base class of every error raised by :mod:`clearance_contact`."""


class ContactLawError(ContactError):
    """A user-defined law (e.g. a friction law) broke its contract during a run: it raised, or returned a value
    outside its valid range. Not a pose the law refuses: an integrator must stop on it, not shrink its step."""


class ContactParameterError(ContactError, ValueError):
    """A contact parameter (geometry, material, force law) is invalid.

    Subclass of :class:`ValueError` so that generic callers can catch it too.
    """


def real_number(value: object) -> float | None:
    """``value`` as a float if it is one real number (a Python or numpy scalar, a 0-d numeric array), else None.

    Booleans and strings are not numbers here: a user's law returning ``True`` or ``"0.2"`` is a mistake.
    """
    if isinstance(value, np.ndarray):
        if value.shape != () or value.dtype.kind not in "fiu":
            return None
        value = value.item()
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, numbers.Real):
        return None
    return float(value)


def _origin(definition: object) -> str:
    """Where a function or class is defined: ``module.qualname`` (the same for a reloaded module's definition)."""
    name = getattr(definition, "__qualname__", None) or repr(definition)
    return f"{getattr(definition, '__module__', None) or '?'}.{name}"


def require_unregistered(what: str, name: str, held: object | None, new: object, registered, key: str) -> None:
    """ContactParameterError if ``name`` is registered to another definition than ``new``.

    The same definition again (same module and qualified name: a module reloaded, a notebook cell run twice)
    may register again; a shipped entry cannot be replaced by another.
    """
    if held is None or _origin(held) == _origin(new):
        return
    raise ContactParameterError(
        f"{what} {name!r} is already registered by {_origin(held)}; choose another name (registered: {', '.join(registered)})",
        key=key, value=name,
    )  # fmt: skip


def require_finite(name: str, value: float) -> float:
    """Return ``float(value)``; raise if it is not a finite real number."""
    try:
        x = float(value)
    except (TypeError, ValueError):
        raise ContactParameterError(f"{name}={value!r} must be a real number", key=name, value=value) from None
    if not math.isfinite(x):
        raise ContactParameterError(f"{name}={value!r} must be finite", key=name, value=value)
    return x


def require_positive(name: str, value: float) -> float:
    """Return ``float(value)``; raise unless ``0 < value < inf``."""
    x = require_finite(name, value)
    if not x > 0.0:
        raise ContactParameterError(f"{name}={value!r} must be positive (valid range (0, inf))", key=name, value=value)
    return x


def require_non_negative(name: str, value: float) -> float:
    """Return ``float(value)``; raise unless ``0 <= value < inf``."""
    x = require_finite(name, value)
    if not x >= 0.0:
        raise ContactParameterError(f"{name}={value!r} must be non-negative (valid range [0, inf))", key=name, value=value)
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
        raise ContactParameterError(f"{name}={value!r} is outside the valid range {interval}", key=name, value=value)
    return x


_FLOAT64 = np.dtype(np.float64)


def state_array(name: str, value, shape: tuple) -> np.ndarray:
    """``value`` as a float64 array of ``shape`` for the compiled kernels, else ValueError.

    A float64 ndarray of the right shape, C or Fortran contiguous and writeable, is
    passed through as is (the layouts the kernel library's exports take, Pinocchio's
    views among them); anything else (strided or read-only arrays, lists) is copied
    into a new C-ordered array, so a call never needs another compiled specialisation.
    """
    if type(value) is np.ndarray and value.dtype is _FLOAT64 and value.shape == shape:
        flags = value.flags
        if (flags.c_contiguous or flags.f_contiguous) and flags.writeable and flags.aligned:
            return value
    a = np.array(value, dtype=np.float64, order="C")
    if a.shape != shape:
        raise ValueError(f"{name} must have shape {shape}, got {a.shape}")
    return a


#: the arguments of a joint's ``evaluate`` (and of its compiled kernel), in order
STATE_NAMES = ("outer_rotation", "outer_position", "outer_twist", "inner_rotation", "inner_position", "inner_twist", "onset_rates")
ROTATION_SHAPE, VECTOR_SHAPE, TWIST_SHAPE = (3, 3), (3,), (6,)


def joint_state(
    outer_rotation, outer_position, outer_twist, inner_rotation, inner_position, inner_twist, onset_rates, n_candidates: int
) -> tuple:
    """The seven arrays of a joint state (:data:`STATE_NAMES`) for a compiled kernel (:func:`state_array` each).

    ValueError for a wrong shape or a value that is not numeric, naming the argument.
    """
    shapes = (ROTATION_SHAPE, VECTOR_SHAPE, TWIST_SHAPE, ROTATION_SHAPE, VECTOR_SHAPE, TWIST_SHAPE, (n_candidates,))
    values = (outer_rotation, outer_position, outer_twist, inner_rotation, inner_position, inner_twist, onset_rates)
    try:
        return tuple(state_array(name, value, shape) for name, value, shape in zip(STATE_NAMES, values, shapes))
    except (ValueError, TypeError) as exc:
        raise ValueError(
            f"expected rotations (3, 3), positions (3,), twists (6,) and onset_rates ({n_candidates},): {exc}"
        ) from None


def nonfinite_state_message(names: tuple, values: tuple) -> str:
    """Message of a ContactError for NaN / inf in a joint state: names the bad arguments."""
    bad = [f"{n}={np.asarray(v).tolist()!r}" for n, v in zip(names, values) if not np.all(np.isfinite(v))]
    return f"non-finite input {', '.join(bad)}: check the poses, velocities and onset rates (NaN or inf)"
