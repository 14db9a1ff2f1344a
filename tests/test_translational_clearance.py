"""Translational (prismatic) clearance joint: corner-against-face geometry, forces and their physics.

Hand cases (slider centred, offset, tilted in the plane and out of it), the rate as
the time derivative of the penetration (finite differences along a rigid motion),
the force law (Hertz corner stiffness 4/3 E* sqrt(r)), action = reaction, invariance
under a superposed rigid motion, energy conservation of an impact with restitution 1
(an independent planar rigid-body integration), user-defined friction equal to the
built-in law, the prismatic centring constraints (Jacobian and gamma by finite
differences) and bad parameters named by key.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
from scipy.integrate import solve_ivp

from clearance_contact import (
    BrownMcPheeFriction,
    ContactParameterError,
    CoulombFriction,
    Material,
    NoFriction,
    PlanarTranslationalClearanceJoint,
    TranslationalClearanceJoint,
    joint_type,
    output_layout,
)
from clearance_contact.translational import _P_TABLE, _offsets

STEEL = Material(2.07e11, 0.3)
BRONZE = Material(1.1e11, 0.34)
ZERO = np.zeros(6)


def rot(axis: str, angle: float) -> np.ndarray:
    return pin.exp3({"x": np.array([1.0, 0, 0]), "y": np.array([0, 1.0, 0]), "z": np.array([0, 0, 1.0])}[axis] * angle)


def spatial(length=0.05, width=0.03, height=0.018, c_x=2e-4, c_y=3e-4, **kwargs):
    kwargs.setdefault("corner_radius", 1.5e-3)
    return TranslationalClearanceJoint(length, width, height, width + 2 * c_x, height + 2 * c_y, BRONZE, STEEL, **kwargs)


def planar(length=0.05, width=0.03, c_x=2e-4, **kwargs):
    kwargs.setdefault("corner_radius", 1.5e-3)
    return PlanarTranslationalClearanceJoint(length, width, width + 2 * c_x, BRONZE, STEEL, **kwargs)


def random_pose(rng, scale=1.0):
    return pin.exp3(rng.normal(size=3) * scale), rng.normal(size=3) * 0.3


def evaluate(law, guide, slider, guide_twist=ZERO, slider_twist=ZERO, onset=None):
    onset = np.full(law.N_CANDIDATES, 0.5) if onset is None else onset
    return law.evaluate(guide[0], guide[1], guide_twist, slider[0], slider[1], slider_twist, onset)


def relative(guide, rotation, position):
    """The slider pose whose pose in the guide frame is (rotation, position)."""
    return guide[0] @ rotation, guide[1] + guide[0] @ position


# --------------------------------------------------------------------------- geometry by hand


def test_output_layout_of_the_kernel_is_the_common_layout():
    for k in (4, 16):
        layout = output_layout(k, 2)
        names = ("PENETRATION_RATE", "NORMAL_FORCE", "NORMAL", "POINT_OUTER", "POINT_INNER", "FRICTION_FORCE", "ECCENTRICITY", "WRENCH_OUTER", "WRENCH_INNER", "KIND")
        assert _offsets(k) == tuple(layout[n] for n in names)
    assert spatial().output_size == output_layout(16, 2)["OUTPUT_SIZE"]
    assert joint_type("translational") is TranslationalClearanceJoint
    assert joint_type("planar_translational") is PlanarTranslationalClearanceJoint


def test_centred_slider_has_the_clearance_on_every_face():
    rng = np.random.default_rng(1)
    law = spatial()
    guide = random_pose(rng)
    for slide in (0.0, 0.37, -2.0):  # anywhere along the guide
        contact = evaluate(law, guide, relative(guide, np.eye(3), np.array([0, 0, slide])))
        expected = np.where(np.arange(16) % 2 == 0, -2e-4, -3e-4)  # width faces, height faces
        np.testing.assert_allclose(contact.penetration, expected, atol=1e-15)
        assert not contact.normal_force.any() and not contact.wrench_inner.any()
        np.testing.assert_allclose(law.candidate_clearances(), -expected)


@pytest.mark.parametrize("kind", ["spatial", "planar"])
def test_offset_beyond_the_clearance_penetrates_the_corners_on_that_face_by_offset_minus_clearance(kind):
    law = spatial() if kind == "spatial" else planar()
    rng = np.random.default_rng(2)
    guide = random_pose(rng)
    e = 2e-4 + 7e-6
    contact = evaluate(law, guide, relative(guide, np.eye(3), np.array([e, 0.0, 0.011])))
    table = law.kernel_parameters[_P_TABLE:].reshape(-1, 5)
    width_face = table[:, 3] == 0
    plus = width_face & (table[:, 4] > 0)
    np.testing.assert_allclose(contact.penetration[plus], e - 2e-4, rtol=1e-7)
    np.testing.assert_allclose(contact.penetration[width_face & ~plus], -e - 2e-4, rtol=1e-12)
    assert plus.sum() == (4 if kind == "spatial" else 2)
    assert np.all(contact.normal_force[plus] > 0) and not contact.normal_force[~plus].any()
    # the normals are the guide's +x axis; the force on the slider pushes it back (-x)
    np.testing.assert_allclose(contact.normal[plus], np.tile(guide[0][:, 0], (plus.sum(), 1)), atol=1e-15)
    np.testing.assert_allclose(guide[0].T @ contact.wrench_inner[:3], [-contact.normal_force.sum(), 0, 0], atol=1e-9)


def test_in_plane_tilt_penetrates_two_diagonally_opposite_corners_by_the_exact_value():
    """Tilt theta about the guide's y axis: corners (+a, +L/2) and (-a, -L/2) reach (L/2) sin + a cos."""
    length, width, c_x = 0.05, 0.03, 2e-4
    for law in (spatial(length, width, c_x=c_x), planar(length, width, c_x=c_x)):
        a, half = width / 2, length / 2
        theta_contact = math.asin((a + c_x) / math.hypot(a, half)) - math.atan2(a, half)  # touching angle
        for theta in (0.5 * theta_contact, theta_contact * 1.01, theta_contact * 1.3):
            guide = (rot("z", 0.4) @ rot("x", -1.1), np.array([0.2, -0.1, 0.5]))
            contact = evaluate(law, guide, relative(guide, rot("y", theta), np.array([0.0, 0.0, -0.03])))
            expected = half * math.sin(theta) + a * math.cos(theta) - (a + c_x)
            table = law.kernel_parameters[_P_TABLE:].reshape(-1, 5)
            diagonal = (table[:, 3] == 0) & (np.sign(table[:, 0]) == np.sign(table[:, 2]))
            np.testing.assert_allclose(contact.penetration[diagonal], expected, atol=1e-16)
            other = (table[:, 3] == 0) & ~diagonal
            np.testing.assert_allclose(contact.penetration[other], -half * math.sin(theta) + a * math.cos(theta) - (a + c_x), atol=1e-16)
            assert (contact.normal_force[diagonal] > 0).all() == (expected > 0)
        # the opposite forces of a jammed slider make a couple about y opposing the tilt, no net force
        force, moment = guide[0].T @ contact.wrench_inner[:3], guide[0].T @ contact.wrench_inner[3:]
        assert abs(force[0]) < 1e-9 * contact.normal_force.max() and moment[1] < 0


def test_out_of_plane_tilt_and_offset_reach_the_height_faces():
    """Tilt about the guide's x axis by -phi: corners (.., +b, +L/2) reach (L/2) sin phi + b cos phi on +y."""
    law = spatial()
    length, height, c_y = 0.05, 0.018, 3e-4
    phi = 0.02
    guide = (np.eye(3), np.zeros(3))
    contact = evaluate(law, guide, relative(guide, rot("x", -phi), np.array([0.0, 1e-5, 0.0])))
    table = law.kernel_parameters[_P_TABLE:].reshape(-1, 5)
    top_front = (table[:, 3] == 1) & (table[:, 1] > 0) & (table[:, 2] > 0)
    expected = length / 2 * math.sin(phi) + height / 2 * math.cos(phi) + 1e-5 - (height / 2 + c_y)
    np.testing.assert_allclose(contact.penetration[top_front], expected, atol=1e-16)
    assert expected > 0 and top_front.sum() == 2


def test_penetration_is_the_signed_distance_of_each_corner_to_its_face_for_random_poses():
    """An independent computation: corners from the box's vertices, faces as planes (point, normal)."""
    rng = np.random.default_rng(3)
    law = spatial()
    length, width, height, c_x, c_y = 0.05, 0.03, 0.018, 2e-4, 3e-4
    for _ in range(20):
        guide = random_pose(rng)
        slider = relative(guide, pin.exp3(rng.normal(size=3) * 0.01), np.array([*rng.normal(size=2) * 2e-4, rng.normal()]))
        contact = evaluate(law, guide, slider)
        got = law.penetration(guide[0], guide[1], slider[0], slider[1])
        np.testing.assert_array_equal(got, contact.penetration)
        for c in range(16):
            i, face = divmod(c, 2)
            signs = np.array([1 if i % 2 == 0 else -1, 1 if i % 4 < 2 else -1, 1 if i < 4 else -1])
            corner = slider[1] + slider[0] @ (signs * [width / 2, height / 2, length / 2])
            normal = signs[face] * guide[0][:, face]
            on_face = guide[1] + normal * ((width / 2 + c_x) if face == 0 else (height / 2 + c_y))
            assert contact.penetration[c] == pytest.approx(normal @ (corner - on_face), abs=1e-15)
            np.testing.assert_allclose(contact.point_inner[c], corner, atol=1e-15)
            np.testing.assert_allclose(contact.point_outer[c], corner - contact.penetration[c] * normal, atol=1e-15)


# --------------------------------------------------------------------------- rate, forces


def moved(pose, twist, dt):
    """Pose after moving with the constant world twist [v, w] of its origin for dt (exact rigid motion)."""
    rotation, position = pose
    w = twist[3:]
    # the origin follows v + w x (p - p0) about p0: a screw; rotation R(t) = exp(w t) R
    step = pin.exp3(w * dt)
    if np.linalg.norm(w) * abs(dt) < 1e-12:
        return step @ rotation, position + twist[:3] * dt
    # integrate the origin exactly: p' = v + w x (p - p0), with p - p0 = d(t)
    theta = np.linalg.norm(w) * dt
    k = w / np.linalg.norm(w)
    v = twist[:3]
    # d(t) = V(t) v with V the SO(3) left Jacobian times t
    K = pin.skew(k)
    V = dt * (np.eye(3) + (1 - math.cos(theta)) / theta * K + (theta - math.sin(theta)) / theta * K @ K)
    return step @ rotation, position + V @ v


def test_penetration_rate_is_the_time_derivative_of_the_penetration():
    rng = np.random.default_rng(4)
    for law in (spatial(), planar()):
        for _ in range(5):
            guide = random_pose(rng)
            slider = relative(guide, pin.exp3(rng.normal(size=3) * 0.01), np.array([*rng.normal(size=2) * 2e-4, 0.02]))
            tg, ts = rng.normal(size=6), rng.normal(size=6)
            contact = evaluate(law, guide, slider, tg, ts)
            h = 1e-6
            ahead = law.penetration(*moved(guide, tg, h), *moved(slider, ts, h))
            behind = law.penetration(*moved(guide, tg, -h), *moved(slider, ts, -h))
            np.testing.assert_allclose(contact.penetration_rate, (ahead - behind) / (2 * h), atol=1e-8, rtol=1e-6)


def test_corner_force_is_hertz_with_the_rounded_corner_stiffness():
    radius = 2.5e-3
    law = spatial(corner_radius=radius, restitution=0.7)
    e_star = 1.0 / ((1 - 0.3**2) / 2.07e11 + (1 - 0.34**2) / 1.1e11)
    k = 4.0 / 3.0 * e_star * math.sqrt(radius)
    assert law.stiffness == pytest.approx(k, rel=1e-14) and law.exponent == 1.5
    guide = (np.eye(3), np.zeros(3))
    previous = 0.0
    for depth in (-1e-7, 0.0, 1e-9, 1e-7, 4e-6):  # through the onset: continuous from 0
        contact = evaluate(law, guide, relative(guide, np.eye(3), np.array([2e-4 + depth, 0, 0])))
        assert contact.penetration[0] == pytest.approx(depth, abs=1e-17)
        expected = 4 * k * max(contact.penetration[0], 0.0) ** 1.5  # 4 corners on the +x face, at rest: no damping
        assert contact.normal_force.sum() == pytest.approx(expected, rel=1e-12, abs=1e-300)
        assert contact.normal_force.sum() >= previous
        previous = contact.normal_force.sum()
    # given stiffness and exponent instead
    law = planar(corner_radius=None, stiffness=3e8, exponent=1.2)
    contact = evaluate(law, guide, relative(guide, np.eye(3), np.array([-2e-4 - 3e-6, 0, 0])))
    assert contact.normal_force.sum() == pytest.approx(2 * 3e8 * (3e-6) ** 1.2, rel=1e-12)


def _in_contact_state(rng, law):
    guide = random_pose(rng)
    slider = relative(guide, rot("y", 0.012) @ pin.exp3(rng.normal(size=3) * 1e-3), np.array([1e-4, 2e-4, 0.01]))
    return guide, slider, rng.normal(size=6) * 0.2, rng.normal(size=6) * 0.2


@pytest.mark.parametrize("friction", [NoFriction(), BrownMcPheeFriction(0.15, 0.1, 1e-3), CoulombFriction(0.2, 1e-3)])
def test_action_equals_reaction_about_any_point(friction):
    rng = np.random.default_rng(5)
    for law in (spatial(friction=friction), planar(friction=friction)):
        guide, slider, tg, ts = _in_contact_state(rng, law)
        contact = evaluate(law, guide, slider, tg, ts)
        assert contact.normal_force.max() > 1.0
        fo, mo, fi, mi = contact.wrench_outer[:3], contact.wrench_outer[3:], contact.wrench_inner[:3], contact.wrench_inner[3:]
        scale = np.abs(fi).max()
        np.testing.assert_allclose(fo, -fi, atol=1e-12 * scale)
        point = rng.normal(size=3)
        total = mo + np.cross(guide[1] - point, fo) + mi + np.cross(slider[1] - point, fi)
        np.testing.assert_allclose(total, 0.0, atol=1e-12 * scale)
        # friction opposes the slip and lies in the face
        active = contact.normal_force > 0
        np.testing.assert_allclose(np.einsum("ij,ij->i", contact.friction_force, contact.normal)[active], 0.0, atol=1e-9 * scale)


def test_contact_is_invariant_under_a_superposed_rigid_motion():
    rng = np.random.default_rng(6)
    law = spatial(friction=BrownMcPheeFriction(0.15, 0.1, 1e-3))
    guide, slider, tg, ts = _in_contact_state(rng, law)
    base = evaluate(law, guide, slider, tg, ts)
    rotation, shift = pin.exp3(rng.normal(size=3)), rng.normal(size=3)
    v0, w0 = rng.normal(size=3), rng.normal(size=3)

    def transformed(pose, twist):
        position = rotation @ pose[1] + shift
        return (rotation @ pose[0], position), np.concatenate([rotation @ twist[:3] + v0 + np.cross(w0, position), rotation @ twist[3:] + w0])

    guide2, tg2 = transformed(guide, tg)
    slider2, ts2 = transformed(slider, ts)
    other = evaluate(law, guide2, slider2, tg2, ts2)
    np.testing.assert_allclose(other.penetration, base.penetration, atol=1e-15)
    np.testing.assert_allclose(other.penetration_rate, base.penetration_rate, atol=1e-12)
    np.testing.assert_allclose(other.normal_force, base.normal_force, rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(other.friction_force, base.friction_force @ rotation.T, rtol=1e-8, atol=1e-9)
    np.testing.assert_allclose(other.wrench_inner[:3], rotation @ base.wrench_inner[:3], rtol=1e-9, atol=1e-8)
    np.testing.assert_allclose(other.wrench_inner[3:], rotation @ base.wrench_inner[3:], rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(other.eccentricity, base.eccentricity, atol=1e-15)


def test_user_defined_friction_law_gives_the_built_in_result():
    class MyCoulomb(CoulombFriction):  # a subclass is not encoded: applied in Python by evaluate
        pass

    rng = np.random.default_rng(7)
    built_in, user = spatial(friction=CoulombFriction(0.2, 1e-3)), spatial(friction=MyCoulomb(0.2, 1e-3))
    assert built_in.friction_in_kernel and not user.friction_in_kernel
    state = _in_contact_state(rng, built_in)
    a, b = evaluate(built_in, *state), evaluate(user, *state)
    np.testing.assert_allclose(b.friction_force, a.friction_force, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(b.wrench_outer, a.wrench_outer, rtol=1e-12, atol=1e-10)
    assert np.abs(a.friction_force).max() > 0.1


# --------------------------------------------------------------------------- impact energy


def _planar_impact(restitution: float, theta0: float):
    """A free planar slider (x, z, theta in the guide's x-z plane) thrown at the +x face, tilted.

    Newton-Euler integrated here with scipy (no Pinocchio), the forces from the law's
    evaluate with the onset rate of each corner set when it starts touching.
    """
    law = planar(restitution=restitution)
    mass, inertia = 0.2, 0.2 * (0.05**2 + 0.03**2) / 12
    guide = (np.eye(3), np.zeros(3))
    onset = np.zeros(4)

    def forces(y):
        x, z, theta, vx, vz, w = y
        rotation = rot("y", theta)
        twist = np.array([vx, 0.0, vz, 0.0, w, 0.0])
        contact = evaluate(law, guide, (rotation, np.array([x, 0.0, z])), ZERO, twist, onset)
        return contact

    def rhs(t, y):
        wrench = forces(y).wrench_inner
        return [y[3], y[4], y[5], wrench[0] / mass, wrench[2] / mass, wrench[4] / inertia]

    y = np.array([0.0, 0.0, theta0, 0.4, 0.3, 0.5])  # moving toward +x, spinning
    energy = lambda y: 0.5 * mass * (y[3] ** 2 + y[4] ** 2) + 0.5 * inertia * y[5] ** 2
    start, t, free_energies, impacts = energy(y), 0.0, [], 0
    while t < 3e-3:
        pen = law.penetration(np.eye(3), np.zeros(3), rot("y", y[2]), np.array([y[0], 0.0, y[1]]))
        rates = forces(y).penetration_rate
        fresh = (pen > 0) & (onset == 0)
        impacts += int(fresh.any() and not (onset > 0).any())
        onset[fresh] = np.maximum(rates[fresh], 1e-4)
        onset[pen <= 0] = 0.0
        if impacts and not (pen > 0).any():
            free_energies.append(energy(y))  # in flight after an impact
        step = solve_ivp(rhs, (t, t + 1e-5), y, method="DOP853", rtol=1e-11, atol=1e-14)
        y, t = step.y[:, -1], t + 1e-5
    return impacts, start, np.array(free_energies)


def test_impact_with_restitution_one_and_no_friction_conserves_energy():
    impacts, before, in_flight = _planar_impact(1.0, 0.004)
    assert impacts >= 2 and in_flight.size > 50  # bounced between the two faces
    np.testing.assert_allclose(in_flight, before, rtol=1e-7)
    impacts, before, in_flight = _planar_impact(0.6, 0.004)
    assert impacts >= 1 and in_flight[-1] < 0.9 * before  # the L-N hysteresis dissipates


# --------------------------------------------------------------------------- bad parameters


@pytest.mark.parametrize(
    "kwargs, key",
    [
        ({"slider_length": -0.01}, "slider_length"),
        ({"guide_width": 0.02}, "guide_width"),
        ({"guide_height": 0.018}, "guide_height"),
        ({"stiffness": 1e9}, "stiffness"),  # and corner_radius: ambiguous
        ({"corner_radius": None}, "corner_radius"),  # no stiffness at all
        ({"exponent": 1.2}, "exponent"),  # Hertz corner needs 1.5
        ({"corner_radius": 0.0}, "corner_radius"),
        ({"restitution": 0.0}, "restitution"),
        ({"slider_material": 3.0}, "slider_material"),
    ],
)
def test_bad_parameters_name_the_key(kwargs, key):
    arguments = dict(slider_length=0.05, slider_width=0.03, slider_height=0.018, guide_width=0.0304, guide_height=0.0186,
                     slider_material=BRONZE, guide_material=STEEL, corner_radius=1e-3)  # fmt: skip
    arguments.update(kwargs)
    with pytest.raises(ContactParameterError, match=key):
        TranslationalClearanceJoint(**arguments)


# --------------------------------------------------------------------------- prismatic sites


def test_a_prismatic_tree_joint_becomes_a_free_joint_with_guide_aligned_element_frames():
    from robot.data import shipped_urdf
    from robot.model.mechanism import build_mechanism

    ideal = build_mechanism(shipped_urdf("slider_crank.urdf"))
    mechanism = build_mechanism(shipped_urdf("slider_crank.urdf"), {"slider": "parent"})
    assert mechanism.model.nv == ideal.model.nv + 5
    (site,) = mechanism.clearance_sites
    assert site.kind == "prismatic" and site.replaces == "joint"
    data = mechanism.model.createData()
    pin.framesForwardKinematics(mechanism.model, data, pin.neutral(mechanism.model))
    guide = data.oMf[site.outer_frame]
    np.testing.assert_allclose(guide.rotation[:, 2], [1, 0, 0], atol=1e-15)  # guide axis = the joint axis (world x)
    np.testing.assert_allclose(guide.rotation[:, 0], [0, 1, 0], atol=1e-15)  # width direction in the plane
    with pytest.raises(Exception, match="actuated"):
        build_mechanism(shipped_urdf("slider_crank.urdf"), {"crank": "child"})


def test_prismatic_centring_rows_jacobian_and_gamma_by_finite_differences():
    """Phi_q v = d/dt Phi and gamma = -d2/dt2 Phi along q(t) = integrate(q, t v) (zero joint acceleration)."""
    from robot.data import shipped_urdf
    from robot.model import constraints as C
    from robot.model.mechanism import build_mechanism

    mechanism = build_mechanism(shipped_urdf("slider_crank.urdf"), {"slider": "parent"})
    model = mechanism.model
    constraints = C.constraint_set(mechanism, driven=False, centre_clearance=True)
    assert constraints.row_labels[-5:] == ("slider:x", "slider:y", "slider:rot_x", "slider:rot_y", "slider:rot_z")
    rng = np.random.default_rng(8)
    q = pin.randomConfiguration(model, -np.ones(model.nq), np.ones(model.nq))
    v = rng.normal(size=model.nv)
    data = model.createData()

    def phi(t):
        pin.framesForwardKinematics(model, data, pin.integrate(model, q, t * v))
        return C.residual(constraints, data, q, None)

    pin.computeJointJacobians(model, data, q)
    pin.updateFramePlacements(model, data)
    jacobian = C.jacobian(constraints, model, data)
    pin.forwardKinematics(model, data, q, v, np.zeros(model.nv))
    pin.updateFramePlacements(model, data)
    gamma = C.gamma(constraints, model, data, None)
    h = 1e-4
    rows = slice(-5, None)
    np.testing.assert_allclose((jacobian @ v)[rows], ((phi(h) - phi(-h)) / (2 * h))[rows], atol=1e-7)
    np.testing.assert_allclose(gamma[rows], (-(phi(h) - 2 * phi(0.0) + phi(-h)) / h**2)[rows], atol=1e-5, rtol=1e-5)
    assert np.abs(phi(0.0)[rows]).min() > 1e-3  # a generic pose: the rows are not trivially zero


def test_scene_type_must_fit_the_joint_and_bad_keys_are_named(tmp_path):
    from robot.errors import SceneError
    from robot.scene.loader import load_scene

    text = (Path(__file__).resolve().parents[1] / "robot" / "scene" / "scenes" / "slider_crank_translational.toml").read_text()
    (tmp_path / "revolute_site.toml").write_text(text.replace('joint = "slider"', 'joint = "crank_rod"'))
    with pytest.raises(SceneError, match=r"type='translational' cannot replace 'crank_rod', a revolute joint .* use type = .*'revolute'"):
        load_scene(tmp_path / "revolute_site.toml")
    (tmp_path / "wrong_type.toml").write_text(text.replace('type = "translational"', 'type = "revolute"'))
    with pytest.raises(SceneError, match="unknown key"):
        load_scene(tmp_path / "wrong_type.toml")
    (tmp_path / "zero_gap.toml").write_text(text.replace("width_clearance = 2.0e-4", "width_clearance = 0.0"))
    with pytest.raises(SceneError, match="width_clearance"):
        load_scene(tmp_path / "zero_gap.toml")
    (tmp_path / "both.toml").write_text(text.replace("corner_radius = 1.0e-3", "corner_radius = 1.0e-3\nstiffness = 1e9"))
    with pytest.raises(SceneError, match="stiffness"):
        load_scene(tmp_path / "both.toml")


@pytest.mark.parametrize("model", ["lankarani_nikravesh", "hunt_crossley", "gonthier", "flores", "hu_guo"])
def test_corner_force_follows_the_chosen_dissipation_model(model):
    """A compressing corner: F_N = K delta^n (1 + chi(c_e) delta_dot / delta_dot0) with the model's chi."""
    from clearance_contact.dissipation import dissipation_factor

    law = planar(stiffness=2.0e9, corner_radius=None, exponent=1.5, restitution=0.6, dissipation=model)
    guide = (np.eye(3), np.zeros(3))
    e = 2e-4 + 5e-6  # 5 um into the +x width face
    speed = 0.03  # m/s towards the face
    contact = evaluate(law, guide, relative(guide, np.eye(3), np.array([e, 0.0, 0.0])), slider_twist=np.array([speed, 0, 0, 0, 0, 0]), onset=np.full(4, 0.1))
    touching = contact.penetration > 0.0
    assert touching.sum() == 2 and law.dissipation == model
    delta = contact.penetration[touching]
    expected = 2.0e9 * delta**1.5 * (1.0 + dissipation_factor(model, 0.6) * speed / 0.1)
    np.testing.assert_allclose(contact.normal_force[touching], expected, rtol=1e-12)
