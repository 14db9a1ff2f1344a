"""Positions and ``LOCAL_WORLD_ALIGNED`` Jacobians of points fixed to links, on one ``pin.Data``.

Requires the joint placements ``data.oMi`` and the world joint Jacobians
``data.J`` at q (``computeJointJacobians``, ``computeAllTerms`` or
``computeJointJacobiansTimeVariation``), which every right-hand side computes.
A point ``p`` on joint ``j`` (offset ``r`` in the joint frame) is at
``p = R_j r + o_j`` and moves with ``v_p = J_lin v``, ``J_lin`` the linear rows of
``pin.getFrameJacobian(model, data, j, SE3(I, r), LOCAL_WORLD_ALIGNED)``; a fixed
world point (joint 0) has a zero Jacobian.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from robot.dynamics.forces.base import BodyPoint
from robot.model.pinocchio_arrays import frame_jacobian, joint_jacobian



class PointKinematics:
    """Point positions and Jacobians on ``data`` (see the module docstring).

    Per point, the joint's rotation and translation are numpy views into
    ``data.oMi`` bound on first use (they follow every kinematics update; reading
    ``data.oMi[j]`` anew costs ~10 us), with the point's ``SE3`` placement.
    """

    def __init__(self, model: pin.Model, data: pin.Data):
        self.model, self.data = model, data
        self._bound: dict[tuple[int, bytes], tuple[np.ndarray, np.ndarray, pin.SE3]] = {}
        self._zero = np.zeros((3, model.nv))

    def _views(self, point: BodyPoint) -> tuple[np.ndarray, np.ndarray, pin.SE3]:
        key = (point.joint, point.offset.tobytes())
        views = self._bound.get(key)
        if views is None:
            placement = self.data.oMi[point.joint]
            views = self._bound[key] = (placement.rotation, placement.translation, pin.SE3(np.eye(3), point.offset))
        return views

    def position(self, point: BodyPoint) -> np.ndarray:
        if point.joint == 0:
            return point.offset
        rotation, translation, _ = self._views(point)
        return rotation @ point.offset + translation

    def linear_jacobian(self, point: BodyPoint) -> np.ndarray:
        """3 x nv: ``v_p = J v`` (world axes)."""
        if point.joint == 0:
            return self._zero
        return frame_jacobian(self.model, self.data, point.joint, placement=self._views(point)[2])[:3]

    def angular_jacobian(self, joint: int) -> np.ndarray:
        """3 x nv: the angular velocity (world axes) of the body of joint ``joint``."""
        if joint == 0:
            return self._zero
        return joint_jacobian(self.model, self.data, joint)[3:]
