"""Benettin's largest Lyapunov exponent driven through the simulator (robot.analysis.simulator_flow).

Known answers:

* the driven damped pendulum of Baker & Gollub (*Chaotic Dynamics: An
  Introduction*, 2nd ed., Cambridge 1996, Ch. 3-5),
  ``theta'' + theta' / q + sin(theta) = g cos(omega_D tau)`` in the time
  ``tau = omega_0 t``, built as a one-joint URDF with physical (not unit)
  parameters (mass 1.7 kg, centre of mass 0.35 m from the axis, its own
  inertia): a ``joint_torque`` (harmonic) and a ``joint_spring_damper``
  (stiffness 0). Against the same pendulum as a plain ODE with the separately
  validated :class:`~robot.analysis.lyapunov_benettin.OdeFlow`: the per-interval
  stretches agree while the two reference trajectories coincide (before chaos
  amplifies their integration differences); the exponent of the chaotic
  pendulum (q = 4, g = 1.5, omega_D = 2/3) against the ODE's long-run value;
  the period-1 attractor (q = 2, g = 0.9) against ``-1 / (2 q)``: on a stable
  periodic orbit with a complex pair of Floquet multipliers both exponents are
  equal and sum to the trace of the flow's Jacobian, ``-1 / q``.
* a free, damped, closed-loop (overconstrained) four-bar, oscillating about the
  equilibrium set by a crank spring: the real part of the root of
  ``m_r s^2 + c_r s + k_r`` with ``m_r = N^T M N`` etc. on the constraints' null
  space ``N`` (the linearised reduced system); the perturbation satisfies the
  closures.
* the registered ``lyapunov_benettin`` through the sweep engine (two runs),
  equal to the direct call.
"""

from __future__ import annotations

import math
import warnings
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
from scipy.linalg import null_space

from robot import load_scene, simulate
from robot.analysis import ANALYSES, AnalysisError
from robot.analysis.lyapunov_benettin import OdeFlow, benettin_exponent
from robot.analysis.simulator_flow import SimulatorFlow, characteristic_length, translational_coordinates
from robot.errors import RedundantConstraintWarning
from robot.model import constraints as C
from robot.model.kinematics import update_kinematics
from robot.run import build_run

DATA = Path(__file__).parent / "data"

# the pendulum's physical parameters: bob of 1.7 kg, centre of mass 0.35 m below the axis, 0.02 kg m^2 about it
MASS, LEVER, OWN_INERTIA, GRAVITY = 1.7, 0.35, 0.02, 9.81
INERTIA = OWN_INERTIA + MASS * LEVER**2
OMEGA_0 = math.sqrt(MASS * GRAVITY * LEVER / INERTIA)  # rad/s; the dimensionless time is omega_0 t
DRIVE_FREQUENCY = 2.0 / 3.0  # omega_D, in units of omega_0
THETA_0 = 0.2  # rad, initial angle (at rest)

#: the chaotic pendulum's exponent (per unit of omega_0 t): the ODE (OdeFlow, DOP853 rtol 1e-9) over 3000 drive periods
#: from theta = 0.2 at rest; Baker & Gollub's value for this pendulum is about 0.15
CHAOTIC_EXPONENT = 0.1625
#: standard deviation of the 60-period exponent over the attractor (50 disjoint windows of the same ODE run)
CHAOTIC_SPREAD_60 = 0.0156


def pendulum_scene(directory: Path, q: float, g: float, name: str = "pendulum") -> Path:
    """The Baker-Gollub pendulum as a URDF and a scene (DOP853, rtol 1e-9)."""
    (directory / "pendulum.urdf").write_text(
        f"""<?xml version="1.0"?>
<robot name="pendulum">
  <link name="support"/>
  <link name="bob">
    <inertial><origin xyz="0 0 {-LEVER}"/><mass value="{MASS}"/>
      <inertia ixx="{OWN_INERTIA}" ixy="0" ixz="0" iyy="{OWN_INERTIA}" iyz="0" izz="0.001"/></inertial>
  </link>
  <joint name="swing" type="revolute">
    <parent link="support"/><child link="bob"/><origin xyz="0 0 0"/><axis xyz="0 1 0"/>
    <limit lower="-1e6" upper="1e6" effort="0" velocity="1e6"/>
  </joint>
</robot>
"""
    )
    drive_rate = DRIVE_FREQUENCY * OMEGA_0  # rad/s
    path = directory / f"{name}.toml"
    path.write_text(
        f"""name = "{name}"
mechanism = "pendulum.urdf"
end_effector = "bob"
duration = 1.0
gravity = [0.0, 0.0, {-GRAVITY}]

[actuators]
swing = {{ mode = "none" }}

[[force]]
name = "drive"                       # g cos(omega_D tau), in N m
type = "joint_torque"
joint = "swing"
function = "harmonic"
amplitude = {g * MASS * GRAVITY * LEVER!r}
frequency = {drive_rate / (2 * math.pi)!r}
phase = {math.pi / 2!r}

[[force]]
name = "damper"                      # theta' / q, in N m s/rad
type = "joint_spring_damper"
joint = "swing"
stiffness = 0.0
damping = {INERTIA * OMEGA_0 / q!r}

[initial]
positions = {{ swing = {THETA_0} }}

[solver]
method = "DOP853"
rtol = 1e-9
atol = 1e-11
max_step = 1.0
"""
    )
    return path


def pendulum_ode(q: float, g: float) -> OdeFlow:
    return OdeFlow(lambda tau, x: np.array([x[1], -x[1] / q - math.sin(x[0]) + g * math.cos(DRIVE_FREQUENCY * tau)]), rtol=1e-10, atol=1e-12)


def drive_period() -> float:
    """The drive period in s."""
    return 2.0 * math.pi / (DRIVE_FREQUENCY * OMEGA_0)


@pytest.fixture(scope="module")
def chaotic_flow(tmp_path_factory) -> SimulatorFlow:
    # T = 1 / omega_0 makes the scaled state (theta, theta_dot / omega_0) the ODE's (theta, d theta / d tau)
    return SimulatorFlow(build_run(pendulum_scene(tmp_path_factory.mktemp("chaotic"), q=4.0, g=1.5)), time_scale=1.0 / OMEGA_0)


def test_pendulum_stretches_agree_with_the_ode_formulation(chaotic_flow):
    """Same start, same perturbation direction: ln(d_k / d0) of the simulator and of the ODE, interval by interval.

    Before chaos separates the two references (integration differences ~1e-10
    grown by e^{0.16 omega_0 t}), the stretches agree to ~1e-6 (measured
    1.5e-6 over the first five drive periods).
    """
    flow, n = chaotic_flow, 5
    assert flow.time_scale == pytest.approx(1.0 / OMEGA_0) and flow.length_scale == pytest.approx(LEVER)
    simulated = benettin_exponent(flow, flow.state([THETA_0, 0.0], 0.0), renormalisation_time=drive_period(), n_intervals=n, separation=1e-7, n_alignment=0)
    ode = benettin_exponent(pendulum_ode(4.0, 1.5), [THETA_0, 0.0], renormalisation_time=2 * math.pi / DRIVE_FREQUENCY, n_intervals=n, separation=1e-7, n_alignment=0)
    np.testing.assert_allclose(simulated.log_stretch, ode.log_stretch, rtol=0, atol=1e-5)  # 10 x the measured 1.5e-6
    assert simulated.exponent == pytest.approx(ode.exponent * OMEGA_0, rel=1e-6)  # 1/s against 1/(omega_0 t); measured 9e-9


def test_chaotic_pendulum_exponent(chaotic_flow):
    """60 drive periods: the ODE's long-run value within 3 standard deviations of the 60-period exponent."""
    flow = chaotic_flow
    result = benettin_exponent(flow, flow.state([THETA_0, 0.0], 0.0), renormalisation_time=drive_period(), n_intervals=60, separation=1e-7, n_alignment=3)
    exponent = result.exponent / OMEGA_0
    assert abs(exponent - CHAOTIC_EXPONENT) < 3 * CHAOTIC_SPREAD_60, exponent
    assert abs(exponent - 0.15) < 3 * CHAOTIC_SPREAD_60, exponent  # Baker & Gollub
    # the run's own error bar (batch means, 8 batches of 7 periods) estimates the window-to-window spread
    # measured independently over 50 windows; one estimate from 8 batches is good to ~ +-30 % (1 sigma)
    standard_error = result.standard_error / OMEGA_0
    assert 0.5 * CHAOTIC_SPREAD_60 < standard_error < 2.0 * CHAOTIC_SPREAD_60, standard_error


def test_periodic_pendulum_exponent_is_half_the_damping_trace(tmp_path):
    """Period-1 attractor (q = 2, g = 0.9): lambda = -1 / (2 q) = -0.25 (in omega_0 units)."""
    q = 2.0
    flow = SimulatorFlow(build_run(pendulum_scene(tmp_path, q=q, g=0.9)))  # default scales: L = lever, T = sqrt(L / g)
    period = drive_period()
    result = benettin_exponent(flow, flow.state([THETA_0, 0.0], 0.0), renormalisation_time=period, n_intervals=15, separation=1e-7, transient_time=15 * period)
    # the telescoped sum leaves a bounded term ln(kappa) / horizon; kappa ~ 3 for this orbit's Floquet vectors
    assert result.exponent / OMEGA_0 == pytest.approx(-1.0 / (2.0 * q), abs=math.log(3.0) / (15 * period * OMEGA_0))


def test_conservative_periodic_pendulum_exponent_is_about_zero(tmp_path):
    """An undamped, undriven pendulum swinging at 0.2 rad (a periodic orbit of a conservative system):
    no exponential divergence, only the shear of the amplitude-dependent period (a separation grows
    linearly), so the estimate goes to zero with the horizon: below 0.01 omega_0 over 40 swings
    (measured -0.0014) and smaller than over 10 (-0.0022)."""
    flow = SimulatorFlow(build_run(pendulum_scene(tmp_path, q=math.inf, g=0.0)))
    swing = 2.0 * math.pi / OMEGA_0  # small-amplitude period
    estimates = [
        benettin_exponent(flow, flow.state([THETA_0, 0.0], 0.0), renormalisation_time=swing, n_intervals=n, separation=1e-7, n_alignment=2).exponent / OMEGA_0
        for n in (10, 40)
    ]
    assert abs(estimates[1]) < 0.01 and abs(estimates[1]) < abs(estimates[0]), estimates


def free_four_bar(directory: Path, stiffness: float, crank_damping: float, rocker_damping: float) -> Path:
    path = directory / "four_bar.toml"
    path.write_text(
        f"""name = "free_four_bar"
mechanism = "{(DATA / 'four_bar.urdf').resolve()}"
end_effector = "rocker"
duration = 1.0
gravity = [0.0, 0.0, 0.0]

[actuators]
crank = {{ mode = "none" }}

[[force]]
name = "crank_spring"
type = "joint_spring_damper"
joint = "crank"
stiffness = {stiffness}
damping = {crank_damping}

[[force]]
name = "rocker_damper"
type = "joint_spring_damper"
joint = "rocker"
stiffness = 0.0
damping = {rocker_damping}

[initial]
positions = {{ crank = 0.0 }}

[solver]
method = "DOP853"
rtol = 1e-9
atol = 1e-11
max_step = 1.0
"""
    )
    return path


def test_damped_four_bar_exponent_and_projection(tmp_path):
    """Closed loop with redundant closure rows: the reduced linear system's decay rate; perturbations on the closures."""
    stiffness, crank_damping, rocker_damping = 0.8, 2e-3, 4e-3
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RedundantConstraintWarning)
        run = build_run(free_four_bar(tmp_path, stiffness, crank_damping, rocker_damping))
        model, data = run.mechanism.model, run.mechanism.model.createData()
        q0 = run.y0[: model.nq]
        update_kinematics(model, data, q0)
        basis = null_space(C.jacobian(run.dynamics.constraints, model, data))  # (3, 1): one degree of freedom
        mass = pin.crba(model, data, q0)
        mass = np.triu(mass) + np.triu(mass, 1).T
        damping, spring = np.zeros((3, 3)), np.zeros((3, 3))
        index = {name: model.idx_vs[model.getJointId(name)] for name in ("crank", "rocker")}
        damping[index["crank"], index["crank"]], damping[index["rocker"], index["rocker"]] = crank_damping, rocker_damping
        spring[index["crank"], index["crank"]] = stiffness
        m_r, c_r, k_r = (float((basis.T @ matrix @ basis)[0, 0]) for matrix in (mass, damping, spring))
        roots = np.roots([m_r, c_r, k_r])
        expected, oscillation = roots.real.max(), 2 * math.pi / np.abs(roots.imag).max()

        flow = SimulatorFlow(run)  # no gravity: T = period / (2 pi) of the (unused) trajectory table, 1 / (2 pi) s
        start = flow.state(run.y0, 0.0)
        other = flow.perturb(start, np.random.default_rng(3).standard_normal(6), 1e-6)
        update_kinematics(model, data, other[: model.nq])
        assert np.max(np.abs(C.residual(run.dynamics.constraints, data, other[: model.nq], None))) < 1e-12
        assert np.max(np.abs(C.jacobian(run.dynamics.constraints, model, data) @ other[model.nq : model.nq + model.nv])) < 1e-12
        assert flow.distance(start, other) == pytest.approx(1e-6, rel=1e-6)

        result = benettin_exponent(flow, start, renormalisation_time=oscillation / 2, n_intervals=12, separation=1e-6, n_alignment=0)
    # the bounded telescoping term vanishes on this pair; measured 1.3e-5 relative over 12 half oscillations
    assert result.exponent == pytest.approx(expected, rel=5e-5)


def test_scales_and_bad_input(chaotic_flow):
    model = chaotic_flow.model
    assert not translational_coordinates(model).any() and characteristic_length(model) == pytest.approx(LEVER)
    with pytest.raises(AnalysisError, match="direction has shape"):
        chaotic_flow.perturb(chaotic_flow.state([0.1, 0.0], 0.0), np.ones(3), 1e-6)
    with pytest.raises(AnalysisError, match="not at t0"):
        chaotic_flow.advance(chaotic_flow.state([0.1, 0.0], 0.0), 1.0, 2.0)
    with pytest.raises(AnalysisError, match="time_scale"):
        SimulatorFlow(chaotic_flow.run, time_scale=-1.0)
    result = simulate(chaotic_flow.run.scene, t_end=0.5)
    analysis = ANALYSES["lyapunov_benettin"]
    arrays = {name: result[name] for name in ("t", "q", "v", "onset_rates")}
    with pytest.raises(AnalysisError, match="separation=1e-09 is below 10 x"):
        analysis(run=chaotic_flow.run, **arrays, renormalisation_time=0.1, separation=1e-9)
    with pytest.raises(AnalysisError, match="needs the input"):
        analysis(**arrays, renormalisation_time=0.1)
    with pytest.raises(AnalysisError, match="t_start=9.0 is after"):
        analysis(run=chaotic_flow.run, **arrays, renormalisation_time=0.1, t_start=9.0)


SWEEP = """
[sweep]
scene = "pendulum.toml"
t_end = {t_end!r}

[[axis]]
key = "force.drive.amplitude"
name = "drive_amplitude"
values = {amplitudes!r}

[[analysis]]
name = "lyapunov_benettin"
label = "lyapunov"
renormalisation_time = {period!r}
n_intervals = 4
n_alignment = 1
separation = 1e-7
"""


def test_sweep_engine_runs_the_registered_analysis(tmp_path):
    """Two runs (g = 0.9 and 1.5) through the dask engine: the stored exponents equal the direct call's."""
    from robot.sweep import load_sweep, open_sweep, run_sweep

    pendulum_scene(tmp_path, q=2.0, g=0.9)
    period, t_end = drive_period(), 3 * drive_period()
    amplitudes = [g * MASS * GRAVITY * LEVER for g in (0.9, 1.5)]
    sweep = tmp_path / "sweep.toml"
    sweep.write_text(SWEEP.format(t_end=t_end, amplitudes=amplitudes, period=period))
    spec = load_sweep(sweep)
    run_sweep(spec, tmp_path / "out", workers=1, progress=False)  # one worker process: the engine, cheaper to start
    dataset = open_sweep(tmp_path / "out" / "sweep.zarr").load()
    assert list(dataset.status.values) == [0, 0]
    for k, amplitude in enumerate(amplitudes):
        run = build_run(load_scene(tmp_path / "pendulum.toml").with_changes({"force.drive.amplitude": amplitude, "duration": t_end}))
        result = simulate(run.scene)
        direct = ANALYSES["lyapunov_benettin"](
            run=run, **{name: result[name] for name in ("t", "q", "v", "onset_rates")}, renormalisation_time=period, n_intervals=4, n_alignment=1, separation=1e-7
        )
        stored = dataset.isel(drive_amplitude=k)
        assert float(stored.lyapunov_t_start) == pytest.approx(t_end)
        assert float(stored.lyapunov_exponent) == direct["exponent"]
        np.testing.assert_array_equal(stored.lyapunov_running.values, direct["running"])
