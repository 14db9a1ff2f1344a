"""What ``clearance animate`` accepts: which mechanism file a result is drawn on, result files that are
not results, an output that is the input, the bound of --exaggerate, and the default view's extent.

The mechanism is a one-link pendulum written here (a 1 m bar whose visual origin is its middle), saved
under the name of a shipped file (four_bar.urdf) to check that a user's file is never mistaken for it.
Results are made without integrating (robot.io.results.save_result).
"""

from __future__ import annotations

import base64
import re
from pathlib import Path

import numpy as np
import pytest
import umsgpack

from robot.cli.common import EXIT_BAD_INPUT
from robot.cli.main import main
from robot.data import shipped_urdf
from robot.errors import ResultFileError
from robot.io.results import SimulationResult, load_result, mechanism_fingerprint, save_result
from robot.viz.animation import AnimationError, AnimationOptions, export_html, load_for_animation

SHIPPED_NAME = "four_bar.urdf"
BAR_LENGTH = 1.0


def pendulum_urdf(length: float = BAR_LENGTH) -> str:
    return f"""<robot name="pendulum">
  <link name="ground"/>
  <link name="bar">
    <inertial><origin xyz="{length / 2} 0 0"/><mass value="1"/><inertia ixx="1e-4" ixy="0" ixz="0" iyy="0.08" iyz="0" izz="0.08"/></inertial>
    <visual><origin xyz="{length / 2} 0 0"/><geometry><box size="{length} 0.02 0.02"/></geometry></visual>
  </link>
  <joint name="swing" type="revolute">
    <parent link="ground"/><child link="bar"/><axis xyz="0 0 1"/>
    <limit lower="-10" upper="10" effort="1" velocity="10"/>
  </joint>
</robot>
"""


def result_of(urdf_text: str, recorded_path: Path | None, nq: int = 1, n: int = 4) -> SimulationResult:
    """A result of an ideal mechanism at rest, as ``clearance run`` records its mechanism file."""
    t = np.linspace(0.0, 0.1, n)
    arrays = {"t": t, "q": np.zeros((n, nq)), "v": np.zeros((n, nq)), "record_kind": np.zeros(n, dtype=np.int8)}
    metadata = {
        "mechanism": SHIPPED_NAME,
        "mechanism_path": None if recorded_path is None else str(recorded_path),
        "urdf_sha256": mechanism_fingerprint(urdf_text),
        "clearance": [],
    }
    counts = {"n_steps": n, "n_rejected": 0, "n_rhs": 0, "n_events": 0, "n_restarts": 0, "cpu_time": 0.0, "wall_time": 0.0}
    return SimulationResult("pendulum", 0, "made by the tests", None, 0.1, counts, arrays, metadata)


@pytest.fixture
def user_result(tmp_path) -> tuple[Path, Path]:
    """(the user's mechanism file, named like a shipped one; a result computed with it)."""
    assert shipped_urdf(SHIPPED_NAME).is_file()  # the name clash this file is about
    urdf = tmp_path / "mine" / SHIPPED_NAME
    urdf.parent.mkdir()
    urdf.write_text(pendulum_urdf(), encoding="utf-8")
    return urdf, save_result(result_of(pendulum_urdf(), urdf), tmp_path / "mine" / "pendulum.npz")


@pytest.fixture
def no_kernel_build(monkeypatch):
    """``clearance animate`` makes the kernel library ready first; these commands never reach a kernel."""
    monkeypatch.setattr("robot.dynamics.kernel_build.ensure_library", lambda *args, **kwargs: None)


def run_cli(capsys, *argv) -> tuple[int, str]:
    code = main([str(a) for a in argv])
    return code, capsys.readouterr().err


# --------------------------------------------------------------------------- which mechanism file


def test_the_file_the_run_read_wins_over_a_shipped_file_of_the_same_name(user_result):
    urdf, result = user_result
    mechanism, _ = load_for_animation(result)
    assert mechanism.description.path == urdf
    assert mechanism.name == "pendulum"


def test_a_moved_result_is_drawn_on_the_shipped_file_with_its_fingerprint(tmp_path):
    shipped = shipped_urdf(SHIPPED_NAME)
    text = shipped.read_text(encoding="utf-8")
    nq = 3  # crank, coupler, rocker
    path = save_result(result_of(text, tmp_path / "gone" / SHIPPED_NAME, nq=nq), tmp_path / "moved.npz")
    mechanism, _ = load_for_animation(path)
    assert mechanism.description.path == shipped


def test_when_no_file_matches_every_path_tried_is_named(user_result):
    urdf, result = user_result
    urdf.write_text(pendulum_urdf(length=0.5), encoding="utf-8")  # edited after the run
    with pytest.raises(ResultFileError) as caught:
        load_for_animation(result)
    message = str(caught.value)
    assert str(urdf) in message and str(shipped_urdf(SHIPPED_NAME)) in message
    assert message.count("fingerprint differs") == 2 and "--urdf" in message


# --------------------------------------------------------------------------- result files that are not results


def test_a_text_file_is_said_not_to_be_a_result_without_advice_to_unpickle(tmp_path):
    readme = tmp_path / "README.npz"
    readme.write_text("# a project\n\nSome text that numpy would try to unpickle.\n")
    with pytest.raises(ResultFileError) as caught:
        load_result(readme)
    message = str(caught.value)
    assert "is not a result file (.npz) of `clearance run`" in message
    assert "pickle" not in message.lower()


def test_a_folder_is_said_to_be_a_folder_and_a_missing_file_points_to_clearance_run(tmp_path):
    (tmp_path / "folder.npz").mkdir()
    with pytest.raises(ResultFileError, match=r"'.*folder.npz' is a folder"):
        load_result(tmp_path / "folder.npz")
    with pytest.raises(ResultFileError, match=r"does not exist; run `clearance run` first"):
        load_result(tmp_path / "missing.npz")


def test_a_damaged_archive_is_said_to_be_damaged(tmp_path, user_result):
    _, result = user_result
    damaged = tmp_path / "damaged.npz"
    damaged.write_bytes(result.read_bytes()[:200])
    with pytest.raises(ResultFileError, match="incomplete or damaged"):
        load_result(damaged)


# --------------------------------------------------------------------------- the output is not the input


def test_the_page_is_never_written_over_the_result(user_result, capsys, monkeypatch, no_kernel_build):
    _, result = user_result
    before = result.read_bytes()
    with pytest.raises(AnimationError, match="is the result file being animated"):
        export_html(result, result)
    monkeypatch.chdir(result.parent)
    # the same file spelled another way
    code, err = run_cli(capsys, "animate", result.name, "--html", Path("..") / result.parent.name / result.name)
    assert code == EXIT_BAD_INPUT, err
    assert "--html=" in err and "is the result file being animated" in err and "Traceback" not in err
    assert result.read_bytes() == before


# --------------------------------------------------------------------------- --exaggerate


@pytest.mark.parametrize("k", [1e300, 1e7, float("nan"), float("inf"), 0.5])
def test_exaggeration_outside_its_range_is_refused_naming_the_range(k):
    with pytest.raises(AnimationError, match=r"exaggerate=.* is outside the valid range \[1, 1,000,000\]"):
        AnimationOptions(exaggerate=k).check()


def test_the_largest_exaggeration_is_accepted():
    AnimationOptions(exaggerate=1e6).check()


def test_the_command_refuses_a_huge_exaggeration_with_exit_2(user_result, tmp_path, capsys, no_kernel_build):
    _, result = user_result
    code, err = run_cli(capsys, "animate", result, "--html", tmp_path / "a.html", "--exaggerate", "1e300")
    assert code == EXIT_BAD_INPUT and "valid range" in err
    assert not (tmp_path / "a.html").exists()


# --------------------------------------------------------------------------- the default view


def camera_distance(page: str) -> float:
    """Distance of the default camera from the view's centre (the world is shifted so the centre is at 0)."""
    for blob in re.findall(r'meshcatCommand\("([A-Za-z0-9+/=]+)"\)', page):
        command = umsgpack.unpackb(base64.b64decode(blob))
        if command.get("type") == "set_property" and command["path"].startswith("/Cameras/default") and command["property"] == "position":
            return float(np.linalg.norm(command["value"]))
    raise AssertionError("no camera position in the page")


def test_the_default_view_holds_a_long_link_whole(user_result, tmp_path):
    urdf, result = user_result
    page = export_html(result, tmp_path / "pendulum.html", urdf=urdf).html_path.read_text()
    # the camera stands 1.9 view radii away; the bar's half length is the least radius that shows it whole
    assert camera_distance(page) >= 1.9 * BAR_LENGTH / 2
