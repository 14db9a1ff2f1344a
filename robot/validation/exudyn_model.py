"""The mechanism in Exudyn: an independent engine (the role ADAMS plays in the seed paper).

Exudyn (https://github.com/jgerstmayr/EXUDYN, C++ with a Python interface) is a
redundant-coordinate multibody code: Lagrange multipliers, index-3 constraints,
implicit generalized-alpha integration. Only the geometry input
(:mod:`.bodies`), the initial state (the Lagrange run's ``y0`` mapped to
absolute coordinates, :func:`.newton_euler.initial_state`), the prescribed
actuator lengths (``robot.model.trajectory``) and the contact law
(``clearance_contact``) are shared; Exudyn builds and solves its own equations.

Model
-----
* Every moving link is an ``ObjectRigidBody`` on a ``NodeRigidBodyEP`` (Euler
  parameters) placed at its centre of mass, link axes as body axes; gravity is a
  ``LoadMassProportional`` (the run's gravity: the scene's ``gravity``, default -9.81 m/s^2 along z).
* Revolute joints (``U*_x``, ``U*_y``, ``R1``): ``GenericJoint`` with marker
  frames whose z is the joint axis, ``constrainedAxes = [1,1,1,1,1,0]``.
  Spherical closures ``S*``: ``SphericalJoint``.
* Prismatic joints: ``GenericJoint`` with the translation along the axis free,
  ``constrainedAxes = [1,1,0,1,1,1]``, plus the **actuator** as an
  ``ObjectConnectorDistance`` between the cylinder's hinge point and the piston's
  hinge point (both on the leg axis, so their distance is the prescribed length
  ``s_k``); the distance is set to ``s_k(t_{n+1})`` in a pre-step user function
  (Exudyn passes the end time of the step) and enforced at position level
  (index 3) at the end of the step. The driving force is the connector's
  constraint force with the sign of ``robot.dynamics.equations`` (positive pushes):
  ``driving = -Force`` (the sign checked against the Lagrange model).
  The lengths ``s_k(t)`` come from :func:`actuator_lengths`.
  Why not a ``GenericJoint`` with all six axes locked and an ``offsetUserFunction``
  along z (the documented way to prescribe a joint motion): with the two marker
  points 1.2 m apart the locked translational equations lose rank in Exudyn
  1.13.6 (``ComputeSystemDegreeOfFreedom`` reports 3 redundant constraints for one
  U-P-S leg closed on a fixed platform instead of 1, and Newton diverges at the
  first step); with coincident markers it works, but the piston slides along
  the cylinder, so the markers cannot stay coincident.
* Clearance joints impose no joint; each is an ``ObjectGenericODE2`` on the
  nodes of the two bodies with a ``forceUserFunction`` that rebuilds the element
  frames from the node coordinates, calls the same ``clearance_contact`` law and
  returns the generalized forces: for a wrench ``[f, m]`` about an element origin
  at ``s = A s'`` from the COM, ``Q_pos = f`` and ``Q_ep = G^T (m + s x f)``, with
  ``omega = G ep_dot`` (``EulerParameters2G``). Its Jacobian is computed by
  Exudyn's numerical differentiation.
* Lankarani-Nikravesh onset rates: Exudyn has no event location, so after each
  converged step every candidate out of contact stores its current penetration
  rate (floored); once a step ends in contact the value stays until separation.
  The onset rate used by an impact is thus the approach rate at the start of the
  step that enters contact (error ``O(h a)``, ``a`` the relative acceleration
  before the impact).

Scope
-----
The Newton-Euler model's (:data:`.newton_euler.SCOPE`: its bodies, with links
on fixed joints merged, element frames and contact sites are used here), and
every prescribed actuator length must stay > 0 over the run: the
``ObjectConnectorDistance`` is an unsigned distance, so a rail coordinate at
or through 0 cannot be prescribed (:func:`check_actuator_lengths`, called by
:func:`check_supported` before any run and by :func:`simulate` before the model
is built). Refusals raise :class:`.bodies.UnsupportedFeatureError`.

Initial conditions
------------------
Positions and velocities from the Lagrange run's ``y0``. Exudyn's own
``computeInitialAccelerations`` ignores constraint motion prescribed from
Python (documented in ``GeneralizedAlphaSettings``): the driving forces then
start 84 N off and ring for 2 ms. Instead :func:`consistent_accelerations`
solves the initial acceleration problem with Exudyn's own mass matrix, forces
and constraint Jacobian, the constraints' acceleration right-hand side (with the
drivers' ``s''``) taken from the kinematic accelerations of the mechanism with
its clearance joints centred (:func:`kinematic_accelerations`).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np
import pinocchio as pin
from scipy.interpolate import CubicHermiteSpline

from clearance_contact import ONSET_RATE_FLOOR

from robot.model import constraints as C
from robot.model.kinematics import acceleration_analysis, assemble, velocity_analysis
from robot.scene.loader import misalignment_rotation
from robot.model.mechanism import rotation_z_to
from robot.run import Run
from robot.validation import newton_euler as NE
from robot.validation.bodies import UnsupportedFeatureError, rpy_matrix

#: spacing (s) of the exact actuator lengths the drive spline goes through
DRIVE_TABLE_SPACING = 2e-4


@dataclass(frozen=True)
class ExudynSettings:
    """Generalized-alpha settings (fixed step; Newton on the index-3 system)."""

    step_size: float = 1e-4
    spectral_radius: float = 0.5
    newton_relative_tolerance: float = 1e-12
    newton_absolute_tolerance: float = 1e-14
    adaptive_step: bool = True  # Exudyn halves the step if Newton fails (no error control)
    verbose: int = 0  # Exudyn's verboseMode


@dataclass
class ExudynResult:
    """Outputs of an Exudyn run, one row per time step."""

    success: bool
    message: str
    settings: ExudynSettings
    t: np.ndarray
    ee_position: np.ndarray
    driving_force: np.ndarray
    contact: dict = field(default_factory=dict)  # site -> {"normal_force": (n, k), "penetration": (n, k)}
    wall_time: float = 0.0  # build + initial accelerations + integration
    n_steps: int = 0
    solve_time: float = 0.0  # SolveDynamic only (includes the per-step Python logging)
    body_origins: np.ndarray = field(default_factory=lambda: np.zeros((0, 0, 3)))  # (steps, bodies, 3) link-frame origins


def _qmul(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return np.concatenate([[a[0] * b[0] - a[1:] @ b[1:]], a[0] * b[1:] + b[0] * a[1:] + np.cross(a[1:], b[1:])])


def _cross(a, b) -> np.ndarray:
    """Cross product of two 3-vectors (much cheaper than ``np.cross`` for single vectors)."""
    return np.array([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]])


def _ep_G(ep: np.ndarray) -> np.ndarray:
    """omega (world) = G ep_dot."""
    e0, e1, e2, e3 = ep
    return 2.0 * np.array([[-e1, e0, -e3, e2], [-e2, e3, e0, -e1], [-e3, -e2, e1, e0]])


def kinematic_accelerations(run: Run, geometry, t: float = 0.0) -> np.ndarray:
    """COM accelerations and Euler-parameter second derivatives (n, 7) of the ideal mechanism at time t.

    Position, velocity and acceleration analysis (``robot.model.kinematics``) of the
    mechanism with its clearance joints replaced by the ideal joints (centred,
    with the scene's initial misalignment), driven by the prescribed lengths.
    """
    mechanism = run.mechanism
    model = mechanism.model
    data = model.createData()
    nq = model.nq
    misalignment = {joint: misalignment_rotation(angle) for joint, angle in run.scene.misalignment_deg.items()}
    constraints = C.constraint_set(mechanism, driven=True, centre_clearance=True, misalignment=misalignment)
    s, sd, sdd = run.dynamics.drive.drive(t)
    q0 = run.y0[:nq] if t == 0.0 else assemble(constraints, run.y0[:nq], s).q
    v0 = run.y0[nq : nq + model.nv] if t == 0.0 else velocity_analysis(constraints, q0, sd)
    a0 = acceleration_analysis(constraints, q0, v0, sdd)
    pin.forwardKinematics(model, data, q0, v0, a0)
    pin.updateFramePlacements(model, data)
    out = np.empty((len(geometry.bodies), 7))
    lwa = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
    for k, body in enumerate(geometry.bodies):
        fid = model.getFrameId(body.name, pin.FrameType.BODY)
        R = data.oMf[fid].rotation
        velocity = pin.getFrameVelocity(model, data, fid, lwa)
        acceleration = pin.getFrameClassicalAcceleration(model, data, fid, lwa)
        lever = R @ body.com
        omega, alpha = velocity.angular, acceleration.angular
        ep = NE.matrix_to_quaternion(R)
        ep_t = 0.5 * _qmul(np.concatenate([[0.0], omega]), ep)
        out[k, :3] = acceleration.linear + np.cross(alpha, lever) + np.cross(omega, np.cross(omega, lever))
        out[k, 3:] = 0.5 * _qmul(np.concatenate([[0.0], alpha]), ep) + 0.5 * _qmul(np.concatenate([[0.0], omega]), ep_t)
    return out


def consistent_accelerations(mbs, settings, kinematic: np.ndarray) -> np.ndarray:
    """Exudyn's own initial accelerations, with the prescribed actuator accelerations included.

    Solves ``[M C_q^T; C_q 0] [a; lambda] = [f; C_q a_kin]`` with Exudyn's mass
    matrix ``M``, force vector ``f`` and constraint Jacobian ``C_q`` at the initial
    state. ``a_kin`` is any acceleration consistent with the constraints (here
    the ideal mechanism's, from the kinematic analysis); ``C_q a_kin`` is then the
    acceleration right-hand side including the drivers' ``s''`` that Exudyn's
    ``computeInitialAccelerations`` leaves out.
    """
    import exudyn as exu

    solver = exu.MainSolverImplicitSecondOrder()
    solver.InitializeSolver(mbs, settings)
    n2 = solver.GetODE2size()
    solver.ComputeMassMatrix(mbs)
    mass = np.array(solver.GetSystemMassMatrix())[:n2, :n2]
    solver.ComputeODE2RHS(mbs)
    force = np.array(solver.GetSystemResidual())[:n2]
    solver.ComputeJacobianODE2RHS(mbs, scalarFactor_ODE2=0.0, scalarFactor_ODE2_t=0.0, scalarFactor_ODE1=0.0)
    solver.ComputeJacobianAE(mbs, scalarFactor_ODE2=1.0, scalarFactor_ODE2_t=0.0, scalarFactor_ODE1=1.0, velocityLevel=False)
    jacobian = np.array(solver.GetSystemJacobian())
    solver.FinalizeSolver(mbs, settings)
    cq_t = jacobian[:n2, n2:]
    n_ae = cq_t.shape[1]
    kkt = np.block([[mass, cq_t], [cq_t.T, np.zeros((n_ae, n_ae))]])
    rhs = np.concatenate([force, cq_t.T @ kinematic])
    solution, *_ = np.linalg.lstsq(kkt, rhs, rcond=None)
    return solution[:n2]


def actuator_lengths(drive, t_end: float, spacing: float = DRIVE_TABLE_SPACING):
    """The prescribed lengths s(t) as a clamped cubic spline through exact values every ``spacing`` seconds.

    Evaluating the platform inverse kinematics at every Exudyn step (1e-5 s) costs
    more than the rest of the Python side; the spline has the exact values and
    end slopes, and its error (``spacing^4 max|s^(4)| / 384``, about 2e-14 m for the
    reference motion) is far below the accuracies compared here.
    """
    n = max(2, int(math.ceil(t_end / spacing)) + 1)
    times = np.linspace(0.0, (n - 1) * spacing, n)
    values = [drive.drive(float(t)) for t in times]
    s = np.array([v[0] for v in values])
    sd = np.array([v[1] for v in values])
    return CubicHermiteSpline(times, s, sd)


def check_actuator_lengths(lengths, joints: list[str], t_end: float) -> None:
    """``UnsupportedFeatureError`` if a prescribed actuator length ``lengths(t)`` is not > 0 somewhere in ``[0, t_end]``.

    The model drives a prismatic joint by the distance between its two hinge
    points (``ObjectConnectorDistance``), an unsigned length: at 0 its direction is
    undefined (Exudyn refuses a distance of 0) and a negative prescribed
    coordinate cannot be met. Checked on the spline Exudyn is given, at its nodes
    and 8 points between each two (a cubic between exact positive values).
    """
    if not joints:
        return
    times = np.union1d(lengths.x[lengths.x <= t_end], np.linspace(0.0, t_end, 8 * len(lengths.x) + 1))
    values = lengths(times).reshape(len(times), -1)
    for k, joint in enumerate(joints):
        bad = np.flatnonzero(~(values[:, k] > 0.0))
        if bad.size:
            raise UnsupportedFeatureError(
                f"actuator {joint!r}: its prescribed length is {values[bad[0], k]:.6g} m at t = {times[bad[0]]:.6g} s; the Exudyn "
                "model drives a prismatic joint by the distance between its hinge points, an unsigned length, which must stay > 0 "
                "over the run (move the joint origin so that the coordinate stays positive, or leave Exudyn out: --engines newton_euler)"
            )


def check_supported(run: Run, t_end: float | None = None) -> None:
    """``UnsupportedFeatureError`` naming what the Exudyn model of ``run`` cannot have (nothing is run).

    Its scope is the Newton-Euler model's (:func:`.newton_euler.build_model`,
    whose bodies, frames and contact sites it uses), and every prescribed
    actuator length must stay positive over ``[0, t_end]`` (:func:`check_actuator_lengths`).
    """
    NE.check_supported(run)
    actuated = list(run.mechanism.description.actuated_joints)
    if actuated:
        t_end = run.scene.duration if t_end is None else t_end
        check_actuator_lengths(actuator_lengths(run.dynamics.drive, t_end), actuated, t_end)


class _ContactElement:
    """State and force function of one clearance joint between two Exudyn nodes (or a node and the ground)."""

    def __init__(self, site: NE.ContactSiteNE, nodes: list, references: dict):
        self.site = site
        self.law = site.law
        self.frames = (site.outer, site.inner)
        self.bodies = [f.body for f in self.frames if f.body >= 0]
        self.nodes = [nodes[b] for b in self.bodies]
        self.reference = np.concatenate([references[b] for b in self.bodies]) if self.bodies else np.zeros(0)
        self.onset = np.full(self.law.n_candidates, ONSET_RATE_FLOOR)

    def _frame_states(self, q: np.ndarray, q_t: np.ndarray):
        """(rotation, position, twist, lever, G) of the outer and inner element frames."""
        states = []
        for frame in self.frames:
            if frame.body < 0:
                states.append((frame.rotation, frame.offset.copy(), np.zeros(6), None, None))
                continue
            k = self.bodies.index(frame.body)
            x = q[7 * k : 7 * k + 7] + self.reference[7 * k : 7 * k + 7]
            xd = q_t[7 * k : 7 * k + 7]
            ep = x[3:]
            A = NE.quaternion_to_matrix(ep[None, :])[0]  # Exudyn's formula, valid for non-unit parameters too
            G = _ep_G(ep)
            omega = G @ xd[3:]
            lever = A @ frame.offset
            twist = np.concatenate([xd[:3] + _cross(omega, lever), omega])
            states.append((A @ frame.rotation, x[:3] + lever, twist, lever, G))
        return states

    def evaluate(self, q: np.ndarray, q_t: np.ndarray):
        (Ro, po, two, lo, Go), (Ri, pi_, twi, li, Gi) = self._frame_states(q, q_t)
        return self.law.evaluate(Ro, po, two, Ri, pi_, twi, self.onset), (lo, Go), (li, Gi)

    def force(self, mbs, t, item, q, q_t):
        result, outer, inner = self.evaluate(np.asarray(q), np.asarray(q_t))
        out = np.zeros(7 * len(self.bodies))
        for frame, (lever, G), wrench in ((self.frames[0], outer, result.wrench_outer), (self.frames[1], inner, result.wrench_inner)):
            if frame.body < 0:
                continue
            k = self.bodies.index(frame.body)
            out[7 * k : 7 * k + 3] = wrench[:3]
            out[7 * k + 3 : 7 * k + 7] = G.T @ (wrench[3:] + _cross(lever, wrench[:3]))
        return out

    def node_state(self, mbs, exu):
        q, q_t = [], []
        for node in self.nodes:
            q.append(np.asarray(mbs.GetNodeOutput(node, exu.OutputVariableType.Coordinates)))
            q_t.append(np.asarray(mbs.GetNodeOutput(node, exu.OutputVariableType.Coordinates_t)))
        return (np.concatenate(q), np.concatenate(q_t)) if q else (np.zeros(0), np.zeros(0))


class _ExudynMechanism:
    """The mechanism of a run as Exudyn items: bodies, joints, closures, drives, contact elements."""

    def __init__(self, exu, items, run: Run, ne, geometry):
        self.exu, self.I, self.run, self.ne, self.geometry = exu, items, run, ne, geometry
        self.container = exu.SystemContainer()  # owns the system: kept alive as long as this object
        self.mbs = self.container.AddSystem()
        self.ground = self.mbs.AddObject(items.ObjectGround())
        self.nodes: list = []
        self.bodies: list = []
        self.references: dict = {}
        self.drives: dict = {}
        self.elements: list = []
        self.com = {b.name: b.com for b in geometry.bodies}
        self.com[geometry.ground] = np.zeros(3)

    def add_bodies(self, y0: np.ndarray) -> None:
        """Rigid bodies with Euler-parameter nodes at the run's initial state, and gravity."""
        I, mbs = self.I, self.mbs
        r, p, v, w = self.ne.split(y0)
        for k, body in enumerate(self.geometry.bodies):
            ep = p[k] / np.linalg.norm(p[k])
            ep_t = 0.5 * _qmul(ep, np.concatenate([[0.0], w[k]]))
            reference = np.concatenate([r[k], ep])
            self.references[k] = reference
            node = mbs.AddNode(I.NodeRigidBodyEP(referenceCoordinates=list(reference), initialVelocities=list(v[k]) + list(ep_t)))
            J = body.inertia
            obj = mbs.AddObject(
                I.ObjectRigidBody(mass=body.mass, inertia=[J[0, 0], J[1, 1], J[2, 2], J[1, 2], J[0, 2], J[0, 1]], nodeNumber=node)
            )
            mbs.AddLoad(I.LoadMassProportional(markerNumber=mbs.AddMarker(I.MarkerBodyMass(bodyNumber=obj)), loadVector=list(self.run.mechanism.model.gravity.linear)))
            self.nodes.append(node)
            self.bodies.append(obj)

    def marker(self, link: str, xyz, rotation=np.eye(3)):
        """A rigid marker at the frame (``xyz``, ``rotation``) given on ``link``, on the body carrying the link."""
        carrier, xyz, rotation = self.geometry.place(link, xyz, rotation)
        k = self.geometry.body_index(carrier)
        owner = self.ground if k < 0 else self.bodies[k]
        local = self.exu.HT(rotation=rotation, translation=xyz - self.com[carrier])
        return self.mbs.AddMarker(self.I.MarkerBodyRigid(bodyNumber=owner, localHT=local))

    def add_joints(self, clearance: set, actuated: list, s0: np.ndarray) -> None:
        """Ideal tree joints (generic joints), prescribed actuator distances on the actuated prismatic joints."""
        I, mbs = self.I, self.mbs
        for joint in self.geometry.joints:
            if joint.kind == "floating" or joint.name in clearance:
                continue
            align = rotation_z_to(joint.axis)
            m0 = self.marker(joint.parent, joint.origin_xyz, joint.origin_rotation @ align)
            m1 = self.marker(joint.child, np.zeros(3), align)
            if joint.kind in ("revolute", "continuous"):
                mbs.AddObject(I.GenericJoint(markerNumbers=[m0, m1], constrainedAxes=[1, 1, 1, 1, 1, 0]))
            elif joint.kind == "prismatic":
                mbs.AddObject(I.GenericJoint(markerNumbers=[m0, m1], constrainedAxes=[1, 1, 0, 1, 1, 1]))
                if joint.name in actuated:
                    k = actuated.index(joint.name)
                    hinge0, hinge1 = self.marker(joint.parent, joint.origin_xyz), self.marker(joint.child, np.zeros(3))
                    self.drives[k] = mbs.AddObject(I.ObjectConnectorDistance(markerNumbers=[hinge0, hinge1], distance=float(s0[k])))

    def add_closures(self, clearance: set) -> None:
        """The ideal closures: spherical joints (the only ideal kind modelled: ``NE.build_model`` refuses the others)."""
        for closure in self.run.mechanism.description.closures:
            if closure.name in clearance:
                continue
            a, b = closure.parent, closure.child
            markers = [self.marker(a.link, a.xyz, rpy_matrix(a.rpy)), self.marker(b.link, b.xyz, rpy_matrix(b.rpy))]
            self.mbs.AddObject(self.I.SphericalJoint(markerNumbers=markers, constrainedAxes=[1, 1, 1]))

    def add_contacts(self) -> None:
        """Clearance joints as generic ODE2 objects whose user force is the project's contact law."""
        for site in self.ne.contacts:
            element = _ContactElement(site, self.nodes, self.references)
            size = 7 * len(element.nodes)
            self.mbs.AddObject(
                self.I.ObjectGenericODE2(nodeNumbers=element.nodes, massMatrix=np.zeros((size, size)), forceUserFunction=element.force)
            )
            self.elements.append(element)


class _Recorder:
    """End-effector position, actuator forces and contact forces after each converged step."""

    def __init__(self, built: _ExudynMechanism, n_actuators: int):
        self.built, self.n_actuators = built, n_actuators
        self.t: list = []
        self.ee: list = []
        self.origins: list = []  # (n_bodies, 3) link-frame origins per step
        self.force: list = []
        self.contact = {e.site.name: ([], []) for e in built.elements}

    def __call__(self, mbs, t: float, initial: bool = False) -> None:
        built, exu = self.built, self.built.exu
        self.t.append(t)
        self.ee.append(self.position(built.ne.ee_body, built.ne.ee_offset))
        self.origins.append([self.position(k, -body.com) for k, body in enumerate(built.geometry.bodies)])
        if initial:
            self.force.append(np.full(self.n_actuators, np.nan))
        else:
            self.force.append(np.array([-mbs.GetObjectOutput(built.drives[k], exu.OutputVariableType.Force) for k in range(self.n_actuators)]))
        for e in built.elements:
            q, q_t = e.node_state(mbs, exu)
            result, _, _ = e.evaluate(q, q_t)
            if not initial:  # after a converged step: candidates out of contact track their approach rate
                out = result.penetration <= 0.0
                e.onset[out] = np.maximum(result.penetration_rate[out], ONSET_RATE_FLOOR)
            self.contact[e.site.name][0].append(result.normal_force.copy())
            self.contact[e.site.name][1].append(result.penetration.copy())

    def position(self, body: int, offset: np.ndarray) -> np.ndarray:
        """World position of the point at ``offset`` from a body's COM (body axes); on the ground (-1) ``offset`` itself."""
        if body < 0:
            return np.array(offset, dtype=float)
        exu = self.built.exu
        return np.asarray(self.built.mbs.GetObjectOutputBody(self.built.bodies[body], exu.OutputVariableType.Position, localPosition=list(offset)))

    def contact_arrays(self) -> dict:
        return {name: {"normal_force": np.array(f), "penetration": np.array(p)} for name, (f, p) in self.contact.items()}


def _simulation_settings(exu, settings: ExudynSettings, t_end: float):
    ss = exu.SimulationSettings()
    ti = ss.timeIntegration
    ti.numberOfSteps = int(round(t_end / settings.step_size))
    ti.endTime = t_end
    ti.generalizedAlpha.spectralRadius = settings.spectral_radius
    ti.generalizedAlpha.computeInitialAccelerations = False
    ti.generalizedAlpha.resetAccelerations = False
    ti.newton.relativeTolerance = settings.newton_relative_tolerance
    ti.newton.absoluteTolerance = settings.newton_absolute_tolerance
    ti.adaptiveStep = settings.adaptive_step
    ti.verboseMode = settings.verbose
    ss.solution.file.write = False
    ss.show.computationTime = False
    return ss


def _install_step_functions(mbs, built: _ExudynMechanism, lengths, record: _Recorder) -> None:
    def pre_step(mbs, t):
        s = lengths(t)  # t is the end of the step
        for k, obj in built.drives.items():
            mbs.SetObjectParameter(obj, "distance", float(s[k]))
        return True

    def post_step(mbs, t):
        if t > record.t[-1]:  # Exudyn also calls it once at the start time
            record(mbs, t)
        return True

    mbs.SetPreStepUserFunction(pre_step)
    mbs.SetPostStepUserFunction(post_step)


def simulate(run: Run, settings: ExudynSettings = ExudynSettings(), t_end: float | None = None) -> ExudynResult:
    """Build the mechanism of ``run`` in Exudyn and integrate it over ``[0, t_end]``."""
    import exudyn as exu
    from exudyn import itemInterface as I

    started = time.perf_counter()
    t_end = run.scene.duration if t_end is None else t_end
    ne = NE.build_model(run)  # geometry, element frames and laws only (no equations of motion)
    geometry = ne.geometry
    drive = run.dynamics.drive
    actuated = list(run.mechanism.description.actuated_joints)
    lengths = actuator_lengths(drive, t_end)
    check_actuator_lengths(lengths, actuated, t_end)
    clearance = {c.joint for c in run.scene.clearances}
    built = _ExudynMechanism(exu, I, run, ne, geometry)
    built.add_bodies(NE.initial_state(ne, run))
    built.add_joints(clearance, actuated, drive.drive(0.0)[0])
    built.add_closures(clearance)
    built.add_contacts()
    record = _Recorder(built, len(actuated))
    mbs = built.mbs
    _install_step_functions(mbs, built, lengths, record)
    mbs.Assemble()
    ss = _simulation_settings(exu, settings, t_end)
    initial = consistent_accelerations(mbs, ss, kinematic_accelerations(run, geometry).ravel())
    mbs.systemData.SetODE2Coordinates_tt(list(initial), configuration=exu.ConfigurationType.Initial)
    record(mbs, 0.0, initial=True)
    success, message = True, "the integration reached the end time"
    solve_started = time.perf_counter()
    try:
        mbs.SolveDynamic(ss, solverType=exu.DynamicSolverType.GeneralizedAlpha)
    except Exception as exc:  # noqa: BLE001 - Exudyn raises its own SolverError; report, keep the steps
        success, message = False, f"{type(exc).__name__}: {exc}"
    wall = time.perf_counter() - started
    solve_time = time.perf_counter() - solve_started
    n = len(record.t)
    return ExudynResult(
        success, message, settings, np.array(record.t), np.array(record.ee), np.array(record.force).reshape(n, len(actuated)),
        record.contact_arrays(), wall, n - 1, solve_time, np.array(record.origins).reshape(n, len(geometry.bodies), 3),
    )
