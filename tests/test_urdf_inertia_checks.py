"""Masses and inertias of a URDF are checked when it is read (robot/model/description.py).

Pinocchio (and urdfdom, which prints "not a float" and carries on) takes a
negative, zero or NaN mass and an inertia with a negative principal moment; the run
then fails at t = 0 in the solver. They are refused at load time instead, naming
the link, the value and the valid range; a link without ``<inertial>`` stays a
legitimate massless link (a ground or a frame), unless it is all a movable
joint carries (a singular mass matrix).
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from robot.cli.main import main
from robot.errors import InertiaWarning, MechanismFileError
from robot.model.description import parse_mechanism
from robot.model.mechanism import build_mechanism

ARM = '<inertial><origin xyz="0 0 -0.25" rpy="0 0 0"/><mass value="{mass}"/><inertia {inertia}/></inertial>'
GOOD_INERTIA = 'ixx="0.02715" ixy="0" ixz="0" iyy="0.02735" iyz="0" izz="0.0004"'
FOREARM = '<inertial><origin xyz="0 0 -0.21" rpy="0 0 0"/><mass value="0.7"/><inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.0002"/></inertial>'

URDF = """<?xml version="1.0"?>
<robot name="arm">
  <link name="base"/>
  <link name="upper_arm">{upper}</link>
  <link name="forearm">{forearm}</link>
  <link name="tip"/>
  <joint name="shoulder" type="revolute"><parent link="base"/><child link="upper_arm"/><axis xyz="0 1 0"/>
    <limit lower="-10" upper="10" effort="1" velocity="1"/></joint>
  <joint name="elbow" type="revolute"><parent link="upper_arm"/><child link="forearm"/><origin xyz="0 0 -0.5"/><axis xyz="0 1 0"/>
    <limit lower="-10" upper="10" effort="1" velocity="1"/></joint>
  <joint name="tip_joint" type="fixed"><parent link="forearm"/><child link="tip"/><origin xyz="0 0 -0.42"/></joint>
</robot>
"""


def arm(mass="1.3", inertia=GOOD_INERTIA, upper=None, forearm=FOREARM) -> str:
    return URDF.format(upper=ARM.format(mass=mass, inertia=inertia) if upper is None else upper, forearm=forearm)


def test_a_valid_arm_with_massless_ground_and_frame_links_loads():
    mechanism = build_mechanism(parse_mechanism(arm(), is_text=True))
    assert mechanism.total_mass() == pytest.approx(2.0)


@pytest.mark.parametrize("mass", ["-1", "-1e-9", "nan", "NaN", "inf", "-inf", "abc", ""])
def test_a_mass_out_of_range_is_refused_naming_link_value_and_range(mass):
    with pytest.raises(MechanismFileError, match=rf"link 'upper_arm': mass='{mass}' is outside the valid range: a finite number >= 0 \(kg") as error:
        parse_mechanism(arm(mass=mass), is_text=True)
    assert error.value.key == "upper_arm.mass" and error.value.value == mass
    assert "no <inertial>" in str(error.value)  # how to declare a massless link instead


def test_an_inertial_without_mass_is_refused():
    upper = f'<inertial><origin xyz="0 0 0"/><inertia {GOOD_INERTIA}/></inertial>'
    with pytest.raises(MechanismFileError, match=r"link 'upper_arm': <inertial> has no <mass value=\.\.\.>"):
        parse_mechanism(arm(upper=upper), is_text=True)


@pytest.mark.parametrize(
    "inertia, message",
    [
        # negative moment
        ('ixx="-0.02715" ixy="0" ixz="0" iyy="0.02735" iyz="0" izz="0.0004"', r"ixx=-0.02715.* has a negative principal moment \(-0.02715, "),
        # positive diagonal, indefinite through a product of inertia
        ('ixx="0.02715" ixy="0.03" ixz="0" iyy="0.02735" iyz="0" izz="0.0004"', r"ixy=0.03.* has a negative principal moment"),
        # non-finite or missing components
        ('ixx="0.02715" ixy="0" ixz="0" iyy="0.02735" iyz="0" izz="nan"', r"<inertia> izz='nan' must be a finite number \(kg m\^2\)"),
        ('ixx="inf" ixy="0" ixz="0" iyy="0.02735" iyz="0" izz="0.0004"', r"<inertia> ixx='inf' must be a finite number"),
        ('ixy="0" ixz="0" iyy="0.02735" iyz="0" izz="0.0004"', r"<inertia> attribute ixx is missing; it must be a finite number"),
    ],
)
def test_an_inertia_out_of_range_is_refused_naming_link_value_and_range(inertia, message):
    with pytest.raises(MechanismFileError, match=r"link 'upper_arm': .*" + message) as error:
        parse_mechanism(arm(inertia=inertia), is_text=True)
    if "finite" not in message:
        assert "triangle inequalities Ixx + Iyy >= Izz" in str(error.value)  # the valid range


@pytest.mark.parametrize(
    "inertia, message",
    [
        # no body has these moments
        ('ixx="0.02715" ixy="0" ixz="0" iyy="0.02735" iyz="0" izz="0.06"', r"breaks the triangle inequality \(0.02715 \+ 0.02735 < 0.06 kg m\^2\)"),
        # diagonal fine in the given axes; a product of inertia makes a principal moment too large (0.1, 1, 1.9)
        ('ixx="1" ixy="0" ixz="0" iyy="1" iyz="0.9" izz="1"', r"triangle inequality \(principal moments: 0.1 \+ 1 < 1.9 kg m\^2\)"),
        # a planar link's file giving only the moment that matters
        ('ixx="0" ixy="0" ixz="0" iyy="0" iyz="0" izz="0.02"', r"triangle inequality \(0 \+ 0 < 0.02 kg m\^2\)"),
    ],
)
def test_a_broken_triangle_inequality_is_warned_about_and_used_as_given(inertia, message):
    """Not refused: files often give only the moment that matters (izz of a planar link); the run can use them."""
    with pytest.warns(InertiaWarning, match=message):
        mechanism = build_mechanism(parse_mechanism(arm(inertia=inertia), is_text=True))
    assert mechanism.total_mass() == pytest.approx(2.0)


def test_moments_rounded_to_a_thin_plate_are_accepted():
    # izz = ixx + iyy of a thin plate, rounded: 1/12 and 1/3 -> 0.0833 + 0.3333 = 0.4166 < 0.4167
    parse_mechanism(arm(inertia='ixx="0.0833" ixy="0" ixz="0" iyy="0.3333" iyz="0" izz="0.4167"'), is_text=True)


def test_a_non_finite_centre_of_mass_is_refused():
    upper = f'<inertial><origin xyz="0 0 nan"/><mass value="1"/><inertia {GOOD_INERTIA}/></inertial>'
    with pytest.raises(MechanismFileError, match=r"link 'upper_arm' <inertial><origin>: attribute xyz='0 0 nan' must be three finite numbers"):
        parse_mechanism(arm(upper=upper), is_text=True)


def test_a_massless_link_carried_with_mass_below_it_loads():
    """upper_arm has no <inertial>: the shoulder still moves the forearm's mass."""
    mechanism = build_mechanism(parse_mechanism(arm(upper=""), is_text=True))
    assert mechanism.total_mass() == pytest.approx(0.7)
    data = mechanism.model.createData()
    assert np.all(np.linalg.eigvalsh(pin.crba(mechanism.model, data, np.array([0.0, 0.3]))) > 0)


def test_a_movable_joint_that_carries_no_mass_is_refused():
    """Nothing below the elbow has an <inertial>: Pinocchio gives it zero inertia, a singular mass matrix."""
    text = arm(forearm="")
    model = pin.buildModelFromXML(text)
    assert pin.crba(model, model.createData(), pin.neutral(model))[1, 1] == 0.0  # why it is refused
    with pytest.raises(MechanismFileError, match=r"joint 'elbow' \(revolute\) moves link\(s\) forearm, tip, none of which has mass or inertia") as error:
        parse_mechanism(text, is_text=True)
    assert "mass matrix is singular" in str(error.value) and error.value.key == "elbow"


def test_describe_exits_2_with_the_message_and_no_traceback(tmp_path, capsys):
    path = tmp_path / "negative.urdf"
    path.write_text(arm(mass="-1"))
    assert main(["describe", "--urdf", str(path)]) == 2
    err = capsys.readouterr().err
    assert "negative.urdf: link 'upper_arm': mass='-1' is outside the valid range: a finite number >= 0 (kg" in err
    assert "Traceback" not in err



@pytest.mark.parametrize(
    "inertia",
    [
        'ixx="0" ixy="0" ixz="0" iyy="0" iyz="0" izz="0"',  # a point mass
        'ixx="0" ixy="0" ixz="0" iyy="0.0208" iyz="0" izz="0.0208"',  # a thin rod along x (m L^2 / 12)
    ],
)
def test_a_point_mass_or_a_thin_rod_loads_and_moves(inertia):
    """Common idealisations of link files: a semi-definite inertia is a body (the mass still makes M regular here)."""
    mechanism = build_mechanism(parse_mechanism(arm(inertia=inertia), is_text=True))
    data = mechanism.model.createData()
    q = pin.neutral(mechanism.model)
    mass_matrix = pin.crba(mechanism.model, data, q)
    assert np.all(np.linalg.eigvalsh(0.5 * (mass_matrix + mass_matrix.T)) > 0)


ZERO = 'ixx="0" ixy="0" ixz="0" iyy="0" iyz="0" izz="0"'


def test_mass_and_inertia_written_as_zero_are_a_massless_link():
    """Exporters write massless frames as <mass value="0"/> with a zero inertia (and noise like -1e-12)."""
    noisy_zero = ZERO.replace('ixx="0"', 'ixx="-1e-12"')
    upper = f'<inertial><mass value="0"/><inertia {noisy_zero}/></inertial>'
    mechanism = build_mechanism(parse_mechanism(arm(upper=upper), is_text=True))
    assert mechanism.total_mass() == pytest.approx(0.7)


UNIVERSAL = """<?xml version="1.0"?>
<robot name="u_joint">
  <link name="base"/>
  <link name="cross"><inertial><mass value="0"/><inertia {zero}/></inertial></link>
  <link name="shaft"><inertial><origin xyz="0 0 -0.2"/><mass value="0.5"/><inertia ixx="0.007" ixy="0" ixz="0" iyy="0.007" iyz="0" izz="0.0001"/></inertial></link>
  <link name="tool"><inertial><mass value="0"/><inertia {zero}/></inertial></link>
  <joint name="u1" type="revolute"><parent link="base"/><child link="cross"/><axis xyz="1 0 0"/>
    <limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
  <joint name="u2" type="revolute"><parent link="cross"/><child link="shaft"/><axis xyz="0 1 0"/>
    <limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
  <joint name="tool_joint" type="fixed"><parent link="shaft"/><child link="tool"/><origin xyz="0 0 -0.4"/></joint>
</robot>
"""


def test_a_universal_joint_with_a_massless_cross_and_a_zero_mass_tool_frame_loads():
    mechanism = build_mechanism(parse_mechanism(UNIVERSAL.format(zero=ZERO), is_text=True))
    mass_matrix = pin.crba(mechanism.model, mechanism.model.createData(), pin.neutral(mechanism.model))
    assert np.all(np.linalg.eigvalsh(0.5 * (mass_matrix + mass_matrix.T)) > 0)


def test_a_joint_moving_only_zero_mass_links_is_refused():
    text = UNIVERSAL.format(zero=ZERO).replace('<mass value="0.5"/><inertia ixx="0.007" ixy="0" ixz="0" iyy="0.007" iyz="0" izz="0.0001"/>', f'<mass value="0"/><inertia {ZERO}/>')
    with pytest.raises(MechanismFileError, match=r"joint 'u1' \(revolute\) moves link\(s\) .*singular"):
        parse_mechanism(text, is_text=True)
