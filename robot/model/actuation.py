"""Actuator modes: which joints are driven by a prescribed motion, which by a prescribed force, which are free.

By default every joint named in a URDF ``<transmission>`` is motion-driven (a
driving constraint ``q_k - s_k(t) = 0``, seed paper eq. (22)). A scene's
``[actuators]`` table changes that per joint:

* ``motion``: driving constraint, its motion from ``[trajectory]``; the
  actuator's effort is the constraint's multiplier (``driving_force``);
* ``force``: no constraint: the joint is free and the actuator applies the
  generalized force ``f(t)`` (N on a prismatic joint, N m on a revolute one,
  positive in the direction of increasing coordinate), built as a
  ``joint_force``/``joint_torque`` element flagged ``actuator`` (its work is
  actuator work);
* ``none``: no constraint, no force: the joint is free.

Any one-coordinate joint may be listed, with or without a transmission. A
mechanism with no motion-driven joint (e.g. a URDF without transmissions)
moves under gravity and its force elements only.
"""

from __future__ import annotations

import dataclasses
from typing import Mapping

from robot.errors import SceneError
from robot.model.description import MechanismDescription

ONE_COORDINATE = ("revolute", "prismatic", "continuous")


def with_motion_actuators(description: MechanismDescription, actuators: Mapping, where: str) -> MechanismDescription:
    """The description with ``actuated_joints`` = the motion-driven joints (transmissions first, in file order)."""
    for joint, spec in actuators.items():
        declaration = description.joints.get(joint)
        if declaration is None or declaration.kind not in ONE_COORDINATE:
            movable = sorted(n for n, j in description.joints.items() if j.kind in ONE_COORDINATE)
            kind = "not a joint" if declaration is None else f"a {declaration.kind} joint"
            raise SceneError(
                f"{where} [actuators]: {joint!r} is {kind} of {description.name!r}; actuators drive one-coordinate joints: {', '.join(movable)}",
                key=joint,
                value=spec.mode,
            )
    listed = [j for j in description.actuated_joints if actuators.get(j) is None or actuators[j].mode == "motion"]
    listed += [j for j, spec in actuators.items() if spec.mode == "motion" and j not in description.actuated_joints]
    return dataclasses.replace(description, actuated_joints=tuple(listed))


def force_actuators(actuators: Mapping) -> dict:
    """Joint -> time function of the force-driven actuators."""
    return {joint: spec.function for joint, spec in actuators.items() if spec.mode == "force"}
