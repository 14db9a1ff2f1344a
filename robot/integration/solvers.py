"""The integrators on offer: scipy's ``OdeSolver`` family, fixed-step schemes and SUNDIALS CVODE.

Every method is a one-step solver with the contract of ``scipy.integrate.OdeSolver``
(scipy's methods are its subclasses, the package's own subclass
:class:`robot.integration.solver_base.OdeSolver`, which mirrors it without importing
scipy), stepped one accepted step at a time by :mod:`robot.integration.simulation`
(so each step is recorded, checked and scanned for events). Fixed-step schemes
take ``first_step`` as their step size.

* ``RK23``, ``RK45``, ``DOP853``, ``Radau``, ``BDF``, ``LSODA``: scipy, variable step;
* ``RK4``: classical Runge-Kutta, fixed step, explicit;
* ``GenAlpha``: the generalized-alpha method of Chung and Hulbert (1993) for
  ``qdd = a(t, q, v)`` in the form of Arnold and Bruls (2007), on the Lie group of
  the configuration (Bruls, Cardona and Arnold 2012: free-flyer quaternions are
  updated by Pinocchio's ``integrate``), spectral radius at infinity
  ``rho_inf = 0.8`` (numerical damping of the high frequencies, second order);
  implicit, fixed step, modified Newton iterations on a finite-difference
  iteration matrix (refreshed when the iterations stall). The multibody codes'
  workhorse (Exudyn, MBDyn, Adams' HHT/GSTIFF family);
* ``Newmark``: the same with ``rho_inf = 1`` (trapezoidal rule / average
  acceleration: no numerical damping);
* ``CVODE_BDF``, ``CVODE_Adams``: SUNDIALS CVODE (variable order, variable step)
  through the ``scikit-sundae`` binding (a dependency of the package).

Each method's traits (fixed step, Jacobian, structure, stages, replay) are its
record in :mod:`robot.integration.methods`; a new method registers there.

The step loop counts rejected steps where the method allows it: an explicit
Runge-Kutta attempt costs ``stages`` right-hand-side calls (FSAL, a registered
trait), so ``rejected = (calls - n_stages accepted) / n_stages``; a solver with an
``n_rejected`` attribute reports it itself; scipy's implicit methods and CVODE do
not expose it (reported as -1).
"""

from __future__ import annotations

import copy
import math
from dataclasses import dataclass
from typing import Callable

import numpy as np

from robot.integration import cvode_direct
from robot.integration import methods as registry
from robot.integration.dense import HermiteDense, RestepDense
from robot.integration.solver_base import DenseOutput, OdeSolver
# the old trait tables, as live views of the registry (robot.integration.methods)
from robot.integration.methods import FIXED_STEP_METHODS, JACOBIAN_METHODS, METHODS, STAGES, STRUCTURED_METHODS  # noqa: F401

EPS = np.finfo(float).eps


def _fixed_step(first_step, t0: float, t_bound: float) -> float:
    """The step size of a fixed-step method; these integrate forward in time only."""
    if first_step is None or not first_step > 0:
        raise ValueError(f"fixed-step method needs first_step > 0 (the step size), got {first_step!r}")
    if not t_bound >= t0:
        raise ValueError(f"fixed-step methods integrate forward: t_bound={t_bound!r} must be >= t0={t0!r}")
    return float(first_step)


def _step_size_setting(solver) -> float:
    """The method's step size (scipy's ``OdeSolver`` gives the last step's; a fixed-step
    method's is its setting, also before the first step and after a shortened last one:
    the step loop restarts it with this size)."""
    return solver.h_fixed


_FIXED_STEP_SIZE = property(_step_size_setting)


class StepFailure(RuntimeError):
    """A solver's failure met outside its own step (a fixed-step method restepping to locate a contact onset),
    with the run's failure cause (``failure_cause``, as a failed step sets it on the solver)."""

    def __init__(self, failure_cause: str, message: str):
        super().__init__(message)
        self.failure_cause = failure_cause


class FixedStepRK4(OdeSolver):
    """Classical fourth-order Runge-Kutta with a constant step ``first_step``.

    No error control: the step size is the user's choice, which is exactly what
    the stability studies vary (``scripts/work_precision.py``).
    """

    n_stages = 4

    def __init__(self, fun, t0, y0, t_bound, first_step=None, vectorized=False, **extraneous):
        super().__init__(fun, t0, y0, t_bound, vectorized)
        self.h_fixed = _fixed_step(first_step, t0, t_bound)
        self.f = self.fun(self.t, self.y)
        self.y_old = None
        self.f_old = None
        self.n_restep_calls = 0  # right-hand sides of the restep dense outputs (not step attempts)

    def _step_impl(self):
        h = min(self.h_fixed, abs(self.t_bound - self.t))
        t, y, f = self.t, self.y, self.f
        self.y_old, self.f_old, self.t_old_value = y, f, t
        self.y = self._rk4_step(t, y, f, h)
        self.t = t + h
        self.f = self.fun(self.t, self.y)
        return True, None

    def _rk4_step(self, t: float, y: np.ndarray, f: np.ndarray, h: float) -> np.ndarray:
        """The state a step ``h`` after ``(t, y)``, ``f = fun(t, y)`` (three right-hand sides)."""
        k2 = self.fun(t + h / 2, y + h / 2 * f)
        k3 = self.fun(t + h / 2, y + h / 2 * k2)
        k4 = self.fun(t + h, y + h * k3)
        return y + h / 6 * (f + 2 * k2 + 2 * k3 + k4)

    def _dense_output_impl(self):
        return HermiteDense(self.t_old_value, self.t, self.y_old, self.f_old, self.y, self.f)

    def restep_dense_output(self) -> RestepDense:
        """The last step's states as RK4 steps from its start (:class:`~robot.integration.dense.RestepDense`)."""
        t_old, y_old, f_old = self.t_old_value, self.y_old, self.f_old

        def restep(h: float) -> np.ndarray:
            calls = self.nfev
            y = self._rk4_step(t_old, y_old, f_old, h)
            self.n_restep_calls += self.nfev - calls
            return y

        return RestepDense(t_old, self.t, y_old, restep)

    step_size = _FIXED_STEP_SIZE


@dataclass(frozen=True)
class SecondOrderStructure:
    """Layout of a state ``y = [q, v, extra]`` with ``dq/dt = G(q) v``, ``dv/dt = a(t, q, v)``.

    ``integrate(q, dq)`` moves q along the tangent vector dq (``pin.integrate``);
    the ``extra`` components (work accumulators) are quadratures of ``f`` itself.
    """

    nq: int
    nv: int
    integrate: Callable[[np.ndarray, np.ndarray], np.ndarray]


class GeneralizedAlpha(OdeSolver):
    """Generalized-alpha (Chung-Hulbert) for ``qdd = a(t, q, v)``, fixed step ``first_step``.

    Arnold-Bruls form with the pseudo-acceleration ``x``::

        q+ = q (+) [h v + h^2 ((1/2 - beta) x + beta x+)]     (Lie-group update)
        v+ = v + h ((1 - gamma) x + gamma x+)
        (1 - alpha_m) x+ + alpha_m x = (1 - alpha_f) a+ + alpha_f a,   a+ = a(t+, q+, v+)

    ``alpha_m = (2 rho - 1)/(rho + 1)``, ``alpha_f = rho/(rho + 1)``,
    ``gamma = 1/2 + alpha_f - alpha_m``, ``beta = (gamma + 1/2)^2 / 4``: second
    order, unconditionally stable for linear problems, high-frequency damping set
    by ``rho = rho_inf`` in [0, 1]. The unknown ``a+`` solves
    ``a+ - a(t+, q+(a+), v+(a+)) = 0`` by modified Newton iterations with the
    iteration matrix ``I - beta' h^2 da/dq - gamma' h da/dv`` (finite differences,
    2 nv right-hand sides, refreshed when an iteration stalls or diverges);
    converged when the implied change of (q, v) is below ``atol + rtol |y|``
    (the tolerances govern only the iterations). The extra components (work
    accumulators) follow the trapezoidal rule. A step whose iterations do not
    converge even with a fresh matrix fails with ``failure_cause`` set.
    """

    max_iterations = 8
    max_refreshes = 3
    #: the registered method's name, in the failure messages (:class:`Newmark` is the same class with rho_inf = 1)
    method_name = "GenAlpha"

    def __init__(
        self,
        fun,
        t0,
        y0,
        t_bound,
        first_step=None,
        rtol=1e-6,
        atol=1e-9,
        structure: SecondOrderStructure | None = None,
        rho_inf: float = 0.8,
        vectorized=False,
        **extraneous,
    ):
        super().__init__(fun, t0, y0, t_bound, vectorized)
        if structure is None:
            raise ValueError(f"the {self.method_name} method (generalized-alpha) needs the second-order structure of the state (nq, nv, integrate)")
        if not 0.0 <= rho_inf <= 1.0:
            raise ValueError(f"rho_inf={rho_inf!r} must be in [0, 1]")
        self.h_fixed = _fixed_step(first_step, t0, t_bound)
        self.structure = structure
        self.rtol, self.atol = float(rtol), float(atol)
        rho = self.rho_inf = float(rho_inf)
        self.alpha_m = (2.0 * rho - 1.0) / (rho + 1.0)
        self.alpha_f = rho / (rho + 1.0)
        self.gamma = 0.5 + self.alpha_f - self.alpha_m
        self.beta = 0.25 * (self.gamma + 0.5) ** 2
        self.f = self.fun(self.t, self.y)
        nq, nv = structure.nq, structure.nv
        self.acc = self.f[nq : nq + nv].copy()  # a_n
        self.pseudo = self.acc.copy()  # x_n (a_0 = x_0)
        self.iteration_matrix_inverse = None
        self.n_newton = 0
        self.n_rejected = 0
        self.failure_cause = None
        self.newton_tol = max(10.0 * EPS / self.rtol, min(0.03, math.sqrt(self.rtol)))
        self.y_old = self.f_old = None
        self.step_start = None  # (t, y, f, a, x) at the start of the last step
        self.n_restep_calls = 0  # right-hand sides of the restep dense outputs (not step attempts)

    step_size = _FIXED_STEP_SIZE

    def _state(self, h: float, acc_new: np.ndarray, extra_rate: np.ndarray):
        """(q+, v+, extra+, x+) implied by a+."""
        nq, nv = self.structure.nq, self.structure.nv
        y = self.y
        x_new = ((1.0 - self.alpha_f) * acc_new + self.alpha_f * self.acc - self.alpha_m * self.pseudo) / (1.0 - self.alpha_m)
        v = y[nq : nq + nv]
        dq = h * v + h * h * ((0.5 - self.beta) * self.pseudo + self.beta * x_new)
        out = np.empty_like(y)
        out[:nq] = self.structure.integrate(y[:nq], dq)
        out[nq : nq + nv] = v + h * ((1.0 - self.gamma) * self.pseudo + self.gamma * x_new)
        out[nq + nv :] = y[nq + nv :] + 0.5 * h * (self.f[nq + nv :] + extra_rate)
        return out, x_new

    def _refresh_matrix(self, t: float, y: np.ndarray, f: np.ndarray, h: float) -> bool:
        """Finite-difference iteration matrix at (t, y); False if it is not usable."""
        nq, nv = self.structure.nq, self.structure.nv
        base = f[nq : nq + nv]
        q, v = y[:nq], y[nq : nq + nv]
        jac_q = np.empty((nv, nv))
        jac_v = np.empty((nv, nv))
        trial = y.copy()
        for j in range(nv):
            step = math.sqrt(EPS) * max(1.0, abs(v[j]))
            trial[nq : nq + nv] = v
            trial[nq + j] = v[j] + step
            jac_v[:, j] = (self.fun(t, trial)[nq : nq + nv] - base) / step
        trial[nq : nq + nv] = v
        dq = np.zeros(nv)
        step = math.sqrt(EPS)
        for j in range(nv):
            dq[j] = step
            trial[:nq] = self.structure.integrate(q, dq)
            jac_q[:, j] = (self.fun(t, trial)[nq : nq + nv] - base) / step
            dq[j] = 0.0
        self.njev += 1  # OdeSolver's count of Jacobian evaluations
        scale = (1.0 - self.alpha_f) / (1.0 - self.alpha_m)
        matrix = np.eye(nv) - self.beta * scale * h * h * jac_q - self.gamma * scale * h * jac_v
        if not np.all(np.isfinite(matrix)):
            return False
        try:
            self.iteration_matrix_inverse = np.linalg.inv(matrix)
        except np.linalg.LinAlgError:
            return False
        return bool(np.all(np.isfinite(self.iteration_matrix_inverse)))

    def _newton(self, t_new: float, h: float):
        """Solve for a+; returns (y+, f+, a+, x+), or None if the iterations fail (``self._last`` keeps the last iterate)."""
        nq, nv = self.structure.nq, self.structure.nv
        acc_new = self.acc.copy()  # predictor: a+ = a_n
        extra_rate = self.f[nq + nv :]
        scale_q = self.beta * (1.0 - self.alpha_f) / (1.0 - self.alpha_m) * h * h
        scale_v = self.gamma * (1.0 - self.alpha_f) / (1.0 - self.alpha_m) * h
        previous = None
        converged = False
        for k in range(self.max_iterations):
            y_new, x_new = self._state(h, acc_new, extra_rate)
            f_new = self.fun(t_new, y_new)
            self.n_newton += 1
            residual = acc_new - f_new[nq : nq + nv]
            if not np.all(np.isfinite(residual)):
                return None
            self._last = (y_new, f_new)
            if self.iteration_matrix_inverse is None and not self._refresh_matrix(t_new, y_new, f_new, h):
                return None
            delta = -(self.iteration_matrix_inverse @ residual)
            # size of the implied change of (q, v), scaled by the tolerances (q in its tangent space, unit scale)
            size = math.sqrt(
                0.5 * float(np.mean((scale_q * delta / (self.atol + self.rtol)) ** 2))
                + 0.5 * float(np.mean((scale_v * delta / (self.atol + self.rtol * np.abs(y_new[nq : nq + nv]))) ** 2))
            )
            rate = size / previous if previous else None
            if rate is not None and (rate >= 1.0 or rate ** (self.max_iterations - k) / (1.0 - rate) * size > self.newton_tol):
                return None  # diverging, or too slow to converge in the iterations left
            acc_new = acc_new + delta
            if size == 0.0 or (rate is not None and rate / (1.0 - rate) * size < self.newton_tol):
                converged = True
                break
            previous = size
        if not converged:
            return None
        extra_rate = f_new[nq + nv :]
        y_new, x_new = self._state(h, acc_new, extra_rate)
        return y_new, f_new, acc_new, x_new

    def _step_impl(self):
        h = min(self.h_fixed, abs(self.t_bound - self.t))
        t_new = self.t + h
        result = self._solve(t_new, h)
        if result is None:
            self.failure_cause = "Newton divergence"
            return False, self._divergence_message(t_new, h)
        y_new, f_new, acc_new, x_new = result
        self.step_start = (self.t, self.y, self.f, self.acc, self.pseudo)
        self.y_old, self.f_old, self.t_old_value = self.y, self.f, self.t
        self.y, self.f, self.t = y_new, f_new, t_new
        self.acc, self.pseudo = acc_new, x_new
        return True, None

    def _solve(self, t_new: float, h: float):
        """(y+, f+, a+, x+) of the step ``h`` from the current state, or None if the iterations fail even with fresh matrices."""
        self._last = None
        result = self._newton(t_new, h)
        for _ in range(self.max_refreshes):
            if result is not None:
                break
            # stale iteration matrix (e.g. a contact closed during the step): refresh it at the last
            # iterate (where the new contact forces act), else at the start of the step, and retry
            self.n_rejected += 1
            self.iteration_matrix_inverse = None
            y_at, f_at = self._last if self._last is not None else (self.y, self.f)
            if not self._refresh_matrix(t_new if self._last is not None else self.t, y_at, f_at, h):
                break
            result = self._newton(t_new, h)
        return result

    def _divergence_message(self, t_new: float, h: float) -> str:
        return (
            f"{self.method_name} (generalized-alpha, rho_inf = {self.rho_inf:g}): the Newton iterations did not converge at "
            f"t={t_new:.9g} s with the fixed step h={h:.3e} s (step too large for the dynamics)"
        )

    def _dense_output_impl(self):
        return HermiteDense(self.t_old_value, self.t, self.y_old, self.f_old, self.y, self.f)

    def restep_dense_output(self) -> RestepDense:
        """The last step's states as steps of the method from its start (:class:`~robot.integration.dense.RestepDense`).

        Each from the step's start state with its history (the pseudo-acceleration
        ``x``), on a copy of the solver: the copy's iteration matrix is refreshed
        for the shorter steps when needed, and the solver goes on unchanged.
        """
        start = self.step_start
        t_old = start[0]
        replica = copy.copy(self)

        def restep(h: float) -> np.ndarray:
            replica.t, replica.y, replica.f, replica.acc, replica.pseudo = start
            calls, jacobians = self.nfev, replica.njev  # the copy calls the solver's counted fun
            result = replica._solve(t_old + h, h)
            self.n_restep_calls += self.nfev - calls
            self.njev += replica.njev - jacobians
            if result is None:
                raise StepFailure("Newton divergence", f"{self._divergence_message(t_old + h, h)}, restepping from t={t_old:.9g} s to locate a contact onset")
            return result[0]

        return RestepDense(t_old, self.t, start[1], restep)


class Newmark(GeneralizedAlpha):
    """Generalized-alpha with ``rho_inf = 1``: the trapezoidal rule (Newmark average acceleration)."""

    method_name = "Newmark"

    def __init__(self, *args, **kwargs):
        kwargs["rho_inf"] = 1.0
        super().__init__(*args, **kwargs)


class _CVODEDense(DenseOutput):
    """CVODE's own interpolant of the last step (``CVodeGetDky``; through ``step(t)`` with scikit-sundae's binding)."""

    def __init__(self, t_old, t, solver):
        super().__init__(t_old, t)
        self.solver = solver
        self.t_end = t
        self.y_end = solver.y.copy()

    def _one(self, t):
        if t == self.t_end:
            return self.y_end.copy()
        direct = self.solver._direct
        if direct is not None:
            return direct.interpolate(float(t))
        result = self.solver._cvode.step(float(t))
        if result.status < 0:
            raise RuntimeError(f"CVODE interpolation at t={t!r}: {result.message}")
        return np.array(result.y, dtype=float)

    def _call_impl(self, t):
        if isinstance(t, float) or t.ndim == 0:
            return self._one(float(t))
        return np.column_stack([self._one(float(tt)) for tt in np.asarray(t)])


class _CVODEBase(OdeSolver):
    """SUNDIALS CVODE stepped one internal step at a time (``onestep`` with ``tstop``).

    Driven through CVODE's C interface (:mod:`robot.integration.cvode_direct`) where
    the libraries scikit-sundae ships can be loaded, else through scikit-sundae's
    binding; the same library with the same options either way (the same steps).
    """

    cvode_method = "BDF"
    min_step = 1e-12

    def __init__(self, fun, t0, y0, t_bound, rtol=1e-3, atol=1e-6, max_step=np.inf, first_step=None, vectorized=False, jac=None, **extraneous):
        direct = cvode_direct.available()
        binding = None if direct else cvode_direct.scikit_sundae_cvode()
        if not direct and binding is None:
            raise ValueError("CVODE needs the scikit-sundae package (pip install scikit-sundae)")
        super().__init__(fun, t0, y0, t_bound, vectorized)

        def rhsfn(t, y, yp):
            # the user function directly (scipy's wrapper would copy y and convert the result
            # again): it reads y during the call only, and CVODE owns both buffers
            self.nfev += 1
            yp[:] = fun(t, y)

        options = dict(
            method=self.cvode_method,
            rtol=float(rtol),
            atol=float(atol),
            max_num_steps=100000,
            # CVODE's own first-step estimate can be ~1e-14 s at tight tolerances, which the
            # simulation would take for a step-size collapse (FailureLimits.min_step = 1e-13 s)
            min_step=self.min_step,
            max_step=float(max_step) if np.isfinite(max_step) else max(abs(float(t_bound) - float(t0)), 1.0),
        )
        if first_step is not None:
            options["first_step"] = float(first_step)
        self.failure_cause = None
        self._direct = self._cvode = None
        if direct:
            # CVODE's dense matrix is filled in place (``jac(t, y, out)``)
            self._direct = cvode_direct.DirectCVODE(
                rhsfn, float(t0), np.asarray(y0, dtype=float), jacobian=jac, stop_time=float(t_bound), **options
            )
            return
        if jac is not None:
            def jacfn(t, y, yp, matrix):
                jac(t, y, matrix)

            options["jacfn"] = jacfn
        self._cvode = binding(rhsfn, **options)
        result = self._cvode.init_step(float(t0), np.asarray(y0, dtype=float))
        if result.status < 0:
            raise ValueError(f"CVODE initialisation failed: {result.message}")

    @property
    def njev(self) -> int:
        """Jacobians evaluated so far (CVODE's count)."""
        direct = self.__dict__.get("_direct")
        return direct.n_jacobians if direct is not None else self.__dict__.get("_njev", 0)

    @njev.setter
    def njev(self, value: int) -> None:  # OdeSolver.__init__ sets 0
        self._njev = value

    def _step_impl(self):
        direct = self._direct
        if direct is not None:
            flag = direct.one_step(self.t_bound)
            if flag < 0:
                self.failure_cause = "step size collapse" if flag in cvode_direct.STEP_SIZE_FLAGS else "solver error"
                return False, f"CVODE: {direct.message(flag)} (flag {flag})"
            self.t = direct.t
            self.y = direct.y.copy()
            return True, None
        for _ in range(3):
            result = self._cvode.step(self.t_bound, method="onestep", tstop=self.t_bound)
            # after an interpolation call (dense output) the first one-step call only returns the
            # current state: step again
            if result.status < 0 or float(np.ravel(result.t)[-1]) != self.t:
                break
        if result.status < 0:
            self.failure_cause = "step size collapse" if result.status in (-3, -4) else "solver error"
            return False, f"CVODE: {result.message} (flag {result.status})"
        self.t = float(np.ravel(result.t)[-1])
        self.y = np.array(result.y, dtype=float).reshape(-1)
        self._njev = int(result.njev)
        return True, None

    def _dense_output_impl(self):
        return _CVODEDense(self.t_old, self.t, self)


class CVODEBDF(_CVODEBase):
    cvode_method = "BDF"


class CVODEAdams(_CVODEBase):
    cvode_method = "Adams"


def make_solver(
    method: str,
    fun,
    t0: float,
    y0: np.ndarray,
    t_bound: float,
    rtol: float,
    atol: float,
    max_step: float,
    first_step: float | None,
    structure: SecondOrderStructure | None = None,
    jacobian: Callable[..., np.ndarray] | None = None,
) -> OdeSolver:
    """Instantiate the named method, as its registered traits say (:mod:`robot.integration.methods`).

    ``jacobian(t, y, out=None) -> df/dy`` (a new array when ``out`` is None): the
    iteration matrix's Jacobian for the methods that take one (``takes_jacobian``;
    ignored by the others); None lets the solver difference ``fun`` itself.
    """
    traits = registry.traits(method)  # ValueError naming the method and the choices
    cls = traits.solver_class()
    if traits.second_order_structure:
        return cls(fun, t0, y0, t_bound, first_step=first_step, rtol=rtol, atol=atol, structure=structure)
    if traits.fixed_step:
        return cls(fun, t0, y0, t_bound, first_step=first_step)
    kwargs = dict(rtol=rtol, atol=atol, max_step=max_step)
    if jacobian is not None and traits.takes_jacobian:
        kwargs["jac"] = jacobian  # scipy keeps the returned matrix (a new one per call); CVODE fills its own
    if first_step is not None:
        kwargs["first_step"] = min(first_step, abs(t_bound - t0))
    return cls(fun, t0, y0, t_bound, **kwargs)
