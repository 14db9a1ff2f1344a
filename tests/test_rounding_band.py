"""The rounding band (robot.analysis.studies.rounding_band): runs repeat bit for bit, rounding moves little."""

from __future__ import annotations

import math

import pytest

import dataclasses

import numpy as np

from robot.analysis.errors import AnalysisError
from robot.analysis.studies.common import simulate
from robot.analysis.studies.rounding_band import perturbations, relative_changes, rounding_band, summary
from robot.run import build_run, compile_kernels


@pytest.fixture(scope="module")
def slider_crank():
    run = build_run("slider_crank_revolute")
    compile_kernels(run)
    return run


def test_a_repeated_run_is_identical_bit_for_bit(slider_crank):
    first = summary(simulate(slider_crank, slider_crank.scene.solver, 0.05))
    second = summary(simulate(slider_crank, slider_crank.scene.solver, 0.05))
    assert first == second  # exact: runs are deterministic
    assert any(name.startswith("peak") and value > 0.0 for name, value in first.items())  # the horizon has contact


def test_band_of_the_paper_scene_through_its_main_impact():
    """compound_misaligned to just past its largest impact (0.425 s): the band is measured and small.

    Measured: peaks 2e-5, impulses 1e-5, steps 12 %, every variant moving the run
    (the step count over a short horizon is the most sensitive quantity; over the
    whole 2 s it is 2 %).
    """
    run = build_run("compound_misaligned")
    compile_kernels(run)
    report = rounding_band(run, t_end=0.45)
    assert set(report["band"]) == set(report["reference"]) == {"peak S1", "peak R1", "impulse S1", "impulse R1", "steps"}
    assert len(report["variants"]) == 6  # 4 nudged coordinates, 2 tolerances
    assert report["moved"] == 6  # every rounding-level perturbation moves this run
    assert report["reference"]["peak R1"] > 1000.0  # the horizon holds the main impact
    for name, value in report["band"].items():
        # 1e-16 perturbations are amplified by the impacts, but not to engineering size
        assert 0.0 <= value < (0.5 if name == "steps" else 1e-3), (name, value)
    assert max(report["band"][name] for name in report["band"] if name != "steps") > 0.0  # amplification exists
    # the band is the largest change over the variants
    for name, value in report["band"].items():
        assert value == max(changes[name] for changes in report["variants"].values())


def test_relative_changes():
    assert relative_changes({"a": 2.0, "b": 0.0, "c": 0.0}, {"a": 2.5, "b": 0.0, "c": 1.0}) == {"a": 0.25, "b": 0.0, "c": math.inf}


def test_a_coordinate_outside_the_state_is_refused(slider_crank):
    size = slider_crank.y0.shape[0]
    with pytest.raises(AnalysisError, match=rf"coordinates: index {size} is outside the state \(0 \.\.\. {size - 1}\)"):
        perturbations(slider_crank, slider_crank.scene.solver, (size,))


@pytest.mark.parametrize("scene", ["slider_crank_revolute", "rssr_rocker_clearance", "compound_misaligned"])
def test_every_nudge_is_one_ulp_of_its_blocks_scale(scene_runs, scene):
    """A coordinate at or near zero still moves by rounding's size for its block, at least one ulp of 1.0
    (planar slider-crank, spatial RSSR linkage, the 4-UPS/RPS with its free bodies' quaternions)."""
    run = scene_runs(scene)
    nq, nv = run.mechanism.model.nq, run.mechanism.model.nv
    variants = perturbations(run, run.scene.solver, tuple(range(run.y0.shape[0])))
    nudged = [name for name in variants if name.startswith("y0[")]
    assert len(nudged) == nq + nv  # every q and v; the works are skipped
    small = 0
    for name in nudged:
        y0 = variants[name][0].y0
        (index,) = np.flatnonzero(y0 != run.y0)
        block = slice(0, nq) if index < nq else slice(nq, nq + nv)
        scale = max(1.0, float(np.max(np.abs(run.y0[block]))))
        assert y0[index] == run.y0[index] + np.spacing(scale)
        # rounding's size for the block, not the coordinate's own ulp: they differ where the coordinate is
        # much smaller than its block's largest (a coordinate near zero would move by ~1e-300)
        if abs(run.y0[index]) < 0.25 * scale:
            assert y0[index] - run.y0[index] > np.spacing(run.y0[index]), (name, scale)
            small += 1
    assert small >= 1  # the scene has such coordinates (zeros among them)


def test_a_block_at_rest_is_nudged_by_one_ulp_of_one(slider_crank):
    nq, nv = slider_crank.mechanism.model.nq, slider_crank.mechanism.model.nv
    y0 = slider_crank.y0.copy()
    y0[nq : nq + nv] = 0.0
    at_rest = dataclasses.replace(slider_crank, y0=y0)
    variants = perturbations(at_rest, at_rest.scene.solver, (nq,))
    assert len(variants) == 3  # one coordinate, two tolerances
    assert variants[f"y0[{nq}] + {np.spacing(1.0):.1e}"][0].y0[nq] == np.spacing(1.0)
