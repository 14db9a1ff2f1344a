"""A readable summary of a :class:`~robot.model.mechanism.Mechanism`: bodies, joints, closures, mobility.

``summarize(mechanism)`` returns a :class:`MechanismSummary` (plain data);
``describe(mechanism)`` its text rendering (``scripts/describe_model.py``).

Mobility is reported twice:

* **Grubler-Kutzbach count** ``6 n - sum(c_j)``: ``n`` moving bodies (one per
  joint of the Pinocchio tree), ``c_j`` the constraints of each tree joint
  (``6 - nv_j``: revolute and prismatic 5, free-flyer 0) and of each imposed
  closure (spherical 3, revolute 5). A clearance joint imposes nothing, so it
  counts as removed constraints. Since ``n`` equals the number of tree joints the
  count is also ``nv - (closure equations)``. Driven: minus one per actuator.
* **numerical mobility** ``nv - rank(Phi_q)`` at an assembled configuration
  (:func:`robot.model.kinematics.mobility`), with the actuators free (closures only) and
  driven (closures plus one driving row per actuator). It differs from the count
  when equations are redundant (overconstrained mechanisms) or at singular
  configurations. The redundant closure equations are listed by name
  (:func:`robot.model.redundancy.detect`, e.g. ``K:z, K:rot_x, K:rot_y``).

The configuration: for a UPS/RPS platform (:class:`~robot.model.platform_kinematics.PlatformLayout`)
the inverse kinematics of the home pose ``[x0, z0, 0, 0, 0]`` (``x0, z0`` from
the origin of the platform's floating joint), otherwise the neutral
configuration; then :func:`robot.model.kinematics.assemble` with the closures and the
centring equations of the clearance sites (ball centred in its socket, journal
axis on the bearing axis), actuators free.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from robot.model import constraints as C
from robot.model import kinematics as K
from robot.model import redundancy as R
from robot.errors import KinematicsError
from robot.model.mechanism import Mechanism

_JOINT_KINDS = {
    "JointModelRX": "revolute",
    "JointModelRY": "revolute",
    "JointModelRZ": "revolute",
    "JointModelRevoluteUnaligned": "revolute",
    "JointModelRUBX": "continuous",
    "JointModelRUBY": "continuous",
    "JointModelRUBZ": "continuous",
    "JointModelRevoluteUnboundedUnaligned": "continuous",
    "JointModelPX": "prismatic",
    "JointModelPY": "prismatic",
    "JointModelPZ": "prismatic",
    "JointModelPrismaticUnaligned": "prismatic",
    "JointModelFreeFlyer": "free-flyer",
    "JointModelSpherical": "spherical",
    "JointModelSphericalZYX": "spherical",
    "JointModelPlanar": "planar",
    "JointModelTranslation": "translation",
}


@dataclass(frozen=True)
class BodyInfo:
    """A URDF link: its mass and the tree joint that carries it (``None``: fixed to the ground)."""

    name: str
    mass: float
    joint: str | None


@dataclass(frozen=True)
class JointInfo:
    """A joint of the Pinocchio tree (after the clearance choice)."""

    name: str
    kind: str
    urdf_kind: str | None
    nq: int
    nv: int
    actuated: bool
    clearance: bool

    @property
    def n_constraints(self) -> int:
        """Constraints the joint imposes between its two bodies (6 - nv)."""
        return 6 - self.nv


@dataclass(frozen=True)
class ClosureInfo:
    """A loop closure declared in the file; ``imposed`` is False when it carries clearance."""

    name: str
    kind: str
    parent_link: str
    child_link: str
    n_equations: int
    imposed: bool


@dataclass(frozen=True)
class ClearanceInfo:
    """A clearance site: what it replaces, which body holds the outer element, its frames."""

    name: str
    kind: str
    replaces: str
    outer_on: str
    outer_frame: str
    inner_frame: str
    released: int


@dataclass(frozen=True)
class MechanismSummary:
    """Everything :func:`describe` prints, as data."""

    name: str
    source: str
    bodies: tuple[BodyInfo, ...]
    joints: tuple[JointInfo, ...]
    closures: tuple[ClosureInfo, ...]
    actuated_joints: tuple[str, ...]
    clearance_sites: tuple[ClearanceInfo, ...]
    nq: int
    nv: int
    n_moving_bodies: int
    n_closure_equations: int
    grubler_free: int
    grubler_driven: int
    configuration: str
    assembly_residual: float | None
    rank_free: int | None
    rank_driven: int | None
    mobility_free: int | None
    mobility_driven: int | None
    redundant_equations: tuple[str, ...] | None  # closure rows dependent on the others (robot.model.redundancy)
    moving_mass: float
    fixed_mass: float

    @property
    def total_mass(self) -> float:
        return self.moving_mass + self.fixed_mass

    def text(self) -> str:
        return render(self)


def _link_masses(urdf_text: str) -> dict[str, float]:
    root = ET.fromstring(urdf_text)
    masses = {}
    for link in root.findall("link"):
        mass = link.find("inertial/mass")
        masses[link.get("name")] = float(mass.get("value", "0")) if mass is not None else 0.0
    return masses


def grubler_kutzbach(mechanism: Mechanism) -> tuple[int, int]:
    """Spatial Grubler-Kutzbach count ``6 n - sum(c_j)``: (actuators free, actuators driven)."""
    model = mechanism.model
    n_bodies = model.njoints - 1
    tree_constraints = sum(6 - model.nvs[j] for j in range(1, model.njoints))
    free = 6 * n_bodies - tree_constraints - mechanism.n_closure_equations
    return free, free - mechanism.n_actuators


def reference_configuration(mechanism: Mechanism) -> tuple[np.ndarray, str]:
    """An initial guess for the assembly and how it was obtained (see module docstring)."""
    from robot.model.platform_kinematics import PlatformLayout, inverse_kinematics

    model = mechanism.model
    try:
        layout = PlatformLayout.from_mechanism(mechanism)
    except KinematicsError:
        return pin.neutral(model), "assembled from the neutral configuration, actuators free"
    origin = model.jointPlacements[layout.platform_joint].translation
    home = np.array([origin[0], origin[2], 0.0, 0.0, 0.0])
    q, _ = inverse_kinematics(layout, home)
    pose = ", ".join(f"{x:g}" for x in home)
    return q, f"inverse kinematics of the home pose [x, z, roll, pitch, yaw] = [{pose}], then assembled"


def _bodies(mechanism: Mechanism) -> tuple[BodyInfo, ...]:
    model, description = mechanism.model, mechanism.description
    masses = _link_masses(description.urdf_text)
    bodies = []
    for link in description.links:
        frame = model.frames[model.getFrameId(link, pin.FrameType.BODY)]
        joint = model.names[frame.parentJoint] if frame.parentJoint != 0 else None
        bodies.append(BodyInfo(link, masses.get(link, 0.0), joint))
    return tuple(bodies)


def _joints(mechanism: Mechanism) -> tuple[JointInfo, ...]:
    model, description = mechanism.model, mechanism.description
    clearance_joints = {s.name for s in mechanism.clearance_sites if s.replaces == "joint"}
    joints = []
    for j in range(1, model.njoints):
        name = model.names[j]
        declaration = description.joints.get(name)
        shortname = model.joints[j].shortname()
        joints.append(
            JointInfo(
                name, _JOINT_KINDS.get(shortname, shortname), declaration.kind if declaration else None, model.nqs[j], model.nvs[j],
                name in mechanism.actuated_joints, name in clearance_joints,
            )
        )  # fmt: skip
    return tuple(joints)


def _closures_and_sites(mechanism: Mechanism) -> tuple[tuple[ClosureInfo, ...], tuple[ClearanceInfo, ...]]:
    model = mechanism.model
    imposed = {c.name for c in mechanism.closures}
    closures = tuple(
        ClosureInfo(c.name, c.kind, c.parent.link, c.child.link, 3 if c.kind == "spherical" else 5, c.name in imposed)
        for c in mechanism.description.closures
    )
    sites = tuple(
        ClearanceInfo(
            s.name, s.kind, s.replaces, s.outer_on, model.frames[s.outer_frame].name, model.frames[s.inner_frame].name,
            3 if s.kind == "spherical" else 5,
        )
        for s in mechanism.clearance_sites
    )  # fmt: skip
    return closures, sites


def _configuration(mechanism: Mechanism, q: np.ndarray | None) -> tuple[np.ndarray | None, str, float | None]:
    """The configuration the ranks are taken at (assembled when not given), its description and closure residual."""
    if q is None:
        try:
            guess, configuration = reference_configuration(mechanism)
            assembly = K.assemble(C.constraint_set(mechanism, driven=False, centre_clearance=True), guess)
            return assembly.q, configuration, assembly.residual_norm
        except KinematicsError as exc:
            return None, f"no assembled configuration ({exc})", None
    data = mechanism.model.createData()
    K.update_kinematics(mechanism.model, data, q)
    phi = C.residual(C.constraint_set(mechanism, driven=False), data, q, None)
    return q, "the configuration given by the caller", float(np.max(np.abs(phi))) if phi.size else 0.0


def summarize(mechanism: Mechanism, q: np.ndarray | None = None) -> MechanismSummary:
    """Summary of ``mechanism``; mobility at ``q`` (assembled here when not given)."""
    model = mechanism.model
    closures, sites = _closures_and_sites(mechanism)
    grubler_free, grubler_driven = grubler_kutzbach(mechanism)
    q, configuration, residual = _configuration(mechanism, q)
    rank_free = rank_driven = mobility_free = mobility_driven = redundant = None
    if q is not None:
        mobility_free = K.mobility(C.constraint_set(mechanism, driven=False), q)
        mobility_driven = K.mobility(C.constraint_set(mechanism, driven=True), q)
        rank_free, rank_driven = model.nv - mobility_free, model.nv - mobility_driven
        redundant = _redundant_equations(mechanism, q)
    return MechanismSummary(
        name=mechanism.name,
        source=str(mechanism.description.path) if mechanism.description.path else "<urdf text>",
        bodies=_bodies(mechanism),
        joints=_joints(mechanism),
        closures=closures,
        actuated_joints=mechanism.actuated_joints,
        clearance_sites=sites,
        nq=model.nq,
        nv=model.nv,
        n_moving_bodies=model.njoints - 1,
        n_closure_equations=mechanism.n_closure_equations,
        grubler_free=grubler_free,
        grubler_driven=grubler_driven,
        configuration=configuration,
        assembly_residual=residual,
        rank_free=rank_free,
        rank_driven=rank_driven,
        mobility_free=mobility_free,
        mobility_driven=mobility_driven,
        redundant_equations=redundant,
        moving_mass=float(sum(inertia.mass for inertia in model.inertias[1:])),
        fixed_mass=float(model.inertias[0].mass),
    )


def _redundant_equations(mechanism: Mechanism, q: np.ndarray) -> tuple[str, ...]:
    """Names of the closure equations that depend on the others at q (actuators free)."""
    constraints = C.constraint_set(mechanism, driven=False)
    data = mechanism.model.createData()
    K.update_kinematics(mechanism.model, data, q)
    return R.detect(constraints, mechanism.model, data, C.jacobian(constraints, mechanism.model, data), warn=False).labels


def render(summary: MechanismSummary) -> str:
    """The text of :func:`describe`."""
    s = summary
    lines = [f"Mechanism {s.name!r} ({s.source})"]
    lines.append(f"Clearance joints: {', '.join(c.name for c in s.clearance_sites) or 'none (ideal joints)'}")
    lines.append("")
    lines.append(f"Bodies: {s.n_moving_bodies} moving (one per tree joint), links:")
    lines.append(f"  {'link':<18} {'mass [kg]':>10}  carried by joint")
    for b in s.bodies:
        lines.append(f"  {b.name:<18} {b.mass:>10.4g}  {b.joint or '(fixed to the ground)'}")
    lines.append("")
    lines.append("Joints of the tree:")
    lines.append(f"  {'name':<14} {'type':<12} {'nq':>3} {'nv':>3} {'constraints':>11}  notes")
    for j in s.joints:
        notes = []
        if j.actuated:
            notes.append("actuated")
        if j.clearance:
            notes.append(f"clearance joint (URDF {j.urdf_kind}, ideal joint replaced by a free-flyer)")
        elif j.urdf_kind and j.urdf_kind != j.kind and not (j.urdf_kind == "floating" and j.kind == "free-flyer"):
            notes.append(f"URDF {j.urdf_kind}")
        lines.append(f"  {j.name:<14} {j.kind:<12} {j.nq:>3} {j.nv:>3} {j.n_constraints:>11}  {', '.join(notes)}")
    lines.append("")
    lines.append("Loop closures:")
    if not s.closures:
        lines.append("  none")
    for c in s.closures:
        state = f"{c.n_equations} equations" if c.imposed else "not imposed (clearance joint)"
        lines.append(f"  {c.name:<6} {c.kind:<10} {c.parent_link} -- {c.child_link}: {state}")
    lines.append("")
    lines.append(f"Actuated joints ({len(s.actuated_joints)}): {', '.join(s.actuated_joints) or 'none'}")
    lines.append("Clearance sites:")
    if not s.clearance_sites:
        lines.append("  none")
    for c in s.clearance_sites:
        lines.append(
            f"  {c.name:<6} {c.kind:<10} replaces a {c.replaces}, releases {c.released} constraints; "
            f"outer element on the {c.outer_on} body (frames {c.outer_frame}, {c.inner_frame})"
        )
    lines.append("")
    n_actuators = len(s.actuated_joints)
    tree = sum(j.n_constraints for j in s.joints)
    lines.append(f"Coordinates: nq = {s.nq}, nv = {s.nv}")
    lines.append(f"Equations: closures {s.n_closure_equations}, driving {n_actuators}")
    lines.append(
        f"Grubler-Kutzbach: 6 x {s.n_moving_bodies} - {tree} (tree joints) - {s.n_closure_equations} (closures) = "
        f"{s.grubler_free} with actuators free, {s.grubler_driven} driven"
    )
    if s.mobility_free is None:
        lines.append(f"Numerical mobility: not computed: {s.configuration}")
    else:
        lines.append(
            f"Numerical mobility (nv - rank Phi_q): {s.mobility_free} with actuators free (rank {s.rank_free}), "
            f"{s.mobility_driven} driven (rank {s.rank_driven})"
        )
        residual = "" if s.assembly_residual is None else f"; closure residual {s.assembly_residual:.1e} m"
        lines.append(f"  at: {s.configuration}{residual}")
        redundant = ", ".join(s.redundant_equations) or "none"
        lines.append(
            f"Redundant closure equations (dependent on the others, relative tolerance {R.REDUNDANCY_TOLERANCE:.0e}): "
            f"{len(s.redundant_equations)}: {redundant}"
        )
    lines.append(f"Total mass: {s.total_mass:.6g} kg (moving {s.moving_mass:.6g} kg, fixed to the ground {s.fixed_mass:.6g} kg)")
    return "\n".join(lines) + "\n"


def describe(mechanism: Mechanism) -> str:
    """Text summary of ``mechanism`` (bodies, joints, closures, actuators, clearance, mobility, mass)."""
    return summarize(mechanism).text()
