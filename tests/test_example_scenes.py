"""The shipped example scenes run, on short horizons, and their results are physical.

* ``four_bar`` (ideal, redundant revolute closure): the driving torque is Lagrange's
  closed form (the helper of ``tests/test_redundant_constraints.py``).
* ``four_bar_revolute``, ``slider_crank_revolute`` (revolute clearance at a closure):
  normal forces >= 0, friction within the static coefficient, the journal centre within
  the radial clearance plus the deepest penetration, the radial force the resultant of
  the radial candidates; the slider-crank of Flores & Ambrosio (2004) at 5000 rpm: the
  ideal slider acceleration peak r w^2 (1 + r/l) and the impacts' larger peaks.
* ``slider_crank_translational`` (translational clearance at the slider): forces >= 0,
  the slider within the width clearance, the height faces never touched in this planar
  motion, the slide following the ideal kinematics; with restitution 1 and no friction
  the contact work returns to zero after each impact and the energy balances.
"""

from __future__ import annotations

import filecmp
import math
import warnings
from pathlib import Path

import numpy as np
import pytest

from robot.errors import RedundantConstraintWarning
from robot.run import build_run, run_scene
from robot.scene.loader import load_scene, shipped_scenes
from test_redundant_constraints import FOUR_BAR, THETA0, four_bar_torque

ROOT = Path(__file__).resolve().parents[1]


def run(name: str, duration: float, overrides: dict | None = None):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RedundantConstraintWarning)
        built = build_run(load_scene(name, overrides, duration=duration))
        result = run_scene(built)
    assert result.success, result.message
    return built, result


def test_the_examples_are_shipped():
    assert {"four_bar", "four_bar_revolute", "slider_crank_revolute", "slider_crank_translational"} <= set(shipped_scenes())
    assert filecmp.cmp(ROOT / "urdf" / "four_bar.urdf", FOUR_BAR, shallow=False)  # the closed form's mechanism


def test_ideal_four_bar_crank_torque_is_the_lagrange_closed_form():
    built, result = run("four_bar", 0.05)
    omega = 20.0
    theta = THETA0 + result["q"][:, built.mechanism.actuator_q_index[0]]
    expected = four_bar_torque(theta, omega, np.array([0.0, -9.81]))
    error = np.abs(result["driving_force"][:, 0] - expected).max() / np.abs(expected).max()
    assert error < 1e-6, error


def _journal_checks(built, result, joint: str, static_coefficient: float | None):
    law = built.scene.clearances[0].law
    normal, friction = result[f"{joint}_normal_force"], result[f"{joint}_friction_force"]
    assert normal.min() >= 0.0 and normal.max() > 0.0  # contact happened, never pulling
    if static_coefficient is not None:
        assert np.all(friction <= static_coefficient * normal + 1e-12)
    deepest = result[f"{joint}_penetration"][:, [0, 2]].max()
    radial = np.hypot(*result[f"{joint}_centre_in_outer"][:, :2].T)
    assert radial.max() <= law.radial_clearance + deepest + 1e-12
    assert radial.max() > 0.5 * law.radial_clearance  # the journal did cross its clearance
    assert np.abs(result[f"{joint}_centre_in_outer"][:, 2]).max() < 0.5 * law.axial_clearance  # planar motion
    # radial force: the resultant of the two radial candidates' normal forces (parallel in planar motion)
    np.testing.assert_allclose(result[f"{joint}_radial_force"], normal[:, 0] + normal[:, 2], rtol=1e-9, atol=1e-9)
    assert not result[f"{joint}_axial_force"].any()


def test_four_bar_with_a_revolute_clearance_joint():
    built, result = run("four_bar_revolute", 0.03)
    _journal_checks(built, result, "B", 0.07)


def test_slider_crank_revolute_clearance_benchmark_of_flores_and_ambrosio():
    """5000 rpm, 0.5 mm clearance: the journal flies and impacts; slider accelerations above the ideal peak."""
    built, result = run("slider_crank_revolute", 0.004)
    _journal_checks(built, result, "K", None)
    r, l, omega = 0.05, 0.12, 5000 * 2 * math.pi / 60
    ideal_peak = r * omega**2 * (1 + r / l)  # slider acceleration at the crank's dead centre
    assert ideal_peak == pytest.approx(19420, rel=1e-3)
    acceleration = np.abs(result["ee_acceleration"][:, 0])
    assert acceleration.max() > ideal_peak  # impacts in the clearance add acceleration spikes
    assert result["K_normal_force"].max() > 1e3  # kN-range impact forces (Hertz K = 6.9e10 N/m^1.5)


def test_slider_crank_translational_clearance():
    built, result = run("slider_crank_translational", 0.02)
    law = built.scene.clearances[0].law
    normal = result["slider_normal_force"]
    assert normal.min() >= 0.0 and normal.max() > 0.0
    assert np.all(result["slider_friction_force"] <= 0.12 * normal + 1e-12)
    width_faces = np.arange(16) % 2 == 0
    assert not normal[:, ~width_faces].any()  # the planar motion never reaches the height faces
    centre = result["slider_centre_in_outer"]
    deepest = result["slider_penetration"][:, width_faces].max()
    assert np.abs(centre[:, 0]).max() <= law.width_clearance + deepest + 1e-9
    assert np.abs(centre[:, 1]).max() < 1e-9
    # the slide along the guide follows the ideal slider-crank within a few clearances
    r, l = 0.05, 0.12
    theta = THETA0 + result["q"][:, built.mechanism.actuator_q_index[0]]
    ideal = r * np.cos(theta) + np.sqrt(l * l - (r * np.sin(theta)) ** 2) - 0.14  # from the joint origin
    assert np.abs(centre[:, 2] - ideal).max() < 5 * law.width_clearance
    # lateral force: the resultant of the corner forces, +x face (candidates 0, 4, 8, 12) against -x (2, 6, 10, 14)
    np.testing.assert_allclose(result["slider_lateral_force"], np.abs(normal[:, 0::4].sum(1) - normal[:, 2::4].sum(1)), rtol=1e-6, atol=1e-9)


def test_translational_impacts_with_restitution_one_and_no_friction_keep_the_energy():
    """Out of contact the contact work is back to 0 and E_kin + E_pot - W_actuator is constant."""
    built, result = run(
        "slider_crank_translational", 0.02, {"clearance.slider.restitution": 1.0, "clearance.slider.friction.law": "none", "solver.rtol": 1e-9, "solver.atol": 1e-12}
    )
    free = (result["slider_penetration"] <= 0).all(axis=1)
    touched = np.maximum.accumulate((result["slider_normal_force"] > 0).any(axis=1))
    after = free & touched
    assert after.sum() > 10  # records in flight after an impact
    work = result["contact_work"]
    peak = np.abs(work).max()
    assert peak > 0
    assert np.abs(work[after]).max() < 1e-6 * peak  # measured 2e-8 (rtol 1e-9)
    balance = result["kinetic_energy"] + result["potential_energy"] - result["actuator_work"]
    scale = np.abs(result["actuator_work"]).max() + result["kinetic_energy"].max()
    assert np.abs(balance[after] - balance[0]).max() < 1e-9 * scale  # measured 1.6e-11
