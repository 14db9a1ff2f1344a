"""The base of the package's own one-step solvers and dense outputs (no scipy import).

It mirrors the public contract of ``scipy.integrate.OdeSolver`` and
``scipy.integrate._ivp.base.DenseOutput`` (scipy 1.x, ``scipy/integrate/_ivp/base.py``),
so the step loop (:mod:`robot.integration.event_loop`, :mod:`robot.integration.force_peaks`)
drives scipy's methods (RK45, Radau, BDF, LSODA, ...) and the package's own
(RK4, generalized-alpha, CVODE: :mod:`robot.integration.solvers`) the same way,
by duck typing. The loop uses, of a solver:

* ``t``, ``y``: the state at the end of the last accepted step;
* ``t_old``: the start of that step (None before the first);
* ``t_bound``, ``direction`` (+1 or -1), ``n`` (state size);
* ``status``: ``"running"``, ``"finished"`` (``t`` reached ``t_bound``) or ``"failed"``;
* ``step() -> message``: one accepted step (the message says why it failed);
* ``dense_output()``: the interpolant over the last accepted step, callable on a
  time or a 1-D array of times (``(n,)`` or ``(n, k)`` values);
* ``step_size``: the size of the last accepted step (None before the first);
* ``nfev``, ``njev``, ``nlu``: right-hand sides, Jacobians, LU factorisations.

A subclass implements ``_step_impl() -> (success, message)`` and
``_dense_output_impl()`` and calls ``self.fun(t, y)`` for its right-hand sides
(counted in ``nfev``), exactly as for scipy. Kept out on purpose: complex
states (``support_complex``) and the warning about extraneous arguments
(the package's solvers take and ignore the options of the other methods).

Importing scipy's base would import ``scipy.integrate`` and with it
``scipy.optimize``, ``scipy.sparse`` and ``scipy.special`` (0.15-0.3 s): a run
with the package's own methods needs none of them (issue 16, import time).
"""

from __future__ import annotations

from typing import Callable

import numpy as np


def check_arguments(fun: Callable, y0) -> tuple[Callable, np.ndarray]:
    """``(fun returning a float array, y0 as a finite 1-D float array)``; ValueError otherwise (as scipy's)."""
    y0 = np.asarray(y0)
    if np.issubdtype(y0.dtype, np.complexfloating):
        raise ValueError("`y0` is complex, but the chosen solver does not support integration in a complex domain.")
    y0 = y0.astype(float, copy=False)
    if y0.ndim != 1:
        raise ValueError("`y0` must be 1-dimensional.")
    if not np.isfinite(y0).all():
        raise ValueError("All components of the initial state `y0` must be finite.")

    def fun_wrapped(t, y):
        return np.asarray(fun(t, y), dtype=float)

    return fun_wrapped, y0


class OdeSolver:
    """One-step ODE solver for ``dy/dt = fun(t, y)`` from ``(t0, y0)`` towards ``t_bound`` (scipy's contract)."""

    TOO_SMALL_STEP = "Required step size is less than spacing between numbers."

    def __init__(self, fun: Callable, t0: float, y0, t_bound: float, vectorized: bool = False):
        self.t_old = None
        self.t = t0
        self._fun, self.y = check_arguments(fun, y0)
        self.t_bound = t_bound
        self.vectorized = vectorized
        if vectorized:
            def fun_single(t, y):
                return self._fun(t, y[:, None]).ravel()

            fun_vectorized = self._fun
        else:
            fun_single = self._fun

            def fun_vectorized(t, y):
                f = np.empty_like(y)
                for i, yi in enumerate(y.T):
                    f[:, i] = self._fun(t, yi)
                return f

        def counted(t, y):
            self.nfev += 1
            return self.fun_single(t, y)

        self.fun = counted
        self.fun_single = fun_single  # not counted (finite-difference Jacobians, as in scipy)
        self.fun_vectorized = fun_vectorized
        self.direction = np.sign(t_bound - t0) if t_bound != t0 else 1
        self.n = self.y.size
        self.status = "running"
        self.nfev = 0
        self.njev = 0
        self.nlu = 0

    @property
    def step_size(self) -> float | None:
        """Size of the last accepted step (None before the first)."""
        return None if self.t_old is None else abs(self.t - self.t_old)

    def step(self) -> str | None:
        """One accepted step; returns the failure's message (``status == "failed"``) or None."""
        if self.status != "running":
            raise RuntimeError("Attempt to step on a failed or finished solver.")
        if self.n == 0 or self.t == self.t_bound:
            # nothing to integrate: an empty state or an empty interval
            self.t_old = self.t
            self.t = self.t_bound
            self.status = "finished"
            return None
        t = self.t
        success, message = self._step_impl()
        if not success:
            self.status = "failed"
        else:
            self.t_old = t
            if self.direction * (self.t - self.t_bound) >= 0:
                self.status = "finished"
        return message

    def dense_output(self) -> "DenseOutput":
        """The interpolant over the last accepted step."""
        if self.t_old is None:
            raise RuntimeError("Dense output is available after a successful step was made.")
        if self.n == 0 or self.t == self.t_old:
            return ConstantDenseOutput(self.t_old, self.t, self.y)
        return self._dense_output_impl()

    def _step_impl(self) -> tuple[bool, str | None]:
        raise NotImplementedError(f"{type(self).__qualname__} does not implement _step_impl() -> (success, message): the solver cannot step")

    def _dense_output_impl(self) -> "DenseOutput":
        raise NotImplementedError(
            f"{type(self).__qualname__} does not implement _dense_output_impl() -> DenseOutput: the step loop needs the interpolant "
            "over a step to locate contact onsets, penetration and force peaks and output times (e.g. return a HermiteDense)"
        )


class DenseOutput:
    """Interpolant over one step ``[t_old, t]`` (``t_min``, ``t_max``: its ends in increasing order)."""

    def __init__(self, t_old: float, t: float):
        self.t_old = t_old
        self.t = t
        self.t_min = min(t, t_old)
        self.t_max = max(t, t_old)

    def __call__(self, t):
        """The state at ``t`` (a time: shape ``(n,)``; a 1-D array of k times: ``(n, k)``)."""
        if isinstance(t, float):  # the step loop's calls (output times, event and peak location): no array layer
            return self._call_impl(t)
        t = np.asarray(t)
        if t.ndim > 1:
            raise ValueError("`t` must be a float or a 1-D array.")
        return self._call_impl(t)

    def _call_impl(self, t: float | np.ndarray) -> np.ndarray:
        """The state at ``t``: a float or a 0-d array (one time), or a 1-D array of times."""
        raise NotImplementedError


class ConstantDenseOutput(DenseOutput):
    """The constant state of an empty step (equal ends or an empty state)."""

    def __init__(self, t_old: float, t: float, value: np.ndarray):
        super().__init__(t_old, t)
        self.value = value

    def _call_impl(self, t: float | np.ndarray) -> np.ndarray:
        if isinstance(t, float) or t.ndim == 0:
            return self.value
        out = np.empty((self.value.shape[0], t.shape[0]))
        out[:] = self.value[:, None]
        return out
