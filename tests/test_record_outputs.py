"""The result arrays through the compiled right-hand side equal the reference evaluation at every record.

:func:`robot.io.record_outputs.compiled_outputs` reads the outputs off the
integrator's compiled right-hand side; :func:`reference_outputs` evaluates the
equations in Python (``robot.dynamics.equations.evaluate``, every contact law's
``evaluate``). Two independent compositions of the same equations: they must
agree to rounding (1e-12 of each array's scale) on runs with contact (spherical,
revolute with misalignment, both), an ideal mechanism, and parameters the shipped
scenes do not use. Also: evaluating only the records a scene's ``[output]`` keeps
gives exactly the rows the file would keep of the full evaluation.
"""

from __future__ import annotations

import numpy as np
import pytest

from robot.integration.simulation import RECORD_ONSET, RECORD_OUTPUT, integrate
from robot.io import record_outputs as RO
from robot.io.results import make_result, select_records
from robot.run import build_run
from tests.conftest import CALIBRATED_COMPOUND
from robot.scene.loader import OutputSpec

CASES = {
    "compound_misaligned": ("compound_misaligned", CALIBRATED_COMPOUND, 0.04),
    "revolute": ("revolute", {}, 0.04),
    "spherical": ("spherical", {}, 0.04),
    "ideal": ("ideal", {}, 0.01),
    # another mechanism with a revolute clearance joint, and one with force elements
    "slider-crank, revolute clearance": ("slider_crank_revolute", {}, 0.05),
    "four-bar, revolute clearance": ("four_bar_revolute", {}, 0.05),
    "slider-crank, translational clearance": ("slider_crank_translational", {}, 0.1),
    "force elements": ("free_two_link_spring", {}, 0.05),
    # revolute closures: redundant rows, the KKT solve on the independent ones
    "four-bar, ideal": ("four_bar", {}, 0.05),
    # parameters away from the shipped ones: larger clearances, softer restitution, another ball
    "other parameters": (
        "compound",
        {**CALIBRATED_COMPOUND, "clearance.R1.radial_clearance": 2.5e-4, "clearance.S1.clearance": 3e-4, "clearance.S1.ball_radius": 0.011, "clearance.R1.restitution": 0.5},
        0.04,
    ),
}


def _records(scene: str, overrides: dict, t_end: float):
    run = build_run(scene, duration=t_end, **overrides)
    trajectory = integrate(run.dynamics, run.y0, run.t_span, run.scene.solver, run.scene.limits)
    assert trajectory.success, trajectory.message
    order = np.argsort(trajectory.t, kind="stable")
    return run, trajectory, (trajectory.t[order], trajectory.y[order], trajectory.onset_rates[order])


@pytest.mark.parametrize("case", list(CASES))
def test_compiled_outputs_equal_the_reference_evaluation(case):
    run, trajectory, records = _records(*CASES[case])
    dynamics = run.dynamics
    assert RO.compiled_applies(dynamics, RO.D.make_workspace(dynamics))
    reference = RO.reference_outputs(dynamics, *records)
    compiled = RO.compiled_outputs(dynamics, *records)
    assert sorted(compiled) == sorted(reference)
    if dynamics.contacts:
        # the comparison means something only if the run has impacts
        assert np.any(trajectory.kind == RECORD_ONSET)
        # every clearance joint of every case peaks at 395 N (four-bar) to 15 kN: above 100 N
        assert min(np.max(reference[f"{c.site.name}_normal_force"]) for c in dynamics.contacts) > 100.0
    if dynamics.forces is not None:
        assert np.max(np.abs(reference["force_energy"])) > 0.0
    for key, expected in reference.items():
        got = compiled[key]
        assert got.shape == expected.shape and got.dtype == expected.dtype, key
        if expected.dtype.kind in "iub":
            assert np.array_equal(got, expected), key
            continue
        scale = max(float(np.max(np.abs(expected), initial=0.0)), 1e-300)
        error = float(np.max(np.abs(got - expected), initial=0.0))
        assert error <= 1e-12 * scale, (key, error, scale)


def test_outputs_at_the_kept_records_are_the_kept_rows_of_all_outputs():
    run, trajectory, _ = _records("compound_misaligned", CALIBRATED_COMPOUND, 0.03)
    output = OutputSpec(step=1e-3, precision="float64")
    assert np.any(trajectory.kind == RECORD_OUTPUT)  # the scene records its output grid
    full = make_result("x", run.dynamics, trajectory, {})
    kept = make_result("x", run.dynamics, trajectory, {}, output)
    selected = select_records(full, output)
    assert len(kept.arrays["t"]) < len(full.arrays["t"])
    assert sorted(kept.arrays) == sorted(selected.arrays)
    for key, value in selected.arrays.items():
        assert np.array_equal(kept.arrays[key], value), key
    # and the thinned result is already what the file keeps
    again = select_records(kept, output)
    for key, value in again.arrays.items():
        assert np.array_equal(kept.arrays[key], value), key


def test_compiled_outputs_refuse_a_model_without_compiled_right_hand_side():
    run, _, records = _records("compound", {}, 1e-4)
    workspace = RO.D.make_workspace(run.dynamics)
    workspace.compiled = None
    with pytest.raises(ValueError, match="compiled right-hand side"):
        RO.compiled_outputs(run.dynamics, *records, workspace=workspace)


def test_compiled_outputs_do_not_depend_on_the_chunk_size(monkeypatch):
    """The laws' outputs buffered per CHUNK records: chunks of 1, 7 and n - 1 records (a last partial
    chunk) give every array bit for bit as one chunk of all n records."""
    run, trajectory, records = _records("compound_misaligned", CALIBRATED_COMPOUND, 0.05)
    n = len(records[0])
    monkeypatch.setattr(RO, "CHUNK", n)
    whole = RO.compiled_outputs(run.dynamics, *records)
    assert np.max(whole["R1_normal_force"]) > 100.0 and np.max(whole["S1_normal_force"]) > 100.0  # both joints in contact
    assert n % 7 != 0 and n > 8
    for chunk in (1, 7, n - 1):
        monkeypatch.setattr(RO, "CHUNK", chunk)
        got = RO.compiled_outputs(run.dynamics, *records)
        assert sorted(got) == sorted(whole)
        for key, value in whole.items():
            assert np.array_equal(got[key], value, equal_nan=True), (chunk, key)
