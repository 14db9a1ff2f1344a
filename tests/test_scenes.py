"""Shipped scenes run; scene files are validated with clear errors."""

from __future__ import annotations

import numpy as np
import pytest

from robot.errors import SceneError
from robot.run import build_run, run_scene
from robot.scene.loader import load_scene, shipped_scenes
from robot.integration.simulation import SolverOptions
from robot.analysis.studies.work_precision import DRIFT_TARGET
from robot.validation.settings import with_solver


def test_the_five_scenes_are_shipped():
    assert set(shipped_scenes()) >= {"ideal", "spherical", "revolute", "compound", "compound_misaligned"}


@pytest.mark.parametrize("name", ["spherical", "revolute", "compound", "compound_misaligned"])
def test_clearance_scene_short_horizon(name):
    """Each scene runs with its own solver: penetrations far below the clearance (0.1 mm), drift
    within the engineering target its solver was chosen against (work-precision study). Baumgarte
    stabilisation itself is checked with a pinned tight solver (RK45 rtol 1e-7): drift < 1e-10 m."""
    run = build_run(name, duration=0.03)
    result = run_scene(run)
    assert result.success, result.message
    assert result["constraint_residual"].max() < DRIFT_TARGET
    tight = run_scene(with_solver(run, SolverOptions("RK45", rtol=1e-7, atol=1e-9, max_step=1e-3)))
    assert tight.success, tight.message
    assert tight["constraint_residual"].max() < 1e-10
    for joint in result.clearance_joints:
        assert result[f"{joint}_penetration"].max() < 0.2 * 1e-4
        assert np.all(np.isfinite(result[f"{joint}_normal_force"]))


def test_scene_builds_only_what_it_uses():
    ideal, spherical, revolute, compound = (build_run(n, duration=0.01) for n in ("ideal", "spherical", "revolute", "compound"))
    assert ideal.mechanism.model.nv == 20 and ideal.dynamics.n_candidates == 0
    assert spherical.mechanism.model.nv == 20 and spherical.dynamics.n_candidates == 1
    assert spherical.mechanism.n_closure_equations == 12
    assert revolute.mechanism.model.nv == 25 and revolute.dynamics.n_candidates == 4
    assert compound.mechanism.model.nv == 25 and compound.dynamics.n_candidates == 5


def test_misaligned_scene_starts_with_the_bearing_rotated():
    """Centred start: the tilt is exactly the scene's. (Resting, the shipped start, tilts the journal
    further under the ideal joint's moment: tests/test_resting_state.py.)"""
    centred = {"initial.clearance_state": "centred"}
    aligned = build_run(load_scene("compound").with_changes(centred))
    misaligned = build_run(load_scene("compound_misaligned").with_changes(centred))
    import pinocchio as pin

    def bearing_tilt(run):
        model = run.mechanism.model
        data = model.createData()
        pin.framesForwardKinematics(model, data, run.y0[: model.nq])
        site = run.mechanism.site("R1")
        outer, inner = data.oMf[site.outer_frame].rotation, data.oMf[site.inner_frame].rotation
        return np.degrees(np.arccos(np.clip(outer[:, 2] @ inner[:, 2], -1, 1)))

    assert bearing_tilt(aligned) == pytest.approx(0.0, abs=1e-7)
    assert bearing_tilt(misaligned) == pytest.approx(0.035, abs=1e-6)


def test_user_scene_by_path(tmp_path):
    path = tmp_path / "mine.toml"
    path.write_text('extends = "spherical"\nname = "mine"\nduration = 0.5\n')
    scene = load_scene(str(path))
    assert scene.name == "mine" and scene.duration == 0.5 and scene.clearance_joints == ("S1",)


@pytest.mark.parametrize(
    "text, message",
    [
        ('extends = "ideal"\nbogus = 1\n', "unknown key(s) bogus"),
        ('extends = "ideal"\n[solver]\nmethod = "Euler"\n', "method='Euler' is not on offer"),
        ('extends = "ideal"\n[solver]\nrtol = -1\n', "rtol=-1 is out of range"),
        ('extends = "ideal"\nduration = 0\n', "duration=0 is out of range"),
        ('extends = "ideal"\n[[clearance]]\njoint = "S1"\ntype = "spherical"\nball_radius = 0.015\nclearance = 0.0\n', "clearance"),
        (
            'extends = "ideal"\n[[clearance]]\njoint = "R1"\ntype = "revolute"\njournal_radius = 0.02\nradial_clearance = -1e-4\n'
            "bearing_outer_radius = 0.03\nbearing_length = 0.04\naxial_clearance = 1e-4\n",
            "R1",
        ),
        ('extends = "ideal"\n[[clearance]]\njoint = "S1"\ntype = "cylindrical"\n', "type='cylindrical'"),
        ('extends = "ideal"\n[[clearance]]\njoint = "S1"\ntype = "spherical"\nball_radius = 0.015\nclearance = 1e-4\nmaterial = "gold"\n', "material='gold' is not defined"),
        ('extends = "ideal"\nmechanism = "nowhere.urdf"\n', "does not exist"),
        ("this is not toml", "not valid TOML"),
        ('extends = "ideal"\n[initial]\nmisalignment_deg = { R1 = 0.035 }\n', "not a revolute clearance joint"),
        (
            'extends = "ideal"\n[[clearance]]\njoint = "S1"\ntype = "revolute"\njournal_radius = 0.02\nradial_clearance = 1e-4\n'
            "bearing_outer_radius = 0.03\nbearing_length = 0.04\naxial_clearance = 1e-4\n",
            "clearance 'S1': type='revolute' cannot replace 'S1', a spherical closure",
        ),
        (
            'extends = "ideal"\n[[clearance]]\njoint = "R1"\ntype = "spherical"\nball_radius = 0.015\nclearance = 1e-4\n',
            "clearance 'R1': type='spherical' cannot replace 'R1', a revolute joint",
        ),
        ('extends = "ideal"\n[[clearance]]\njoint = "S1"\ntype = "spherical"\nball_radius = 0.015\n', "missing required key 'clearance'"),
    ],
)
def test_bad_scene_files_give_clear_errors(tmp_path, text, message):
    path = tmp_path / "bad.toml"
    path.write_text(text)
    with pytest.raises(SceneError, match=None) as info:
        load_scene(str(path))
    assert message in str(info.value)


def test_clearances_are_reported_as_given():
    """radial_clearance = 1e-4 is stored as a bore radius journal + 1e-4, but reported as 1e-4 exactly."""
    from robot.run import clearance_geometry

    scene = load_scene("compound")
    laws = {c.joint: c.law for c in scene.clearances}
    revolute = laws["R1"]
    assert revolute.bearing_inner_radius - revolute.journal_radius != 1e-4  # the subtraction does not round-trip
    assert revolute.radial_clearance == 1e-4 and revolute.axial_clearance == 1e-4
    assert clearance_geometry(revolute)["radial_clearance"] == 1e-4
    assert clearance_geometry(laws["S1"]) == {"ball_radius": 0.015, "clearance": 1e-4}
    np.testing.assert_array_equal(revolute.candidate_clearances(), [1e-4, 1e-4, 1e-4, 1e-4])


def test_unknown_scene_name():
    with pytest.raises(SceneError, match="neither a file nor a shipped scene"):
        load_scene("no_such_scene")


def test_clearance_on_a_joint_that_does_not_exist(tmp_path):
    path = tmp_path / "bad.toml"
    path.write_text('extends = "spherical"\n[[clearance]]\njoint = "Q9"\ntype = "spherical"\nball_radius = 0.015\nclearance = 1e-4\n')
    with pytest.raises(Exception, match="Q9"):
        build_run(str(path))


@pytest.mark.parametrize(
    ("overrides", "words"),
    [
        ({"trajectory.crank.rate": "fast"}, "crank: rate='fast' must be a finite number"),
        ({"trajectory.crank.offset": float("nan")}, "crank: offset=nan must be a finite number"),
        ({"trajectory.crank.amplitudes": [0.1, "x"], "trajectory.crank.harmonics": [1, 2], "trajectory.crank.phases": [0, 0]}, "amplitudes[1]='x' must be a finite number"),
        ({"trajectory.crank.amplitudes": 0.1}, "amplitudes=0.1 must be a list of finite numbers"),
        ({"trajectory.crank.amplitudes": [0.1], "trajectory.crank.harmonics": [1, 2]}, "must have the same length"),
    ],
)
def test_a_fourier_coordinate_s_numbers_are_checked_when_the_scene_is_read(overrides, words):
    """Refused before any run (a sweep's axis value too), naming the coordinate, key and value (once a run failed
    with 'could not convert string to float' on the point that had it)."""
    with pytest.raises(SceneError) as refused:
        load_scene("slider_crank_revolute", overrides)
    assert words in str(refused.value)


def test_an_override_that_changes_the_friction_law_starts_a_new_table():
    """`friction.law` is a kind key, like a time function's `function` (docs/scenes.md, "extends"): switching it drops
    the old law's keys, the keys given with it fill the new table whatever their order, and a key of no law in use
    (a swept `friction.dynamic` on a frictionless joint) is refused, not ignored."""
    off = load_scene("slider_crank_translational", {"clearance.slider.friction.law": "none"})
    assert off.clearances[0].law.scene_parameters["friction"] == {"law": "none"}
    coulomb = load_scene("slider_crank_translational", {"clearance.slider.friction.coefficient": 0.2, "clearance.slider.friction.law": "coulomb"})
    assert coulomb.clearances[0].law.scene_parameters["friction"]["coefficient"] == 0.2
    with pytest.raises(SceneError, match="unknown key.*dynamic.*of friction law 'none'"):
        load_scene("slider_crank_translational", {"clearance.slider.friction.law": "none", "clearance.slider.friction.dynamic": 0.2})


def test_an_override_switching_an_actuator_s_function_gives_the_whole_new_table():
    """Two kind keys in one table (an actuator's mode and its function): the table is emptied once, then filled with
    every key of the call, in any order (a second kind key emptied it again once)."""
    overrides = {"actuators.shoulder.value": 0.5, "actuators.shoulder.function": "constant", "actuators.shoulder.mode": "force"}
    scene = load_scene("free_two_link_spring", overrides)
    assert scene.document["actuators"]["shoulder"] == {"mode": "force", "function": "constant", "value": 0.5}
    with pytest.raises(SceneError, match="mode"):  # the new table without its mode: refused, naming it
        load_scene("free_two_link_spring", {"actuators.shoulder.function": "constant", "actuators.shoulder.value": 0.5})
