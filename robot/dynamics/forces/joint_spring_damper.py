"""Spring-damper on the coordinate of a one-coordinate joint (revolute or prismatic).

``Q_k = -(k (q_k - q0) + c qd_k)`` on the joint's coordinate k: a torque (N m; k
in N m/rad, c in N m s/rad) about a revolute joint's axis, a force (N; k in N/m,
c in N s/m) along a prismatic joint's axis, positive in the direction of
increasing coordinate. Potential energy ``k (q_k - q0)^2 / 2``; the scalar output
is the restoring load ``k (q_k - q0) + c qd_k``. A ``continuous`` joint
(Pinocchio stores ``cos, sin``) has no unwrapped angle: declare it revolute
with wide limits.

Scene: ``type = "joint_spring_damper"``, ``name``, ``joint``, ``stiffness``,
``rest_position`` (rad or m) [0], ``damping`` [0].
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from robot.dynamics.forces.base import ForceElement, joint_coordinate
from robot.dynamics.forces.registry import register
from robot.errors import SceneError
from robot.scene.loader import _number


@register("joint_spring_damper")
class JointSpringDamper(ForceElement):
    KEYS = {"joint", "stiffness", "rest_position", "damping"}

    def __init__(self, name: str, coordinate, stiffness: float, rest_position: float, damping: float):
        self.name, self.coordinate = name, coordinate
        self.stiffness, self.rest_position, self.damping = stiffness, rest_position, damping

    @classmethod
    def parse(cls, table: dict, where: str, base_dir: Path | None) -> dict[str, Any]:
        joint = table.get("joint")
        if not isinstance(joint, str) or not joint:
            raise SceneError(f"{where}: joint={joint!r} must name a joint", key="joint", value=joint)
        return {
            "joint": joint,
            "stiffness": _number(table, "stiffness", where, required=True, low=0.0),
            "rest_position": _number(table, "rest_position", where, 0.0),
            "damping": _number(table, "damping", where, 0.0, low=0.0),
        }

    @classmethod
    def build(cls, name, parameters, mechanism, where) -> "JointSpringDamper":
        what = "a joint spring needs a revolute or prismatic joint (a continuous joint has no unwrapped angle: declare it revolute)"
        coordinate = joint_coordinate(mechanism, parameters["joint"], ("revolute", "prismatic"), "joint", where, what)
        return cls(name, coordinate, parameters["stiffness"], parameters["rest_position"], parameters["damping"])

    def apply(self, kinematics, t, q, v, out) -> float:
        load = self.stiffness * (q[self.coordinate.q_index] - self.rest_position) + self.damping * v[self.coordinate.v_index]
        out[self.coordinate.v_index] -= load
        return float(load)

    def potential_energy(self, kinematics, q) -> float:
        return 0.5 * self.stiffness * float(q[self.coordinate.q_index] - self.rest_position) ** 2
