"""Prescribed motions: the actuator histories s(t), ds/dt, d2s/dt2 of the driving constraints.

The seed paper's end-effector trajectory formula was lost in extraction; ours
is a smooth periodic 5-DOF motion of the platform (period T, omega = 2 pi / T),
each pose coordinate a truncated Fourier series::

    c(t) = offset + sum_i A_i sin(h_i omega t + phi_i)
    dc/dt = sum_i A_i h_i omega cos(h_i omega t + phi_i)
    d2c/dt2 = -sum_i A_i (h_i omega)^2 sin(h_i omega t + phi_i)

Reference motion (``reference_platform_motion``, T = 1 s): ``x = 0.03 sin(wt)``,
``z = 1.20 + 0.02 sin(2wt)``, ``roll = 0.05 sin(wt + pi/4)``,
``pitch = 0.04 sin(wt)``, ``yaw = 0.06 sin(wt + pi/2)`` (m, rad). Its actuator
lengths stay in [1.18, 1.30] m (UPS legs 1.218-1.294 m, RPS leg 1.180-1.220 m;
strokes [0.98, 1.55] m), the actuator rates within 0.38 m/s and accelerations
within 4.1 m/s^2 (T = 1 s), and the actuation Jacobian's condition number between
12.3 and 13.0 (``tests/test_kinematics.py``, ``docs/kinematics.md``).

A :class:`PlatformTrajectory` maps the pose through the exact inverse
kinematics (``platform_kinematics``), so the actuator rates and accelerations
are exact, not finite differences. A :class:`JointTrajectory` prescribes the
actuated joint coordinates directly (e.g. a crank turning at constant speed:
``offset + rate t``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from robot.model.platform_kinematics import PlatformLayout, leg_kinematics, platform_state
from robot.scene.loader import POSE_COORDINATES  # the scene schema's coordinate names



@dataclass(frozen=True)
class FourierCoordinate:
    """``offset + rate t + sum_i amplitude_i sin(harmonic_i omega t + phase_i)``."""

    offset: float = 0.0
    rate: float = 0.0
    amplitudes: tuple[float, ...] = ()
    harmonics: tuple[float, ...] = ()
    phases: tuple[float, ...] = ()

    def evaluate(self, t: float, omega: float) -> tuple[float, float, float]:
        value = self.offset + self.rate * t
        rate = self.rate
        accel = 0.0
        for amplitude, harmonic, phase in zip(self.amplitudes, self.harmonics, self.phases):
            w = harmonic * omega
            s, c = math.sin(w * t + phase), math.cos(w * t + phase)
            value += amplitude * s
            rate += amplitude * w * c
            accel -= amplitude * w * w * s
        return value, rate, accel


@dataclass(frozen=True, eq=False)
class PlatformTrajectory:
    """A periodic platform pose ``[x, z, roll, pitch, yaw](t)`` driven through the IK."""

    layout: PlatformLayout
    period: float
    coordinates: tuple[FourierCoordinate, ...]
    _cache: dict = field(default_factory=dict, repr=False, compare=False)

    def pose(self, t: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        omega = 2.0 * math.pi / self.period
        values = np.array([c.evaluate(t, omega) for c in self.coordinates])
        return values[:, 0], values[:, 1], values[:, 2]

    def drive(self, t: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Actuator coordinates s(t) and their exact first and second derivatives."""
        cached = self._cache.get("last")
        if cached is not None and cached[0] == t:
            return cached[1]
        pose, rate, accel = self.pose(t)
        legs = leg_kinematics(self.layout, platform_state(self.layout, pose, rate, accel))
        result = (legs.lengths, legs.rates, legs.accelerations)
        self._cache["last"] = (t, result)
        return result


@dataclass(frozen=True, eq=False)
class JointTrajectory:
    """Actuated joint coordinates prescribed directly, one time function each (:mod:`robot.model.time_functions`:
    a :class:`FourierCoordinate` through ``time_functions.Fourier``, a polynomial, a spline through a table...).

    No functions (a mechanism without motion-driven actuators): empty arrays.
    """

    functions: tuple

    def drive(self, t: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        values = np.array([f.evaluate(t) for f in self.functions], dtype=float).reshape(len(self.functions), 3)
        return values[:, 0], values[:, 1], values[:, 2]


def reference_platform_motion(layout: PlatformLayout, period: float = 1.0) -> PlatformTrajectory:
    """The reference 5-DOF platform motion documented in the module docstring."""
    quarter = math.pi / 4.0
    return PlatformTrajectory(
        layout,
        period,
        (
            FourierCoordinate(0.0, 0.0, (0.03,), (1,), (0.0,)),
            FourierCoordinate(1.20, 0.0, (0.02,), (2,), (0.0,)),
            FourierCoordinate(0.0, 0.0, (0.05,), (1,), (quarter,)),
            FourierCoordinate(0.0, 0.0, (0.04,), (1,), (0.0,)),
            FourierCoordinate(0.0, 0.0, (0.06,), (1,), (2 * quarter,)),
        ),
    )
