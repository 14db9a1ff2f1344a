"""The paper's claims: each measure is checked on constructed results whose verdict is known, and on a real run."""

from __future__ import annotations

import json

import numpy as np
import pytest

from robot.analysis import claims as CL
from robot.analysis.paper import run_study, write_outputs
from robot.io.results import Result

T = np.linspace(0.0, 2.0, 4001)


def _result(name: str, r1_force, s1_force, ee_position, driving) -> Result:
    arrays = {
        "t": T,
        "R1_normal_force": np.column_stack([r1_force, np.zeros_like(T)]),
        "S1_normal_force": s1_force[:, None],
        "ee_position": ee_position,
        "ee_velocity": np.gradient(ee_position, T, axis=0),
        "ee_acceleration": np.gradient(np.gradient(ee_position, T, axis=0), T, axis=0),
        "driving_force": driving,
    }
    return Result(name, 0, "", None, 2.0, {}, arrays, {"actuated_joints": ["P1", "P5"], "clearance": ["S1", "R1"]})


def _ideal_motion() -> np.ndarray:
    return np.column_stack([0.015 * np.sin(2 * np.pi * T), 0.0 * T, 1.0 + 0.01 * np.cos(2 * np.pi * T)])


def _cases(first_impact_aligned: float, first_impact_misaligned: float, stable_r1: float, wobble: float):
    ideal_motion = _ideal_motion()
    ripple = np.column_stack([0 * T, wobble * np.sin(40 * np.pi * T), 0 * T])
    impact = lambda peak: peak * np.exp(-(((T - 0.02) / 0.003) ** 2))  # noqa: E731 - one transient per case
    s1 = 1000.0 + 200.0 * np.sin(2 * np.pi * T) ** 2
    r1 = stable_r1 * (1.0 + 0.2 * np.sin(2 * np.pi * T) ** 2)
    driving = lambda peak: np.column_stack([100 + 0 * T, 500 + impact(peak)])  # noqa: E731
    return {
        "ideal": _result("ideal", 0 * T, 0 * T, ideal_motion, driving(0.0)),
        "compound": _result("compound", r1 + impact(first_impact_aligned), s1 + impact(first_impact_aligned), ideal_motion + ripple, driving(first_impact_aligned)),
        "compound_misaligned": _result(
            "compound_misaligned", r1 + impact(first_impact_misaligned), s1 + impact(first_impact_misaligned), ideal_motion + ripple, driving(first_impact_misaligned)
        ),
    }


def test_claims_hold_where_constructed_to_hold():
    results = _cases(first_impact_aligned=2000.0, first_impact_misaligned=9000.0, stable_r1=500.0, wobble=2e-6)
    a, b, c, e = CL.claim_a(results), CL.claim_b(results, 1.0), CL.claim_c(results, 1.0), CL.claim_e(results, 1.0)
    assert a.holds and b.holds and c.holds
    assert a.numbers["R1_peak_N"]["misaligned"] == pytest.approx(500.0 + 9000.0, rel=1e-3)
    assert b.numbers["ee_rms_difference_between_cases_m"] == pytest.approx(0.0, abs=1e-15)  # identical after the transient
    assert c.numbers["compound"]["R1_over_S1"] == pytest.approx(600.0 / 1200.0, rel=1e-3)
    # a 2 um ripple at 20 Hz: inconspicuous in position, large in acceleration ((40 pi)^2 x 2e-6 ~ 0.03 m/s^2 vs 0.6 m/s^2 ideal)
    assert e.numbers["ee_position"]["relative"] < CL.INCONSPICUOUS
    assert e.numbers["ee_acceleration"]["relative"] == pytest.approx(
        (40 * np.pi) ** 2 * 2e-6 / np.sqrt(2) / (4 * np.pi**2 * np.sqrt(0.015**2 + 0.01**2) / np.sqrt(2)), rel=0.05
    )


def test_claims_fail_where_constructed_to_fail():
    results = _cases(first_impact_aligned=9000.0, first_impact_misaligned=2000.0, stable_r1=3000.0, wobble=2e-3)
    assert not CL.claim_a(results).holds  # aligned impact is the harder one
    assert not CL.claim_c(results, 1.0).holds  # R1 stable peak 3600 N above S1's 1200 N
    assert not CL.claim_e(results, 1.0).holds  # a 2 mm wander is not inconspicuous
    short = {k: Result(v.scene, 0, "", None, 0.5, {}, {kk: vv[T <= 0.5] for kk, vv in v.arrays.items()}, v.metadata) for k, v in results.items()}
    assert CL.claim_b(short, 1.0).holds is None and CL.claim_b(short, 1.0).verdict().startswith("n/a")


def test_claims_on_a_real_run(tmp_path):
    """The ideal RPS limb is planar: the fitted limb plane holds the ideal S1 path to round-off."""
    results = run_study(tmp_path, duration=0.03, workers=1, log=lambda message: None)
    out_of_plane = CL.s1_out_of_plane(results)
    assert np.max(np.abs(out_of_plane["ideal"])) < 1e-9
    write_outputs(results, tmp_path)
    data = json.loads((tmp_path / "summary.json").read_text())
    assert [c["label"] for c in data["claims"]] == list("abcde")
    a = data["claims"][0]
    compound = results["compound"]
    window = compound["t"] <= CL.INITIAL_STAGE
    assert a["numbers"]["R1_peak_N"]["aligned"] == pytest.approx(compound["R1_normal_force"].sum(axis=1)[window].max())
    report = (tmp_path / "claims.md").read_text()
    assert report.count("| (") == 5
