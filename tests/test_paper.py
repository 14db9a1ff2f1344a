"""The main job (scripts/reproduce_paper.py) on a short horizon: outputs exist and say the right things."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from robot.analysis.paper import SCENES, acceleration_rms_deviation, run_study, summary, transient_duration, write_outputs

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def study(tmp_path_factory):
    out = tmp_path_factory.mktemp("paper")
    return out, run_study(out, duration=0.02, workers=1, log=lambda message: None)


def test_study_writes_figures_and_summary(study):
    out, results = study
    written = write_outputs(results, out)
    names = {path.name for path in written}
    assert {"figure7_clearance_joints.png", "figure8_forces.png", "figure9_end_effector.png", "summary.json"} <= names
    for path in written:
        assert path.stat().st_size > 1000
    data = json.loads((out / "summary.json").read_text())
    assert set(SCENES) <= set(data)
    assert set(data["compound"]["peak_contact_force_N"]) == {"S1", "R1"}
    assert data["ideal"]["max_constraint_residual"] < 1e-8


def test_rms_deviation_of_ideal_from_itself_is_zero(study):
    _, results = study
    assert acceleration_rms_deviation(results["ideal"], results["ideal"]) == pytest.approx(0.0, abs=1e-12)
    assert acceleration_rms_deviation(results["compound"], results["ideal"]) > 0.0


def test_transient_needs_two_periods(study):
    _, results = study
    assert transient_duration(results["compound"], "S1", period=1.0) is None
    assert transient_duration(results["compound"], "S1", period=0.005) is not None


def test_summary_peaks_match_the_arrays(study):
    _, results = study
    data = summary(results)
    compound = results["compound"]
    assert data["compound"]["peak_contact_force_N"]["S1"] == pytest.approx(compound["S1_normal_force"].sum(axis=1).max())
    assert data["compound"]["peak_driving_force_N"] == pytest.approx(np.abs(compound["driving_force"]).max(axis=0).round(3).tolist())


def test_reproduce_paper_command_runs(tmp_path):
    completed = subprocess.run(
        [sys.executable, str(ROOT / "scripts" / "reproduce_paper.py"), "--out", str(tmp_path), "--t-end", "0.01", "--workers", "2"],
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert completed.returncode == 0, completed.stderr
    assert (tmp_path / "summary.json").is_file()
    assert (tmp_path / "compound_misaligned.html").is_file()


def test_figure10_newton_euler_agrees_with_lagrange_on_a_short_horizon(tmp_path):
    """Two formulations of the same clearance mechanism (absolute coordinates and Newton-Euler
    against Pinocchio coordinates and Lagrange multipliers) from the same initial state."""
    from robot.analysis.paper import PAPER_AXES, figure10_numbers, figure10_series, figure_10

    series = figure10_series(0.004)
    assert series["t"][-1] == pytest.approx(0.004)
    numbers = figure10_numbers(series)
    for axis, _, _ in PAPER_AXES:
        assert numbers[f"max_abs_difference_{axis}_m"] < 1e-7  # 0.1 um (on motions of 1-100 um in 4 ms)
    assert numbers["range_X_m"] > 1e-6 and numbers["range_Y_m"] > 1e-6
    assert figure_10(series, tmp_path / "figure10.png").stat().st_size > 1000


def test_paper_axes_are_a_right_handed_relabelling_of_the_world_axes():
    from robot.analysis.paper import PAPER_AXES

    frame = np.zeros((3, 3))
    for row, (_, column, sign) in enumerate(PAPER_AXES):
        frame[row, column] = sign
    assert np.linalg.det(frame) == pytest.approx(1.0)
    assert [name for name, _, _ in PAPER_AXES] == ["X", "Y", "Z"]
