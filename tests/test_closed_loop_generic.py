"""Generality: the closure declarations, the clearance choice and the kinematics work for
closed-loop mechanisms other than the 4-UPS/RPS (tests/data/*.urdf):

* a spatial RSSR four-bar (two spherical closures): mobility 2 = crank + idle spin of
  the coupler about the line through its two ball centres;
* a planar slider-crank written spatially with a revolute closure: overconstrained,
  Grubler-Kutzbach gives -2 but the numerical mobility is 1.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

from robot.model import constraints as C
from robot.model import kinematics as K
from robot.model.description import parse_mechanism
from robot.errors import ClearanceChoiceError, UnreachablePoseError
from robot.model.mechanism import build_mechanism
from robot.model.platform_kinematics import PlatformLayout
from robot.model.summary import grubler_kutzbach, summarize

DATA = Path(__file__).resolve().parent / "data"
RSSR = DATA / "rssr.urdf"
SLIDER_CRANK = DATA / "slider_crank.urdf"
CRANK, ROD = 0.05, 0.12


def _assembled(mechanism, q_guess=None, drive=None):
    constraints = C.constraint_set(mechanism, driven=drive is not None, centre_clearance=True)
    guess = pin.neutral(mechanism.model) if q_guess is None else q_guess
    return K.assemble(constraints, guess, drive).q


def _world(mechanism, q, link, point):
    data = mechanism.model.createData()
    pin.framesForwardKinematics(mechanism.model, data, q)
    return data.oMf[mechanism.model.getFrameId(link, pin.FrameType.BODY)].act(np.asarray(point, dtype=float))


# --------------------------------------------------------------------------- RSSR


def test_rssr_loads_with_two_spherical_closures():
    mechanism = build_mechanism(RSSR)
    assert (mechanism.model.nq, mechanism.model.nv) == (9, 8)
    assert [(c.name, c.kind, c.n_equations) for c in mechanism.closures] == [("Sa", "spherical", 3), ("Sb", "spherical", 3)]
    assert mechanism.actuated_joints == ("crank",)
    assert mechanism.total_mass() == pytest.approx(12.5)


@pytest.mark.parametrize(
    ("choice", "nq", "nv", "free", "driven"),
    [(None, 9, 8, 2, 1), ("Sb", 9, 8, 5, 4), ("rocker", 15, 13, 7, 6)],
    ids=["ideal", "Sb-clearance", "rocker-clearance"],
)
def test_rssr_mobility(choice, nq, nv, free, driven):
    mechanism = build_mechanism(RSSR, clearance=choice)
    assert (mechanism.model.nq, mechanism.model.nv) == (nq, nv)
    q = _assembled(mechanism)
    assert K.mobility(C.constraint_set(mechanism, driven=False), q) == free
    assert K.mobility(C.constraint_set(mechanism, driven=True), q) == driven
    assert grubler_kutzbach(mechanism) == (free, driven)


def test_rssr_idle_spin_is_the_driven_null_space():
    """With the crank driven, the remaining motion is the coupler spinning about its own axis."""
    mechanism = build_mechanism(RSSR)
    model = mechanism.model
    q = _assembled(mechanism)
    data = model.createData()
    K.update_kinematics(model, data, q)
    phi_q = C.jacobian(C.constraint_set(mechanism), model, data)
    _, _, vt = np.linalg.svd(phi_q)
    null = vt[-1]
    assert np.abs(phi_q @ null).max() < 1e-12
    coupler = model.getJointId("coupler_free")
    twist = pin.Motion(null[model.idx_vs[coupler] : model.idx_vs[coupler] + 6])  # local frame
    world = data.oMi[coupler].act(twist)
    a, b = _world(mechanism, q, "crank", [0, 0.1, 0]), _world(mechanism, q, "rocker", [0, 0.2, 0])
    axis = (b - a) / np.linalg.norm(b - a)
    assert np.linalg.norm(np.cross(world.angular, axis)) < 1e-12  # rotation about the ball-ball line
    # world.linear is the velocity of the point at the world origin: the point a does not move
    np.testing.assert_allclose(world.linear + np.cross(world.angular, a), 0.0, atol=1e-12)
    assert np.linalg.norm(world.angular) > 0.1
    others = np.delete(null, range(model.idx_vs[coupler], model.idx_vs[coupler] + 6))
    np.testing.assert_allclose(others, 0.0, atol=1e-12)  # crank and rocker do not move


def test_rssr_driven_assembly_and_velocity_preserve_the_coupler_length():
    mechanism = build_mechanism(RSSR)
    model = mechanism.model
    constraints = C.constraint_set(mechanism)
    q = pin.neutral(model)
    length = np.hypot(0.4, 0.1)
    for angle in np.linspace(0.0, 2 * math.pi, 9):
        q = K.assemble(constraints, q, np.array([angle]), tolerance=1e-13).q
        a = _world(mechanism, q, "crank", [0, 0.1, 0])
        b = _world(mechanism, q, "rocker", [0, 0.2, 0])
        assert np.linalg.norm(b - a) == pytest.approx(length, abs=1e-12)
        np.testing.assert_allclose(a, [0, 0.1 * math.cos(angle), 0.1 * math.sin(angle)], atol=1e-12)
        # velocity: the ball-to-ball distance does not change (minimum-norm spin = 0)
        v = K.velocity_analysis(constraints, q, np.array([2.0]))
        data = model.createData()
        pin.forwardKinematics(model, data, q, v)
        pin.updateFramePlacements(model, data)
        va = pin.getFrameVelocity(model, data, mechanism.closures[0].frame_a, C.LWA).linear
        vb = pin.getFrameVelocity(model, data, mechanism.closures[1].frame_a, C.LWA).linear
        assert abs((b - a) @ (vb - va)) < 1e-12
        np.testing.assert_allclose(va, 2.0 * np.cross([1, 0, 0], a), atol=1e-12)


def test_rssr_clearance_on_the_actuated_crank_is_refused():
    with pytest.raises(ClearanceChoiceError, match=r"clearance joint 'crank' is actuated"):
        build_mechanism(RSSR, clearance="crank")


def test_rssr_is_not_a_platform():
    with pytest.raises(UnreachablePoseError, match=r"has no link 'platform'"):
        PlatformLayout.from_mechanism(build_mechanism(RSSR))


# --------------------------------------------------------------------------- slider-crank


def _slider_crank(axis: str):
    """The slider-crank of tests/data, or the same mechanism moving in the x-z plane (axes
    along world y; the revolute closure's axis is then not its frames' z axis)."""
    if axis == "z":
        return build_mechanism(SLIDER_CRANK)
    text = SLIDER_CRANK.read_text()
    for old, new in (('rpy="0 0 1.0471975511965976"', 'rpy="0 1.0471975511965976 0"'), ('rpy="0 0 -1.4"', 'rpy="0 -1.4 0"')):
        assert text.count(old) == 1
        text = text.replace(old, new)
    assert text.count('<axis xyz="0 0 1"/>') == 3
    return build_mechanism(parse_mechanism(text.replace('<axis xyz="0 0 1"/>', '<axis xyz="0 1 0"/>'), is_text=True))


@pytest.mark.parametrize("axis", ["z", "y"])
def test_slider_crank_is_overconstrained_but_movable(axis):
    mechanism = _slider_crank(axis)
    assert [(c.name, c.kind, c.n_equations) for c in mechanism.closures] == [("K", "revolute", 5)]
    summary = summarize(mechanism)
    assert (summary.grubler_free, summary.grubler_driven) == (-2, -3)
    assert (summary.mobility_free, summary.mobility_driven) == (1, 0)
    assert summary.rank_free == 2
    assert summary.configuration.startswith("assembled from the neutral configuration")


@pytest.mark.parametrize("axis", ["z", "y"])
def test_slider_crank_position_velocity_acceleration_match_the_closed_form(axis):
    """Slider position x = r cos(th) + sqrt(l^2 - r^2 sin^2 th) and its derivatives."""
    mechanism = _slider_crank(axis)
    model = mechanism.model
    constraints = C.constraint_set(mechanism)
    slider = model.idx_vs[model.getJointId("slider")]
    q = pin.neutral(model)
    omega, alpha = 3.0, -2.0
    for angle in np.linspace(-1.0, 5.0, 7):
        # the crank coordinate is measured from the joint origin's 60 deg
        theta = angle + math.pi / 3
        q = K.assemble(constraints, q, np.array([angle])).q
        v = K.velocity_analysis(constraints, q, np.array([omega]))
        a = K.acceleration_analysis(constraints, q, v, np.array([alpha]))
        s, c = math.sin(theta), math.cos(theta)
        root = math.sqrt(ROD**2 - CRANK**2 * s**2)
        x = CRANK * c + root
        dx_dth = -CRANK * s - CRANK**2 * s * c / root
        d2x_dth2 = -CRANK * c - CRANK**2 * (c * c - s * s) / root - CRANK**4 * s * s * c * c / root**3
        assert 0.14 + q[slider] == pytest.approx(x, abs=1e-12)
        assert v[slider] == pytest.approx(dx_dth * omega, abs=1e-11)
        assert a[slider] == pytest.approx(d2x_dth2 * omega**2 + dx_dth * alpha, abs=1e-10)


@pytest.mark.parametrize(
    ("choice", "nq", "nv", "kind", "free", "driven"),
    [("crank_rod", 9, 8, "JointModelFreeFlyer", 3, 2), ("K", 3, 3, "JointModelRZ", 3, 2)],
    ids=["tree-joint", "closure"],
)
def test_slider_crank_with_a_clearance_revolute(choice, nq, nv, kind, free, driven):
    """Clearance on the rod's revolute joint (free-flyer, +5 DOF) or on the revolute closure
    (not imposed); both leave the rod 3 DOF relative to the crank-slider system."""
    mechanism = build_mechanism(SLIDER_CRANK, clearance=choice)
    model = mechanism.model
    assert (model.nq, model.nv) == (nq, nv)
    assert model.joints[model.getJointId("crank_rod")].shortname() == kind
    site = mechanism.site(choice)
    assert site.kind == "revolute"
    q = _assembled(mechanism, drive=np.array([0.4]))
    assert K.mobility(C.constraint_set(mechanism, driven=False), q) == free
    assert K.mobility(C.constraint_set(mechanism, driven=True), q) == driven
    assert grubler_kutzbach(mechanism) == (free, driven)
    # assembled with the centring equations: the element frames coincide, z along the world z axis
    data = model.createData()
    pin.framesForwardKinematics(model, data, q)
    outer, inner = data.oMf[site.outer_frame], data.oMf[site.inner_frame]
    # (the rotation about the axis is free: the centring equations are those of a revolute joint)
    np.testing.assert_allclose(outer.translation, inner.translation, atol=1e-12)
    np.testing.assert_allclose(outer.rotation[:, 2], [0, 0, 1], atol=1e-12)
    np.testing.assert_allclose(inner.rotation[:, 2], [0, 0, 1], atol=1e-12)
    expected = _world(mechanism, q, "crank", [CRANK, 0, 0]) if choice == "crank_rod" else _world(mechanism, q, "slider", [0, 0, 0])
    np.testing.assert_allclose(outer.translation, expected, atol=1e-12)
