"""Scalar functions of time: prescribed joint motions and time-varying forces.

Each function gives its value, rate and acceleration at t (``evaluate``), the
rate and acceleration exact for the analytic forms:

* :class:`Constant`: ``f = c``;
* :class:`Polynomial`: ``f = sum_k c_k t^k`` (``constant_rate`` is ``[offset, rate]``);
* :class:`Harmonic`: ``f = offset + amplitude sin(2 pi frequency t + phase)``;
* :class:`Fourier`: a :class:`robot.model.trajectory.FourierCoordinate` at a fixed
  ``omega = 2 pi / period`` (``offset + rate t + sum_i A_i sin(h_i omega t + phi_i)``);
* :class:`Tabulated`: samples ``(x_i, y_i)`` joined by a cubic spline
  (``scipy.interpolate.CubicSpline``, not-a-knot ends: C2, error
  ``O(h^4)`` in the value, ``O(h^3)`` in the rate, ``O(h^2)`` in the
  acceleration for a smooth sampled function, Hall and Meyer, J. Approx.
  Theory 16 (1976) 105-122). Outside ``[x_0, x_n]`` it continues as the straight
  line tangent at the end (C1, zero second derivative): a spring table
  extends with its end stiffness, a motion with its end rate. The same class
  serves force-length tables (x a length) and time tables.

:func:`read_table_csv` reads a two-column CSV file (x, y; an optional header
line; ``#`` comments).
"""

from __future__ import annotations

import csv
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Protocol, Sequence

import numpy as np


class TimeFunction(Protocol):
    """``evaluate(t) -> (value, rate, acceleration)``."""

    def evaluate(self, t: float) -> tuple[float, float, float]: ...


@dataclass(frozen=True)
class Constant:
    value: float

    def evaluate(self, t: float) -> tuple[float, float, float]:
        return self.value, 0.0, 0.0


@dataclass(frozen=True)
class Polynomial:
    """``sum_k coefficients[k] t^k`` (Horner's scheme for the value and both derivatives)."""

    coefficients: tuple[float, ...]

    def evaluate(self, t: float) -> tuple[float, float, float]:
        value = rate = acceleration = 0.0
        for c in reversed(self.coefficients):
            acceleration = acceleration * t + 2.0 * rate
            rate = rate * t + value
            value = value * t + c
        return value, rate, acceleration


@dataclass(frozen=True)
class Harmonic:
    """``offset + amplitude sin(2 pi frequency t + phase)`` (frequency in Hz, phase in rad)."""

    amplitude: float
    frequency: float
    phase: float = 0.0
    offset: float = 0.0

    def evaluate(self, t: float) -> tuple[float, float, float]:
        omega = 2.0 * math.pi * self.frequency
        s, c = math.sin(omega * t + self.phase), math.cos(omega * t + self.phase)
        return self.offset + self.amplitude * s, self.amplitude * omega * c, -self.amplitude * omega * omega * s


@dataclass(frozen=True)
class Fourier:
    """A Fourier coordinate (``robot.model.trajectory.FourierCoordinate``) at ``omega = 2 pi / period``."""

    coordinate: object
    omega: float

    def evaluate(self, t: float) -> tuple[float, float, float]:
        return self.coordinate.evaluate(t, self.omega)


@dataclass(frozen=True, eq=False)
class Tabulated:
    """A cubic spline through ``(x_i, y_i)``, continued by its end tangents (module docstring).

    ``x`` strictly increasing, at least 2 points (2 or 3 points: scipy's spline is
    then the interpolating line or parabola).
    """

    x: np.ndarray
    y: np.ndarray
    _spline: object = field(init=False, repr=False)

    def __post_init__(self):
        from scipy.interpolate import CubicSpline  # scipy.interpolate costs ~0.2 s to import: only when a table is used

        x, y = np.asarray(self.x, dtype=float), np.asarray(self.y, dtype=float)
        if x.ndim != 1 or x.shape != y.shape or x.shape[0] < 2:
            raise ValueError(f"a table needs two 1-D arrays of the same length >= 2; got shapes {x.shape} and {y.shape}")
        if not np.all(np.diff(x) > 0):
            raise ValueError("the table's abscissae must be strictly increasing")
        object.__setattr__(self, "x", x)
        object.__setattr__(self, "y", y)
        object.__setattr__(self, "_spline", CubicSpline(x, y))

    def evaluate(self, t: float) -> tuple[float, float, float]:
        x0, x1 = self.x[0], self.x[-1]
        if t < x0 or t > x1:  # the tangent line at the nearer end
            end = x0 if t < x0 else x1
            value, slope = float(self._spline(end)), float(self._spline(end, 1))
            return value + slope * (t - end), slope, 0.0
        return float(self._spline(t)), float(self._spline(t, 1)), float(self._spline(t, 2))

    def integral(self, x: float) -> float:
        """``int_{x_0}^{x} y(s) ds`` of the continued curve (a spring's potential energy from a force table)."""
        x0, x1 = self.x[0], self.x[-1]
        inner = min(max(x, x0), x1)
        area = float(self._spline.integrate(x0, inner))
        if x != inner:  # the tangent line beyond the end
            value, slope, _ = self.evaluate(inner)
            d = x - inner
            area += value * d + 0.5 * slope * d * d
        return area


def read_table_csv(path: Path) -> tuple[np.ndarray, np.ndarray]:
    """Two columns ``x, y`` of a CSV file; a first line that is not numeric is a header; ``#`` starts a comment.

    Raises ``FileNotFoundError`` for a missing file and ``ValueError`` naming the
    line for a malformed one.
    """
    rows: list[tuple[float, float]] = []
    with open(path, newline="", encoding="utf-8") as handle:
        for number, row in enumerate(csv.reader(handle), start=1):
            cells = [c.strip() for c in row]
            if not cells or not cells[0] or cells[0].startswith("#"):
                continue
            try:
                values = [float(c) for c in cells if c]
            except ValueError:
                if not rows and number == 1:
                    continue  # a header
                raise ValueError(f"line {number}: {row!r} is not two numbers") from None
            if len(values) != 2:
                raise ValueError(f"line {number}: {row!r} has {len(values)} columns; expected 2 (time, value)")
            rows.append((values[0], values[1]))
    if len(rows) < 2:
        raise ValueError(f"{len(rows)} data rows; a table needs at least 2")
    table = np.array(rows)
    return table[:, 0], table[:, 1]


def first_non_increasing(x: Sequence[float]) -> int | None:
    """Index i of the first ``x[i] <= x[i - 1]``, or None if ``x`` is strictly increasing."""
    for i in range(1, len(x)):
        if not x[i] > x[i - 1]:
            return i
    return None
