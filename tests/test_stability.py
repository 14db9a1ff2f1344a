"""Runs made to fail are reported as failed, with the right cause, never a crash or garbage.

Each case drives a method past a failure boundary mapped by ``scripts/work_precision.py``
(``docs/work-precision.md``) on a short horizon: a fixed step too large for the contact
stiffness, stabilisation off with a loose tolerance, Baumgarte gains beyond an explicit
method's stability region, a generalized-alpha step too large for its Newton iterations,
step-size collapse, the wall-time limit, and the hidden-contact guard.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from robot.dynamics.equations import Baumgarte
from robot.run import build_run
from robot.integration.simulation import FAILED, FailureLimits, SolverOptions, integrate
from robot.analysis.studies import stability
from robot.analysis.studies.common import simulate
from tests.conftest import calibrated_scene, calibrated_scene_file

# blown-up trial states make numpy and scipy warn on their way to the reported failure
pytestmark = pytest.mark.filterwarnings("ignore::RuntimeWarning")


@pytest.fixture(scope="module")
def misaligned():
    return build_run(calibrated_scene("compound_misaligned"))


@pytest.fixture(scope="module")
def ideal():
    return build_run("ideal")


def _failed(trajectory, causes, t_max):
    assert trajectory.status == FAILED
    assert trajectory.cause in causes, (trajectory.cause, trajectory.message)
    assert trajectory.message.startswith("t="), trajectory.message
    assert 0.0 < trajectory.t_end < t_max
    assert np.all(np.isfinite(trajectory.y))  # what is kept is the good part
    assert trajectory.t[-1] == pytest.approx(trajectory.t_end)


def test_fixed_step_too_large_for_the_contact_stiffness(misaligned):
    """RK4 with h = 5e-4 s: stable in free flight, unstable through the impacts.

    (h = 2e-4 s failed here while the step that crossed into contact damped its late stages with
    the stored onset rate; located on restepped states it goes through: test_event_loop_failures.)
    """
    trajectory = integrate(misaligned.dynamics, misaligned.y0, (0.0, 0.02), SolverOptions("RK4", first_step=5e-4))
    _failed(trajectory, {"non-finite state", "penetration beyond physical bound", "unphysical pose"}, 0.02)
    assert trajectory.t_end > 0.004  # the free flight before the first impact went through


def test_spherical_joint_blow_up_is_a_penetration_beyond_its_bound():
    run = build_run("spherical")
    trajectory = integrate(run.dynamics, run.y0, (0.0, 0.05), SolverOptions("RK4", first_step=5e-4))
    _failed(trajectory, {"penetration beyond physical bound"}, 0.05)
    assert "exceeds" in trajectory.message and "x clearance" in trajectory.message


def test_absurd_pose_of_an_accepted_step_is_reported_not_raised(misaligned):
    """RK4 with h = 1e-3 s turns the journal half round in one step: the contact layer refuses the
    pose; the run stops with 'unphysical pose' instead of raising ContactError."""
    trajectory = integrate(misaligned.dynamics, misaligned.y0, (0.0, 0.02), SolverOptions("RK4", first_step=1e-3))
    _failed(trajectory, {"unphysical pose", "non-finite state", "penetration beyond physical bound"}, 0.02)


def test_generalized_alpha_step_too_large_is_a_newton_divergence(misaligned):
    trajectory = integrate(misaligned.dynamics, misaligned.y0, (0.0, 0.01), SolverOptions("GenAlpha", first_step=1e-4))
    _failed(trajectory, {"Newton divergence"}, 0.01)
    assert "h=1.000e-04" in trajectory.message
    good = integrate(misaligned.dynamics, misaligned.y0, (0.0, 0.006), SolverOptions("GenAlpha", first_step=1e-5))
    assert good.success and good.n_events > 0  # through the first impact with a small enough step


def test_no_stabilisation_and_a_loose_tolerance_drift(ideal):
    loose = SolverOptions("RK45", rtol=1e-3, atol=1e-3, max_step=0.05)
    unstabilised = dataclasses.replace(ideal.dynamics, baumgarte=Baumgarte(0.0, 0.0))
    _failed(integrate(unstabilised, ideal.y0, (0.0, 0.5), loose, FailureLimits(max_residual=1e-8)), {"constraint drift"}, 0.5)


def test_baumgarte_gain_beyond_the_explicit_stability_region(ideal):
    """alpha = 1000 1/s with RK4 at h = 2 ms: -2 alpha h = -4 is outside RK4's region (-2.79):
    the constraint error grows each step and the drift check stops the run; the A-stable
    generalized-alpha integrates the same gains."""
    gains = dataclasses.replace(ideal.dynamics, baumgarte=Baumgarte(1000.0, 5.0))
    _failed(integrate(gains, ideal.y0, (0.0, 0.2), SolverOptions("RK4", first_step=2e-3)), {"constraint drift", "non-finite state"}, 0.2)
    assert integrate(gains, ideal.y0, (0.0, 0.2), SolverOptions("GenAlpha", first_step=2e-3)).success


def test_step_size_collapse(misaligned):
    trajectory = integrate(misaligned.dynamics, misaligned.y0, (0.0, 0.01), SolverOptions("RK45"), FailureLimits(min_step=1e-4))
    _failed(trajectory, {"step size collapse"}, 0.01)
    assert "below" in trajectory.message


def test_wall_time_limit(misaligned):
    trajectory = integrate(misaligned.dynamics, misaligned.y0, (0.0, 1.0), SolverOptions("RK45"), FailureLimits(max_wall_time=0.1))
    _failed(trajectory, {"wall time"}, 1.0)


def test_hidden_contact_guard_finds_an_impact_inside_a_step():
    """Penetration < 0 at both ends of a step, > 0 inside: the guard samples the dense
    output and returns the onset (the first zero crossing)."""
    from robot.integration.events import hidden_contact

    def dense(t):
        return np.array([t])

    def probe(t, y):  # a grazing impact between t = 0.42 and t = 0.48 inside the step [0, 1]
        depth = 1e-6 - 1e-3 * (y[0] - 0.45) ** 2
        return np.array([depth]), np.array([-2e-3 * (y[0] - 0.45)]), 0.0

    found = hidden_contact(lambda t: probe(t, dense(t))[0][0], 0.0, 1.0, samples=20)
    assert found == pytest.approx(0.45 - np.sqrt(1e-3), abs=1e-12)
    assert hidden_contact(lambda t: -1.0, 0.0, 1.0) is None


def test_hidden_contact_guard_in_a_run(misaligned):
    """Loose tolerances and a long max_step (RK45, rtol 1e-2 to 3e-2, max_step 5-10 ms) let
    steps straddle whole impacts in the first 0.1 s of the misaligned scene: the guard
    finds them; without the guard no onset is counted as hidden.

    Which step straddles an impact at such tolerances depends on the last bits of the
    arithmetic, so the count is summed over three settings (each finds 0-4)."""
    found, onsets_guarded, onsets_unguarded = 0, 0, 0
    for rtol, max_step in ((1e-2, 1e-2), (1e-2, 5e-3), (3e-2, 1e-2)):
        options = dict(rtol=rtol, atol=rtol / 100, max_step=max_step)
        guarded = integrate(misaligned.dynamics, misaligned.y0, (0.0, 0.1), SolverOptions("RK45", hidden_contacts=True, **options))
        unguarded = integrate(misaligned.dynamics, misaligned.y0, (0.0, 0.1), SolverOptions("RK45", hidden_contacts=False, **options))
        assert guarded.success and unguarded.success
        found += guarded.n_hidden_contacts
        onsets_guarded += sum(1 for event in guarded.events if event[2] == "onset")
        onsets_unguarded += sum(1 for event in unguarded.events if event[2] == "onset")
    assert found >= 1
    # what the guard changes: impacts straddled by a step are counted as contacts, not lost
    assert onsets_guarded > onsets_unguarded


def test_study_maps_record_causes(misaligned, tmp_path):
    """The stability studies run through and label every run (tiny grids)."""
    stiff = stability.stiffness_map(
        str(calibrated_scene_file(tmp_path, "compound_misaligned")), scales=(1.0,), steps=(1e-3, 1e-5), methods=("RK4",), t_end=0.006, folder=tmp_path
    )
    results = {row["h"]: row["result"] for row in stiff["methods"]["RK4"]}
    assert results[1e-5] == stability.OK
    assert results[1e-3] != stability.OK
    assert stiff["boundary"]["RK4"]["1.0"] == 1e-5
    gains = stability.baumgarte_map(alphas=(5.0, 1000.0), betas=(5.0,), cases=(("RK4", None, 2e-3),), t_end=0.1)
    outcome = {row["alpha"]: row["result"] for row in gains["cases"][0]["grid"]}
    assert outcome[5.0] == stability.OK and outcome[1000.0] != stability.OK
    stability.plot_stiffness(stiff, tmp_path / "stiffness.png")
    stability.plot_baumgarte(gains, tmp_path / "gains.png")
    assert (tmp_path / "stiffness.png").stat().st_size > 0


def test_simulate_summarises_a_failed_run(misaligned):
    outcome = simulate(misaligned, SolverOptions("RK4", first_step=5e-4), 0.02)
    assert not outcome.success and outcome.cause
    assert np.isfinite(outcome.max_residual) and outcome.peaks


def test_energy_error_closes_with_force_elements():
    """The studies' energy balance includes the force elements' work: on the two-link arm with springs
    (and a torque element) it closes to the integration error, not to the springs' energy swing."""
    import robot

    run = build_run("free_two_link_spring")
    options = dataclasses.replace(run.scene.solver, method="DOP853", rtol=1e-10, atol=1e-12)
    outcome = simulate(run, options, 0.5)
    assert outcome.status == 0
    swing = np.ptp(robot.simulate(run.scene, t_end=0.5)["force_energy"])
    assert swing > 0.1  # the springs exchange energy: leaving their work out would show
    assert outcome.energy_error < 1e-6 * swing
