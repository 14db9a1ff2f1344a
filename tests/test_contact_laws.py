"""Normal contact laws and stiffnesses: Lankarani-Nikravesh, Hertz (physics checks)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.integrate import solve_ivp

from clearance_contact import (
    ONSET_RATE_FLOOR,
    STEEL,
    ContactParameterError,
    Material,
    combined_modulus,
    cylinder_line_stiffness,
    flat_punch_stiffness,
    hertz_impact_maximum,
    hertz_sphere_stiffness,
    lankarani_nikravesh,
    validate_normal_law,
)

K_STEEL = 2.2e11  # N/m^1.5, order of a 15 mm steel ball in a 15.1 mm socket


# --- Lankarani-Nikravesh -------------------------------------------------------------
@pytest.mark.parametrize("penetration", [0.0, -1e-9, -1e-3])
@pytest.mark.parametrize("rate", [-10.0, 0.0, 10.0])
def test_no_force_without_penetration(penetration: float, rate: float) -> None:
    assert lankarani_nikravesh(penetration, rate, 1.0, K_STEEL, 1.5, 0.5) == 0.0


@pytest.mark.parametrize("exponent", [1.0, 1.25, 1.5])
def test_perfectly_elastic_law_is_pure_hertz(exponent: float) -> None:
    """c_e = 1: the damping term vanishes whatever the rate: F = K delta^n."""
    for delta in (1e-7, 1e-6, 2e-5):
        for rate in (-3.0, 0.0, 0.7):
            expected = K_STEEL * delta**exponent
            assert lankarani_nikravesh(delta, rate, 0.5, K_STEEL, exponent, 1.0) == pytest.approx(expected, rel=1e-14)


@pytest.mark.parametrize("restitution", [0.3, 0.7, 0.9, 0.99])
def test_hysteresis_term(restitution: float) -> None:
    """F / (K delta^n) - 1 = 3 (1 - c_e^2)/4 * rate / onset_rate, independent of delta."""
    onset = 0.4
    for delta in (1e-7, 1e-5):
        elastic = K_STEEL * delta**1.5
        for rate in (0.4, 0.1, -0.1):
            force = lankarani_nikravesh(delta, rate, onset, K_STEEL, 1.5, restitution)
            expected = 0.75 * (1.0 - restitution**2) * rate / onset
            assert force / elastic - 1.0 == pytest.approx(expected, rel=1e-12)


def test_loading_is_stiffer_than_unloading() -> None:
    """Hysteresis: same penetration, approaching (rate > 0) pushes harder than separating."""
    f_in = lankarani_nikravesh(1e-5, 0.3, 0.5, K_STEEL, 1.5, 0.8)
    f_out = lankarani_nikravesh(1e-5, -0.3, 0.5, K_STEEL, 1.5, 0.8)
    f_static = lankarani_nikravesh(1e-5, 0.0, 0.5, K_STEEL, 1.5, 0.8)
    assert f_in > f_static > f_out > 0.0


@pytest.mark.parametrize("onset", [0.0, -0.2, 0.5 * ONSET_RATE_FLOOR, ONSET_RATE_FLOOR])
def test_onset_rate_floor(onset: float) -> None:
    """Grazing or non-approaching onset: the floor replaces the onset rate (finite force)."""
    floored = lankarani_nikravesh(1e-6, 1e-5, ONSET_RATE_FLOOR, K_STEEL, 1.5, 0.9)
    force = lankarani_nikravesh(1e-6, 1e-5, onset, K_STEEL, 1.5, 0.9)
    assert math.isfinite(force)
    assert force == floored
    assert force > K_STEEL * 1e-6**1.5  # the damping term acts, with the floored rate


def test_force_is_clamped_at_zero_in_fast_separation() -> None:
    """Damping larger than the elastic term would pull: the law clamps at 0 (no adhesion)."""
    assert lankarani_nikravesh(1e-6, -1.0, ONSET_RATE_FLOOR, K_STEEL, 1.5, 0.5) == 0.0


@settings(max_examples=300, deadline=None)
@given(
    delta=st.floats(-1e-3, 1e-3),
    rate=st.floats(-100.0, 100.0),
    onset=st.floats(-10.0, 10.0),
    exponent=st.floats(1.0, 1.5),
    restitution=st.floats(1e-3, 1.0),
)
def test_force_is_finite_and_non_negative(delta, rate, onset, exponent, restitution) -> None:
    force = lankarani_nikravesh(delta, rate, onset, K_STEEL, exponent, restitution)
    assert math.isfinite(force) and force >= 0.0


# --- Hertz impact peak ------------------------------------------------------------------
@pytest.mark.parametrize("exponent", [1.0, 1.25, 1.5])
def test_hertz_impact_maximum_matches_integration(exponent: float) -> None:
    """Integrate m x'' = -K x^n from x = 0, x' = v: the peak equals the energy balance."""
    k, m, v = (K_STEEL if exponent == 1.5 else 1e9), 2.0, 0.8

    def rhs(t, y):
        return [y[1], -lankarani_nikravesh(y[0], y[1], v, k, exponent, 1.0) / m]

    def turning(t, y):
        return y[1]

    turning.terminal = True
    turning.direction = -1
    sol = solve_ivp(rhs, (0.0, 1.0), [0.0, v], method="DOP853", rtol=1e-12, atol=1e-18, events=turning)
    delta_num = sol.y_events[0][0][0]
    peak = hertz_impact_maximum(k, m, v, exponent)
    assert delta_num == pytest.approx(peak.penetration, rel=1e-8)
    assert k * delta_num**exponent == pytest.approx(peak.force, rel=1e-8)


def test_hertz_impact_maximum_hertz_form() -> None:
    """n = 3/2: delta_max = (5 m v^2 / (4 K))^(2/5), F_max = K delta_max^1.5 (MODEL-NOTES 4)."""
    k, m, v = K_STEEL, 0.7, 0.3
    peak = hertz_impact_maximum(k, m, v)
    delta = (5.0 * m * v**2 / (4.0 * k)) ** 0.4
    assert peak.penetration == pytest.approx(delta, rel=1e-14)
    assert peak.force == pytest.approx(k * delta**1.5, rel=1e-14)


# --- stiffnesses --------------------------------------------------------------------------
def test_internal_sphere_stiffness_formula() -> None:
    """K = 4 / (3 (s_i + s_j)) sqrt(R_i R_j / (R_i - R_j)), s = (1 - nu^2)/E (MODEL-NOTES 4)."""
    socket, ball = Material(210e9, 0.29), Material(70e9, 0.33)
    r_i, r_j = 0.0151, 0.015
    s_i = (1 - 0.29**2) / 210e9
    s_j = (1 - 0.33**2) / 70e9
    expected = 4.0 / (3.0 * (s_i + s_j)) * math.sqrt(r_i * r_j / (r_i - r_j))
    assert hertz_sphere_stiffness(r_i, r_j, socket, ball) == pytest.approx(expected, rel=1e-14)
    # the order of the two materials does not matter, the order of the radii does
    assert hertz_sphere_stiffness(r_i, r_j, ball, socket) == pytest.approx(expected, rel=1e-14)


def test_sphere_on_flat_limit() -> None:
    """A socket of huge radius is a flat: K -> 4/3 E* sqrt(R_ball) (Johnson 1985, sphere on plane)."""
    r = 0.01
    e_star = combined_modulus(STEEL, STEEL)
    flat = 4.0 / 3.0 * e_star * math.sqrt(r)
    for internal in (True, False):
        assert hertz_sphere_stiffness(1e6, r, STEEL, STEEL, internal=internal) == pytest.approx(flat, rel=1e-7)


def test_equal_spheres_external() -> None:
    """Two identical steel spheres: R* = R/2, E* = E / (2 (1 - nu^2))."""
    r = 0.02
    e_star = 200e9 / (2.0 * (1.0 - 0.3**2))
    expected = 4.0 / 3.0 * e_star * math.sqrt(r / 2.0)
    assert hertz_sphere_stiffness(r, r, STEEL, STEEL, internal=False) == pytest.approx(expected, rel=1e-14)


def test_conformity_stiffens_internal_contact() -> None:
    """Smaller clearance, more conforming surfaces: internal stiffness grows as c^(-1/2)."""
    ks = [hertz_sphere_stiffness(0.015 + c, 0.015, STEEL, STEEL) for c in (1e-3, 1e-4, 1e-5)]
    assert ks[0] < ks[1] < ks[2]
    # K ~ sqrt(R^2 / c) for c << R: a factor 10 in c is sqrt(10) in K (to O(c/R))
    assert ks[2] / ks[1] == pytest.approx(math.sqrt(10.0), rel=1e-2)


def test_line_stiffness_from_2d_hertz() -> None:
    """K = pi/4 E* L: with the 2-D Hertz half-width a^2 = 4 P R/(pi E*), F = K a^2 / R."""
    length, r_eff, force = 0.02, 0.3, 500.0
    e_star = combined_modulus(STEEL, STEEL)
    a2 = 4.0 * (force / length) * r_eff / (math.pi * e_star)
    assert cylinder_line_stiffness(length, STEEL, STEEL) * a2 / r_eff == pytest.approx(force, rel=1e-13)


def test_flat_punch_stiffness() -> None:
    """Rigid flat punch (Boussinesq): F = 2 a E* delta; linear in the radius."""
    e_star = combined_modulus(STEEL, Material(70e9, 0.33))
    assert flat_punch_stiffness(0.01, STEEL, Material(70e9, 0.33)) == pytest.approx(2 * 0.01 * e_star, rel=1e-14)
    assert flat_punch_stiffness(0.02, STEEL, STEEL) == pytest.approx(2 * flat_punch_stiffness(0.01, STEEL, STEEL))


# --- invalid parameters -----------------------------------------------------------------------
@pytest.mark.parametrize(
    ("kwargs", "name"),
    [
        ({"youngs_modulus": 0.0, "poisson_ratio": 0.3}, "youngs_modulus"),
        ({"youngs_modulus": -1e9, "poisson_ratio": 0.3}, "youngs_modulus"),
        ({"youngs_modulus": float("nan"), "poisson_ratio": 0.3}, "youngs_modulus"),
        ({"youngs_modulus": 2e11, "poisson_ratio": 0.5}, "poisson_ratio"),
        ({"youngs_modulus": 2e11, "poisson_ratio": -1.0}, "poisson_ratio"),
        ({"youngs_modulus": 2e11, "poisson_ratio": 0.7}, "poisson_ratio"),
    ],
)
def test_invalid_material(kwargs: dict, name: str) -> None:
    with pytest.raises(ContactParameterError, match=name):
        Material(**kwargs)


@pytest.mark.parametrize(
    ("args", "name"),
    [
        ((0.0, 1.5, 0.9), "stiffness"),
        ((-1e10, 1.5, 0.9), "stiffness"),
        ((1e10, 0.99, 0.9), "exponent"),
        ((1e10, 1.6, 0.9), "exponent"),
        ((1e10, 1.5, 0.0), "restitution"),
        ((1e10, 1.5, -0.2), "restitution"),
        ((1e10, 1.5, 1.01), "restitution"),
    ],
)
def test_invalid_normal_law(args: tuple, name: str) -> None:
    with pytest.raises(ContactParameterError, match=name) as info:
        validate_normal_law(*args)
    assert isinstance(info.value, ValueError)


def test_invalid_stiffness_inputs() -> None:
    with pytest.raises(ContactParameterError, match=r"outer_radius=0\.015 must be larger than inner_radius=0\.015"):
        hertz_sphere_stiffness(0.015, 0.015, STEEL, STEEL)
    with pytest.raises(ContactParameterError, match="inner_radius"):
        hertz_sphere_stiffness(0.015, -0.01, STEEL, STEEL)
    with pytest.raises(ContactParameterError, match="length"):
        cylinder_line_stiffness(0.0, STEEL, STEEL)
    with pytest.raises(ContactParameterError, match="radius"):
        flat_punch_stiffness(-1.0, STEEL, STEEL)
    with pytest.raises(ContactParameterError, match="effective_mass"):
        hertz_impact_maximum(1e10, 0.0, 1.0)
    with pytest.raises(ContactParameterError, match="impact_speed"):
        hertz_impact_maximum(1e10, 1.0, -1.0)


def test_restitution_message_names_range() -> None:
    with pytest.raises(ContactParameterError, match=r"restitution=1\.2 is outside the valid range \(0, 1\]"):
        validate_normal_law(1e10, 1.5, 1.2)
    assert np.isfinite(ONSET_RATE_FLOOR) and ONSET_RATE_FLOOR > 0.0
