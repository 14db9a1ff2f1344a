"""Constraint equations Phi(q, t) = 0, their Jacobian Phi_q and acceleration term gamma.

Seed paper eqs (18)-(23): universal, prismatic, revolute and spherical joint
constraints, and the driving constraints; here the universal, prismatic and
ideal revolute joints are joints of Pinocchio's tree (they hold by
construction), so the constraint set holds only

* **closures** (paper eq. (21), spherical; a revolute closure adds eq. (20)):
  spherical  ``Phi = p_a - p_b``  (3 rows, world axes);
  revolute   additionally ``z_a . x_b = 0``, ``z_a . y_b = 0`` (axes parallel);
* **driving constraints** (paper eq. (22)): ``Phi_k = q_k - s_k(t)`` for each
  actuated joint k (its coordinate is the actuator length);
* optionally **centring constraints** of clearance sites, used only to assemble
  the initial state (ball centred in its socket, journal axis on the bearing axis,
  with an optional bearing misalignment).

Velocity and acceleration (paper eq. (24)):
``Phi_q qd = -Phi_t`` and ``Phi_q qdd = gamma``, with
``gamma = -(d/dt Phi_q) qd - Phi_tt`` computed from Pinocchio's classical
frame accelerations at zero joint acceleration. Baumgarte stabilisation
(paper eq. (24), ref. 35) replaces ``gamma`` by
``gamma - 2 alpha Phid - beta^2 Phi``.

Pinocchio supplies kinematics and frame Jacobians (``LOCAL_WORLD_ALIGNED``:
linear velocity of the frame origin and angular velocity, in world axes).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from .mechanism import Closure, Mechanism

LWA = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED


@dataclass(frozen=True)
class ClosureRows:
    """A closure with its row offset in Phi, and an optional rotation offset on frame b."""

    closure: Closure
    row: int
    rotation_offset_b: np.ndarray | None = None


@dataclass(frozen=True, eq=False)
class ConstraintSet:
    """Which constraint equations are imposed: closures, drivers, centring of clearance sites.

    Rows: closures first (in mechanism order), then the centring constraints, then
    one driving row per actuator when ``driven``.
    """

    mechanism: Mechanism
    closures: tuple[ClosureRows, ...]
    driven: bool

    @property
    def n_closure_rows(self) -> int:
        return sum(c.closure.n_equations for c in self.closures)

    @property
    def n_rows(self) -> int:
        return self.n_closure_rows + (self.mechanism.n_actuators if self.driven else 0)

    @property
    def driving_rows(self) -> slice:
        return slice(self.n_closure_rows, self.n_rows)


def constraint_set(
    mechanism: Mechanism,
    *,
    driven: bool = True,
    centre_clearance: bool = False,
    misalignment: dict[str, np.ndarray] | None = None,
) -> ConstraintSet:
    """The constraints of ``mechanism``.

    ``centre_clearance`` adds, for every clearance site, the equations of the
    ideal joint it replaces (used for the initial assembly). ``misalignment``
    maps a revolute site name to a rotation applied to its inner element frame
    in those centring equations, so the assembled bearing axis is the journal axis
    rotated by it.
    """
    rows = []
    offset = 0
    for closure in mechanism.closures:
        rows.append(ClosureRows(closure, offset))
        offset += closure.n_equations
    if centre_clearance:
        misalignment = misalignment or {}
        for site in mechanism.clearance_sites:
            closure = Closure(site.name, site.kind, site.outer_frame, site.inner_frame)
            rows.append(ClosureRows(closure, offset, misalignment.get(site.name)))
            offset += closure.n_equations
    return ConstraintSet(mechanism, tuple(rows), driven)


def _frame_b_rotation(data: pin.Data, rows: ClosureRows) -> np.ndarray:
    rotation = data.oMf[rows.closure.frame_b].rotation
    return rotation if rows.rotation_offset_b is None else rotation @ rows.rotation_offset_b


def residual(constraints: ConstraintSet, data: pin.Data, q: np.ndarray, drive: np.ndarray | None) -> np.ndarray:
    """Phi(q, t). Requires ``framesForwardKinematics`` (or forwardKinematics + updateFramePlacements) at q.

    ``drive`` holds the prescribed actuator coordinates s(t) (ignored if not driven).
    """
    phi = np.empty(constraints.n_rows)
    for rows in constraints.closures:
        a, b = rows.closure.frame_a, rows.closure.frame_b
        r = rows.row
        phi[r : r + 3] = data.oMf[a].translation - data.oMf[b].translation
        if rows.closure.kind == "revolute":
            z_a = data.oMf[a].rotation[:, 2]
            rotation_b = _frame_b_rotation(data, rows)
            phi[r + 3] = z_a @ rotation_b[:, 0]
            phi[r + 4] = z_a @ rotation_b[:, 1]
    if constraints.driven:
        phi[constraints.driving_rows] = q[constraints.mechanism.actuator_q_index] - drive
    return phi


def jacobian(constraints: ConstraintSet, model: pin.Model, data: pin.Data) -> np.ndarray:
    """Phi_q (n_rows x nv). Requires ``computeJointJacobians`` and ``updateFramePlacements`` at q."""
    mechanism = constraints.mechanism
    phi_q = np.zeros((constraints.n_rows, model.nv))
    for rows in constraints.closures:
        a, b = rows.closure.frame_a, rows.closure.frame_b
        r = rows.row
        jac_a = pin.getFrameJacobian(model, data, a, LWA)
        jac_b = pin.getFrameJacobian(model, data, b, LWA)
        phi_q[r : r + 3] = jac_a[:3] - jac_b[:3]
        if rows.closure.kind == "revolute":
            z_a = data.oMf[a].rotation[:, 2]
            rotation_b = _frame_b_rotation(data, rows)
            relative = jac_a[3:] - jac_b[3:]
            phi_q[r + 3] = np.cross(z_a, rotation_b[:, 0]) @ relative
            phi_q[r + 4] = np.cross(z_a, rotation_b[:, 1]) @ relative
    if constraints.driven:
        phi_q[np.arange(constraints.driving_rows.start, constraints.n_rows), mechanism.actuator_v_index] = 1.0
    return phi_q


def gamma(
    constraints: ConstraintSet,
    model: pin.Model,
    data: pin.Data,
    drive_acceleration: np.ndarray | None,
) -> np.ndarray:
    """gamma = -(d/dt Phi_q) qd - Phi_tt, the right-hand side of Phi_q qdd = gamma.

    Requires ``forwardKinematics(model, data, q, v, 0)`` and ``updateFramePlacements``:
    the classical frame accelerations are then the velocity-product terms.
    """
    out = np.empty(constraints.n_rows)
    for rows in constraints.closures:
        a, b = rows.closure.frame_a, rows.closure.frame_b
        r = rows.row
        acc_a = pin.getFrameClassicalAcceleration(model, data, a, LWA)
        acc_b = pin.getFrameClassicalAcceleration(model, data, b, LWA)
        out[r : r + 3] = -(acc_a.linear - acc_b.linear)
        if rows.closure.kind == "revolute":
            vel_a = pin.getFrameVelocity(model, data, a, LWA).angular
            vel_b = pin.getFrameVelocity(model, data, b, LWA).angular
            z_a = data.oMf[a].rotation[:, 2]
            rotation_b = _frame_b_rotation(data, rows)
            d_omega = vel_a - vel_b
            d_alpha = acc_a.angular - acc_b.angular
            z_a_dot = np.cross(vel_a, z_a)
            for k in (0, 1):
                axis_b = rotation_b[:, k]
                axis_b_dot = np.cross(vel_b, axis_b)
                cross = np.cross(z_a, axis_b)
                cross_dot = np.cross(z_a_dot, axis_b) + np.cross(z_a, axis_b_dot)
                out[r + 3 + k] = -(d_alpha @ cross + d_omega @ cross_dot)
    if constraints.driven:
        out[constraints.driving_rows] = drive_acceleration
    return out


def velocity_rhs(constraints: ConstraintSet, drive_rate: np.ndarray | None) -> np.ndarray:
    """-Phi_t: the right-hand side of Phi_q qd = -Phi_t (only drivers depend on t)."""
    out = np.zeros(constraints.n_rows)
    if constraints.driven:
        out[constraints.driving_rows] = drive_rate
    return out
