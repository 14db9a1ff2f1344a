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
    assert coarse["finished"] is True and fine["finished"] is True  # what "ok" said: no failure cause
    assert {"peak_force", "driving", "ee"} <= set(coarse["inaccurate_by"])
    assert coarse["errors"]["peak_force"] > 1.0 and coarse["errors"]["driving"] > 0.5  # measured, stored
    assert fine["result"] == "accurate" == stability.OK and fine["inaccurate_by"] == []
    assert all(fine["errors"][key] <= limit for key, limit in stability.THRESHOLDS.items() if fine["errors"][key] is not None)
    # boundary keeps its meaning (largest step that finished); the largest accurate step is boundary_accurate
    assert stiff["boundary"]["RK4"]["1.0"] == 1e-4
    assert stiff["boundary_accurate"]["RK4"]["1.0"] == 3e-5
    assert "boundary_finished" not in stiff
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
    assert all(cell["finished"] for cell in cells.values())
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
    assert measured["driving"] is None and measured["driving_rms"] is None  # not applicable (null in the JSON, as NaN was)
    assert measured["ee"] == pytest.approx(2e-7 * np.sqrt(3)) and measured["engineering_accuracy"]


# --------------------------------------------------------------------------------------
# classification on synthetic runs (no integration): the rules, not the shipped scenes
# --------------------------------------------------------------------------------------


def _outcome(offset: float = 0.0, *, success: bool = True, energy_error: float = 1e-9, actuator_work: float = 0.0,
             driving: float | None = None, t_end: float = 0.01):  # fmt: skip
    """An Outcome of 6 output points: end effector moved by ``offset``; one actuator of force ``driving``
    (N, None: no actuator); one clearance joint J of peak 10 N."""
    from robot.analysis.studies.common import Outcome

    t = np.linspace(0.0, t_end, 6)
    run = Outcome(label="x", options={}, status=0 if success else -1, cause=None if success else "non-finite state",
                  message="", t_reached=t_end, cpu_time=0.0, wall_time=0.0, n_steps=5, n_rejected=0, n_rhs=30,
                  n_jacobians=0, n_events=0, n_hidden_contacts=0, max_onset_overshoot=0.0)  # fmt: skip
    run.max_residual, run.energy_error, run.actuator_work_scale = 1e-9, energy_error, actuator_work
    forces = np.zeros((len(t), 0)) if driving is None else np.full((len(t), 1), driving)
    run.grid_t, run.grid_ee, run.grid_force = t, np.outer(t, [1.0, 0.0, 0.0]) + offset, forces
    run.peaks, run.impulses = {"J": 10.0}, {"J": 1.0}
    return run


def _reference(energy_scale: float = float("nan"), **options):
    from robot.analysis.studies.work_precision import Reference

    reference = _outcome(**options)
    reference.energy_scale = energy_scale  # as simulate records it
    return Reference(reference, _outcome(**options), window=0.01, window_tolerance=1e-9)


def test_a_mechanism_without_actuators_is_classified_without_the_driving_forces():
    """No actuator: the driving-force measures do not apply (None), and that is not a failure or an inaccuracy."""
    cell = stability.classify(_outcome(), _reference(energy_scale=5.0))
    assert cell["result"] == stability.OK and cell["finished"] is True and cell["inaccurate_by"] == []
    assert cell["errors"]["driving"] is None and cell["errors"]["driving_n"] is None and cell["errors"]["driving_rms"] is None
    # with an actuator, the same measure applies and is checked
    actuated = stability.classify(_outcome(driving=110.0, actuator_work=1.0), _reference(driving=100.0, actuator_work=1.0))
    assert actuated["result"] == stability.INACCURATE and actuated["inaccurate_by"] == ["driving"]
    assert actuated["errors"]["driving"] == pytest.approx(0.1) and actuated["errors"]["driving_n"] == pytest.approx(10.0)


def test_a_finished_run_whose_reference_failed_has_no_reference_and_a_failed_run_its_cause():
    unchecked = stability.classify(_outcome(), None)
    assert unchecked == {"result": stability.UNCHECKED, "finished": True, "errors": None, "inaccurate_by": []}
    assert unchecked["result"] == "no reference"
    failed = stability.classify(_outcome(success=False), _reference())
    assert failed["result"] == "non-finite state" and failed["finished"] is False


def test_a_measure_that_could_not_be_taken_counts_as_inaccurate():
    """NaN (the run's grid does not match the reference's: the end effector cannot be compared) is beyond."""
    run = _outcome()
    run.grid_t = run.grid_t + 1e-3  # another output grid
    cell = stability.classify(run, _reference(energy_scale=5.0))
    assert np.isnan(cell["errors"]["ee"]) and "ee" in cell["inaccurate_by"]
    assert cell["result"] == stability.INACCURATE and cell["finished"] is True
    assert "end-effector position not measured" in stability.describe(cell)


def test_a_passive_mechanism_with_a_10_J_energy_error_is_inaccurate():
    """No actuator work in the reference: the energy balance is relative to its mechanical energy (here 5 J);
    it was not checked at all (energy_relative None), so a 10 J error was accurate."""
    cell = stability.classify(_outcome(energy_error=10.0), _reference(energy_scale=5.0))
    assert cell["errors"]["energy_relative"] == pytest.approx(2.0)
    assert cell["result"] == stability.INACCURATE and cell["inaccurate_by"] == ["energy_relative"]
    assert stability.classify(_outcome(energy_error=1e-3), _reference(energy_scale=5.0))["result"] == stability.OK
    # with actuator work it stays relative to the work
    worked = stability.classify(_outcome(energy_error=10.0, actuator_work=2000.0), _reference(actuator_work=2000.0))
    assert worked["errors"]["energy_relative"] == pytest.approx(5e-3) and worked["result"] == stability.OK
    # the work-precision study reports the same measure (one measures function)
    from robot.analysis.studies.work_precision import errors

    assert errors(_outcome(energy_error=10.0), _reference(energy_scale=5.0))["energy_relative"] == pytest.approx(2.0)


def test_beyond_thresholds_none_is_not_applicable_nan_is_beyond_and_the_threshold_itself_is_within():
    within = dict(stability.THRESHOLDS)  # every measure exactly at its threshold: within (<=)
    assert stability.beyond_thresholds(within) == []
    assert stability.beyond_thresholds({key: None for key in stability.THRESHOLDS}) == []
    assert stability.beyond_thresholds({}) == []  # missing: not applicable
    assert stability.beyond_thresholds({**within, "driving": float("nan")}) == ["driving"]
    assert stability.beyond_thresholds({**within, "drift": 2 * stability.THRESHOLDS["drift"]}) == ["drift"]
    # the work-precision study's engineering accuracy uses the same rule (drift at its threshold: within)
    from robot.analysis.studies import work_precision as wp

    measured = wp.errors(_outcome(), _reference(energy_scale=5.0))
    assert measured["engineering_accuracy"]
    assert wp.beyond({**measured, "drift": wp.DRIFT_TARGET}, wp.ENGINEERING) == []


def test_old_names_keep_their_meaning(tmp_path, monkeypatch):
    """finished is the old "ok" test; boundary is the largest step that finished; the hidden-contact map
    writes "ok"; a map written before the classification is drawn without claiming accuracy."""

    def fake(run, options, t_end, **kwargs):
        h = options.first_step
        if h == 1e-3:
            return _outcome(success=False)
        return _outcome(offset=1e-5 if h == 1e-4 else 0.0)  # 1e-4: finishes, 10 um off

    monkeypatch.setattr(stability, "simulate", fake)
    monkeypatch.setattr(stability.wp, "reference", lambda *args, **kwargs: _reference(energy_scale=5.0))
    stiff = stability.stiffness_map("slider_crank_revolute", scales=(1.0,), steps=(1e-3, 1e-4, 1e-5), methods=("RK4",), t_end=0.01)
    rows = {row["h"]: row for row in stiff["methods"]["RK4"]}
    assert [rows[h]["finished"] for h in (1e-3, 1e-4, 1e-5)] == [False, True, True]
    assert [rows[h]["result"] for h in (1e-3, 1e-4, 1e-5)] == ["non-finite state", stability.INACCURATE, stability.OK]
    assert stiff["boundary"]["RK4"]["1.0"] == 1e-4 and stiff["boundary_accurate"]["RK4"]["1.0"] == 1e-5
    assert stiff["adaptive"]["1.0"]["finished"] is True

    run = type("R", (), {})()
    run.scene = type("S", (), {"name": "fake"})()
    monkeypatch.setattr(stability, "_clearances", lambda run: [1e-4])
    hidden = stability.hidden_contact_map(run, methods=("RK45",), tolerances=(1e-3,), reference_peaks={"J": 10.0})
    assert [row["result"] for row in hidden["runs"]] == ["ok", "ok"] == [stability.FINISHED] * 2
    assert all(row["finished"] and row["inaccurate_by"] == [] for row in hidden["runs"])

    # the figure: a classified map has both lines and the thresholds in its title; an old one neither
    titles = []
    monkeypatch.setattr(stability, "save_png", lambda fig, path: titles.append((fig._suptitle.get_text(), [t.get_text() for t in fig.legends[0].get_texts()])))
    stability.plot_stiffness(stiff, tmp_path / "new.png")
    old = {key: value for key, value in stiff.items() if key not in ("boundary_accurate", "thresholds", "reference")}
    old["methods"] = {"RK4": [{"scale": r["scale"], "h": r["h"], "result": "ok" if r["finished"] else r["result"]} for r in stiff["methods"]["RK4"]]}
    old["adaptive"] = {k: {**v, "result": "ok"} for k, v in stiff["adaptive"].items()}
    stability.plot_stiffness(old, tmp_path / "old.png")
    (new_title, new_legend), (old_title, old_legend) = titles
    assert "against DOP853" in new_title and "largest accurate step" in new_legend and "largest step that finished" in new_legend
    assert "against DOP853" not in old_title and "accurate" not in " ".join(old_legend).replace("inaccurate", "")
    assert "largest step that finished" in old_legend and "largest accurate step" not in old_legend
