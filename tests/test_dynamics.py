"""Physics of the equations of motion: inverse dynamics, energy balance, KKT conventions."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from robot.model import constraints as C
from robot.dynamics import equations as D
from robot.model import kinematics as K
from robot.model.platform_kinematics import inverse_kinematics
from robot.run import build_run, run_scene


@pytest.fixture(scope="module")
def ideal_run():
    run = build_run("ideal", duration=0.25)
    return run, run_scene(run)


def test_ideal_driving_forces_equal_closed_loop_inverse_dynamics(ideal_run):
    """Simulated driving forces = inverse dynamics on the exact kinematics, to 1e-6 relative."""
    run, result = ideal_run
    assert result.success, result.message
    dynamics = run.dynamics
    workspace = D.make_workspace(dynamics)
    t = result["t"]
    for i in range(0, len(t), max(1, len(t) // 25)):
        pose, _, _ = dynamics.drive.pose(t[i])
        s, sd, sdd = dynamics.drive.drive(t[i])
        q = K.assemble(dynamics.constraints, inverse_kinematics(run.layout, pose)[0], s).q
        v = K.velocity_analysis(dynamics.constraints, q, sd)
        qdd = K.acceleration_analysis(dynamics.constraints, q, v, sdd)
        expected = D.inverse_dynamics_driving_forces(dynamics, workspace, q, v, qdd)
        assert np.max(np.abs(result["driving_force"][i] - expected)) <= 1e-6 * np.max(np.abs(expected))


def test_ideal_constraint_residual_stays_small(ideal_run):
    _, result = ideal_run
    assert result["constraint_residual"].max() < 1e-8


def test_ideal_end_effector_follows_prescribed_pose(ideal_run):
    run, result = ideal_run
    for i in range(0, len(result["t"]), 20):
        pose, rate, _ = run.dynamics.drive.pose(result["t"][i])
        assert result["ee_position"][i][0] == pytest.approx(pose[0], abs=1e-9)
        assert result["ee_position"][i][2] == pytest.approx(pose[1], abs=1e-9)
        assert result["ee_velocity"][i][0] == pytest.approx(rate[0], abs=1e-7)


def test_kkt_solution_matches_dense_solve():
    """Pinocchio's forwardDynamics with our sign conventions = a dense KKT solve of paper eq. (24)."""
    run = build_run("compound")
    dynamics = run.dynamics
    model = run.mechanism.model
    workspace = D.make_workspace(dynamics)
    rng = np.random.default_rng(3)
    nq, nv = dynamics.nq, dynamics.nv
    q, v = run.y0[:nq], run.y0[nq : nq + nv] + 1e-3 * rng.normal(size=nv)
    onset = np.full(dynamics.n_candidates, 0.1)
    evaluation = D.evaluate(dynamics, workspace, 0.0, q, v, onset)
    data = model.createData()
    pin.computeAllTerms(model, data, q, v)
    pin.updateFramePlacements(model, data)
    mass = np.triu(data.M) + np.triu(data.M, 1).T
    phi_q = C.jacobian(dynamics.constraints, model, data)
    s, sd, sdd = dynamics.drive.drive(0.0)
    phi = C.residual(dynamics.constraints, data, q, s)
    phi_dot = phi_q @ v - C.velocity_rhs(dynamics.constraints, sd)
    alpha, beta = dynamics.baumgarte.alpha, dynamics.baumgarte.beta
    rhs = C.gamma(dynamics.constraints, model, data, sdd) - 2 * alpha * phi_dot - beta**2 * phi
    m = phi_q.shape[0]
    kkt = np.block([[mass, phi_q.T], [phi_q, np.zeros((m, m))]])
    solution = np.linalg.solve(kkt, np.concatenate([evaluation.generalized_contact_force - data.nle, rhs]))
    np.testing.assert_allclose(evaluation.qdd, solution[:nv], rtol=1e-8, atol=1e-8)
    np.testing.assert_allclose(evaluation.multipliers, solution[nv:], rtol=1e-7, atol=1e-6)


def _elastic_scene(tmp_path, duration: float) -> str:
    path = tmp_path / "elastic.toml"
    path.write_text(
        f"""
extends = "spherical"
name = "elastic"
duration = {duration}
[solver]
rtol = 1e-10
atol = 1e-12
max_step = 1e-3
[[clearance]]
joint = "S1"
type = "spherical"
material = "steel"
ball_radius = 0.015
clearance = 1.0e-4
restitution = 1.0
"""
    )
    return str(path)


def test_energy_balance_closes_and_elastic_impacts_do_no_work(tmp_path):
    """Delta(T + V) = W_act + W_contact; with ce = 1, no friction: zero contact work per impact."""
    run = build_run(_elastic_scene(tmp_path, 0.04))
    result = run_scene(run)
    assert result.success, result.message
    energy = result["kinetic_energy"] + result["potential_energy"]
    balance = energy - energy[0] - result["actuator_work"] - result["contact_work"]
    scale = max(np.abs(energy - energy[0]).max(), np.abs(result["actuator_work"]).max())
    assert np.abs(balance).max() < 1e-6 * scale
    t, penetration, work = result["t"], result["S1_penetration"][:, 0], result["contact_work"]
    onsets = result["event_t"][result["event_is_onset"]]
    completed = 0
    for t_on in onsets:
        start = np.searchsorted(t, t_on)
        after = np.flatnonzero((t > t_on) & (penetration <= 0))
        if not after.size:
            continue
        stored = np.abs(work[start : after[0]] - work[start]).max()
        assert abs(work[after[0]] - work[start]) < 1e-5 * max(stored, 1e-9)
        completed += 1
    assert completed >= 2, "the test needs completed impacts to check"
