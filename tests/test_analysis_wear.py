"""Archard wear around the bearing: local depth, volume conservation, uniform spreading."""

from __future__ import annotations

import numpy as np
import pytest

from clearance_contact.materials import STEEL, Material, combined_modulus
from robot.analysis import ANALYSES, AnalysisError
from robot.analysis.wear import archard_wear, hertz_line_half_width

K_W = 3.7e-5  # dimensionless wear coefficient (arbitrary: every check scales with it)
HARDNESS = 1.9e9  # Pa
R_B, R_J, LENGTH = 0.0101, 0.0100, 0.02  # m


def test_constant_contact_at_a_fixed_angle_gives_the_local_archard_depth():
    n_bins = 72  # 5 degree bins
    theta0 = 2 * np.pi * (13 + 0.5) / n_bins  # centre of bin 13
    force, speed, duration = 350.0, 0.12, 2.5
    b = 2.2 * (2 * np.pi / n_bins) * R_B  # patch half-width: 2.2 bins each side
    t = np.linspace(0.0, duration, 501)
    out = archard_wear(
        t, np.full_like(t, force), np.full_like(t, theta0), np.full_like(t, speed), np.full_like(t, b),
        wear_coefficient=K_W, hardness=HARDNESS, bearing_radius=R_B, length=LENGTH, n_bins=n_bins,
    )
    pressure = force / (2 * b * LENGTH)
    local = K_W * pressure * speed * duration / HARDNESS
    depth = out["depth"]
    # the patch spans bins 13.5 +- 2.2 = [11.3, 15.7]: bins 12..14 fully, 11 and 15 to 0.7, the rest untouched
    np.testing.assert_allclose(depth[12:15], local, rtol=1e-12)
    np.testing.assert_allclose(depth[[11, 15]], 0.7 * local, rtol=1e-9)
    assert np.all(depth[:11] == 0.0) and np.all(depth[16:] == 0.0)
    assert float(out["max_depth"]) == pytest.approx(local, rel=1e-12)
    assert round(float(out["angle_of_max_depth"]) / (2 * np.pi / n_bins) - 0.5) in (12, 13, 14)
    # Archard's volume law V = k_w F s / H
    assert float(out["volume"]) == pytest.approx(K_W * force * speed * duration / HARDNESS, rel=1e-12)
    assert float(out["sliding_distance"]) == pytest.approx(speed * duration)


def test_hertz_half_width_matches_the_peak_pressure_form():
    """b from b^2 = 4 F R* / (pi L E*) against b = 2 F / (pi L p0), p0 = sqrt(F E* / (pi L R*)) (Johnson 1985, 4.2)."""
    bronze = Material(1.1e11, 0.34)
    e_star = combined_modulus(STEEL, bronze)
    force = np.array([0.0, 10.0, 2.5e3])
    b = hertz_line_half_width(force, journal_radius=R_J, bearing_radius=R_B, length=LENGTH, combined_modulus=e_star)
    r_star = R_J * R_B / (R_B - R_J)
    p0 = np.sqrt(force[1:] * e_star / (np.pi * LENGTH * r_star))
    np.testing.assert_allclose(b[1:], 2 * force[1:] / (np.pi * LENGTH * p0), rtol=1e-12)
    assert b[0] == 0.0


@pytest.mark.parametrize("n_bins, seed", [(37, 1), (360, 2)])
def test_volume_is_conserved_for_any_history(n_bins, seed):
    """sum_j h_j R_b dtheta L = (k_w / H) integral F v_s dt, whatever the force, angle, width histories."""
    rng = np.random.default_rng(seed)
    t = np.cumsum(rng.uniform(1e-4, 2e-3, 3000))
    force = np.clip(400 * np.sin(7 * t) + rng.normal(0, 50, t.size), 0.0, None)  # contact lost and regained
    angle = 6.0 * np.sin(3 * t) + rng.normal(0, 0.3, t.size)  # crosses 0 and 2 pi both ways
    speed = 0.2 * np.cos(11 * t)  # sign does not matter
    out = archard_wear(
        t, force, angle, speed, wear_coefficient=K_W, hardness=HARDNESS, bearing_radius=R_B, length=LENGTH,
        n_bins=n_bins, journal_radius=R_J, combined_modulus=combined_modulus(STEEL, STEEL),
    )
    expected = K_W / HARDNESS * np.trapezoid(force * np.abs(speed), t)
    assert float(out["volume"]) == pytest.approx(expected, rel=1e-12)
    assert np.all(out["depth"] >= 0.0)


def test_force_history_with_analytic_integral():
    # F = F0 (1 + sin(w t)) over whole periods, constant slip: V = k_w F0 v T / H
    t = np.linspace(0.0, 4 * np.pi, 20001)
    force = 120.0 * (1 + np.sin(t))
    out = archard_wear(
        t, force, np.full_like(t, 1.0), np.full_like(t, 0.05), np.full_like(t, 1e-4),
        wear_coefficient=K_W, hardness=HARDNESS, bearing_radius=R_B, length=LENGTH,
    )
    assert float(out["volume"]) == pytest.approx(K_W * 120.0 * 0.05 * 4 * np.pi / HARDNESS, rel=1e-7)


def test_rotating_contact_spreads_wear_uniformly():
    revolutions, omega = 5, 2 * np.pi * 3.0
    t = np.linspace(0.0, revolutions * 2 * np.pi / omega, 50001)
    force, speed = 80.0, omega * R_J
    out = ANALYSES["archard_wear"](
        t=t, normal_force=np.full_like(t, force), contact_angle=omega * t + 0.3, sliding_speed=np.full_like(t, speed),
        wear_coefficient=K_W, hardness=HARDNESS, bearing_radius=R_B, length=LENGTH, n_bins=90,
        journal_radius=R_J, combined_modulus=combined_modulus(STEEL, STEEL),
    )
    uniform = K_W * force * speed * t[-1] / HARDNESS / (2 * np.pi * R_B * LENGTH)
    np.testing.assert_allclose(out["depth"], uniform, rtol=2e-4)


def test_bad_inputs_raise():
    t = np.linspace(0, 1, 5)
    one = np.ones(5)
    common = dict(wear_coefficient=K_W, hardness=HARDNESS, bearing_radius=R_B, length=LENGTH)
    with pytest.raises(AnalysisError, match="normal_force must be >= 0"):
        archard_wear(t, -one, one, one, one, **common)
    with pytest.raises(AnalysisError, match="give half_width, or journal_radius and combined_modulus"):
        archard_wear(t, one, one, one, **common)
    with pytest.raises(AnalysisError, match="exceeds half the bearing circumference"):
        archard_wear(t, one, one, one, 4 * R_B * one, **common)
    with pytest.raises(AnalysisError, match="bearing_radius=0.01 must exceed journal_radius=0.0101"):
        hertz_line_half_width(one, journal_radius=R_B, bearing_radius=R_J, length=LENGTH, combined_modulus=1e11)
    with pytest.raises(AnalysisError, match="hardness=-1.0 must be positive"):
        archard_wear(t, one, one, one, one, **{**common, "hardness": -1.0})
    with pytest.raises(AnalysisError, match="contact_angle has 4 rows"):
        archard_wear(t, one, one[:4], one, one, **common)
