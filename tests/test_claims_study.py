"""The claims study driver: parameter sets from sweep files, shared runs, one table row per set."""

from __future__ import annotations

import json

import pytest

from robot.sweep.claims_study import main, parameter_sets, run_file
from robot.sweep.errors import SweepError

SWEEP = """
[sweep]
name = "tiny"
scene = "compound"
t_end = 0.01

[[axis]]
key = "clearance.R1.bearing_length"
values = [0.06, 0.09]
"""


def test_study_runs_triples_shares_the_ideal_and_writes_the_table(tmp_path):
    sweep = tmp_path / "tiny.toml"
    sweep.write_text(SWEEP)
    state = tmp_path / "state.toml"
    state.write_text(SWEEP.replace('"tiny"', '"state"').replace("clearance.R1.bearing_length", "initial.clearance_state").replace("[0.06, 0.09]", '["resting"]'))
    sets = parameter_sets([sweep, state])
    assert [s.label for s in sets] == ["tiny: bearing_length=0.06", "tiny: bearing_length=0.09", "state: clearance_state=resting"]
    # 0.09 m and the resting start are both the shipped default: one run serves both sets
    assert run_file(tmp_path, "compound", sets[1].overrides, 0.01) == run_file(tmp_path, "compound", sets[2].overrides, 0.01)
    out = tmp_path / "out"
    assert main([str(sweep), str(state), "--out", str(out)]) == 0
    assert len(list((out / "runs").glob("*.npz"))) == 1 + 2 * 2  # one ideal, two parameter sets' clearance runs
    entries = json.loads((out / "claims_study.json").read_text())
    assert [e["label"] for e in entries] == [s.label for s in sets]
    for entry in entries:
        assert [c["label"] for c in entry["claims"]] == list("abcde")
        assert not entry["failed_runs"]
    # a run of 0.01 s has no second period: (b) and (c) cannot be judged
    assert [c["verdict"] for c in entries[0]["claims"]][1:3] == ["n/a (run too short)"] * 2
    assert "tiny: bearing_length=0.06" in (out / "claims_study.md").read_text()


def test_a_study_varies_the_aligned_scene_only(tmp_path):
    sweep = tmp_path / "other.toml"
    sweep.write_text(SWEEP.replace('scene = "compound"', 'scene = "revolute"'))
    with pytest.raises(SweepError, match="varies scene 'compound'"):
        parameter_sets([sweep])
