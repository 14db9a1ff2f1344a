"""Compiled kernels of the integrator's right-hand side (:func:`robot.dynamics.equations.state_derivative`).

Pinocchio computes, in C++, the joint placements, the world joint Jacobian
``J = data.J`` (6 x nv, spatial velocity ``(v_0, omega)`` of each body at the
world origin, world axes) and its time derivative ``dJ = data.dJ``
(``computeJointJacobiansTimeVariation``). Everything else the right-hand side
needs per frame is a few lines of vector algebra on those, compiled with numba
(``clearance_contact.compiled.jit``) so it costs no Python per frame:

* velocity of a point ``p`` of body ``i``: ``v_p = J_lin v + omega x p``,
  ``omega = J_ang v`` (columns of i's supporting joints only);
* its Jacobian: column ``c`` is ``J_lin[:, c] + J_ang[:, c] x p``;
* its classical acceleration at zero joint acceleration (the ``gamma`` of
  paper eq. (24)): ``a_p = dJ_lin v + (dJ_ang v) x p + omega x v_p``;
* a wrench ``(f, m)`` at ``p`` (world axes, moment about p) as a generalized
  force: ``tau_c = J_lin[:, c] . f + J_ang[:, c] . (m + p x f)`` (its power is
  ``f . v_p + m . omega``).

The frame placements are read from ``data.oMf`` through one (n_frames, 12)
array view (:func:`placement_buffer`: each ``SE3`` is 9 column-major rotation
entries then 3 translation entries, contiguous in Pinocchio's aligned vector;
the layout is verified when the view is made).

The closures' rows are paper eq. (21) (``Phi = p_a - p_b``; spherical and
revolute closures) and, for a revolute closure, eq. (20) (``z_a . x_b = 0``,
``z_a . y_b = 0``: the axes stay parallel; their Jacobian and velocity-product
rows use the frames' angular velocities ``J_ang v`` and accelerations at zero
joint acceleration ``dJ_ang v``), the driving rows eq. (22)
(``Phi = q_k - s_k(t)``), stabilised as in eq. (24):
the kernel returns Pinocchio's ``drift = 2 alpha Phid + beta^2 Phi - gamma``
(``robot.dynamics.equations`` for the sign convention). ``tests/test_integrators.py``
checks all of it against the reference functions of ``robot.model.constraints``
(Pinocchio's frame Jacobians and classical accelerations).

Called from Python, a compiled function costs ~0.1 us per array argument
(numba unboxes each one): so a right-hand side makes two calls,
:func:`rhs_terms` before Pinocchio's KKT solve and :func:`finish_derivative`
after it, and the step loop's probe one, :func:`probe_terms`, each on two
packed buffers (:func:`pack`) instead of some twenty arrays; the functions
they call are the building blocks above. The drive's ``[s, sd, sdd]`` are summed
inside these calls from its table's polynomial (:func:`power_series`, which
writes as many values as its output holds: the drive's value count is checked
once, ``robot.dynamics.equations.check_drive_size``).
"""

from __future__ import annotations

import ctypes
from collections.abc import Mapping
from pathlib import Path

import numpy as np
import pinocchio as pin
from numpy.typing import ArrayLike

from clearance_contact.compiled import jit, watch_numba_cache
from clearance_contact.revolute import RevoluteClearanceJoint, revolute_kernel
from clearance_contact.spherical import SphericalClearanceJoint, spherical_kernel
from clearance_contact.translational import TranslationalClearanceJoint, translational_kernel

# this package's compiled code calls clearance_contact's law kernels (see watch_numba_cache)
_ROBOT = Path(__file__).resolve().parent
watch_numba_cache(lambda: [*_ROBOT.glob("*.py"), *(_ROBOT.parents[1] / "clearance_contact").glob("*.py")], _ROBOT / "__pycache__")

SE3_FLOATS = 12  # 3x3 rotation (column-major) + translation


def placement_buffer(placements: "pin.StdVec_SE3") -> np.ndarray:
    """(n, 12) float view of a Pinocchio ``StdVec_SE3`` (e.g. ``data.oMf``): rotation (column-major), translation.

    The view follows every kinematics update of the ``Data`` it was made from
    (keep that ``Data`` alive). Raises ``RuntimeError`` if Pinocchio's memory
    layout is not the expected contiguous one.
    """
    n = len(placements)
    first = placements[0].rotation
    base = first.__array_interface__["data"][0]
    view = np.frombuffer((ctypes.c_double * (n * SE3_FLOATS)).from_address(base), dtype=float).reshape(n, SE3_FLOATS)
    for k in range(n):
        rotation, translation = placements[k].rotation, placements[k].translation
        if (
            rotation.__array_interface__["data"][0] != base + 8 * SE3_FLOATS * k
            or translation.__array_interface__["data"][0] != base + 8 * (SE3_FLOATS * k + 9)
            or not rotation.flags["F_CONTIGUOUS"]
        ):
            raise RuntimeError("unexpected memory layout of Pinocchio's SE3 vector: the compiled right-hand side cannot read it")
    return view


def support_mask(model: pin.Model, frame_ids) -> np.ndarray:
    """(len(frame_ids), nv) uint8: 1 where a velocity coordinate moves the frame's body.

    The kernels only test an entry for nonzero: :func:`pack` stores the masks as int64.
    """
    mask = np.zeros((len(frame_ids), model.nv), dtype=np.uint8)
    for row, frame_id in enumerate(frame_ids):
        for joint in model.supports[model.frames[frame_id].parentJoint]:
            if joint > 0:
                mask[row, model.idx_vs[joint] : model.idx_vs[joint] + model.nvs[joint]] = 1
    return mask


@jit
def _spatial_velocity(J, mask_row, v):
    """(v_0, omega) = J v over the columns of ``mask_row`` (6 floats; J or its time derivative)."""
    vx = vy = vz = wx = wy = wz = 0.0
    for c in range(J.shape[1]):
        if mask_row[c]:
            vc = v[c]
            vx += J[0, c] * vc
            vy += J[1, c] * vc
            vz += J[2, c] * vc
            wx += J[3, c] * vc
            wy += J[4, c] * vc
            wz += J[5, c] * vc
    return vx, vy, vz, wx, wy, wz


@jit
def point_velocity(placements, J, mask_row, frame, v, out):
    """out[0:3] = v_p, out[3:6] = omega of frame ``frame``'s origin (world axes); the LWA twist."""
    px, py, pz = placements[frame, 9], placements[frame, 10], placements[frame, 11]
    vx, vy, vz, wx, wy, wz = _spatial_velocity(J, mask_row, v)
    out[0] = vx + wy * pz - wz * py
    out[1] = vy + wz * px - wx * pz
    out[2] = vz + wx * py - wy * px
    out[3] = wx
    out[4] = wy
    out[5] = wz


@jit
def add_point_jacobian(J, mask_row, px, py, pz, sign, phi_q, row):
    for c in range(J.shape[1]):
        if mask_row[c]:
            wx, wy, wz = J[3, c], J[4, c], J[5, c]
            phi_q[row, c] += sign * (J[0, c] + wy * pz - wz * py)
            phi_q[row + 1, c] += sign * (J[1, c] + wz * px - wx * pz)
            phi_q[row + 2, c] += sign * (J[2, c] + wx * py - wy * px)


@jit
def _point_bias_acceleration(placements, J, dJ, mask_row, frame, v):
    """Classical acceleration of frame ``frame``'s origin at zero joint acceleration (world axes)."""
    px, py, pz = placements[frame, 9], placements[frame, 10], placements[frame, 11]
    vx, vy, vz, wx, wy, wz = _spatial_velocity(J, mask_row, v)
    ax, ay, az, bx, by, bz = _spatial_velocity(dJ, mask_row, v)
    # v_p = v_0 + omega x p;  a_p = a_0 + alpha x p + omega x v_p
    upx = vx + wy * pz - wz * py
    upy = vy + wz * px - wx * pz
    upz = vz + wx * py - wy * px
    return (
        ax + by * pz - bz * py + wy * upz - wz * upy,
        ay + bz * px - bx * pz + wz * upx - wx * upz,
        az + bx * py - by * px + wx * upy - wy * upx,
    )


@jit
def _point_rows(placements, J, dJ, mask_a, mask_b, fa, fb, v, two_alpha, beta_squared, phi_q, drift, row):
    """Rows ``row..row+2``: ``Phi = p_a - p_b`` (paper eq. (21)) of a spherical or revolute closure."""
    nv = J.shape[1]
    for k in range(3):
        for c in range(nv):
            phi_q[row + k, c] = 0.0
    add_point_jacobian(J, mask_a, placements[fa, 9], placements[fa, 10], placements[fa, 11], 1.0, phi_q, row)
    add_point_jacobian(J, mask_b, placements[fb, 9], placements[fb, 10], placements[fb, 11], -1.0, phi_q, row)
    aax, aay, aaz = _point_bias_acceleration(placements, J, dJ, mask_a, fa, v)
    abx, aby, abz = _point_bias_acceleration(placements, J, dJ, mask_b, fb, v)
    for k in range(3):
        rate = 0.0
        for c in range(nv):
            rate += phi_q[row + k, c] * v[c]
        phi = placements[fa, 9 + k] - placements[fb, 9 + k]
        # gamma = -(a_a - a_b) at zero joint acceleration
        bias = (aax, aay, aaz)[k] - (abx, aby, abz)[k]
        drift[row + k] = two_alpha * rate + beta_squared * phi + bias


@jit
def _cross(ax, ay, az, bx, by, bz):
    return ay * bz - az * by, az * bx - ax * bz, ax * by - ay * bx


@jit
def _axis_rows(placements, J, dJ, mask_a, mask_b, fa, fb, v, two_alpha, beta_squared, phi_q, drift, row):
    """Rows ``row, row+1``: the axis rows ``Phi = z_a . x_b``, ``z_a . y_b`` of a revolute closure (paper eq. (20)).

    With ``n = z_a x e_b`` (``e_b`` = x_b or y_b, columns of frame b's rotation) and the
    frames' angular velocities ``omega`` and accelerations at zero joint acceleration
    ``alpha = dJ_ang v``: ``Phi_q = n . (J_ang,a - J_ang,b)`` and
    ``gamma = -(n . (alpha_a - alpha_b) + n' . (omega_a - omega_b))``,
    ``n' = (omega_a x z_a) x e_b + z_a x (omega_b x e_b)`` (the reference rows of
    :func:`robot.model.constraints._closure_gamma`).
    """
    nv = J.shape[1]
    # column-major rotations: x axis entries 0..2, y axis 3..5, z axis 6..8
    zx, zy, zz = placements[fa, 6], placements[fa, 7], placements[fa, 8]
    _, _, _, oax, oay, oaz = _spatial_velocity(J, mask_a, v)
    _, _, _, obx, oby, obz = _spatial_velocity(J, mask_b, v)
    _, _, _, lax, lay, laz = _spatial_velocity(dJ, mask_a, v)
    _, _, _, lbx, lby, lbz = _spatial_velocity(dJ, mask_b, v)
    zdx, zdy, zdz = _cross(oax, oay, oaz, zx, zy, zz)  # d z_a / dt
    for k in range(2):
        ex, ey, ez = placements[fb, 3 * k], placements[fb, 3 * k + 1], placements[fb, 3 * k + 2]
        nx, ny, nz = _cross(zx, zy, zz, ex, ey, ez)
        edx, edy, edz = _cross(obx, oby, obz, ex, ey, ez)  # d e_b / dt
        p1x, p1y, p1z = _cross(zdx, zdy, zdz, ex, ey, ez)
        p2x, p2y, p2z = _cross(zx, zy, zz, edx, edy, edz)
        ndx, ndy, ndz = p1x + p2x, p1y + p2y, p1z + p2z
        r = row + k
        rate = 0.0
        for c in range(nv):
            entry = 0.0
            if mask_a[c]:
                entry += nx * J[3, c] + ny * J[4, c] + nz * J[5, c]
            if mask_b[c]:
                entry -= nx * J[3, c] + ny * J[4, c] + nz * J[5, c]
            phi_q[r, c] = entry
            rate += entry * v[c]
        phi = zx * ex + zy * ey + zz * ez
        bias = nx * (lax - lbx) + ny * (lay - lby) + nz * (laz - lbz) + ndx * (oax - obx) + ndy * (oay - oby) + ndz * (oaz - obz)
        drift[r] = two_alpha * rate + beta_squared * phi + bias


@jit
def closure_drift(
    placements, J, dJ, masks, frames_a, frames_b, closure_rows, q, v, drive, actuator_q, actuator_v, two_alpha, beta_squared, phi_q, drift
):
    """Rows of ``Phi_q`` and Pinocchio's ``drift`` for the closures then the drivers (module docstring).

    Closure i owns rows ``closure_rows[i] .. closure_rows[i + 1] - 1``: 3 (spherical:
    ``p_a - p_b``) or 5 (revolute: then the two axis rows, :func:`_axis_rows`);
    the drivers follow from ``closure_rows[-1]``. ``masks`` rows 2i, 2i+1 are the
    supports of ``frames_a[i]``, ``frames_b[i]``; ``drive`` = [s, sd, sdd] (3 m
    values for m actuators). ``phi_q``'s driving rows (constant unit rows) are not
    touched; its closure rows are overwritten.
    """
    for i in range(frames_a.shape[0]):
        fa, fb, row = frames_a[i], frames_b[i], closure_rows[i]
        _point_rows(placements, J, dJ, masks[2 * i], masks[2 * i + 1], fa, fb, v, two_alpha, beta_squared, phi_q, drift, row)
        if closure_rows[i + 1] - row == 5:
            _axis_rows(placements, J, dJ, masks[2 * i], masks[2 * i + 1], fa, fb, v, two_alpha, beta_squared, phi_q, drift, row + 3)
    m = actuator_q.shape[0]
    first = closure_rows[frames_a.shape[0]]
    for k in range(m):
        phi = q[actuator_q[k]] - drive[k]
        rate = v[actuator_v[k]] - drive[m + k]
        drift[first + k] = two_alpha * rate + beta_squared * phi - drive[2 * m + k]


@jit
def add_wrench(placements, J, mask_row, frame, wrench, tau):
    """tau += J^T w for a wrench ``w = (f, m)`` at frame ``frame``'s origin (world axes, moment about it)."""
    fx, fy, fz = wrench[0], wrench[1], wrench[2]
    if fx == 0.0 and fy == 0.0 and fz == 0.0 and wrench[3] == 0.0 and wrench[4] == 0.0 and wrench[5] == 0.0:
        return
    px, py, pz = placements[frame, 9], placements[frame, 10], placements[frame, 11]
    # the same wrench about the world origin: moment m + p x f
    mx = wrench[3] + py * fz - pz * fy
    my = wrench[4] + pz * fx - px * fz
    mz = wrench[5] + px * fy - py * fx
    for c in range(J.shape[1]):
        if mask_row[c]:
            tau[c] += J[0, c] * fx + J[1, c] * fy + J[2, c] * fz + J[3, c] * mx + J[4, c] * my + J[5, c] * mz


# site_twists and add_site_wrenches: the site-by-site path (a law with no compiled kernel, e.g. a user's friction law)
@jit(exports=("void(f8[:, ::1], f8[::1, :], i8[:, ::1], i8, i8, f8[::1], f8[:, ::1])",))
def site_twists(placements, J, masks, frame_outer, frame_inner, v, twists):
    """twists[0], twists[1] = LWA twists of the outer and inner element frames (``masks`` rows 0, 1)."""
    point_velocity(placements, J, masks[0], frame_outer, v, twists[0])
    point_velocity(placements, J, masks[1], frame_inner, v, twists[1])


@jit(exports=("void(f8[:, ::1], f8[::1, :], i8[:, ::1], i8, i8, f8[::1], i8, i8, f8[::1])",))
def add_site_wrenches(placements, J, masks, frame_outer, frame_inner, out, wrench_outer, wrench_inner, tau):
    """tau += J^T w of a clearance joint's two wrenches, at offsets ``wrench_outer``/``wrench_inner`` of its law's ``out``."""
    add_wrench(placements, J, masks[0], frame_outer, out[wrench_outer : wrench_outer + 6], tau)
    add_wrench(placements, J, masks[1], frame_inner, out[wrench_inner : wrench_inner + 6], tau)


@jit
def write_powers(multipliers, first_driving_row, v, actuator_v, tau, out, offset):
    """out[offset] = actuator power ``sum_k lambda_pin_k v_k`` (driving rows), out[offset + 1] = contact power ``tau . v``."""
    power = 0.0
    for k in range(actuator_v.shape[0]):
        power += multipliers[first_driving_row + k] * v[actuator_v[k]]
    out[offset] = power
    power = 0.0
    for c in range(v.shape[0]):
        power += tau[c] * v[c]
    out[offset + 1] = power


@jit(exports=("f8(f8[:, ::1], i8[::1], i8[::1], i8[::1], f8[::1], f8[::1], i8[::1])",))
def largest_residual(placements, frames_a, frames_b, closure_rows, q, drive, actuator_q):
    """max |Phi| over the closures (``p_a - p_b``; a revolute closure's ``z_a . x_b``, ``z_a . y_b``)
    and the drivers (``q_k - s_k``); NaN if any is NaN."""
    worst = 0.0
    for i in range(frames_a.shape[0]):
        fa, fb = frames_a[i], frames_b[i]
        for k in range(9, 12):
            size = abs(placements[fa, k] - placements[fb, k])
            if size != size:
                return size
            worst = max(worst, size)
        if closure_rows[i + 1] - closure_rows[i] == 5:
            for k in range(2):
                size = abs(placements[fa, 6] * placements[fb, 3 * k] + placements[fa, 7] * placements[fb, 3 * k + 1] + placements[fa, 8] * placements[fb, 3 * k + 2])
                if size != size:
                    return size
                worst = max(worst, size)
    for k in range(actuator_q.shape[0]):
        size = abs(q[actuator_q[k]] - drive[k])
        if size != size:
            return size
        worst = max(worst, size)
    return worst


@jit(exports=("void(f8[:, ::1], f8, f8[::1])",))
def power_series(coefficients, x, out):
    """out[j] = sum_k coefficients[k, j] x^k (Horner's rule), for every j of ``out``.

    ``coefficients`` must have at least ``out.shape[0]`` columns (not checked here: the
    compiled code has no bounds checks; ``check_drive_size`` checks the drive once).
    """
    n = coefficients.shape[0]
    for j in range(out.shape[0]):
        value = coefficients[n - 1, j]
        for k in range(n - 2, -1, -1):
            value = value * x + coefficients[k, j]
        out[j] = value


#: the compiled joint types' kernels and the ids the compiled code knows them by (each type's
#: ``KERNEL_ID``). numba caches a compiled function on disk only if no argument is itself a compiled
#: function, and a kernel passed as an argument costs ~7 us of dispatch a call: so the law is chosen
#: by an integer inside compiled code. A type without a branch in law_kernel (KERNEL_ID None, e.g.
#: defined outside clearance_contact) is evaluated through its ``evaluate``.
SPHERICAL_LAW, REVOLUTE_LAW = SphericalClearanceJoint.KERNEL_ID, RevoluteClearanceJoint.KERNEL_ID
TRANSLATIONAL_LAW = TranslationalClearanceJoint.KERNEL_ID  # spatial and planar: the kernel reads its corner count
LAW_IDS = {SphericalClearanceJoint.kernel: SPHERICAL_LAW, RevoluteClearanceJoint.kernel: REVOLUTE_LAW, TranslationalClearanceJoint.kernel: TRANSLATIONAL_LAW}


#: status of :func:`law_kernel` for a law id it does not know (nothing written)
STATUS_UNKNOWN_LAW = 15


@jit
def law_kernel(law_id, parameters, outer_rotation, outer_position, outer_twist, inner_rotation, inner_position, inner_twist, onset, out):
    """The kernel of law ``law_id`` (:data:`LAW_IDS`); returns its status (:data:`STATUS_UNKNOWN_LAW` for another id)."""
    if law_id == SPHERICAL_LAW:
        return spherical_kernel(parameters, outer_rotation, outer_position, outer_twist, inner_rotation, inner_position, inner_twist, onset, out)
    if law_id == REVOLUTE_LAW:
        return revolute_kernel(parameters, outer_rotation, outer_position, outer_twist, inner_rotation, inner_position, inner_twist, onset, out)
    if law_id == TRANSLATIONAL_LAW:
        return translational_kernel(parameters, outer_rotation, outer_position, outer_twist, inner_rotation, inner_position, inner_twist, onset, out)
    return STATUS_UNKNOWN_LAW


#: columns of the site table of :func:`all_sites` (one row per clearance joint)
(
    SITE_LAW, SITE_OUTER, SITE_INNER, SITE_FIRST, SITE_LAST, SITE_PARAMETERS, SITE_PARAMETERS_END,
    SITE_OUT, SITE_OUT_END, SITE_WRENCH_OUTER, SITE_WRENCH_INNER,
) = range(11)  # fmt: skip
SITE_COLUMNS = 11


@jit
def all_sites(placements, J, v, onset_rates, tau, table, masks, parameters, outputs, twists):
    """Evaluate every clearance joint of a mechanism and add ``J^T w`` to ``tau`` (one compiled call).

    ``table`` (n_sites x :data:`SITE_COLUMNS`, int64): per joint its law id,
    element frames, candidate range, the ranges of its kernel parameters in
    ``parameters`` and of its law output in ``outputs`` (flat float arrays of all
    joints), and its wrenches' offsets in that output; ``masks`` (n_sites, 2, nv)
    the frames' supports; ``twists`` (n_sites, 2, 6) receives their twists.
    Returns 0, or ``16 * (index + 1) + status`` for the first joint whose law
    returned a nonzero status (``tau`` then holds the joints before it).
    """
    for i in range(table.shape[0]):
        outer, inner = table[i, SITE_OUTER], table[i, SITE_INNER]
        out = outputs[table[i, SITE_OUT] : table[i, SITE_OUT_END]]
        site_twists(placements, J, masks[i], outer, inner, v, twists[i])
        status = law_kernel(
            table[i, SITE_LAW],
            parameters[table[i, SITE_PARAMETERS] : table[i, SITE_PARAMETERS_END]],
            placements[outer, 0:9].reshape((3, 3)).T,
            placements[outer, 9:12],
            twists[i, 0],
            placements[inner, 0:9].reshape((3, 3)).T,
            placements[inner, 9:12],
            twists[i, 1],
            onset_rates[table[i, SITE_FIRST] : table[i, SITE_LAST]],
            out,
        )
        if status != 0:
            return 16 * (i + 1) + status
        add_site_wrenches(placements, J, masks[i], outer, inner, out, table[i, SITE_WRENCH_OUTER], table[i, SITE_WRENCH_INNER], tau)
    return 0


#: slots of the packed arrays of one compiled right-hand side (:func:`pack`, ``CompiledTerms``): int64 ...
(
    FRAMES_A, FRAMES_B, CLOSURE_ROWS, ACTUATOR_Q, ACTUATOR_V, CLOSURE_MASKS, SITE_TABLE, SITE_MASKS, PROBE_GATHER,
) = range(9)  # fmt: skip
#: ... then float64 (``GAINS`` = [2 alpha, beta^2]; ``DRIVE`` = [s, sd, sdd] of the driving rows, empty without)
DRIFT, TAU, GAINS, DRIVE, LAW_PARAMETERS, LAW_OUTPUTS, SITE_TWISTS = range(9, 16)
#: the number of slots: those below ``DRIFT`` are int64, the others float64
N_SLOTS = SITE_TWISTS + 1


def pack(arrays: Mapping[int, ArrayLike]) -> tuple[np.ndarray, np.ndarray, dict[int, np.ndarray]]:
    """``(indices, work, views)``: the arrays ``{slot: array}`` (at most 3-D) copied into one int64 and one float64 buffer.

    Why: numba unboxes every array argument of a compiled call (~0.1 us each), so
    the fused kernels below take these two buffers instead of some twenty arrays.
    ``arrays`` has one entry per slot constant above (``ValueError`` otherwise);
    a slot below ``DRIFT`` is converted to int64, the others to float64.
    ``indices`` starts with a header of 4 int64 per slot, in slot order: the slot's
    offset in its buffer and its shape padded with 1s; the int64 data follow the
    header. ``views[slot]`` is a view of its buffer shaped as the slot's array (the
    caller keeps them: writing one writes what the kernels read, and the other way round).
    """
    if sorted(arrays) != list(range(N_SLOTS)):
        missing, unknown = sorted(set(range(N_SLOTS)) - set(arrays)), sorted(set(arrays) - set(range(N_SLOTS)))
        raise ValueError(f"pack needs one array per slot 0..{N_SLOTS - 1}; missing slots {missing}, unknown slots {unknown}")
    slots = [np.asarray(arrays[slot], dtype=np.int64 if slot < DRIFT else np.float64) for slot in range(N_SLOTS)]
    if any(array.ndim > 3 for array in slots):
        raise ValueError(f"pack takes arrays of at most 3 dimensions; got shapes {[array.shape for array in slots]}")
    header = 4 * N_SLOTS
    indices = np.zeros(header + sum(array.size for array in slots[:DRIFT]), dtype=np.int64)
    work = np.zeros(sum(array.size for array in slots[DRIFT:]))
    views, offsets = {}, [header, 0]
    for slot, array in enumerate(slots):
        buffer, kind = (indices, 0) if slot < DRIFT else (work, 1)
        start = offsets[kind]
        indices[4 * slot : 4 * slot + 4] = [start, *array.shape, *(1,) * (3 - array.ndim)]
        view = buffer[start : start + array.size].reshape(array.shape)
        view[...] = array
        views[slot] = view
        offsets[kind] += array.size
    return indices, work, views


@jit
def _flat(buffer, indices, slot):
    """Slot ``slot`` of a packed buffer (:func:`pack`), flat."""
    start = indices[4 * slot]
    return buffer[start : start + indices[4 * slot + 1] * indices[4 * slot + 2] * indices[4 * slot + 3]]


@jit
def _matrix(buffer, indices, slot):
    return _flat(buffer, indices, slot).reshape((indices[4 * slot + 1], indices[4 * slot + 2]))


@jit
def _cube(buffer, indices, slot):
    return _flat(buffer, indices, slot).reshape((indices[4 * slot + 1], indices[4 * slot + 2], indices[4 * slot + 3]))


@jit(exports=("i8(f8[::1], i8[::1], f8[:, ::1], f8[::1, :], f8[::1, :], f8[::1], f8[::1], f8[:, ::1], f8, f8[::1], f8[:, ::1])",))
def rhs_terms(work, indices, placements, J, dJ, q, v, drive_coefficients, x, onset_rates, phi_q):
    """The compiled terms of one right-hand side before its KKT solve, in one call (packed arrays, :func:`pack`).

    The ``DRIVE`` slot from the drive's polynomial (:func:`power_series`,
    ``DriveTable.polynomial``), :func:`closure_drift` (``phi_q``'s closure rows and
    the ``DRIFT`` slot), then ``TAU = 0`` and, for the sites of the ``SITE_TABLE``
    slot (none when the laws are evaluated site by site), :func:`all_sites`, whose code it returns.
    """
    gains = _flat(work, indices, GAINS)
    drive = _flat(work, indices, DRIVE)
    power_series(drive_coefficients, x, drive)
    closure_drift(
        placements, J, dJ, _matrix(indices, indices, CLOSURE_MASKS), _flat(indices, indices, FRAMES_A), _flat(indices, indices, FRAMES_B),
        _flat(indices, indices, CLOSURE_ROWS), q, v, drive, _flat(indices, indices, ACTUATOR_Q), _flat(indices, indices, ACTUATOR_V),
        gains[0], gains[1], phi_q, _flat(work, indices, DRIFT),
    )  # fmt: skip
    tau = _flat(work, indices, TAU)
    for c in range(tau.shape[0]):
        tau[c] = 0.0
    return _packed_sites(work, indices, placements, J, v, onset_rates, tau)


@jit
def _packed_sites(work, indices, placements, J, v, onset_rates, tau):
    """:func:`all_sites` on the packed arrays."""
    return all_sites(
        placements, J, v, onset_rates, tau, _matrix(indices, indices, SITE_TABLE), _cube(indices, indices, SITE_MASKS),
        _flat(work, indices, LAW_PARAMETERS), _flat(work, indices, LAW_OUTPUTS), _cube(work, indices, SITE_TWISTS),
    )  # fmt: skip


@jit(exports=("void(f8[::1], i8[::1], f8[::1], i8, f8[::1], f8[::1], f8[::1], f8[::1])",))
def finish_derivative(work, indices, multipliers, first_driving_row, v, qdd, configuration_rate, out):
    """``out = [q', qdd, actuator power, contact power]`` (:func:`write_powers`) after the KKT solve (one call).

    ``configuration_rate``: Pinocchio's tangent map product (nq values; eigenpy hands a
    one-value result over as 1 x 1); ``out``'s entries after the two powers are not written.
    """
    configuration_rate = configuration_rate.reshape(configuration_rate.size)
    nq, nv = configuration_rate.shape[0], v.shape[0]
    for i in range(nq):
        out[i] = configuration_rate[i]
    for i in range(nv):
        out[nq + i] = qdd[i]
    write_powers(multipliers, first_driving_row, v, _flat(indices, indices, ACTUATOR_V), _flat(work, indices, TAU), out, nq + nv)


@jit(exports=("Tuple((i8, f8))(f8[::1], i8[::1], f8[:, ::1], f8[::1, :], f8[::1], f8[::1], f8[:, ::1], f8, f8[::1], f8[::1], f8[::1], f8[::1], b1)",))
def probe_terms(
    work, indices, placements, J, q, v, drive_coefficients, x, onset_rates, penetration, penetration_rate, normal_force, residual
):
    """Every clearance joint's laws (:func:`all_sites`, on the packed arrays) with each candidate's penetration,
    its rate and normal force gathered into the three arrays (``PROBE_GATHER``: per candidate the indices of the
    three in ``LAW_OUTPUTS``), and, if ``residual``, :func:`largest_residual` (else NaN; the drive as in
    :func:`rhs_terms`), in one call: ``(code, max |Phi|)``; with ``code != 0`` (:func:`all_sites`' code) the three
    arrays are not written."""
    worst = np.nan
    if residual:
        drive = _flat(work, indices, DRIVE)
        power_series(drive_coefficients, x, drive)
        worst = largest_residual(
            placements, _flat(indices, indices, FRAMES_A), _flat(indices, indices, FRAMES_B), _flat(indices, indices, CLOSURE_ROWS),
            q, drive, _flat(indices, indices, ACTUATOR_Q),
        )  # fmt: skip
    code = _packed_sites(work, indices, placements, J, v, onset_rates, _flat(work, indices, TAU))
    if code != 0:
        return code, worst
    outputs, gather = _flat(work, indices, LAW_OUTPUTS), _matrix(indices, indices, PROBE_GATHER)
    for j in range(gather.shape[0]):
        penetration[j] = outputs[gather[j, 0]]
        penetration_rate[j] = outputs[gather[j, 1]]
        normal_force[j] = outputs[gather[j, 2]]
    return code, worst
