"""Building a Pinocchio model of a closed-loop mechanism, with a choice of clearance joints.

A :class:`Mechanism` is the immutable description of one modelling choice: the
Pinocchio ``Model`` (the kinematic tree), its loop closures, its actuated
joints, its clearance sites and its visual/collision geometry. Algorithms take
``(mechanism, data, state)``; per-run state lives in ``pinocchio.Data`` and in
the simulator, never here.

A clearance joint imposes no kinematic constraint (seed paper, section
"Dynamics model ...": R1 and S1 "impose no kinematic constraints"):

* a **closure** chosen as clearance joint is simply not imposed: its two bodies
  interact only through contact forces (no new coordinates);
* a **tree joint** (revolute or prismatic) chosen as clearance joint becomes a
  free-flyer joint at the same origin: the child body gains the five relative
  degrees of freedom the joint used to remove (nv grows by 5).

So the model holds exactly the coordinates and constraints the choice needs.
Each clearance site gets two operational frames, ``NAME_outer`` (socket or
bearing) and ``NAME_inner`` (ball or journal); for a revolute or prismatic site
their local z is the joint axis (for a prismatic site the guide axis; local x, the
guide's width direction, is the joint frame's x made perpendicular to the axis, or its
y when the axis is within 26 deg of x: :func:`rotation_z_to`). Which body carries the outer element is a choice
(``outer_on="child"`` by default: the socket on the platform for S1 and the
bearing on the limb for R1, as in the seed paper's ADAMS model).
"""

from __future__ import annotations

import warnings
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path
from typing import Mapping, Sequence

import numpy as np
import pinocchio as pin

from robot.model.description import CLEARANCE_TREE_KINDS, ClosureDeclaration, FrameOnLink, MechanismDescription, parse_mechanism
from robot.errors import ClearanceChoiceError, ClosureDeclarationWarning, MechanismFileError, RobotWarning

CLEARANCE_SIDES = ("child", "parent")
#: how many folders above the URDF's are searched for meshes (``package://PKG/...`` with the file in ``PKG/urdf/``)
MESH_FOLDER_PARENTS = 2


class VisualGeometryWarning(RobotWarning):
    """A mesh of the URDF's visuals or collision geometry could not be loaded; the mechanism is built without it."""


@dataclass(frozen=True)
class Closure:
    """A loop closure between two operational frames of the model.

    ``spherical``: origins coincide (3 equations). ``revolute``: origins coincide
    and the z axes of the two frames stay parallel (5 equations).
    """

    name: str
    kind: str
    frame_a: int
    frame_b: int

    @property
    def n_equations(self) -> int:
        return 3 if self.kind == "spherical" else 5


@dataclass(frozen=True)
class ClearanceSite:
    """A joint (or closure) replaced by a clearance joint.

    ``outer_frame``/``inner_frame``: frame ids of the socket/bearing/guide and the
    ball/journal/slider element frames (z = joint axis for a revolute or prismatic
    site). ``kind``: ``"spherical"``, ``"revolute"`` or ``"prismatic"``.
    ``replaces`` is ``"closure"`` or ``"joint"``; for a joint, ``free_joint`` is
    the name of the free-flyer joint that replaced it.
    """

    name: str
    kind: str
    replaces: str
    outer_frame: int
    inner_frame: int
    outer_on: str
    free_joint: str | None


@dataclass(frozen=True, eq=False)
class Mechanism:
    """One modelling choice of a mechanism: tree, closures, actuators, clearance sites."""

    description: MechanismDescription
    model: pin.Model
    visual_model: pin.GeometryModel
    collision_model: pin.GeometryModel
    closures: tuple[Closure, ...]
    clearance_sites: tuple[ClearanceSite, ...]
    actuated_joints: tuple[str, ...]
    actuator_q_index: np.ndarray
    actuator_v_index: np.ndarray
    stroke_lower: np.ndarray
    stroke_upper: np.ndarray
    free_flyers: tuple[tuple[int, int], ...]

    @property
    def name(self) -> str:
        return self.description.name

    @property
    def n_closure_equations(self) -> int:
        return sum(c.n_equations for c in self.closures)

    @property
    def n_actuators(self) -> int:
        return len(self.actuated_joints)

    @property
    def clearance_names(self) -> tuple[str, ...]:
        return tuple(site.name for site in self.clearance_sites)

    def site(self, name: str) -> ClearanceSite:
        for site in self.clearance_sites:
            if site.name == name:
                return site
        raise KeyError(f"no clearance site {name!r}; sites: {self.clearance_names}")

    def frame_id(self, name: str) -> int:
        """Id of the frame ``name``; a link's BODY frame wins over a joint frame of the same name."""
        if self.model.existFrame(name, pin.FrameType.BODY):
            return self.model.getFrameId(name, pin.FrameType.BODY)
        matches = [i for i, frame in enumerate(self.model.frames) if frame.name == name]
        if not matches:
            raise KeyError(f"frame {name!r} is not in the model")
        return matches[0]

    def total_mass(self) -> float:
        return float(sum(inertia.mass for inertia in self.model.inertias))


def rotation_z_to(axis: Sequence[float]) -> np.ndarray:
    """A rotation whose third column is the unit vector ``axis`` (z mapped onto the axis)."""
    z = np.asarray(axis, dtype=float)
    z = z / np.linalg.norm(z)
    helper = np.array([1.0, 0.0, 0.0]) if abs(z[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    x = helper - z * (helper @ z)
    x /= np.linalg.norm(x)
    return np.column_stack([x, np.cross(z, x), z])


def _link_frame(model: pin.Model, frame: FrameOnLink) -> tuple[int, pin.SE3]:
    """Parent joint id and placement (in that joint) of a frame fixed to a link."""
    body = model.frames[model.getFrameId(frame.link, pin.FrameType.BODY)]
    offset = pin.SE3(pin.rpy.rpyToMatrix(*frame.rpy), np.array(frame.xyz))
    return body.parentJoint, body.placement * offset


def _add_frame(model: pin.Model, name: str, joint: int, placement: pin.SE3) -> int:
    if model.existFrame(name):
        raise MechanismFileError(f"frame name {name!r} collides with an existing frame; rename the closure or link")
    return model.addFrame(pin.Frame(name, joint, placement, pin.FrameType.OP_FRAME))


def _closure_frames(model: pin.Model, declaration: ClosureDeclaration, names: tuple[str, str]) -> tuple[int, int]:
    """Add the two frames of a closure; for a revolute one, their z is the axis."""
    joint_a, placement_a = _link_frame(model, declaration.parent)
    joint_b, placement_b = _link_frame(model, declaration.child)
    if declaration.kind == "revolute":
        align = pin.SE3(rotation_z_to(declaration.axis), np.zeros(3))
        placement_a = placement_a * align
        # the child frame's axis is the same world line when the closure is assembled:
        # express it by the relative rotation of the two link frames at q = neutral.
        data = model.createData()
        pin.forwardKinematics(model, data, pin.neutral(model))
        world_a = data.oMi[joint_a] * placement_a
        world_b = data.oMi[joint_b] * placement_b
        derived = placement_b * pin.SE3(world_b.rotation.T @ world_a.rotation, np.zeros(3))
        _check_child_axis(declaration, placement_b.rotation[:, 2], derived.rotation[:, 2])
        placement_b = derived
    return _add_frame(model, names[0], joint_a, placement_a), _add_frame(model, names[1], joint_b, placement_b)


def _check_child_axis(declaration: ClosureDeclaration, declared_axis: np.ndarray, used_axis: np.ndarray) -> None:
    """Warn when a revolute closure's child frame declares an orientation (non-zero rpy) whose z is not the axis used.

    The child-side axis is the parent's axis at the neutral configuration (docs/kinematics.md, section 2); a
    declared child orientation is not used, and if it disagrees the closure may not assemble where the file meant.
    """
    if not any(declaration.child.rpy) or np.linalg.norm(np.cross(declared_axis, used_axis)) < 1e-9:
        return
    warnings.warn(
        f"closure {declaration.name!r}: the child frame's rpy {tuple(declaration.child.rpy)} puts its z axis at "
        f"{np.round(declared_axis, 6).tolist()} in link {declaration.child.link!r}, but a revolute closure's child-side "
        f"axis is the parent's axis at the neutral configuration, {np.round(used_axis, 6).tolist()} there (docs/kinematics.md, "
        "section 2): the declared rpy is not used. Write the tree joints' origins so that the two axes are parallel "
        "at q = 0 (the positions need not meet there)",
        ClosureDeclarationWarning,
        stacklevel=4,
    )


STANDARD_GRAVITY = (0.0, 0.0, -9.81)


def _gravity_vector(gravity: Sequence[float]) -> np.ndarray:
    try:
        vector = np.asarray(gravity, dtype=float)
    except (TypeError, ValueError):
        vector = np.full(1, np.nan)
    if vector.shape != (3,) or not np.all(np.isfinite(vector)):
        raise MechanismFileError(
            f"gravity={gravity!r} must be three finite numbers [gx, gy, gz] in m/s^2 (world axes)", key="gravity", value=gravity
        )
    return vector


def _element_names(site: str, outer_on: str) -> tuple[str, str]:
    """Frame names (parent side, child side) of a clearance site's two elements."""
    return (f"{site}_inner", f"{site}_outer") if outer_on == "child" else (f"{site}_outer", f"{site}_inner")


def _normalise_choice(clearance: Sequence[str] | Mapping[str, str] | None) -> dict[str, str]:
    if clearance is None:
        return {}
    if isinstance(clearance, str):
        clearance = [c for c in clearance.split(",") if c.strip()]
    if isinstance(clearance, Mapping):
        choice = dict(clearance)
    else:
        choice = {name.strip(): "child" for name in clearance}
    for name, side in choice.items():
        if side not in CLEARANCE_SIDES:
            raise ClearanceChoiceError(
                f"clearance joint {name!r}: outer_on={side!r} is not valid; use one of {CLEARANCE_SIDES}"
            )
    return choice


def _free_joint_urdf(description: MechanismDescription, joint_names: Sequence[str]) -> str:
    """The URDF text with the named joints turned into ``floating`` joints."""
    if not joint_names:
        return description.urdf_text
    root = ET.fromstring(description.urdf_text)
    for element in root.findall("joint"):
        if element.get("name") in joint_names:
            element.set("type", "floating")
            for tag in ("axis", "limit", "dynamics", "mimic", "safety_controller"):
                for child in element.findall(tag):
                    element.remove(child)
    return ET.tostring(root, encoding="unicode")


def _clearance_tree_joints(description: MechanismDescription, choice: Mapping[str, str]) -> list[str]:
    """The tree joints of ``choice`` (the rest are closures), checked: they become free joints."""
    closure_names = {c.name for c in description.closures}
    free_joints = []
    for name in choice:
        if name in closure_names:
            continue
        joint = description.joints.get(name)
        if joint is None:
            tree = [n for n, j in description.joints.items() if j.kind in CLEARANCE_TREE_KINDS and n not in description.actuated_joints]
            raise ClearanceChoiceError(
                f"clearance joint {name!r} is neither a joint nor a closure of {description.name!r}; "
                f"joints that can carry clearance: {', '.join(sorted(tree + list(closure_names))) or 'none'}"
            )
        if joint.kind not in CLEARANCE_TREE_KINDS:
            raise ClearanceChoiceError(
                f"clearance joint {name!r} is a {joint.kind} joint; clearance is modelled for revolute and prismatic "
                "joints and spherical or revolute closures"
            )
        if name in description.actuated_joints:
            raise ClearanceChoiceError(f"clearance joint {name!r} is actuated; an actuated joint cannot carry clearance")
        free_joints.append(name)
    return free_joints


def _mesh_folders(description: MechanismDescription) -> list[str]:
    """Where Pinocchio looks for meshes: the URDF's folder (relative file names), then its parent and grandparent
    (``package://PKG/...`` of a file in ``PKG/`` or in a ROS package's ``PKG/urdf/``); none for URDF text."""
    if description.path is None:
        return []
    folder = description.path.resolve().parent
    return [str(folder)] + [str(parent) for parent in list(folder.parents)[:MESH_FOLDER_PARENTS]]


def _mesh_found(filename: str, folders: Sequence[str]) -> bool:
    """Whether a ``<mesh filename=...>`` names an existing file, resolved as Pinocchio resolves it with ``folders``."""
    if filename.startswith("package://"):
        candidates = [Path(folder) / filename[len("package://"):] for folder in folders]
    elif filename.startswith("file://"):
        candidates = [Path(filename[len("file://"):])]
    elif Path(filename).is_absolute():
        candidates = [Path(filename)]
    else:
        candidates = [Path(folder) / filename for folder in folders]
    return any(candidate.is_file() for candidate in candidates)


def _without_meshes(urdf_text: str, keep) -> tuple[str, list[str]]:
    """The URDF text without the ``<visual>``/``<collision>`` meshes ``keep(filename)`` refuses, and those dropped."""
    root = ET.fromstring(urdf_text)
    dropped = []
    for link in root.findall("link"):
        for element in link.findall("visual") + link.findall("collision"):
            mesh = element.find("geometry/mesh")
            if mesh is not None and not keep(mesh.get("filename", "")):
                link.remove(element)
                dropped.append(f"{mesh.get('filename', '')!r} of link {link.get('name')!r}")
    return ET.tostring(root, encoding="unicode"), list(dict.fromkeys(dropped))


def _one_line(exc: Exception) -> str:
    """A library's message on one line, without its final full stop (it is quoted inside ours)."""
    return " ".join(str(exc).split()).rstrip(".")


def _geometry_models(model: pin.Model, urdf_text: str, folders: Sequence[str]) -> tuple[pin.GeometryModel, pin.GeometryModel]:
    extra = {"package_dirs": list(folders)} if folders else {}
    return (
        pin.buildGeomFromUrdfString(model, urdf_text, pin.GeometryType.VISUAL, **extra),
        pin.buildGeomFromUrdfString(model, urdf_text, pin.GeometryType.COLLISION, **extra),
    )


def _geometry_without_failing_meshes(
    model: pin.Model, description: MechanismDescription, urdf_text: str
) -> tuple[pin.GeometryModel, pin.GeometryModel]:
    """The visual and collision models; a mesh that cannot be loaded is left out with one warning.

    Only the animation draws these geometries (the dynamics use the inertias), so a missing or
    unreadable mesh must not stop a run or ``describe``. The meshes not found are dropped first;
    if the rest still fails (e.g. a corrupt file), every mesh is.
    """
    folders = _mesh_folders(description)
    try:
        return _geometry_models(model, urdf_text, folders)
    except (RuntimeError, ValueError) as exc:
        error = _one_line(exc)
    for keep in (lambda filename: _mesh_found(filename, folders), lambda filename: False):
        text, dropped = _without_meshes(urdf_text, keep)
        if not dropped:
            continue
        try:
            geometry = _geometry_models(model, text, folders)
        except (RuntimeError, ValueError) as exc:
            error = _one_line(exc)
            continue
        searched = f"searched {', '.join(folders)}" if folders else "no folder to search: URDF given as text"
        warnings.warn(
            f"mechanism {description.name!r}: left out the mesh(es) {', '.join(dropped)}, which could not be loaded "
            f"({error}; {searched}); the dynamics do not use them, the animation draws those links without them",
            VisualGeometryWarning,
            stacklevel=4,
        )
        return geometry
    raise MechanismFileError(f"geometry of {description.name!r} could not be built: {error}")


def _pinocchio_models(
    description: MechanismDescription, urdf_text: str, gravity: Sequence[float]
) -> tuple[pin.Model, pin.GeometryModel, pin.GeometryModel]:
    try:
        model = pin.buildModelFromXML(urdf_text)
    except (RuntimeError, ValueError) as exc:
        raise MechanismFileError(f"Pinocchio could not build the model of {description.name!r}: {exc}") from None
    model.gravity = pin.Motion(_gravity_vector(gravity), np.zeros(3))
    visual_model, collision_model = _geometry_without_failing_meshes(model, description, urdf_text)
    return model, visual_model, collision_model


def _site(name: str, kind: str, where: str, outer_on: str, parent_side: int, child_side: int, joint: str | None) -> ClearanceSite:
    outer, inner = (child_side, parent_side) if outer_on == "child" else (parent_side, child_side)
    return ClearanceSite(name, kind, where, outer, inner, outer_on, joint)


def _closures_and_sites(model: pin.Model, description: MechanismDescription, choice: Mapping[str, str], free_joints: list[str]):
    """Ideal closures (frame pairs) and clearance sites (element frames) added to ``model``."""
    closures, sites = [], []
    for declaration in description.closures:
        if declaration.name in choice:
            names = _element_names(declaration.name, choice[declaration.name])
            parent_side, child_side = _closure_frames(model, declaration, names)
            sites.append(_site(declaration.name, declaration.kind, "closure", choice[declaration.name], parent_side, child_side, None))
        else:
            frame_a, frame_b = _closure_frames(model, declaration, (f"{declaration.name}_parent", f"{declaration.name}_child"))
            closures.append(Closure(declaration.name, declaration.kind, frame_a, frame_b))
    for name in free_joints:
        free_id = model.getJointId(name)
        align = pin.SE3(rotation_z_to(description.joints[name].axis), np.zeros(3))
        names = _element_names(name, choice[name])
        parent_side = _add_frame(model, names[0], model.parents[free_id], model.jointPlacements[free_id] * align)
        child_side = _add_frame(model, names[1], free_id, align)
        kind = CLEARANCE_TREE_KINDS[description.joints[name].kind]
        sites.append(_site(name, kind, "joint", choice[name], parent_side, child_side, name))
    return closures, sites


def _actuators(model: pin.Model, description: MechanismDescription) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Coordinate and velocity indices of the actuated joints, and their stroke limits."""
    q_index, v_index, lower, upper = [], [], [], []
    for name in description.actuated_joints:
        joint_id = model.getJointId(name)
        if model.nqs[joint_id] != 1 or model.nvs[joint_id] != 1:
            raise MechanismFileError(
                f"actuated joint {name!r} is a {description.joints[name].kind} joint stored by Pinocchio with "
                f"nq = {model.nqs[joint_id]} (cos, sin): a driving constraint needs one coordinate; declare it "
                "'revolute' with wide limits (e.g. lower=\"-1e4\" upper=\"1e4\") to prescribe its angle"
            )
        q_index.append(model.idx_qs[joint_id])
        v_index.append(model.idx_vs[joint_id])
        declaration = description.joints[name]
        lower.append(-np.inf if declaration.lower is None else declaration.lower)
        upper.append(np.inf if declaration.upper is None else declaration.upper)
    return np.array(q_index, dtype=int), np.array(v_index, dtype=int), np.array(lower), np.array(upper)


def build_mechanism(
    source: str | Path | MechanismDescription,
    clearance: Sequence[str] | Mapping[str, str] | str | None = None,
    gravity: Sequence[float] = STANDARD_GRAVITY,
) -> Mechanism:
    """Load a URDF with closure declarations into a :class:`Mechanism`.

    Parameters
    ----------
    source:
        Path of the URDF file, or an already parsed :class:`MechanismDescription`.
    clearance:
        Names of the joints or closures that carry clearance (``["R1", "S1"]`` or
        ``"R1,S1"``), or a mapping name -> ``outer_on`` (``"child"`` or
        ``"parent"``: which body carries the socket/bearing). Revolute tree
        joints and spherical or revolute closures can carry clearance.
    gravity:
        Gravitational acceleration in world axes (m/s^2), set as the Pinocchio
        model's ``gravity`` (used by ``nonLinearEffects``, RNEA and the potential
        energy). Default ``[0, 0, -9.81]``.
    """
    description = source if isinstance(source, MechanismDescription) else parse_mechanism(source)
    choice = _normalise_choice(clearance)
    free_joints = _clearance_tree_joints(description, choice)
    model, visual_model, collision_model = _pinocchio_models(description, _free_joint_urdf(description, free_joints), gravity)
    closures, sites = _closures_and_sites(model, description, choice, free_joints)
    q_index, v_index, lower, upper = _actuators(model, description)
    free_flyers = tuple(
        (model.idx_qs[j], model.idx_vs[j]) for j in range(1, model.njoints) if model.joints[j].shortname() == "JointModelFreeFlyer"
    )
    return Mechanism(
        description=description,
        model=model,
        visual_model=visual_model,
        collision_model=collision_model,
        closures=tuple(closures),
        clearance_sites=tuple(sites),
        actuated_joints=description.actuated_joints,
        actuator_q_index=q_index,
        actuator_v_index=v_index,
        stroke_lower=lower,
        stroke_upper=upper,
        free_flyers=free_flyers,
    )
