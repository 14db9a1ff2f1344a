"""Poincare sections: stroboscopic samples and hyperplane crossings on systems with known answers."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from robot.analysis import ANALYSES, AnalysisError
from robot.analysis.bifurcation import distinct_points
from robot.analysis.poincare import hyperplane_section, stroboscopic_section

# solver tolerances of the reference trajectories (DOP853); max_step keeps the cubic
# interpolant's O(h^4) error between records below the checked tolerance
RTOL, ATOL = 1e-10, 1e-12


def damped_driven(zeta: float, omega0: float, omega: float, force: float, t_end: float, steps_per_period: int):
    """x'' + 2 zeta omega0 x' + omega0^2 x = force cos(omega t) from rest, on the solver's own (non-uniform) steps."""
    period = 2 * np.pi / omega
    rhs = lambda t, y: [y[1], -2 * zeta * omega0 * y[1] - omega0**2 * y[0] + force * np.cos(omega * t)]
    sol = solve_ivp(rhs, (0.0, t_end), [0.0, 0.0], method="DOP853", rtol=RTOL, atol=ATOL, max_step=period / steps_per_period)
    return sol.t, sol.y.T


def steady_state_point(zeta, omega0, omega, force):
    """(x, v) of the steady state x = X cos(omega t - phi) at t = k T."""
    amplitude = force / np.hypot(omega0**2 - omega**2, 2 * zeta * omega0 * omega)
    phi = np.arctan2(2 * zeta * omega0 * omega, omega0**2 - omega**2)
    return np.array([amplitude * np.cos(phi), amplitude * omega * np.sin(phi)])


@pytest.mark.parametrize("zeta, omega0, omega, force", [(0.1, 2.0, 1.3, 0.7), (0.05, 1.0, 2.9, 3.0)])
def test_stroboscopic_samples_converge_to_the_steady_state(zeta, omega0, omega, force):
    period = 2 * np.pi / omega
    t, y = damped_driven(zeta, omega0, omega, force, 40 * period + 0.37, steps_per_period=100)
    assert np.ptp(np.diff(t)) > 0.01 * np.mean(np.diff(t))  # the grid is not uniform
    out = stroboscopic_section(t, y, period=period, max_points=64)
    count = int(out["count"])
    assert count == 41  # k = 0 .. 40
    points = out["points"][:count]
    np.testing.assert_allclose(out["times"][:count], np.arange(41) * period, rtol=0, atol=1e-12)
    assert np.all(np.isnan(out["points"][count:]))
    expected = steady_state_point(zeta, omega0, omega, force)
    scale = np.linalg.norm(expected)
    distance = np.linalg.norm(points - expected, axis=1)
    # the homogeneous part decays as exp(-zeta omega0 t): fit the rate of the distance over the periods
    decaying = distance > 1e-6 * scale
    k = np.arange(count)[decaying]
    rate = -np.polyfit(k * period, np.log(distance[decaying]), 1)[0]
    assert rate == pytest.approx(zeta * omega0, rel=0.05)
    # and the last sample is the analytic steady-state point
    remaining = np.exp(-zeta * omega0 * 40 * period)
    assert distance[-1] < max(2 * remaining, 1e-6) * scale


def test_transient_and_phase_select_the_samples():
    omega = 1.7
    period = 2 * np.pi / omega
    t = np.sort(np.concatenate([[0.0, 30.0], np.random.default_rng(1).uniform(0, 30, 4000)]))
    x = np.sin(omega * t)
    out = stroboscopic_section(t, x, period=period, phase=0.25 * period, transient=10.0, max_points=32)
    times = out["times"][: int(out["count"])]
    assert times[0] >= 10.0 and times[0] - period < 10.0
    # sin(omega (t0 + k T)) with t0 = T/4: every sample at the crest
    np.testing.assert_allclose(out["points"][: int(out["count"]), 0], 1.0, atol=1e-6)


def test_constructed_period_two_signal_gives_two_points():
    omega = 2.3
    period = 2 * np.pi / omega
    t = np.sort(np.random.default_rng(2).uniform(0, 60 * period, 20000))
    x = np.cos(omega * t) + 0.3 * np.cos(0.5 * omega * t)  # subharmonic: period 2T
    phase = t[0]
    out = stroboscopic_section(t, x, period=period, phase=phase, transient=0.0, max_points=128)
    samples = out["points"][: int(out["count"]), 0]
    assert distinct_points(samples, 1e-4) == 2
    k = np.arange(len(samples)) + int(np.ceil((t[0] - phase) / period - 1e-9))
    expected = np.cos(omega * (phase + k * period)) + 0.3 * np.cos(0.5 * omega * (phase + k * period))
    np.testing.assert_allclose(samples, expected, atol=1e-6)


@pytest.mark.parametrize("forcing, period_number", [(0.20, 1), (0.28, 2), (0.29, 4), (0.37, 5)])
def test_duffing_period_doubling_cascade(forcing, period_number):
    """x'' + 0.3 x' - x + x^3 = G cos(1.2 t) from (1, 0): period 1, 2, 4 at G = 0.20, 0.28, 0.29 and the
    period-5 window at G = 0.37 (Jordan & Smith, Nonlinear Ordinary Differential Equations, 4th ed.,
    2007, Sec. 13.3)."""
    omega = 1.2
    period = 2 * np.pi / omega
    rhs = lambda t, y: [y[1], -0.3 * y[1] + y[0] - y[0] ** 3 + forcing * np.cos(omega * t)]
    sol = solve_ivp(rhs, (0.0, 260 * period), [1.0, 0.0], method="DOP853", rtol=RTOL, atol=ATOL, max_step=period / 50)
    out = stroboscopic_section(sol.t, sol.y.T, period=period, transient=200 * period, max_points=64)
    points = out["points"][: int(out["count"])]
    assert len(points) == 61
    assert distinct_points(points[:, 0], 1e-5) == period_number
    # the orbit closes after period_number drive periods
    np.testing.assert_allclose(points[period_number:], points[:-period_number], atol=1e-6)


def test_hyperplane_crossings_of_a_harmonic_orbit():
    # x = cos t, v = -sin t crosses x = 0 upward (v > 0) at t = 3 pi / 2 + 2 pi k, with v = 1
    t = np.sort(np.concatenate([[0.0, 40.0], np.random.default_rng(3).uniform(0, 40, 3000)]))
    state = np.column_stack([np.cos(t), -np.sin(t)])
    up = hyperplane_section(t, state, normal=[1.0, 0.0], direction=1)
    count = int(up["count"])
    np.testing.assert_allclose(up["times"][:count], 1.5 * np.pi + 2 * np.pi * np.arange(count), atol=1e-7)
    np.testing.assert_allclose(up["points"][:count], np.tile([0.0, 1.0], (count, 1)), atol=1e-7)
    down = hyperplane_section(t, state, normal=[1.0, 0.0], direction=-1)
    np.testing.assert_allclose(down["points"][: int(down["count"]), 1], -1.0, atol=1e-7)
    both = hyperplane_section(t, state, normal=[1.0, 0.0], direction=0)
    assert int(both["count"]) == count + int(down["count"])
    # an oblique plane: n . x = c with the crossing point on the plane
    oblique = hyperplane_section(t, state, normal=[0.6, 0.8], offset=0.5, direction=1, transient=5.0)
    pts = oblique["points"][: int(oblique["count"])]
    np.testing.assert_allclose(pts @ [0.6, 0.8], 0.5, atol=1e-9)
    assert np.all(oblique["times"][: int(oblique["count"])] >= t[0] + 5.0)


def test_padding_keeps_the_last_points_and_registry_shapes():
    t = np.linspace(0, 100, 5001)
    out = ANALYSES["poincare_stroboscopic"](t=t, state=np.column_stack([t, t]), period=1.0, max_points=10)
    assert out["points"].shape == (10, 2) and int(out["count"]) == 10
    np.testing.assert_allclose(out["times"], np.arange(91, 101))
    shapes = ANALYSES["poincare_stroboscopic"].output_shapes({"time": 5001, "component": 2}, period=1.0, max_points=10)
    assert shapes == {name: value.shape for name, value in out.items()}


@pytest.mark.parametrize(
    "kwargs, message",
    [
        ({"period": -1.0}, "period=-1.0 must be positive"),
        ({"period": 1.0, "transient": 1e3}, "transient=1000.0 leaves nothing"),
        ({"period": 1.0, "max_points": 0}, "max_points=0 is outside the valid range"),
    ],
)
def test_bad_arguments_raise(kwargs, message):
    t = np.linspace(0, 10, 101)
    with pytest.raises(AnalysisError, match=message):
        stroboscopic_section(t, np.sin(t), **kwargs)


def test_bad_time_grid_raises():
    with pytest.raises(AnalysisError, match=r"t must be non-decreasing; t\[2\]=0.5 < t\[1\]=1.0"):
        stroboscopic_section([0.0, 1.0, 0.5, 2.0], [0.0, 1.0, 2.0, 3.0], period=1.0)
    with pytest.raises(AnalysisError, match="state has 3 rows but the time grid has 4 points"):
        stroboscopic_section([0.0, 1.0, 2.0, 3.0], [0.0, 1.0, 2.0], period=1.0)
    with pytest.raises(AnalysisError, match="normal must be a non-zero vector of 2 components"):
        hyperplane_section([0.0, 1.0, 2.0], np.zeros((3, 2)), normal=[1.0, 0.0, 0.0])


def test_repeated_record_times_are_merged():
    # an onset record and the step end it cut share a time: not a zero-length interval
    t = np.array([0.0, 0.5, 1.0, 1.0, 1.5, 2.0, 2.5])
    x = 2.0 * t
    out = stroboscopic_section(t, x, period=0.5, max_points=8)
    np.testing.assert_allclose(out["points"][: int(out["count"]), 0], 2.0 * np.arange(0, 2.51, 0.5))
