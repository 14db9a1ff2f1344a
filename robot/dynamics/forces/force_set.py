"""The force elements of one run and their evaluation on a workspace's ``pin.Data``.

:class:`ForceSet` (immutable, on the :class:`robot.dynamics.equations.DynamicsModel`)
holds the elements a scene declares (and the force-driven actuators);
:meth:`ForceSet.bind` gives the per-workspace :class:`BoundForces` with its
buffers. ``BoundForces.evaluate(t, q, v)`` returns the total generalized force
``Q = Q_elements + Q_actuators`` (nv) added to the right-hand side of the KKT
system, and fills ``powers = [Q_actuators . v, Q_elements . v]``: the first is
integrated with the actuator work, the second as the force-element work
(``force_work``). A scene without elements has no ``ForceSet`` at all (the
right-hand side then does no extra work).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from robot.dynamics.forces.base import ForceElement, NonFiniteForceError
from robot.dynamics.forces.kinematics import PointKinematics
from robot.dynamics.forces.registry import class_name


@dataclass(frozen=True, eq=False)
class ForceSet:
    elements: tuple[ForceElement, ...]

    @property
    def names(self) -> tuple[str, ...]:
        return tuple(e.name for e in self.elements)

    @property
    def state_dependent(self) -> bool:
        """True if an element's law depends on (q, v) (springs, dampers), not only on t."""
        return any(e.state_dependent for e in self.elements)

    def bind(self, model: pin.Model, data: pin.Data) -> "BoundForces":
        return BoundForces(self, model, data)


class BoundForces:
    """A :class:`ForceSet` on one ``pin.Data`` (needs ``data.oMi`` and ``data.J`` at q: see ``kinematics.py``)."""

    def __init__(self, force_set: ForceSet, model: pin.Model, data: pin.Data):
        self.elements = force_set.elements
        self.kinematics = PointKinematics(model, data)
        self.total = np.zeros(model.nv)
        self.from_elements = np.zeros(model.nv)
        self.from_actuators = np.zeros(model.nv)
        self.scalars = np.zeros(len(self.elements))  # each element's scalar force or torque at the last call
        self.powers = np.zeros(2)  # [actuator power, element power] at the last call

    def evaluate(self, t: float, q: np.ndarray, v: np.ndarray) -> np.ndarray:
        """``Q(q, v, t)`` (a buffer, overwritten by the next call); ``scalars`` and ``powers`` updated."""
        self.from_elements[:] = 0.0
        self.from_actuators[:] = 0.0
        kinematics = self.kinematics
        for index, element in enumerate(self.elements):
            self.scalars[index] = element.apply(kinematics, t, q, v, self.from_actuators if element.actuator else self.from_elements)
        self.powers[0] = actuator_power = self.from_actuators @ v
        self.powers[1] = element_power = self.from_elements @ v
        np.add(self.from_elements, self.from_actuators, out=self.total)
        # Q . v is non-finite if a component of Q is: one check for every element's force and scalar (~0.3 us)
        if not math.isfinite(actuator_power + element_power + sum(self.scalars.tolist())):
            self.raise_for_non_finite_element(t, q, v)
        return self.total

    def raise_for_non_finite_element(self, t: float, q: np.ndarray, v: np.ndarray) -> None:
        """NonFiniteForceError naming the first element whose force or scalar is not finite at this finite state.

        A non-finite state (a trial stage after a refused contact pose) is not the
        elements' doing: the solver rejects that step on its non-finite derivative.
        Each element is evaluated again on its own buffer (``apply`` is a pure function).
        """
        if not (math.isfinite(t) and np.isfinite(q).all() and np.isfinite(v).all()):
            return
        alone = np.zeros_like(self.total)
        for element in self.elements:
            alone[:] = 0.0
            scalar = element.apply(self.kinematics, t, q, v, alone)
            problem = _non_finite_output(alone, scalar)
            if problem is not None:
                raise NonFiniteForceError(
                    f"force element {element.name!r} (type {type(element).type_name!r}, class {class_name(type(element))}) {problem} "
                    f"at t={t:.9g} s from a finite state: fix its apply (where its law is undefined, raise "
                    "robot.dynamics.forces.ForceElementError saying why)",
                    key=element.name,
                )

    def potential_energy(self, q: np.ndarray) -> float:
        """Energy stored in the elements at q (same kinematics requirement)."""
        return float(sum(e.potential_energy(self.kinematics, q) for e in self.elements))


def _non_finite_output(force: np.ndarray, scalar: object) -> str | None:
    """What is wrong with an element's generalized force and returned scalar; None if both are finite."""
    if not np.isfinite(force).all():
        return f"gave a non-finite generalized force {np.array2string(force, precision=3)}"
    try:
        value = float(scalar)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        return f"returned {scalar!r} from apply, not its scalar force or torque (a float)"
    if not math.isfinite(value):
        return f"returned a non-finite scalar force or torque ({scalar!r})"
    return None
