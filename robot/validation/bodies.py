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
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from dataclasses import dataclass

import numpy as np

from robot.model.description import MechanismDescription


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
    """A moving link: mass, centre of mass in its link frame, inertia about the COM (link axes)."""

    name: str
    mass: float
    com: np.ndarray
    inertia: np.ndarray


@dataclass(frozen=True)
class JointSpec:
    """A URDF joint: kind, parent/child links, origin in the parent link frame, axis (joint frame)."""

    name: str
    kind: str
    parent: str
    child: str
    origin_xyz: np.ndarray
    origin_rotation: np.ndarray
    axis: np.ndarray


@dataclass(frozen=True)
class MechanismGeometry:
    """Bodies, joints and the ground link of a mechanism file."""

    ground: str
    bodies: tuple[BodySpec, ...]
    joints: tuple[JointSpec, ...]

    def body_index(self, link: str) -> int:
        """Index of a moving link in :attr:`bodies`; -1 for the ground."""
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


def _vector(element: ET.Element | None, attribute: str, default: str = "0 0 0") -> np.ndarray:
    text = default if element is None else element.get(attribute, default)
    return np.array([float(x) for x in text.split()])


def read_geometry(description: MechanismDescription) -> MechanismGeometry:
    """Masses, inertias and joint frames of every link and joint of the URDF."""
    root = ET.fromstring(description.urdf_text)
    children = {j.find("child").get("link") for j in root.findall("joint")}
    links = [link.get("name") for link in root.findall("link")]
    grounds = [name for name in links if name not in children]
    if len(grounds) != 1:
        raise ValueError(f"expected one root link, found {grounds}")
    bodies = []
    for link in root.findall("link"):
        name = link.get("name")
        if name == grounds[0]:
            continue
        inertial = link.find("inertial")
        if inertial is None:
            raise ValueError(f"link {name!r} has no <inertial>: a moving body needs a mass")
        origin = inertial.find("origin")
        com = _vector(origin, "xyz")
        rotation = rpy_matrix(_vector(origin, "rpy"))
        i = inertial.find("inertia")
        tensor = np.array(
            [
                [float(i.get("ixx", 0)), float(i.get("ixy", 0)), float(i.get("ixz", 0))],
                [float(i.get("ixy", 0)), float(i.get("iyy", 0)), float(i.get("iyz", 0))],
                [float(i.get("ixz", 0)), float(i.get("iyz", 0)), float(i.get("izz", 0))],
            ]
        )
        mass = float(inertial.find("mass").get("value"))
        bodies.append(BodySpec(name, mass, com, rotation @ tensor @ rotation.T))
    joints = []
    for element in root.findall("joint"):
        origin = element.find("origin")
        axis = _vector(element.find("axis"), "xyz", "1 0 0")
        norm = np.linalg.norm(axis)
        joints.append(
            JointSpec(
                element.get("name"),
                element.get("type"),
                element.find("parent").get("link"),
                element.find("child").get("link"),
                _vector(origin, "xyz"),
                rpy_matrix(_vector(origin, "rpy")),
                axis / norm if norm > 0 else axis,
            )
        )
    return MechanismGeometry(grounds[0], tuple(bodies), tuple(joints))
