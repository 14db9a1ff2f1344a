"""Exudyn (an independent multibody engine) against the Lagrange model: short horizons, asserted tolerances.

The Lagrange reference runs with the validation's pinned solver
(``robot.validation.settings.VALIDATION_SOLVER``), not with the scene's ``[solver]``.
"""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("exudyn")

from robot.run import run_scene  # noqa: E402
from robot.scene.loader import load_scene  # noqa: E402
from robot.validation import exudyn_model as EX  # noqa: E402
from robot.validation import study  # noqa: E402
from robot.validation.settings import VALIDATION_SOLVER, validation_run  # noqa: E402
from scipy.interpolate import CubicSpline  # noqa: E402
from tests.conftest import calibrated_scene  # noqa: E402


def _pair(scene: str, duration: float):
    # the compound scenes as the thresholds were calibrated (centred start, 40 mm bearing: tests/conftest.py)
    run = validation_run(calibrated_scene(scene, duration=duration) if scene.startswith("compound") else load_scene(scene).with_changes({"duration": duration}))
    lagrange = run_scene(run)
    assert lagrange.metadata["method"] == VALIDATION_SOLVER.method and lagrange.metadata["rtol"] == VALIDATION_SOLVER.rtol
    assert lagrange.success, lagrange.message
    result = EX.simulate(run, study.exudyn_settings_for(run))
    assert result.success, result.message
    return run, lagrange, result


def _interpolated(lagrange, key: str, t: np.ndarray, t_end: float) -> np.ndarray:
    keep = lagrange["t"] < t_end
    times, index = np.unique(lagrange["t"][keep], return_index=True)
    return CubicSpline(times, lagrange[key][keep][index])(t)


def test_ideal_mechanism_agrees_with_the_lagrange_model():
    """Generalized-alpha (h = 1e-4 s) against RK45: driving forces within 0.1 %, end effector within 1 um, over 0.1 s."""
    _, lagrange, result = _pair("ideal", 0.1)
    t = result.t[1:]  # the driving force at t = 0 is not an Exudyn output
    force = _interpolated(lagrange, "driving_force", t, np.inf)
    ee = _interpolated(lagrange, "ee_position", t, np.inf)
    scale = np.max(np.abs(lagrange["driving_force"]))
    assert np.max(np.abs(result.driving_force[1:] - force)) <= 1e-3 * scale
    assert np.max(np.abs(result.ee_position[1:] - ee)) <= 1e-6
    # after the generalized-alpha start-up (first 10 steps) the agreement is much closer
    late = t > 10 * result.settings.step_size
    assert np.max(np.abs(result.driving_force[1:][late] - force[late])) <= 5e-5 * scale


def test_spherical_clearance_agrees_before_and_at_the_first_impact():
    """S1 clearance: pre-impact driving forces within 0.1 %, EE within 1 um; first contact and its peak agree."""
    _, lagrange, result = _pair("spherical", 0.0115)
    first = lagrange["event_t"][lagrange["event_is_onset"]].min()
    h = result.settings.step_size
    before = (result.t > 0) & (result.t < first)
    force = _interpolated(lagrange, "driving_force", result.t[before], first)
    ee = _interpolated(lagrange, "ee_position", result.t[before], first)
    scale = np.max(np.abs(force))
    assert np.max(np.abs(result.driving_force[before] - force)) <= 1e-3 * scale
    assert np.max(np.abs(result.ee_position[before] - ee)) <= 1e-6
    penetration = result.contact["S1"]["penetration"][:, 0]
    exudyn_first = result.t[np.argmax(penetration > 0)]
    assert first <= exudyn_first <= first + h + 1e-12  # the first step that ends in contact
    peak_lagrange = np.max(lagrange["S1_normal_force"])
    peak_exudyn = np.max(result.contact["S1"]["normal_force"])
    assert peak_lagrange > 1000.0
    assert abs(peak_exudyn - peak_lagrange) <= 0.02 * peak_lagrange


def test_compound_clearance_first_impact_agrees():
    """S1 + R1 clearance: the first (axial R1) impact starts in the same step and reaches the same peak."""
    _, lagrange, result = _pair("compound", 0.0052)
    first = lagrange["event_t"][lagrange["event_is_onset"]].min()
    h = result.settings.step_size
    penetration = result.contact["R1"]["penetration"]
    exudyn_first = result.t[np.argmax(np.any(penetration > 0, axis=1))]
    assert first <= exudyn_first <= first + h + 1e-12
    peak_lagrange = np.max(np.sum(lagrange["R1_normal_force"], axis=1))
    peak_exudyn = np.max(np.sum(result.contact["R1"]["normal_force"], axis=1))
    assert peak_lagrange > 1000.0
    assert abs(peak_exudyn - peak_lagrange) <= 0.02 * peak_lagrange
    before = (result.t > 0) & (result.t < first)
    ee = _interpolated(lagrange, "ee_position", result.t[before], first)
    assert np.max(np.abs(result.ee_position[before] - ee)) <= 1e-6
