"""Reading a URDF file with the project's closure declarations.

URDF has no spherical joints and no kinematic loops. This project declares loop
closures in a custom ``<closures>`` element of the same file (Pinocchio and
yourdfpy ignore unknown elements)::

    <closures>
      <closure name="S1" type="spherical">
        <parent link="limb5_piston" xyz="0 0 0" rpy="0 0 0"/>
        <child  link="platform"     xyz="0 0 0" rpy="0 0 0"/>
      </closure>
      <closure name="K" type="revolute">
        <parent link="rod" xyz="..."/> <child link="slider" xyz="..."/>
        <axis xyz="0 0 1"/>                 <!-- in the parent frame -->
      </closure>
    </closures>

Actuated joints are the joints named in standard ``<transmission>`` elements, in
file order. This module only parses and validates; it builds no model.

Masses and inertias are checked here (Pinocchio and urdfdom take any number, NaN
included, and a run would fail later in the solver): an ``<inertial>`` element
needs a finite mass >= 0 and a finite, positive semi-definite inertia (zero for a
point mass, one zero moment for a thin rod); moments that break the triangle
inequalities (Ixx + Iyy >= Izz and permutations, in the given and the principal
axes, beyond 2 % of the trace) are warned about (``InertiaWarning``), not refused:
files often give only the moment that matters, e.g. izz of a planar link. A link
without ``<inertial>``, or with mass and inertia 0, is massless, which URDF allows
(a ground or world link, a tool frame, the cross of a universal joint); but a
movable joint must carry some mass: if no link of its subtree has mass or
inertia, the mass matrix is singular and the file is refused.
"""

from __future__ import annotations

import math
import warnings
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from robot.errors import InertiaWarning, MechanismFileError

CLOSURE_TYPES = ("spherical", "revolute")
#: URDF kinds of tree joints that can carry clearance -> the kind of clearance site they make
CLEARANCE_TREE_KINDS = {"revolute": "revolute", "continuous": "revolute", "prismatic": "prismatic"}
#: URDF kinds of joints that move their child (a "fixed" joint merges it into its parent)
MOVABLE_KINDS = ("revolute", "continuous", "prismatic", "floating", "planar")
#: the six components of a URDF ``<inertia>`` element (kg m^2)
INERTIA_COMPONENTS = ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")
#: slack of the triangle inequalities, relative to the trace (moments rounded to a few digits, e.g. a thin plate's)
TRIANGLE_SLACK = 2e-2
#: a principal moment below -this x the largest is negative beyond rounding (a point mass or a thin rod has zeros)
NEGATIVE_MOMENT_RATIO = 1e-9
#: ... or below -this (kg m^2): exporters' noise on a zero inertia
NEGATIVE_MOMENT_FLOOR = 1e-12
#: the valid range of an inertia, for the messages
INERTIA_RANGE = (
    "valid: a positive semi-definite matrix (zero for a point mass) whose moments satisfy the triangle "
    "inequalities Ixx + Iyy >= Izz, Iyy + Izz >= Ixx, Izz + Ixx >= Iyy"
)


@dataclass(frozen=True)
class FrameOnLink:
    """A frame fixed to a link: translation ``xyz`` and URDF roll-pitch-yaw ``rpy``."""

    link: str
    xyz: tuple[float, float, float]
    rpy: tuple[float, float, float]


@dataclass(frozen=True)
class ClosureDeclaration:
    """A loop-closing joint between frames on two links (``<closure>`` element)."""

    name: str
    kind: str
    parent: FrameOnLink
    child: FrameOnLink
    axis: tuple[float, float, float] | None  # revolute: unit axis in the parent frame


@dataclass(frozen=True)
class JointDeclaration:
    """The parts of a URDF ``<joint>`` the project needs beyond Pinocchio's model."""

    name: str
    kind: str
    parent: str
    child: str
    axis: tuple[float, float, float]
    lower: float | None
    upper: float | None


@dataclass(frozen=True)
class MechanismDescription:
    """A parsed mechanism file: URDF text, joints, closures and actuated joints."""

    path: Path | None
    name: str
    urdf_text: str
    links: tuple[str, ...]
    joints: dict[str, JointDeclaration]
    closures: tuple[ClosureDeclaration, ...]
    actuated_joints: tuple[str, ...]


def _vector(element: ET.Element, attribute: str, where: str, default: str = "0 0 0") -> tuple[float, float, float]:
    text = element.get(attribute, default)
    try:
        values = tuple(float(x) for x in text.split())
    except ValueError:
        raise MechanismFileError(f"{where}: attribute {attribute}={text!r} must be three numbers") from None
    if len(values) != 3 or not all(np.isfinite(values)):
        raise MechanismFileError(f"{where}: attribute {attribute}={text!r} must be three finite numbers")
    return values  # type: ignore[return-value]


def _frame(element: ET.Element | None, role: str, closure: str, links: set[str], label: str) -> FrameOnLink:
    where = f"{label}: closure {closure!r}"
    if element is None:
        raise MechanismFileError(f"{where}: missing <{role} link=... xyz=... rpy=...> element")
    link = element.get("link")
    if link is None:
        raise MechanismFileError(f"{where}: <{role}> has no 'link' attribute")
    if link not in links:
        raise MechanismFileError(
            f"{where}: <{role} link={link!r}> names a link that is not in the URDF "
            f"(links: {', '.join(sorted(links))})"
        )
    return FrameOnLink(link, _vector(element, "xyz", f"{where} <{role}>"), _vector(element, "rpy", f"{where} <{role}>"))


def _read_text(source: str | Path, is_text: bool) -> tuple[str, Path | None]:
    if is_text:
        return str(source), None
    path = Path(source)
    if not path.is_file():
        raise MechanismFileError(f"mechanism file {str(path)!r} does not exist")
    return path.read_text(encoding="utf-8"), path


def _links(root: ET.Element, label: str) -> list[str]:
    links = [link.get("name", "") for link in root.findall("link")]
    if "" in links:
        raise MechanismFileError(f"{label}: a <link> has no name")
    if len(set(links)) != len(links):
        raise MechanismFileError(f"{label}: duplicate link names")
    return links


def _number(text: str | None) -> float:
    """``float(text)``; NaN for a missing or non-numeric text (refused by the checks as not finite)."""
    try:
        return float(text) if text is not None else math.nan
    except ValueError:
        return math.nan


def _check_mass(inertial: ET.Element, link: str, where: str) -> float:
    """The link's mass (kg): finite and >= 0 (0 with a zero inertia is how many exporters write a massless frame)."""
    element = inertial.find("mass")
    text = element.get("value") if element is not None else None
    if text is None:
        raise MechanismFileError(
            f"{where}: <inertial> has no <mass value=...>; give the mass in kg (a finite number >= 0), "
            "or leave out the whole <inertial> element of a massless link (a frame)", key=f"{link}.mass",
        )
    value = _number(text)
    if not (math.isfinite(value) and value >= 0.0):
        raise MechanismFileError(
            f"{where}: mass={text!r} is outside the valid range: a finite number >= 0 (kg; 0 or no <inertial> "
            "element: a massless link)", key=f"{link}.mass", value=text,
        )
    return value


def _inertia_values(inertial: ET.Element, link: str, where: str) -> dict[str, float]:
    """The six components of an ``<inertial>``'s ``<inertia>`` (each present and finite)."""
    element = inertial.find("inertia")
    if element is None:
        raise MechanismFileError(f"{where}: <inertial> has no <inertia ixx=... ixy=... ixz=... iyy=... iyz=... izz=...> (kg m^2)", key=f"{link}.inertia")
    values = {}
    for name in INERTIA_COMPONENTS:
        text = element.get(name)
        values[name] = _number(text)
        if not math.isfinite(values[name]):
            what = f"{name}={text!r} must be" if text is not None else f"attribute {name} is missing; it must be"
            raise MechanismFileError(f"{where}: <inertia> {what} a finite number (kg m^2)", key=f"{link}.inertia.{name}", value=text)
    return values


def _triangle_violation(moments) -> str | None:
    """The first of I1 + I2 >= I3 (and permutations) that ``moments`` break beyond the rounding slack, as text."""
    slack = max(TRIANGLE_SLACK * float(np.sum(moments)), NEGATIVE_MOMENT_FLOOR)
    for i, j, k in ((0, 1, 2), (1, 2, 0), (2, 0, 1)):
        if moments[i] + moments[j] < moments[k] - slack:
            return f"{moments[i]:.6g} + {moments[j]:.6g} < {moments[k]:.6g}"
    return None


def _check_inertia(inertial: ET.Element, link: str, where: str) -> float:
    """The trace of the link's inertia: finite components, no negative principal moment beyond rounding; a broken
    triangle inequality is warned about (files often give only the moment that matters, e.g. izz of a planar link)."""
    values = _inertia_values(inertial, link, where)
    given = ", ".join(f"{name}={value:g}" for name, value in values.items())
    matrix = np.array([
        [values["ixx"], values["ixy"], values["ixz"]],
        [values["ixy"], values["iyy"], values["iyz"]],
        [values["ixz"], values["iyz"], values["izz"]],
    ])  # fmt: skip
    principal = np.linalg.eigvalsh(matrix)  # ascending
    if principal[0] < -max(NEGATIVE_MOMENT_RATIO * principal[-1], NEGATIVE_MOMENT_FLOOR):
        moments = ", ".join(f"{m:.6g}" for m in principal)
        raise MechanismFileError(
            f"{where}: inertia ({given}) has a negative principal moment ({moments} kg m^2); {INERTIA_RANGE}",
            key=f"{link}.inertia", value=given,
        )
    # the given axes first (the numbers of the file); the principal axes catch what products of inertia hide
    for axes, moments in (("", np.diag(matrix)), ("principal moments: ", principal)):
        broken = _triangle_violation(moments)
        if broken is not None:
            warnings.warn(
                f"{where}: inertia ({given}) breaks the triangle inequality ({axes}{broken} kg m^2): no rigid body "
                "has these moments; the run uses them as given", InertiaWarning, stacklevel=2,
            )
            break
    return float(np.trace(matrix))


def _massive_links(root: ET.Element, label: str) -> set[str]:
    """The links with mass or inertia (an ``<inertial>`` element not all zero), each ``<inertial>`` checked."""
    massive = set()
    for element in root.findall("link"):
        inertial = element.find("inertial")
        if inertial is None:
            continue
        name = element.get("name", "")
        where = f"{label}: link {name!r}"
        mass = _check_mass(inertial, name, where)
        trace = _check_inertia(inertial, name, where)
        origin = inertial.find("origin")
        if origin is not None:
            _vector(origin, "xyz", f"{where} <inertial><origin>")
            _vector(origin, "rpy", f"{where} <inertial><origin>")
        if mass > 0.0 or trace > 0.0:  # mass 0 and inertia 0: a massless frame written out
            massive.add(name)
    return massive


def _subtree_links(link: str, children: dict[str, list[str]]) -> list[str]:
    """``link`` and every link below it in the tree of joints (each once, whatever loops the file has)."""
    found, stack = [], [link]
    while stack:
        current = stack.pop()
        if current not in found:
            found.append(current)
            stack.extend(children.get(current, ()))
    return found


def _children(joints: dict[str, JointDeclaration]) -> dict[str, list[str]]:
    """Each link's child links, in the file's order of the joints."""
    children: dict[str, list[str]] = {}
    for joint in joints.values():
        children.setdefault(joint.parent, []).append(joint.child)
    return children


def _check_moving_bodies_have_mass(joints: dict[str, JointDeclaration], massive: set[str], label: str) -> None:
    """Refuse a movable joint whose subtree has no mass or inertia: a singular mass matrix."""
    children = _children(joints)
    for joint in joints.values():
        if joint.kind not in MOVABLE_KINDS:
            continue
        carried = _subtree_links(joint.child, children)
        if not massive.intersection(carried):
            raise MechanismFileError(
                f"{label}: joint {joint.name!r} ({joint.kind}) moves link(s) {', '.join(carried)}, none of which has mass "
                "or inertia (no <inertial> element, or zeros): the body it moves has zero mass and zero inertia, so the mass matrix is singular; "
                "give one of them an <inertial> (mass > 0) or make the joint fixed",
                key=joint.name, value=tuple(carried),
            )


def _limits(element: ET.Element, name: str, kind: str, label: str) -> tuple[float | None, float | None]:
    limit = element.find("limit")
    if limit is None or kind not in ("prismatic", "revolute"):
        return None, None
    try:
        lower = float(limit.get("lower", "nan"))
        upper = float(limit.get("upper", "nan"))
    except ValueError:
        raise MechanismFileError(f"{label}: joint {name!r} has non-numeric limits") from None
    return (None if np.isnan(lower) else lower), (None if np.isnan(upper) else upper)


#: the joint types of the URDF specification (what urdfdom, and so Pinocchio, accepts)
URDF_JOINT_TYPES = ("revolute", "continuous", "prismatic", "fixed", "floating", "planar")


def _joints(root: ET.Element, link_set: set[str], label: str) -> dict[str, JointDeclaration]:
    joints: dict[str, JointDeclaration] = {}
    for element in root.findall("joint"):
        name = element.get("name")
        kind = element.get("type")
        parent = element.find("parent")
        child = element.find("child")
        if not name or not kind or parent is None or child is None:
            raise MechanismFileError(f"{label}: joint {name!r} needs name, type, <parent> and <child>")
        if name in joints:
            raise MechanismFileError(f"{label}: duplicate joint name {name!r}")
        if kind not in URDF_JOINT_TYPES:
            raise MechanismFileError(f"{label}: joint {name!r} has type={kind!r}; URDF joint types: {', '.join(URDF_JOINT_TYPES)}")
        for role, link in (("parent", parent.get("link")), ("child", child.get("link"))):
            if link not in link_set:
                raise MechanismFileError(f"{label}: joint {name!r} {role} link {link!r} is not defined")
        axis_element = element.find("axis")
        axis = _vector(axis_element, "xyz", f"joint {name!r} <axis>", "1 0 0") if axis_element is not None else (1.0, 0.0, 0.0)
        lower, upper = _limits(element, name, kind, label)
        joints[name] = JointDeclaration(name, kind, parent.get("link"), child.get("link"), axis, lower, upper)
    return joints


#: where a file's loops belong, for the messages refusing a joint tree that is not a tree
LOOPS_GO_IN_CLOSURES = (
    "a URDF's joints must form a tree (one parent joint per link, no loops); declare each loop-closing "
    "joint in the <closures> element instead (docs/kinematics.md, section 2)"
)


def _parent_joints(joints: dict[str, JointDeclaration], label: str) -> dict[str, str]:
    """Link -> the joint whose child it is; refuses a link that is the child of two joints."""
    parent_joint: dict[str, str] = {}
    for joint in joints.values():
        earlier = parent_joint.get(joint.child)
        if earlier is not None:
            raise MechanismFileError(
                f"{label}: link {joint.child!r} is the child of two joints, {earlier!r} (parent link "
                f"{joints[earlier].parent!r}) and {joint.name!r} (parent link {joint.parent!r}); {LOOPS_GO_IN_CLOSURES}",
                key=joint.child, value=(earlier, joint.name),
            )
        parent_joint[joint.child] = joint.name
    return parent_joint


def _check_no_cycle(links: list[str], joints: dict[str, JointDeclaration], parent_joint: dict[str, str], label: str) -> None:
    """Refuse joints that lead from a link back to itself (urdfdom and Pinocchio fail on them without naming them)."""
    reaches_root: set[str] = set()
    for start in links:
        chain: list[str] = []  # links walked up from ``start``, child first
        link = start
        while link in parent_joint and link not in reaches_root and link not in chain:
            chain.append(link)
            link = joints[parent_joint[link]].parent
        if link in chain:  # walked back onto the chain: the joints from there on form a cycle
            cycle = [parent_joint[member] for member in reversed(chain[chain.index(link):])]
            path = " -> ".join([link] + [joints[name].child for name in cycle])
            if len(cycle) == 1:
                what = f"joint {cycle[0]!r} has link {link!r} as both its parent and its child"
            else:
                what = f"joints {', '.join(repr(name) for name in cycle)} form a cycle (links {path})"
            raise MechanismFileError(f"{label}: {what}; {LOOPS_GO_IN_CLOSURES}", key=cycle[0], value=tuple(cycle))
        reaches_root.update(chain)


def _check_one_tree(links: list[str], joints: dict[str, JointDeclaration], parent_joint: dict[str, str], label: str) -> None:
    """Refuse links that no chain of joints joins to the root (urdfdom's "two root links found")."""
    children = _children(joints)
    trees = [_subtree_links(link, children) for link in links if link not in parent_joint]
    if len(trees) <= 1:
        return
    root_tree = max(trees, key=len)  # the largest tree is the mechanism; ties: the first in the file
    apart = [link for link in links if link not in root_tree]
    other_roots = [tree[0] for tree in trees if tree is not root_tree]
    unjoined = ", ".join(repr(root) for root in other_roots)
    raise MechanismFileError(
        f"{label}: link(s) {', '.join(repr(link) for link in apart)} cannot be reached from the root link "
        f"{root_tree[0]!r} by any chain of joints ({unjoined} {'is' if len(other_roots) == 1 else 'are'} the child "
        f"of no joint); make {other_roots[0]!r} the child of a joint, or remove the link(s): a URDF's joints must "
        "join all links into one tree",
        key=other_roots[0], value=tuple(apart),
    )


def _check_tree(links: list[str], joints: dict[str, JointDeclaration], label: str) -> None:
    """The joints must make one tree over the links: one parent joint per link, no cycle, nothing apart."""
    parent_joint = _parent_joints(joints, label)
    _check_no_cycle(links, joints, parent_joint, label)
    _check_one_tree(links, joints, parent_joint, label)


def _closure_axis(element: ET.Element, name: str, label: str) -> tuple[float, float, float]:
    axis_element = element.find("axis")
    if axis_element is None:
        raise MechanismFileError(f"{label}: revolute closure {name!r} needs <axis xyz=.../>")
    axis_vector = np.array(_vector(axis_element, "xyz", f"closure {name!r} <axis>"))
    norm = float(np.linalg.norm(axis_vector))
    if norm < 1e-12:
        raise MechanismFileError(f"{label}: revolute closure {name!r} has a zero axis")
    return tuple(float(x) for x in axis_vector / norm)


def _closures(root: ET.Element, joints: dict, link_set: set[str], label: str) -> list[ClosureDeclaration]:
    closures: list[ClosureDeclaration] = []
    closures_element = root.find("closures")
    for element in closures_element.findall("closure") if closures_element is not None else []:
        name = element.get("name")
        kind = element.get("type")
        if not name:
            raise MechanismFileError(f"{label}: a <closure> has no name")
        if name in joints or name in [c.name for c in closures]:
            raise MechanismFileError(f"{label}: closure name {name!r} is already used by a joint or closure")
        if kind not in CLOSURE_TYPES:
            raise MechanismFileError(f"{label}: closure {name!r} has type={kind!r}; valid types: {', '.join(CLOSURE_TYPES)}")
        parent = _frame(element.find("parent"), "parent", name, link_set, label)
        child = _frame(element.find("child"), "child", name, link_set, label)
        if parent.link == child.link:  # its equations would hold two frames of one body together: never met
            raise MechanismFileError(
                f"{label}: closure {name!r} joins link {parent.link!r} to itself (its <parent> and <child> name the "
                "same link); a closure joins two different links",
                key=name, value=parent.link,
            )
        axis = _closure_axis(element, name, label) if kind == "revolute" else None
        closures.append(ClosureDeclaration(name, kind, parent, child, axis))
    return closures


def _actuated(root: ET.Element, joints: dict, label: str) -> list[str]:
    actuated = []
    for transmission in root.findall("transmission"):
        for joint in transmission.findall("joint"):
            joint_name = joint.get("name")
            if joint_name not in joints:
                raise MechanismFileError(
                    f"{label}: transmission {transmission.get('name')!r} names joint {joint_name!r}, which is not defined"
                )
            if joints[joint_name].kind not in ("prismatic", "revolute", "continuous"):
                raise MechanismFileError(f"{label}: actuated joint {joint_name!r} must be 1-DOF, is {joints[joint_name].kind}")
            actuated.append(joint_name)
    return actuated


def parse_mechanism(source: str | Path, *, is_text: bool = False) -> MechanismDescription:
    """Parse a URDF file (or text, ``is_text=True``) with closure declarations.

    Raises :class:`MechanismFileError` for unreadable XML, a missing ``<robot>``
    root, duplicate names, joints that do not form one tree (a link that is the
    child of two joints, a cycle of joints, links joined to no root), closures
    naming missing links or joining a link to itself, unknown closure types,
    a revolute closure without a non-zero axis, a transmission naming a
    missing joint, a mass or inertia out of range (module docstring) or a
    movable joint that carries no mass.
    """
    text, path = _read_text(source, is_text)
    label = str(path) if path else "<urdf text>"
    try:
        root = ET.fromstring(text)
    except ET.ParseError as exc:
        raise MechanismFileError(f"{label}: malformed XML ({exc}); fix the file or regenerate it") from None
    if root.tag != "robot":
        raise MechanismFileError(f"{label}: root element is <{root.tag}>, a URDF needs <robot>")
    links = _links(root, label)
    joints = _joints(root, set(links), label)
    _check_tree(links, joints, label)
    _check_moving_bodies_have_mass(joints, _massive_links(root, label), label)
    return MechanismDescription(
        path=path,
        name=root.get("name", "robot"),
        urdf_text=text,
        links=tuple(links),
        joints=joints,
        closures=tuple(_closures(root, joints, set(links), label)),
        actuated_joints=tuple(_actuated(root, joints, label)),
    )
