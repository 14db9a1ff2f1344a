"""The 4-UPS/RPS model file and its loading: URDF up to date and valid, coordinates and
mass of every clearance choice, the summary printed by scripts/describe_model.py, and
clear errors for bad mechanism files and bad clearance choices."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
import yourdfpy

from robot.model import constraints as C
from robot.model import kinematics as K
from robot.model.description import parse_mechanism
from robot.errors import ClearanceChoiceError, MechanismFileError
from robot.model.mechanism import build_mechanism
from robot.model.summary import describe, grubler_kutzbach, summarize
from robot.model.ups_rps_design import UpsRpsDesign, ups_rps_urdf

ROOT = Path(__file__).resolve().parents[1]
URDF = ROOT / "urdf" / "ups_rps.urdf"
DESIGN = UpsRpsDesign()
MOVING_MASS = DESIGN.platform_mass + 5 * (DESIGN.cylinder.mass + DESIGN.piston.mass) + 4 * DESIGN.cross_mass


# --------------------------------------------------------------------------- the model file


def test_urdf_file_is_generated_from_the_design():
    """urdf/ups_rps.urdf is exactly what scripts/build_urdf.py writes (regenerate it if this fails)."""
    assert URDF.read_text(encoding="utf-8") == ups_rps_urdf()


def test_urdf_validates_with_yourdfpy():
    robot = yourdfpy.URDF.load(str(URDF), build_scene_graph=False, load_meshes=False)
    assert robot.validate()
    assert len(robot.robot.links) == 16 and len(robot.robot.joints) == 15


def test_inertias_follow_the_stated_shapes():
    """Link inertias in the model equal the solid-cylinder / disc formulas of docs/parameters.md."""
    model = build_mechanism(URDF).model
    cylinder = model.inertias[model.getJointId("U1_y")]
    m, r, length = 25.96, 0.045, 0.76
    np.testing.assert_allclose(np.diag(cylinder.inertia), [m * (3 * r**2 + length**2) / 12] * 2 + [m * r**2 / 2])
    np.testing.assert_allclose(cylinder.lever, [0, 0, 0.38])
    piston = model.inertias[model.getJointId("P1")]
    np.testing.assert_allclose(piston.lever, [0, 0, -0.45])
    assert piston.mass == pytest.approx(8.45)
    platform = model.inertias[model.getJointId("platform_free")]
    m, r, t = 37.48, 0.35, 0.03
    np.testing.assert_allclose(np.diag(platform.inertia), [m * (3 * r**2 + t**2) / 12] * 2 + [m * r**2 / 2])


# --------------------------------------------------------------------------- clearance choices


@pytest.mark.parametrize(
    ("choice", "nq", "nv", "closures", "sites"),
    [
        (None, 21, 20, ("S1", "S2", "S3", "S4", "S5"), ()),
        ("S1", 21, 20, ("S2", "S3", "S4", "S5"), ("S1",)),
        ("R1", 27, 25, ("S1", "S2", "S3", "S4", "S5"), ("R1",)),
        ("R1,S1", 27, 25, ("S2", "S3", "S4", "S5"), ("S1", "R1")),
    ],
    ids=["ideal", "S1", "R1", "R1,S1"],
)
def test_clearance_choice_builds_the_right_coordinates(choice, nq, nv, closures, sites):
    mechanism = build_mechanism(URDF, clearance=choice)
    model = mechanism.model
    assert (model.nq, model.nv) == (nq, nv)
    assert tuple(c.name for c in mechanism.closures) == closures
    assert mechanism.clearance_names == sites
    assert mechanism.actuated_joints == ("P1", "P2", "P3", "P4", "P5")
    r1 = model.joints[model.getJointId("R1")].shortname()
    assert r1 == ("JointModelFreeFlyer" if "R1" in sites else "JointModelRY")
    # the actuator coordinates are the prismatic joints' (their stroke limits come along)
    for k, name in enumerate(mechanism.actuated_joints):
        assert mechanism.actuator_q_index[k] == model.idx_qs[model.getJointId(name)]
    np.testing.assert_array_equal(mechanism.stroke_lower, 0.98)
    np.testing.assert_array_equal(mechanism.stroke_upper, 1.55)
    assert mechanism.total_mass() - model.inertias[0].mass == pytest.approx(MOVING_MASS)


def test_clearance_element_frames_sit_on_the_ideal_joint():
    """At the assembled, centred home pose each site's outer and inner frames coincide, on the
    ideal joint: S1 at the platform origin, R1 at the base centre with z along world y."""
    from robot.model.platform_kinematics import PlatformLayout, inverse_kinematics

    mechanism = build_mechanism(URDF, clearance="R1,S1")
    model = mechanism.model
    data = model.createData()
    q, _ = inverse_kinematics(PlatformLayout.from_mechanism(mechanism), np.array([0.0, 1.2, 0.0, 0.0, 0.0]))
    pin.framesForwardKinematics(model, data, q)
    s1, r1 = mechanism.site("S1"), mechanism.site("R1")
    for site in (s1, r1):
        np.testing.assert_allclose(data.oMf[site.outer_frame].homogeneous, data.oMf[site.inner_frame].homogeneous, atol=1e-12)
    np.testing.assert_allclose(data.oMf[s1.outer_frame].translation, [0, 0, 1.2], atol=1e-12)
    assert model.frames[s1.outer_frame].parentJoint == model.getJointId("platform_free")  # socket on the platform
    np.testing.assert_allclose(data.oMf[r1.outer_frame].translation, 0.0, atol=1e-12)
    np.testing.assert_allclose(data.oMf[r1.outer_frame].rotation[:, 2], [0, 1, 0], atol=1e-12)
    assert model.frames[r1.outer_frame].parentJoint == model.getJointId("R1")  # bearing on the limb


def test_clearance_outer_element_side_can_be_chosen():
    mechanism = build_mechanism(URDF, clearance={"S1": "parent"})
    site = mechanism.site("S1")
    assert site.outer_on == "parent"
    assert mechanism.model.frames[site.outer_frame].parentJoint == mechanism.model.getJointId("P5")
    with pytest.raises(ClearanceChoiceError, match=r"outer_on='left' is not valid"):
        build_mechanism(URDF, clearance={"S1": "left"})


# --------------------------------------------------------------------------- summary


@pytest.mark.parametrize(
    ("choice", "free", "driven"), [(None, 5, 0), ("S1", 8, 3), ("R1", 10, 5), ("R1,S1", 13, 8)], ids=["ideal", "S1", "R1", "R1,S1"]
)
def test_summary_mobility_and_grubler_kutzbach(choice, free, driven):
    mechanism = build_mechanism(URDF, clearance=choice)
    summary = summarize(mechanism)
    assert (summary.mobility_free, summary.mobility_driven) == (free, driven)
    assert (summary.grubler_free, summary.grubler_driven) == (free, driven) == grubler_kutzbach(mechanism)
    assert summary.n_moving_bodies == 15
    assert summary.assembly_residual < 1e-12
    assert summary.moving_mass == pytest.approx(MOVING_MASS)
    assert summary.fixed_mass == pytest.approx(DESIGN.base_mass)
    assert sum(b.mass for b in summary.bodies) == pytest.approx(summary.total_mass)
    text = summary.text()
    assert f"{free} with actuators free" in text and f"{driven} driven" in text
    assert "Actuated joints (5): P1, P2, P3, P4, P5" in text


def test_describe_lists_joints_closures_and_clearance_sites():
    text = describe(build_mechanism(URDF, clearance="R1,S1"))
    assert "R1             free-flyer     7   6" in text
    assert "S1     spherical  limb5_piston -- platform: not imposed (clearance joint)" in text
    assert "S2     spherical  limb1_piston -- platform: 3 equations" in text
    assert "R1     revolute   replaces a joint, releases 5 constraints" in text
    assert "nq = 27, nv = 25" in text
    assert "Total mass: 290.73 kg (moving 210.73 kg" in text


def test_describe_model_script_runs():
    result = subprocess.run(
        [sys.executable, str(ROOT / "scripts" / "describe_model.py"), "--clearance", "S1"],
        capture_output=True,
        text=True,
        check=True,
        timeout=60,
    )
    assert "8 with actuators free (rank 12), 3 driven (rank 17)" in result.stdout
    bad = subprocess.run(
        [sys.executable, str(ROOT / "scripts" / "describe_model.py"), "--clearance", "Q9"],
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert bad.returncode == 2 and "clearance joint 'Q9' is neither a joint nor a closure" in bad.stderr


# --------------------------------------------------------------------------- bad input

MINIMAL = """<?xml version="1.0"?>
<robot name="bad">
  <link name="ground"/>
  <link name="arm"><inertial><mass value="1"/><inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/></inertial></link>
  <joint name="hinge" type="revolute"><parent link="ground"/><child link="arm"/><axis xyz="0 0 1"/>
    <limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
  {extra}
</robot>
"""


def _closure(kind="spherical", parent="arm", child="ground", axis=""):
    return (
        f'<closures><closure name="C" type="{kind}"><parent link="{parent}" xyz="0.1 0 0"/>'
        f'<child link="{child}" xyz="0.1 0 0"/>{axis}</closure></closures>'
    )


def test_malformed_xml_is_reported_with_its_position(tmp_path):
    path = tmp_path / "broken.urdf"
    path.write_text(MINIMAL.format(extra="<closures><closure name='C'></closures>"))
    with pytest.raises(MechanismFileError, match=r"broken\.urdf: malformed XML \(mismatched tag: line \d+, column \d+\)"):
        build_mechanism(path)


def test_missing_file_and_wrong_root():
    with pytest.raises(MechanismFileError, match=r"mechanism file '.*nowhere\.urdf' does not exist"):
        build_mechanism(Path("nowhere.urdf"))
    with pytest.raises(MechanismFileError, match=r"root element is <sdf>, a URDF needs <robot>"):
        parse_mechanism("<sdf/>", is_text=True)


def test_closure_naming_a_missing_link():
    with pytest.raises(MechanismFileError, match=r"closure 'C': <child link='wheel'> names a link that is not in the URDF \(links: arm, ground\)"):
        parse_mechanism(MINIMAL.format(extra=_closure(child="wheel")), is_text=True)


def test_a_misspelt_joint_type_is_named_with_its_file(tmp_path):
    """urdfdom's own message ('not a valid URDF model') names neither the joint nor the type."""
    path = tmp_path / "typo.urdf"
    path.write_text(MINIMAL.format(extra="").replace('type="revolute"', 'type="revolut"', 1))
    with pytest.raises(MechanismFileError, match=r"typo\.urdf: joint 'hinge' has type='revolut'; URDF joint types: revolute, continuous"):
        parse_mechanism(path)
    path.write_text(MINIMAL.format(extra=_closure(child="wheel")))
    with pytest.raises(MechanismFileError, match=r"typo\.urdf: closure 'C': <child link='wheel'>"):
        parse_mechanism(path)


def test_unknown_closure_type():
    with pytest.raises(MechanismFileError, match=r"closure 'C' has type='prismatic'; valid types: spherical, revolute"):
        parse_mechanism(MINIMAL.format(extra=_closure(kind="prismatic")), is_text=True)


def test_revolute_closure_needs_a_nonzero_axis():
    with pytest.raises(MechanismFileError, match=r"revolute closure 'C' needs <axis"):
        parse_mechanism(MINIMAL.format(extra=_closure(kind="revolute")), is_text=True)
    with pytest.raises(MechanismFileError, match=r"revolute closure 'C' has a zero axis"):
        parse_mechanism(MINIMAL.format(extra=_closure(kind="revolute", axis='<axis xyz="0 0 0"/>')), is_text=True)


def test_closure_with_bad_numbers():
    text = MINIMAL.format(extra=_closure()).replace('xyz="0.1 0 0"', 'xyz="0.1 zero 0"', 1)
    with pytest.raises(MechanismFileError, match=r"closure 'C' <parent>: attribute xyz='0.1 zero 0' must be three numbers"):
        parse_mechanism(text, is_text=True)


def test_transmission_naming_a_missing_joint():
    transmission = (
        '<transmission name="T"><type>transmission_interface/SimpleTransmission</type>'
        '<joint name="elbow"/><actuator name="A"/></transmission>'
    )
    with pytest.raises(MechanismFileError, match=r"transmission 'T' names joint 'elbow', which is not defined"):
        parse_mechanism(MINIMAL.format(extra=transmission), is_text=True)


def test_actuated_continuous_joint_is_rejected_with_advice():
    """A continuous joint has two coordinates (cos, sin): driving 'q = s(t)' would be wrong."""
    transmission = '<transmission name="T"><joint name="hinge"/><actuator name="A"/></transmission>'
    text = MINIMAL.format(extra=transmission).replace('type="revolute"', 'type="continuous"')
    with pytest.raises(MechanismFileError, match=r"actuated joint 'hinge' is a continuous joint .* nq = 2 .*declare it 'revolute'"):
        build_mechanism(parse_mechanism(text, is_text=True))


def test_bad_clearance_choices():
    with pytest.raises(ClearanceChoiceError, match=r"clearance joint 'R7' is neither a joint nor a closure of 'ups_rps'") as refused:
        build_mechanism(URDF, clearance="R7")
    offered = str(refused.value).split("joints that can carry clearance: ")[1].split(", ")
    assert "S1" in offered and not {"P1", "P5"} & set(offered)  # actuated joints cannot carry clearance: not offered
    # prismatic joints can carry clearance (translational types), but P5 is actuated
    with pytest.raises(ClearanceChoiceError, match=r"clearance joint 'P5' is actuated; an actuated joint cannot carry clearance"):
        build_mechanism(URDF, clearance="P5")


def test_all_closures_as_clearance_leaves_a_mechanism_without_loops():
    """Extreme choice: every spherical joint with clearance -> no loop equations, 5 actuators."""
    mechanism = build_mechanism(URDF, clearance="S1,S2,S3,S4,S5")
    assert mechanism.closures == () and mechanism.n_closure_equations == 0
    q = pin.neutral(mechanism.model)
    assert K.mobility(C.constraint_set(mechanism, driven=False), q) == mechanism.model.nv == 20
