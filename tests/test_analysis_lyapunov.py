"""Largest Lyapunov exponents against known values: Benettin on flows, Rosenstein on a time series.

Integration: scipy DOP853; the tolerance of each flow is stated where it is built.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.spatial.transform import Rotation

from robot.analysis import ANALYSES, AnalysisError
from robot.analysis.lyapunov_benettin import EuclideanFlow, Flow, OdeFlow, batch_means_standard_error, benettin_exponent
from robot.analysis.lyapunov_rosenstein import rosenstein_exponent

LORENZ_EXPONENT = 0.9056  # sigma = 10, rho = 28, beta = 8/3 (Sprott, Chaos and Time-Series Analysis, 2003, App. A)


def lorenz(t, y, sigma=10.0, rho=28.0, beta=8.0 / 3.0):
    return np.array([sigma * (y[1] - y[0]), y[0] * (rho - y[2]) - y[1], y[0] * y[1] - beta * y[2]])


@pytest.fixture(scope="module")
def lorenz_benettin():
    # rtol = atol = 1e-10; d0 = 1e-7 (attractor size ~ 40); 400 intervals of 0.5 = 200 time units
    flow = OdeFlow(lorenz, rtol=1e-10, atol=1e-10)
    return benettin_exponent(flow, [1.0, 1.0, 1.0], renormalisation_time=0.5, n_intervals=400, separation=1e-7, transient_time=20.0)


def test_benettin_lorenz(lorenz_benettin):
    # measured 0.909 (0.937 after the first 200 intervals): the statistical spread at 200 time units is a few %
    assert lorenz_benettin.exponent == pytest.approx(LORENZ_EXPONENT, abs=0.05)
    assert lorenz_benettin.running.shape == (400,) and lorenz_benettin.times[-1] == pytest.approx(20.0 + 410 * 0.5)


def test_benettin_lorenz_standard_error_covers_the_known_value(lorenz_benettin):
    """The batch-means standard error is a usable error bar: the published exponent lies within
    3 of them. It is well below the naive one: a stretch beyond the average is followed by a
    shorter one (ln d's fluctuations are bounded and telescope), which the batches see."""
    se = lorenz_benettin.standard_error
    rates = lorenz_benettin.log_stretch / 0.5
    assert 0.0 < se < 0.1
    assert abs(lorenz_benettin.exponent - LORENZ_EXPONENT) < 3.0 * se
    assert se < 0.5 * np.std(rates, ddof=1) / np.sqrt(rates.size)


def test_batch_means_standard_error_of_independent_and_correlated_series():
    """Against the exact variance of the mean: i.i.d. normal (sigma^2 / K) and AR(1),
    x_k = phi x_(k-1) + e_k, whose long-run variance is sigma_e^2 / (1 - phi)^2; averaged over seeds."""
    rng = np.random.default_rng(5)
    k = 400
    iid = np.mean([batch_means_standard_error(rng.normal(0.0, 2.0, k)) ** 2 for _ in range(400)])
    assert iid / (4.0 / k) == pytest.approx(1.0, abs=0.12)
    phi, k = 0.6, 2500
    ratios = []
    for _ in range(200):
        noise = rng.normal(size=k + 200)
        series = np.empty_like(noise)
        series[0] = noise[0]
        for i in range(1, series.size):
            series[i] = phi * series[i - 1] + noise[i]
        ratios.append(batch_means_standard_error(series[200:]) ** 2 / (1.0 / (1.0 - phi) ** 2 / k))
    assert np.mean(ratios) == pytest.approx(1.0, abs=0.15)
    assert np.isnan(batch_means_standard_error([1.0, 2.0, 3.0]))
    assert batch_means_standard_error(np.full(50, 7.0)) == 0.0


def test_benettin_ueda_oscillator():
    """x'' + 0.05 x' + x^3 = 7.5 cos t (Ueda, J. Stat. Phys. 20 (1979) 181-196; one of Sprott's examples,
    Chaos and Time-Series Analysis, 2003): lambda_1 = 0.0999 per unit time (the spectrum 0.0999, 0, -0.1499,
    whose sum is -0.05 = -damping, from a Gram-Schmidt RK4 computation published with the system).
    300 drive periods, rtol = atol = 1e-8, d0 = 1e-6: four initial conditions gave 0.089 .. 0.097 (the
    spread of the finite-time estimate), hence the 15 % band."""
    flow = OdeFlow(lambda t, y: np.array([y[1], -0.05 * y[1] - y[0] ** 3 + 7.5 * np.cos(t)]), rtol=1e-8, atol=1e-8)
    result = benettin_exponent(
        flow, [2.5, 0.0], renormalisation_time=2 * np.pi, n_intervals=300, separation=1e-6, transient_time=100 * np.pi
    )
    assert result.exponent == pytest.approx(0.0999, rel=0.15)


def test_benettin_forced_linear_oscillator_gives_minus_zeta_omega():
    """Separations of x'' + 2 zeta w x' + w^2 x = F cos(W t) obey the homogeneous equation: both
    exponents are -zeta w (underdamped), whatever the forcing. rtol = 1e-10, atol = 1e-14."""
    zeta, omega = 0.04, 3.0
    rhs = lambda t, y: np.array([y[1], -2 * zeta * omega * y[1] - omega**2 * y[0] + 5.0 * np.cos(1.7 * t)])
    flow = OdeFlow(rhs, rtol=1e-10, atol=1e-14)
    result = benettin_exponent(flow, [0.3, 0.0], renormalisation_time=1.0, n_intervals=150, separation=1e-6)
    # sum of ln(d_k / d0) telescopes to -zeta w T + ln(|M u_T| / |M u_0|), M the map to the mode's
    # coordinates (w x, v): the bracket is at most ln(w / 1) = ln 3, so |error| <= ln 3 / T (measured 0.0017)
    assert result.exponent == pytest.approx(-zeta * omega, abs=np.log(omega) / 150.0)


def test_benettin_limit_cycle_gives_zero():
    """Van der Pol oscillator (mu = 1): on the stable limit cycle lambda_1 = 0 (the phase direction)."""
    mu = 1.0
    flow = OdeFlow(lambda t, y: np.array([y[1], mu * (1 - y[0] ** 2) * y[1] - y[0]]), rtol=1e-10, atol=1e-12)
    result = benettin_exponent(flow, [2.0, 0.0], renormalisation_time=1.0, n_intervals=300, separation=1e-7, transient_time=50.0)
    # the estimate decays like (bounded fluctuation of ln d) / T, T = 300
    assert abs(result.exponent) < 0.01


class SpinningBody:
    """Torque-free rigid body, state (quaternion x, y, z, w; body angular velocity): a state with a unit
    quaternion, whose separation is the tangent-space difference (log map) and perturbation the exp map."""

    def __init__(self, inertia: np.ndarray) -> None:
        self.inertia = inertia

    def rhs(self, t, y):
        q, w = y[:4], y[4:]
        i1, i2, i3 = self.inertia
        dw = np.array([(i2 - i3) * w[1] * w[2] / i1, (i3 - i1) * w[2] * w[0] / i2, (i1 - i2) * w[0] * w[1] / i3])
        x, yq, z, s = q  # dq/dt = q (x) (w, 0) / 2, scalar last
        dq = 0.5 * np.array([s * w[0] + yq * w[2] - z * w[1], s * w[1] + z * w[0] - x * w[2], s * w[2] + x * w[1] - yq * w[0], -(x * w[0] + yq * w[1] + z * w[2])])
        return np.concatenate([dq, dw])

    def advance(self, state, t0, t1):
        y = solve_ivp(self.rhs, (t0, t1), state, method="DOP853", rtol=1e-11, atol=1e-13).y[:, -1]
        return np.concatenate([y[:4] / np.linalg.norm(y[:4]), y[4:]])

    def separation(self, reference, other):
        relative = Rotation.from_quat(reference[:4]).inv() * Rotation.from_quat(other[:4])
        return np.concatenate([relative.as_rotvec(), other[4:] - reference[4:]])

    def distance(self, reference, other):
        return float(np.linalg.norm(self.separation(reference, other)))

    def perturb(self, state, direction, size):
        step = size * direction / np.linalg.norm(direction)
        rotation = Rotation.from_quat(state[:4]) * Rotation.from_rotvec(step[:3])
        return np.concatenate([rotation.as_quat(), state[4:] + step[3:]])


def test_benettin_on_a_quaternion_state_with_tangent_space_geometry():
    """Spin Omega about the intermediate axis (I1 > I2 > I3): the linearised Euler equations grow at
    lambda = Omega sqrt((I1 - I2)(I2 - I3) / (I1 I3)); the reference stays on the steady spin exactly."""
    inertia = np.array([3.0, 2.0, 1.2])
    spin = 1.5
    body = SpinningBody(inertia)
    assert isinstance(body, Flow)
    state = np.concatenate([Rotation.from_rotvec([0.3, -0.2, 0.9]).as_quat(), [0.0, spin, 0.0]])
    result = benettin_exponent(body, state, renormalisation_time=0.5, n_intervals=100, separation=1e-9, n_alignment=10)
    expected = spin * np.sqrt((inertia[0] - inertia[1]) * (inertia[1] - inertia[2]) / (inertia[0] * inertia[2]))
    # finite-time bias: a bounded ln-term over T = 50 (measured -0.00098, i.e. -0.049 / T; -0.0024 at T = 20)
    assert result.exponent == pytest.approx(expected, abs=0.1 / 50.0)
    assert np.linalg.norm(result.final_state[:4]) == pytest.approx(1.0, abs=1e-12)


def test_benettin_bad_arguments():
    flow = OdeFlow(lorenz)
    with pytest.raises(AnalysisError, match="renormalisation_time=0.0 must be positive"):
        benettin_exponent(flow, [1, 1, 1], renormalisation_time=0.0, n_intervals=10, separation=1e-7)
    with pytest.raises(AnalysisError, match="flow must provide advance, separation, distance and perturb"):
        benettin_exponent(object(), [1, 1, 1], renormalisation_time=1.0, n_intervals=10, separation=1e-7)

    class Frozen(EuclideanFlow):
        def advance(self, state, t0, t1):
            return np.zeros_like(state)

    with pytest.raises(AnalysisError, match="separation became 0.0 at t=1"):
        benettin_exponent(Frozen(), [1.0, 2.0], renormalisation_time=1.0, n_intervals=3, separation=1e-3)


@pytest.fixture(scope="module")
def lorenz_series():
    # rtol = atol = 1e-9 on the solver's own non-uniform steps; 100 time units after a transient of 50
    solution = solve_ivp(lorenz, (0.0, 150.0), [-3.0, 2.0, 20.0], method="DOP853", rtol=1e-9, atol=1e-9)
    keep = solution.t > 50.0
    return solution.t[keep], solution.y[0, keep]


def test_rosenstein_lorenz_x(lorenz_series, lorenz_benettin):
    """Rosenstein et al. 1993 on x(t) sampled at 0.01: m = 5, default delay and Theiler window, fit over
    the linear region k dt in [0.5, 2.5]. Measured 0.936: within 5 % of the reference (3.4 %) and of Benettin (3 %)."""
    t, x = lorenz_series
    out = ANALYSES["lyapunov_rosenstein"](
        t=t, signal=x, sample_interval=0.01, embedding_dimension=5, n_steps=300, fit_start=50, fit_end=250
    )
    assert float(out["exponent"]) == pytest.approx(LORENZ_EXPONENT, rel=0.05)
    assert float(out["exponent"]) == pytest.approx(lorenz_benettin.exponent, rel=0.05)
    assert out["divergence"].shape == (301,) and int(out["n_pairs"]) > 9000
    # the divergence grows in the fitted range and is then close to saturation
    assert np.all(np.diff(out["divergence"][50:251]) > 0.0)


def test_rosenstein_periodic_signal_gives_zero():
    t = np.linspace(0.0, 100.0, 10001)
    x = np.sin(1.3 * t) + 0.5 * np.sin(2.6 * t + 0.4)
    out = rosenstein_exponent(t, x, sample_interval=0.01, embedding_dimension=3, n_steps=300, fit_start=0, fit_end=300)
    assert abs(float(out["exponent"])) < 0.01


def test_rosenstein_bad_arguments(lorenz_series):
    t, x = lorenz_series
    with pytest.raises(AnalysisError, match=r"fit range \[fit_start=10, fit_end=500\]"):
        rosenstein_exponent(t, x, sample_interval=0.01, n_steps=300, fit_start=10, fit_end=500)
    with pytest.raises(AnalysisError, match="embedding_dimension=10 with delay=40 leaves -212 vectors of 148 samples"):
        rosenstein_exponent(t[:50], x[:50], sample_interval=0.01, embedding_dimension=10, delay=40)
