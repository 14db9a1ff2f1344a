"""The step loop at the edges where methods fail, on a mechanism of its own: what a run reports and keeps.

* a fixed-step method's step that crosses into a contact: its late stages met the
  contact with the stored onset rate (the floor, 1e-4 m/s: Lankarani-Nikravesh
  damping ~1e4 times too large) and the onset was located on the step's corrupted
  interpolant; now the stages use the approach rate and the onset is located on
  the method's own steps from the step's start (:class:`RestepDense`);
* a restart state (the located onset) is checked as an accepted step's end is;
* a step short only because the span is short is still a step-size collapse (the
  user's min_step is kept), and its message says to lower min_step; a collapse's
  message shows the step below the limit;
* a failing Newmark run names Newmark, and a Newton divergence met while restepping
  keeps its cause;
* a trial stage of an explicit method in a pose the contact law refuses is rejected
  without numpy's "invalid value" warning.
"""

from __future__ import annotations

import math
import re
import warnings

import numpy as np
import pytest

from clearance_contact import ContactError

from robot.integration.event_loop import EventDrivenIntegrator
from robot.integration.options import FailureLimits, SolverOptions
from robot.integration.records import RECORD_ONSET, RECORD_PEAK, RECORD_STEP
from robot.integration.simulation import integrate
from robot.integration.solvers import SecondOrderStructure, make_solver
from robot.run import build_run, run_scene
from robot.validation.event_loop import FunctionSystem
from tests.conftest import four_bar_torque_scene


#: past the first impact's force maximum
FIRST_IMPACT = 0.0025
FORCE_PEAK = 5  # event_kind of a force maximum


def _build(tmp_path, solver: str, duration: float, extra: str = ""):
    # damped impacts (restitution 0.8)
    path = four_bar_torque_scene(tmp_path / "four_bar.toml", name="four_bar_torque_damped", duration=duration, solver=solver, restitution=0.8, extra=extra)
    return build_run(str(path))


def _run(tmp_path, solver: str, duration: float, extra: str = ""):
    return run_scene(_build(tmp_path, solver, duration, extra))


def _fixed(method: str, step: float) -> str:
    return f'method = "{method}"\nfirst_step = {step}'


@pytest.fixture(scope="module")
def reference(tmp_path_factory):
    return _run(tmp_path_factory.mktemp("reference"), 'method = "DOP853"\nrtol = 1e-10\natol = 1e-13\nmax_step = 1e-5', FIRST_IMPACT)


@pytest.mark.parametrize("method", ["RK4", "GenAlpha", "Newmark"])
def test_fixed_step_methods_take_the_first_impact_as_the_adaptive_reference(tmp_path, reference, method):
    """h = 1e-5 s. Before: RK4 started the impact with the floor onset rate 1e-4 m/s (instead of 0.214 m/s)
    and drifted off; GenAlpha and Newmark failed at the crossing step ("Newton divergence")."""
    result = _run(tmp_path, _fixed(method, 1e-5), FIRST_IMPACT)
    assert result.success, result.message
    onsets, onsets_ref = result["event_is_onset"], reference["event_is_onset"]
    assert np.count_nonzero(onsets) == np.count_nonzero(onsets_ref) > 0
    np.testing.assert_allclose(result["event_t"][onsets], reference["event_t"][onsets_ref], rtol=0, atol=1e-8)
    rates = result["event_value"][onsets]
    np.testing.assert_allclose(rates, reference["event_value"][onsets_ref], rtol=1e-3)
    assert np.all(rates > 0.1)  # m/s: an approach rate, not the floor
    peak, peak_ref = (r["event_value"][r["event_kind"] == FORCE_PEAK] for r in (result, reference))
    assert peak.size == peak_ref.size > 0
    np.testing.assert_allclose(peak, peak_ref, rtol=2e-2)  # N: the method's accuracy at this step


def test_a_fixed_step_run_continued_in_contact_starts_with_the_impacts_onset_rate(tmp_path, reference):
    """From a step end of the first impact's compression, with its onset rates (a continued run): the new
    solver's first derivative already damps with the impact's onset rate, not the stored floor (the solvers
    evaluate it when they are made, before the first step). RK4 with h = 1e-6 s follows DOP853 for 20 steps."""
    kind, t = reference["record_kind"], reference["t"]
    t_onset, t_peak = t[kind == RECORD_ONSET][0], t[kind == RECORD_PEAK][0]
    compression = np.flatnonzero((kind == RECORD_STEP) & (t > t_onset) & (t < t_peak))
    i = int(compression[compression.size // 2])
    t0, y0, onset = float(reference["t"][i]), np.concatenate([reference["q"][i], reference["v"][i]]), reference["onset_rates"][i]
    assert np.max(onset) > 0.1  # m/s: in contact, with the impact's onset rate
    run = _build(tmp_path, _fixed("RK4", 1e-6), FIRST_IMPACT)
    span = (t0, t0 + 2e-5)
    fine = integrate(run.dynamics, y0, span, SolverOptions("DOP853", rtol=1e-11, atol=1e-14, max_step=1e-6), onset_rates=onset)
    fixed = integrate(run.dynamics, y0, span, SolverOptions("RK4", first_step=1e-6), onset_rates=onset)
    assert fine.success and fixed.success, (fine.message, fixed.message)
    nq = run.dynamics.nq
    assert np.max(np.abs(fixed.y[-1, :nq] - fine.y[-1, :nq])) < 1e-9  # m, rad (3.2e-5 with the floor in the first stage)


def _oscillator(omega: float = 30.0):
    """``q'' = -omega^2 q`` with its power ``v q''`` as an extra (quadrature) component, and its structure."""

    def fun(t, y):
        acceleration = -(omega**2) * y[0]
        return np.array([y[1], acceleration, y[1] * acceleration])

    return fun, SecondOrderStructure(1, 1, lambda q, dq: q + dq)


@pytest.mark.parametrize("method", ["RK4", "GenAlpha", "Newmark"])
def test_restep_dense_output_is_the_method_from_the_step_start_and_leaves_the_solver_unchanged(method):
    fun, structure = _oscillator()
    h, y0 = 0.01, np.array([1.0, 0.0, 0.0])
    solvers = [make_solver(method, fun, 0.0, y0, 1.0, 1e-12, 1e-14, math.inf, h, structure) for _ in range(2)]
    for solver in solvers:
        for _ in range(3):
            solver.step()
    probed, untouched = solvers
    t_old, y_old = probed.t_old, probed.dense_output()(probed.t_old)
    dense = probed.restep_dense_output()
    assert np.array_equal(dense(t_old), y_old)
    # at the step's end: the step itself (GenAlpha: from the step's own history x_n, to the Newton tolerance)
    np.testing.assert_allclose(dense(probed.t), probed.y, rtol=1e-9, atol=1e-12)
    for fraction in (0.25, 0.5, 0.75):
        t = t_old + fraction * h
        if method == "RK4":  # a step of size t - t_old from (t_old, y_old): what a new solver takes there
            fresh = make_solver(method, fun, t_old, y_old, t, 1e-12, 1e-14, math.inf, t - t_old)
            fresh.step()
            np.testing.assert_allclose(dense(t), fresh.y, rtol=1e-14, atol=1e-15)
        # a state of the oscillator's motion (its energy level, to the method's accuracy)
        energy = 0.5 * dense(t)[1] ** 2 + 0.5 * 900.0 * dense(t)[0] ** 2
        assert energy == pytest.approx(450.0, rel=1e-4)
    # the solver goes on as if the dense output had not been asked for
    for _ in range(3):
        probed.step()
        untouched.step()
    assert np.array_equal(probed.y, untouched.y)


def test_a_restart_state_beyond_the_limits_stops_the_run_there(tmp_path):
    """Baumgarte gains 1e6 with RK4 (beyond its stability region): the constraint residual grows past
    max_residual between two step ends, at the first onset. Before, the onset was recorded with residual
    3.6e-4 and the run went on from it, to fail later as a penetration beyond its bound."""
    result = _run(tmp_path, _fixed("RK4", 1e-5), 0.003, "[baumgarte]\nalpha = 1.0e6\nbeta = 1.0e6")
    assert result.status == -1 and result.cause == "constraint drift", (result.cause, result.message)
    t_failed = float(re.match(r"t=(\S+) s:", result.message).group(1))
    assert 2e-5 < t_failed < 3e-5  # between two step ends: the onset located inside the step
    assert np.max(np.abs(result["constraint_residual"])) <= FailureLimits().max_residual  # what is kept passed the checks
    assert result.t_end < t_failed


@pytest.mark.parametrize("duration", [1e-10, 1e-11])
def test_a_tiny_span_keeps_the_limit_and_says_to_lower_it(tmp_path, duration):
    """LSODA's first step is 1e-3 of the span: 1e-13 s on 1e-10 s. The user's min_step is kept (a run that must not
    take such steps fails there), and the message says why the steps are short and what to change; with a lower
    min_step the run finishes. Before: "step size 1.000e-13 s below 1.0e-13 s", no advice."""
    result = _run(tmp_path, 'method = "LSODA"\nrtol = 1e-6\natol = 1e-8', duration)
    assert result.cause == "step size collapse" and "lower [limits] min_step for a run this short" in result.message, result.message
    size, limit = map(float, re.search(r"step size (\S+) s below (\S+) s", result.message).groups())
    assert size < limit
    result = _run(tmp_path, 'method = "LSODA"\nrtol = 1e-6\natol = 1e-8', duration, "[limits]\nmin_step = 1e-20")
    assert result.success, result.message
    assert result.t_end == duration


def _decay_system(refused_below: float = -math.inf) -> FunctionSystem:
    """``y' = -50 y`` with one candidate never in contact; a state below ``refused_below`` is a pose the law refuses."""

    def rhs(t, y, onset):
        if y[0] < refused_below:
            raise ContactError(f"y = {y[0]:.3g}: an absurd pose")
        return -50.0 * y

    return FunctionSystem(rhs, lambda t, y, onset: (np.array([-1.0]), np.array([0.0])), 1, 1, lambda y: y)


def test_a_collapse_message_shows_the_step_below_the_limit():
    """The limit set just above the first step: both printed to the digits that tell them apart."""
    span = (0.0, 1e5)
    first = EventDrivenIntegrator(_decay_system(), np.array([1.0]), span, SolverOptions("RK45"))
    first.start()
    first.start_solver()
    first.solver.step()
    h = first.solver.step_size
    limits = FailureLimits(min_step=h * (1.0 + 1e-12))
    trajectory = EventDrivenIntegrator(_decay_system(), np.array([1.0]), span, SolverOptions("RK45"), limits).run()
    assert trajectory.cause == "step size collapse", trajectory.message
    size, limit = map(float, re.search(r"step size (\S+) s below (\S+) s", trajectory.message).groups())
    assert size < limit and size == pytest.approx(h, rel=1e-11)


def test_a_failing_newmark_run_names_newmark(tmp_path):
    result = _run(tmp_path, _fixed("Newmark", 1e-4), 0.003)
    assert result.cause == "Newton divergence", result.message
    assert "Newmark (generalized-alpha, rho_inf = 1)" in result.message


@pytest.mark.parametrize("method", ["RK45", "DOP853", "RK23"])
def test_a_refused_trial_stage_is_rejected_without_numpy_warnings(method):
    """A first step of 0.2 s on y' = -50 y overshoots into a refused pose (y < -0.5) in a trial stage:
    the step is rejected and shrunk. Answered with inf, the stages' zero weights made numpy warn
    "invalid value encountered in dot" on a run that went on fine."""
    options = SolverOptions(method, rtol=1e-8, atol=1e-12, max_step=1.0, first_step=0.2)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        trajectory = EventDrivenIntegrator(_decay_system(refused_below=-0.5), np.array([1.0]), (0.0, 0.2), options).run()
    assert trajectory.success, trajectory.message
    assert trajectory.n_rejected > 0  # the overshooting first step
    assert trajectory.y[-1, 0] == pytest.approx(math.exp(-10.0), rel=1e-6)


def test_a_solver_failure_met_while_restepping_keeps_its_cause(monkeypatch):
    """GenAlpha's Newton iterations diverging while it resteps to locate an onset: "Newton divergence", as in a
    step of its own (it was reported as a "solver error", a RuntimeError)."""
    from robot.integration.solvers import StepFailure

    def diverging(self):
        raise StepFailure("Newton divergence", "GenAlpha: Newton iterations diverged, restepping from t=0 s to locate a contact onset")

    monkeypatch.setattr(EventDrivenIntegrator, "advance", diverging)
    trajectory = EventDrivenIntegrator(_decay_system(), np.array([1.0]), (0.0, 1.0), SolverOptions("RK4", first_step=1e-3)).run()
    assert trajectory.status == -1 and trajectory.cause == "Newton divergence", trajectory.message
    assert "restepping" in trajectory.message
