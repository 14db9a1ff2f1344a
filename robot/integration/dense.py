"""Cubic Hermite dense output: the state between two accepted step ends.

For a step ``[t_old, t]`` of size ``h`` with end states ``y_old, y`` and
derivatives ``f_old, f``, in ``s = (t' - t_old) / h``:

    y(t') = (2s^3 - 3s^2 + 1) y_old + (s^3 - 2s^2 + s) h f_old + (-2s^3 + 3s^2) y + (s^3 - s^2) h f

exact for cubic polynomials, error ``h^4 max|y''''| / 384`` (Hairer, Norsett and
Wanner, *Solving ODEs I*, II.6). The dense output of the fixed-step methods
(:mod:`robot.integration.solvers`) and, for methods whose step cannot be redone
alone, of the force-peak search's earlier steps (:mod:`robot.integration.force_peaks`).
:class:`RestepDense`: the fixed-step methods' states inside a step as steps of
the method from the step's start (the contact onsets' dense output).
"""

from __future__ import annotations

from typing import Callable

import numpy as np
from robot.integration.solver_base import DenseOutput


class HermiteDense(DenseOutput):
    """Cubic Hermite interpolation between two states (values and derivatives), a dense output with scipy's contract."""

    def __init__(self, t_old: float, t: float, y_old: np.ndarray, f_old: np.ndarray, y: np.ndarray, f: np.ndarray):
        super().__init__(t_old, t)
        self.h = t - t_old
        self.y_old, self.y, self.f_old, self.f = y_old, y, f_old, f

    def _call_impl(self, t):
        if isinstance(t, float) or t.ndim == 0:
            # in Python floats: the same IEEE operations (pow included) as numpy's scalars, at a fraction of the cost
            h = float(self.h)
            h00, h10, h01, h11 = _basis((float(t) - float(self.t_old)) / h)
            return h00 * self.y_old + h10 * h * self.f_old + h01 * self.y + h11 * h * self.f
        h00, h10, h01, h11 = _basis((t - self.t_old) / self.h)
        return np.outer(self.y_old, h00) + np.outer(self.f_old, h10 * self.h) + np.outer(self.y, h01) + np.outer(self.f, h11 * self.h)


def _basis(s):
    """The cubic Hermite basis functions (module docstring) at ``s`` (a float or an array)."""
    s2, s3 = s**2, s**3
    return 2 * s3 - 3 * s2 + 1, s3 - 2 * s2 + s, -2 * s3 + 3 * s2, s3 - s2


class RestepDense(DenseOutput):
    """The states inside a fixed-step method's step ``[t_old, t]`` as steps of the method itself from the step's start.

    ``restep(h)`` is the method's step of size ``h`` from the step's start state
    ``y_old`` (at ``t_old``), so the state at ``t_old + h`` is as accurate as the
    method's steps (local error ``O(h^(p+1))`` for a method of order p) and uses
    the right-hand side up to ``t_old + h`` only. An interpolant of the step's
    ends (:class:`HermiteDense`) carries what the end and the late stages met: a
    fixed-step method accepts a step whose late stages cross into a contact,
    where an adaptive method's error control would reject it, so the step loop
    locates contact onsets and takes the restart state on this one
    (:meth:`robot.integration.event_loop.EventDrivenIntegrator.onset_dense_output`).
    Each time costs one step of the method.
    """

    def __init__(self, t_old: float, t: float, y_old: np.ndarray, restep: Callable[[float], np.ndarray]):
        super().__init__(t_old, t)
        self.y_old, self.restep = y_old, restep

    def _call_impl(self, t):
        if isinstance(t, float) or t.ndim == 0:
            h = float(t) - float(self.t_old)
            return self.y_old if h == 0.0 else self.restep(h)
        return np.column_stack([self._call_impl(float(tt)) for tt in t])
