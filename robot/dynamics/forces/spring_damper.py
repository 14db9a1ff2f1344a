"""Translational spring-damper-actuator between a point of link A and a point of link B (or the world).

With ``d = p_B - p_A``, ``L = |d|``, ``u = d / L`` and ``dL/dt = u . (v_B - v_A)``
(``v_A = J_A v``, ``J_A`` the point's LWA linear Jacobian), the element's tension
(positive pulls the points together) is

    f = k (L - L0) + c dL/dt + f_act          (linear spring)
    f = F(L)       + c dL/dt + f_act          (tabulated force-length F, cubic spline)

It pulls A by ``+f u`` and B by ``-f u``, so ``Q = -f (J_B - J_A)^T u`` and its power
``Q . v = -f dL/dt``. Potential energy: ``k (L - L0)^2 / 2``, or
``int_{L_1}^{L} F(s) ds`` from the table's first length ``L_1`` (the spline's
exact integral; beyond the table the curve continues along its end tangent).
The line of action is undefined at ``L = 0``: :class:`ForceElementError`.

Scene (``[[force]]``): ``type = "spring_damper"``, ``name``, ``link_a``, ``xyz_a``
[0 0 0], ``link_b`` (a link or ``"world"``), ``xyz_b`` [0 0 0] (link frames; world
frame for ``"world"``), either ``stiffness`` (N/m) and ``free_length`` (m) or
``length = [...]`` and ``force = [...]`` (m, N; lengths strictly increasing),
``damping`` (N s/m) [0], ``actuator_force`` (N, tension) [0].
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np

from robot.dynamics.forces.base import ForceElement, ForceElementError, body_point
from robot.dynamics.forces.registry import register
from robot.errors import SceneError
from robot.scene.loader import _number
from robot.scene.values import number_list, table_curve, vector3


@register("spring_damper")
class SpringDamper(ForceElement):
    KEYS = {"link_a", "xyz_a", "link_b", "xyz_b", "stiffness", "free_length", "length", "force", "damping", "actuator_force"}

    def __init__(self, name: str, point_a, point_b, stiffness: float, free_length: float, curve, damping: float, actuator_force: float):
        self.name = name
        self.point_a, self.point_b = point_a, point_b
        self.stiffness, self.free_length, self.curve = stiffness, free_length, curve
        self.damping, self.actuator_force = damping, actuator_force

    @classmethod
    def parse(cls, table: dict, where: str, base_dir: Path | None) -> dict[str, Any]:
        links = {}
        for key in ("link_a", "link_b"):
            link = table.get(key)
            if not isinstance(link, str) or not link:
                raise SceneError(f"{where}: {key}={link!r} must name a link (link_b may be 'world')", key=key, value=link)
            links[key] = link
        tabulated = "length" in table or "force" in table
        if tabulated and ("stiffness" in table or "free_length" in table):
            raise SceneError(f"{where}: give either stiffness and free_length or a length/force table, not both", key="stiffness", value=table.get("stiffness"))
        parameters = {
            **links,
            "xyz_a": vector3(table, "xyz_a", where, (0.0, 0.0, 0.0)),
            "xyz_b": vector3(table, "xyz_b", where, (0.0, 0.0, 0.0)),
            "damping": _number(table, "damping", where, 0.0, low=0.0),
            "actuator_force": _number(table, "actuator_force", where, 0.0),
            "stiffness": 0.0,
            "free_length": 0.0,
            "curve": None,
        }
        if tabulated:
            length, force = number_list(table, "length", where, min_length=2), number_list(table, "force", where, min_length=2)
            parameters["curve"] = table_curve(length, force, "length", "force", where)
        else:
            parameters["stiffness"] = _number(table, "stiffness", where, required=True, low=0.0)
            parameters["free_length"] = _number(table, "free_length", where, required=True, low=0.0)
        return parameters

    @classmethod
    def build(cls, name, parameters, mechanism, where) -> "SpringDamper":
        if parameters["link_a"] == "world":
            raise SceneError(f"{where}: link_a='world': the world end is link_b", key="link_a", value="world")
        point_a = body_point(mechanism, parameters["link_a"], parameters["xyz_a"], "link_a", where)
        point_b = body_point(mechanism, parameters["link_b"], parameters["xyz_b"], "link_b", where)
        p = parameters
        return cls(name, point_a, point_b, p["stiffness"], p["free_length"], p["curve"], p["damping"], p["actuator_force"])

    def _line(self, kinematics) -> tuple[float, np.ndarray]:
        d = kinematics.position(self.point_b) - kinematics.position(self.point_a)
        length = math.sqrt(float(d @ d))
        if length == 0.0:  # a NaN length is a non-finite state (a rejected trial stage), not this element's failure
            raise ForceElementError(f"spring_damper {self.name!r}: its two points coincide (length {length!r}); the line of action is undefined")
        return length, d / length

    def elastic_force(self, length: float) -> float:
        if self.curve is None:
            return self.stiffness * (length - self.free_length)
        return self.curve.evaluate(length)[0]

    def apply(self, kinematics, t, q, v, out) -> float:
        length, u = self._line(kinematics)
        relative = kinematics.linear_jacobian(self.point_b) - kinematics.linear_jacobian(self.point_a)
        direction = u @ relative  # dL/dt = direction . v
        tension = self.elastic_force(length) + self.damping * float(direction @ v) + self.actuator_force
        out -= tension * direction
        return tension

    def potential_energy(self, kinematics, q) -> float:
        length, _ = self._line(kinematics)
        if self.curve is None:
            return 0.5 * self.stiffness * (length - self.free_length) ** 2
        return self.curve.integral(length)
