"""The integrator registry: a method registered from outside the package runs through the step loop.

Explicit Euler, defined and registered here only (fixed step, one right-hand side
per step), integrates the ideal mechanism: its global error is first order in the
step (halving the step halves the error against a tight RK45 reference), every
step is accepted and counted by the loop from the registered traits, and the old
trait tables (live views of the registry) list it while it is registered.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import OdeSolver

from robot.integration import methods as registry
from robot.integration.dense import HermiteDense
from robot.integration.simulation import SolverOptions, integrate
from robot.integration.solvers import FIXED_STEP_METHODS, METHODS, STAGES, make_solver
from robot.run import build_run
from robot.validation.event_loop import SOLVERS as VALIDATION_METHODS

NAME = "ToyExplicitEuler"


class ExplicitEuler(OdeSolver):
    """y+ = y + h f(t, y), constant step ``first_step``; cubic Hermite dense output."""

    def __init__(self, fun, t0, y0, t_bound, first_step=None, vectorized=False, **extraneous):
        super().__init__(fun, t0, y0, t_bound, vectorized)
        self.h = float(first_step)
        self.f = self.fun(self.t, self.y)
        self.previous = None

    @property
    def step_size(self):
        return self.h

    def _step_impl(self):
        h = min(self.h, self.t_bound - self.t)
        self.previous = (self.t, self.y, self.f)
        self.y = self.y + h * self.f
        self.t = self.t + h
        self.f = self.fun(self.t, self.y)
        return True, None

    def _dense_output_impl(self):
        t_old, y_old, f_old = self.previous
        return HermiteDense(t_old, self.t, y_old, f_old, self.y, self.f)


@pytest.fixture
def toy_method():
    registry.register(registry.IntegratorTraits(NAME, ExplicitEuler, fixed_step=True, explicit=True, stages=1, replayable=True))
    yield NAME
    registry.unregister(NAME)


def test_a_registered_method_runs_a_simulation_at_first_order(toy_method):
    run = build_run("ideal")
    t_span = (0.0, 0.02)
    reference = integrate(run.dynamics, run.y0, t_span, SolverOptions("RK45", rtol=1e-11, atol=1e-13))
    nq = run.dynamics.nq
    errors = []
    for h in (2e-5, 1e-5):
        trajectory = integrate(run.dynamics, run.y0, t_span, SolverOptions(toy_method, first_step=h))
        assert trajectory.success, trajectory.message
        # fixed step, read from the traits (plus at most a sliver step left by the rounding of t)
        assert trajectory.n_steps - round((t_span[1] - t_span[0]) / h) in (0, 1)
        assert trajectory.n_rejected == 0  # counted from the registered stages: one call per step
        assert trajectory.n_rhs == trajectory.n_steps + 1
        errors.append(np.max(np.abs(trajectory.y[-1, :nq] - reference.y[-1, :nq])))
    assert 1.7 < errors[0] / errors[1] < 2.3  # first order
    assert errors[1] < 1e-5


def test_the_trait_tables_are_views_of_the_registry(toy_method):
    assert toy_method in METHODS and METHODS[toy_method] is ExplicitEuler
    assert toy_method in FIXED_STEP_METHODS and STAGES[toy_method] == 1
    assert toy_method not in VALIDATION_METHODS  # the validation offers explicit variable-step methods only
    assert list(VALIDATION_METHODS) == ["RK45", "RK23", "DOP853"]
    with pytest.raises(ValueError, match=f"method={toy_method!r} is already registered"):
        registry.register(registry.IntegratorTraits(toy_method, ExplicitEuler))
    registry.unregister(toy_method)
    assert toy_method not in METHODS and toy_method not in FIXED_STEP_METHODS
    with pytest.raises(ValueError, match=f"method={toy_method!r} is not on offer; choose one of RK45, "):
        make_solver(toy_method, lambda t, y: -y, 0.0, np.ones(1), 1.0, 1e-6, 1e-9, np.inf, 1e-3)


def test_unavailable_methods_are_not_on_offer():
    registry.register(registry.IntegratorTraits("ToyMissing", "no_such_module:Solver", available=lambda: False))
    try:
        assert "ToyMissing" not in METHODS
        with pytest.raises(ValueError, match="not on offer"):
            registry.traits("ToyMissing")
    finally:
        registry.unregister("ToyMissing")
