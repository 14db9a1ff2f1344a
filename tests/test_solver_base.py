"""robot.integration.solver_base keeps scipy.integrate.OdeSolver's contract (what the step loop relies on).

One toy method (Heun's method with a Hermite dense output) is written once and
built on both bases; stepped side by side, forwards and backwards, they must
agree exactly in every attribute the loop reads (t, y, t_old, step_size,
status, direction, nfev, dense output on scalars and arrays), in the corner
cases (empty interval, empty state) and in the errors.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import OdeSolver as ScipySolver

from robot.integration import solver_base
from robot.integration.dense import HermiteDense


def _heun(base: type) -> type:
    class Heun(base):
        def __init__(self, fun, t0, y0, t_bound, first_step=0.1, vectorized=False, **extraneous):
            super().__init__(fun, t0, y0, t_bound, vectorized)
            self.h = first_step
            self.f = self.fun(self.t, self.y) if self.n else None

        def _step_impl(self):
            h = self.direction * min(self.h, abs(self.t_bound - self.t))
            predictor = self.y + h * self.f
            t_new = self.t + h
            f_predicted = self.fun(t_new, predictor)
            self.previous = (self.t, self.y, self.f)
            self.y = self.y + 0.5 * h * (self.f + f_predicted)
            self.t = t_new
            self.f = self.fun(self.t, self.y)
            return True, None

        def _dense_output_impl(self):
            t_old, y_old, f_old = self.previous
            return HermiteDense(t_old, self.t, y_old, f_old, self.y, self.f)

    return Heun


OURS, THEIRS = _heun(solver_base.OdeSolver), _heun(ScipySolver)


def oscillator(t, y):
    return [y[1], -4.0 * y[0] + np.sin(t)]


@pytest.mark.parametrize("t0, t_bound", [(0.0, 1.05), (2.0, -0.3)])
def test_the_same_steps_as_on_scipys_base(t0, t_bound):
    ours, theirs = OURS(oscillator, t0, [1.0, 0.0], t_bound, first_step=0.1), THEIRS(oscillator, t0, [1.0, 0.0], t_bound, first_step=0.1)
    assert ours.step_size is None and theirs.step_size is None and ours.t_old is None
    assert ours.direction == theirs.direction and ours.n == theirs.n == 2
    steps = 0
    while theirs.status == "running":
        assert ours.step() == theirs.step()
        steps += 1
        assert (ours.t, ours.t_old, ours.step_size, ours.status, ours.nfev) == (theirs.t, theirs.t_old, theirs.step_size, theirs.status, theirs.nfev)
        assert np.array_equal(ours.y, theirs.y)
        a, b = ours.dense_output(), theirs.dense_output()
        times = np.linspace(ours.t_old, ours.t, 5)
        assert np.array_equal(a(times), b(times)) and np.array_equal(a(times[2]), b(times[2]))
        assert (a.t_min, a.t_max) == (b.t_min, b.t_max)
    assert ours.status == "finished" and steps == int(np.ceil(abs(t_bound - t0) / 0.1 - 1e-9))
    with pytest.raises(RuntimeError):
        ours.step()


def test_empty_interval_and_empty_state():
    for t0, y0 in ((0.5, [1.0]), (0.0, np.zeros(0))):
        t_bound = 0.5 if len(y0) else 1.0
        ours, theirs = OURS(lambda t, y: -y, t0, y0, t_bound), THEIRS(lambda t, y: -y, t0, y0, t_bound)
        ours.step(), theirs.step()
        assert (ours.status, ours.t, ours.t_old) == (theirs.status, theirs.t, theirs.t_old) == ("finished", t_bound, t0)
        assert np.array_equal(ours.dense_output()(np.array([t0, t_bound])), theirs.dense_output()(np.array([t0, t_bound])))


def test_dense_output_before_a_step_and_bad_inputs_fail_as_scipy():
    with pytest.raises(RuntimeError):
        OURS(oscillator, 0.0, [1.0, 0.0], 1.0).dense_output()
    for bad in ([[1.0, 0.0]], [np.nan, 0.0], [1j, 0.0]):
        with pytest.raises(ValueError):
            THEIRS(oscillator, 0.0, bad, 1.0)
        with pytest.raises(ValueError):
            OURS(oscillator, 0.0, bad, 1.0)
    solver = OURS(oscillator, 0.0, [1.0, 0.0], 1.0)
    solver.step()
    with pytest.raises(ValueError):
        solver.dense_output()(np.zeros((2, 2)))


@pytest.mark.parametrize("method", ["RK4", "GenAlpha", "Newmark"])
def test_fixed_step_methods_refuse_to_integrate_backwards(method):
    """They step forward only: a t_bound before t0 is refused (it used to step forward forever)."""
    from robot.integration.solvers import SecondOrderStructure, make_solver

    structure = SecondOrderStructure(1, 1, lambda q, dq: q + dq)  # y = [x, x']
    with pytest.raises(ValueError, match=r"integrate forward: t_bound=0\.0 must be >= t0=1\.0"):
        make_solver(method, oscillator, 1.0, np.array([1.0, 0.0]), 0.0, 1e-6, 1e-9, np.inf, 0.1, structure=structure)
