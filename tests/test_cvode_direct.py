"""CVODE through its C interface (robot.integration.cvode_direct) takes exactly the steps of scikit-sundae's binding.

The same SUNDIALS library with the same options must give the same numbers:
step by step (times, states, interpolated states, counts) on a stiff problem
with and without an analytic Jacobian, both methods, and a whole simulation
(the trajectory bit for bit). Also: exceptions raised in the callbacks come
out of ``one_step``; failures are returned as CVODE's flags.
"""

from __future__ import annotations

import numpy as np
import pytest

from robot.integration import cvode_direct
from robot.integration import solvers as S

pytestmark = pytest.mark.skipif(not cvode_direct.available() or cvode_direct.scikit_sundae_cvode() is None, reason="SUNDIALS libraries of scikit-sundae not found")

# Robertson's chemical kinetics: the classic stiff test (rates 0.04, 1e4, 3e7)
def robertson(t, y):
    return np.array([-0.04 * y[0] + 1e4 * y[1] * y[2], 0.04 * y[0] - 1e4 * y[1] * y[2] - 3e7 * y[1] ** 2, 3e7 * y[1] ** 2])


def robertson_jacobian(t, y, out):
    out[:] = [[-0.04, 1e4 * y[2], 1e4 * y[1]], [0.04, -1e4 * y[2] - 6e7 * y[1], -1e4 * y[1]], [0.0, 6e7 * y[1], 0.0]]
    return out


def _march(solver_class, monkeypatch, direct: bool, jacobian, steps: int = 300):
    monkeypatch.setattr(cvode_direct, "available", lambda: direct)
    solver = solver_class(robertson, 0.0, np.array([1.0, 0.0, 0.0]), 40.0, rtol=1e-6, atol=1e-10, max_step=5.0, jac=jacobian)
    assert (solver._direct is not None) == direct
    out = []
    for _ in range(steps):
        solver.step()
        if solver.status != "running":
            break
        dense = solver.dense_output()
        middle = 0.5 * (solver.t_old + solver.t)
        out.append((solver.t, solver.y.copy(), dense(middle), dense(solver.t_old + 0.1 * (solver.t - solver.t_old))))
    return out, solver.nfev, solver.njev, solver.status


@pytest.mark.parametrize("solver_class", [S.CVODEBDF, S.CVODEAdams])
@pytest.mark.parametrize("jacobian", [robertson_jacobian, None])
def test_same_steps_as_the_binding(monkeypatch, solver_class, jacobian):
    direct, nfev_d, njev_d, status_d = _march(solver_class, monkeypatch, True, jacobian)
    binding, nfev_b, njev_b, status_b = _march(solver_class, monkeypatch, False, jacobian)
    assert len(direct) == len(binding) > 50 and status_d == status_b
    for a, b in zip(direct, binding):
        for x, y in zip(a, b):
            assert np.array_equal(x, y)
    assert (nfev_d, njev_d) == (nfev_b, njev_b)
    # and the answer is Robertson's: mass conserved to the tolerance
    assert abs(np.sum(direct[-1][1]) - 1.0) < 1e-5


def test_a_simulation_is_the_same_bit_for_bit(monkeypatch):
    from robot.integration.simulation import integrate
    from robot.run import build_run

    run = build_run("compound_misaligned", duration=0.03)
    trajectories = []
    for direct in (True, False):
        monkeypatch.setattr(cvode_direct, "available", lambda direct=direct: direct)
        trajectories.append(integrate(run.dynamics, run.y0, run.t_span, run.scene.solver, run.scene.limits))
    a, b = trajectories
    assert a.success and a.n_events > 0 and a.n_jacobians > 0
    assert np.array_equal(a.t, b.t) and np.array_equal(a.y, b.y) and np.array_equal(a.kind, b.kind)
    assert (a.n_steps, a.n_rhs, a.n_jacobians, a.events) == (b.n_steps, b.n_rhs, b.n_jacobians, b.events)


def test_callback_exceptions_come_out_of_one_step():
    calls = []

    def rhs(t, y, ydot):
        calls.append(t)
        if len(calls) > 5:
            raise KeyboardInterrupt
        ydot[:] = -y

    cvode = cvode_direct.DirectCVODE(rhs, 0.0, np.ones(2), method="BDF", rtol=1e-6, atol=1e-8, max_step=0.1, min_step=0.0)
    with pytest.raises(KeyboardInterrupt):
        for _ in range(10):
            cvode.one_step(1.0)


def test_a_collapsing_step_is_a_flag():
    # y' = y^2 from 1 blows up at t = 1: CVODE cannot pass it with a minimum step
    cvode = cvode_direct.DirectCVODE(lambda t, y, ydot: ydot.__setitem__(0, y[0] ** 2), 0.0, np.ones(1), method="BDF", rtol=1e-8, atol=1e-10, max_step=0.1, min_step=1e-6)
    flags = [cvode.one_step(2.0) for _ in range(5000)]
    failed = [f for f in flags if f < 0]
    assert failed and failed[0] in (-2, -3, -4) and cvode.t < 1.0
    assert "step" in cvode.message(-3)
