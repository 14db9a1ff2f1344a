"""Equations of motion: Lagrange multipliers, Baumgarte stabilisation, clearance contact.

Seed paper eq. (24) (MODEL-NOTES 5)::

    [ M(q)   Phi_q^T ] [ qdd    ]   [ Q(q, qd, t)                          ]
    [ Phi_q  0       ] [ lambda ] = [ gamma - 2 alpha Phid - beta^2 Phi    ]

``Q = -h(q, qd) + sum_c J_c^T w_c``: ``h`` gathers gravity and velocity terms
(Pinocchio's ``nonLinearEffects``), ``w_c`` are the clearance contact wrenches
(``clearance_contact``, about each element frame origin, world axes) mapped
through the ``LOCAL_WORLD_ALIGNED`` frame Jacobians ``J_c`` of those frames.
``Phi`` holds the closures and the five driving constraints
``q_k - s_k(t) = 0`` (``robot.constraints``); ``Phid = Phi_q qd - [0; sd]``.

Pinocchio's ``forwardDynamics(model, data, tau, J, drift)`` solves the same KKT
system in C++ with its own signs: ``M qdd + h = tau + J^T lambda_pin`` and
``J qdd = -drift``. Hence ``drift = -(gamma - 2 alpha Phid - beta^2 Phi)`` and
``lambda = -lambda_pin`` in the paper's convention.

**Driving force sign.** The driving row of actuator k is the unit row of its
prismatic coordinate (the leg length), so the actuator's generalized force is
``-lambda_k = lambda_pin_k``: ``driving_force > 0`` means the actuator pushes
(extends the leg), ``< 0`` pulls.

Everything per-run lives in :class:`DynamicsWorkspace` (Pinocchio ``Data`` and
caches); :class:`DynamicsModel` is immutable.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Protocol, Sequence

import numpy as np
import pinocchio as pin

from . import constraints as C
from .mechanism import ClearanceSite, Mechanism

LWA = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED


class Drive(Protocol):
    """Prescribed actuator coordinates: ``drive(t) -> (s, sd, sdd)``."""

    def drive(self, t: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]: ...


class ClearanceJointLaw(Protocol):
    """What the dynamics needs from a ``clearance_contact`` joint."""

    n_candidates: int

    def evaluate(self, outer_rotation, outer_position, outer_twist, inner_rotation, inner_position, inner_twist, onset_rates): ...

    def penetration(self, outer_rotation, outer_position, inner_rotation, inner_position) -> np.ndarray: ...


@dataclass(frozen=True, eq=False)
class ContactSite:
    """A clearance site of the mechanism bound to its contact law."""

    site: ClearanceSite
    law: ClearanceJointLaw
    first_candidate: int  # offset of its candidates in the global candidate list

    @property
    def candidates(self) -> slice:
        return slice(self.first_candidate, self.first_candidate + self.law.n_candidates)


@dataclass(frozen=True)
class Baumgarte:
    """Baumgarte gains: ``Phidd + 2 alpha Phid + beta^2 Phi = 0`` (paper ref. 35)."""

    alpha: float = 5.0
    beta: float = 5.0

    def __post_init__(self) -> None:
        for name in ("alpha", "beta"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value >= 0.0):
                raise ValueError(f"Baumgarte {name}={value!r} must be a finite number >= 0")


@dataclass(frozen=True, eq=False)
class DynamicsModel:
    """Mechanism + constraints + contact laws + prescribed motion + stabilisation."""

    mechanism: Mechanism
    constraints: C.ConstraintSet
    contacts: tuple[ContactSite, ...]
    drive: Drive
    baumgarte: Baumgarte = Baumgarte()
    end_effector_frame: int = -1

    @property
    def n_candidates(self) -> int:
        return sum(c.law.n_candidates for c in self.contacts)

    @property
    def nq(self) -> int:
        return self.mechanism.model.nq

    @property
    def nv(self) -> int:
        return self.mechanism.model.nv


def make_dynamics_model(
    mechanism: Mechanism,
    laws: dict[str, ClearanceJointLaw],
    drive: Drive,
    baumgarte: Baumgarte = Baumgarte(),
    end_effector_frame: str | None = None,
) -> DynamicsModel:
    """Bind every clearance site of ``mechanism`` to its law in ``laws`` (by site name)."""
    missing = [s.name for s in mechanism.clearance_sites if s.name not in laws]
    extra = [name for name in laws if name not in mechanism.clearance_names]
    if missing or extra:
        raise ValueError(f"contact laws must match the clearance sites {mechanism.clearance_names}: missing {missing}, unknown {extra}")
    contacts, offset = [], 0
    for site in mechanism.clearance_sites:
        law = laws[site.name]
        if (site.kind == "spherical") != (law.n_candidates == 1):
            raise ValueError(f"clearance site {site.name!r} is {site.kind} but its law has {law.n_candidates} candidates")
        contacts.append(ContactSite(site, law, offset))
        offset += law.n_candidates
    ee = mechanism.model.getFrameId(end_effector_frame) if end_effector_frame else len(mechanism.model.frames) - 1
    return DynamicsModel(mechanism, C.constraint_set(mechanism, driven=True), tuple(contacts), drive, baumgarte, ee)


@dataclass
class DynamicsWorkspace:
    """Per-run mutable state: Pinocchio data and counters."""

    data: pin.Data
    rhs_calls: int = 0
    rejected_stages: int = 0  # trial stages in an absurd pose (see robot.simulation)
    simple_q: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=int))
    simple_v: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=int))


def make_workspace(dynamics: DynamicsModel) -> DynamicsWorkspace:
    model = dynamics.mechanism.model
    simple_q, simple_v = [], []
    for j in range(1, model.njoints):
        if model.nqs[j] == model.nvs[j]:
            simple_q.extend(range(model.idx_qs[j], model.idx_qs[j] + model.nqs[j]))
            simple_v.extend(range(model.idx_vs[j], model.idx_vs[j] + model.nvs[j]))
    return DynamicsWorkspace(model.createData(), simple_q=np.array(simple_q, dtype=int), simple_v=np.array(simple_v, dtype=int))


def normalise_quaternions(mechanism: Mechanism, q: np.ndarray) -> np.ndarray:
    """A copy of q with every free-flyer quaternion of unit norm."""
    q = np.array(q, dtype=float)
    for iq, _ in mechanism.free_flyers:
        quat = q[iq + 3 : iq + 7]
        q[iq + 3 : iq + 7] = quat / math.sqrt(quat @ quat)
    return q


def configuration_rate(dynamics: DynamicsModel, workspace: DynamicsWorkspace, q: np.ndarray, v: np.ndarray) -> np.ndarray:
    """dq/dt from the generalized velocity v (free-flyer: local twist to position and quaternion rates).

    Free-flyer (Pinocchio): position rate ``R v_lin``; quaternion ``(x, y, z, w)``
    rate ``0.5 q (x) (omega, 0)`` with ``omega`` in the body frame.
    """
    qdot = np.empty(dynamics.nq)
    qdot[workspace.simple_q] = v[workspace.simple_v]
    for iq, iv in dynamics.mechanism.free_flyers:
        x, y, z, w = q[iq + 3 : iq + 7]
        vec = np.array([x, y, z])
        omega = v[iv + 3 : iv + 6]
        rotation = pin.Quaternion(w, x, y, z).toRotationMatrix()
        qdot[iq : iq + 3] = rotation @ v[iv : iv + 3]
        qdot[iq + 3 : iq + 6] = 0.5 * (w * omega + np.cross(vec, omega))
        qdot[iq + 6] = -0.5 * (vec @ omega)
    return qdot


@dataclass
class Evaluation:
    """Everything computed at one (t, q, v): accelerations, multipliers, contacts."""

    qdd: np.ndarray
    multipliers: np.ndarray  # paper convention lambda (M qdd + Phi_q^T lambda = Q)
    residual: np.ndarray
    residual_rate: np.ndarray
    contacts: list
    generalized_contact_force: np.ndarray

    def driving_force(self, constraints: C.ConstraintSet) -> np.ndarray:
        return -self.multipliers[constraints.driving_rows]


def element_states(data: pin.Data, model: pin.Model, site: ClearanceSite):
    """Rotation, position and twist (world axes) of the outer and inner element frames."""
    outer, inner = data.oMf[site.outer_frame], data.oMf[site.inner_frame]
    outer_twist = pin.getFrameVelocity(model, data, site.outer_frame, LWA).vector
    inner_twist = pin.getFrameVelocity(model, data, site.inner_frame, LWA).vector
    return outer.rotation, outer.translation, outer_twist, inner.rotation, inner.translation, inner_twist


def evaluate(
    dynamics: DynamicsModel,
    workspace: DynamicsWorkspace,
    t: float,
    q: np.ndarray,
    v: np.ndarray,
    onset_rates: np.ndarray,
) -> Evaluation:
    """Solve the stabilised KKT system (paper eq. (24)) at (t, q, v)."""
    mechanism = dynamics.mechanism
    model, data = mechanism.model, workspace.data
    constraints = dynamics.constraints
    workspace.rhs_calls += 1
    s, sd, sdd = dynamics.drive.drive(t)
    pin.computeAllTerms(model, data, q, v)
    pin.updateFramePlacements(model, data)
    phi = C.residual(constraints, data, q, s)
    phi_q = C.jacobian(constraints, model, data)
    phi_dot = phi_q @ v - C.velocity_rhs(constraints, sd)
    gains = dynamics.baumgarte
    rhs = C.gamma(constraints, model, data, sdd) - 2.0 * gains.alpha * phi_dot - gains.beta**2 * phi
    tau = np.zeros(model.nv)
    contacts = []
    for contact in dynamics.contacts:
        site = contact.site
        result = contact.law.evaluate(*element_states(data, model, site), onset_rates[contact.candidates])
        contacts.append(result)
        if np.any(result.in_contact):
            tau += pin.getFrameJacobian(model, data, site.outer_frame, LWA).T @ result.wrench_outer
            tau += pin.getFrameJacobian(model, data, site.inner_frame, LWA).T @ result.wrench_inner
    qdd = pin.forwardDynamics(model, data, tau, phi_q, -rhs).copy()
    return Evaluation(qdd, -data.lambda_c.copy(), phi, phi_dot, contacts, tau)


def penetrations(dynamics: DynamicsModel, workspace: DynamicsWorkspace, q: np.ndarray) -> np.ndarray:
    """Penetration of every contact candidate at q (positions only; cheap, for event functions)."""
    if not dynamics.contacts:
        return np.zeros(0)
    model, data = dynamics.mechanism.model, workspace.data
    pin.framesForwardKinematics(model, data, q)
    out = np.empty(dynamics.n_candidates)
    for contact in dynamics.contacts:
        site = contact.site
        outer, inner = data.oMf[site.outer_frame], data.oMf[site.inner_frame]
        out[contact.candidates] = contact.law.penetration(outer.rotation, outer.translation, inner.rotation, inner.translation)
    return out


def inverse_dynamics_driving_forces(
    dynamics: DynamicsModel, workspace: DynamicsWorkspace, q: np.ndarray, v: np.ndarray, qdd: np.ndarray
) -> np.ndarray:
    """Closed-loop inverse dynamics of the ideal mechanism: the multipliers that produce ``qdd``.

    ``Phi_q^T lambda = -h - M qdd`` solved in the least-squares sense (exact for a
    consistent motion); returns the driving forces ``-lambda_drive``. Independent
    of the integrator: used to check the simulated driving forces.
    """
    model, data = dynamics.mechanism.model, workspace.data
    tau = pin.rnea(model, data, q, v, qdd)  # M qdd + h
    pin.computeJointJacobians(model, data, q)
    pin.updateFramePlacements(model, data)
    phi_q = C.jacobian(dynamics.constraints, model, data)
    multipliers, *_ = np.linalg.lstsq(phi_q.T, -tau, rcond=None)
    return -multipliers[dynamics.constraints.driving_rows]


def energy(dynamics: DynamicsModel, workspace: DynamicsWorkspace, q: np.ndarray, v: np.ndarray) -> tuple[float, float]:
    """Kinetic and potential (gravity) energy of the mechanism."""
    model, data = dynamics.mechanism.model, workspace.data
    return float(pin.computeKineticEnergy(model, data, q, v)), float(pin.computePotentialEnergy(model, data, q))


def stack_candidates(contacts: Sequence, attribute: str) -> np.ndarray:
    """Concatenate one per-candidate attribute over the contact sites."""
    if not contacts:
        return np.zeros(0)
    return np.concatenate([np.atleast_1d(getattr(c, attribute)) for c in contacts])
