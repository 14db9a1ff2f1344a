"""Newton-Euler formulation of the mechanism in absolute coordinates (the paper's second method).

Written independently of Pinocchio's dynamics (no ``crba``/``rnea``/``aba``/
``forwardDynamics``/``computeAllTerms``/Jacobians here): Pinocchio only maps the
Lagrange model's initial state to absolute coordinates (:func:`initial_state`).

Coordinates and equations
-------------------------
Each of the n moving bodies (every URDF link but the ground) has the position
``r`` of its centre of mass (world), a unit quaternion ``p = (e0, e1, e2, e3)``
(body -> world rotation ``A(p)``, body axes = the link's axes), the COM velocity
``v`` (world) and the angular velocity ``w'`` in body axes. The state is
``y = [r (3n), p (4n), v (3n), w' (3n)]`` and

    r_dot = v,      p_dot = 1/2 p (x) (0, w'),
    m v_dot          = m g + f_contact - (Phi_r^T lambda)
    J' w'_dot + w' x J' w' = n'_contact - (Phi_pi'^T lambda)

(Newton's law for the COM, Euler's for the rotation about the COM, body axes).
The joint reactions are the multipliers ``lambda`` of the constraint equations
written out in absolute coordinates (:mod:`.absolute_constraints`): revolute
(spherical + 2 dot-1), universal (two revolutes through the cross), prismatic
(3 dot-1 + 2 dot-2), spherical closures, and the five driving constraints
``h . d - s_k(t) = 0`` (the actuator length along the prismatic axis). With
``M = blockdiag(m_i I, J'_i)``, ``a = [v_dot, w'_dot]`` and the Baumgarte
stabilised acceleration constraint, each evaluation solves the augmented system
(index-1 DAE, seed paper eq. (24) in absolute coordinates)

    [ M     Phi_q^T ] [ a      ]   [ Q                                  ]
    [ Phi_q 0       ] [ lambda ] = [ gamma - 2 alpha Phi_dot - beta^2 Phi ]

``Q = [m g + f_c; -w' x J' w' + n'_c]``. It is solved by its range-space
(Schur-complement) form, exact for the block-diagonal ``M``:
``(Phi_q M^-1 Phi_q^T) lambda = Phi_q M^-1 Q - rhs``, ``a = M^-1 (Q - Phi_q^T lambda)``.
``Phi_dot = Phi_q [v; w'] + Phi_t``. The driving force of actuator k is
``-lambda_k`` (positive: the actuator pushes), as in ``robot.dynamics.equations``.

Clearance joints impose no constraint (the joint or closure is left out); the
contact layer ``clearance_contact`` gives the wrenches ``[f, m]`` about each
element frame origin (world axes); on the body carrying the element, at
``s = A s'`` from its COM: ``f_c += f``, ``n'_c += A^T (m + s x f)``.

The initial state is the Lagrange model's ``y0`` mapped through Pinocchio's
forward kinematics (positions, rotations and velocities of the link frames).

Scope
-----
Modelled (:data:`SCOPE`): revolute, continuous, prismatic and floating joints,
fixed joints (their child merged into the parent body, :mod:`.bodies`),
spherical closures (and any closure or joint carrying a clearance joint),
prescribed-motion actuators on prismatic joints, gravity and the clearance
contacts. Anything else (an actuated revolute joint, a revolute closure without
clearance, a planar joint, a massless moving body, ``[[force]]`` elements,
force-driven actuators) raises :class:`.bodies.UnsupportedFeatureError` when
the model is built (:func:`build_model`, :func:`check_supported`), before any
integration: the engine never computes another mechanism than the Lagrange
model's. With no ideal constraint left (every joint a clearance joint) the
bodies move freely and the constraint residual is 0.
"""

from __future__ import annotations

import dataclasses
import math
import time
from dataclasses import dataclass, field

import numpy as np
import pinocchio as pin

from clearance_contact import ONSET_RATE_FLOOR
from robot.model.mechanism import rotation_z_to
from robot.run import Run
from robot.integration.event_loop import ContactProbe
from robot.integration.options import SolverOptions
from robot.validation.absolute_constraints import BodyStates, ConstraintSet, cross
from robot.validation.bodies import MechanismGeometry, UnsupportedFeatureError, read_geometry, rpy_matrix
from robot.validation.event_loop import EventRun, run_events

GRAVITY = np.array([0.0, 0.0, -9.81])  # the default; a model uses its run's gravity (NewtonEulerModel.gravity)


# --- quaternions (e0 scalar) -------------------------------------------------------------
def quaternion_to_matrix(p: np.ndarray) -> np.ndarray:
    """Rotation matrices of unit quaternions (k, 4) -> (k, 3, 3)."""
    e0, e1, e2, e3 = p[:, 0], p[:, 1], p[:, 2], p[:, 3]
    out = np.empty((p.shape[0], 3, 3))
    out[:, 0, 0] = 1 - 2 * (e2 * e2 + e3 * e3)
    out[:, 0, 1] = 2 * (e1 * e2 - e0 * e3)
    out[:, 0, 2] = 2 * (e1 * e3 + e0 * e2)
    out[:, 1, 0] = 2 * (e1 * e2 + e0 * e3)
    out[:, 1, 1] = 1 - 2 * (e1 * e1 + e3 * e3)
    out[:, 1, 2] = 2 * (e2 * e3 - e0 * e1)
    out[:, 2, 0] = 2 * (e1 * e3 - e0 * e2)
    out[:, 2, 1] = 2 * (e2 * e3 + e0 * e1)
    out[:, 2, 2] = 1 - 2 * (e1 * e1 + e2 * e2)
    return out


def matrix_to_quaternion(R: np.ndarray) -> np.ndarray:
    """Unit quaternion (e0 >= 0) of a rotation matrix."""
    q = pin.Quaternion(np.asarray(R, dtype=float))
    out = np.array([q.w, q.x, q.y, q.z])
    return out if out[0] >= 0 else -out


def quaternion_rate(p: np.ndarray, w: np.ndarray) -> np.ndarray:
    """p_dot = 1/2 p (x) (0, w') for body-axes angular velocities (k, 3)."""
    e0, e = p[:, :1], p[:, 1:]
    return 0.5 * np.hstack([-np.einsum("ki,ki->k", e, w)[:, None], e0 * w + cross(e, w)])


# --- the model ----------------------------------------------------------------------------
@dataclass(frozen=True)
class ElementFrame:
    """A contact element frame fixed to a body: body index, offset from the COM and rotation (body axes)."""

    body: int
    offset: np.ndarray
    rotation: np.ndarray


@dataclass(frozen=True)
class ContactSiteNE:
    name: str
    law: object
    outer: ElementFrame
    inner: ElementFrame
    first: int

    @property
    def candidates(self) -> slice:
        return slice(self.first, self.first + self.law.n_candidates)


@dataclass
class NewtonEulerModel:
    """Bodies, constraints, contact sites and drive of the mechanism in absolute coordinates."""

    geometry: MechanismGeometry
    mass: np.ndarray
    inertia: np.ndarray
    inertia_inv: np.ndarray
    constraints: ConstraintSet
    contacts: tuple[ContactSiteNE, ...]
    drive: object
    alpha: float
    beta: float
    ee_body: int
    ee_offset: np.ndarray
    n_candidates: int
    rhs_calls: int = 0
    names: tuple[str, ...] = field(default_factory=tuple)
    gravity: np.ndarray = field(default_factory=lambda: GRAVITY.copy())  # m/s^2, world axes (the scene's gravity)
    minv: np.ndarray = field(default=None, repr=False)  # (n, 6, 6) block inverses of M
    minv_rows: np.ndarray = field(default=None, repr=False)  # (rows, 2, 6, 6) M^-1 blocks of each row's bodies

    def __post_init__(self) -> None:
        n = self.n
        self.minv = np.zeros((n + 1, 6, 6))  # the ground (index n) has no inverse mass
        self.minv[:n, :3, :3] = np.eye(3) / self.mass[:, None, None]
        self.minv[:n, 3:, 3:] = self.inertia_inv
        self.minv_rows = self.minv[self.constraints.bodies]
        self.minv = self.minv[:n]

    @property
    def n(self) -> int:
        return len(self.mass)

    # state layout
    def split(self, y: np.ndarray):
        n = self.n
        r = y[: 3 * n].reshape(n, 3)
        p = y[3 * n : 7 * n].reshape(n, 4)
        v = y[7 * n : 10 * n].reshape(n, 3)
        w = y[10 * n : 13 * n].reshape(n, 3)
        return r, p, v, w

    def normalise(self, y: np.ndarray) -> np.ndarray:
        y = np.array(y, dtype=float)
        n = self.n
        p = y[3 * n : 7 * n].reshape(n, 4)
        p /= np.linalg.norm(p, axis=1)[:, None]
        return y

    def states(self, y: np.ndarray) -> BodyStates:
        r, p, v, w = self.split(y)
        p = p / np.linalg.norm(p, axis=1)[:, None]
        A = quaternion_to_matrix(p)
        zero = np.zeros((1, 3))
        return BodyStates(np.vstack([r, zero]), np.concatenate([A, np.eye(3)[None]]), np.vstack([v, zero]), np.vstack([w, zero]))


#: the movable joint kinds the absolute-coordinate formulations model (a fixed joint merges its child into its parent)
MODELLED_JOINT_KINDS = ("revolute", "continuous", "prismatic", "floating")
#: what the Newton-Euler and Exudyn models cover, for the messages of what they refuse
SCOPE = (
    "the Newton-Euler and Exudyn models cover revolute, continuous, prismatic, floating and fixed joints, spherical "
    "closures (any closure with a clearance joint), prescribed-motion actuators on prismatic joints, gravity and the clearance contacts"
)


def _element(geometry: MechanismGeometry, link: str, xyz, rotation) -> ElementFrame:
    """A frame given on ``link`` as a frame on the body carrying it (offset from the body's COM)."""
    carrier, xyz, rotation = geometry.place(link, xyz, rotation)
    body = geometry.body(carrier)
    com = np.zeros(3) if body is None else body.com
    return ElementFrame(geometry.body_index(carrier), xyz - com, rotation)


def _perpendiculars(axis: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    frame = rotation_z_to(axis)
    return frame[:, 0], frame[:, 1]


def _contact_sites(geometry: MechanismGeometry, description, clearances) -> tuple[ContactSiteNE, ...]:
    """The clearance sites in the Lagrange model's order (closures first, then tree joints), candidates numbered alike."""
    contacts, first = [], 0
    closures = {c.name: c for c in description.closures}
    ordered = [c for c in clearances if c.joint in closures] + [c for c in clearances if c.joint not in closures]
    for spec in ordered:
        if spec.joint in closures:
            c = closures[spec.joint]
            parent = _element(geometry, c.parent.link, c.parent.xyz, rpy_matrix(c.parent.rpy))
            child = _element(geometry, c.child.link, c.child.xyz, rpy_matrix(c.child.rpy))
        else:
            joint = geometry.joint(spec.joint)
            align = rotation_z_to(joint.axis)
            parent = _element(geometry, joint.parent, joint.origin_xyz, joint.origin_rotation @ align)
            child = _element(geometry, joint.child, np.zeros(3), align)
        outer, inner = (child, parent) if spec.outer_on == "child" else (parent, child)
        contacts.append(ContactSiteNE(spec.joint, spec.law, outer, inner, first))
        first += spec.law.n_candidates
    return tuple(contacts)


def check_scene_loads(scene) -> None:
    """``UnsupportedFeatureError`` for the scene's loads the models leave out: ``[[force]]`` elements, force-driven actuators.

    Both would otherwise be silently missing from the Newton-Euler and Exudyn
    mechanisms, which would then be other mechanisms than the Lagrange model's.
    An actuator with ``mode = "none"`` is a free joint, which both model.
    """
    if scene.forces:
        names = ", ".join(f"{spec.name!r} ({spec.kind})" for spec in scene.forces)
        raise UnsupportedFeatureError(
            f"force element(s) {names} of [[force]]: the cross-check engines model no force elements; {SCOPE}"
        )
    forced = [joint for joint, spec in scene.actuators.items() if spec.mode == "force"]
    if forced:
        raise UnsupportedFeatureError(
            f"force-driven actuator(s) {', '.join(map(repr, forced))} ([actuators] mode = 'force'): the cross-check engines "
            f"model prescribed-motion actuators (mode = 'motion') and free joints (mode = 'none') only; {SCOPE}"
        )


def _check_joints(geometry: MechanismGeometry, description, clearance: set) -> None:
    """``UnsupportedFeatureError`` for a joint kind, an actuated joint or a closure the models do not have."""
    for joint in geometry.joints:
        if joint.kind not in MODELLED_JOINT_KINDS:
            raise UnsupportedFeatureError(f"joint {joint.name!r} is {joint.kind}: {SCOPE}")
    for name in description.actuated_joints:
        kind = geometry.joint(name).kind
        if kind != "prismatic":
            raise UnsupportedFeatureError(
                f"actuated joint {name!r} is {kind}: the cross-check engines drive prismatic joints only (a prescribed length); {SCOPE}"
            )
    for closure in description.closures:
        if closure.name not in clearance and closure.kind != "spherical":
            raise UnsupportedFeatureError(f"closure {closure.name!r} is a {closure.kind} closure without clearance: {SCOPE}")


def end_effector_link(geometry: MechanismGeometry, description, frame: str) -> str:
    """The link whose origin is the end-effector frame ``frame`` (a link, or a joint: its child link)."""
    if frame in geometry.placements:
        return frame
    joint = description.joints.get(frame)
    if joint is None:
        raise UnsupportedFeatureError(f"end_effector {frame!r} is neither a link nor a joint: the cross-check engines place it on a link's origin")
    return joint.child


def _joint_constraints(cs: ConstraintSet, geometry: MechanismGeometry, com: dict, actuated: list[str], clearance: set) -> None:
    """The ideal tree joints as constraint equations (revolute: spherical + 2 dot-1; prismatic: 3 dot-1 + 2 dot-2 [+ drive])."""
    for joint in geometry.joints:
        if joint.name in clearance or joint.kind == "floating":
            continue
        i, j = geometry.body_index(joint.parent), geometry.body_index(joint.child)
        point_i = joint.origin_xyz - com[joint.parent]  # joint origin, parent body frame
        point_j = -com[joint.child]  # child link origin, child body frame
        axis_i = joint.origin_rotation @ joint.axis  # joint axis in the parent link frame
        if joint.kind in ("revolute", "continuous"):
            cs.spherical(i, point_i, j, point_j, joint.name)
            g, h = _perpendiculars(joint.axis)  # normal to the axis, child frame
            cs.dot1(i, axis_i, j, g, f"{joint.name}:axis-1")
            cs.dot1(i, axis_i, j, h, f"{joint.name}:axis-2")
        else:  # prismatic (the kinds were checked by _check_joints)
            R = joint.origin_rotation
            cs.dot1(i, R[:, 0], j, np.array([0.0, 1.0, 0.0]), f"{joint.name}:lock-z")
            cs.dot1(i, R[:, 1], j, np.array([0.0, 0.0, 1.0]), f"{joint.name}:lock-x")
            cs.dot1(i, R[:, 2], j, np.array([1.0, 0.0, 0.0]), f"{joint.name}:lock-y")
            g, h = _perpendiculars(axis_i)
            cs.dot2(i, g, point_i, j, point_j, f"{joint.name}:line-1")
            cs.dot2(i, h, point_i, j, point_j, f"{joint.name}:line-2")
            if joint.name in actuated:
                cs.dot2(i, axis_i, point_i, j, point_j, f"{joint.name}:drive", driver=actuated.index(joint.name))


def build_model(run: Run) -> NewtonEulerModel:
    """The Newton-Euler model of a built run (same URDF, clearance joints, laws, drive and gains).

    ``UnsupportedFeatureError`` (before anything is integrated) for what it does
    not model: see :data:`SCOPE` and :func:`check_scene_loads`.
    """
    scene, description = run.scene, run.mechanism.description
    check_scene_loads(scene)
    geometry = read_geometry(description)
    clearance = {c.joint for c in scene.clearances}
    _check_joints(geometry, description, clearance)
    ee_carrier, ee_xyz, _ = geometry.place(end_effector_link(geometry, description, scene.end_effector))
    bodies = geometry.bodies
    com = {b.name: b.com for b in bodies}
    com[geometry.ground] = np.zeros(3)
    cs = ConstraintSet()
    _joint_constraints(cs, geometry, com, list(description.actuated_joints), clearance)
    for closure in description.closures:
        if closure.name in clearance:
            continue
        a, b = (geometry.place(frame.link, frame.xyz) for frame in (closure.parent, closure.child))
        cs.spherical(geometry.body_index(a[0]), a[1] - com[a[0]], geometry.body_index(b[0]), b[1] - com[b[0]], closure.name)
    cs.freeze(len(bodies))

    contacts = _contact_sites(geometry, description, scene.clearances)
    mass = np.array([b.mass for b in bodies])
    inertia = np.array([b.inertia for b in bodies])
    return NewtonEulerModel(
        geometry=geometry,
        mass=mass,
        inertia=inertia,
        inertia_inv=np.linalg.inv(inertia),
        constraints=cs,
        contacts=contacts,
        drive=run.dynamics.drive,
        alpha=scene.baumgarte.alpha,
        beta=scene.baumgarte.beta,
        ee_body=geometry.body_index(ee_carrier),
        ee_offset=ee_xyz - com[ee_carrier],
        n_candidates=sum(site.law.n_candidates for site in contacts),
        names=tuple(b.name for b in bodies),
        gravity=np.array(run.mechanism.model.gravity.linear),
    )


def check_supported(run: Run) -> NewtonEulerModel:
    """The Newton-Euler model of ``run`` if it can be built, else ``UnsupportedFeatureError`` naming what it lacks (nothing run)."""
    return build_model(run)


# --- initial state --------------------------------------------------------------------------
def initial_state(model: NewtonEulerModel, run: Run) -> np.ndarray:
    """The Lagrange initial state ``run.y0`` in absolute coordinates (input mapping through Pinocchio kinematics)."""
    pmodel = run.mechanism.model
    data = pmodel.createData()
    nq, nv = pmodel.nq, pmodel.nv
    q, v = run.y0[:nq], run.y0[nq : nq + nv]
    pin.forwardKinematics(pmodel, data, q, v)
    pin.updateFramePlacements(pmodel, data)
    n = model.n
    r, p, vel, w = np.empty((n, 3)), np.empty((n, 4)), np.empty((n, 3)), np.empty((n, 3))
    for k, body in enumerate(model.geometry.bodies):
        fid = pmodel.getFrameId(body.name, pin.FrameType.BODY)
        placement = data.oMf[fid]
        twist = pin.getFrameVelocity(pmodel, data, fid, pin.ReferenceFrame.LOCAL_WORLD_ALIGNED)
        R = placement.rotation
        lever = R @ body.com
        r[k] = placement.translation + lever
        p[k] = matrix_to_quaternion(R)
        vel[k] = twist.linear + np.cross(twist.angular, lever)
        w[k] = R.T @ twist.angular
    return np.concatenate([r.ravel(), p.ravel(), vel.ravel(), w.ravel()])


# --- evaluation -------------------------------------------------------------------------------
@dataclass
class NEEvaluation:
    ydot: np.ndarray
    multipliers: np.ndarray
    residual: np.ndarray
    contacts: list
    driving_force: np.ndarray
    ee_position: np.ndarray


def _element_state(states: BodyStates, frame: ElementFrame):
    b = frame.body if frame.body >= 0 else states.n
    A = states.A[b]
    lever = A @ frame.offset
    omega = A @ states.w[b]
    return A @ frame.rotation, states.r[b] + lever, np.concatenate([states.v[b] + cross(omega, lever), omega]), lever


def evaluate(model: NewtonEulerModel, t: float, y: np.ndarray, onset: np.ndarray) -> NEEvaluation:
    """Solve the stabilised augmented system at (t, y)."""
    model.rhs_calls += 1
    n = model.n
    states = model.states(y)
    rows = model.constraints.evaluate(states, model.drive.drive(t))
    A, w = states.A[:n], states.w[:n]
    force = model.mass[:, None] * model.gravity
    Jw = np.einsum("kij,kj->ki", model.inertia, w)
    torque = -cross(w, Jw)
    contacts = []
    for site in model.contacts:
        Ro, po, two, lever_o = _element_state(states, site.outer)
        Ri, pi_, twi, lever_i = _element_state(states, site.inner)
        result = site.law.evaluate(Ro, po, two, Ri, pi_, twi, onset[site.candidates])
        contacts.append(result)
        for frame, lever, wrench in ((site.outer, lever_o, result.wrench_outer), (site.inner, lever_i, result.wrench_inner)):
            if frame.body < 0 or not np.any(wrench):
                continue
            b = frame.body
            force[b] += wrench[:3]
            torque[b] += A[b].T @ (wrench[3:] + cross(lever, wrench[:3]))
    cs = model.constraints
    J = rows.jacobian
    phi_dot = cs.times(J, np.hstack([states.v[:n], w])) + rows.phi_t
    rhs = rows.gamma - 2.0 * model.alpha * phi_dot - model.beta**2 * rows.phi
    Q = np.hstack([force, torque])  # (n, 6)
    JM = np.einsum("rsij,rsj->rsi", model.minv_rows, J)  # Phi_q M^-1, row blocks
    schur = cs.weighted_gram(J, JM)  # Phi_q M^-1 Phi_q^T
    padded_q = np.vstack([Q, np.zeros((1, 6))])
    lam = np.linalg.solve(schur, np.einsum("rsk,rsk->r", JM, padded_q[cs.bodies]) - rhs)
    acc = np.einsum("kij,kj->ki", model.minv, Q - cs.transpose_times(J, lam))
    r, p, v, _ = model.split(y)
    p = p / np.linalg.norm(p, axis=1)[:, None]
    ydot = np.concatenate([v.ravel(), quaternion_rate(p, w).ravel(), acc[:, :3].ravel(), acc[:, 3:].ravel()])
    driving = np.empty(len(cs.driving_order))
    driving[cs.driving_order] = -lam[cs.driving_rows]
    ee = states.r[model.ee_body] + states.A[model.ee_body] @ model.ee_offset
    return NEEvaluation(ydot, lam, rows.phi, contacts, driving, ee)


def contact_kinematics(model: NewtonEulerModel, y: np.ndarray, onset: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Penetration, its rate and the normal force of every contact candidate."""
    states = model.states(y)
    pen = np.empty(model.n_candidates)
    rate = np.empty(model.n_candidates)
    force = np.empty(model.n_candidates)
    for site in model.contacts:
        Ro, po, two, _ = _element_state(states, site.outer)
        Ri, pi_, twi, _ = _element_state(states, site.inner)
        result = site.law.evaluate(Ro, po, two, Ri, pi_, twi, onset[site.candidates])
        pen[site.candidates] = result.penetration
        rate[site.candidates] = result.penetration_rate
        force[site.candidates] = result.normal_force
    return pen, rate, force


def penetrations(model: NewtonEulerModel, y: np.ndarray, onset: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Penetration and its rate for every contact candidate."""
    return contact_kinematics(model, y, onset)[:2]


class NewtonEulerSystem:
    """The Newton-Euler model behind the step loop's protocol (:class:`robot.integration.event_loop.EventSystem`).

    Its own equations of motion (:func:`evaluate`) and contact kinematics; no
    penetration bound, no residual check, no Jacobian (explicit methods only).
    """

    structure = None
    jacobian = None

    def __init__(self, model: NewtonEulerModel):
        self.model = model
        self.size = 13 * model.n
        self.n_candidates = model.n_candidates
        self.penetration_bounds = np.full(model.n_candidates, np.inf)
        self.rhs_calls = 0
        self._floor = np.full(model.n_candidates, ONSET_RATE_FLOOR)  # penetrations do not depend on the onset rates

    def derivative(self, t: float, y: np.ndarray, onset: np.ndarray) -> np.ndarray:
        self.rhs_calls += 1
        return evaluate(self.model, t, y, onset).ydot

    def probe(self, t: float, y: np.ndarray, onset: np.ndarray, residual: bool = True) -> ContactProbe:
        penetration, rate, force = contact_kinematics(self.model, y, onset)
        return ContactProbe(penetration, rate, math.nan, force)

    def penetrations(self, t: float, y: np.ndarray) -> np.ndarray:
        return contact_kinematics(self.model, y, self._floor)[0]

    def normalise(self, y: np.ndarray) -> np.ndarray:
        return self.model.normalise(y)

    def replica(self) -> "NewtonEulerSystem":
        return NewtonEulerSystem(self.model)


# --- simulation -------------------------------------------------------------------------------
@dataclass
class NEResult:
    """Outputs of a Newton-Euler run at its records and at the requested output times."""

    run: EventRun
    arrays: dict
    eval_arrays: dict
    wall_time: float

    @property
    def success(self) -> bool:
        return self.run.success


def body_origins(model: NewtonEulerModel, y: np.ndarray) -> np.ndarray:
    """World positions (n, 3) of the bodies' link-frame origins (``r - A c'``: the COM is at ``c'`` in the link frame)."""
    states = model.states(y)
    com = np.array([body.com for body in model.geometry.bodies]).reshape(-1, 3)
    return states.r[: model.n] - np.einsum("kij,kj->ki", states.A[: model.n], com)


def outputs(model: NewtonEulerModel, t: np.ndarray, y: np.ndarray, onset: np.ndarray) -> dict:
    """Driving forces, end-effector position, body origins, constraint residual and contact forces at given states.

    ``constraint_residual``: the largest ``|Phi|``, 0 when no ideal constraint is
    left (every joint a clearance joint or floating: the bodies move freely).
    """
    n = len(t)
    out = {
        "t": np.asarray(t),
        "driving_force": np.full((n, len(model.constraints.driving_order)), np.nan),
        "ee_position": np.full((n, 3), np.nan),
        "body_origins": np.full((n, model.n, 3), np.nan),
        "constraint_residual": np.full(n, np.nan),
    }
    for site in model.contacts:
        k = site.law.n_candidates
        out[f"{site.name}_normal_force"] = np.full((n, k), np.nan)
        out[f"{site.name}_penetration"] = np.full((n, k), np.nan)
    for i in range(n):
        if not np.all(np.isfinite(y[i])):
            continue
        ev = evaluate(model, float(t[i]), model.normalise(y[i]), onset[i])
        out["driving_force"][i] = ev.driving_force
        out["ee_position"][i] = ev.ee_position
        out["body_origins"][i] = body_origins(model, y[i])
        out["constraint_residual"][i] = np.max(np.abs(ev.residual), initial=0.0)
        for site, result in zip(model.contacts, ev.contacts):
            out[f"{site.name}_normal_force"][i] = result.normal_force
            out[f"{site.name}_penetration"][i] = result.penetration
    return out


def simulate(
    run: Run,
    *,
    t_end: float | None = None,
    method: str | None = None,
    rtol: float | None = None,
    atol: float | None = None,
    max_step: float | None = None,
    t_eval: np.ndarray | None = None,
    solver: SolverOptions | None = None,
) -> NEResult:
    """Integrate the Newton-Euler model of ``run``.

    Solver settings: ``solver`` if given, else ``run.scene.solver``, i.e. the
    same as :func:`robot.run.run_scene` uses for the Lagrange model of this
    ``run``; ``method``, ``rtol``, ``atol``, ``max_step`` override single fields.
    The validation builds its runs with
    :func:`robot.validation.settings.validation_run`, whose ``scene.solver`` is the
    pinned :data:`~robot.validation.settings.VALIDATION_SOLVER`, not the scene
    file's ``[solver]``. A method outside :data:`.event_loop.SOLVERS` raises
    ``ValueError``.
    """
    started = time.perf_counter()
    solver = run.scene.solver if solver is None else solver
    overrides = {k: v for k, v in dict(method=method, rtol=rtol, atol=atol, max_step=max_step).items() if v is not None}
    solver = dataclasses.replace(solver, **overrides)
    model = build_model(run)
    y0 = initial_state(model, run)
    events = run_events(NewtonEulerSystem(model), y0, (0.0, run.scene.duration if t_end is None else t_end), solver, t_eval)
    arrays = outputs(model, events.t, events.y, events.onset_rates)
    arrays["record_kind"] = events.kind
    eval_arrays = outputs(model, events.t_eval, events.y_eval, events.onset_eval) if len(events.t_eval) else {}
    return NEResult(events, arrays, eval_arrays, time.perf_counter() - started)


__all__ = [
    "NewtonEulerModel",
    "build_model",
    "check_supported",
    "check_scene_loads",
    "body_origins",
    "initial_state",
    "evaluate",
    "simulate",
    "NEResult",
]
