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
  with an optional bearing misalignment; for a prismatic site, the ideal prismatic
  joint: slider on the guide axis, ``x_a . (p_a - p_b) = y_a . (p_a - p_b) = 0``, and not
  rotated, ``z_a . x_b = z_a . y_b = x_a . y_b = 0``; free along the axis), or
  their **offset** form that places
  the inner element at a given pose relative to the outer one (the resting
  state, :mod:`robot.model.resting_state`): the point ``p_a + R_a d`` of frame a
  (``d`` in frame a's axes) coincides with the origin of frame b,
  ``Phi = p_a + R_a d - p_b``; its Jacobian rows use the velocity of that point,
  ``v_a + w_a x (R_a d)``, and its gamma the classical acceleration
  ``a_a + alpha_a x r + w_a x (w_a x r)``, ``r = R_a d``.

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
from functools import cached_property

import numpy as np
import pinocchio as pin

from robot.model.mechanism import Closure, Mechanism
from robot.model.pinocchio_arrays import constraints_jacobian, frame_jacobian

LWA = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED


@dataclass(frozen=True)
class ClosureRows:
    """A closure with its row offset in Phi, an optional rotation offset on frame b and an
    optional translation offset of frame a's point (frame a's axes, module docstring)."""

    closure: Closure
    row: int
    rotation_offset_b: np.ndarray | None = None
    translation_offset_a: np.ndarray | None = None


@dataclass(frozen=True, eq=False)
class ConstraintSet:
    """Which constraint equations are imposed: closures, drivers, centring of clearance sites.

    Rows: closures first (in mechanism order), then the centring constraints, then
    one driving row per actuator when ``driven``.
    """

    mechanism: Mechanism
    closures: tuple[ClosureRows, ...]
    driven: bool

    @cached_property
    def n_closure_rows(self) -> int:
        return sum(c.closure.n_equations for c in self.closures)

    @cached_property
    def n_rows(self) -> int:
        return self.n_closure_rows + (self.mechanism.n_actuators if self.driven else 0)

    @property
    def driving_rows(self) -> slice:
        return slice(self.n_closure_rows, self.n_rows)

    @cached_property
    def row_labels(self) -> tuple[str, ...]:
        """One name per row of Phi: ``CLOSURE:x|y|z`` (world axes), ``CLOSURE:rot_x|rot_y`` (the revolute
        axis rows along frame b's x and y axes), ``JOINT:drive``."""
        labels = []
        for rows in self.closures:
            components = ("x", "y", "z", "rot_x", "rot_y")[: rows.closure.n_equations]
            if rows.closure.kind == "prismatic":
                components = ("x", "y", "rot_x", "rot_y", "rot_z")
            labels += [f"{rows.closure.name}:{component}" for component in components]
        if self.driven:
            labels += [f"{joint}:drive" for joint in self.mechanism.actuated_joints]
        return tuple(labels)


def constraint_set(
    mechanism: Mechanism,
    *,
    driven: bool = True,
    centre_clearance: bool = False,
    misalignment: dict[str, np.ndarray] | None = None,
    offsets: dict[str, np.ndarray] | None = None,
) -> ConstraintSet:
    """The constraints of ``mechanism``.

    ``centre_clearance`` adds, for every clearance site, the equations of the
    ideal joint it replaces (used for the initial assembly). ``misalignment``
    maps a revolute site name to a rotation applied to its inner element frame
    in those centring equations, so the assembled bearing axis is the journal axis
    rotated by it. ``offsets`` maps a site name to the position (outer element
    frame axes, m) of the inner element's origin relative to the outer one's: the
    centring equations then place the inner element there (module docstring).
    """
    rows = []
    offset = 0
    for closure in mechanism.closures:
        rows.append(ClosureRows(closure, offset))
        offset += closure.n_equations
    if centre_clearance:
        misalignment, offsets = misalignment or {}, offsets or {}
        for site in mechanism.clearance_sites:
            closure = Closure(site.name, site.kind, site.outer_frame, site.inner_frame)
            translation = offsets.get(site.name)
            translation = None if translation is None else np.asarray(translation, dtype=float).reshape(3)
            rows.append(ClosureRows(closure, offset, misalignment.get(site.name), translation))
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
        _closure_residual(constraints.mechanism.model, data, rows, phi)
    if constraints.driven:
        phi[constraints.driving_rows] = q[constraints.mechanism.actuator_q_index] - drive
    return phi


def jacobian(constraints: ConstraintSet, model: pin.Model, data: pin.Data) -> np.ndarray:
    """Phi_q (n_rows x nv). Requires ``computeJointJacobians`` and ``updateFramePlacements`` at q."""
    mechanism = constraints.mechanism
    phi_q = np.zeros((constraints.n_rows, model.nv))
    for rows in constraints.closures:
        _closure_jacobian(model, data, rows, phi_q)
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
        _closure_gamma(model, data, rows, out)
    if constraints.driven:
        out[constraints.driving_rows] = drive_acceleration
    return out


def velocity_rhs(constraints: ConstraintSet, drive_rate: np.ndarray | None) -> np.ndarray:
    """-Phi_t: the right-hand side of Phi_q qd = -Phi_t (only drivers depend on t)."""
    out = np.zeros(constraints.n_rows)
    if constraints.driven:
        out[constraints.driving_rows] = drive_rate
    return out


class ConstraintKernel:
    """Phi, Phi_q and gamma of one :class:`ConstraintSet` on one ``pin.Data``, for the hot path.

    The same equations as :func:`residual`, :func:`jacobian` and :func:`gamma`
    (``tests/test_integrators.py`` checks them equal), organised for speed: the
    frame translations are numpy *views* into the Pinocchio ``Data`` bound once
    (they follow every kinematics update), the spherical closures' Jacobian rows
    come from one ``getConstraintsJacobian`` call on ``CONTACT_3D`` /
    ``LOCAL_WORLD_ALIGNED`` constraint models (the same rows ``p_a - p_b`` in world
    axes), 3-vectors are handled as Python floats, and ``Phi_q`` is a buffer whose
    constant driving rows are written once. Revolute closures (and centring rows)
    use the reference code row by row.

    Requires, at (q, v): ``computeAllTerms`` (or ``forwardKinematics(q, v, 0)`` +
    ``computeJointJacobians``) and ``updateFramePlacements`` on ``data``.
    """

    def __init__(self, constraints: ConstraintSet, data: pin.Data):
        mechanism = constraints.mechanism
        model = mechanism.model
        self.constraints = constraints
        self.model = model
        self.data = data
        self.n_rows = constraints.n_rows
        self.n_closure_rows = constraints.n_closure_rows
        self.driven = constraints.driven
        self.actuator_q = np.asarray(mechanism.actuator_q_index, dtype=int)
        self._spherical = []  # (frame_a, frame_b, translation view a, translation view b)
        self._others = []  # ClosureRows handled by the reference code
        rows = []
        self._models = pin.StdVec_RigidConstraintModel()
        self._datas = pin.StdVec_RigidConstraintData()
        for closure_rows in constraints.closures:
            closure = closure_rows.closure
            if closure.kind == "spherical" and closure_rows.translation_offset_a is None:
                fa, fb = model.frames[closure.frame_a], model.frames[closure.frame_b]
                self._spherical.append(
                    (closure.frame_a, closure.frame_b, data.oMf[closure.frame_a].translation, data.oMf[closure.frame_b].translation)
                )
                self._models.append(
                    pin.RigidConstraintModel(pin.ContactType.CONTACT_3D, model, fa.parentJoint, fa.placement, fb.parentJoint, fb.placement, LWA)
                )
                rows.extend(range(closure_rows.row, closure_rows.row + 3))
            else:
                self._others.append(closure_rows)
        for constraint_model in self._models:
            self._datas.append(constraint_model.createData())
        self._calcs = [(m.calc, d) for m, d in zip(self._models, self._datas)]
        self._rows = np.array(rows, dtype=int)
        # the spherical rows usually come first and contiguous: a slice is cheaper than fancy indexing
        n_sph = len(rows)
        self._sph_slice = slice(0, n_sph) if rows == list(range(n_sph)) else None
        self.phi_q = np.zeros((self.n_rows, model.nv))
        if self.driven:
            self.phi_q[np.arange(constraints.driving_rows.start, self.n_rows), mechanism.actuator_v_index] = 1.0

    def residual(self, q: np.ndarray, drive: np.ndarray | None) -> np.ndarray:
        """Phi(q, t) (as :func:`residual`); needs frame placements only."""
        values = []
        for _, _, ta, tb in self._spherical:
            xa, ya, za = ta.tolist()
            xb, yb, zb = tb.tolist()
            values += (xa - xb, ya - yb, za - zb)
        return self._assemble(values, q[self.actuator_q] - drive if self.driven else None, _closure_residual)

    def update(self, q: np.ndarray, drive: np.ndarray | None, drive_acceleration: np.ndarray | None) -> tuple[np.ndarray, np.ndarray]:
        """Phi and gamma (new arrays); ``self.phi_q`` is overwritten with Phi_q."""
        model, data = self.model, self.data
        classical = pin.getFrameClassicalAcceleration
        values, accelerations = [], []
        for fa, fb, ta, tb in self._spherical:
            xa, ya, za = ta.tolist()
            xb, yb, zb = tb.tolist()
            values += (xa - xb, ya - yb, za - zb)
            # gamma = -(a_a - a_b) (classical accelerations at zero joint acceleration)
            accelerations += (classical(model, data, fb, LWA) - classical(model, data, fa, LWA)).linear.tolist()
        if self._spherical:
            for calc, constraint_data in self._calcs:
                calc(model, data, constraint_data)
            jac = constraints_jacobian(model, data, self._models, self._datas, len(self._rows))
            if self._sph_slice is not None:
                self.phi_q[self._sph_slice] = jac
            else:
                self.phi_q[self._rows] = jac
        phi = self._assemble(values, q[self.actuator_q] - drive if self.driven else None, _closure_residual)
        gam = self._assemble(accelerations, drive_acceleration if self.driven else None, _closure_gamma)
        for rows in self._others:
            _closure_jacobian(model, data, rows, self.phi_q)
        return phi, gam

    def stabilised_drift(
        self,
        q: np.ndarray,
        v: np.ndarray,
        drive: np.ndarray | None,
        drive_rate: np.ndarray | None,
        drive_acceleration: np.ndarray | None,
        two_alpha: float,
        beta_squared: float,
    ) -> np.ndarray:
        """``2 alpha Phid + beta^2 Phi - gamma`` (minus the stabilised right-hand side), ``self.phi_q`` updated.

        The Python right-hand side's form of :meth:`update` (mechanisms whose closures
        the compiled kernels of :mod:`robot.dynamics.rhs_kernels` do not have, and the
        reference of the compiled path in the tests).
        """
        phi, gam = self.update(q, drive, drive_acceleration)
        phi_dot = self.phi_q @ v
        if self.driven:
            phi_dot[self.n_closure_rows :] -= drive_rate
        return two_alpha * phi_dot + beta_squared * phi - gam

    def _assemble(self, spherical_values: list, driving: np.ndarray | None, other) -> np.ndarray:
        out = np.empty(self.n_rows)
        if self._sph_slice is not None:
            out[self._sph_slice] = spherical_values
        elif self._spherical:
            out[self._rows] = spherical_values
        for rows in self._others:
            other(self.model, self.data, rows, out)
        if driving is not None:
            out[self.n_closure_rows :] = driving
        return out


#: rotation rows (axis of frame a, axis of frame b): u_a . w_b = 0 for each pair
_ROTATION_PAIRS = {"revolute": ((2, 0), (2, 1)), "prismatic": ((2, 0), (2, 1), (0, 1))}


def _position_rows(kind: str) -> int:
    """Number of position rows: 3 (p_a - p_b, world) or, prismatic, 2 (x_a, y_a . (p_a - p_b))."""
    return 2 if kind == "prismatic" else 3


def reaction_on_b(data: pin.Data, rows: ClosureRows, multipliers: np.ndarray) -> np.ndarray:
    """The wrench ``[F, M]`` (world axes, moment about frame b's origin) the closure's rows exert on frame b.

    With ``M qdd + Phi_q^T lambda = Q`` the constraint force is ``-Phi_q^T lambda``;
    frame b enters the rows as ``-p_b`` and through ``x_b``, ``y_b`` in
    ``z_a . x_b``, ``z_a . y_b`` (d/dt = ``-w_b . (z_a x x_b)`` + terms of a), so on b:
    ``F = lambda_t``, ``M = lambda_x (z_a x x_b) + lambda_y (z_a x y_b)``.
    ``multipliers``: the full multiplier vector of the set. Requires frame placements.
    """
    r = rows.row
    force = np.array(multipliers[r : r + 3], dtype=float)
    moment = np.zeros(3)
    if rows.closure.kind == "revolute":
        z_a = data.oMf[rows.closure.frame_a].rotation[:, 2]
        rotation_b = _frame_b_rotation(data, rows)
        moment = multipliers[r + 3] * np.cross(z_a, rotation_b[:, 0]) + multipliers[r + 4] * np.cross(z_a, rotation_b[:, 1])
    return np.concatenate([force, moment])


def _offset_a(data: pin.Data, rows: ClosureRows) -> np.ndarray | None:
    """``R_a d`` (world axes) of a closure with a translation offset, else None."""
    if rows.translation_offset_a is None:
        return None
    return data.oMf[rows.closure.frame_a].rotation @ rows.translation_offset_a


def _skew(vector: np.ndarray) -> np.ndarray:
    x, y, z = vector
    return np.array([[0.0, -z, y], [z, 0.0, -x], [-y, x, 0.0]])


def _closure_residual(model: pin.Model, data: pin.Data, rows: ClosureRows, out: np.ndarray) -> None:
    """Rows of one closure in Phi (reference equations of :func:`residual`)."""
    a, b, r = rows.closure.frame_a, rows.closure.frame_b, rows.row
    kind = rows.closure.kind
    gap = data.oMf[a].translation - data.oMf[b].translation
    rotation_a = data.oMf[a].rotation
    if kind == "prismatic":
        out[r : r + 2] = rotation_a[:, :2].T @ gap
    else:
        out[r : r + 3] = gap
        lever = _offset_a(data, rows)
        if lever is not None:
            out[r : r + 3] += lever
    rotation_b = _frame_b_rotation(data, rows)
    for k, (i, j) in enumerate(_ROTATION_PAIRS.get(kind, ()), start=r + _position_rows(kind)):
        out[k] = rotation_a[:, i] @ rotation_b[:, j]


def _closure_jacobian(model: pin.Model, data: pin.Data, rows: ClosureRows, out: np.ndarray) -> None:
    """Rows of one closure in Phi_q (reference equations of :func:`jacobian`).

    d/dt (u_a . d) = u_a . (v_a - v_b) + (u_a x d) . w_a for d = p_a - p_b (prismatic);
    d/dt (u_a . w_b) = (u_a x w_b) . (w_a - w_b) for the rotation rows.
    """
    a, b, r = rows.closure.frame_a, rows.closure.frame_b, rows.row
    kind = rows.closure.kind
    jac_a = frame_jacobian(model, data, a)
    jac_b = frame_jacobian(model, data, b)
    rotation_a = data.oMf[a].rotation
    if kind == "prismatic":
        gap = data.oMf[a].translation - data.oMf[b].translation
        for k in range(2):
            axis = rotation_a[:, k]
            out[r + k] = axis @ (jac_a[:3] - jac_b[:3]) + np.cross(axis, gap) @ jac_a[3:]
    else:
        out[r : r + 3] = jac_a[:3] - jac_b[:3]
        lever = _offset_a(data, rows)
        if lever is not None:  # velocity of the point: v_a + w_a x lever = v_a - [lever]x w_a
            out[r : r + 3] -= _skew(lever) @ jac_a[3:]
    rotation_b = _frame_b_rotation(data, rows)
    relative = jac_a[3:] - jac_b[3:]
    for k, (i, j) in enumerate(_ROTATION_PAIRS.get(kind, ()), start=r + _position_rows(kind)):
        out[k] = np.cross(rotation_a[:, i], rotation_b[:, j]) @ relative


def _closure_gamma(model: pin.Model, data: pin.Data, rows: ClosureRows, out: np.ndarray) -> None:
    """Rows of one closure in gamma (reference equations of :func:`gamma`): minus the rows' second
    time derivative at zero joint acceleration (classical accelerations of the frames)."""
    a, b, r = rows.closure.frame_a, rows.closure.frame_b, rows.row
    kind = rows.closure.kind
    acc_a = pin.getFrameClassicalAcceleration(model, data, a, LWA)
    acc_b = pin.getFrameClassicalAcceleration(model, data, b, LWA)
    vel_a = pin.getFrameVelocity(model, data, a, LWA)
    vel_b = pin.getFrameVelocity(model, data, b, LWA)
    rotation_a = data.oMf[a].rotation
    if kind == "prismatic":
        # (u . d)'' = u'' . d + 2 u' . d' + u . d'',  u' = w_a x u,  u'' = alpha_a x u + w_a x u'
        gap = data.oMf[a].translation - data.oMf[b].translation
        gap_dot = vel_a.linear - vel_b.linear
        gap_ddot = acc_a.linear - acc_b.linear
        for k in range(2):
            axis = rotation_a[:, k]
            axis_dot = np.cross(vel_a.angular, axis)
            axis_ddot = np.cross(acc_a.angular, axis) + np.cross(vel_a.angular, axis_dot)
            out[r + k] = -(axis_ddot @ gap + 2.0 * axis_dot @ gap_dot + axis @ gap_ddot)
    else:
        out[r : r + 3] = -(acc_a.linear - acc_b.linear)
        lever = _offset_a(data, rows)
        if lever is not None:  # classical acceleration of the point at zero joint acceleration
            out[r : r + 3] -= np.cross(acc_a.angular, lever) + np.cross(vel_a.angular, np.cross(vel_a.angular, lever))
    pairs = _ROTATION_PAIRS.get(kind, ())
    if not pairs:
        return
    rotation_b = _frame_b_rotation(data, rows)
    d_omega = vel_a.angular - vel_b.angular
    d_alpha = acc_a.angular - acc_b.angular
    for k, (i, j) in enumerate(pairs, start=r + _position_rows(kind)):
        axis_a, axis_b = rotation_a[:, i], rotation_b[:, j]
        axis_a_dot = np.cross(vel_a.angular, axis_a)
        axis_b_dot = np.cross(vel_b.angular, axis_b)
        cross = np.cross(axis_a, axis_b)
        cross_dot = np.cross(axis_a_dot, axis_b) + np.cross(axis_a, axis_b_dot)
        out[k] = -(d_alpha @ cross + d_omega @ cross_dot)
