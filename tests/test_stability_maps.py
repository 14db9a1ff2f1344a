"""The stability maps say what a user needs to know of each run (robot.analysis.studies.stability).

A cell is failed (with its cause), finished but inaccurate (naming the measures beyond their
thresholds against a tight reference of the same scene and horizon), or accurate; the
stiffness map scales the stiffness the contact laws use, explicit stiffness keys included,
or refuses the scene. Tiny grids and short horizons: seconds each.
"""

from __future__ import annotations

import numpy as np
import pytest

from robot.errors import SceneError
from robot.scene.loader import load_scene
from robot.analysis.studies import stability

# blown-up trial states make numpy and scipy warn on their way to the reported failure
pytestmark = pytest.mark.filterwarnings("ignore::RuntimeWarning")


def test_a_fixed_step_too_large_for_the_contact_finishes_but_is_classified_inaccurate(tmp_path):
    """RK4 at h = 1e-4 s goes through the contact of the misaligned 4-UPS/RPS without a failure cause, but its
    peak contact force is 2.4 times too high and its driving forces 77 % off: inaccurate, not green."""
    stiff = stability.stiffness_map("compound_misaligned", scales=(1.0,), steps=(1e-4, 3e-5), methods=("RK4",), t_end=0.01)
    cells = {row["h"]: row for row in stiff["methods"]["RK4"]}
    coarse, fine = cells[1e-4], cells[3e-5]
    assert coarse["message"].startswith("the integration reached the end")  # it finished: no failure cause
    assert coarse["result"] == "inaccurate"  # was "ok", drawn green
    assert {"peak_force", "driving", "ee"} <= set(coarse["inaccurate_by"])
    assert coarse["errors"]["peak_force"] > 1.0 and coarse["errors"]["driving"] > 0.5  # measured, stored
    assert fine["result"] == "accurate" == stability.OK and fine["inaccurate_by"] == []
    assert all(fine["errors"][key] <= limit for key, limit in stability.THRESHOLDS.items() if fine["errors"][key] is not None)
    # the boundary is the largest accurate step; the largest that merely finished is kept apart
    assert stiff["boundary"]["RK4"]["1.0"] == 3e-5
    assert stiff["boundary_finished"]["RK4"]["1.0"] == 1e-4
    assert stiff["reference"]["1.0"]["method"] == "DOP853" and stiff["thresholds"] == stability.THRESHOLDS
    stability.plot_stiffness(stiff, tmp_path / "stiffness.png")
    assert (tmp_path / "stiffness.png").read_bytes().startswith(b"\x89PNG")


def test_a_large_baumgarte_gain_at_a_loose_tolerance_gives_wrong_driving_forces_and_is_classified_so(tmp_path):
    """RK45 at rtol 1e-3 on the ideal mechanism: without stabilisation accurate; with beta = 1000 1/s (a point
    of the shipped gain map) it finishes without a failure cause while its driving forces are off by more
    than their maximum: inaccurate by the driving forces."""
    gains = stability.baumgarte_map(alphas=(0.0,), betas=(0.0, 1000.0), cases=(("RK45", 1e-3, None),), t_end=0.1)
    cells = {row["beta"]: row for row in gains["cases"][0]["grid"]}
    large = cells[1000.0]
    assert large["result"] == "inaccurate"  # was "ok"
    assert cells[0.0]["result"] == "accurate"
    assert "driving" in large["inaccurate_by"]
    assert large["errors"]["driving"] > 0.5 and large["errors"]["driving_n"] > 100.0  # N, against a ~680 N maximum
    assert large["max_residual"] < gains["max_residual_limit"]  # no failure cause: the drift limit was not reached
    assert stability.describe(large).startswith("inaccurate: ") and "driving forces" in stability.describe(large)
    stability.plot_baumgarte(gains, tmp_path / "gains.png")
    assert (tmp_path / "gains.png").read_bytes().startswith(b"\x89PNG")


def test_the_stiffness_map_scales_an_explicit_radial_stiffness():
    """slider_crank_revolute sets radial_stiffness explicitly (Flores & Ambrosio's K): scaling only the Young's
    modulus left its contact untouched (the same runs at every scale). Now the runs differ with the scale."""
    stiff = stability.stiffness_map("slider_crank_revolute", scales=(1.0, 100.0), steps=(5e-6,), methods=("RK4",), t_end=0.002)
    results = {row["scale"]: row["result"] for row in stiff["methods"]["RK4"]}
    assert results[100.0] == "penetration beyond physical bound"  # was "ok", as at 1 x: the scale had no effect
    assert results[1.0] == "accurate"
    assert stiff["adaptive"]["100.0"]["steps"] != stiff["adaptive"]["1.0"]["steps"]
    assert stiff["scaled"]["keys"]["K"] == {"radial_stiffness": 6.949e10}
    assert stiff["scaled"]["materials"] == {"steel": 2.07e11}
    peaks = {scale: stiff["reference"][repr(scale)]["peak_force"]["K"] for scale in (1.0, 100.0)}
    assert peaks[100.0] > 5.0 * peaks[1.0]  # Hertz-like: ~100^0.4 = 6.3 times the peak at 100 x the stiffness
    # and the law itself: its contact force at a fixed penetration follows the scale
    scene = load_scene("slider_crank_revolute")
    variant = scene.with_changes(stability.stiffness_overrides(stiff["scaled"], 100.0))
    nominal, scaled = stability._probe_forces(scene.clearances[0].law), stability._probe_forces(variant.clearances[0].law)
    touching = nominal > 0
    assert touching.sum() >= 4 and np.allclose(scaled[touching], 100.0 * nominal[touching], rtol=1e-9)


def test_a_scene_whose_stiffness_the_map_cannot_scale_is_refused_naming_the_joint(monkeypatch):
    """A stiffness that follows neither the materials nor a '*stiffness' key (here: the explicit key left out,
    as the map did before) is refused before any run, naming the joint and its keys."""
    scale_all = stability.stiffness_overrides
    monkeypatch.setattr(stability, "stiffness_overrides", lambda scaled, scale: scale_all({**scaled, "keys": {}}, scale))
    with pytest.raises(SceneError, match="cannot scale the contact stiffness of clearance joint 'K'") as refused:
        stability.stiffness_map("slider_crank_revolute", scales=(1.0,), steps=(5e-6,), methods=("RK4",), t_end=0.002)
    assert refused.value.key == "clearance.K"
    assert "radial_exponent" in str(refused.value)
    with pytest.raises(SceneError, match="no clearance joint"):
        stability.stiffness_map("ideal", scales=(1.0,), steps=(1e-4,), methods=("RK4",), t_end=0.002)


def test_work_precision_errors_of_a_mechanism_without_actuators_leave_the_driving_force_out():
    """A free mechanism (no driving constraint: driving_force has no column) is compared on the rest.
    Before, the maximum of the empty driving-force error raised ValueError."""
    from robot.analysis.studies.common import Outcome
    from robot.analysis.studies.work_precision import Reference, errors

    t = np.linspace(0.0, 0.01, 6)

    def outcome(offset: float) -> Outcome:
        run = Outcome(label="x", options={}, status=0, cause=None, message="", t_reached=0.01, cpu_time=0.0, wall_time=0.0,
                      n_steps=5, n_rejected=0, n_rhs=30, n_jacobians=0, n_events=0, n_hidden_contacts=0, max_onset_overshoot=0.0)  # fmt: skip
        run.max_residual, run.energy_error, run.actuator_work_scale = 0.0, 1e-9, 0.0
        run.grid_t, run.grid_ee, run.grid_force = t, np.outer(t, [1.0, 0.0, 0.0]) + offset, np.zeros((len(t), 0))
        run.peaks, run.impulses = {"J": 10.0 + offset}, {"J": 1.0}
        return run

    reference = Reference(outcome(0.0), outcome(0.0), window=0.01, window_tolerance=1e-9)
    measured = errors(outcome(2e-7), reference)
    assert np.isnan(measured["driving"]) and np.isnan(measured["driving_rms"])
    assert measured["ee"] == pytest.approx(2e-7 * np.sqrt(3)) and measured["engineering_accuracy"]
