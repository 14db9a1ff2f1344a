"""The integrators on offer: scipy's ``OdeSolver`` family plus fixed-step schemes.

Every method is an ``scipy.integrate.OdeSolver`` subclass, stepped one accepted
step at a time by :mod:`robot.simulation` (so each step is recorded, checked and
scanned for events). Fixed-step schemes take ``first_step`` as their step size.

``rejected_steps(solver, accepted)`` recovers the number of rejected steps where
the method allows it: an explicit Runge-Kutta attempt costs ``n_stages``
right-hand-side calls (FSAL), so ``rejected = (nfev - start - n_stages accepted) /
n_stages``; implicit methods do not expose it (reported as -1).
"""

from __future__ import annotations

import numpy as np
from scipy.integrate import BDF, DOP853, LSODA, RK23, RK45, OdeSolver, Radau
from scipy.integrate._ivp.base import DenseOutput


class _HermiteDense(DenseOutput):
    """Cubic Hermite interpolation between two states (values and derivatives)."""

    def __init__(self, t_old, t, y_old, y, f_old, f):
        super().__init__(t_old, t)
        self.h = t - t_old
        self.y_old, self.y, self.f_old, self.f = y_old, y, f_old, f

    def _call_impl(self, t):
        s = (np.asarray(t) - self.t_old) / self.h
        h00 = 2 * s**3 - 3 * s**2 + 1
        h10 = s**3 - 2 * s**2 + s
        h01 = -2 * s**3 + 3 * s**2
        h11 = s**3 - s**2
        if np.ndim(s) == 0:
            return h00 * self.y_old + h10 * self.h * self.f_old + h01 * self.y + h11 * self.h * self.f
        return (
            np.outer(self.y_old, h00) + np.outer(self.f_old, h10 * self.h) + np.outer(self.y, h01) + np.outer(self.f, h11 * self.h)
        )


class FixedStepRK4(OdeSolver):
    """Classical fourth-order Runge-Kutta with a constant step ``first_step``.

    No error control: the step size is the user's choice, which is exactly what
    the stability studies vary (``scripts/work_precision.py``).
    """

    n_stages = 4

    def __init__(self, fun, t0, y0, t_bound, first_step=None, vectorized=False, **extraneous):
        super().__init__(fun, t0, y0, t_bound, vectorized)
        if first_step is None or not first_step > 0:
            raise ValueError(f"fixed-step method needs first_step > 0 (the step size), got {first_step!r}")
        self.h_fixed = float(first_step)
        self.f = self.fun(self.t, self.y)
        self.y_old = None
        self.f_old = None

    def _step_impl(self):
        h = min(self.h_fixed, abs(self.t_bound - self.t))
        t, y, f = self.t, self.y, self.f
        k1 = f
        k2 = self.fun(t + h / 2, y + h / 2 * k1)
        k3 = self.fun(t + h / 2, y + h / 2 * k2)
        k4 = self.fun(t + h, y + h * k3)
        self.y_old, self.f_old, self.t_old_value = y, f, t
        self.y = y + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        self.t = t + h
        self.f = self.fun(self.t, self.y)
        self.h_previous = h
        return True, None

    def _dense_output_impl(self):
        return _HermiteDense(self.t_old_value, self.t, self.y_old, self.y, self.f_old, self.f)

    @property
    def step_size(self):
        return self.h_fixed


METHODS: dict[str, type[OdeSolver]] = {
    "RK23": RK23,
    "RK45": RK45,
    "DOP853": DOP853,
    "Radau": Radau,
    "BDF": BDF,
    "LSODA": LSODA,
    "RK4": FixedStepRK4,
}

FIXED_STEP_METHODS = {"RK4"}

#: right-hand-side calls per attempted step (explicit RK, FSAL); None: not countable
STAGES = {"RK23": 3, "RK45": 6, "DOP853": 12, "RK4": 4}


def make_solver(method: str, fun, t0: float, y0: np.ndarray, t_bound: float, rtol: float, atol: float, max_step: float, first_step: float | None) -> OdeSolver:
    """Instantiate the named method (see :data:`METHODS`)."""
    if method not in METHODS:
        raise ValueError(f"integrator method={method!r} is not on offer; choose one of {', '.join(METHODS)}")
    cls = METHODS[method]
    if method in FIXED_STEP_METHODS:
        return cls(fun, t0, y0, t_bound, first_step=first_step)
    kwargs = dict(rtol=rtol, atol=atol, max_step=max_step)
    if first_step is not None:
        kwargs["first_step"] = min(first_step, abs(t_bound - t0))
    return cls(fun, t0, y0, t_bound, **kwargs)
