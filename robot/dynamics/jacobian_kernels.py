"""Compiled kernels of the state Jacobian's contact terms (:mod:`robot.dynamics.state_jacobian`).

For a clearance joint in contact: the derivative of its two wrenches with
respect to both element frames' poses and twists, by forward differences of its
compiled law kernel (:func:`site_derivative`), chained to generalized
coordinates through the frames' LWA Jacobians (:func:`add_site_stiffness`).

The law is chosen by its integer id among the shipped laws
(:data:`robot.dynamics.rhs_kernels.LAW_IDS`, so that these functions are cached on disk);
:func:`robot.dynamics.state_jacobian.for_workspace` leaves any other law to the solver's
own finite differences.
"""

from __future__ import annotations

import numpy as np

from clearance_contact.compiled import jit
from robot.dynamics.rhs_kernels import add_point_jacobian, law_kernel

#: forward-difference steps of the contact-wrench derivatives (pose: m, rad; twist: m/s, rad/s),
#: small against the penetrations (~1e-6..1e-5 m) and slip velocities the laws resolve
POSITION_STEP, ROTATION_STEP, VELOCITY_STEP, ANGULAR_VELOCITY_STEP = 1e-9, 1e-8, 1e-7, 1e-6


@jit
def frame_jacobian(placements, J, mask_row, frame, G, row):
    """G[row:row + 6] = LWA Jacobian of frame ``frame``'s origin: (J_lin + J_ang x p; J_ang) over its support."""
    for k in range(6):
        for c in range(J.shape[1]):
            G[row + k, c] = 0.0
    add_point_jacobian(J, mask_row, placements[frame, 9], placements[frame, 10], placements[frame, 11], 1.0, G, row)
    for c in range(J.shape[1]):
        if mask_row[c]:
            G[row + 3, c] = J[3, c]
            G[row + 4, c] = J[4, c]
            G[row + 5, c] = J[5, c]


@jit
def _perturb(rotation, position, twist, k, step, rotation_out, position_out, twist_out):
    """Copies of a frame's pose and twist with input ``k`` moved by ``step``.

    k = 0..2: position; 3..5: rotation ``exp(step [e_(k-3)]x) R`` (world axes, the
    convention of the LWA Jacobian's angular rows); 6..11: twist entry k - 6.
    """
    for i in range(3):
        position_out[i] = position[i]
        for j in range(3):
            rotation_out[i, j] = rotation[i, j]
    for i in range(6):
        twist_out[i] = twist[i]
    if k < 3:
        position_out[k] += step
    elif k < 6:
        a = k - 3
        b, c = (a + 1) % 3, (a + 2) % 3
        cosine, sine = np.cos(step), np.sin(step)
        for j in range(3):
            rotation_out[b, j] = cosine * rotation[b, j] - sine * rotation[c, j]
            rotation_out[c, j] = sine * rotation[b, j] + cosine * rotation[c, j]
    else:
        twist_out[k - 6] += step


@jit
def _input_step(k):
    """Forward-difference step of frame input k (see :func:`_perturb`)."""
    if k < 3:
        return POSITION_STEP
    if k < 6:
        return ROTATION_STEP
    if k < 9:
        return VELOCITY_STEP
    return ANGULAR_VELOCITY_STEP


@jit
def _chain(derivative, first_column, G, target):
    """target += G^T derivative[:, first_column:first_column + 12] G."""
    nv = G.shape[1]
    for c in range(nv):
        for r in range(12):
            dw = 0.0  # (D G)[r, c]
            for k in range(12):
                dw += derivative[r, first_column + k] * G[k, c]
            if dw != 0.0:
                for a in range(nv):
                    target[a, c] += G[r, a] * dw


@jit
def add_site_stiffness(placements, J, masks, frame_outer, frame_inner, derivative, G, dtau_dpose, dtau_dtwist):
    """Chain a site's wrench derivatives to generalized coordinates.

    ``derivative`` (12 x 24): rows the wrenches ``(w_outer, w_inner)``, columns the
    inputs ``(pose_outer, pose_inner, twist_outer, twist_inner)``, each pose
    ``(dp, dtheta)`` and twist ``(v, omega)`` in world axes. With ``G = [G_outer;
    G_inner]`` the frames' LWA Jacobians (12 x nv; a tangent displacement ``dxi``
    moves the frames by ``G dxi``, a velocity ``dv`` changes their twists by ``G
    dv``) and ``tau = G^T w``: ``dtau/dxi += G^T D_pose G``, ``dtau/dv += G^T
    D_twist G`` (the variation of ``G`` itself, ``O(|w|)`` and ``O(|v|)``, is left out).
    """
    frame_jacobian(placements, J, masks[0], frame_outer, G, 0)
    frame_jacobian(placements, J, masks[1], frame_inner, G, 6)
    _chain(derivative, 0, G, dtau_dpose)
    _chain(derivative, 12, G, dtau_dtwist)


@jit(exports=(
        "i8(i8, f8[::1], f8[:, ::1], f8[::1, :], i8[:, ::1], i8, i8, f8[::1], f8[:, ::1], f8[::1], i8, i8, f8[:, ::1], f8[:, ::1],"
        " Tuple((f8[:, :, ::1], f8[:, ::1], f8[:, ::1], f8[::1])), f8[:, ::1], f8[:, ::1])",
    ))
def site_stiffness(law_id, parameters, placements, J, masks, frame_outer, frame_inner, onset, twists, out, wrench_outer, wrench_inner, derivative, G, perturbed, dtau_dpose, dtau_dtwist):
    """Add one clearance joint's ``dtau_c/dxi`` and ``dtau_c/dv`` (zero out of contact); returns the law's status.

    Reads the joint's frame twists (``twists``) and law output (``out``) as the
    right-hand side left them at this state (:func:`robot.dynamics.rhs_kernels.all_sites`,
    same kinematics): if any wrench entry is nonzero (in contact), the 12 x 24
    derivative of its wrenches with respect to both frames' poses and twists
    (:func:`site_derivative`), chained by :func:`add_site_stiffness`. Scratch:
    ``derivative`` (12 x 24), ``G`` (12 x nv), ``perturbed`` (see
    :func:`site_derivative`).
    """
    if wrench_is_zero(out, wrench_outer, wrench_inner):
        return 0
    outer_rotation = placements[frame_outer, 0:9].reshape((3, 3)).T
    inner_rotation = placements[frame_inner, 0:9].reshape((3, 3)).T
    outer_position, inner_position = placements[frame_outer, 9:12], placements[frame_inner, 9:12]
    status = site_derivative(law_id, parameters, outer_rotation, outer_position, twists[0], inner_rotation, inner_position, twists[1], onset, out, wrench_outer, wrench_inner, derivative, perturbed)
    if status != 0:
        return status
    add_site_stiffness(placements, J, masks, frame_outer, frame_inner, derivative, G, dtau_dpose, dtau_dtwist)
    return 0


@jit
def wrench_is_zero(out, wrench_outer, wrench_inner):
    """True if both wrenches of a law's output are exactly zero (the joint is out of contact)."""
    for k in range(6):
        if out[wrench_outer + k] != 0.0 or out[wrench_inner + k] != 0.0:
            return False
    return True


@jit
def site_derivative(law_id, parameters, outer_rotation, outer_position, outer_twist, inner_rotation, inner_position, inner_twist, onset, base, wrench_outer, wrench_inner, derivative, perturbed):
    """derivative (12 x 24) = d(w_outer, w_inner)/d(pose_outer, pose_inner, twist_outer, twist_inner), forward differences.

    ``base``: the law's output at the unperturbed input. Column layout: outer
    pose (dp, dtheta) 0..5, inner pose 6..11, outer twist 12..17, inner twist
    18..23 (see :func:`_perturb`). ``perturbed``: scratch ``(rotations (2, 3, 3),
    positions (2, 3), twists (2, 6), law output)``: the law runs on copies.
    Forward differences (24 law calls) suffice: the matrix only steers Newton
    iterations, and their error (step / penetration ~ 1e-3) is far below what
    that tolerates. Returns the first nonzero status of the law.
    """
    rotations, positions, twists, scratch = perturbed
    for column in range(24):
        side = (column // 6) % 2  # 0: outer, 1: inner
        k = column % 6 + (6 if column >= 12 else 0)
        step = _input_step(k)
        _perturb(outer_rotation, outer_position, outer_twist, k, step if side == 0 else 0.0, rotations[0], positions[0], twists[0])
        _perturb(inner_rotation, inner_position, inner_twist, k, step if side == 1 else 0.0, rotations[1], positions[1], twists[1])
        status = law_kernel(law_id, parameters, rotations[0], positions[0], twists[0], rotations[1], positions[1], twists[1], onset, scratch)
        if status != 0:
            return status
        for r in range(6):
            derivative[r, column] = (scratch[wrench_outer + r] - base[wrench_outer + r]) / step
            derivative[6 + r, column] = (scratch[wrench_inner + r] - base[wrench_inner + r]) / step
    return 0

