"""The URDF's joints must form one tree (robot.model.description), and meshes are found beside the URDF
or left out with a warning (robot.model.mechanism).

Each file is a small planar four-bar written here: ground, crank, coupler, rocker, the loop closed
by the revolute closure D. The faults are made by changing one joint's parent or child.
"""

from __future__ import annotations

import re
import struct
import warnings
from pathlib import Path

import pytest

from robot.cli.common import EXIT_BAD_INPUT
from robot.cli.main import main
from robot.errors import MechanismFileError
from robot.model.description import parse_mechanism
from robot.model.mechanism import VisualGeometryWarning, build_mechanism

INERTIAL = '<inertial><mass value="0.2"/><inertia ixx="1e-5" ixy="0" ixz="0" iyy="5e-4" iyz="0" izz="5e-4"/></inertial>'


def four_bar(
    crank_parent: str = "ground",
    rocker_parent: str = "coupler",
    rocker_child: str = "rocker",
    closure_child: str = "rocker",
    coupler_visual: str = '<box size="0.2 0.01 0.01"/>',
) -> str:
    """A four-bar URDF; the arguments break its tree (or its closure) one joint at a time."""
    joint = '<joint name="{name}" type="revolute"><parent link="{parent}"/><child link="{child}"/>' \
        '<origin xyz="{x} 0 0"/><axis xyz="0 0 1"/><limit lower="-1000" upper="1000" effort="1" velocity="100"/></joint>'
    return f"""<robot name="tree_test">
  <link name="ground"/>
  <link name="crank">{INERTIAL}</link>
  <link name="coupler">{INERTIAL}<visual><origin xyz="0.1 0 0"/><geometry>{coupler_visual}</geometry></visual></link>
  <link name="rocker">{INERTIAL}</link>
  {joint.format(name="crank", parent=crank_parent, child="crank", x=0)}
  {joint.format(name="coupler", parent="crank", child="coupler", x=0.05)}
  {joint.format(name="rocker", parent=rocker_parent, child=rocker_child, x=0.2)}
  <transmission name="t"><joint name="crank"/><actuator name="M1"/></transmission>
  <closures>
    <closure name="D" type="revolute">
      <parent link="coupler" xyz="0.2 0 0"/><child link="{closure_child}" xyz="0.15 0 0"/><axis xyz="0 0 1"/>
    </closure>
  </closures>
</robot>
"""


def write(tmp_path: Path, text: str, name: str = "mechanism.urdf") -> Path:
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path


def refusal(tmp_path: Path, text: str) -> str:
    with pytest.raises(MechanismFileError) as caught:
        parse_mechanism(write(tmp_path, text))
    return str(caught.value)


def test_a_sound_tree_is_accepted(tmp_path):
    description = parse_mechanism(write(tmp_path, four_bar()))
    assert set(description.joints) == {"crank", "coupler", "rocker"}


def test_a_cycle_of_joints_is_refused_naming_its_joints(tmp_path):
    # ground -> (nothing); crank's parent is the rocker: crank -> coupler -> rocker -> crank
    message = refusal(tmp_path, four_bar(crank_parent="rocker"))
    assert "form a cycle" in message
    assert re.search(r"joints 'coupler', 'rocker', 'crank'", message), message
    assert "crank -> coupler -> rocker -> crank" in message
    assert "<closures>" in message and "docs/kinematics.md" in message


def test_a_joint_whose_parent_is_its_own_child_is_refused(tmp_path):
    message = refusal(tmp_path, four_bar(rocker_parent="rocker"))
    assert "joint 'rocker' has link 'rocker' as both its parent and its child" in message


def test_a_link_with_two_parent_joints_is_refused_naming_the_link_and_both_joints(tmp_path):
    # the rocker joint now also ends at the coupler; the rocker link hangs from nothing
    message = refusal(tmp_path, four_bar(rocker_parent="ground", rocker_child="coupler"))
    assert "link 'coupler' is the child of two joints, 'coupler'" in message
    assert "and 'rocker' (parent link 'ground')" in message


def test_a_link_joined_to_no_root_is_refused_naming_it(tmp_path):
    text = four_bar().replace('<link name="ground"/>', '<link name="ground"/>\n  <link name="orphan"/>')
    message = refusal(tmp_path, text)
    assert "link(s) 'orphan' cannot be reached from the root link 'ground'" in message


def test_a_closure_joining_a_link_to_itself_is_refused(tmp_path):
    message = refusal(tmp_path, four_bar(closure_child="coupler"))
    assert "closure 'D' joins link 'coupler' to itself" in message


@pytest.mark.parametrize("fault", [dict(crank_parent="rocker"), dict(rocker_parent="rocker"),
                                   dict(rocker_parent="ground", rocker_child="coupler")])
def test_describe_reports_a_broken_tree_in_one_line_with_exit_2(tmp_path, capsys, fault):
    code = main(["describe", "--urdf", str(write(tmp_path, four_bar(**fault)))])
    err = capsys.readouterr().err
    assert code == EXIT_BAD_INPUT, err
    assert err.startswith("error: ") and err.count("\n") == 1 and "Traceback" not in err
    assert "'rocker'" in err  # the joint at fault in each of the three files
    assert "<closures>" in err


# --------------------------------------------------------------------------- meshes


def stl_triangle(path: Path) -> None:
    """A binary STL file of one triangle (what assimp reads)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    facet = struct.pack("<12fH", 0, 0, 1, 0, 0, 0, 0.2, 0, 0, 0, 0.01, 0, 0)
    path.write_bytes(b"\0" * 80 + struct.pack("<I", 1) + facet)


def test_a_relative_mesh_is_found_beside_the_urdf(tmp_path, monkeypatch):
    stl_triangle(tmp_path / "robot" / "meshes" / "coupler.stl")
    path = write(tmp_path / "robot", four_bar(coupler_visual='<mesh filename="meshes/coupler.stl"/>'))
    monkeypatch.chdir(tmp_path)  # not the URDF's folder
    with warnings.catch_warnings():
        warnings.simplefilter("error", VisualGeometryWarning)
        mechanism = build_mechanism(path)
    (coupler,) = [g for g in mechanism.visual_model.geometryObjects if g.name.startswith("coupler")]
    assert Path(coupler.meshPath) == (tmp_path / "robot" / "meshes" / "coupler.stl").resolve()


def test_a_package_mesh_is_found_from_a_ros_package_layout(tmp_path, monkeypatch):
    # my_pkg/urdf/mechanism.urdf names package://my_pkg/meshes/coupler.stl
    stl_triangle(tmp_path / "my_pkg" / "meshes" / "coupler.stl")
    (tmp_path / "my_pkg" / "urdf").mkdir()
    text = four_bar(coupler_visual='<mesh filename="package://my_pkg/meshes/coupler.stl"/>')
    monkeypatch.chdir(tmp_path / "my_pkg")
    with warnings.catch_warnings():
        warnings.simplefilter("error", VisualGeometryWarning)
        mechanism = build_mechanism(write(tmp_path / "my_pkg" / "urdf", text))
    assert any(g.meshPath.endswith("my_pkg/meshes/coupler.stl") for g in mechanism.visual_model.geometryObjects)


@pytest.mark.parametrize("content", [None, b"not a mesh"], ids=["missing", "unreadable"])
def test_a_mesh_that_cannot_be_loaded_is_left_out_with_one_warning(tmp_path, content):
    if content is not None:
        (tmp_path / "meshes").mkdir()
        (tmp_path / "meshes" / "coupler.stl").write_bytes(content)
    path = write(tmp_path, four_bar(coupler_visual='<mesh filename="meshes/coupler.stl"/>'))
    with pytest.warns(VisualGeometryWarning) as caught:
        mechanism = build_mechanism(path, "D")
    messages = [str(w.message) for w in caught if issubclass(w.category, VisualGeometryWarning)]
    assert len(messages) == 1 and "\n" not in messages[0]
    assert "'meshes/coupler.stl' of link 'coupler'" in messages[0]
    assert not any(g.name.startswith("coupler") for g in mechanism.visual_model.geometryObjects)
    assert mechanism.model.nq == 3  # the dynamics' model is whole


def test_describe_goes_on_without_a_missing_mesh(tmp_path, capsys):
    path = write(tmp_path, four_bar(coupler_visual='<mesh filename="package://nowhere/coupler.stl"/>'))
    with pytest.warns(VisualGeometryWarning, match="package://nowhere/coupler.stl"):
        code = main(["describe", "--urdf", str(path)])
    captured = capsys.readouterr()
    assert code == 0, captured.err
    assert "Mechanism 'tree_test'" in captured.out
