"""Scene-level inputs and outputs: shipped mechanism files, admissible misalignment, the [output] table, packaging."""

from __future__ import annotations

import math
import shutil
import tomllib
from pathlib import Path

import numpy as np
import pytest
from scipy.optimize import brentq

from clearance_contact import STEEL, RevoluteClearanceJoint
from robot.data import shipped_urdf, shipped_urdf_dir
from robot.errors import SceneError
from robot.integration.simulation import RECORD_OUTPUT, RECORD_STEP
from robot.io.array_names import is_bulk
from robot.io.results import load_result, save_result, select_records
from robot.run import build_run, run_scene
from robot.scene.loader import OutputSpec, admissible_misalignment, load_scene, misalignment_rotation, safe_file_stem

ROOT = Path(__file__).resolve().parents[1]


# --- mechanism files -----------------------------------------------------------------------


def test_shipped_mechanism_resolves_by_bare_name_and_package_url(tmp_path):
    for form in ("ups_rps.urdf", "package://ups_rps.urdf"):
        path = tmp_path / "s.toml"
        path.write_text(f'extends = "ideal"\nmechanism = "{form}"\n')
        assert load_scene(path).mechanism_path == shipped_urdf("ups_rps.urdf")
    assert (shipped_urdf_dir() / "ups_rps.urdf").is_file()


def test_a_user_mechanism_beside_the_scene_wins_over_the_shipped_one(tmp_path):
    (tmp_path / "sub").mkdir()
    shutil.copy(ROOT / "tests" / "data" / "rssr.urdf", tmp_path / "sub" / "ups_rps.urdf")
    scene = tmp_path / "sub" / "s.toml"
    scene.write_text('extends = "ideal"\nmechanism = "ups_rps.urdf"\n')
    assert load_scene(scene).mechanism_path == (tmp_path / "sub" / "ups_rps.urdf").resolve()
    nested = tmp_path / "nested.toml"
    nested.write_text('extends = "ideal"\nmechanism = "sub/ups_rps.urdf"\n')
    assert load_scene(nested).mechanism_path == (tmp_path / "sub" / "ups_rps.urdf").resolve()


@pytest.mark.parametrize("name, stem", [("compound", "compound"), ("a b/c", "a_b_c"), ("..", "scene"), ("x" * 300, "x" * 100), ("é", "scene")])
def test_safe_file_stem(name, stem):
    assert safe_file_stem(name) == stem
    assert "/" not in safe_file_stem(name) and not safe_file_stem(name).startswith(".")


# --- initial misalignment ------------------------------------------------------------------


def _bearing(radial: float, axial: float, outer: float = 0.035, length: float = 0.04, journal: float = 0.02) -> RevoluteClearanceJoint:
    return RevoluteClearanceJoint(
        journal_radius=journal,
        bearing_inner_radius=journal + radial,
        bearing_outer_radius=outer,
        journal_length=length + axial,
        bearing_length=length,
        journal_material=STEEL,
        bearing_material=STEEL,
        restitution=0.9,
    )


@pytest.mark.parametrize("outer, length, axial", [(0.035, 0.04, 1e-4), (0.05, 0.02, 3e-4), (0.03, 0.1, 2e-5)])
def test_axial_limit_of_misalignment_is_the_end_face_edge_touching_the_flange(outer, length, axial):
    """Radial clearance ample: the bearing's end-face edge (R_b2, L_b/2), rotated by a about x,
    rises to R_b2 sin a + L_b/2 cos a; it meets the journal flange at L_b/2 + c_a/2."""
    law = _bearing(radial=5e-3, axial=axial, outer=outer, length=length)
    expected = math.degrees(brentq(lambda a: outer * math.sin(a) + 0.5 * length * (math.cos(a) - 1.0) - 0.5 * axial, 0.0, 0.5))
    for sign in (1.0, -1.0):
        assert admissible_misalignment(law, sign) == pytest.approx(expected, abs=2e-6)


def test_admissible_misalignment_is_the_contact_boundary_of_the_law():
    """Radially limited geometry (long bearing, ample axial clearance): just below the angle no
    candidate touches, just above one does."""
    law = _bearing(radial=2e-5, axial=5e-3, length=0.08, outer=0.03)
    largest = admissible_misalignment(law)
    assert 0.0 < largest < 5.0
    centre = np.zeros(3)
    depth = lambda deg: float(np.max(law.penetration(misalignment_rotation(deg), centre, np.eye(3), centre)))  # noqa: E731
    assert depth(largest - 1e-4) <= 0.0 < depth(largest + 1e-4)
    # first order: the bearing's end ring, offset L_b/2 sin a from the journal axis, closes the radial gap
    assert largest == pytest.approx(math.degrees(math.asin(2e-5 / 0.04)), rel=0.05)


def test_shipped_misaligned_scene_is_admissible_and_the_refusal_names_the_limit(tmp_path):
    scene = load_scene("compound_misaligned")
    limit = admissible_misalignment(scene.clearances[1].law, -1.0)
    assert abs(scene.misalignment_deg["R1"]) < limit
    path = tmp_path / "s.toml"
    path.write_text(f'extends = "compound_misaligned"\n[initial]\nmisalignment_deg = {{ R1 = {-1.01 * limit} }}\n')
    with pytest.raises(SceneError, match=rf"misalignment_deg R1=.*at most -{limit:.6g} deg"):
        load_scene(path)


# --- [output] --------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def spherical_run(tmp_path_factory):
    """A short spherical-clearance run with contact, on a 1 ms output grid."""
    folder = tmp_path_factory.mktemp("scene")
    path = folder / "s.toml"
    path.write_text('extends = "spherical"\nname = "grid"\nduration = 0.03\n[output]\nstep = 1e-3\n')
    run = build_run(path)
    assert run.scene.solver.output_step == 1e-3
    return run, run_scene(run)


def test_output_grid_keeps_grid_and_located_records_with_exact_forces(spherical_run, tmp_path):
    run, result = spherical_run
    kind = result["record_kind"]
    assert np.any(kind == RECORD_OUTPUT) and np.any(kind == RECORD_STEP)
    saved = load_result(save_result(result, tmp_path / "r.npz", run.scene.output))
    rows = (kind != RECORD_STEP) | (np.arange(kind.size) == kind.size - 1)
    assert np.array_equal(saved["t"], result["t"][rows])
    assert np.count_nonzero(saved["record_kind"] == RECORD_OUTPUT) == math.floor(result.t_end / 1e-3 + 1e-9)
    for key in ("driving_force", "S1_normal_force", "S1_penetration", "kinetic_energy", "t"):
        assert saved[key].dtype == np.float64 and np.array_equal(saved[key], result[key][rows]), key
    # the located force maxima survive the thinning: the peak force is the run's
    assert saved["S1_normal_force"].max() == result["S1_normal_force"].max()
    assert saved["t"][-1] == result.t_end


def test_float32_only_for_bulk_arrays_and_within_single_precision(spherical_run):
    run, result = spherical_run
    thinned = select_records(result, OutputSpec(step=None, precision="float32"))
    for key, value in thinned.arrays.items():
        original = result[key]
        if is_bulk(key):
            assert value.dtype == np.float32, key
            np.testing.assert_allclose(value, original, rtol=1e-7, atol=1e-30 + 1e-7 * np.abs(original).max())
        else:
            assert value.dtype == original.dtype and np.array_equal(value, original), key
    assert select_records(result, OutputSpec(step=None, precision="float64"))["q"].dtype == np.float64


def test_keep_selects_arrays(spherical_run, tmp_path):
    run, result = spherical_run
    saved = load_result(save_result(result, tmp_path / "r.npz", OutputSpec(keep=("driving_force", "S1_normal_force"))))
    assert set(saved.arrays) == {"t", "record_kind", "driving_force", "S1_normal_force"}
    assert saved.metadata["output"]["keep"] == ["driving_force", "S1_normal_force"]


def test_step_zero_keeps_every_record(tmp_path):
    path = tmp_path / "s.toml"
    path.write_text('extends = "ideal"\n[output]\nstep = 0\nprecision = "float64"\n')
    scene = load_scene(path)
    assert scene.output == OutputSpec(step=None, keep=None, precision="float64") and scene.solver.output_step is None


# --- packaging -----------------------------------------------------------------------------


def test_pyproject_lists_every_package_and_ships_the_urdf():
    from setuptools import find_packages

    config = tomllib.loads((ROOT / "pyproject.toml").read_text())
    listed = set(config["tool"]["setuptools"]["packages"])
    found = set(find_packages(str(ROOT), include=["robot*", "clearance_contact*"]))
    assert listed == found | {"robot.data.urdf"}
    assert config["tool"]["setuptools"]["package-dir"]["robot.data.urdf"] == "urdf"
    assert config["project"]["scripts"]["clearance"] == "robot.cli.main:console_main"
    for scene in (ROOT / "robot" / "scene" / "scenes").glob("*.toml"):
        mechanism = tomllib.loads(scene.read_text()).get("mechanism")
        assert mechanism is None or "/" not in mechanism.removeprefix("package://"), f"{scene.name}: {mechanism}"
