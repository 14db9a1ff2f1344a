"""The resting initial state of clearance joints (``[initial] clearance_state = "resting"``).

Physics checked: the resting pose transmits exactly the ideal joint's load at the
static penetration (Hertz sphere: ``delta = (|F| / K)^(1/n)``, analytic), for
loads, sizes, materials and poses the code was not written around; the offset
centring rows' Jacobian is the finite difference of their residual; in the
4-UPS/RPS the first contact force after a resting start stays near the static
load while a centred start's first impact is many times larger.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from clearance_contact import BrownMcPheeFriction, Material, RevoluteClearanceJoint, SphericalClearanceJoint
from clearance_contact.materials import hertz_sphere_stiffness
from robot.errors import SceneError
from robot.model import constraints as C
from robot.model.kinematics import update_kinematics
from robot.model.resting_state import TOLERANCE, ideal_reactions, resting_pose
from robot.run import build_run, run_scene
from robot.scene.loader import load_scene

STEEL = Material(2.0e11, 0.3)
BRONZE = Material(1.1e11, 0.34)


def _placement(rng: np.random.Generator) -> pin.SE3:
    return pin.SE3(pin.exp3(rng.normal(size=3)), rng.normal(size=3))


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_sphere_rests_at_the_hertz_static_penetration_opposite_the_load(seed):
    rng = np.random.default_rng(seed)
    ball, clearance = rng.uniform(0.004, 0.05), rng.uniform(1e-5, 5e-4)
    law = SphericalClearanceJoint(ball, ball + clearance, STEEL, BRONZE, friction=BrownMcPheeFriction(0.1, 0.08, 1e-3))
    outer = _placement(rng)
    load = np.concatenate([rng.normal(size=3) * 10.0 ** rng.uniform(0, 4), np.zeros(3)])
    pose = resting_pose(law, "spherical", outer, outer, load, tilt_free=True)
    stiffness = hertz_sphere_stiffness(ball + clearance, ball, BRONZE, STEEL)
    force = np.linalg.norm(load[:3])
    assert pose.penetration[0] == pytest.approx((force / stiffness) ** (1 / 1.5), rel=1e-6)
    displacement = outer.rotation @ pose.translation  # world axes
    assert np.linalg.norm(displacement) == pytest.approx(clearance + pose.penetration[0], rel=1e-9)
    np.testing.assert_allclose(displacement / np.linalg.norm(displacement), -load[:3] / force, atol=1e-9)


@pytest.mark.parametrize("seed", [3, 4])
def test_journal_rests_with_the_load_and_moment_of_the_ideal_joint(seed):
    """Radial, axial and tilting load at once: the law's wrench on the journal equals it."""
    rng = np.random.default_rng(seed)
    radius, c_r, c_a = rng.uniform(0.01, 0.04), rng.uniform(3e-5, 2e-4), rng.uniform(5e-5, 2e-4)
    length = radius * rng.uniform(1.0, 4.0)
    law = RevoluteClearanceJoint(radius, radius + c_r, 1.8 * radius, length + c_a, length, STEEL, STEEL)
    outer = _placement(rng)
    axes = outer.rotation
    force = axes @ np.array([rng.normal() * 800, rng.normal() * 800, rng.normal() * 100])
    moment = axes @ np.array([rng.normal() * 20, rng.normal() * 20, 0.0])
    load = np.concatenate([force, moment])
    pose = resting_pose(law, "revolute", outer, outer, load, tilt_free=True)
    inner = pin.SE3(outer.rotation @ pin.exp3(np.array([*pose.tilt, 0.0])), outer.translation + axes @ pose.translation)
    contact = law.evaluate(outer.rotation, outer.translation, np.zeros(6), inner.rotation, inner.translation, np.zeros(6), np.zeros(4))
    np.testing.assert_allclose(contact.wrench_inner[:3], force, atol=10 * TOLERANCE * np.linalg.norm(force))
    normal_moment = axes[:, :2].T @ contact.wrench_inner[3:]
    np.testing.assert_allclose(normal_moment, axes[:, :2].T @ moment, atol=1e-6 * np.linalg.norm(moment))
    # in contact: the deepest candidate penetrates (by micrometres: elastic, not an interference)
    assert 0.0 < pose.penetration.max() < 0.2 * c_r


def test_offset_centring_rows_jacobian_is_the_derivative_of_their_residual():
    run = build_run(load_scene("compound").with_changes({"initial.clearance_state": "centred"}))
    mechanism = run.mechanism
    model, nq = mechanism.model, mechanism.model.nq
    offsets = {"S1": np.array([3e-5, -4e-5, 7e-5]), "R1": np.array([-6e-5, 2e-5, 1e-5])}
    rotations = {"R1": pin.exp3(np.array([1e-3, -2e-3, 0.0]))}
    constraints = C.constraint_set(mechanism, centre_clearance=True, misalignment=rotations, offsets=offsets)
    data = model.createData()
    q = run.y0[:nq]
    update_kinematics(model, data, q)
    jacobian = C.jacobian(constraints, model, data)
    step = 1e-7
    numeric = np.empty_like(jacobian)
    for k in range(model.nv):
        dv = np.zeros(model.nv)
        dv[k] = step
        values = []
        for sign in (1.0, -1.0):
            qk = pin.integrate(model, q, sign * dv)
            update_kinematics(model, data, qk)
            values.append(C.residual(constraints, data, qk, np.zeros(mechanism.n_actuators)))
        numeric[:, k] = (values[0] - values[1]) / (2 * step)
    np.testing.assert_allclose(jacobian, numeric, atol=1e-6)


def _first_peak(state: str):
    scene = load_scene("compound").with_changes({"initial.clearance_state": state, "duration": 0.03})
    run = build_run(scene)
    result = run_scene(run)
    assert result.success, result.message
    return result


def test_resting_start_has_no_impact_and_starts_at_the_static_penetration():
    resting, centred = _first_peak("resting"), _first_peak("centred")
    for joint in ("R1", "S1"):
        force = resting[f"{joint}_normal_force"].sum(axis=1)
        assert force[0] > 0.0  # already carrying the load at t = 0
        # the load changes with the motion, but no impact: within 50 % of the initial load
        assert force.max() < 1.5 * force[0]
        assert centred[f"{joint}_normal_force"].sum(axis=1).max() > 3.0 * force.max()
    # S1: the initial contact force is the ideal joint's reaction (from the centred, ideal state's
    # multipliers), the initial penetration the Hertz static one of that force
    run = build_run(load_scene("compound").with_changes({"initial.clearance_state": "centred"}))
    nq = run.mechanism.model.nq
    centring = C.constraint_set(run.mechanism, centre_clearance=True)
    load = ideal_reactions(centring, run.y0[:nq], run.y0[nq:], run.dynamics.drive.drive(0.0)[2])["S1"]
    force0 = resting["S1_normal_force"][0, 0]
    assert force0 == pytest.approx(np.linalg.norm(load[:3]), rel=1e-3)
    stiffness = hertz_sphere_stiffness(0.0151, 0.015, STEEL, STEEL)
    assert resting["S1_penetration"][0, 0] == pytest.approx((np.linalg.norm(load[:3]) / stiffness) ** (1 / 1.5), rel=1e-3)


def test_bad_clearance_state_names_the_key():
    with pytest.raises(SceneError, match="clearance_state='floating'.*centred.*resting"):
        load_scene("compound").with_changes({"initial.clearance_state": "floating"})
