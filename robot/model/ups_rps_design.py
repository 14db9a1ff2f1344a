"""Design parameters of the 4-UPS/RPS parallel mechanism and its URDF writer.

The seed paper's Table 1 (geometry and mass) was lost; the values here follow
``MODEL-NOTES.md`` section 2 (masses and rod lengths from the sister paper of the
same group, Shock and Vibration 2019, article 6242971, Table 1). The layout (base
and platform radii, attachment angles, home height) is ours, chosen so that the
actuation Jacobian stays well conditioned along the whole reference trajectory
(see ``docs/parameters.md`` and ``tests/test_kinematics.py``).

Frames (all right-handed, SI units):

* world = base frame: z up, gravity -z. ``R1`` sits at the base centre with its
  axis along world y, so the RPS limb swings in the x-z plane and the centre of
  ``S1`` (the platform origin) stays in the plane y = 0.
* UPS limb k: universal joint = revolute ``Uk_x`` (axis x of the base) followed by
  revolute ``Uk_y`` (axis y of the cross), then the actuated prismatic ``Pk`` along
  the leg axis (local z). The prismatic coordinate **is the actuator length**:
  the hinge-to-hinge distance between the universal-joint centre and the
  spherical-joint centre.
* RPS limb: revolute ``R1`` (axis y), actuated prismatic ``P5`` (local z, again
  the hinge-to-hinge length), spherical ``S1`` to the platform.
* The platform is attached to the tree by a ``floating`` joint (a free-flyer);
  the five spherical joints are loop closures declared in ``<closures>``.

This module is the single source of the numbers; ``scripts/build_urdf.py``
writes ``urdf/ups_rps.urdf`` from it and a test checks the file is up to date.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from xml.sax.saxutils import quoteattr


@dataclass(frozen=True)
class RodShape:
    """A limb rod modelled as a uniform solid cylinder (inertia derived from it)."""

    mass: float
    length: float
    radius: float
    com_from_hinge: float

    def inertia(self) -> tuple[float, float, float]:
        """Principal inertia (Ixx, Iyy, Izz) about the centre of mass, axis z.

        Solid cylinder: I_xx = I_yy = m (3 r^2 + l^2) / 12, I_zz = m r^2 / 2.
        """
        transverse = self.mass * (3.0 * self.radius**2 + self.length**2) / 12.0
        return transverse, transverse, 0.5 * self.mass * self.radius**2


@dataclass(frozen=True)
class UpsRpsDesign:
    """Every number of the mechanism, with its source in ``docs/parameters.md``."""

    # --- reference set (MODEL-NOTES.md section 2) ---
    platform_mass: float = 37.48
    cylinder: RodShape = RodShape(mass=25.96, length=0.76, radius=0.045, com_from_hinge=0.38)
    piston: RodShape = RodShape(mass=8.45, length=0.88, radius=0.025, com_from_hinge=0.45)
    # --- ours: layout chosen for conditioning (docs/parameters.md) ---
    base_radius: float = 0.55
    platform_radius: float = 0.30
    platform_thickness: float = 0.03
    base_angles_deg: tuple[float, ...] = (45.0, 135.0, 225.0, 315.0)
    platform_angle_offset_deg: float = 35.0
    home_height: float = 1.20
    stroke: tuple[float, float] = (0.98, 1.55)
    cross_mass: float = 0.30
    cross_size: float = 0.05
    base_mass: float = 80.0
    base_thickness: float = 0.04
    actuator_force_limit: float = 5.0e4
    actuator_velocity_limit: float = 1.0

    @property
    def platform_radius_disc(self) -> float:
        """Radius of the platform disc: attachment circle plus a rim."""
        return self.platform_radius + 0.05

    def ups_base_points(self) -> list[tuple[float, float, float]]:
        return [
            (self.base_radius * math.cos(math.radians(a)), self.base_radius * math.sin(math.radians(a)), 0.0)
            for a in self.base_angles_deg
        ]

    def ups_platform_points(self) -> list[tuple[float, float, float]]:
        """Platform attachment points in the platform frame, rotated from the base angles.

        Limbs 1 and 2 are offset by +offset, limbs 3 and 4 by -offset. Uniform or
        alternating offsets are singular at the home pose (a 4x4 minor of the
        actuation Jacobian vanishes: with the RPS limb vertical, the platform can
        rotate with all leg rates zero, MODEL-NOTES 1, singularity trap); this
        pattern gives a condition number of about 13 at home.
        """
        points = []
        for index, angle in enumerate(self.base_angles_deg):
            sign = 1.0 if index < 2 else -1.0
            a = math.radians(angle + sign * self.platform_angle_offset_deg)
            points.append((self.platform_radius * math.cos(a), self.platform_radius * math.sin(a), 0.0))
        return points

    def platform_inertia(self) -> tuple[float, float, float]:
        """Uniform disc of radius ``platform_radius_disc`` and thickness ``platform_thickness``."""
        r, t, m = self.platform_radius_disc, self.platform_thickness, self.platform_mass
        transverse = m * (3.0 * r**2 + t**2) / 12.0
        return transverse, transverse, 0.5 * m * r**2


def _f(value: float) -> str:
    return repr(float(value)) if value != 0 else "0"


def _xyz(vector) -> str:
    return " ".join(_f(c) for c in vector)


def _inertial(mass: float, com, inertia) -> str:
    ixx, iyy, izz = inertia
    return (
        f'    <inertial>\n      <origin xyz="{_xyz(com)}" rpy="0 0 0"/>\n'
        f'      <mass value="{_f(mass)}"/>\n'
        f'      <inertia ixx="{_f(ixx)}" ixy="0" ixz="0" iyy="{_f(iyy)}" iyz="0" izz="{_f(izz)}"/>\n'
        f"    </inertial>\n"
    )


def _shape(kind: str, geometry: str, origin, material: str | None = None) -> str:
    mat = f'      <material name="{material}"/>\n' if material and kind == "visual" else ""
    return (
        f"    <{kind}>\n      <origin xyz=\"{_xyz(origin)}\" rpy=\"0 0 0\"/>\n"
        f"      <geometry>{geometry}</geometry>\n{mat}    </{kind}>\n"
    )


def _link(name: str, mass: float, com, inertia, geometry: str, geometry_origin, material: str) -> str:
    return (
        f"  <link name={quoteattr(name)}>\n"
        + _inertial(mass, com, inertia)
        + _shape("visual", geometry, geometry_origin, material)
        + _shape("collision", geometry, geometry_origin)
        + "  </link>\n"
    )


def _rod_link(name: str, rod: RodShape, hinge_at_top: bool, material: str) -> str:
    """A rod whose frame origin is its hinge; it extends along +z (cylinder) or -z (piston)."""
    sign = -1.0 if hinge_at_top else 1.0
    com = (0.0, 0.0, sign * rod.com_from_hinge)
    centre = (0.0, 0.0, sign * rod.length / 2.0)
    geometry = f'<cylinder radius="{_f(rod.radius)}" length="{_f(rod.length)}"/>'
    return _link(name, rod.mass, com, rod.inertia(), geometry, centre, material)


def _joint(name: str, kind: str, parent: str, child: str, origin=(0, 0, 0), axis=None, limit: str = "") -> str:
    axis_xml = f'    <axis xyz="{_xyz(axis)}"/>\n' if axis is not None else ""
    return (
        f'  <joint name="{name}" type="{kind}">\n    <parent link="{parent}"/>\n    <child link="{child}"/>\n'
        f'    <origin xyz="{_xyz(origin)}" rpy="0 0 0"/>\n{axis_xml}{limit}  </joint>\n'
    )


def _transmission(joint: str, actuator: str) -> str:
    return (
        f'  <transmission name="{actuator}_transmission">\n'
        "    <type>transmission_interface/SimpleTransmission</type>\n"
        f'    <joint name="{joint}"><hardwareInterface>hardware_interface/EffortJointInterface</hardwareInterface></joint>\n'
        f'    <actuator name="{actuator}"><mechanicalReduction>1</mechanicalReduction></actuator>\n'
        "  </transmission>\n"
    )


CLOSURES_DOC = """  <!--
    Loop closures (project extension; Pinocchio and yourdfpy ignore this element).
    <closures>
      <closure name="NAME" type="spherical|revolute">
        <parent link="LINK" xyz="x y z" rpy="r p y"/>   frame on the first body
        <child  link="LINK" xyz="x y z" rpy="r p y"/>   frame on the second body
        <axis xyz="x y z"/>   (revolute only) joint axis in the parent frame
      </closure>
    </closures>
    spherical: the origins of the two frames coincide (3 equations);
    revolute: origins coincide and the axis, fixed in both frames, stays common
    (5 equations). Actuated joints are the joints named in <transmission> elements.
  -->
"""


def _closure(name: str, parent: str, parent_xyz, child: str, child_xyz) -> str:
    return (
        f'    <closure name="{name}" type="spherical">\n'
        f'      <parent link="{parent}" xyz="{_xyz(parent_xyz)}" rpy="0 0 0"/>\n'
        f'      <child link="{child}" xyz="{_xyz(child_xyz)}" rpy="0 0 0"/>\n'
        "    </closure>\n"
    )


def ups_rps_urdf(design: UpsRpsDesign = UpsRpsDesign()) -> str:
    """The URDF text of the 4-UPS/RPS mechanism described by ``design``."""
    lower, upper = design.stroke
    prismatic_limit = (
        f'    <limit lower="{_f(lower)}" upper="{_f(upper)}" effort="{_f(design.actuator_force_limit)}"'
        f' velocity="{_f(design.actuator_velocity_limit)}"/>\n'
    )
    revolute_limit = '    <limit lower="-1.2" upper="1.2" effort="0" velocity="10"/>\n'
    parts = [
        '<?xml version="1.0"?>\n<robot name="ups_rps">\n',
        '  <material name="steel"><color rgba="0.6 0.6 0.65 1"/></material>\n',
        '  <material name="piston"><color rgba="0.85 0.55 0.2 1"/></material>\n',
        '  <material name="platform"><color rgba="0.2 0.45 0.8 1"/></material>\n',
        '  <material name="base"><color rgba="0.3 0.3 0.3 1"/></material>\n',
    ]
    base_geometry = f'<cylinder radius="{_f(design.base_radius + 0.08)}" length="{_f(design.base_thickness)}"/>'
    base_inertia = (
        design.base_mass * (3 * (design.base_radius + 0.08) ** 2 + design.base_thickness**2) / 12.0,
        design.base_mass * (3 * (design.base_radius + 0.08) ** 2 + design.base_thickness**2) / 12.0,
        0.5 * design.base_mass * (design.base_radius + 0.08) ** 2,
    )
    below = (0.0, 0.0, -design.base_thickness / 2.0 - 0.03)
    parts.append(_link("base", design.base_mass, below, base_inertia, base_geometry, below, "base"))
    platform_geometry = f'<cylinder radius="{_f(design.platform_radius_disc)}" length="{_f(design.platform_thickness)}"/>'
    platform_centre = (0.0, 0.0, design.platform_thickness / 2.0)
    parts.append(
        _link("platform", design.platform_mass, platform_centre, design.platform_inertia(), platform_geometry, platform_centre, "platform")
    )
    parts.append(_joint("platform_free", "floating", "base", "platform", (0.0, 0.0, design.home_height)))
    cross_inertia = (design.cross_mass * design.cross_size**2 / 6.0,) * 3
    cross_geometry = f'<box size="{_xyz((design.cross_size,) * 3)}"/>'
    closures = []
    for k, (base_point, platform_point) in enumerate(zip(design.ups_base_points(), design.ups_platform_points()), start=1):
        cross, cylinder, piston = f"limb{k}_cross", f"limb{k}_cylinder", f"limb{k}_piston"
        parts.append(_link(cross, design.cross_mass, (0, 0, 0), cross_inertia, cross_geometry, (0, 0, 0), "steel"))
        parts.append(_rod_link(cylinder, design.cylinder, hinge_at_top=False, material="steel"))
        parts.append(_rod_link(piston, design.piston, hinge_at_top=True, material="piston"))
        parts.append(_joint(f"U{k}_x", "revolute", "base", cross, base_point, (1, 0, 0), revolute_limit))
        parts.append(_joint(f"U{k}_y", "revolute", cross, cylinder, (0, 0, 0), (0, 1, 0), revolute_limit))
        parts.append(_joint(f"P{k}", "prismatic", cylinder, piston, (0, 0, 0), (0, 0, 1), prismatic_limit))
        parts.append(_transmission(f"P{k}", f"A{k}"))
        closures.append(_closure(f"S{k + 1}", piston, (0, 0, 0), "platform", platform_point))
    parts.append(_rod_link("limb5_cylinder", design.cylinder, hinge_at_top=False, material="steel"))
    parts.append(_rod_link("limb5_piston", design.piston, hinge_at_top=True, material="piston"))
    parts.append(_joint("R1", "revolute", "base", "limb5_cylinder", (0, 0, 0), (0, 1, 0), revolute_limit))
    parts.append(_joint("P5", "prismatic", "limb5_cylinder", "limb5_piston", (0, 0, 0), (0, 0, 1), prismatic_limit))
    parts.append(_transmission("P5", "A5"))
    closures.insert(0, _closure("S1", "limb5_piston", (0, 0, 0), "platform", (0, 0, 0)))
    parts.append(CLOSURES_DOC)
    parts.append("  <closures>\n" + "".join(closures) + "  </closures>\n")
    parts.append("</robot>\n")
    return "".join(parts)
