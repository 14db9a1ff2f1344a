"""Geometry input for the independent formulations: bodies, joints and closures read from the URDF.

Only data is read here (masses, centres of mass, inertias, joint origins and
axes, closure frames), straight from the URDF text with ElementTree; no model
is built and no equation of motion is shared with the Lagrange model.

Frames
------
* The **link frame** of a link is the URDF one. The **body frame** used by the
  absolute-coordinate formulations has the orientation of the link frame and its
  origin at the centre of mass ``c'`` (the URDF ``<inertial><origin>``; the
  inertial ``rpy`` is applied to the inertia tensor,
  ``J' = R_in J_principal R_in^T``). A point with link-frame coordinates
  ``x'`` has body-frame coordinates ``x' - c'``.
* The **root link** (the one that is no joint's child, ``base``) is the ground:
  its link frame is the world frame.
* A joint's origin ``(xyz, rpy)`` places the joint frame in the parent link frame;
  at zero joint coordinate the child link frame coincides with it. Revolute:
  the child rotates about ``axis`` (joint frame); prismatic: the child origin
  moves along ``axis`` by the joint coordinate; ``floating``: no constraint.
* A link on a **fixed** joint is part of its parent's body (as in Pinocchio,
  which merges it the same way): its mass, if any, is added to the parent's
  (combined centre of mass, inertia moved there by the parallel-axis theorem),
  and every frame given on it (joint origins, closure and contact frames, the
  end effector) is expressed in the parent's link frame (:meth:`MechanismGeometry.place`).
  A massless link on a fixed joint (a tool frame, a tip marker) thus contributes
  nothing but its frame. Links fixed to the root are part of the ground.

What the independent formulations cannot model raises
:class:`UnsupportedFeatureError` (a moving body without mass or with a singular
inertia: their equations divide by both).
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from dataclasses import dataclass, field

import numpy as np

from robot.errors import RobotError
from robot.model.description import MechanismDescription


class UnsupportedFeatureError(RobotError, ValueError):
    """A feature of a scene or mechanism that an independent formulation (Newton-Euler, Exudyn) does not model.

    Raised before any run (``robot.validation.study.check_scenes``), naming the
    feature and what the formulation supports; ``clearance validate`` exits 2.
    """


def rpy_matrix(rpy) -> np.ndarray:
    """URDF roll-pitch-yaw: ``R = Rz(yaw) Ry(pitch) Rx(roll)``."""
    r, p, y = (float(a) for a in rpy)
    cr, sr, cp, sp, cy, sy = np.cos(r), np.sin(r), np.cos(p), np.sin(p), np.cos(y), np.sin(y)
    return np.array(
        [
            [cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
            [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
            [-sp, cp * sr, cp * cr],
        ]
    )


@dataclass(frozen=True)
class BodySpec:
    """A moving body: mass, centre of mass in its link frame, inertia about the COM (link axes).

    ``name`` is the link that carries the body (the child of a movable joint); the
    links fixed to it are merged in (see the module docstring).
    """

    name: str
    mass: float
    com: np.ndarray
    inertia: np.ndarray


@dataclass(frozen=True)
class JointSpec:
    """A movable URDF joint: kind, parent/child bodies, origin in the parent body's link frame, axis (joint frame)."""

    name: str
    kind: str
    parent: str
    child: str
    origin_xyz: np.ndarray
    origin_rotation: np.ndarray
    axis: np.ndarray


@dataclass(frozen=True)
class LinkPlacement:
    """Where a link's frame sits on the body (or ground) carrying it: ``x_carrier = rotation x_link + translation``."""

    carrier: str
    rotation: np.ndarray
    translation: np.ndarray


@dataclass(frozen=True)
class MechanismGeometry:
    """Bodies, movable joints, the ground link and the placement of every link of a mechanism file."""

    ground: str
    bodies: tuple[BodySpec, ...]
    joints: tuple[JointSpec, ...]
    placements: dict = field(default_factory=dict)  # link -> LinkPlacement (identity for a body's own link)

    def body_index(self, link: str) -> int:
        """Index of a moving body in :attr:`bodies`; -1 for the ground (a link fixed to a body: its carrier's)."""
        link = self.placements[link].carrier if link in self.placements else link
        if link == self.ground:
            return -1
        for k, body in enumerate(self.bodies):
            if body.name == link:
                return k
        raise KeyError(f"link {link!r} is not in the mechanism")

    def body(self, link: str) -> BodySpec | None:
        k = self.body_index(link)
        return None if k < 0 else self.bodies[k]

    def joint(self, name: str) -> JointSpec:
        for joint in self.joints:
            if joint.name == name:
                return joint
        raise KeyError(f"joint {name!r} is not in the mechanism")

    def place(self, link: str, xyz=(0.0, 0.0, 0.0), rotation=np.eye(3)) -> tuple[str, np.ndarray, np.ndarray]:
        """A frame given on ``link`` (``xyz``, ``rotation`` in its link frame) on the body carrying it: (carrier, xyz, rotation)."""
        return _place(self.placements[link], xyz, rotation)


def _place(placement: LinkPlacement, xyz, rotation) -> tuple[str, np.ndarray, np.ndarray]:
    """The frame (``xyz``, ``rotation``) of a link in the link frame of its carrier."""
    xyz, rotation = np.asarray(xyz, float), np.asarray(rotation, float)
    return placement.carrier, placement.rotation @ xyz + placement.translation, placement.rotation @ rotation


def _vector(element: ET.Element | None, attribute: str, default: str = "0 0 0") -> np.ndarray:
    text = default if element is None else element.get(attribute, default)
    return np.array([float(x) for x in text.split()])


def _joint_element(element: ET.Element) -> JointSpec:
    origin = element.find("origin")
    axis = _vector(element.find("axis"), "xyz", "1 0 0")
    norm = np.linalg.norm(axis)
    return JointSpec(
        element.get("name"),
        element.get("type"),
        element.find("parent").get("link"),
        element.find("child").get("link"),
        _vector(origin, "xyz"),
        rpy_matrix(_vector(origin, "rpy")),
        axis / norm if norm > 0 else axis,
    )


def _inertial(link: ET.Element) -> tuple[float, np.ndarray, np.ndarray] | None:
    """(mass, centre of mass, inertia about it in link axes) of a link's ``<inertial>``; None without one."""
    inertial = link.find("inertial")
    if inertial is None:
        return None
    origin = inertial.find("origin")
    rotation = rpy_matrix(_vector(origin, "rpy"))
    i = inertial.find("inertia")
    value = (lambda key: 0.0) if i is None else (lambda key: float(i.get(key, 0)))
    tensor = np.array(
        [
            [value("ixx"), value("ixy"), value("ixz")],
            [value("ixy"), value("iyy"), value("iyz")],
            [value("ixz"), value("iyz"), value("izz")],
        ]
    )
    mass = inertial.find("mass")
    return (0.0 if mass is None else float(mass.get("value"))), _vector(origin, "xyz"), rotation @ tensor @ rotation.T


def _placements(ground: str, links: list[str], fixed: dict[str, JointSpec]) -> dict[str, LinkPlacement]:
    """Every link's carrier (itself, or the first ancestor not on a fixed joint) and its frame there."""
    placements: dict[str, LinkPlacement] = {}

    def placement(link: str) -> LinkPlacement:
        if link not in placements:
            joint = fixed.get(link)
            if joint is None:  # the ground or the child of a movable joint: carries itself
                placements[link] = LinkPlacement(link, np.eye(3), np.zeros(3))
            else:
                up = placement(joint.parent)
                placements[link] = LinkPlacement(up.carrier, up.rotation @ joint.origin_rotation, up.rotation @ joint.origin_xyz + up.translation)
        return placements[link]

    for link in [ground, *links]:
        placement(link)
    return placements


def _merged_body(name: str, parts: list[tuple[float, np.ndarray, np.ndarray]]) -> BodySpec:
    """One rigid body from the masses fixed together (each: mass, COM and inertia in the carrier's link frame)."""
    if len(parts) == 1:  # a link alone: its own values, unchanged by the arithmetic below
        return BodySpec(name, *parts[0])
    mass = sum(m for m, _, _ in parts)
    com = sum(m * c for m, c, _ in parts) / mass if mass > 0 else np.zeros(3)
    inertia = np.zeros((3, 3))
    for m, c, tensor in parts:  # parallel-axis theorem: each part's inertia moved to the common COM
        d = c - com
        inertia += tensor + m * (d @ d * np.eye(3) - np.outer(d, d))
    return BodySpec(name, mass, com, inertia)


def read_geometry(description: MechanismDescription) -> MechanismGeometry:
    """Masses, inertias and joint frames of the URDF's bodies (links on fixed joints merged into their parents).

    ``UnsupportedFeatureError`` if a moving body has no mass or a singular inertia.
    """
    root = ET.fromstring(description.urdf_text)
    all_joints = [_joint_element(element) for element in root.findall("joint")]
    children = {j.child for j in all_joints}
    links = [link.get("name") for link in root.findall("link")]
    grounds = [name for name in links if name not in children]
    if len(grounds) != 1:
        raise UnsupportedFeatureError(f"expected one root link (the ground), found {grounds}")
    ground = grounds[0]
    placements = _placements(ground, links, {j.child: j for j in all_joints if j.kind == "fixed"})
    parts: dict[str, list] = {}
    members: dict[str, list[str]] = {}
    for link in root.findall("link"):
        name, where = link.get("name"), placements[link.get("name")]
        members.setdefault(where.carrier, []).append(name)
        inertial = _inertial(link)
        if inertial is not None and where.carrier != ground:
            m, c, tensor = inertial
            parts.setdefault(where.carrier, []).append((m, where.rotation @ c + where.translation, where.rotation @ tensor @ where.rotation.T))
    bodies = [_merged_body(name, parts.get(name, [])) for name in links if placements[name].carrier == name and name != ground]
    for body in bodies:
        _check_body(body, members[body.name])
    joints = []
    for joint in all_joints:
        if joint.kind == "fixed":
            continue
        carrier, xyz, rotation = _place(placements[joint.parent], joint.origin_xyz, joint.origin_rotation)
        joints.append(JointSpec(joint.name, joint.kind, carrier, joint.child, xyz, rotation, joint.axis))
    return MechanismGeometry(ground, tuple(bodies), tuple(joints), placements)


def _check_body(body: BodySpec, links: list[str]) -> None:
    """``UnsupportedFeatureError`` unless the body has a mass and an invertible inertia (Newton's and Euler's laws divide by them)."""
    names = ", ".join(repr(link) for link in links)
    if not body.mass > 0:
        raise UnsupportedFeatureError(
            f"link {names} moves on a movable joint and has no mass (no <inertial> or mass 0): the Newton-Euler and Exudyn "
            "models need a mass > 0 and an invertible inertia on every moving body (massless links are supported on fixed joints only)"
        )
    moments = np.linalg.eigvalsh(body.inertia)
    if not moments.min() > 1e-12 * max(moments.max(), 1e-300):
        raise UnsupportedFeatureError(
            f"link {names} has a singular inertia (principal moments {', '.join(f'{m:.3g}' for m in moments)} kg m^2): the "
            "Newton-Euler and Exudyn models need an invertible inertia on every moving body (a point mass or a thin rod cannot rotate there)"
        )
