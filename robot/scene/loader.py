"""Scenes: one TOML file says everything a run needs.

A scene names the mechanism file, the clearance joints and their parameters,
the force and friction laws, the prescribed motion, the duration, the
integrator, its tolerances and the Baumgarte gains. Building a scene builds only
what it uses: the mechanism is loaded with exactly its clearance joints
(:func:`robot.model.mechanism.build_mechanism`).

Shipped scenes live in ``robot/scene/scenes/*.toml`` and are found by name; any other
path to a ``.toml`` file works too. ``extends = "NAME_OR_PATH"`` starts from
another scene and overrides it table by table, nested tables key by key (arrays
of tables such as ``[[clearance]]`` are replaced whole, and so is a table that
sets another ``function`` or ``mode``); the child inherits every key but
``name``, and each relative path resolves against the folder of the file that
wrote it. Unknown keys and bad values raise
:class:`robot.errors.SceneError` naming the key, the value and what is valid.

Schema (defaults in brackets)::

    name = "compound"                    # [file stem]
    description = "..."
    mechanism = "ups_rps.urdf"           # a path relative to this file; a bare file name not found
                                         # beside it (or "package://NAME") is a shipped mechanism
                                         # (robot.data: the repository's urdf/, package data when installed)
    end_effector = "platform"            # frame whose motion is reported
    duration = 2.0                       # s
    gravity = [0.0, 0.0, -9.81]          # m/s^2, world axes [default]

    [trajectory]                         # prescribed motion (none: no table, or type = "joints" and no entries)
    type = "platform"                    # "platform" (pose through IK) or "joints"
    preset = "reference"                 # platform: the reference motion of robot.trajectory
    period = 1.0                         # s
    # platform, instead of preset: x, z, roll, pitch, yaw = {offset, amplitudes, harmonics, phases}
    # joints: one table per motion-driven actuator (rad or m), by `function`:
    #   P1 = {offset, rate, amplitudes, harmonics, phases}   # no function (or "fourier"): Fourier series of `period`
    #   P1 = {function = "constant_rate", offset, rate}      # or "constant" {value}, "polynomial" {coefficients}
    #   P1 = {function = "harmonic", amplitude, frequency, phase, offset}   # Hz, rad
    #   P1 = {function = "tabulated", file = "motion.csv"}   # CSV: time, value (relative to this file;
    #        or time = [...], value = [...]); cubic spline: value, rate, acceleration; must cover [0, duration]

    [actuators]        # per actuated joint (default: every URDF <transmission> joint, mode "motion")
    P1 = {mode = "motion"}               # prescribed motion from [trajectory] (driving constraint)
    P2 = {mode = "force", function = "harmonic", amplitude = 5.0, frequency = 2.0}  # prescribed
                                         # generalized force (N, prismatic; N m, revolute), the joint free;
                                         # function keys as in [trajectory] joints (robot.scene.values)
    P3 = {mode = "none"}                 # not actuated: the joint is free
    # any 1-dof joint may be listed (also one without a transmission)

    [[force]]          # force elements (robot.dynamics.forces; one table each, outputs force_<name>)
    name = "spring"    # unique [<type>_<index>]
    type = "spring_damper"   # link_a, xyz_a, link_b (or "world"), xyz_b, stiffness + free_length
                             # or length = [...] + force = [...], damping, actuator_force
    # "joint_spring_damper": joint, stiffness, rest_position, damping
    # "joint_torque" (revolute) / "joint_force" (prismatic): joint + a time function (function = ...)
    # "body_force": link, xyz, direction (world) + a time function; "body_torque": link, axis + function

    [solver]   method ["RK45"], rtol [1e-7], atol [1e-9], max_step [1e-3], first_step,
               jacobian ["structured"] (implicit methods' Newton matrix; or "finite-difference")
    [baumgarte] alpha [5.0], beta [5.0]
    [limits]   penetration_ratio [0.5], max_residual [1e-4], min_step [1e-13], max_wall_time,
               max_steps [1e8] (steps taken plus those the last 10,000 steps' pace needs)

    [materials.steel]  youngs_modulus, poisson_ratio

    [[clearance]]      # one per clearance joint
    joint = "S1"       # the joint or closure it replaces
    type = "spherical" # a registered joint type: "spherical", "revolute" (clearance_contact.joint_types())
    outer_on = "child" # body carrying the socket / bearing
    material = "steel" # or outer_material / inner_material
    restitution = 0.9
    friction = {law = "brown_mcphee", static = 0.07, dynamic = 0.05, transition_velocity = 5e-3}
                       # law: "none" [default], "brown_mcphee", "coulomb", or a law a module registered
                       # (clearance_contact.register_friction_law); its keys are checked by its registry entry
    # the type's own keys (its SCENE_KEYS: numbers, and names for its NAME_KEYS):
    # spherical: ball_radius, clearance, exponent [1.5], stiffness [Hertz], dissipation
    # revolute: journal_radius, radial_clearance, bearing_outer_radius, bearing_length,
    #           axial_clearance, radial_exponent, axial_exponent, point_exponent, *_stiffness,
    #           radial_law ["linear"; or "johnson", "pereira", "hertz_point"], dissipation
    # both: dissipation ["lankarani_nikravesh"; or "hunt_crossley", "gonthier", "flores", "hu_guo"]

    [initial]
    misalignment_deg = { R1 = -0.035 }   # revolute clearance joints: bearing rotated about its
                                         # local x axis at t = 0 (degrees, right-hand rule); refused
                                         # when the tilted bearing already penetrates the journal
    positions = { crank_rod = -1.4 }     # 1-DOF tree joints: coordinate at t = 0 (rad or m); held
                                         # when independent, else a guess (robot.model.initial_state)
    velocities = { crank_rod = 0.0 }     # their rates at t = 0 (rad/s or m/s), projected onto the constraints
    clearance_state = "centred"          # clearance joints at t = 0: "centred" (elements concentric) or
                                         # "resting" (in contact under the ideal joint's load, at the static
                                         # penetration: robot.model.resting_state)

    [output]   step [2e-4] (0: every step), keep [all arrays], precision ["float32"] (or "float64"):
               see :class:`OutputSpec`

Every key with its unit, default, valid range and examples: ``docs/scenes.md``
(``tests/test_scene_docs.py`` checks it names every key accepted here).

The output files are named after ``name`` made safe (:attr:`Scene.file_stem`).
"""

from __future__ import annotations

import copy
import dataclasses
import math
import tomllib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Mapping

import numpy as np

from clearance_contact import ContactError, Material, joint_type, joint_types
from clearance_contact.friction import friction_law_from_scene
from clearance_contact.registry import COMMON_SCENE_KEYS

from robot.data import shipped_urdf
from robot.errors import MechanismFileError, SceneError
from robot.extensions import load_extensions
from robot.io.array_names import result_array_names
from robot.model.description import CLEARANCE_TREE_KINDS, parse_mechanism
from robot.scene.overrides import KIND_KEYS, apply_overrides
from robot.dynamics.baumgarte import Baumgarte
from robot.integration.options import STRUCTURED, FailureLimits, SolverOptions
from robot.integration.solvers import FIXED_STEP_METHODS, METHODS

SCENE_DIR = Path(__file__).resolve().parent / "scenes"
#: how clearance joints start (``[initial] clearance_state``; robot.model.initial_state builds them)
CLEARANCE_STATES = ("centred", "resting")
#: the platform pose coordinates a platform trajectory prescribes (robot.model.trajectory uses them)
POSE_COORDINATES = ("x", "z", "roll", "pitch", "yaw")

_TOP_KEYS = {"name", "description", "mechanism", "end_effector", "duration", "gravity", "trajectory", "solver", "baumgarte", "limits", "materials", "clearance", "initial", "output", "extends", "force", "actuators"}
_OUTPUT_KEYS = {"step", "keep", "precision"}
PRECISIONS = ("float64", "float32")
#: prefix of a shipped mechanism file in a scene's ``mechanism`` key
PACKAGE_PREFIX = "package://"
#: the largest initial misalignment looked at (degrees); the admissible one is set by the clearances
MAX_MISALIGNMENT_DEG = 5.0
#: default output grid (s): 5 kHz
DEFAULT_OUTPUT_STEP = 2e-4
_SOLVER_KEYS = {"method", "rtol", "atol", "max_step", "first_step", "jacobian"}
#: valid ``[solver] rtol`` (closed range): the one definition, used by the scenes and by
#: ``clearance work-precision --tolerances/--candidates``. The lower bound is what the
#: integrators honour: scipy's methods replace an rtol below ``100 * eps`` (2.2e-14) by
#: it with a warning, so a smaller value would be run as another than the one recorded.
RTOL_RANGE = (100 * float(np.finfo(float).eps), 1e-1)
#: valid ``[solver] atol`` (closed range)
ATOL_RANGE = (1e-16, 1e-1)
_BAUMGARTE_KEYS = {"alpha", "beta"}
_LIMIT_KEYS = {"penetration_ratio", "max_residual", "min_step", "max_wall_time", "max_steps"}
_MATERIAL_KEYS = {"youngs_modulus", "poisson_ratio"}
_COORDINATE_KEYS = {"offset", "rate", "amplitudes", "harmonics", "phases"}
_TRAJECTORY_KEYS = {"type", "period", "preset"}  # besides the coordinates' tables
_INITIAL_KEYS = {"misalignment_deg", "positions", "velocities", "clearance_state"}


@dataclass(frozen=True)
class ClearanceSpec:
    """A clearance joint of a scene: where it is, its contact law, its initial misalignment."""

    joint: str
    kind: str
    outer_on: str
    law: Any


@dataclass(frozen=True)
class TrajectorySpec:
    kind: str
    period: float
    preset: str | None
    coordinates: dict[str, dict]
    #: joints: per joint a time function (robot.model.time_functions) when the table names a `function`
    functions: dict[str, Any] = field(default_factory=dict)


@dataclass(frozen=True)
class OutputSpec:
    """What a result file keeps (scene table ``[output]``).

    ``step``: the output grid (s). With it the run also records the state at every
    multiple of ``step`` (``SolverOptions.output_step``) and the file keeps those
    records and the located ones (start, contact onsets, penetration and force
    maxima) but not the ends of the integration steps; ``None`` (scene: ``step =
    0``): every record. Default 2e-4 s (5 kHz) with single-precision bulk: the 2 s
    ``compound`` run's file is 4.7 MB instead of 27 MB (every accepted step in
    double precision), its force and penetration maxima unchanged.
    ``keep``: the names of the arrays to write (``t`` and ``record_kind`` always
    are); ``None``: all. ``precision``: ``"float32"`` stores the bulk arrays
    (:data:`robot.io.results.BULK_ARRAYS`: ``q``, ``v``, end-effector kinematics,
    eccentricities, energies, powers, works) in single precision; time, forces,
    penetrations and driving forces always stay in double precision.
    """

    step: float | None = DEFAULT_OUTPUT_STEP
    keep: tuple[str, ...] | None = None
    precision: str = "float32"


@dataclass(frozen=True)
class Scene:
    """A validated scene (still independent of Pinocchio: see :func:`robot.run.build_run`)."""

    name: str
    path: Path | None
    description: str
    mechanism_path: Path
    end_effector: str
    duration: float
    trajectory: TrajectorySpec
    solver: SolverOptions
    baumgarte: Baumgarte
    limits: FailureLimits
    clearances: tuple[ClearanceSpec, ...] = field(default_factory=tuple)
    misalignment_deg: dict[str, float] = field(default_factory=dict)
    gravity: tuple[float, float, float] = (0.0, 0.0, -9.81)
    initial_positions: dict[str, float] = field(default_factory=dict)
    initial_velocities: dict[str, float] = field(default_factory=dict)
    clearance_state: str = "centred"  # [initial] clearance_state: one of CLEARANCE_STATES
    output: OutputSpec = field(default_factory=OutputSpec)
    forces: tuple = field(default_factory=tuple)  # robot.scene.forces.ForceSpec per [[force]] table
    actuators: dict = field(default_factory=dict)  # joint -> robot.scene.forces.ActuatorSpec
    #: the scene's TOML document as resolved (``extends`` merged, overrides applied)
    document: dict[str, Any] = field(default_factory=dict, compare=False, repr=False)
    #: the folder that relative paths of the document are relative to
    base_dir: Path | None = field(default=None, compare=False, repr=False)
    #: the clearances validated from ``document`` (the same tuple as ``clearances`` unless they were
    #: replaced afterwards, e.g. by ``dataclasses.replace``: then the document no longer says them)
    document_clearances: tuple[ClearanceSpec, ...] | None = field(default=None, compare=False, repr=False)

    def with_changes(self, overrides: Mapping[str, Any]) -> "Scene":
        """A new scene: this one's document with key paths changed, validated again.

        ``scene.with_changes({"solver.rtol": 1e-8, "clearance.R1.radial_clearance": 2e-4})``.
        SceneError if this scene's clearances were replaced outside its document (its
        validation would silently bring back the document's laws): name the law in the
        document instead (``clearance.J.friction``, a registered friction law).
        """
        if self.path is None or self.base_dir is None:
            raise SceneError("this scene was not loaded from a document; build it with load_scene(...)")
        self._require_document_clearances()
        return scene_from_document(apply_overrides(self.document, overrides), self.path, self.base_dir)

    def _require_document_clearances(self) -> None:
        """SceneError naming the clearance joints whose laws are not the ones the document validated to."""
        if self.document_clearances is None or self.clearances is self.document_clearances:
            return
        validated = {spec.joint: spec for spec in self.document_clearances}
        changed = [spec.joint for spec in self.clearances if validated.get(spec.joint) is not spec]
        changed += [joint for joint in validated if joint not in self.clearance_joints]
        if changed:
            raise SceneError(
                f"scene {self.name!r}: the clearance joint(s) {', '.join(map(repr, changed))} were replaced outside the scene's "
                "document (dataclasses.replace?), and validating the document again would silently bring back its own laws; "
                "change them through the document instead: register a friction law with "
                "clearance_contact.register_friction_law and name it, "
                "scene.with_changes({'clearance.JOINT.friction': {'law': NAME, ...}})",
                key="clearance", value=changed,
            )  # fmt: skip

    @property
    def clearance_joints(self) -> tuple[str, ...]:
        return tuple(c.joint for c in self.clearances)

    @property
    def file_stem(self) -> str:
        """The scene name made safe as a file name (output files are ``<out>/<file_stem>.npz``)."""
        return safe_file_stem(self.name)


def safe_file_stem(name: str) -> str:
    """``name`` as a plain file name: no folders, no leading dot, only ``[A-Za-z0-9._-]``.

    Every other character becomes ``_`` ("../escaped" -> "escaped", "/tmp/x" ->
    "tmp_x"), so a result is always written inside the output folder; an empty
    name becomes ``"scene"``.
    """
    cleaned = "".join(c if c.isascii() and (c.isalnum() or c in "._-") else "_" for c in name)
    cleaned = cleaned.strip("._-")[:100]
    return cleaned or "scene"


def shipped_scenes() -> list[str]:
    return sorted(p.stem for p in SCENE_DIR.glob("*.toml"))


def resolve_scene_path(name_or_path: str | Path) -> Path:
    """A shipped scene name, or a path to a TOML file."""
    candidate = Path(name_or_path)
    # a folder of the working directory named like a shipped scene (e.g. an --out folder "ideal") is not the scene
    if candidate.suffix == ".toml" or candidate.is_file():
        if not candidate.is_file():
            what = "is a folder, not a scene file" if candidate.is_dir() else "does not exist"
            raise SceneError(f"scene file {str(candidate)!r} {what}")
        return candidate.resolve()
    shipped = SCENE_DIR / f"{name_or_path}.toml"
    if shipped.is_file():
        return shipped
    if candidate.is_dir():
        raise SceneError(f"scene {str(name_or_path)!r} is a folder, not a scene file or a shipped scene; shipped scenes: {', '.join(shipped_scenes())}")
    raise SceneError(f"scene {str(name_or_path)!r} is neither a file nor a shipped scene; shipped scenes: {', '.join(shipped_scenes())}")


def _read(path: Path, seen: tuple[Path, ...] = ()) -> dict:
    """The document of scene file ``path`` with its ``extends`` chain merged in.

    The file's own relative paths stay as written; ``"__dir__"`` holds the folder
    they are relative to (``path.parent``; :func:`load_scene` pops it as the
    scene's ``base_dir``). Inherited paths are already absolute
    (:func:`_inherited`), so every path resolves against the file that wrote it.
    """
    if path in seen:
        raise SceneError(f"scene {path.name}: 'extends' forms a cycle through {', '.join(p.name for p in seen)}")
    try:
        data = tomllib.loads(path.read_text(encoding="utf-8"))
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
        raise SceneError(f"scene {str(path)!r} is not valid TOML: {exc}") from None
    parent = data.pop("extends", None)
    if parent is not None:
        data = _merge(_inherited(parent, path, seen), data)
    data["__dir__"] = str(path.parent)
    return data


def _inherited(parent: Any, path: Path, seen: tuple[Path, ...]) -> dict:
    """What scene ``path`` inherits from ``extends = parent``: the parent's document, its paths absolute, without ``name``.

    The parent's ``name`` is dropped: a child is named by its own ``name`` or its
    file's stem, so that its results never overwrite the parent's.
    """
    if not isinstance(parent, str):
        raise SceneError(f"scene {path.name}: extends={parent!r} must be a scene name or path", key="extends", value=parent)
    # a .toml parent is a path relative to this scene; anything else a shipped scene name
    parent_path = resolve_scene_path(path.parent / parent if parent.endswith(".toml") else parent)
    document = _read(parent_path, seen + (path,))
    document = _absolute_paths(document, Path(document.pop("__dir__")))
    document.pop("name", None)
    return document


def _merge(parent: dict, child: dict) -> dict:
    """``child`` over ``parent``: tables (nested ones too) key by key, any other value replaced whole.

    Arrays of tables (``[[clearance]]``, ``[[force]]``) are lists, so a child that
    writes one replaces the parent's whole array; a table that chooses another
    kind (:data:`KIND_KEYS`) replaces the parent's table whole (docs/scenes.md, "extends").
    """
    merged = dict(parent)
    for key, value in child.items():
        if isinstance(value, dict) and isinstance(merged.get(key), dict) and not _changes_kind(merged[key], value):
            merged[key] = _merge(merged[key], value)
        else:
            merged[key] = value
    return merged


def _changes_kind(parent: dict, child: dict) -> bool:
    """Whether ``child`` sets a :data:`KIND_KEYS` key to another value than ``parent``'s.

    The keys of one time function (or actuator mode) do not fit another, so such a
    table is not merged: a child switching ``shoulder`` from a harmonic to a
    constant torque must not inherit ``amplitude`` and ``frequency``.
    """
    return any(key in child and child[key] != parent.get(key) for key in KIND_KEYS)


def _path_entries(document: dict) -> list[tuple[dict, str]]:
    """The ``(table, key)`` pairs of a document whose value is a file path.

    ``mechanism``, and the ``file`` of a tabulated time function: in a joint of
    ``[trajectory]``, an entry of ``[actuators]`` or a ``[[force]]`` table.
    """
    entries = [(document, "mechanism")]
    for section in ("trajectory", "actuators"):
        table = document.get(section)
        if isinstance(table, dict):
            entries += [(entry, "file") for entry in table.values() if isinstance(entry, dict)]
    forces = document.get("force")
    if isinstance(forces, list):
        entries += [(entry, "file") for entry in forces if isinstance(entry, dict)]
    return entries


def _absolute_paths(document: dict, folder: Path) -> dict:
    """``document`` with its relative paths made absolute against ``folder``, the folder of the file that wrote them.

    A ``mechanism`` that names a shipped file (a bare name with no such file in
    ``folder``) becomes ``package://NAME``, so a file of that name beside a child
    scene does not take its place. Values that are not paths are left for the
    validation to refuse.
    """
    for table, key in _path_entries(document):
        value = table.get(key)
        if not isinstance(value, str) or not value or value.startswith(PACKAGE_PREFIX):
            continue
        local = folder / value
        shipped = key == "mechanism" and not local.is_file() and Path(value).name == value
        table[key] = PACKAGE_PREFIX + value if shipped else str(local)
    return document


def _unknown(table: dict, allowed: set[str], where: str) -> None:
    unknown = sorted(set(table) - allowed)
    if unknown:
        raise SceneError(
            f"{where}: unknown key(s) {', '.join(unknown)}; valid keys: {', '.join(sorted(allowed))}", key=unknown[0], value=table[unknown[0]]
        )


def _number(table: dict, key: str, where: str, default=None, *, low=-math.inf, high=math.inf, low_open=False, required=False) -> float:
    if key not in table:
        if required:
            raise SceneError(f"{where}: missing required key {key!r}", key=key)
        return default
    value = table[key]
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise SceneError(f"{where}: {key}={value!r} must be a finite number", key=key, value=value)
    ok = (value > low if low_open else value >= low) and value <= high
    if not ok:
        bracket = "(" if low_open else "["
        raise SceneError(f"{where}: {key}={value!r} is out of range {bracket}{low}, {high}]", key=key, value=value)
    return float(value)


def _name(table: dict, key: str, where: str) -> str:
    """The text value of ``key`` (a model's name: whether it is a known one is for its registry to say)."""
    value = table[key]
    if not isinstance(value, str) or not value:
        raise SceneError(f"{where}: {key}={value!r} must be a name (a non-empty string)", key=key, value=value)
    return value


def _table(data: dict, key: str, where: str) -> dict:
    value = data.get(key, {})
    if not isinstance(value, dict):
        raise SceneError(f"{where}: [{key}] must be a table, got {value!r}")
    return value


def _materials(data: dict, where: str) -> dict[str, Material]:
    out = {}
    for name, table in _table(data, "materials", where).items():
        w = f"{where} [materials.{name}]"
        if not isinstance(table, dict):
            raise SceneError(f"{w} must be a table")
        _unknown(table, _MATERIAL_KEYS, w)
        try:
            out[name] = Material(
                _number(table, "youngs_modulus", w, required=True), _number(table, "poisson_ratio", w, required=True)
            )
        except ContactError as exc:
            raise SceneError(f"{w}: {exc}", key=getattr(exc, "key", None), value=getattr(exc, "value", None)) from None
    return out


def _friction(table: Any, where: str) -> tuple[Any, dict]:
    """(law, its table as validated) of a clearance's ``friction`` table: a law registered by name
    (:func:`clearance_contact.friction.register_friction_law`; the shipped ones and any a user module
    registered), its keys checked there; no table: no friction.  SceneError naming key, value and range."""
    if table is not None and not isinstance(table, dict):
        raise SceneError(f"{where}: friction must be a table {{law = NAME, ...}}, got {table!r}", key="friction", value=table)
    try:
        return friction_law_from_scene(table)
    except ContactError as exc:
        raise SceneError(f"{where}: {exc}", key=getattr(exc, "key", None), value=getattr(exc, "value", None)) from None


def _clearance(table: Any, index: int, materials: dict[str, Material], where: str) -> ClearanceSpec:
    w = f"{where} [[clearance]] #{index + 1}"
    if not isinstance(table, dict):
        raise SceneError(f"{w} must be a table")
    kind = table.get("type")
    if not isinstance(kind, str) or kind not in joint_types():
        raise SceneError(f"{w}: type={kind!r} is not a clearance joint type; registered types: {', '.join(joint_types())}", key="type", value=kind)
    law_type = joint_type(kind)
    _unknown(table, COMMON_SCENE_KEYS | set(law_type.SCENE_KEYS), w)
    joint = table.get("joint")
    if not isinstance(joint, str) or not joint:
        raise SceneError(f"{w}: joint={joint!r} must name the joint or closure it replaces", key="joint", value=joint)
    w = f"{where} clearance {joint!r}"
    outer_on = table.get("outer_on", "child")
    if outer_on not in ("child", "parent"):
        raise SceneError(f"{w}: outer_on={outer_on!r} must be 'child' or 'parent'", key="outer_on", value=outer_on)

    def material(key: str) -> Material:
        written = key if key in table else "material" if "material" in table else None
        name = table[written] if written else "steel"
        if name not in materials:
            defined = f"defined materials: {', '.join(materials) or 'none'}"
            if written is None:  # the default: name no key the user did not write
                raise SceneError(
                    f"{w}: no material is given, and the default material 'steel' is not defined ({defined}); define "
                    "[materials.steel] (youngs_modulus, poisson_ratio) or set material = \"NAME\" in this [[clearance]] table",
                    key="material", value=name,
                )
            raise SceneError(f"{w}: {written}={name!r} is not defined; {defined}", key=written, value=name)
        return materials[name]

    outer, inner = material("outer_material"), material("inner_material")
    restitution = _number(table, "restitution", w, 0.9)
    for key in law_type.REQUIRED_KEYS:
        if key not in table:
            raise SceneError(f"{w}: missing required key {key!r}", key=key)
    # dimensions (the type's GEOMETRY_KEYS) are positive: checked here, under the user's key names;
    # NAME_KEYS are names of models (the joint checks a name against its registry)
    positive = {"low": 0.0, "low_open": True}
    parameters = {
        key: _name(table, key, w) if key in law_type.NAME_KEYS else _number(table, key, w, **(positive if key in law_type.GEOMETRY_KEYS else {}))
        for key in law_type.SCENE_KEYS
        if key in table
    }
    friction, friction_table = _friction(table.get("friction"), f"{w} friction")
    try:
        law = law_type.from_scene(parameters, outer, inner, restitution, friction, friction_table=friction_table)
    except ContactError as exc:
        raise SceneError(f"{w}: {exc}", key=getattr(exc, "key", None), value=getattr(exc, "value", None)) from None
    return ClearanceSpec(joint, kind, outer_on, law)


def _check_site_kinds(clearances: tuple[ClearanceSpec, ...], mechanism_path: Path, where: str) -> None:
    """Each clearance type must fit the kind of joint it replaces (its ``SITE_KINDS``).

    The mechanism file is only parsed as XML here (no model is built); a joint it does
    not have, or a file it cannot read, is left to :func:`robot.model.mechanism.build_mechanism`.
    """
    if not clearances:
        return
    try:
        description = parse_mechanism(mechanism_path)
    except MechanismFileError:
        return
    kinds = {c.name: (c.kind, "closure") for c in description.closures}
    for name, joint in description.joints.items():
        if joint.kind in CLEARANCE_TREE_KINDS:  # a tree joint with clearance becomes a free joint
            kinds.setdefault(name, (CLEARANCE_TREE_KINDS[joint.kind], "joint"))
    for spec in clearances:
        if spec.joint not in kinds:
            continue
        site_kind, element = kinds[spec.joint]
        law_type = joint_type(spec.kind)
        if site_kind not in law_type.SITE_KINDS:
            fitting = [name for name in joint_types() if site_kind in joint_type(name).SITE_KINDS]
            raise SceneError(
                f"{where} clearance {spec.joint!r}: type={spec.kind!r} cannot replace {spec.joint!r}, a {site_kind} "
                f"{element} of {description.name!r} (a {spec.kind} clearance joint replaces {' or '.join(law_type.SITE_KINDS)} "
                f"joints); use type = {' or '.join(repr(n) for n in fitting) or 'a type for ' + site_kind + ' joints'}"
            )


def resolve_mechanism(mechanism: Any, base_dir: Path, where: str) -> Path:
    """The scene's ``mechanism``: a path relative to the scene file, else a shipped file.

    ``"package://NAME"``, or a bare file name with no file of that name beside the
    scene, is the shipped mechanism ``NAME`` (:func:`robot.data.shipped_urdf`): it
    resolves in a checkout and in an installed wheel alike.
    """
    if not isinstance(mechanism, str) or not mechanism:
        raise SceneError(f"{where}: mechanism={mechanism!r} must be the path of a URDF file")
    if mechanism.startswith(PACKAGE_PREFIX):
        candidate = shipped_urdf(mechanism[len(PACKAGE_PREFIX) :])
    else:
        candidate = (base_dir / mechanism).resolve()
        if not candidate.is_file() and Path(mechanism).name == mechanism:
            candidate = shipped_urdf(mechanism)
    if not candidate.is_file():
        raise SceneError(f"{where}: mechanism={mechanism!r}: the file {str(candidate)!r} does not exist")
    return candidate


def _output(table: dict, clearance_joints: dict[str, tuple[str, ...]], where: str) -> OutputSpec:
    w = f"{where} [output]"
    _unknown(table, _OUTPUT_KEYS, w)
    step = _number(table, "step", w, DEFAULT_OUTPUT_STEP, low=0.0) or None
    keep = table.get("keep")
    if keep is not None and (not isinstance(keep, list) or not all(isinstance(k, str) and k for k in keep)):
        raise SceneError(f"{w}: keep={keep!r} must be a list of array names, e.g. [\"driving_force\", \"S1_normal_force\"]")
    if keep is not None:
        known = result_array_names(clearance_joints)
        unknown = [k for k in keep if k not in known]
        if unknown:
            raise SceneError(f"{w}: keep names {', '.join(map(repr, unknown))}, not an array of this scene's results; arrays: {', '.join(known)}")
    precision = table.get("precision", "float32")
    if precision not in PRECISIONS:
        raise SceneError(f"{w}: precision={precision!r} must be one of {', '.join(map(repr, PRECISIONS))}")
    return OutputSpec(step, None if keep is None else tuple(keep), precision)


def _misalignment(initial: dict, clearances: tuple[ClearanceSpec, ...], where: str) -> dict[str, float]:
    """``[initial] misalignment_deg``, each checked against the joint's clearances (:func:`admissible_misalignment`)."""
    w = f"{where} [initial]"
    _unknown(initial, _INITIAL_KEYS, w)
    misalignment = initial.get("misalignment_deg", {})
    if not isinstance(misalignment, dict):
        raise SceneError(f"{w}: misalignment_deg={misalignment!r} must be a table {{JOINT = degrees}}")
    laws = {c.joint: c.law for c in clearances if c.kind == "revolute"}
    out = {}
    for joint in misalignment:
        if joint not in laws:
            raise SceneError(f"{w}: misalignment_deg names {joint!r}, which is not a revolute clearance joint of the scene ({sorted(laws)})")
        degrees = _number(misalignment, joint, f"{w} misalignment_deg", low=-MAX_MISALIGNMENT_DEG, high=MAX_MISALIGNMENT_DEG)
        largest = admissible_misalignment(laws[joint], math.copysign(1.0, degrees))
        if abs(degrees) > largest:
            raise SceneError(
                f"{w}: misalignment_deg {joint}={degrees!r}: the tilted bearing already penetrates the journal at t = 0; "
                f"the clearances of {joint} admit at most {math.copysign(largest, degrees):.6g} deg"
            )
        out[joint] = float(degrees)
    return out


def admissible_misalignment(law: Any, sign: float = 1.0, tolerance_deg: float = 1e-6) -> float:
    """Largest |angle| (deg, up to ``MAX_MISALIGNMENT_DEG``) by which the bearing can start tilted.

    The initial state centres the journal in the bearing and tilts the bearing
    about its local x axis (:mod:`robot.model.initial_state`); the joint's own
    ``penetration`` (the contact law's geometry, not a copy of it) says when a
    candidate touches. Penetration grows with the tilt, so bisection finds the angle
    where the deepest candidate reaches zero (for the shipped R1: the bearing's
    end faces meet the journal flanges, R_b2 sin(angle) = c_a / 2).
    """
    centre = np.zeros(3)

    def penetrates(degrees: float) -> bool:
        rotation = misalignment_rotation(sign * degrees)
        return float(np.max(law.penetration(rotation, centre, np.eye(3), centre))) > 0.0

    if not penetrates(MAX_MISALIGNMENT_DEG):
        return MAX_MISALIGNMENT_DEG
    low, high = 0.0, MAX_MISALIGNMENT_DEG
    while high - low > tolerance_deg:
        middle = 0.5 * (low + high)
        low, high = (low, middle) if penetrates(middle) else (middle, high)
    return low


def _trajectory(table: dict, where: str, base_dir: Path | None = None) -> TrajectorySpec:
    w = f"{where} [trajectory]"
    kind = table.get("type", "platform" if table else "joints")  # no table: no prescribed motion
    if kind not in ("platform", "joints"):
        raise SceneError(f"{w}: type={kind!r} must be 'platform' or 'joints'", key="type", value=kind)
    period = _number(table, "period", w, 1.0, low=0.0, low_open=True)
    preset = table.get("preset")
    coordinates = {k: v for k, v in table.items() if k not in _TRAJECTORY_KEYS}
    if kind == "platform":
        _unknown(coordinates, set(POSE_COORDINATES), w)
        if preset not in (None, "reference"):
            raise SceneError(f"{w}: preset={preset!r} is not known; use 'reference' or give x, z, roll, pitch, yaw", key="preset", value=preset)
        if preset is None and set(coordinates) != set(POSE_COORDINATES):
            raise SceneError(f"{w}: a platform trajectory needs preset = 'reference' or all of {', '.join(POSE_COORDINATES)}")
    elif preset is not None:
        raise SceneError(f"{w}: preset is only for platform trajectories")
    functions = {}
    for name, coordinate in coordinates.items():
        if not isinstance(coordinate, dict):
            raise SceneError(f"{w}: {name} must be a table {{offset, rate, amplitudes, harmonics, phases}}")
        if kind == "joints" and coordinate.get("function", "fourier") != "fourier":
            from robot.scene.values import time_function  # imports this module: import on use

            functions[name] = time_function(coordinate, f"{w} {name}", base_dir)
            continue
        _unknown(coordinate, _COORDINATE_KEYS | ({"function"} if kind == "joints" else set()), f"{w} {name}")
        _fourier_numbers(coordinate, f"{w} {name}")
    return TrajectorySpec(kind, period, preset, coordinates, functions)


def _fourier_numbers(coordinate: dict, where: str) -> None:
    """A Fourier coordinate's ``offset`` and ``rate`` finite numbers; its three lists of finite numbers, of one length."""
    for key in ("offset", "rate"):
        _number(coordinate, key, where)
    lengths = set()
    for key in ("amplitudes", "harmonics", "phases"):
        values = coordinate.get(key, [])
        if not isinstance(values, list):
            raise SceneError(f"{where}: {key}={values!r} must be a list of finite numbers", key=key, value=values)
        for index, value in enumerate(values):
            _number({f"{key}[{index}]": value}, f"{key}[{index}]", where)
        lengths.add(len(values))
    if len(lengths) > 1:
        raise SceneError(f"{where}: amplitudes, harmonics and phases must have the same length")


def load_scene(name_or_path: str | Path, overrides: Mapping[str, Any] | None = None, **top_level: Any) -> Scene:
    """Read and validate a scene.

    ``overrides``: key paths and values (``{"solver.rtol": 1e-8,
    "clearance.R1.radial_clearance": 2e-4}``, :mod:`robot.scene.overrides`);
    ``top_level``: top-level keys as keyword arguments (``duration=0.1``; ``None``
    values are ignored). Both are validated like the file itself.
    """
    path = resolve_scene_path(name_or_path)
    data = _read(path)
    base_dir = Path(data.pop("__dir__"))
    data = apply_overrides(data, {**(overrides or {}), **{k: v for k, v in top_level.items() if v is not None}})
    return scene_from_document(data, path, base_dir)


def solver_options(solver_table: dict, where: str) -> SolverOptions:
    """``[solver]``: a registered method and its tolerances (fixed-step methods need ``first_step``)."""
    w = f"{where} [solver]"
    _unknown(solver_table, _SOLVER_KEYS, w)
    method = solver_table.get("method", "RK45")
    if not isinstance(method, str):
        raise SceneError(f"{w}: method={method!r} must be a method name (a string); choose one of {', '.join(METHODS)}", key="method", value=method)
    if method not in METHODS:
        hint = " (the CVODE methods need the scikit-sundae package: pip install scikit-sundae)" if method.startswith("CVODE") else ""
        raise SceneError(f"{w}: method={method!r} is not on offer{hint}; choose one of {', '.join(METHODS)}", key="method", value=method)
    numbers = (
        _rtol(solver_table, w),
        _number(solver_table, "atol", w, 1e-9, low=ATOL_RANGE[0], high=ATOL_RANGE[1]),
        _number(solver_table, "max_step", w, 1e-3, low=0.0, low_open=True),
        _number(solver_table, "first_step", w, None, low=0.0, low_open=True),
    )
    try:
        solver = SolverOptions(method, *numbers, jacobian=solver_table.get("jacobian", STRUCTURED))
    except ValueError as exc:  # SolverOptions checks its choices (the jacobian)
        raise SceneError(f"{w}: {exc}", key=getattr(exc, "key", None), value=getattr(exc, "value", None)) from None
    if method in FIXED_STEP_METHODS and solver.first_step is None:
        raise SceneError(f"{w}: the fixed-step method {method} needs first_step (its step size)", key="first_step", value=None)
    return solver


def smallest_step(method: str, limits: FailureLimits) -> float:
    """The smallest ``max_step`` a run of ``method`` can take: ``limits.min_step`` (a smaller step is a
    step-size collapse), or the method's own floor if larger (CVODE is given ``min_step`` 1e-12 s and
    refuses a smaller ``max_step``)."""
    own = getattr(METHODS[method], "min_step", None)
    return max(limits.min_step, float(own)) if isinstance(own, (int, float)) and not isinstance(own, bool) else limits.min_step


def check_steps(solver: SolverOptions, limits: FailureLimits, where: str) -> None:
    """A variable-step method's ``[solver] max_step`` not below :func:`smallest_step`, its ``first_step`` not below
    ``limits.min_step``: such a run could never proceed, every step would be a step-size collapse (CVODE refuses
    the ``max_step`` outright). ``min_step`` is no limit of the fixed-step methods (their step is ``first_step``).
    """
    if solver.method in FIXED_STEP_METHODS:
        return
    w = f"{where} [solver]"
    floor = smallest_step(solver.method, limits)
    if solver.max_step < floor:
        bound = f"limits.min_step = {limits.min_step:g} s"
        if floor > limits.min_step:
            bound = f"{floor:g} s, the smallest step {solver.method} takes (limits.min_step = {limits.min_step:g} s)"
        raise SceneError(
            f"{w}: max_step={solver.max_step!r} must be >= {bound}: a run with a smaller largest step can never proceed",
            key="max_step",
            value=solver.max_step,
        )
    if solver.first_step is not None and solver.first_step < limits.min_step:
        raise SceneError(
            f"{w}: first_step={solver.first_step!r} must be >= limits.min_step = {limits.min_step:g} s: a first step below it is a step-size collapse",
            key="first_step",
            value=solver.first_step,
        )


def rtol_floor_reason(rtol: Any) -> str:
    """Why an rtol below :data:`RTOL_RANGE` is refused, to append to the message ("" for any other value):
    one wording for the scenes and ``clearance work-precision``."""
    below = isinstance(rtol, (int, float)) and not isinstance(rtol, bool) and 0 < rtol < RTOL_RANGE[0]
    return " (scipy's integrators replace an rtol below 100 eps = 2.2e-14 by 2.2e-14)" if below else ""


def _rtol(solver_table: dict, where: str) -> float:
    """``rtol`` in :data:`RTOL_RANGE`; below it, the message says why (the integrators would not honour it)."""
    try:
        return _number(solver_table, "rtol", where, 1e-7, low=RTOL_RANGE[0], high=RTOL_RANGE[1])
    except SceneError as exc:
        value = solver_table.get("rtol")
        if rtol_floor_reason(value):
            raise SceneError(f"{exc}{rtol_floor_reason(value)}", key="rtol", value=value) from None
        raise


def _baumgarte(table: dict, where: str) -> Baumgarte:
    w = f"{where} [baumgarte]"
    _unknown(table, _BAUMGARTE_KEYS, w)
    return Baumgarte(_number(table, "alpha", w, 5.0, low=0.0, high=1e6), _number(table, "beta", w, 5.0, low=0.0, high=1e6))


def _limits(table: dict, where: str) -> FailureLimits:
    w = f"{where} [limits]"
    _unknown(table, _LIMIT_KEYS, w)
    defaults = FailureLimits()
    return FailureLimits(
        _number(table, "penetration_ratio", w, defaults.penetration_ratio, low=0.0, low_open=True),
        _number(table, "max_residual", w, defaults.max_residual, low=0.0, low_open=True),
        _number(table, "min_step", w, defaults.min_step, low=0.0),
        _number(table, "max_wall_time", w, defaults.max_wall_time, low=0.0, low_open=True),
        _number(table, "max_steps", w, defaults.max_steps, low=1.0),
    )


def scene_from_document(data: dict[str, Any], path: Path, base_dir: Path) -> Scene:
    """Validate a scene's TOML document (``extends`` already merged); relative paths from ``base_dir``.

    The user's extension modules (``CLEARANCE_EXTENSIONS``, :mod:`robot.extensions`) are imported first, in
    every process that validates a scene (a sweep's workers too), so the names they register are known.
    """
    load_extensions()
    document = copy.deepcopy(data)
    data = copy.deepcopy(data)
    where = f"scene {path.name}"
    _unknown(data, _TOP_KEYS, where)
    mechanism_path = resolve_mechanism(data.get("mechanism"), base_dir, where)
    name = data.get("name", path.stem)
    if not isinstance(name, str):
        raise SceneError(f"{where}: name={name!r} must be a string", key="name", value=name)
    solver = solver_options(_table(data, "solver", where), where)
    baumgarte = _baumgarte(_table(data, "baumgarte", where), where)
    limits = _limits(_table(data, "limits", where), where)
    check_steps(solver, limits, where)
    materials = _materials(data, where)
    clearance_list = data.get("clearance", [])
    if not isinstance(clearance_list, list):
        raise SceneError(f"{where}: clearance must be an array of tables [[clearance]]")
    clearances = tuple(_clearance(t, i, materials, where) for i, t in enumerate(clearance_list))
    joints = [c.joint for c in clearances]
    if len(set(joints)) != len(joints):
        raise SceneError(f"{where}: a joint carries two clearance definitions: {joints}")
    _check_site_kinds(clearances, mechanism_path, where)
    initial = _table(data, "initial", where)
    misalignment = _misalignment(initial, clearances, where)
    output = _output(_table(data, "output", where), {c.joint: c.law.result_keys() for c in clearances}, where)
    if output.step is not None:
        solver = dataclasses.replace(solver, output_step=output.step)
    duration = _number(data, "duration", where, required=True, low=0.0, low_open=True)
    trajectory = _trajectory(_table(data, "trajectory", where), where, base_dir)
    from robot.scene import forces as F  # imports this module: import on use

    forces, actuators = F.force_specs(data, where, base_dir), F.actuator_specs(_table(data, "actuators", where), where, base_dir)
    F.check_time_tables(trajectory, actuators, forces, duration, where)
    end_effector = data.get("end_effector", "platform")
    if not isinstance(end_effector, str):
        raise SceneError(f"{where}: end_effector={end_effector!r} must be a frame name", key="end_effector", value=end_effector)
    return Scene(
        name=name,
        path=path,
        description=str(data.get("description", "")),
        mechanism_path=mechanism_path,
        end_effector=end_effector,
        duration=duration,
        trajectory=trajectory,
        solver=solver,
        baumgarte=baumgarte,
        limits=limits,
        clearances=clearances,
        misalignment_deg=misalignment,
        output=output,
        forces=forces,
        actuators=actuators,
        document=document,
        base_dir=base_dir,
        gravity=_gravity(data, where),
        initial_positions=_joint_values(initial, "positions", f"{where} [initial]"),
        initial_velocities=_joint_values(initial, "velocities", f"{where} [initial]"),
        clearance_state=_clearance_state(initial, f"{where} [initial]"),
        document_clearances=clearances,
    )


def _clearance_state(table: dict, where: str) -> str:
    """``[initial] clearance_state``: one of :data:`CLEARANCE_STATES`."""

    value = table.get("clearance_state", "centred")
    if value not in CLEARANCE_STATES:
        raise SceneError(
            f"{where}: clearance_state={value!r} must be one of {', '.join(repr(v) for v in CLEARANCE_STATES)}",
            key="initial.clearance_state",
            value=value,
        )
    return value


def _gravity(data: dict, where: str) -> tuple[float, float, float]:
    """``gravity = [gx, gy, gz]`` (m/s^2, world axes): three finite numbers."""
    value = data.get("gravity", [0.0, 0.0, -9.81])
    ok = isinstance(value, list) and len(value) == 3
    ok = ok and all(not isinstance(x, bool) and isinstance(x, (int, float)) and math.isfinite(x) for x in value)
    if not ok:
        raise SceneError(f"{where}: gravity={value!r} must be three finite numbers [gx, gy, gz] in m/s^2 (world axes)")
    return tuple(float(x) for x in value)


def _joint_values(table: dict, key: str, where: str) -> dict[str, float]:
    """A table ``{JOINT = number}`` (the joint names are checked against the mechanism by robot.run.build_run)."""
    values = table.get(key, {})
    if not isinstance(values, dict):
        raise SceneError(f"{where}: {key}={values!r} must be a table {{JOINT = value}}")
    return {joint: _number(values, joint, f"{where} {key}") for joint in values}


def misalignment_rotation(degrees: float) -> np.ndarray:
    """Rotation of the bearing about its local x axis by ``degrees`` (positive: counter-clockwise seen from +x)."""
    angle = math.radians(degrees)
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])
