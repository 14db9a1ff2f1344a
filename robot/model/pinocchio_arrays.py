"""Pinocchio's Jacobians and tangent map as numpy arrays of their full shape, for any number of coordinates.

eigenpy hands an Eigen matrix with one column back as a 1-D array: a frame
Jacobian (6 x nv) of a mechanism with one velocity coordinate comes back with
shape (6,), the constraint Jacobian of a single row as (nv,), and
``tangentMapProduct`` of such a mechanism as (1, 1). Code written for
``J[:3]`` = 3 x nv then fails (or silently broadcasts) at nv = 1. The
functions here are the same Pinocchio calls, reshaped to what they mean
(a view: no copy, the same bits).
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

LWA = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED


def frame_jacobian(model: pin.Model, data: pin.Data, frame: int, reference=LWA, placement: pin.SE3 | None = None) -> np.ndarray:
    """6 x nv Jacobian of frame ``frame`` (``pin.getFrameJacobian``; of the point ``placement`` of joint ``frame`` if given)."""
    if placement is None:
        jacobian = pin.getFrameJacobian(model, data, frame, reference)
    else:
        jacobian = pin.getFrameJacobian(model, data, frame, placement, reference)
    return jacobian.reshape(6, model.nv)  # the array's own reshape: ~0.9 us cheaper than np.reshape


def joint_jacobian(model: pin.Model, data: pin.Data, joint: int, reference=LWA) -> np.ndarray:
    """6 x nv Jacobian of joint ``joint`` (``pin.getJointJacobian``)."""
    return pin.getJointJacobian(model, data, joint, reference).reshape(6, model.nv)


def constraints_jacobian(model: pin.Model, data: pin.Data, models, datas, n_rows: int) -> np.ndarray:
    """``n_rows`` x nv Jacobian of Pinocchio's constraint models (``pin.getConstraintsJacobian``)."""
    return pin.getConstraintsJacobian(model, data, models, datas).reshape(n_rows, model.nv)


def tangent_map_product(model: pin.Model, q: np.ndarray, v: np.ndarray) -> np.ndarray:
    """dq/dt (nq) of the velocity ``v`` (nv) at ``q`` (``pin.tangentMapProduct``; on every right-hand side:
    the array's own ``reshape``, ~0.6 us cheaper than ``np.reshape`` with ``model.nq``)."""
    return pin.tangentMapProduct(model, q, v).reshape(-1)
