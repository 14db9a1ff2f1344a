"""Revolute clearance joint: geometry, distributed line/plane law, continuity, kinematics (physics checks)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.integrate import quad

from clearance_contact import (
    ONSET_RATE_FLOOR,
    STEEL,
    BrownMcPheeFriction,
    ContactError,
    ContactParameterError,
    CoulombFriction,
    RevoluteClearanceJoint,
    cylinder_line_stiffness,
    flat_punch_stiffness,
)
from clearance_contact.revolute import _QUAD_POINTS, _disc_moments, _disc_rule


def disc(dc: float, q: float, r: float, n: float) -> tuple[float, float, float]:
    return _disc_moments(dc, q, r, n, _disc_rule(_QUAD_POINTS, n))


# journal 10 mm in a 10.1 mm bore (c_r = 0.1 mm, MODEL-NOTES 2), end faces out to 16 mm,
# bearing 20 mm long, flanges 20.4 mm apart (c_a = 0.4 mm, 0.2 mm per side)
R_J, R_B1, R_B2, L_J, L_B = 0.010, 0.0101, 0.016, 0.0204, 0.020
C_R, C_A = R_B1 - R_J, L_J - L_B
HL = 0.5 * L_B
I3 = np.eye(3)
Z3 = np.zeros(3)
Z6 = np.zeros(6)
Z4 = np.zeros(4)
BM = BrownMcPheeFriction(static_coefficient=0.08, dynamic_coefficient=0.05, transition_velocity=1e-3)


def make_joint(**kwargs) -> RevoluteClearanceJoint:
    return RevoluteClearanceJoint(R_J, R_B1, R_B2, L_J, L_B, STEEL, STEEL, **kwargs)


def rot(axis, angle: float) -> np.ndarray:
    """Rotation matrix about a unit axis (Rodrigues)."""
    k = np.asarray(axis, dtype=float)
    k = k / np.linalg.norm(k)
    kx = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + math.sin(angle) * kx + (1 - math.cos(angle)) * kx @ kx


def rotation_from_quaternion(q) -> np.ndarray:
    w, x, y, z = np.asarray(q, dtype=float) / np.linalg.norm(q)
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
        ]
    )


def shift_moment(wrench, origin, point) -> np.ndarray:
    """Moment about ``point`` of a wrench given about ``origin``."""
    return wrench[3:] + np.cross(np.asarray(origin) - np.asarray(point), wrench[:3])


def total_about(res, pos_b, pos_j, point) -> tuple[np.ndarray, np.ndarray]:
    """Sum of both wrenches about a common point (zero by action = reaction)."""
    f = res.wrench_outer[:3] + res.wrench_inner[:3]
    m = shift_moment(res.wrench_outer, pos_b, point) + shift_moment(res.wrench_inner, pos_j, point)
    return f, m


BEARING_POSE = rotation_from_quaternion([0.9, 0.2, -0.3, 0.25]), np.array([0.1, -0.2, 0.3])


def pose_in_bearing(rel_rot: np.ndarray, rel_pos) -> tuple[np.ndarray, np.ndarray]:
    """Journal pose given relative to the (rotated, shifted) bearing frame."""
    rb, pb = BEARING_POSE
    return rb @ rel_rot, pb + rb @ np.asarray(rel_pos, dtype=float)


# --- construction ----------------------------------------------------------------------------
def test_clearances_and_default_stiffnesses() -> None:
    joint = make_joint()
    assert joint.n_candidates == 4
    assert joint.radial_clearance == pytest.approx(1e-4, rel=1e-12)
    assert joint.axial_clearance == pytest.approx(4e-4, rel=1e-12)
    assert joint.radial_stiffness == pytest.approx(cylinder_line_stiffness(L_B, STEEL, STEEL), rel=1e-15)
    assert joint.axial_stiffness == pytest.approx(flat_punch_stiffness(R_B2, STEEL, STEEL), rel=1e-15)
    assert joint.radial_exponent == joint.axial_exponent == 1.0
    assert "RevoluteClearanceJoint(" in repr(joint)


@pytest.mark.parametrize(
    ("kwargs", "name"),
    [
        (dict(journal_radius=R_B1), "journal_radius"),  # journal as large as the bore
        (dict(journal_radius=0.011), "journal_radius"),  # journal larger than the bore
        (dict(journal_radius=-0.01), "journal_radius"),
        (dict(bearing_inner_radius=0.0), "bearing_inner_radius"),
        (dict(bearing_outer_radius=R_B1), "bearing_outer_radius"),  # R_b2 <= R_b1
        (dict(bearing_outer_radius=0.009), "bearing_outer_radius"),
        (dict(journal_length=L_B), "journal_length"),  # L_j <= L_b
        (dict(journal_length=0.019), "journal_length"),
        (dict(bearing_length=0.0), "bearing_length"),
        (dict(bearing_length=-0.02), "bearing_length"),
        (dict(journal_length=float("nan")), "journal_length"),
        (dict(restitution=0.0), "restitution"),
        (dict(restitution=1.1), "restitution"),
        (dict(radial_exponent=0.9, radial_stiffness=1e9), "radial_exponent"),
        (dict(axial_exponent=1.6, axial_stiffness=1e9), "axial_exponent"),
        (dict(point_exponent=2.0), "point_exponent"),
        (dict(radial_exponent=1.5), "radial_exponent"),  # needs an explicit stiffness
        (dict(axial_exponent=1.2), "axial_exponent"),
        (dict(radial_stiffness=-1.0), "radial_stiffness"),
        (dict(axial_stiffness=0.0), "axial_stiffness"),
        (dict(point_stiffness=float("inf")), "point_stiffness"),
        (dict(journal_material="steel"), "journal_material"),
        (dict(friction=0.1), "friction"),
    ],
)
def test_bad_parameters_are_rejected(kwargs, name) -> None:
    args = dict(
        journal_radius=R_J,
        bearing_inner_radius=R_B1,
        bearing_outer_radius=R_B2,
        journal_length=L_J,
        bearing_length=L_B,
        journal_material=STEEL,
        bearing_material=STEEL,
    )
    args.update(kwargs)
    with pytest.raises(ContactParameterError) as info:
        RevoluteClearanceJoint(**args)
    assert isinstance(info.value, ValueError)
    message = str(info.value)
    assert name in message
    assert repr(kwargs[name])[:6] in message


def test_bad_states_are_rejected() -> None:
    joint = make_joint()
    with pytest.raises(ValueError):
        joint.evaluate(I3, Z3, Z6, I3, Z3, Z6, np.zeros(3))  # onset_rates must be (4,)
    with pytest.raises(ValueError):
        joint.evaluate(I3, Z3, np.zeros(5), I3, Z3, Z6, Z4)
    with pytest.raises(ContactError, match="90 deg"):  # journal turned upside down
        joint.evaluate(I3, Z3, Z6, rot([1, 0, 0], math.pi), Z3, Z6, Z4)
    with pytest.raises(ContactError, match="90 deg"):
        joint.penetration(I3, Z3, rot([0, 1, 0], 0.5 * math.pi), Z3)
    with pytest.raises(ContactError):
        joint.evaluate(I3, Z3, Z6, I3, np.array([np.nan, 0.0, 0.0]), Z6, Z4)


# --- the four configurations of the seed paper -------------------------------------------------
def test_centred_aligned_journal_has_no_contact() -> None:
    joint = make_joint(friction=BM)
    rj, pj = pose_in_bearing(I3, Z3)
    res = joint.evaluate(*BEARING_POSE, Z6, rj, pj, Z6, Z4)
    np.testing.assert_allclose(res.penetration, [-C_R, -C_A / 2, -C_R, -C_A / 2], rtol=0, atol=1e-15)
    assert res.kind.tolist() == [0, 0, 0, 0] and not res.in_contact.any()
    assert np.all(res.normal_force == 0.0) and np.all(res.friction_force == 0.0)
    assert np.all(res.wrench_inner == 0.0) and np.all(res.wrench_outer == 0.0)
    np.testing.assert_allclose(res.eccentricity, [[0, 0, HL], [0, 0, -HL]], atol=1e-15)
    np.testing.assert_allclose(np.linalg.norm(res.normal, axis=1), 1.0, rtol=1e-14)


@pytest.mark.parametrize(("exponent", "stiffness"), [(1.0, None), (1.35, 3.0e11)])
@pytest.mark.parametrize("angle", [0.0, 2.1])
def test_aligned_radial_offset_is_a_line_contact(exponent, stiffness, angle) -> None:
    """Parallel axes, offset e > c_r: line contact on both rings, total K_line (e - c_r)^n."""
    joint = make_joint(radial_exponent=exponent, radial_stiffness=stiffness)
    delta = 6e-6
    radial = np.array([math.cos(angle), math.sin(angle), 0.0])
    axial_shift = 3e-5  # the journal may slide along its axis: no effect on radial contact
    rj, pj = pose_in_bearing(I3, (C_R + delta) * radial + [0, 0, axial_shift])
    res = joint.evaluate(*BEARING_POSE, Z6, rj, pj, Z6, Z4)
    rb, pb = BEARING_POSE
    n_world = rb @ radial
    assert res.kind.tolist() == [2, 0, 2, 0]
    np.testing.assert_allclose(res.penetration[[0, 2]], delta, rtol=0, atol=1e-15)
    k = joint.radial_stiffness
    np.testing.assert_allclose(res.normal_force[[0, 2]], 0.5 * k * delta**exponent, rtol=1e-9)
    np.testing.assert_allclose(res.normal[[0, 2]], [n_world, n_world], atol=1e-14)
    np.testing.assert_allclose(res.wrench_inner[:3], -k * delta**exponent * n_world, rtol=1e-9)
    np.testing.assert_allclose(res.wrench_outer[:3], k * delta**exponent * n_world, rtol=1e-9)
    # uniform pressure on each half: resultants at z = +-L_b/4 on the bore, opposite moments cancel
    z_points = (res.point_outer - pb) @ rb[:, 2]
    np.testing.assert_allclose(z_points[[0, 2]], [HL / 2, -HL / 2], rtol=1e-12)
    radial_dist = np.linalg.norm((res.point_outer - pb) @ rb[:, :2], axis=1)
    np.testing.assert_allclose(radial_dist[[0, 2]], R_B1, rtol=1e-12)
    np.testing.assert_allclose(res.point_inner[[0, 2]] - res.point_outer[[0, 2]], delta * res.normal[[0, 2]],
                               atol=1e-15)
    assert np.linalg.norm(shift_moment(res.wrench_inner, pj, pj - axial_shift * rb[:, 2])) < 1e-9 * k * delta * L_B
    # eccentricity: ring centres seen from the journal frame
    np.testing.assert_allclose(
        res.eccentricity,
        [-(C_R + delta) * radial + [0, 0, HL - axial_shift], -(C_R + delta) * radial + [0, 0, -HL - axial_shift]],
        atol=1e-15,
    )


@pytest.mark.parametrize("axis_angle", [0.0, 1.0])
def test_tilted_journal_touches_each_ring_at_one_point_on_opposite_sides(axis_angle) -> None:
    """Bearing tilted by zeta about a radial axis through the common centre: edge contacts."""
    joint = make_joint()
    axis = np.array([math.cos(axis_angle), math.sin(axis_angle), 0.0])
    zeta = 0.0105  # touching needs HL tan(zeta) > c_r (minus the ellipse term)
    rb = rot(axis, zeta)
    res = joint.evaluate(rb, Z3, Z6, I3, Z3, Z6, Z4)
    assert res.kind.tolist() == [1, 0, 1, 0]
    # slice penetration at the ring: HL tan(zeta) + R_j / cos(zeta) - R_b1 (the journal's
    # cross-section is an ellipse), within the documented beta^2 / (4 |e|), beta = R_j tan^2
    b = HL * math.tan(zeta) + R_J / math.cos(zeta) - R_B1
    a = R_J / math.cos(zeta) - R_B1  # mid-plane, journal axis through the bearing axis: exact
    beta = R_J * math.tan(zeta) ** 2
    np.testing.assert_allclose(res.penetration[[0, 2]], b, rtol=0, atol=0.25 * beta**2 / (HL * math.tan(zeta)))
    # normals: opposite, normal to the journal axis (world z) and to the tilt axis
    np.testing.assert_allclose(res.normal[0], -res.normal[2], atol=1e-14)
    assert abs(res.normal[0, 2]) < 1e-14 and abs(res.normal[0] @ axis) < 1e-14
    top_dir = np.cross(axis, [0, 0, 1.0])  # where the bearing's top ring moved relative to the journal
    assert res.normal[0] @ top_dir < -0.999
    # linear profile a -> b over the half: contact length lam, energy K/L_b lam b^2 / 4 (n = 1);
    # its gradient is normal to the journal surface, which leans by zeta from the bearing's
    # cross-section: |d delta / d a| = 1 / cos(zeta), force K/L_b * lam * b / 2 / cos(zeta)
    b = res.penetration[0]
    lam = HL * b / (b - a)
    np.testing.assert_allclose(res.normal_force[[0, 2]], joint.radial_stiffness / L_B * lam * b / 2 / math.cos(zeta),
                               rtol=1e-12)
    # resultant at lam/3 from the ring end, on the line of action through the journal surface
    # (the bore + delta): its height at the bore differs by at most delta tan(zeta)
    z_points = (res.point_outer - Z3) @ rb[:, 2]
    np.testing.assert_allclose(z_points[[0, 2]], [HL - lam / 3, -(HL - lam / 3)], rtol=0, atol=b * math.tan(zeta))
    # equal and opposite forces: a pure couple on the journal, restoring the alignment
    assert np.linalg.norm(res.wrench_inner[:3]) < 1e-9 * res.normal_force[0]
    assert res.wrench_inner[3:] @ axis > 0.9 * res.normal_force[0] * 2 * (HL - lam / 3)


@pytest.mark.parametrize("ring", [+1, -1])
def test_axial_offset_plane_contact_when_aligned(ring) -> None:
    joint = make_joint()
    delta = 5e-6
    k_ax = 1 if ring > 0 else 3
    # journal slides along -ring: its top (bottom) flange comes onto the top (bottom) end face
    pj = np.array([0.0, 0.0, -ring * (C_A / 2 + delta)])
    res = joint.evaluate(I3, Z3, Z6, I3, pj, Z6, Z4)
    expected_kind = [0, 0, 0, 0]
    expected_kind[k_ax] = 3
    assert res.kind.tolist() == expected_kind
    assert res.penetration[k_ax] == pytest.approx(delta, abs=1e-15)
    assert res.penetration[4 - k_ax] == pytest.approx(-C_A - delta, abs=1e-15)
    assert res.normal_force[k_ax] == pytest.approx(joint.axial_stiffness * delta, rel=1e-12)
    np.testing.assert_allclose(res.normal[k_ax], [0, 0, -ring], atol=0)
    np.testing.assert_allclose(res.point_outer[k_ax], [0, 0, ring * HL], atol=1e-15)  # centroid on the axis
    np.testing.assert_allclose(res.point_inner[k_ax], [0, 0, ring * (HL - delta)], atol=1e-15)  # flange face
    np.testing.assert_allclose(res.wrench_inner, [0, 0, ring * joint.axial_stiffness * delta, 0, 0, 0], atol=1e-9)


@pytest.mark.parametrize("ring", [+1, -1])
@pytest.mark.parametrize(("face_centre", "exponent"), [(5e-6, 1.0), (-1e-5, 1.0), (-1e-5, 1.5)])
def test_tilted_axial_contact_is_a_rim_contact(ring, face_centre, exponent) -> None:
    """Tilted faces: contact on the deep side of the annulus, deepest at R_b2; brute-force check."""
    joint = make_joint(axial_exponent=exponent, axial_stiffness=None if exponent == 1.0 else 1e13)
    k_ax = 1 if ring > 0 else 3
    zeta = 2e-3
    rb = rot([1, 0, 0], zeta)  # bearing tilted about its centre
    pj = np.array([0.0, 0.0, -ring * (C_A / 2 + face_centre)])
    res = joint.evaluate(rb, Z3, Z6, I3, pj, Z6, Z4)
    dc = HL * math.cos(zeta) - L_B / 2 + face_centre
    assert res.penetration[k_ax] == pytest.approx(dc + R_B2 * math.sin(zeta), abs=1e-16)
    assert res.kind[k_ax] == 1 and res.kind.tolist().count(0) == 3
    # brute force: penetration field on a polar grid of the annulus, p = K/A max(depth, 0)^n
    r = np.linspace(R_B1, R_B2, 401)
    th = np.linspace(0, 2 * np.pi, 4001)
    rr, tt = np.meshgrid(0.5 * (r[1:] + r[:-1]), 0.5 * (th[1:] + th[:-1]), indexing="ij")
    da = (r[1] - r[0]) * (th[1] - th[0]) * rr
    pts = np.stack([rr * np.cos(tt), rr * np.sin(tt), np.full_like(rr, ring * HL)], axis=-1) @ rb.T
    depth = ring * (pts[..., 2] - (pj[2] + ring * L_J / 2))  # beyond the flange face
    p = np.maximum(depth, 0.0) ** exponent * joint.axial_stiffness / (math.pi * (R_B2**2 - R_B1**2))
    force = (p * da).sum()
    centroid = (p[..., None] * da[..., None] * pts).sum(axis=(0, 1)) / force
    assert res.normal_force[k_ax] == pytest.approx(force, rel=1e-4)
    np.testing.assert_allclose(res.point_outer[k_ax], centroid, atol=1e-6)
    # the deepest point is on the outer rim R_b2; the resultant lies on the same (deep) side
    deepest = rb.T @ pts.reshape(-1, 3)[np.argmax(depth)]
    assert np.hypot(deepest[0], deepest[1]) == pytest.approx(R_B2, rel=1e-3)
    d = rb.T @ [0.0, 0.0, 1.0]  # journal axis in the bearing frame: the face rises along ring * (d_x, d_y)
    deep_dir = ring * d[:2] / np.hypot(d[0], d[1])
    assert deep_dir @ deepest[:2] / np.hypot(*deepest[:2]) > 1 - 1e-5  # grid resolution
    local = rb.T @ res.point_outer[k_ax]
    assert local[2] == pytest.approx(ring * HL, abs=1e-15)
    assert local[:2] @ deep_dir / np.hypot(*local[:2]) > 1 - 1e-12
    if face_centre < 0:  # only the part of the annulus beyond a line on the deep side touches
        assert local[:2] @ deep_dir > -dc / math.sin(zeta) > 0.0


# --- the distributed law: integrals and continuity ------------------------------------------
@pytest.mark.parametrize("n", [1.0, 1.25, 1.5])
def test_disc_integrals_match_quadrature(n) -> None:
    """Force, centroid and second moment over a disc with a linear penetration field."""
    r, q = 0.016, 3e-5
    worst = [0.0, 0.0, 0.0]
    opts = dict(epsabs=0, epsrel=1e-13, limit=400)
    for alpha in [-0.999999, -0.9999, -0.995, -0.9, -0.878, -0.877, -0.3, 0.2, 0.8, 0.95, 0.999, 0.99999, 1.0,
                  1.0001, 1.5, 40.0]:
        dc = alpha * q
        d0, d1, d2 = disc(dc, q, r, n)
        if alpha < 1.0:  # crescent v > v0 = -alpha; v = 1 - y0 s^2 removes both endpoint singularities
            y0 = (dc + q) / q  # from the same rounded input (the rim penetration dc + q)

            def g(s, k):
                v = 1 - y0 * s * s
                return (q * y0 * (1 - s * s)) ** n * v**k * math.sqrt(y0 * (2 - y0 * s * s)) * 2 * y0 * s * s

        else:

            def g(s, k):  # v = -cos(pi s)
                v = -math.cos(math.pi * s)
                return (dc + q * v) ** n * v**k * math.sin(math.pi * s) ** 2 * math.pi

        r0 = 2 * r * r * quad(lambda s: g(s, 0), 0, 1, **opts)[0]
        # (the first moment nearly cancels for a full disc: absolute tolerance)
        r1 = 2 * r**3 * quad(lambda s: g(s, 1), 0, 1, epsabs=1e-14 * r0 / (2 * r * r), epsrel=1e-13, limit=400)[0]
        r2 = 2 * r**4 * quad(lambda s: (g(s, 0) + 2 * g(s, 2)) / 3, 0, 1, **opts)[0]
        worst[0] = max(worst[0], abs(d0 / r0 - 1))
        worst[1] = max(worst[1], abs(d1 / d0 - r1 / r0) / r)
        worst[2] = max(worst[2], abs(d2 / r2 - 1))
    # documented accuracy: closed form (n = 1) or 10-point rule (force 4e-6, centroid 1.2e-6 r)
    bound = (3e-11, 3e-11, 3e-11) if n == 1.0 else (4e-6, 5e-8, 4e-6)
    assert worst[0] < bound[0] and worst[1] < bound[1] and worst[2] < bound[2], worst
    # a uniform pressure (aligned faces) is integrated exactly by both
    d0, d1, d2 = disc(2e-6, 0.0, r, n)
    assert d0 == pytest.approx(math.pi * r * r * 2e-6**n, rel=1e-14)
    assert d2 / d0 == pytest.approx(r * r / 2, rel=1e-9)


def test_disc_integrals_continuous_where_the_rule_changes() -> None:
    """n = 1: closed form above a crescent half-angle of 0.5 rad, quadrature below."""
    r, q = 0.016, 3e-5
    dc = -math.cos(0.5) * q
    lo = disc(dc * (1 + 1e-13), q, r, 1.0)
    hi = disc(dc * (1 - 1e-13), q, r, 1.0)
    for x, y in zip(lo, hi):
        assert abs(x - y) <= 3e-11 * abs(y)


def test_slice_penetration_error_bound() -> None:
    """Slice penetration: |exact max - value| <= min(0.3 beta, beta^2/(4|e|)), beta = R_j tan^2."""
    joint = make_joint()
    rng = np.random.default_rng(7)
    phi = np.linspace(0, 2 * np.pi, 40001)
    nn = np.stack([np.cos(phi), np.sin(phi)])
    for tilt in (1e-3, 1e-2):
        beta = R_J * math.tan(tilt) ** 2
        t = math.tan(tilt) * np.array([math.cos(0.3), math.sin(0.3)])
        for _ in range(80):
            a = rng.uniform(0, 7)
            e = 10 ** rng.uniform(-3, 3) * beta * np.array([math.cos(a), math.sin(a)])
            f = e @ nn + R_J * np.sqrt(1 + (t @ nn) ** 2)  # support function of the cross-section
            i = int(np.argmax(f))
            fl, fc, fr = f[i - 1], f[i], f[(i + 1) % f.size]  # refine with a local parabola
            exact = fc + (fl - fr) ** 2 / (8 * (2 * fc - fl - fr)) if 2 * fc - fl - fr > 0 else fc
            got = joint._slice(e[0], e[1], t[0], t[1], beta) + R_B1
            assert abs(exact - got) <= min(0.3 * beta, 0.25 * beta**2 / np.linalg.norm(e)) + 1e-17
        # exact where the journal axis crosses the bearing axis (e = 0)
        got = joint._slice(0.0, 0.0, t[0], t[1], beta) + R_B1
        assert got == pytest.approx(R_J / math.cos(tilt), rel=1e-15)


def contact_sweep_state(zeta: float, axis_angle: float = 0.4):
    """Journal pressed radially (delta 2 um) and onto the top face (3 um), bearing tilted by zeta."""
    rb = rot([math.cos(axis_angle), math.sin(axis_angle), 0.0], zeta)
    pj = np.array([C_R + 2e-6, 0.0, -(C_A / 2 + 3e-6)])
    tw_b = np.array([0.0, 0.0, 0.0, 0.3, -0.2, 0.0])  # rocking: damping and friction active
    tw_j = np.array([-0.002, 0.001, 0.003, 0.0, 0.1, 5.0])
    return rb, Z3, tw_b, I3, pj, tw_j, np.full(4, 0.05)


@pytest.mark.parametrize("friction", [BM, CoulombFriction(0.1, regularisation_velocity=1e-3)])
def test_force_and_moment_continuous_through_zero_tilt(friction) -> None:
    """Sweep the tilt through zero: radial line <-> edge and axial plane <-> rim transitions."""
    joint = make_joint(friction=friction)

    def wrench(zeta: float) -> np.ndarray:  # on the journal, moment about its (fixed) origin
        return joint.evaluate(*contact_sweep_state(zeta)).wrench_inner

    zetas = np.linspace(-1e-3, 1e-3, 2001)
    w = np.array([wrench(z) for z in zetas])
    kinds = {tuple(joint.evaluate(*contact_sweep_state(z)).kind) for z in zetas}
    assert (2, 3, 2, 0) in kinds and any(k[1] == 1 for k in kinds) and any(k[0] == 1 for k in kinds)
    h = zetas[1] - zetas[0]
    slope = np.abs(np.diff(w, axis=0)).max(axis=0) / h
    scale = np.abs(w).max(axis=0)
    # bounded difference quotient (a jump of size J would give J / h ~ 1e6 J)
    assert np.all(slope <= 2e4 * scale), slope / scale
    # and differences shrink with the step right at zero tilt (no jump)
    for eps in (1e-7, 1e-9, 1e-11):
        jump = np.abs(wrench(eps) - wrench(-eps))
        assert np.all(jump <= 2 * slope * 2 * eps + 1e-12 * scale), (eps, jump)


@pytest.mark.parametrize("tilt", [1e-30, 1e-46, 1e-80])
def test_a_centred_journal_tilted_by_rounding_has_a_finite_state(tilt) -> None:
    """Eccentricity exactly 0 and a tilt of rounding size: the slice's d = |e|^2 + (R_j |t|^2)^2 is ~1e-182, d^2
    underflows to 0 (a ZeroDivisionError of the compiled kernels in a free-flying arm's warm-up). Out of contact,
    finite, and the same as a slightly larger tilt's state."""
    joint = make_joint()
    twist = np.array([0.0, 0.0, 0.0, 0.3, -0.2, 2.0])  # turning and rocking
    result = joint.evaluate(I3, Z3, Z6, rot([1.0, 0.0, 0.0], tilt), Z3, twist, np.full(joint.N_CANDIDATES, 0.1))
    assert np.all(np.isfinite(result.penetration)) and np.all(np.isfinite(result.penetration_rate))
    assert np.all(result.penetration < 0) and not result.normal_force.any()
    reference = joint.evaluate(I3, Z3, Z6, rot([1.0, 0.0, 0.0], 1e-12), Z3, twist, np.full(joint.N_CANDIDATES, 0.1))
    np.testing.assert_allclose(result.penetration, reference.penetration, rtol=0, atol=1e-13)  # the 1e-12 tilt moves it 2e-14


# --- damping and friction --------------------------------------------------------------------
def test_lankarani_nikravesh_damping_of_a_line_contact() -> None:
    joint = make_joint(restitution=0.8)
    delta, rate, onset = 5e-6, 0.02, 0.05
    pj = np.array([C_R + delta, 0.0, 0.0])
    res = joint.evaluate(I3, Z3, Z6, I3, pj, np.array([rate, 0, 0, 0, 0, 0]), np.full(4, onset))
    np.testing.assert_allclose(res.penetration_rate[[0, 2]], rate, rtol=1e-14)
    factor = 1 + 0.75 * (1 - 0.8**2) * rate / onset
    np.testing.assert_allclose(res.normal_force[[0, 2]], 0.5 * joint.radial_stiffness * delta * factor, rtol=1e-12)
    # onset rate floored, force clamped at zero when separating fast
    res = joint.evaluate(I3, Z3, Z6, I3, pj, np.array([-1e-3, 0, 0, 0, 0, 0]), Z4)
    assert res.normal_force[0] == 0.0 and res.kind[0] == 2
    res = joint.evaluate(I3, Z3, Z6, I3, pj, np.array([1e-4, 0, 0, 0, 0, 0]), Z4)
    factor = 1 + 0.75 * (1 - 0.8**2) * 1e-4 / ONSET_RATE_FLOOR
    assert res.normal_force[0] == pytest.approx(0.5 * joint.radial_stiffness * delta * factor, rel=1e-12)


def test_damping_of_a_rocking_line_contact_uses_the_centroid_rate() -> None:
    """Aligned line contact, journal rocking about a radial axis through its centre.

    The penetration rate grows linearly from 0 at the mid-plane to l w at the ring end, so
    the pointwise L-N law integrated over the half equals the law at the centroid rate
    l w / 2; the reported rate is the deepest point's right derivative, l w at the top
    ring (and 0, the mid-plane's, at the bottom one).
    """
    joint = make_joint(restitution=0.7)
    delta, w, onset = 4e-6, 2.0, 0.03
    res = joint.evaluate(I3, Z3, Z6, I3, np.array([C_R + delta, 0, 0]), np.array([0, 0, 0, 0, w, 0]),
                         np.full(4, onset))
    assert res.kind.tolist() == [2, 0, 2, 0]
    np.testing.assert_allclose(res.penetration_rate[[0, 2]], [HL * w, 0.0], atol=1e-15)
    damping = 0.75 * (1 - 0.7**2) / onset
    el = 0.5 * joint.radial_stiffness * delta
    expected = [el * (1 + damping * HL * w / 2), el * (1 - damping * HL * w / 2)]
    np.testing.assert_allclose(res.normal_force[[0, 2]], expected, rtol=1e-12)


@pytest.mark.parametrize("ring", [+1, -1])
def test_damping_of_a_rocking_rim_contact_is_the_integrated_pointwise_law(ring) -> None:
    joint = make_joint(restitution=0.6)
    k_ax = 1 if ring > 0 else 3
    zeta, face_centre, onset = 2e-3, -1e-5, 0.02
    rb = rot([1, 0, 0], zeta)
    pj = np.array([0.0, 0.0, -ring * (C_A / 2 + face_centre)])
    omega = np.array([1.5, 0.7, 0.0])  # bearing rocking about its origin
    res = joint.evaluate(rb, Z3, np.concatenate([Z3, omega]), I3, pj, Z6, np.full(4, onset))
    assert res.kind[k_ax] == 1
    r = np.linspace(R_B1, R_B2, 401)
    th = np.linspace(0, 2 * np.pi, 4001)
    rr, tt = np.meshgrid(0.5 * (r[1:] + r[:-1]), 0.5 * (th[1:] + th[:-1]), indexing="ij")
    da = (r[1] - r[0]) * (th[1] - th[0]) * rr
    pts = np.stack([rr * np.cos(tt), rr * np.sin(tt), np.full_like(rr, ring * HL)], axis=-1) @ rb.T
    depth = ring * (pts[..., 2] - (pj[2] + ring * L_J / 2))
    depth_rate = ring * np.cross(omega, pts)[..., 2]
    p = np.maximum(depth, 0.0) * joint.axial_stiffness / (math.pi * (R_B2**2 - R_B1**2))
    damping = 0.75 * (1 - 0.6**2) / onset
    force = (p * (1 + damping * depth_rate) * da).sum()
    assert res.normal_force[k_ax] == pytest.approx(force, rel=2e-4)
    # and the reported rate is the deepest (rim) point's
    deepest = np.unravel_index(np.argmax(depth), depth.shape)
    assert res.penetration_rate[k_ax] == pytest.approx(depth_rate[deepest], rel=1e-3)


def test_friction_torque_of_a_turning_journal() -> None:
    """Journal spinning in a line contact and on a plane contact: tangential / spin friction."""
    mu = 0.1
    joint = make_joint(friction=CoulombFriction(mu, regularisation_velocity=1e-6))
    omega = 10.0
    delta = 5e-6
    # radial line contact: slip R w at the bore, friction mu F tangential, torque -mu F R about the axis
    res = joint.evaluate(I3, Z3, Z6, I3, np.array([C_R + delta, 0, 0]), np.array([0, 0, 0, 0, 0, omega]), Z4)
    f_n = res.normal_force.sum()
    np.testing.assert_allclose(res.friction_force[0], [0, -mu * res.normal_force[0], 0], rtol=1e-9, atol=1e-9)
    assert res.wrench_inner[5] == pytest.approx(-mu * f_n * (R_B1 + delta / 2 - C_R - delta), rel=1e-9)
    # plane contact, flange turning on the end face: torque mu F r_rms, r_rms^2 = (R_b1^2 + R_b2^2)/2
    res = joint.evaluate(I3, Z3, Z6, I3, np.array([0, 0, -(C_A / 2 + delta)]), np.array([0, 0, 0, 0, 0, omega]), Z4)
    assert res.kind.tolist() == [0, 3, 0, 0]
    np.testing.assert_allclose(res.friction_force[1], 0.0, atol=1e-12)
    torque = -mu * res.normal_force[1] * math.sqrt(0.5 * (R_B1**2 + R_B2**2))
    assert res.wrench_inner[5] == pytest.approx(torque, rel=1e-9)
    assert res.wrench_outer[5] == pytest.approx(-torque, rel=1e-9)


# --- invariance, action = reaction, finite differences -----------------------------------------
quaternions = st.lists(st.floats(-1.0, 1.0), min_size=4, max_size=4).filter(lambda q: np.linalg.norm(q) > 0.1)


def vec(bound: float):
    return st.lists(st.floats(-bound, bound), min_size=3, max_size=3).map(np.array)


@st.composite
def configurations(draw):
    """Bearing anywhere; journal near or in contact: offsets up to c + 20 um, tilts up to 1.2e-2."""
    rb = rotation_from_quaternion(draw(quaternions))
    pb = draw(vec(0.5))
    # parallel, or tilted clearly above rounding (the axial rate has a kink at zero tilt, its
    # direction is conditioned as eps / tilt)
    tilt = draw(st.one_of(st.just(0.0), st.floats(1e-6, 1.2e-2)))
    tilt_axis = draw(st.floats(0.0, 2 * math.pi))
    rel_rot = rot([math.cos(tilt_axis), math.sin(tilt_axis), 0.0], tilt) @ rot([0, 0, 1], draw(st.floats(-3, 3)))
    ecc = draw(st.floats(0.2 * C_R, C_R + 2e-5))  # centred (e = 0) leaves the radial normal undefined
    ecc_angle = draw(st.floats(0.0, 2 * math.pi))
    shift = draw(st.floats(-(C_A / 2 + 2e-5), C_A / 2 + 2e-5))
    pj = pb + rb @ [ecc * math.cos(ecc_angle), ecc * math.sin(ecc_angle), shift]
    rj = rb @ rel_rot
    tw_b = np.concatenate([draw(vec(0.5)), draw(vec(5.0))])
    tw_j = np.concatenate([draw(vec(0.5)), draw(vec(5.0))])
    onset = np.array([draw(st.floats(0.0, 1.0)) for _ in range(4)])
    return rb, pb, tw_b, rj, pj, tw_j, onset


@settings(max_examples=150, deadline=None)
@given(configurations(), quaternions, vec(1.0), vec(2.0), vec(3.0))
def test_invariance_under_a_common_rigid_motion(state, q, shift, lin, ang) -> None:
    joint = make_joint(friction=BM)
    rb, pb, tw_b, rj, pj, tw_j, onset = state
    ref = joint.evaluate(*state)
    # the cheap event function agrees with evaluate()
    np.testing.assert_array_equal(joint.penetration(rb, pb, rj, pj), ref.penetration)
    # (1) the same configuration seen in another world frame: x -> Q x + s
    qm = rotation_from_quaternion(q)
    moved = joint.evaluate(
        qm @ rb, qm @ pb + shift, np.concatenate([qm @ tw_b[:3], qm @ tw_b[3:]]),
        qm @ rj, qm @ pj + shift, np.concatenate([qm @ tw_j[:3], qm @ tw_j[3:]]), onset,
    )
    # (2) a common rigid velocity field (V, W) added to both bodies
    def add(tw, p):
        return np.concatenate([tw[:3] + lin + np.cross(ang, p), tw[3:] + ang])

    boosted = joint.evaluate(rb, pb, add(tw_b, pb), rj, pj, add(tw_j, pj), onset)
    gain = 1 + 0.75 * (1 - 0.9**2) * np.abs(ref.penetration_rate).max() / max(onset.min(), ONSET_RATE_FLOOR)
    f_tol = max(joint.radial_stiffness, joint.axial_stiffness) * 2e-15 * gain
    for other in (moved, boosted):
        np.testing.assert_allclose(other.penetration, ref.penetration, rtol=1e-9, atol=1e-15)
        np.testing.assert_allclose(other.penetration_rate, ref.penetration_rate, rtol=1e-7, atol=1e-9)
        # absolute tolerance: rounding of the penetration (~1e-15 m at these coordinates) times the
        # stiffness, amplified by the L-N damping factor at the (floored) onset rate
        np.testing.assert_allclose(other.normal_force, ref.normal_force, rtol=1e-6, atol=f_tol)
        np.testing.assert_allclose(np.linalg.norm(other.friction_force, axis=1),
                                   np.linalg.norm(ref.friction_force, axis=1), rtol=1e-6, atol=f_tol)
        clear = np.abs(ref.penetration) > 1e-12
        assert ((other.kind > 0) == (ref.kind > 0))[clear].all()
        np.testing.assert_allclose(other.eccentricity, ref.eccentricity, rtol=1e-9, atol=1e-14)
    np.testing.assert_allclose(moved.normal, ref.normal @ qm.T, atol=1e-9)
    np.testing.assert_allclose(moved.wrench_inner[:3], qm @ ref.wrench_inner[:3], rtol=1e-6, atol=f_tol)
    np.testing.assert_allclose(moved.wrench_inner[3:], qm @ ref.wrench_inner[3:], rtol=1e-6, atol=0.03 * f_tol)
    # action = reaction about any common point
    for res, b, j in ((ref, pb, pj), (moved, qm @ pb + shift, qm @ pj + shift)):
        scale = 1.0 + np.abs(res.normal_force).sum()
        for point in (b, j, b + shift):
            f, m = total_about(res, b, j, point)
            assert np.linalg.norm(f) <= 1e-12 * scale
            assert np.linalg.norm(m) <= 1e-12 * scale


def advance(rot_m, pos, twist, t: float):
    """Pose after a rigid motion with constant twist (v of the origin, w), world axes."""
    return rot(twist[3:], np.linalg.norm(twist[3:]) * t) @ rot_m if np.any(twist[3:]) else rot_m, pos + twist[:3] * t


def test_penetration_rate_matches_finite_differences() -> None:
    joint = make_joint()
    rng = np.random.default_rng(11)
    checked = 0
    for _ in range(60):
        rb = rotation_from_quaternion(rng.normal(size=4))
        pb = rng.uniform(-0.3, 0.3, 3)
        tilt, tilt_axis = rng.uniform(1e-4, 1.2e-2), rng.uniform(0, 2 * math.pi)
        rel = rot([math.cos(tilt_axis), math.sin(tilt_axis), 0.0], tilt) @ rot([0, 0, 1], rng.uniform(-3, 3))
        ea = rng.uniform(0, 2 * math.pi)
        pj = pb + rb @ [rng.uniform(0, 1.2 * C_R) * math.cos(ea), rng.uniform(0, 1.2 * C_R) * math.sin(ea),
                        rng.uniform(-C_A, C_A) / 2]
        rj = rb @ rel
        tw_b = np.concatenate([rng.normal(0, 0.05, 3), rng.normal(0, 1.0, 3)])
        tw_j = np.concatenate([rng.normal(0, 0.05, 3), rng.normal(0, 1.0, 3)])
        res = joint.evaluate(rb, pb, tw_b, rj, pj, tw_j, Z4)
        h = 1e-7

        def pen(t):
            return joint.penetration(*advance(rb, pb, tw_b, t), *advance(rj, pj, tw_j, t))

        fd = (pen(h) - pen(-h)) / (2 * h)
        # skip a candidate whose deepest point switches inside [-h, h] (derivative undefined)
        smooth = np.abs((pen(h) - pen(0.0)) - (pen(0.0) - pen(-h))) < 1e-11  # kink: ~|jump| h ~ 1e-9
        np.testing.assert_allclose(res.penetration_rate[smooth], fd[smooth], rtol=1e-5, atol=1e-8)
        checked += smooth.sum()
    assert checked >= 230, checked
