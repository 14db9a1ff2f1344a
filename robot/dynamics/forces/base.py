"""What every force element is: a generalized force ``Q(q, v, t)`` (nv), its scalar output, its potential energy.

An element applies forces on the mechanism's bodies; its generalized force is
``Q = sum_i J_i^T f_i`` over the points (or bodies) it acts on, ``J_i`` the
``LOCAL_WORLD_ALIGNED`` Jacobian of the point (linear rows; angular rows for a
torque) and ``f_i`` the world-frame force (torque) on it: the principle of
virtual power, ``Q . v = sum_i f_i . v_i`` is the element's power on the
mechanism. The equations of motion add ``Q`` to the right-hand side of the
KKT system (``robot.dynamics.equations``).

Elements are written against :class:`PointKinematics` (``kinematics.py``:
positions and Jacobians of points fixed to links), so this package's element
modules import no Pinocchio and scene parsing stays Pinocchio-free.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, ClassVar

import numpy as np

from robot.errors import RobotError, SceneError

if TYPE_CHECKING:  # pragma: no cover
    from robot.dynamics.forces.kinematics import PointKinematics
    from robot.model.mechanism import Mechanism

WORLD = "world"


class ForceElementError(RobotError, ArithmeticError):
    """A force element met a state where its law is undefined (e.g. the two points of a spring coincide).

    An ``ArithmeticError``: raised inside a run, the step loop stops the run as a
    failure (cause ``solver error``, the message naming the element) and keeps the
    records so far.
    """


class NonFiniteForceError(ForceElementError):
    """A force element gave a non-finite generalized force or scalar output at a finite state."""


@dataclass(frozen=True)
class BodyPoint:
    """A point fixed to a link: its parent joint (0: the world) and its position in that joint's frame."""

    link: str
    joint: int
    offset: np.ndarray


@dataclass(frozen=True)
class JointCoordinate:
    """A joint of one velocity coordinate: its URDF kind and its indices in q and v."""

    name: str
    kind: str
    q_index: int
    v_index: int
    nq: int


class ForceElement(ABC):
    """A force element; subclasses register with :func:`robot.dynamics.forces.registry.register`.

    The contract (checked by ``register``; ``docs/dynamics.md``, "Adding a force element"):

    * ``KEYS``: the scene keys of its ``[[force]]`` table besides ``name`` and ``type``;
    * ``parse(table, where, base_dir)`` (classmethod): the validated parameters,
      a :class:`SceneError` naming key and value for a bad table (any other
      ``LookupError``, ``TypeError``, ``ValueError`` or ``ArithmeticError`` it
      raises becomes a SceneError naming the element and the exception);
    * ``build(name, parameters, mechanism, where)`` (classmethod): the element,
      with ``name`` set;
    * ``apply(kinematics, t, q, v, out)``: adds its generalized force to ``out``
      (nv) and returns its scalar force or torque (a finite float). A pure
      function of its arguments: the step loop evaluates a state again when it
      replays steps. A non-finite result at a finite state stops the run
      (:class:`NonFiniteForceError`, naming the element);
    * ``potential_energy(kinematics, q)``: its stored energy (default 0);
    * ``state_dependent`` (bool): its law depends on (q, v) (springs, dampers),
      not only on t through the Jacobians (applied loads); ``actuator`` (bool):
      its power counts as actuator work (a force-driven actuator), not as
      force-element work.
    """

    type_name: ClassVar[str] = ""
    KEYS: ClassVar[set[str]] = set()
    state_dependent: ClassVar[bool] = True
    actuator: bool = False
    name: str = ""

    @classmethod
    @abstractmethod
    def parse(cls, table: dict, where: str, base_dir: Path | None) -> dict[str, Any]:
        """Validated parameters of a scene table (no Pinocchio); SceneError naming key and value."""

    @classmethod
    @abstractmethod
    def build(cls, name: str, parameters: dict[str, Any], mechanism: "Mechanism", where: str) -> "ForceElement":
        """The element on ``mechanism`` (links and joints resolved); SceneError for unknown ones."""

    @abstractmethod
    def apply(self, kinematics: "PointKinematics", t: float, q: np.ndarray, v: np.ndarray, out: np.ndarray) -> float:
        """``out += Q(q, v, t)``; returns the element's scalar force (N) or torque (N m) for the outputs."""

    def potential_energy(self, kinematics: "PointKinematics", q: np.ndarray) -> float:
        """Potential energy stored in the element (0 for elements without one)."""
        return 0.0


def body_point(mechanism: "Mechanism", link: str, xyz: np.ndarray, key: str, where: str) -> BodyPoint:
    """The point ``xyz`` (in the link frame) of link ``link``, or a fixed world point for ``link = "world"``."""
    model = mechanism.model
    if link == WORLD:
        return BodyPoint(link, 0, np.asarray(xyz, dtype=float))
    if link not in mechanism.description.links:
        raise SceneError(
            f"{where}: {key}={link!r} is not a link of {mechanism.name!r}; links: {', '.join(mechanism.description.links)} (or 'world')",
            key=key,
            value=link,
        )
    frame = model.frames[mechanism.frame_id(link)]
    placement = frame.placement
    return BodyPoint(link, int(frame.parentJoint), placement.rotation @ np.asarray(xyz, dtype=float) + placement.translation)


def joint_coordinate(mechanism: "Mechanism", joint: str, kinds: tuple[str, ...], key: str, where: str, what: str) -> JointCoordinate:
    """A joint of the mechanism with one velocity coordinate whose URDF kind is one of ``kinds``."""
    declarations = mechanism.description.joints
    movable = sorted(n for n, j in declarations.items() if j.kind in ("revolute", "continuous", "prismatic"))
    if joint not in declarations:
        raise SceneError(f"{where}: {key}={joint!r} is not a joint of {mechanism.name!r}; its 1-dof joints: {', '.join(movable)}", key=key, value=joint)
    kind = declarations[joint].kind
    model = mechanism.model
    joint_id = model.getJointId(joint) if model.existJointName(joint) else model.njoints
    if joint_id >= model.njoints or model.nvs[joint_id] != 1:
        raise SceneError(f"{where}: {key}={joint!r} is not a one-coordinate joint of the model (a clearance joint makes it free)", key=key, value=joint)
    if kind not in kinds:
        raise SceneError(f"{where}: {key}={joint!r} is a {kind} joint; {what}", key=key, value=joint)
    return JointCoordinate(joint, kind, int(model.idx_qs[joint_id]), int(model.idx_vs[joint_id]), int(model.nqs[joint_id]))
