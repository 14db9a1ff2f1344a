"""Friction laws: Brown-McPhee (continuous), Coulomb (sign / regularised), none."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from clearance_contact import (
    BrownMcPheeFriction,
    ContactParameterError,
    CoulombFriction,
    FrictionLaw,
    NoFriction,
    ScalarFrictionLaw,
)

MU_S, MU_K, V_S = 0.12, 0.05, 1e-3
BM = BrownMcPheeFriction(static_coefficient=MU_S, dynamic_coefficient=MU_K, transition_velocity=V_S)

vectors = st.lists(st.floats(-10.0, 10.0), min_size=3, max_size=3).map(np.array)
normal_forces = st.floats(0.0, 1e5)


def _magnitude(law, normal_force: float, speed: float) -> float:
    return float(np.linalg.norm(law.force(normal_force, [speed, 0.0, 0.0])))


def test_protocols() -> None:
    for law in (BM, CoulombFriction(0.1), CoulombFriction(0.1, 1e-3), NoFriction()):
        assert isinstance(law, FrictionLaw)
        assert isinstance(law, ScalarFrictionLaw)


# --- Brown-McPhee ---------------------------------------------------------------------------
@settings(max_examples=200, deadline=None)
@given(normal_force=normal_forces, slip=vectors)
def test_brown_mcphee_is_odd_and_opposed_to_slip(normal_force: float, slip: np.ndarray) -> None:
    law = BrownMcPheeFriction(MU_S, MU_K, V_S, viscous_coefficient=3.0, reference_force=10.0)
    f = law.force(normal_force, slip)
    np.testing.assert_allclose(law.force(normal_force, -slip), -f, rtol=1e-15, atol=0.0)
    assert np.all(np.isfinite(f))
    speed = np.linalg.norm(slip)
    # anti-parallel to the slip: f = -g v with g >= 0
    np.testing.assert_allclose(np.cross(f, slip), 0.0, atol=1e-9 * (1.0 + np.linalg.norm(f) * speed))
    assert f @ slip <= 0.0
    assert law.coefficient(-speed) == pytest.approx(-law.coefficient(speed), rel=1e-15, abs=0.0)


def test_brown_mcphee_finite_and_continuous_at_zero_slip() -> None:
    normal_force = 250.0
    assert np.array_equal(BM.force(normal_force, np.zeros(3)), np.zeros(3))
    g0 = BM.force_over_speed(normal_force, 0.0)
    # analytic limit f(v)/v at v -> 0: F_N (4 mu_k + 16/9 (mu_s - mu_k)) / v_s
    assert g0 == pytest.approx(normal_force * (4 * MU_K + 16.0 / 9.0 * (MU_S - MU_K)) / V_S, rel=1e-14)
    for v in (1e-300, 1e-200, 1e-12, 1e-9):
        assert BM.force_over_speed(normal_force, v) == pytest.approx(g0, rel=1e-9)
    # no jump across zero: the force goes to zero linearly from both sides
    for eps in (1e-6, 1e-9, 1e-12):
        plus = BM.force(normal_force, [eps, 0.0, 0.0])[0]
        minus = BM.force(normal_force, [-eps, 0.0, 0.0])[0]
        assert plus == pytest.approx(-g0 * eps, rel=1e-3)
        assert minus == pytest.approx(g0 * eps, rel=1e-3)


def test_brown_mcphee_peak_near_static_coefficient_at_transition_velocity() -> None:
    speeds = np.linspace(0.0, 10.0 * V_S, 20001)
    mu = np.array([BM.coefficient(v) for v in speeds])
    i = int(np.argmax(mu))
    assert mu[i] == pytest.approx(MU_S, rel=0.01)
    assert speeds[i] == pytest.approx(V_S, rel=0.05)
    assert BM.coefficient(V_S) == pytest.approx(MU_S, rel=1e-3)
    # the peak is a Stribeck hump: higher than both the kinetic level and the low-speed values
    assert mu[i] > BM.coefficient(10 * V_S) > MU_K
    assert BM.coefficient(0.1 * V_S) < 0.5 * MU_S


def test_brown_mcphee_tends_to_kinetic_coefficient() -> None:
    for factor, tol in ((100.0, 2e-4), (1e3, 1e-6), (1e5, 1e-12)):
        assert BM.coefficient(factor * V_S) == pytest.approx(MU_K, rel=tol)
    assert _magnitude(BM, 80.0, 1e3 * V_S) == pytest.approx(MU_K * 80.0, rel=1e-6)


def test_brown_mcphee_viscous_term() -> None:
    """f -> mu_k F_N + mu_v v tanh(4 F_N / F_ref) at high slip; vanishes with F_N."""
    law = BrownMcPheeFriction(MU_S, MU_K, V_S, viscous_coefficient=2.0, reference_force=50.0)
    v = 0.5
    for normal_force in (1.0, 50.0, 1000.0):
        expected = MU_K * normal_force * math.tanh(4 * v / V_S) + 2.0 * v * math.tanh(4 * normal_force / 50.0)
        assert _magnitude(law, normal_force, v) == pytest.approx(expected, rel=1e-6)
    assert _magnitude(law, 0.0, v) == 0.0


def test_zero_normal_force_gives_zero_friction() -> None:
    for law in (BM, CoulombFriction(0.2), CoulombFriction(0.2, 1e-3)):
        assert np.array_equal(law.force(0.0, [0.1, -0.2, 0.3]), np.zeros(3))


@settings(max_examples=100, deadline=None)
@given(normal_force=normal_forces, slip=vectors)
def test_scalar_fast_path_matches_vector_force(normal_force: float, slip: np.ndarray) -> None:
    for law in (BM, CoulombFriction(0.3, 1e-3)):
        g = law.force_over_speed(normal_force, float(np.linalg.norm(slip)))
        np.testing.assert_allclose(-g * slip, law.force(normal_force, slip), rtol=1e-13, atol=1e-300)


# --- Coulomb ----------------------------------------------------------------------------------
@settings(max_examples=200, deadline=None)
@given(
    normal_force=st.floats(1e-3, 1e5),
    slip=vectors,
    scale=st.sampled_from([1e-300, 1e-150, 1e-9, 1.0, 1e3]),
)
def test_coulomb_sign_law_magnitude_at_any_nonzero_slip(normal_force: float, slip: np.ndarray, scale: float) -> None:
    slip = slip * scale
    assume(math.hypot(*slip) > 0.0)
    law = CoulombFriction(0.15)
    f = law.force(normal_force, slip)
    assert np.linalg.norm(f) == pytest.approx(0.15 * normal_force, rel=1e-12)
    unit = slip / np.abs(slip).max()
    unit /= np.linalg.norm(unit)
    np.testing.assert_allclose(f, -0.15 * normal_force * unit, rtol=1e-12, atol=1e-12 * normal_force)


def test_coulomb_sign_law_is_discontinuous_at_zero() -> None:
    """By construction: +-mu F_N on either side of zero slip, 0 at zero slip."""
    law = CoulombFriction(0.15)
    assert law.force(100.0, [1e-12, 0, 0])[0] == pytest.approx(-15.0)
    assert law.force(100.0, [-1e-12, 0, 0])[0] == pytest.approx(15.0)
    assert np.array_equal(law.force(100.0, np.zeros(3)), np.zeros(3))
    assert law.coefficient(0.0) == 0.0 and law.coefficient(1e-30) == 0.15 and law.coefficient(-2.0) == -0.15


def test_regularised_coulomb_is_continuous() -> None:
    law = CoulombFriction(0.15, regularisation_velocity=1e-4)
    g0 = law.force_over_speed(100.0, 0.0)
    assert g0 == pytest.approx(0.15 * 100.0 / 1e-4, rel=1e-14)
    assert law.force(100.0, [1e-12, 0, 0])[0] == pytest.approx(-g0 * 1e-12, rel=1e-6)
    assert _magnitude(law, 100.0, 1.0) == pytest.approx(15.0, rel=1e-12)
    assert law.coefficient(-1.0) == pytest.approx(-0.15)


def test_no_friction() -> None:
    law = NoFriction()
    assert law.coefficient(3.0) == 0.0
    assert np.array_equal(law.force(1e4, [1.0, 2.0, 3.0]), np.zeros(3))
    assert law.force_over_speed(1e4, 0.0) == 0.0


# --- invalid parameters -------------------------------------------------------------------------
@pytest.mark.parametrize(
    ("kwargs", "name"),
    [
        ({"static_coefficient": -0.1, "dynamic_coefficient": 0.05, "transition_velocity": 1e-3}, "static_coefficient"),
        ({"static_coefficient": 0.1, "dynamic_coefficient": -0.05, "transition_velocity": 1e-3}, "dynamic_coefficient"),
        ({"static_coefficient": 0.03, "dynamic_coefficient": 0.05, "transition_velocity": 1e-3}, "static_coefficient"),
        ({"static_coefficient": 0.1, "dynamic_coefficient": 0.05, "transition_velocity": 0.0}, "transition_velocity"),
        ({"static_coefficient": 0.1, "dynamic_coefficient": 0.05, "transition_velocity": -1e-3}, "transition_velocity"),
        (
            {"static_coefficient": 0.1, "dynamic_coefficient": 0.05, "transition_velocity": 1e-3, "viscous_coefficient": -1},
            "viscous_coefficient",
        ),
        (
            {"static_coefficient": 0.1, "dynamic_coefficient": 0.05, "transition_velocity": 1e-3, "reference_force": 0.0},
            "reference_force",
        ),
    ],
)
def test_invalid_brown_mcphee(kwargs: dict, name: str) -> None:
    with pytest.raises(ContactParameterError, match=name) as info:
        BrownMcPheeFriction(**kwargs)
    assert isinstance(info.value, ValueError)


def test_static_below_dynamic_message() -> None:
    with pytest.raises(
        ContactParameterError, match=r"static_coefficient=0\.03 must be >= dynamic_coefficient=0\.05"
    ):
        BrownMcPheeFriction(0.03, 0.05, 1e-3)


@pytest.mark.parametrize(
    ("args", "name"), [((-0.1,), "coefficient"), ((0.1, -1e-3), "regularisation_velocity"), ((float("inf"),), "coefficient")]
)
def test_invalid_coulomb(args: tuple, name: str) -> None:
    with pytest.raises(ContactParameterError, match=name):
        CoulombFriction(*args)
