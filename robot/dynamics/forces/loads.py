"""Applied loads given as functions of time: on a joint coordinate, or on a body.

* ``joint_torque`` (revolute or continuous joint; N m) and ``joint_force``
  (prismatic joint; N): ``Q_k += f(t)`` on the joint's velocity coordinate k,
  positive in the direction of increasing coordinate (right-hand rule about the
  joint axis for a torque). A torque on a prismatic joint (or a force on a
  revolute one) is refused: the type names the unit.
* ``body_force``: a world-frame force ``f(t) e`` (N; ``direction`` e, normalised)
  at the point ``xyz`` of a link: ``Q += J_p^T f e``.
* ``body_torque``: a world-frame torque ``f(t) a`` (N m; ``axis`` a, normalised)
  on a link: ``Q += J_omega^T f a``.

``f(t)``: the table's time function (``robot.scene.values.time_function``:
constant, polynomial, harmonic, tabulated). The scalar output is ``f(t)``. None
has a potential energy; their power ``Q . v`` is integrated as force work (or as
actuator work for a force-driven actuator, ``actuator = True``).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from robot.dynamics.forces.base import ForceElement, body_point, joint_coordinate
from robot.dynamics.forces.registry import register
from robot.errors import SceneError
from robot.scene.values import time_function, vector3


class JointLoad(ForceElement):
    """``f(t)`` on the coordinate of a joint of one of ``KINDS``."""

    KEYS = {"joint"}
    KINDS: tuple[str, ...] = ()
    state_dependent = False

    def __init__(self, name: str, coordinate, function, actuator: bool = False):
        self.name, self.coordinate, self.function, self.actuator = name, coordinate, function, actuator

    @classmethod
    def parse(cls, table: dict, where: str, base_dir: Path | None) -> dict[str, Any]:
        joint = table.get("joint")
        if not isinstance(joint, str) or not joint:
            raise SceneError(f"{where}: joint={joint!r} must name a joint", key="joint", value=joint)
        return {"joint": joint, "function": time_function(table, where, base_dir, extra_keys=cls.KEYS | {"name", "type"})}

    @classmethod
    def build(cls, name, parameters, mechanism, where) -> "JointLoad":
        other = "joint_force" if cls.type_name == "joint_torque" else "joint_torque"
        what = f"type={cls.type_name!r} acts on {' or '.join(cls.KINDS)} joints (use type = {other!r})"
        coordinate = joint_coordinate(mechanism, parameters["joint"], cls.KINDS, "joint", where, what)
        return cls(name, coordinate, parameters["function"])

    def apply(self, kinematics, t, q, v, out) -> float:
        value = self.function.evaluate(t)[0]
        out[self.coordinate.v_index] += value
        return value


@register("joint_torque")
class JointTorque(JointLoad):
    KINDS = ("revolute", "continuous")


@register("joint_force")
class JointForce(JointLoad):
    KINDS = ("prismatic",)


class BodyLoad(ForceElement):
    """``f(t)`` times a world direction, on a link."""

    state_dependent = False
    DIRECTION = ""

    def __init__(self, name: str, point, direction: np.ndarray, function):
        self.name, self.point, self.direction, self.function = name, point, direction, function

    @classmethod
    def parse(cls, table: dict, where: str, base_dir: Path | None) -> dict[str, Any]:
        link = table.get("link")
        if not isinstance(link, str) or not link:
            raise SceneError(f"{where}: link={link!r} must name a link", key="link", value=link)
        return {
            "link": link,
            "xyz": vector3(table, "xyz", where, (0.0, 0.0, 0.0)),
            "direction": vector3(table, cls.DIRECTION, where, unit=True),
            "function": time_function(table, where, base_dir, extra_keys=cls.KEYS | {"name", "type"}),
        }

    @classmethod
    def build(cls, name, parameters, mechanism, where) -> "BodyLoad":
        if parameters["link"] == "world":
            raise SceneError(f"{where}: link='world' is not a body of the mechanism", key="link", value="world")
        point = body_point(mechanism, parameters["link"], parameters["xyz"], "link", where)
        return cls(name, point, parameters["direction"], parameters["function"])


@register("body_force")
class BodyForce(BodyLoad):
    KEYS = {"link", "xyz", "direction"}
    DIRECTION = "direction"

    def apply(self, kinematics, t, q, v, out) -> float:
        value = self.function.evaluate(t)[0]
        out += kinematics.linear_jacobian(self.point).T @ (value * self.direction)
        return value


@register("body_torque")
class BodyTorque(BodyLoad):
    KEYS = {"link", "axis"}
    DIRECTION = "axis"

    def apply(self, kinematics, t, q, v, out) -> float:
        value = self.function.evaluate(t)[0]
        out += kinematics.angular_jacobian(self.point.joint).T @ (value * self.direction)
        return value
