"""Kinematics of the 4-UPS/RPS: assembly, constraint derivatives, velocity and acceleration
analysis, inverse kinematics, actuation Jacobian and the kinematic errors.

Every check compares against an independent computation (finite differences on the
configuration manifold, the platform pose put in, leg geometry recomputed from frame
placements), so a wrong sign, frame or factor makes it fail.
"""

from __future__ import annotations

import math
import re
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

from robot.model import constraints as C
from robot.model import kinematics as K
from robot.model.description import parse_mechanism
from robot.errors import SingularConfigurationError, StrokeLimitError, UnreachablePoseError
from robot.model.mechanism import build_mechanism
from robot.model.platform_kinematics import (
    PlatformLayout,
    actuation_jacobian,
    condition_number,
    cross,
    euler_zyx,
    inverse_kinematics,
    leg_kinematics,
    platform_state,
)
from robot.model.trajectory import reference_platform_motion
from robot.model.ups_rps_design import UpsRpsDesign, ups_rps_urdf

ROOT = Path(__file__).resolve().parents[1]
URDF = ROOT / "urdf" / "ups_rps.urdf"
HOME = np.array([0.0, 1.2, 0.0, 0.0, 0.0])
CHOICES = [None, "S1", "R1", "R1,S1"]
#: sample times along the reference trajectory (period 1 s)
TIMES = np.linspace(0.0, 1.0, 16, endpoint=False) + 0.013


@pytest.fixture(scope="module")
def ideal():
    mechanism = build_mechanism(URDF)
    return mechanism, PlatformLayout.from_mechanism(mechanism)


@pytest.fixture(scope="module", params=CHOICES, ids=lambda c: c or "ideal")
def any_choice(request):
    mechanism = build_mechanism(URDF, clearance=request.param)
    return mechanism, PlatformLayout.from_mechanism(mechanism)


def _platform_frame(mechanism) -> int:
    return mechanism.model.getFrameId("platform", pin.FrameType.BODY)


def _sphere_gaps(mechanism, data) -> np.ndarray:
    """Distances between each piston origin and its platform attachment point, recomputed
    from the frame placements (independent of ``constraints.residual``)."""
    model = mechanism.model
    platform = data.oMf[_platform_frame(mechanism)]
    gaps = []
    for closure in mechanism.description.closures:
        piston = data.oMf[model.getFrameId(closure.parent.link, pin.FrameType.BODY)]
        gaps.append(np.linalg.norm(piston.act(np.array(closure.parent.xyz)) - platform.act(np.array(closure.child.xyz))))
    return np.array(gaps)


def _random_tangent(model, rng, scale):
    return scale * rng.standard_normal(model.nv)


# --------------------------------------------------------------------------- assembly and IK


def test_assembly_along_reference_trajectory_from_perturbed_guess(ideal):
    """Closures close to 1e-10 m and the platform lands on the pose put into the IK."""
    mechanism, layout = ideal
    model = mechanism.model
    data = model.createData()
    trajectory = reference_platform_motion(layout)
    constraints = C.constraint_set(mechanism)
    rng = np.random.default_rng(1)
    worst_gap = worst_pose = 0.0
    for t in TIMES:
        pose, _, _ = trajectory.pose(t)
        q_ik, legs = inverse_kinematics(layout, pose)
        guess = pin.integrate(model, q_ik, _random_tangent(model, rng, 0.02))
        assembly = K.assemble(constraints, guess, legs.lengths)
        pin.framesForwardKinematics(model, data, assembly.q)
        worst_gap = max(worst_gap, _sphere_gaps(mechanism, data).max())
        state = platform_state(layout, pose)
        placement = data.oMf[_platform_frame(mechanism)]
        worst_pose = max(
            worst_pose,
            np.abs(placement.translation - state.position).max(),
            np.abs(placement.rotation - euler_zyx(*pose[2:])).max(),
        )
        np.testing.assert_allclose(assembly.q[mechanism.actuator_q_index], legs.lengths, atol=1e-12)
    assert worst_gap <= 1e-10
    assert worst_pose <= 1e-10


def test_inverse_kinematics_closes_every_loop_and_keeps_the_plane(any_choice):
    """The IK configuration satisfies every closure (and, with clearance, the centred joint)."""
    mechanism, layout = any_choice
    model = mechanism.model
    data = model.createData()
    trajectory = reference_platform_motion(layout)
    constraints = C.constraint_set(mechanism, driven=False, centre_clearance=True)
    for t in TIMES[::3]:
        pose, _, _ = trajectory.pose(t)
        q, legs = inverse_kinematics(layout, pose)
        K.update_kinematics(model, data, q)
        assert np.abs(C.residual(constraints, data, q, None)).max() < 1e-12
        assert _sphere_gaps(mechanism, data).max() < 1e-12
        # the RPS tip (platform origin, centre of S1) stays in the plane y = 0 normal to R1
        assert abs(data.oMf[_platform_frame(mechanism)].translation[1]) < 1e-12
        # the actuator coordinate is the hinge-to-hinge length
        np.testing.assert_allclose(q[mechanism.actuator_q_index], legs.lengths, atol=1e-14)


def test_inverse_kinematics_with_r1_clearance_off_the_origin():
    """A clearance free-flyer replacing R1 is placed relative to its joint origin, like R1.

    (Regression: the free-flyer coordinates used to include the joint placement twice,
    which moved the RPS limb by the R1 origin offset.)
    """
    text = URDF.read_text()
    moved, count = re.subn(
        r'(<joint name="R1" type="revolute">\s*<parent link="base"/>\s*<child link="limb5_cylinder"/>\s*<origin xyz=")0 0 0"',
        r'\g<1>0 0 0.1"',
        text,
    )
    assert count == 1
    description = parse_mechanism(moved, is_text=True)
    pose = np.array([0.01, 1.2, 0.02, 0.03, 0.0])
    pistons = []
    for choice in (None, "R1"):
        mechanism = build_mechanism(description, clearance=choice)
        layout = PlatformLayout.from_mechanism(mechanism)
        q, legs = inverse_kinematics(layout, pose)
        assert legs.lengths[4] == pytest.approx(math.dist((0.0, 0.0, 0.1), platform_state(layout, pose).position))
        data = mechanism.model.createData()
        K.update_kinematics(mechanism.model, data, q)
        assert _sphere_gaps(mechanism, data).max() < 1e-12
        pistons.append(data.oMf[mechanism.model.getFrameId("limb5_piston", pin.FrameType.BODY)].homogeneous)
    np.testing.assert_allclose(pistons[0], pistons[1], atol=1e-12)


# --------------------------------------------------------------------------- derivatives


def _state_for(mechanism, layout, seed):
    """A configuration near (not on) the assembled home pose, and a velocity."""
    model = mechanism.model
    rng = np.random.default_rng(seed)
    q, _ = inverse_kinematics(layout, np.array([0.02, 1.22, 0.03, -0.02, 0.05]))
    q = pin.integrate(model, q, _random_tangent(model, rng, 0.05))
    return q, _random_tangent(model, rng, 1.0)


def _constraints_with_centring(mechanism):
    misalignment = {"R1": pin.exp3(np.array([0.3, -0.1, 0.05]))} if "R1" in mechanism.clearance_names else None
    return C.constraint_set(mechanism, driven=True, centre_clearance=True, misalignment=misalignment)


def _phi(constraints, model, data, q, drive):
    pin.framesForwardKinematics(model, data, q)
    return C.residual(constraints, data, q, drive)


def _phi_q(constraints, model, data, q):
    K.update_kinematics(model, data, q)
    return C.jacobian(constraints, model, data)


def test_constraint_jacobian_matches_finite_differences_on_the_manifold(any_choice):
    """Phi_q e_i = d/deps Phi(integrate(q, eps e_i)), closures, centring (misaligned) and drivers."""
    mechanism, layout = any_choice
    model = mechanism.model
    data = model.createData()
    constraints = _constraints_with_centring(mechanism)
    q, _ = _state_for(mechanism, layout, 2)
    drive = np.full(mechanism.n_actuators, 1.2)
    analytic = _phi_q(constraints, model, data, q)
    eps = 1e-6
    numeric = np.empty_like(analytic)
    for i in range(model.nv):
        step = np.zeros(model.nv)
        step[i] = eps
        numeric[:, i] = (
            _phi(constraints, model, data, pin.integrate(model, q, step), drive)
            - _phi(constraints, model, data, pin.integrate(model, q, -step), drive)
        ) / (2 * eps)
    assert constraints.n_rows == mechanism.n_closure_equations + sum(
        3 if s.kind == "spherical" else 5 for s in mechanism.clearance_sites
    ) + mechanism.n_actuators
    assert np.abs(analytic).max() > 0.5  # not trivially zero
    assert np.abs(analytic - numeric).max() < 1e-8


def test_gamma_matches_derivative_of_jacobian_times_velocity(any_choice):
    """gamma = -(d/dt Phi_q) v along q(t) = integrate(q, t v) (qdd = 0 in Pinocchio's convention)."""
    mechanism, layout = any_choice
    model = mechanism.model
    data = model.createData()
    constraints = _constraints_with_centring(mechanism)
    q, v = _state_for(mechanism, layout, 3)
    pin.forwardKinematics(model, data, q, v, np.zeros(model.nv))
    pin.computeJointJacobians(model, data, q)
    pin.updateFramePlacements(model, data)
    analytic = C.gamma(constraints, model, data, np.zeros(mechanism.n_actuators))
    eps = 1e-6
    numeric = (
        _phi_q(constraints, model, data, pin.integrate(model, q, eps * v)) @ v
        - _phi_q(constraints, model, data, pin.integrate(model, q, -eps * v)) @ v
    ) / (2 * eps)
    rows = slice(0, constraints.n_closure_rows)
    assert np.abs(analytic[rows]).max() > 0.1
    assert np.abs(analytic[rows] + numeric[rows]).max() < 1e-6 * max(1.0, np.abs(analytic).max())


# --------------------------------------------------------------------------- velocity and acceleration


def _log_rotation(rotation):
    return pin.log3(rotation)


def test_velocity_and_acceleration_analysis_reproduce_the_platform_motion(any_choice):
    """Platform twist and acceleration from the joint-space analyses equal the trajectory's,
    and the trajectory's own velocity equals finite differences of its pose."""
    mechanism, layout = any_choice
    model = mechanism.model
    data = model.createData()
    frame = _platform_frame(mechanism)
    trajectory = reference_platform_motion(layout)
    constraints = C.constraint_set(mechanism, driven=True, centre_clearance=True)
    assert constraints.n_rows == model.nv  # clearance centred: square system, unique solution
    worst_v = worst_a = worst_fd = 0.0
    h = 1e-5
    for t in TIMES[::2]:
        pose, rate, accel = trajectory.pose(t)
        state = platform_state(layout, pose, rate, accel)
        q, _ = inverse_kinematics(layout, pose)  # its leg solution is for zero rates
        lengths, rates, accelerations = trajectory.drive(t)
        q = K.assemble(constraints, q, lengths).q
        v = K.velocity_analysis(constraints, q, rates)
        a = K.acceleration_analysis(constraints, q, v, accelerations)
        pin.forwardKinematics(model, data, q, v, a)
        pin.updateFramePlacements(model, data)
        twist = pin.getFrameVelocity(model, data, frame, C.LWA)
        acc = pin.getFrameClassicalAcceleration(model, data, frame, C.LWA)
        worst_v = max(worst_v, np.abs(twist.linear - state.velocity).max(), np.abs(twist.angular - state.angular_velocity).max())
        worst_a = max(
            worst_a,
            np.abs(acc.linear - state.acceleration).max(),
            np.abs(acc.angular - state.angular_acceleration).max(),
        )
        # independent: the platform state's velocity against finite differences of the pose
        before = platform_state(layout, trajectory.pose(t - h)[0])
        after = platform_state(layout, trajectory.pose(t + h)[0])
        omega_fd = _log_rotation(after.rotation @ before.rotation.T) / (2 * h)
        worst_fd = max(
            worst_fd,
            np.abs((after.position - before.position) / (2 * h) - state.velocity).max(),
            np.abs(omega_fd - state.angular_velocity).max(),
        )
    assert worst_v < 1e-10
    assert worst_a < 1e-8
    assert worst_fd < 1e-7


def test_platform_angular_acceleration_matches_finite_differences(ideal):
    _, layout = ideal
    trajectory = reference_platform_motion(layout)
    h = 1e-5
    for t in TIMES[::4]:
        states = [platform_state(layout, *trajectory.pose(s)) for s in (t - h, t, t + h)]
        np.testing.assert_allclose(
            (states[2].angular_velocity - states[0].angular_velocity) / (2 * h), states[1].angular_acceleration, atol=1e-6
        )
        np.testing.assert_allclose((states[2].velocity - states[0].velocity) / (2 * h), states[1].acceleration, atol=1e-6)


def test_cross_product_is_numpys_bit_for_bit_for_vectors_and_stacks():
    """The drive's cross product (Python floats for two 3-vectors, numpy for stacks) gives ``np.cross``'s bits and
    dtype, is antisymmetric, over magnitudes from 1e-6 to 1e6, lists, and broadcast stacks."""

    def same_bits(left, right):
        expected = np.cross(left, right)
        found = cross(left, right)
        return found.dtype == expected.dtype and found.shape == expected.shape and np.array_equal(found.view(np.uint64), expected.view(np.uint64))

    rng = np.random.default_rng(7)
    for _ in range(2000):
        a, b = (rng.normal(size=3) * 10.0 ** rng.uniform(-6, 6) for _ in range(2))
        assert same_bits(a, b)
        assert np.array_equal(cross(b, a), -cross(a, b))
    stack, vector = rng.normal(size=(4, 3)), rng.normal(size=3)
    for left, right in ((vector, stack), (stack, vector), (stack, stack[::-1]), (vector, vector[None, :]), (vector[None, :], vector)):
        assert same_bits(left, right)
    assert same_bits([1.0, 0.0, 0.0], [0.0, 1.0, 0.0])
    assert cross([1, 2, 3], [4, 5, 6]).dtype == np.float64  # integers are taken as floats
    assert np.array_equal(cross([1.0, 0.0, 0.0], [0.0, 1.0, 0.0]), [0.0, 0.0, 1.0])


def test_platform_layout_constants_are_read_only(ideal):
    """The layout's drive constants are made once from its limbs: neither they nor the limbs' points can change."""
    _, layout = ideal
    np.testing.assert_array_equal(layout.platform_points, [limb.platform_point for limb in layout.limbs])
    np.testing.assert_array_equal(layout.base_points, [limb.base_point for limb in layout.limbs])
    axis = layout.limbs[layout.plane_limb].revolute_axis
    np.testing.assert_allclose(layout.plane_normal, axis / np.linalg.norm(axis), rtol=0, atol=1e-16)
    for array in (layout.platform_points, layout.base_points, layout.plane_normal, layout.limbs[0].base_point, layout.limbs[0].platform_point):
        with pytest.raises(ValueError):
            array[0] = 1.0


# --------------------------------------------------------------------------- actuation


def test_actuator_rates_match_finite_differences_and_actuation_jacobian(ideal):
    """Exact actuator rates: = d/dt of the lengths, and = J [xd, zd, w L_c]."""
    _, layout = ideal
    trajectory = reference_platform_motion(layout)
    h = 1e-5
    worst_rate = worst_acc = worst_jac = 0.0
    for t in np.linspace(0.0, 1.0, 41):
        lengths, rates, accelerations = trajectory.drive(t)
        before, after = trajectory.drive(t - h), trajectory.drive(t + h)
        worst_rate = max(worst_rate, np.abs((after[0] - before[0]) / (2 * h) - rates).max())
        worst_acc = max(worst_acc, np.abs((after[1] - before[1]) / (2 * h) - accelerations).max())
        pose, rate, accel = trajectory.pose(t)
        state = platform_state(layout, pose, rate, accel)
        legs = leg_kinematics(layout, state)
        jacobian = actuation_jacobian(layout, legs)
        twist = np.concatenate([[rate[0], rate[1]], state.angular_velocity * layout.characteristic_length])
        worst_jac = max(worst_jac, np.abs(jacobian @ twist - rates).max())
    assert worst_rate < 1e-8
    assert worst_acc < 1e-7
    assert worst_jac < 1e-12


def test_reference_trajectory_stays_well_conditioned_and_inside_the_strokes(ideal):
    mechanism, layout = ideal
    trajectory = reference_platform_motion(layout)
    conditions, lengths, rates, accelerations = [], [], [], []
    for t in np.linspace(0.0, 1.0, 401):
        legs = leg_kinematics(layout, platform_state(layout, *trajectory.pose(t)))
        conditions.append(condition_number(layout, legs))
        lengths.append(legs.lengths)
        rates.append(legs.rates)
        accelerations.append(legs.accelerations)
    lengths = np.array(lengths)
    assert max(conditions) < 20.0
    # numbers stated in robot/trajectory.py's docstring and docs/kinematics.md
    assert 1.18 <= lengths.min() and lengths.max() <= 1.30
    assert 12.3 <= min(conditions) and max(conditions) <= 13.0
    assert np.abs(rates).max() <= 0.38 and np.abs(accelerations).max() <= 4.1
    assert np.all(lengths >= mechanism.stroke_lower) and np.all(lengths <= mechanism.stroke_upper)


# --------------------------------------------------------------------------- mobility


@pytest.mark.parametrize(
    ("choice", "free", "driven"), [(None, 5, 0), ("S1", 8, 3), ("R1", 10, 5), ("R1,S1", 13, 8)], ids=["ideal", "S1", "R1", "R1,S1"]
)
def test_mobility_matches_grubler_kutzbach(choice, free, driven):
    """nv - rank(Phi_q) at an assembled pose = 6*15 - (constraints) (docs/kinematics.md)."""
    from robot.model.summary import grubler_kutzbach

    mechanism = build_mechanism(URDF, clearance=choice)
    layout = PlatformLayout.from_mechanism(mechanism)
    q, _ = inverse_kinematics(layout, np.array([0.02, 1.25, 0.03, -0.02, 0.05]))
    q = K.assemble(C.constraint_set(mechanism, driven=False), q).q
    assert K.mobility(C.constraint_set(mechanism, driven=False), q) == free
    assert K.mobility(C.constraint_set(mechanism, driven=True), q) == driven
    assert grubler_kutzbach(mechanism) == (free, driven)


# --------------------------------------------------------------------------- errors


def test_unreachable_pose_raises_stroke_limit_error(ideal):
    _, layout = ideal
    with pytest.raises(StrokeLimitError, match=r"pose \[0\.0, 3\.0, .*actuator P1 length 3\.02\d+ m is outside its stroke \[0\.98, 1\.55\] m; the pose is outside the workspace"):
        inverse_kinematics(layout, np.array([0.0, 3.0, 0.0, 0.0, 0.0]))


def test_malformed_pose_raises_unreachable_pose_error(ideal):
    _, layout = ideal
    with pytest.raises(UnreachablePoseError, match="pose must be 5 finite numbers"):
        inverse_kinematics(layout, np.array([0.0, np.nan, 0.0, 0.0, 0.0]))
    with pytest.raises(UnreachablePoseError, match="pose must be 5 finite numbers"):
        inverse_kinematics(layout, np.array([0.0, 1.2, 0.0]))


def test_assembly_with_drive_outside_the_strokes_names_the_actuator(ideal):
    mechanism, layout = ideal
    q, legs = inverse_kinematics(layout, HOME)
    drive = legs.lengths.copy()
    drive[2] = 1.7
    with pytest.raises(StrokeLimitError, match=r"actuator P3: length 1\.7 m is outside its stroke \[0\.98, 1\.55\] m"):
        K.assemble(C.constraint_set(mechanism), q, drive)


def test_incompatible_actuator_lengths_do_not_assemble(ideal):
    mechanism, layout = ideal
    q, _ = inverse_kinematics(layout, HOME)
    with pytest.raises(UnreachablePoseError, match=r"assembly did not converge.*cannot be met from the initial guess"):
        K.assemble(C.constraint_set(mechanism), q, np.array([0.98, 0.98, 0.98, 0.98, 1.55]))


def _design_mechanism(tmp_path, design):
    path = tmp_path / "design.urdf"
    path.write_text(ups_rps_urdf(design))
    mechanism = build_mechanism(path)
    return mechanism, PlatformLayout.from_mechanism(mechanism)


class _UniformOffsets(UpsRpsDesign):
    """Every platform point rotated by the same angle from its base point."""

    signs = (1.0, 1.0, 1.0, 1.0)

    def ups_platform_points(self):
        return [
            (
                self.platform_radius * math.cos(math.radians(a + sign * self.platform_angle_offset_deg)),
                self.platform_radius * math.sin(math.radians(a + sign * self.platform_angle_offset_deg)),
                0.0,
            )
            for a, sign in zip(self.base_angles_deg, self.signs)
        ]


class _AlternatingOffsets(_UniformOffsets):
    signs = (1.0, -1.0, 1.0, -1.0)


@pytest.mark.parametrize(
    "design",
    [UpsRpsDesign(platform_angle_offset_deg=0.0), _UniformOffsets(), _AlternatingOffsets()],
    ids=["legs-through-vertical-axis", "uniform-offsets", "alternating-offsets"],
)
def test_singular_layout_raises_singular_configuration_error(tmp_path, design):
    """MODEL-NOTES 1, singularity trap: the home pose of these layouts has a rank-deficient
    actuation Jacobian (the platform can turn with all leg rates zero)."""
    mechanism, layout = _design_mechanism(tmp_path, design)
    _, legs = inverse_kinematics(layout, HOME, check=False)
    singular_values = np.linalg.svd(actuation_jacobian(layout, legs), compute_uv=False)
    assert singular_values[-1] < 1e-12 * singular_values[0]
    with pytest.raises(SingularConfigurationError, match=r"condition number \d\.\d+e\+\d+ exceeds 1e\+06.*singular"):
        inverse_kinematics(layout, HOME)
    # the reference layout (offsets +35, +35, -35, -35 deg) is regular at the same pose
    reference = PlatformLayout.from_mechanism(build_mechanism(URDF))
    assert condition_number(reference, inverse_kinematics(reference, HOME)[1]) < 15.0
