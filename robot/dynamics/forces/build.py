"""The :class:`ForceSet` of a scene: its ``[[force]]`` elements and its force-driven actuators."""

from __future__ import annotations

from robot.dynamics.forces.base import ForceElement, joint_coordinate
from robot.dynamics.forces.force_set import ForceSet
from robot.dynamics.forces.loads import JointForce, JointTorque
from robot.dynamics.forces.registry import FORCE_TYPES
from robot.errors import SceneError
from robot.model.actuation import ONE_COORDINATE, force_actuators
from robot.model.mechanism import Mechanism


def actuator_load(mechanism: Mechanism, joint: str, function, where: str) -> ForceElement:
    """A force-driven actuator: ``f(t)`` on the joint coordinate, its work counted as actuator work."""
    coordinate = joint_coordinate(mechanism, joint, ONE_COORDINATE, joint, f"{where} [actuators]", "")
    cls = JointForce if coordinate.kind == "prismatic" else JointTorque
    element = cls(joint, coordinate, function, actuator=True)
    return element


def build_force_set(scene, mechanism: Mechanism) -> ForceSet | None:
    """Elements in scene order, then the force-driven actuators (named by their joint); None if there are none."""
    where = f"scene {scene.name}"
    elements = [FORCE_TYPES[spec.kind].build(spec.name, spec.parameters, mechanism, spec.where) for spec in scene.forces]
    for joint, function in force_actuators(scene.actuators).items():
        if joint in {e.name for e in elements}:
            raise SceneError(f"{where}: force element name {joint!r} is also a force-driven actuator's name", key="name", value=joint)
        elements.append(actuator_load(mechanism, joint, function, where))
    return ForceSet(tuple(elements)) if elements else None
