"""Revolute joint, radial contact from the exact penetration profile (issue 14).

* against brute-force slicing (40000 slices, exact support function of each slice's
  ellipse found by Newton's method): skew, in-plane and mixed tilts, depths 0.1-10 um,
  tilts up to the geometric maximum, two geometries: force and moment within 1 %;
* conservative: with restitution 1 and no friction the wrench is minus the
  finite-difference gradient of the elastic energy (radial slices + axial annuli,
  computed independently by adaptive quadrature) at random poses (hypothesis);
* continuity where the wetted set changes shape (one piece <-> two pieces in a half).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.integrate import quad
from scipy.optimize import brentq

from clearance_contact import STEEL, RevoluteClearanceJoint
from clearance_contact.radial_profile import dry_interval, slice_gradient

Z3 = np.zeros(3)
Z6 = np.zeros(6)
Z4 = np.zeros(4)

# (R_j, c_r, R_b2, L_b, c_a): R1 of the shipped scenes, the tests' small joint, a loose long one
GEOMETRIES = {
    "R1": (0.020, 1.0e-4, 0.035, 0.040, 2.0e-3),
    "small": (0.010, 1.0e-4, 0.016, 0.020, 2.0e-3),
    "loose": (0.0125, 3.0e-4, 0.020, 0.060, 2.0e-3),
}


def make(geometry: str, **kwargs) -> RevoluteClearanceJoint:
    r_j, c_r, r_b2, l_b, c_a = GEOMETRIES[geometry]
    kwargs.setdefault("restitution", 1.0)
    return RevoluteClearanceJoint(r_j, r_j + c_r, r_b2, l_b + c_a, l_b, STEEL, STEEL, **kwargs)


def rotation_to(axis: np.ndarray) -> np.ndarray:
    """A rotation taking z to the unit vector ``axis`` (about z x axis)."""
    d = axis / np.linalg.norm(axis)
    k = np.cross([0.0, 0.0, 1.0], d)
    s = np.linalg.norm(k)
    if s < 1e-300:
        return np.eye(3)
    k = k / s
    angle = math.atan2(s, d[2])
    kx = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + math.sin(angle) * kx + (1 - math.cos(angle)) * kx @ kx


def rot(axis, angle: float) -> np.ndarray:
    k = np.asarray(axis, dtype=float) / np.linalg.norm(axis)
    kx = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + math.sin(angle) * kx + (1 - math.cos(angle)) * kx @ kx


def journal_pose(tilt: float, tilt_direction: float, offset: float, offset_direction: float, axial: float = 0.0):
    """Journal (rotation, position) in the bearing frame: axis slope |t| = tan(tilt) towards
    ``tilt_direction``, axis through (offset, offset_direction) at z = 0, origin at z = axial."""
    t = math.tan(tilt) * np.array([math.cos(tilt_direction), math.sin(tilt_direction)])
    m = offset * np.array([math.cos(offset_direction), math.sin(offset_direction)])
    d = np.array([t[0], t[1], 1.0])
    return rotation_to(d), np.array([m[0] + axial * t[0], m[1] + axial * t[1], axial])


def deepest_radial(joint, rotation, position) -> float:
    p = joint.penetration(np.eye(3), Z3, rotation, position)
    return max(p[0], p[2])


def pose_at_depth(joint, tilt_fraction: float, skew: float, depth: float):
    """Pose with the given deepest radial penetration, the tilt a fraction of its geometric
    maximum (the tilt at which a journal through the bearing centre reaches that depth), the
    tilt direction ``skew`` rad from the eccentricity direction (0 in-plane, pi/2 skew)."""
    offset_direction = 0.7
    hl = 0.5 * joint.bearing_length

    def through_centre(tilt: float) -> float:
        return deepest_radial(joint, *journal_pose(tilt, offset_direction + skew, 0.0, offset_direction)) - depth

    tilt_max = brentq(through_centre, 0.0, 2.0 * (joint.radial_clearance + depth) / hl, xtol=1e-16, rtol=1e-14)
    tilt = tilt_fraction * tilt_max

    def at(offset: float) -> float:
        return deepest_radial(joint, *journal_pose(tilt, offset_direction + skew, offset, offset_direction)) - depth

    offset = 0.0 if tilt_fraction >= 1.0 - 1e-12 else brentq(  # at the maximum tilt the axis passes the centre
        at, 0.0, joint.radial_clearance + 2 * depth, xtol=1e-17, rtol=1e-15)
    return journal_pose(tilt, offset_direction + skew, offset, offset_direction)


def exact_slices(joint, rotation, position, slices: int = 40000):
    """Brute force: per slice the exact support of the journal's elliptic cross-section
    (Newton on the support angle), the envelope-theorem gradients, midpoint rule."""
    r_j, r_b1, hl = joint.journal_radius, joint.bearing_inner_radius, 0.5 * joint.bearing_length
    d = rotation[:, 2]
    a = position
    t = d[:2] / d[2]
    # midpoints of the slices, then the two ends (for the deepest penetration only)
    z = np.concatenate([-hl + (np.arange(slices) + 0.5) * (2 * hl / slices), [-hl, hl]])
    e = (a[:2] - a[2] * t)[None, :] + z[:, None] * t[None, :]
    theta = np.arctan2(e[:, 1], e[:, 0])
    for _ in range(8):  # quadratic convergence from the direction of e (g'' ~ -|e|)
        n = np.stack([np.cos(theta), np.sin(theta)], axis=1)
        n1 = np.stack([-np.sin(theta), np.cos(theta)], axis=1)
        s = n @ t
        s1 = n1 @ t
        w = np.sqrt(1 + s * s)
        g1 = (e * n1).sum(1) + r_j * s * s1 / w
        g2 = -(e * n).sum(1) + r_j * ((s1 * s1 - s * s) / w - s * s * s1 * s1 / w**3)
        theta = theta - g1 / g2
    n = np.stack([np.cos(theta), np.sin(theta)], axis=1)
    s = n @ t
    delta = (e * n).sum(1) + r_j * np.sqrt(1 + s * s) - r_b1
    deepest = delta.max()
    z, e, n, s, delta = z[:slices], e[:slices], n[:slices], s[:slices], delta[:slices]
    law = joint.radial_law
    wet = np.maximum(delta, 0.0)
    if law.exponent is not None:  # power law: vectorised
        q = law.parameters[0] * wet**law.exponent
    else:
        q = np.array([law.line_density(x) for x in wet])
    q = q * (2 * hl / slices)
    g_t = (r_j * s / np.sqrt(1 + s * s))[:, None] * n
    big_g = (z - a[2])[:, None] * n + g_t
    halves = {}
    for name, mask in (("top", z > 0), ("bottom", z < 0)):
        qm = q[mask][:, None]
        s_g = (qm * n[mask]).sum(0)
        s_big = (qm * big_g[mask]).sum(0)
        force = np.array([-s_g[0], -s_g[1], s_g @ t])
        moment = -np.cross(d, np.array([s_big[0], s_big[1], -s_big @ t]) / d[2])
        halves[name] = (force, moment)
    return halves, deepest


@pytest.mark.parametrize("geometry", list(GEOMETRIES))
@pytest.mark.parametrize("skew", [0.0, math.pi / 4, math.pi / 2, 2.0])
def test_radial_wrench_matches_brute_force_slicing(geometry, skew) -> None:
    check_against_slices(make(geometry), skew)


@pytest.mark.parametrize("law", ["pereira", "hertz_point", "johnson"])
@pytest.mark.parametrize("skew", [math.pi / 4, 2.0])
def test_every_radial_law_matches_brute_force_slicing(law, skew) -> None:
    """The same check with the other radial laws (their line density per slice: nonlinear in depth)."""
    check_against_slices(make("R1", radial_law=law), skew)


def check_against_slices(joint, skew: float) -> None:
    """Force, moment and per-half normal forces of the joint against :func:`exact_slices`, depths 0.1-10 um,
    tilts 0 to the geometric maximum, within 1 %."""
    for depth in (1e-7, 1e-6, 1e-5):
        for fraction in (0.0, 0.5, 0.95, 1.0):
            rotation, position = pose_at_depth(joint, fraction, skew, depth)
            res = joint.evaluate(np.eye(3), Z3, Z6, rotation, position, Z6, Z4)
            halves, deepest = exact_slices(joint, rotation, position)
            # the kernel's slice penetration is the ellipse support blended near e = 0: within
            # beta^2 / (4 |e|), beta = R_j tan^2(tilt), of the exact one (revolute docstring)
            tan2 = (rotation[0, 2] ** 2 + rotation[1, 2] ** 2) / rotation[2, 2] ** 2
            blend = (joint.journal_radius * tan2) ** 2 / (4 * (joint.radial_clearance - depth))
            assert deepest == pytest.approx(depth, rel=1e-9, abs=blend + 1e-15)
            total_f = halves["top"][0] + halves["bottom"][0]
            total_m = halves["top"][1] + halves["bottom"][1]
            scale_f = np.linalg.norm(total_f) + np.linalg.norm(halves["top"][0]) + np.linalg.norm(halves["bottom"][0])
            scale_m = scale_f * joint.bearing_length / 2
            assert np.linalg.norm(res.wrench_inner[:3] - total_f) <= 0.01 * scale_f, (depth, fraction)
            assert np.linalg.norm(res.wrench_inner[3:] - total_m) <= 0.01 * scale_m, (depth, fraction)
            for k, name in ((0, "top"), (2, "bottom")):
                ref = np.linalg.norm(halves[name][0])
                assert res.normal_force[k] == pytest.approx(ref, rel=0.01, abs=1e-3 * scale_f), (name, depth, fraction)


# --- conservative: wrench = -grad U --------------------------------------------------------------
def radial_energy(joint, rotation, position) -> float:
    """U = int Phi(delta(z)) dz over the bearing length, adaptive quadrature split at the roots."""
    r_j, r_b1, hl = joint.journal_radius, joint.bearing_inner_radius, 0.5 * joint.bearing_length
    d = rotation[:, 2]
    t = d[:2] / d[2]
    m = position[:2] - position[2] * t
    law = joint.radial_law

    def phi(delta: float) -> float:
        """Energy per unit length int_0^delta q: k delta^(n+1)/(n+1), or for Johnson's law, from
        delta(P) = P/(pi E*) (ln(4 pi E* dR / P) - 1) by parts: P^2/(2 pi E*) (ln(4 pi E* dR / P) - 3/2)."""
        if delta <= 0.0:
            return 0.0
        if law.exponent is not None:
            return law.parameters[0] * delta ** (law.exponent + 1) / (law.exponent + 1)
        pi_e, four_dr = law.parameters
        p = law.line_density(delta)
        return p * p / (2 * pi_e) * (math.log(pi_e * four_dr / p) - 1.5)

    def density(z: float) -> float:
        return phi(slice_gradient(m[0] + z * t[0], m[1] + z * t[1], t[0], t[1], r_j, r_b1)[0])

    z_a, z_b, dry = dry_interval(m[0], m[1], t[0], t[1], r_j, r_b1)
    points = sorted({-hl, 0.0, hl, *[min(max(z, -hl), hl) for z in (z_a, z_b)]})
    return sum(quad(density, lo, hi, epsabs=0, epsrel=1e-12, limit=200)[0] for lo, hi in zip(points, points[1:]) if hi > lo)


def axial_energy(joint, rotation, position) -> float:
    """U of both end faces: K_plane / area * int int delta^2 / 2 dA (n_a = 1), angle in closed form."""
    hl, hj = 0.5 * joint.bearing_length, 0.5 * joint.journal_length
    u = rotation[:, 2]
    density = joint.axial_stiffness / (math.pi * (joint.bearing_outer_radius**2 - joint.bearing_inner_radius**2))
    total = 0.0
    for ring in (1.0, -1.0):
        centre_depth = ring * ((ring * hl * np.array([0, 0, 1.0]) - position - ring * hj * u) @ u)
        g = ring * np.hypot(u[0], u[1])

        def over_angle(r: float) -> float:
            a_, b_ = centre_depth, abs(g) * r
            if a_ >= b_:
                th = math.pi
            elif a_ <= -b_:
                return 0.0
            else:
                th = math.acos(-a_ / b_)
            return a_ * a_ * 2 * th + 4 * a_ * b_ * math.sin(th) + b_ * b_ * (th + math.sin(th) * math.cos(th))

        total += 0.5 * density * quad(lambda r: r * over_angle(r), joint.bearing_inner_radius,
                                      joint.bearing_outer_radius, epsabs=0, epsrel=1e-13, limit=200)[0]
    return total


def energy(joint, rotation, position) -> float:
    return radial_energy(joint, rotation, position) + axial_energy(joint, rotation, position)


def fd_wrench(joint, rotation, position, step: float) -> np.ndarray:
    """-grad U by central differences: journal translations (m) and rotations about its origin (rad)."""
    out = np.zeros(6)
    arm = 0.5 * joint.bearing_length
    for i in range(3):
        e = np.eye(3)[i]
        out[i] = -(energy(joint, rotation, position + step * e) - energy(joint, rotation, position - step * e)) / (2 * step)
        h = step / arm
        out[3 + i] = -(energy(joint, rot(e, h) @ rotation, position) - energy(joint, rot(e, -h) @ rotation, position)) / (2 * h)
    return out


@settings(max_examples=15, deadline=None)
@given(
    geometry=st.sampled_from(["R1", "small"]),
    law=st.sampled_from(["linear", "pereira", "hertz_point", "johnson"]),
    tilt_fraction=st.floats(0.0, 1.0),
    skew=st.floats(0.0, 2 * math.pi),
    log_depth=st.floats(math.log(2e-7), math.log(1e-5)),
    axial=st.floats(0.2, 1.0) | st.floats(-1.0, -0.2),  # away from the kink of U at zero depth
)
def test_wrench_is_minus_the_energy_gradient(geometry, law, tilt_fraction, skew, log_depth, axial) -> None:
    joint = make(geometry, radial_law=law)
    depth = math.exp(log_depth)
    rotation, position = pose_at_depth(joint, tilt_fraction, skew, depth)
    # press a flange on its end face too (axial depth up to ~depth at the rim)
    c_half = 0.5 * joint.axial_clearance
    position = position + rotation[:, 2] * (-(c_half + axial * depth))
    res = joint.evaluate(np.eye(3), Z3, Z6, rotation, position, Z6, Z4)
    ref = fd_wrench(joint, rotation, position, step=1e-3 * depth)
    scale_f = np.linalg.norm(ref[:3]) + res.normal_force.sum()
    scale_m = np.linalg.norm(ref[3:]) + 1e-3 * scale_f * joint.bearing_length
    assert np.linalg.norm(res.wrench_inner[:3] - ref[:3]) <= 1e-4 * scale_f, (res.wrench_inner, ref)
    assert np.linalg.norm(res.wrench_inner[3:] - ref[3:]) <= 1e-4 * scale_m, (res.wrench_inner, ref)


@pytest.mark.parametrize("ring", [1.0, -1.0])
def test_axial_wrench_is_minus_the_energy_gradient(ring) -> None:
    """A flange rocking on its end face alone (rim crescent to full annulus)."""
    joint = make("small")
    c_half = 0.5 * joint.axial_clearance
    for tilt, press in ((0.0, 3e-6), (1e-4, 2e-6), (1e-3, -5e-6), (2e-3, 1e-6)):
        rotation = rot([0.3, 1.0, 0.0], tilt)
        position = -ring * (c_half + press) * rotation[:, 2]
        res = joint.evaluate(np.eye(3), Z3, Z6, rotation, position, Z6, Z4)
        assert res.normal_force[[0, 2]].sum() == 0.0 and res.normal_force.sum() > 0.0
        ref = fd_wrench(joint, rotation, position, step=1e-9)
        scale = np.linalg.norm(ref[:3])
        assert np.linalg.norm(res.wrench_inner[:3] - ref[:3]) <= 1e-4 * scale
        assert np.linalg.norm(res.wrench_inner[3:] - ref[3:]) <= 1e-4 * (np.linalg.norm(ref[3:]) + 1e-3 * scale * 0.02)


# --- continuity where the wetted set changes shape ---------------------------------------------------
def test_continuous_when_a_dry_gap_opens_inside_a_half() -> None:
    """Skew tilt with the journal axis closest to the bearing axis inside the top half: as the
    offset grows the wetted set of the top half goes from two pieces (both ends wet, dry
    middle) to one; the wrench must not jump."""
    joint = make("small", restitution=0.8)
    hl = 0.5 * joint.bearing_length
    c_r = joint.radial_clearance
    tilt = 0.9 * c_r / hl
    z_star = hl / 2
    twist = np.array([1e-3, -2e-3, 0.0, 0.05, 0.02, 0.0])

    def state(offset: float):
        t = math.tan(tilt) * np.array([0.0, 1.0])
        m = np.array([offset, -z_star * t[1]])
        rotation = rotation_to(np.array([t[0], t[1], 1.0]))
        return rotation, np.array([m[0], m[1], 0.0])

    offsets = np.linspace(c_r - 6e-6, c_r + 2e-6, 1601)
    wrenches = []
    shapes = set()
    for offset in offsets:
        rotation, position = state(offset)
        res = joint.evaluate(np.eye(3), Z3, Z6, rotation, position, twist, np.full(4, 0.05))
        wrenches.append(res.wrench_inner.copy())
        d = rotation[:, 2]
        t = d[:2] / d[2]
        z_a, z_b, dry = dry_interval(*(position[:2] - position[2] * t), *t, joint.journal_radius, joint.bearing_inner_radius)
        shapes.add((bool(dry and 0 < z_a and z_b < hl), res.kind[0]))
    assert (True, 1) in shapes and (False, 2) in shapes  # both shapes of the top half visited
    w = np.array(wrenches)
    step = np.abs(np.diff(w, axis=0)).max(axis=0)
    scale = np.abs(w).max(axis=0)
    # a jump of J would show as one step >> the typical step; the force grows smoothly
    assert np.all(step <= 20 * np.median(np.abs(np.diff(w, axis=0)), axis=0) + 1e-9 * scale), step / scale
