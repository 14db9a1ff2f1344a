"""Force elements: springs, dampers, actuators and applied loads, one module per type, in a registry.

A scene declares elements in ``[[force]]`` tables (``type = ...``, ``name = ...``
and the type's keys; :mod:`robot.scene.loader`). Types (each module's docstring
has its equations and keys):

* ``spring_damper`` (:mod:`.spring_damper`): translational spring-damper-actuator
  between two points (linear or tabulated force-length);
* ``joint_spring_damper`` (:mod:`.joint_spring_damper`): on a joint coordinate;
* ``joint_torque``, ``joint_force``, ``body_force``, ``body_torque``
  (:mod:`.loads`): loads given as functions of time.

Every element gives ``Q(q, v, t) = sum J^T f`` (LWA point/body Jacobians), its
potential energy (springs) and its power ``Q . v``; the equations of motion add
the sum to the KKT right-hand side (``robot.dynamics.equations``). New types:
a module that defines a :class:`ForceElement` subclass decorated with
``@register("type_name")``, imported here (or a user's module imported before
the scene is loaded); ``register`` checks the class against the contract
(:class:`ForceElement`, ``docs/dynamics.md``).

Only :mod:`.force_set` and :mod:`.kinematics` import Pinocchio (not imported
here): scene parsing stays Pinocchio-free.
"""

from robot.dynamics.forces.base import BodyPoint, ForceElement, ForceElementError, JointCoordinate, NonFiniteForceError
from robot.dynamics.forces.registry import FORCE_TYPES, register
from robot.dynamics.forces import joint_spring_damper, loads, spring_damper  # noqa: F401 (registers the types)

__all__ = ["FORCE_TYPES", "register", "ForceElement", "ForceElementError", "NonFiniteForceError", "BodyPoint", "JointCoordinate"]
