"""Jacobian of the state derivative, for the Newton iterations of implicit integrators.

An implicit method (BDF, Radau, CVODE, LSODA when stiff) solves each step by
Newton iterations on ``y - gamma f(t, y) = r`` with the iteration matrix
``I - gamma df/dy``. Left to itself it builds ``df/dy`` by finite differences:
one right-hand side per state coordinate (54 for the 4-UPS/RPS mechanism with
two free bodies), which was 57 % of all right-hand sides of a CVODE_BDF run of
``compound_misaligned``. The matrix only steers the iterations (the error
control of BDF, LSODA and CVODE never sees it; Radau filters its error
estimate through ``(I/h - J)``, a small effect), so it may leave out what is
not stiff; what is stiff here is the contact: ``K ~ 1e9 N/m`` on bodies of a
few kilograms.

State ``y = [q, v, W_act, W_contact]``, ``f = [T(q) v, qdd, P_act, P_contact]``
(:func:`robot.dynamics.equations.state_derivative`). Pinocchio's KKT solution of paper
eq. (24) with ``Phi_q qdd = c`` (``c = gamma - 2 alpha Phid - beta^2 Phi``)::

    qdd = P (tau_c - h) + X c,   S = Phi_q M^-1 Phi_q^T,   X = M^-1 Phi_q^T S^-1,
                                 P = M^-1 - X Phi_q M^-1

Linearised at fixed ``Phi_q``, ``M`` and ``P``, ``X`` (tangent displacement ``xi``,
``q (+) xi = integrate(q, xi)``)::

    d qdd/d xi = P (d tau_c/d xi - d(M qdd + h)/d xi) - beta^2 X Phi_q
    d qdd/d v  = P (d tau_c/d v  - d h/d v)           - 2 alpha X Phi_q

* ``d(M qdd + h)/d(xi, v)``: Pinocchio's ``computeRNEADerivatives`` at ``qdd``
  (analytic; gravity, Coriolis and the ``dM/dq qdd`` term);
* ``d tau_c/d(xi, v) = G^T (dw/d(pose, twist)) G``: the contact wrenches' own
  derivatives by forward differences of the compiled law kernels (24 inputs
  per joint in contact, ~0.5 us each), chained through the frames' LWA
  Jacobians ``G`` (:func:`robot.dynamics.jacobian_kernels.add_site_stiffness`);
* raw configuration columns: ``df/dq = (df/dxi) T^+`` with ``T = dq/dxi``
  (``pin.tangentMap``) and ``T^+ = (T^T T)^-1 T^T``, which annihilates the
  quaternions' radial direction exactly as the normalisation in ``f`` does;
* ``d(T v)/dv = T``;
* the power rows (the accumulators feed nothing back, but their Newton
  corrections enter the convergence test): contact power ``tau_c . v`` gives
  ``v^T d tau_c/d xi`` and ``tau_c^T + v^T d tau_c/d v``; actuator power
  ``lambda_pin,drive . v_act`` with ``d lambda_pin = S^-1 dc - X^T d(tau_c - M qdd - h)``
  (from ``Phi_q^T lambda_pin = M qdd + h - tau_c`` and ``X^T Phi_q^T = I``).

Left out, all of order ``|v|``, ``|omega|``, ``|lambda|`` or ``|w|`` times a
geometric factor, hence not stiff: ``d(T v)/dq``, ``d gamma/d(q, v)``, the
variation of ``Phi_q`` and of ``G`` (``d(Phi_q^T lambda)/dq``, ``dG^T/dq w``)
and the twists' change with ``q`` at fixed ``v``. ``tests/test_state_jacobian.py``
checks the stiff blocks against a central-difference Jacobian of ``f`` and the
iteration matrix's quality (the Newton contraction) at the step sizes in use.

Force elements (:mod:`robot.dynamics.forces`): loads that depend on t only
(joint and body loads, force-driven actuators) leave the blocks above
unchanged (their ``Q`` varies with q only through the Jacobians, a left-out
geometric term) and add ``Q_act`` to the actuator power row and ``Q_elements`` to
the force-work row (``d(Q . v)/dv``). Elements whose law depends on the state
(springs, dampers: ``ForceSet.state_dependent``) are not linearised here:
:func:`for_workspace` then returns None and the solver differences the
right-hand side (exact to its difference step, whatever the elements).

Applies on the compiled right-hand side with ``clearance_contact``'s own
compiled laws (every shipped scene); elsewhere :func:`for_workspace` returns
None and the solver builds its own finite-difference matrix.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from clearance_contact import ContactError

from robot.dynamics import equations as D
from robot.dynamics import jacobian_kernels as JK
from robot.dynamics import rhs_kernels as K
from robot.model.lapack import cholesky_factor, cholesky_solve



class StateJacobian:
    """``df/dy`` of :func:`robot.dynamics.equations.state_derivative` on one workspace (module docstring).

    Call ``jacobian(t, y, onset_rates, out)`` to fill ``out`` (n x n, n =
    ``dynamics.state_size``). Uses (and overwrites) the workspace's Pinocchio data, as a
    right-hand side call does. Raises ``ContactError`` if a contact law refuses
    a perturbed input (callers fall back to finite differences).
    """

    def __init__(self, dynamics: D.DynamicsModel, workspace: D.DynamicsWorkspace):
        compiled = workspace.compiled
        if not _applies(compiled):
            raise ValueError("the structured Jacobian needs the compiled right-hand side and clearance_contact's compiled laws")
        self.dynamics, self.workspace, self.compiled = dynamics, workspace, compiled
        model = dynamics.mechanism.model
        nv = model.nv
        self.dtau_dpose = np.zeros((nv, nv))
        self.dtau_dtwist = np.zeros((nv, nv))
        largest = max((site.outputs.shape[0] for site in compiled.sites), default=0)
        self.scratch = (np.zeros((12, 24)), np.zeros((12, nv)), (np.zeros((2, 3, 3)), np.zeros((2, 3)), np.zeros((2, 6)), np.zeros(largest)))
        self.law_ids = [K.LAW_IDS[site.law_kernel] for site in compiled.sites]
        self.calls = 0

    def contact_stiffness(self, t: float, onset_rates: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``(d tau_c/d xi, d tau_c/d v)`` at the state of the right-hand side last evaluated on the workspace.

        Reuses that evaluation's frame twists and law outputs (no second evaluation).
        """
        self.dtau_dpose[:] = 0.0
        self.dtau_dtwist[:] = 0.0
        compiled = self.compiled
        derivative, G, perturbed = self.scratch
        for index, (_, parameters, masks, outer, inner, candidates, twists, buffer, w_outer, w_inner) in enumerate(compiled.sites):
            status = JK.site_stiffness(
                self.law_ids[index], parameters, compiled.placements, compiled.jacobian, masks, outer, inner, onset_rates[candidates],
                twists, buffer, w_outer, w_inner, derivative, G, perturbed, self.dtau_dpose, self.dtau_dtwist,
            )  # fmt: skip
            if status != 0:
                site = self.dynamics.contacts[index].site.name
                raise ContactError(f"contact law of {site!r} refused a perturbed input (status {status}) at t={t!r}")
        return self.dtau_dpose, self.dtau_dtwist

    def __call__(self, t: float, y: np.ndarray, onset_rates: np.ndarray, out: np.ndarray) -> np.ndarray:
        dynamics, workspace = self.dynamics, self.workspace
        model, data = dynamics.mechanism.model, workspace.data
        nq, nv = model.nq, model.nv
        self.calls += 1
        # the right-hand side at (t, y) leaves Phi_q, the frame Jacobians and qdd in the data (and M,
        # which computeRNEADerivatives writes again, the same values, before it is factorised)
        qdd = D.state_derivative(dynamics, workspace, t, y, onset_rates)[nq : nq + nv]
        # the KKT system the right-hand side solved: its independent rows (robot.model.redundancy)
        rows = workspace.rows
        first = rows.n_closure_kept
        driving_multipliers = data.lambda_c[first:].copy()
        q, v = pin.normalize(model, y[:nq]), y[nq : nq + nv]
        phi_q = self.compiled.phi_q if rows.full else self.compiled.phi_q[rows.independent]
        dtau_c_dxi, dtau_c_dv = self.contact_stiffness(t, onset_rates)
        drnea_dq, drnea_dv, _ = pin.computeRNEADerivatives(model, data, q, v, qdd)
        # M^-1 [Phi_q^T, F_xi, F_v] with one Cholesky factorisation (crba filled M's upper triangle)
        factor = cholesky_factor(data.M)
        m = phi_q.shape[0]
        solved = cholesky_solve(factor, np.hstack([phi_q.T, dtau_c_dxi - drnea_dq, dtau_c_dv - drnea_dv]))
        mass_inverse_phi_t = solved[:, :m]
        # S^-1 Phi_q [M^-1 F_xi, M^-1 F_v, I]: then P F = M^-1 F - M^-1 Phi_q^T S^-1 Phi_q M^-1 F,
        # X Phi_q = M^-1 Phi_q^T S^-1 Phi_q and X^T F = S^-1 Phi_q M^-1 F
        reduced = np.linalg.solve(phi_q @ mass_inverse_phi_t, np.hstack([phi_q @ solved[:, m:], phi_q]))
        gains = dynamics.baumgarte
        lambda_by_xi = reduced[:, :nv] + gains.beta**2 * reduced[:, 2 * nv :]  # -d lambda_pin/d xi
        lambda_by_v = reduced[:, nv : 2 * nv] + 2.0 * gains.alpha * reduced[:, 2 * nv :]  # -d lambda_pin/d v
        by_xi = solved[:, m : m + nv] - mass_inverse_phi_t @ lambda_by_xi
        by_v = solved[:, m + nv :] - mass_inverse_phi_t @ lambda_by_v
        tangent = pin.tangentMap(model, q)
        tangent_inverse = np.linalg.solve(tangent.T @ tangent, tangent.T)  # T^+
        out[:] = 0.0
        out[:nq, nq : nq + nv] = tangent
        out[nq : nq + nv, :nq] = by_xi @ tangent_inverse
        out[nq : nq + nv, nq : nq + nv] = by_v
        # contact power tau_c . v
        out[nq + nv + 1, :nq] = (v @ dtau_c_dxi) @ tangent_inverse
        out[nq + nv + 1, nq : nq + nv] = self.compiled.tau + v @ dtau_c_dv
        # actuator power lambda_pin,drive . v_act
        if first < m:
            actuator_v = self.compiled.actuator_v
            rate = v[actuator_v]
            out[nq + nv, :nq] = -(rate @ lambda_by_xi[first:]) @ tangent_inverse
            out[nq + nv, nq : nq + nv] = -(rate @ lambda_by_v[first:])
            out[nq + nv, nq + actuator_v] += driving_multipliers
        forces = workspace.forces
        if forces is not None:  # time-only loads (module docstring): their powers' velocity derivatives
            out[nq + nv, nq : nq + nv] += forces.from_actuators
            out[nq + nv + 2, nq : nq + nv] = forces.from_elements
        return out


def for_workspace(dynamics: D.DynamicsModel, workspace: D.DynamicsWorkspace) -> StateJacobian | None:
    """The structured Jacobian on ``workspace``, or None where it does not apply (Python right-hand side,
    state-dependent force elements)."""
    if not _applies(workspace.compiled) or (dynamics.forces is not None and dynamics.forces.state_dependent):
        return None
    return StateJacobian(dynamics, workspace)


def _applies(compiled: D.CompiledTerms | None) -> bool:
    """The compiled right-hand side, every law a shipped compiled law (``CompiledTerms.sites_fused``)."""
    return compiled is not None and compiled.sites_fused


def finite_difference_jacobian(fun, t: float, y: np.ndarray, relative_step: float = 1e-7, base: np.ndarray | None = None) -> np.ndarray:
    """``df/dy`` by central differences of ``fun(t, y)`` (the tests' reference), or by forward
    differences from ``base = fun(t, y)`` when it is given (half the calls: the simulation's fallback)."""
    y = np.asarray(y, dtype=float)
    columns = []
    for j in range(y.shape[0]):
        step = relative_step * max(1.0, abs(y[j]))
        plus, minus = y.copy(), y.copy()
        plus[j] += step
        if base is not None:
            columns.append((np.asarray(fun(t, plus)) - base) / step)
            continue
        minus[j] -= step
        columns.append((np.asarray(fun(t, plus)) - np.asarray(fun(t, minus))) / (2.0 * step))
    return np.column_stack(columns)
