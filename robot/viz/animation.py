"""Playing a saved simulation in meshcat: live in a browser, or as one self-contained HTML file.

The mechanism is rebuilt from the result's metadata (mechanism file and
clearance joints) and checked against the result's URDF fingerprint; the links
are drawn from the URDF visuals (Pinocchio geometry model, coal primitives) at
their simulated poses. Each clearance joint adds its two elements as its type draws
them (``ClearanceJoint.drawing``: translucent socket + ball, or bearing tube +
journal with flanges), a trail of the inner element's centre and contact-force
arrows.

Exaggeration (``exaggerate = K``) magnifies only what happens *inside* the
clearance joints, so sub-millimetre motion becomes visible:

* the outer element (socket, bearing) is drawn at its true pose;
* the inner element (ball, journal) is drawn with its centre displaced from the
  outer element's centre by ``K`` times the true displacement; for a revolute
  joint the tilt of the journal axis relative to the bearing axis is magnified
  too, ``tan(drawn tilt) = K tan(true tilt)`` (the spin about the axis is true);
* the gaps are magnified by the same factor (the type's ``magnified``): socket
  radius ``r_ball + K c``, bearing bore ``r_journal + K c_r`` (wall thickness true),
  journal length between flanges ``L_bearing + K c_a``; so the elements touch in the picture
  exactly when they touch in the simulation, and a penetration ``delta`` is drawn
  as ``K delta``;
* links, element radii and lengths other than the gaps are true to scale.

Trails show the inner element's centre relative to the outer element (drawn in
the moving outer frame, magnified by ``K``), growing as the animation plays.
Force arrows end at the contact point of the drawn joint's own contact law (the
type built with magnified gaps) and point along the normal force on the
inner element; length ``arrow_length * F / F_max`` (``F_max``: the largest
normal force of the whole result). Each arrow shows the largest force recorded
within its frame's time window, so impacts shorter than one frame still appear.

Frames are sampled at ``fps`` frames per second of playback, i.e. every
``speed / fps`` seconds of simulated time (configurations interpolated on the
configuration manifold between recorded states).
"""

from __future__ import annotations

import base64
import html as html_lib
import math
import re
import time
import uuid
import warnings
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Mapping

import coal
import numpy as np
import pinocchio as pin

from clearance_contact import STEEL, ClearanceJoint, ContactError, NoFriction, Shape, joint_type, joint_types

from robot.io.atomic import atomic_write
from robot.errors import ResultFileError, RobotError
from robot.model.mechanism import Mechanism, build_mechanism, rotation_z_to
from robot.data import shipped_urdf
from robot.io.results import SimulationResult, load_result, mechanism_fingerprint

OUTER_COLOR = 0x7FA7D0
INNER_COLOR = 0xE0A020
TRAIL_COLOR = 0xC000C0
ARROW_COLOR = 0xE01010
BACKGROUND = ([1.0, 1.0, 1.0], [0.86, 0.88, 0.91])
LINK_OPACITY = 0.35  # links that carry a clearance element
ROOT = "mechanism"  # meshcat node (under /meshcat) holding everything drawn
#: the largest magnification of the motion inside the clearance joints: beyond it the drawn gaps and offsets
#: outgrow any view (and, near 1e38, meshcat's 32-bit floats, which then write infinities into the page)
MAX_EXAGGERATION = 1e6


class AnimationError(RobotError, ValueError):
    """Animation options are out of range (speed, exaggeration, frame rate, frame count)."""


@dataclass(frozen=True)
class AnimationOptions:
    """How a result is played back.

    ``speed``: simulated seconds per second of playback (0.1 = ten times slower
    than real time). ``exaggerate``: magnification ``K >= 1`` of the motion
    inside the clearance joints (module docstring). ``fps``: frames per second of
    playback. ``arrow_length``: drawn length (m) of the largest normal force.
    ``max_frames``: refuse longer animations (they make huge files). ``focus``:
    name of a clearance joint the camera looks at from close by.
    """

    speed: float = 1.0
    exaggerate: float = 1.0
    fps: float = 30.0
    arrow_length: float = 0.15
    trail_segments: int = 200
    max_frames: int = 6000
    loop: bool = True
    focus: str | None = None  # a clearance joint to centre the view on (default: the whole mechanism)

    def check(self) -> None:
        for name in ("speed", "fps", "arrow_length"):
            value = getattr(self, name)
            if not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0):
                raise AnimationError(f"{name}={value!r} must be a positive finite number")
        if not (isinstance(self.exaggerate, (int, float, np.floating)) and 1.0 <= self.exaggerate <= MAX_EXAGGERATION):
            raise AnimationError(
                f"exaggerate={self.exaggerate!r} is outside the valid range [1, {MAX_EXAGGERATION:,.0f}] "
                "(1 = true scale; 1e6 draws a 0.1 mm gap 100 m wide)",
                key="exaggerate", value=self.exaggerate,
            )
        if self.trail_segments < 1 or self.max_frames < 1:
            raise AnimationError("trail_segments and max_frames must be positive")


@dataclass(frozen=True)
class ElementSizes:
    """Dimensions of a clearance joint's elements (m), true scale.

    ``kind``: the joint type's name (:func:`clearance_contact.joint_type`); ``values``:
    its ``GEOMETRY_KEYS`` (e.g. ``ball_radius``, ``clearance``), as the scene gave them;
    ``parameters``: its other scene keys when the result records them (the drawn law
    needs e.g. a stiffness a type has no default for).
    """

    kind: str
    values: dict[str, float]
    source: str = "default"
    parameters: dict[str, float | str] = field(default_factory=dict)

    @property
    def joint_type(self) -> type[ClearanceJoint]:
        return joint_type(self.kind)


@dataclass
class Frames:
    """The sampled frames: simulated times, configurations and per-site normal forces."""

    t: np.ndarray
    q: np.ndarray
    normal_force: dict[str, np.ndarray]
    force_scale: float  # N drawn as arrow_length


@dataclass
class AnimationSummary:
    """What was drawn: frame count, timing and where the element sizes came from."""

    n_frames: int
    fps: float
    speed: float
    exaggerate: float
    t_start: float
    t_end: float
    sizes: dict[str, ElementSizes]
    max_normal_force: float
    html_path: Path | None = None
    html_bytes: int = 0
    url: str | None = None
    notes: list[str] = field(default_factory=list)

    @property
    def playback_seconds(self) -> float:
        return (self.n_frames - 1) / self.fps


# --------------------------------------------------------------------------- loading


def load_for_animation(
    result: str | Path | SimulationResult, urdf: str | Path | None = None
) -> tuple[Mechanism, SimulationResult]:
    """The result and the mechanism it was computed with (rebuilt and fingerprint-checked).

    ``urdf`` defaults to the first of these whose URDF fingerprint is the result's:
    the file the run read (metadata ``mechanism_path``), then the shipped file of the
    same name (metadata ``mechanism``: a result moved to another machine).
    Raises :class:`ResultFileError` for a missing or malformed result, or when no
    mechanism file tried matches (the message names each one and why).
    """
    label = "result" if isinstance(result, SimulationResult) else f"result file {str(result)!r}"
    if not isinstance(result, SimulationResult):
        result = load_result(result)
    metadata = result.metadata if isinstance(result.metadata, dict) else {}
    candidates = [Path(urdf)] if urdf is not None else _recorded_mechanism_files(metadata, label)
    urdf = _matching_mechanism_file(candidates, metadata, label)
    choice = _clearance_choice(metadata, label)
    mechanism = build_mechanism(urdf, choice)
    _check_arrays(mechanism, result, label, site_types(mechanism, result, label))
    return mechanism, result


def _recorded_mechanism_files(metadata: Mapping[str, Any], label: str) -> list[Path]:
    """Where the result's mechanism file may be: the path the run read, then the shipped file of that name."""
    name, recorded = metadata.get("mechanism"), metadata.get("mechanism_path")
    candidates = [Path(recorded)] if isinstance(recorded, str) and recorded else []
    if isinstance(name, str) and name:
        candidates.append(shipped_urdf(name))
    if not candidates:
        raise ResultFileError(f"{label} does not name its mechanism file (metadata 'mechanism'); pass the URDF explicitly (--urdf)")
    return candidates


def _matching_mechanism_file(candidates: list[Path], metadata: Mapping[str, Any], label: str) -> Path:
    """The first candidate whose text has the result's URDF fingerprint: a user's file may share a shipped file's name."""
    tried = []
    for path in candidates:
        if not path.is_file():
            tried.append(f"{str(path)!r} (does not exist)")
            continue
        if metadata.get("urdf_sha256") == mechanism_fingerprint(path.read_text(encoding="utf-8")):
            return path
        tried.append(f"{str(path)!r} (its URDF fingerprint differs: another version or another mechanism)")
    raise ResultFileError(
        f"{label} was computed with mechanism {metadata.get('mechanism')!r}, and no mechanism file tried matches it: "
        f"{'; '.join(tried)}; pass the file the result was computed with (--urdf)"
    )


def site_types(mechanism: Mechanism, result: SimulationResult, label: str = "result") -> dict[str, type[ClearanceJoint]]:
    """The joint type of each clearance joint: metadata ``clearance_type`` (older results: the joint's kind)."""
    recorded = result.metadata.get("clearance_type") if isinstance(result.metadata, Mapping) else None
    recorded = recorded if isinstance(recorded, Mapping) else {}
    out = {}
    for site in mechanism.clearance_sites:
        name = recorded.get(site.name, site.kind)
        try:
            out[site.name] = joint_type(name)
        except ContactError:
            raise ResultFileError(
                f"{label}: clearance joint {site.name!r} is of type {name!r}, which is not registered "
                f"(registered: {', '.join(joint_types())}); import the module that registers it first"
            ) from None
    return out


def _clearance_choice(metadata: Mapping[str, Any], label: str) -> dict[str, str]:
    clearance = metadata.get("clearance", [])
    outer_on = metadata.get("clearance_outer_on", {})
    if isinstance(clearance, Mapping):
        choice = {str(k): str(v) for k, v in clearance.items()}
    elif isinstance(clearance, list) and all(isinstance(c, str) for c in clearance):
        choice = {c: "child" for c in clearance}
    else:
        raise ResultFileError(f"{label}: metadata 'clearance' = {clearance!r} must list the clearance joints")
    if isinstance(outer_on, Mapping):
        choice.update({k: str(v) for k, v in outer_on.items() if k in choice})
    return choice


def _check_arrays(mechanism: Mechanism, result: SimulationResult, label: str, types: Mapping[str, type[ClearanceJoint]]) -> None:
    arrays = result.arrays
    if "q" not in arrays:
        raise ResultFileError(f"{label} was saved without the array 'q' (the scene's [output] keep); rerun keeping \"q\" to animate it")
    t, q = np.asarray(arrays["t"]), np.asarray(arrays["q"])
    n = t.shape[0] if t.ndim == 1 else -1
    if n < 1:
        raise ResultFileError(f"{label}: 't' must be a non-empty 1-D array, got shape {t.shape}")
    if q.shape != (n, mechanism.model.nq):
        raise ResultFileError(
            f"{label}: 'q' has shape {q.shape}, expected ({n}, {mechanism.model.nq}) for mechanism "
            f"{mechanism.name!r} with clearance joints {list(mechanism.clearance_names)}"
        )
    if n > 1 and np.any(np.diff(t) < 0):
        raise ResultFileError(f"{label}: times 't' are not sorted")
    for site in mechanism.clearance_sites:
        k = types[site.name].N_CANDIDATES
        key = f"{site.name}_normal_force"
        if key not in arrays:
            raise ResultFileError(f"{label} lacks the array {key!r} of clearance joint {site.name!r}")
        if np.shape(arrays[key]) != (n, k):
            raise ResultFileError(f"{label}: {key!r} has shape {np.shape(arrays[key])}, expected ({n}, {k})")


# --------------------------------------------------------------------------- element sizes


def clearance_sizes(mechanism: Mechanism, result: SimulationResult) -> tuple[dict[str, ElementSizes], list[str]]:
    """Element dimensions per clearance joint, and notes on where they came from.

    Sources, first found: the result's metadata ``clearance_geometry`` (joint ->
    table with its type's ``GEOMETRY_KEYS``, the scene's key names), written by
    :func:`robot.run.run_scene`; otherwise the type's ``DEFAULT_GEOMETRY``. Sizes
    the type can measure from the result itself (``geometry_from_result``: the
    spherical clearance as |eccentricity| - penetration) are taken from it if they
    differ by more than 2 %.
    """
    notes: list[str] = []
    metadata = result.metadata
    tables: dict[str, dict] = {}
    source = "default"
    geometry = metadata.get("clearance_geometry")
    if isinstance(geometry, Mapping):
        tables = {k: dict(v) for k, v in geometry.items() if isinstance(v, Mapping)}
        source = "result metadata"
    recorded = metadata.get("clearance_parameters")
    recorded = {k: dict(v) for k, v in recorded.items() if isinstance(v, Mapping)} if isinstance(recorded, Mapping) else {}
    sizes = {}
    for site in mechanism.clearance_sites:
        law_type = site_types(mechanism, result)[site.name]
        table = {**law_type.DEFAULT_GEOMETRY, **tables.get(site.name, {})}
        origin = source if site.name in tables else "default"
        if origin == "default":
            notes.append(f"{site.name}: element sizes not recorded in the result; drawn with default sizes")
        values = {key: float(table[key]) for key in law_type.GEOMETRY_KEYS}
        measured = law_type.geometry_from_result(result.arrays.get(f"{site.name}_eccentricity"), result.arrays.get(f"{site.name}_penetration"))
        for key, value in measured.items():
            if abs(value - values[key]) > 0.02 * abs(values[key]):
                notes.append(f"{site.name}: {key} {value:.4g} m taken from the result data (source said {values[key]:.4g} m)")
                values[key] = value
                origin = f"{origin}; {key} from result data"
        parameters = {
            key: value if key in law_type.NAME_KEYS else float(value)  # names of models stay text
            for key, value in recorded.get(site.name, {}).items()
            if key in law_type.SCENE_KEYS and key not in values
        }
        sizes[site.name] = ElementSizes(law_type.type_name, values, source=origin, parameters=parameters)
    return sizes, notes


# --------------------------------------------------------------------------- frames


def frame_count(t_start: float, t_end: float, speed: float, fps: float) -> int:
    """Frames of an animation of simulated times [t_start, t_end]: the first at t_start, then one every speed/fps s."""
    return int(math.floor((t_end - t_start) * fps / speed + 1e-9)) + 1


def sample_frames(mechanism: Mechanism, result: SimulationResult, options: AnimationOptions) -> tuple[Frames, list[str]]:
    """Configurations and peak normal forces at the animation frames."""
    notes = []
    model = mechanism.model
    t = np.asarray(result["t"], dtype=float)
    q = np.asarray(result["q"], dtype=float)
    finite = np.all(np.isfinite(q), axis=1) & np.isfinite(t)
    if not finite.all():
        last = int(np.argmin(finite))  # first non-finite record
        if last == 0:
            raise ResultFileError("the result's first state is not finite: nothing to animate")
        notes.append(f"states after t = {t[last - 1]:.6g} s are not finite and are not shown")
        t, q = t[:last], q[:last]
    n_records = len(t)
    t0, t1 = float(t[0]), float(t[-1])
    n = frame_count(t0, t1, options.speed, options.fps)
    if n > options.max_frames:
        raise AnimationError(
            f"{t1 - t0:.4g} s of simulation at speed {options.speed:g} and {options.fps:g} fps is {n} frames "
            f"(more than {options.max_frames}); raise the speed or lower the frame rate"
        )
    dt = options.speed / options.fps
    times = t0 + dt * np.arange(n)
    q_frames = np.empty((n, model.nq))
    for k, tk in enumerate(times):
        i = int(np.searchsorted(t, tk, side="right"))
        if i >= n_records:
            q_frames[k] = q[-1]
        elif i == 0:
            q_frames[k] = q[0]
        else:
            span = t[i] - t[i - 1]
            alpha = 0.0 if span <= 0 else (tk - t[i - 1]) / span
            q_frames[k] = pin.interpolate(model, q[i - 1], q[i], float(alpha))
    forces = {}
    peak = 0.0
    for site in mechanism.clearance_sites:
        f = np.asarray(result[f"{site.name}_normal_force"], dtype=float)[:n_records]
        f = np.where(np.isfinite(f), np.maximum(f, 0.0), 0.0)
        peak = max(peak, float(f.max(initial=0.0)))
        out = np.zeros((n, f.shape[1]))
        lo = np.searchsorted(t, times - dt / 2, side="left")
        hi = np.searchsorted(t, times + dt / 2, side="left")
        for k in range(n):
            window = f[lo[k]:hi[k]]
            interpolated = np.array([np.interp(times[k], t, f[:, j]) for j in range(f.shape[1])])
            out[k] = np.maximum(interpolated, window.max(axis=0)) if len(window) else interpolated
        forces[site.name] = out
    return Frames(times, q_frames, forces, peak), notes


# --------------------------------------------------------------------------- geometry helpers


def _exaggerated_inner(outer: pin.SE3, inner: pin.SE3, law_type: type[ClearanceJoint], k: float) -> pin.SE3:
    """Drawn pose of the inner element: offset from the outer centre magnified by the type
    (``exaggerated_offset``: times k), and axis tilt if ``EXAGGERATE_TILT``."""
    offset = law_type.exaggerated_offset(outer.rotation.T @ (inner.translation - outer.translation), k)
    position = outer.translation + outer.rotation @ offset
    if not law_type.EXAGGERATE_TILT or k == 1.0:
        return pin.SE3(inner.rotation, position)
    relative = outer.rotation.T @ inner.rotation
    z = relative[:, 2]
    tilt = math.acos(max(-1.0, min(1.0, float(z[2]))))
    axis = np.array([-z[1], z[0], 0.0])  # e_z x z
    if tilt < 1e-15 or np.linalg.norm(axis) < 1e-15:
        return pin.SE3(inner.rotation, position)
    axis /= np.linalg.norm(axis)
    swing = pin.exp3(axis * tilt)
    twist = swing.T @ relative
    drawn = math.atan(k * math.tan(tilt)) if tilt < math.pi / 2 else tilt
    return pin.SE3(outer.rotation @ pin.exp3(axis * drawn) @ twist, position)


def _y_to(direction: np.ndarray) -> np.ndarray:
    """A rotation whose second column (meshcat's cylinder axis y) is ``direction``."""
    return rotation_z_to(direction)[:, [1, 2, 0]]


def _homogeneous(rotation: np.ndarray, translation: np.ndarray) -> np.ndarray:
    matrix = np.eye(4)
    matrix[:3, :3] = rotation
    matrix[:3, 3] = translation
    return matrix


def _drawing_law(size: ElementSizes, k: float) -> ClearanceJoint | None:
    """The contact law of the *drawn* joint (gaps magnified by k), used only for its contact points; None if unavailable."""
    law_type = size.joint_type
    try:
        return law_type.from_scene({**size.parameters, **law_type.magnified(size.values, k)}, STEEL, STEEL, 0.9, NoFriction())
    except Exception:  # noqa: BLE001 - e.g. sizes a type rejects: the arrows are then not drawn
        return None


def _law_contacts(law, outer: pin.SE3, inner_drawn: pin.SE3):
    """Contact points and force directions on the inner element from the contact law; None if it refuses the pose.

    Each arrow sits half-way between the two contact points, where the laws apply the force.
    """
    if law is None:
        return None
    try:
        zero = np.zeros(6)
        r = law.evaluate(outer.rotation, outer.translation, zero, inner_drawn.rotation, inner_drawn.translation, zero, np.zeros(law.n_candidates))
    except Exception:  # noqa: BLE001 - e.g. a drawn tilt the law does not accept
        return None
    points = 0.5 * (np.asarray(r.point_inner) + np.asarray(r.point_outer))
    return [(points[j], -np.asarray(r.normal[j])) for j in range(law.n_candidates)]


def _tube_mesh(inner: float, outer: float, length: float, segments: int = 64):
    """Vertices and faces of a hollow cylinder along z, centred at the origin."""
    a = np.linspace(0.0, 2 * np.pi, segments, endpoint=False)
    c, s = np.cos(a), np.sin(a)
    h = 0.5 * length
    vertices, faces = [], []

    def band(r0, z0, r1, z1):
        base = sum(len(v) for v in vertices)
        vertices.append(np.column_stack([np.concatenate([r0 * c, r1 * c]), np.concatenate([r0 * s, r1 * s]),
                                         np.concatenate([np.full(segments, z0), np.full(segments, z1)])]))
        for i in range(segments):
            j = (i + 1) % segments
            faces.append([base + i, base + j, base + segments + j])
            faces.append([base + i, base + segments + j, base + segments + i])

    band(outer, -h, outer, h)
    band(inner, h, inner, -h)
    band(inner, h, outer, h)
    band(outer, -h, inner, -h)
    return np.vstack(vertices), np.array(faces)


# --------------------------------------------------------------------------- meshcat scene


def _meshcat():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DeprecationWarning)  # meshcat imports zmq.eventloop.ioloop
        import meshcat
        import meshcat.geometry as mg

    return meshcat, mg


def _shifted(geometry_cls, matrix: np.ndarray):
    """A meshcat geometry class with an intrinsic transform (meshcat flattens it row-major; three.js reads column-major)."""
    return type(f"Placed{geometry_cls.__name__}", (geometry_cls,), {"intrinsic_transform": lambda self: matrix.T.copy()})


def _translation(x=0.0, y=0.0, z=0.0) -> np.ndarray:
    matrix = np.eye(4)
    matrix[:3, 3] = (x, y, z)
    return matrix


_Z_FROM_Y = np.array([[1.0, 0, 0, 0], [0, 0, -1.0, 0], [0, 1.0, 0, 0], [0, 0, 0, 1.0]])  # maps meshcat's y axis to z


def _material(mg, color: int, opacity: float = 1.0):
    # translucent objects must not write depth, or whatever lies inside them (ball in socket, ball in piston) vanishes
    return mg.MeshPhongMaterial(color=color, opacity=opacity, transparent=opacity < 1.0, depthWrite=opacity >= 1.0)


def _meshcat_shape(mg, shape: Shape):
    """The meshcat geometry of a :class:`clearance_contact.Shape` (cylinders and tubes along the element's z)."""
    place = _translation(*shape.centre)
    if shape.kind == "sphere":
        return mg.Sphere(shape.radius) if not any(shape.centre) else _shifted(mg.Sphere, place)(shape.radius)
    if shape.kind == "cylinder":
        return _shifted(mg.Cylinder, place @ _Z_FROM_Y)(shape.length, shape.radius)
    if shape.kind == "tube":
        vertices, faces = _tube_mesh(shape.inner_radius, shape.radius, shape.length)
        return mg.TriangularMeshGeometry(vertices + np.asarray(shape.centre), faces)
    if shape.kind == "box":
        return _shifted(mg.Box, place)(list(shape.size))
    raise AnimationError(f"shape {shape.name!r}: kind={shape.kind!r} is not drawable; use sphere, cylinder, tube or box")


def _shape_material(mg, shape: Shape):
    return _material(mg, OUTER_COLOR if shape.element == "outer" else INNER_COLOR, shape.opacity)


def _draw_static(vis, mechanism: Mechanism, sizes: Mapping[str, ElementSizes], options: AnimationOptions):
    """Create every object (URDF visuals, clearance elements, arrows); return the pinocchio visualizer."""
    meshcat, mg = _meshcat()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        from pinocchio.visualize import MeshcatVisualizer

        viz = MeshcatVisualizer(mechanism.model, None, mechanism.visual_model)
        viz.initViewer(viewer=vis)
        viz.loadViewerModel(rootNodeName=f"{ROOT}/links")
        # the links carrying a clearance element are drawn translucent, to show the elements inside them
        carriers = {mechanism.model.frames[f].parentJoint for site in mechanism.clearance_sites for f in (site.outer_frame, site.inner_frame)}
        for geometry in mechanism.visual_model.geometryObjects:
            if geometry.parentJoint in carriers and isinstance(geometry.geometry, coal.ShapeBase):
                shape = viz.loadPrimitive(geometry)
                if shape is not None:
                    color = np.asarray(geometry.meshColor, dtype=float)
                    rgb = int(color[0] * 255) * 65536 + int(color[1] * 255) * 256 + int(color[2] * 255)
                    vis[f"{ROOT}/links/visuals/{geometry.name}"].set_object(shape, _material(mg, rgb, min(float(color[3]), LINK_OPACITY)))
    k = options.exaggerate
    head_length, head_radius, shaft_radius = 0.2 * options.arrow_length, 0.06 * options.arrow_length, 0.02 * options.arrow_length
    for site in mechanism.clearance_sites:
        size = sizes[site.name]
        law_type = size.joint_type
        base = f"{ROOT}/clearance/{site.name}"
        for shape in law_type.drawing(law_type.magnified(size.values, k)):
            vis[f"{base}/{shape.element}/{shape.name}"].set_object(_meshcat_shape(mg, shape), _shape_material(mg, shape))
        vis[f"{base}/inner/centre"].set_object(mg.Sphere(0.12 * law_type.inner_radius(size.values)), _material(mg, TRAIL_COLOR))
        n_candidates = law_type.N_CANDIDATES
        for j in range(n_candidates):
            shaft = _shifted(mg.Cylinder, _translation(y=0.5))
            head = _shifted(mg.Cylinder, _translation(y=-0.5 * head_length))
            vis[f"{base}/force{j}/shaft"].set_object(shaft(1.0, shaft_radius), _material(mg, ARROW_COLOR))
            vis[f"{base}/force{j}/head"].set_object(head(head_length, radiusTop=0.0, radiusBottom=head_radius), _material(mg, ARROW_COLOR))
            for part in ("shaft", "head"):
                vis[f"{base}/force{j}/{part}"].set_property("visible", False)
    return viz, head_length


def build_scene(vis, mechanism: Mechanism, result: SimulationResult, options: AnimationOptions | None = None):
    """Draw the mechanism and its clearance elements in a meshcat visualizer and return (animation, summary)."""
    options = options or AnimationOptions()
    options.check()
    meshcat, mg = _meshcat()
    from meshcat.animation import Animation

    sizes, notes = clearance_sizes(mechanism, result)
    frames, frame_notes = sample_frames(mechanism, result, options)
    notes += frame_notes
    viz, head_length = _draw_static(vis, mechanism, sizes, options)
    model, data = mechanism.model, mechanism.model.createData()
    visual_model, visual_data = mechanism.visual_model, mechanism.visual_model.createData()
    k = options.exaggerate
    force_scale = frames.force_scale
    animation = Animation(default_framerate=options.fps)
    trails = {site.name: [] for site in mechanism.clearance_sites}
    laws = {name: _drawing_law(size, k) for name, size in sizes.items()}
    shown: dict[tuple[str, int], bool] = {}
    link_paths = [(i, f"{ROOT}/links/visuals/{g.name}", np.asarray(g.meshScale).ravel()) for i, g in enumerate(visual_model.geometryObjects)]
    for index, q in enumerate(frames.q):
        pin.framesForwardKinematics(model, data, q)
        pin.updateGeometryPlacements(model, data, visual_model, visual_data)
        frame = animation.at_frame(vis, index)
        for i, path, scale in link_paths:
            matrix = visual_data.oMg[i].homogeneous
            if index == 0:
                vis[path].set_transform(matrix @ np.diag(np.append(scale, 1.0)))
            frame[path].set_transform(matrix)
        for site in mechanism.clearance_sites:
            size = sizes[site.name]
            base = f"{ROOT}/clearance/{site.name}"
            outer, inner = data.oMf[site.outer_frame], data.oMf[site.inner_frame]
            drawn = _exaggerated_inner(outer, inner, size.joint_type, k)
            trails[site.name].append(size.joint_type.exaggerated_offset(outer.rotation.T @ (inner.translation - outer.translation), k))
            for part, pose in (("outer", outer), ("inner", drawn)):
                frame[f"{base}/{part}"].set_transform(pose.homogeneous)
                if index == 0:
                    vis[f"{base}/{part}"].set_transform(pose.homogeneous)
            contacts = _law_contacts(laws[site.name], outer, drawn)
            for j in range(size.joint_type.N_CANDIDATES):
                point, direction = contacts[j] if contacts else (outer.translation, outer.rotation[:, 2])
                force = float(frames.normal_force[site.name][index, j])
                on = force > 0.0 and force_scale > 0.0 and contacts is not None
                shaft, head = frame[f"{base}/force{j}/shaft"], frame[f"{base}/force{j}/head"]
                if on or index == 0:  # a hidden arrow needs no pose: keys only while visible keep files small
                    length = options.arrow_length * force / force_scale if on else 0.0
                    rotation = _y_to(direction)
                    shaft.set_transform(_homogeneous(rotation, point - length * direction))
                    shaft.set_property("scale", "vector3", [1.0, max(length - head_length, 1e-6), 1.0])
                    head.set_transform(_homogeneous(rotation, point))
                    head.set_property("scale", "vector3", [max(min(1.0, length / head_length), 1e-6)] * 3)
                key = (site.name, j)
                if index == 0 or shown[key] != on:  # discrete track: keys at the changes only
                    shaft.set_property("visible", "boolean", bool(on))
                    head.set_property("visible", "boolean", bool(on))
                shown[key] = on
    _draw_trails(vis, animation, trails, options)
    _set_view(vis, mechanism, frames.q[0], sizes, options.focus)
    summary = AnimationSummary(
        n_frames=len(frames.t), fps=options.fps, speed=options.speed, exaggerate=k,
        t_start=float(frames.t[0]), t_end=float(frames.t[-1]), sizes=sizes,
        max_normal_force=force_scale, notes=notes,
    )
    return animation, summary


def _draw_trails(vis, animation, trails: Mapping[str, list], options: AnimationOptions) -> None:
    """Growing trails: the path is cut into segments, each made visible when the animation reaches its end."""
    _, mg = _meshcat()
    for name, points in trails.items():
        points = np.asarray(points)
        n = len(points)
        if n < 2:
            continue
        cuts = np.unique(np.round(np.linspace(0, n - 1, min(n - 1, options.trail_segments) + 1)).astype(int))
        for j in range(len(cuts) - 1):
            a, b = int(cuts[j]), int(cuts[j + 1])
            path = f"{ROOT}/clearance/{name}/outer/trail/{j:04d}"
            geometry = mg.PointsGeometry(points[a:b + 1].T.astype(np.float32))
            vis[path].set_object(mg.Line(geometry, mg.LineBasicMaterial(color=TRAIL_COLOR)))
            vis[path].set_property("visible", False)
            animation.at_frame(vis, 0)[path].set_property("visible", "boolean", False)
            animation.at_frame(vis, b)[path].set_property("visible", "boolean", True)


def _shape_points(shape, scale: np.ndarray) -> np.ndarray:
    """Points on a visual's surface, in its own frame, that bound it closely (the view's sphere must hold them):
    a box's corners, a cylinder's or capsule's rims, a sphere's poles; another shape (a mesh): its bounding box."""
    if isinstance(shape, coal.Box):
        half = np.asarray(shape.halfSide, dtype=float)
        corners = np.array(np.meshgrid(*zip(-half, half), indexing="ij")).reshape(3, -1).T
    elif isinstance(shape, (coal.Cylinder, coal.Capsule)):
        angles = np.linspace(0.0, 2 * np.pi, 16, endpoint=False)
        ring = np.column_stack([shape.radius * np.cos(angles), shape.radius * np.sin(angles), np.zeros(16)])
        half = shape.halfLength + (shape.radius if isinstance(shape, coal.Capsule) else 0.0)
        corners = np.vstack([ring + (0.0, 0.0, -half), ring + (0.0, 0.0, half)])
    elif isinstance(shape, coal.Sphere):
        corners = shape.radius * np.vstack([np.eye(3), -np.eye(3)])
    else:
        shape.computeLocalAABB()
        box = shape.aabb_local
        corners = np.array(np.meshgrid(*zip(box.min_, box.max_), indexing="ij")).reshape(3, -1).T
    return corners * scale


def _view_points(mechanism: Mechanism, data: pin.Data, geometry_data: pin.GeometryData) -> np.ndarray:
    """The points the whole-mechanism view must hold: each visual's extent (a long link's origin is its
    middle, not its ends) and the origins of the link and joint frames (links without visuals)."""
    points = [frame.translation for frame in data.oMf[1:]] or [np.zeros(3)]
    for geometry, placement in zip(mechanism.visual_model.geometryObjects, geometry_data.oMg):
        try:
            local = _shape_points(geometry.geometry, np.asarray(geometry.meshScale, dtype=float).ravel())
        except (AttributeError, RuntimeError):  # a geometry coal cannot bound: its origin only
            local = np.zeros((1, 3))
        points.extend(local @ placement.rotation.T + placement.translation)
    points = np.array(points, dtype=float)
    finite = points[np.all(np.isfinite(points), axis=1)]  # a plane or half-space is unbounded
    return finite if len(finite) else np.zeros((1, 3))


def _set_view(vis, mechanism: Mechanism, q0: np.ndarray, sizes: Mapping[str, ElementSizes], focus: str | None = None) -> None:
    """Centre the view on the mechanism or on one clearance joint (the whole world is shifted rigidly) and place the camera."""
    model, data = mechanism.model, mechanism.model.createData()
    geometry_data = mechanism.visual_model.createData()
    pin.framesForwardKinematics(model, data, q0)
    pin.updateGeometryPlacements(model, data, mechanism.visual_model, geometry_data)
    points = _view_points(mechanism, data, geometry_data)
    low, high = points.min(axis=0), points.max(axis=0)
    centre = 0.5 * (low + high)
    radius = max(float(np.max(np.linalg.norm(points - centre, axis=1))), 0.1)  # the sphere that holds every point
    direction = np.array([1.0, 0.75, 0.45])
    if focus is not None:
        site = mechanism.site(focus)
        centre = np.array(data.oMf[site.outer_frame].translation)
        size = sizes[focus]
        shapes = size.joint_type.drawing(size.values)
        radius = 4.0 * max([s.extent for s in shapes] + [size.joint_type.inner_radius(size.values), 0.01])
        axis = data.oMf[site.outer_frame].rotation[:, 2]
        if site.kind == "revolute":  # look across the bearing rather than along it
            direction = direction - 0.85 * (direction @ axis) * axis
    shift = _translation(*(-centre))
    vis["/meshcat"].set_transform(shift)
    vis["/Axes"].set_transform(shift)
    # meshcat's 20 m grid renders badly in software WebGL: a floor grid the size of the mechanism instead
    vis["/Grid"].set_property("visible", False)
    _, mg = _meshcat()
    half = math.ceil(max(abs(low[0]), abs(high[0]), abs(low[1]), abs(high[1])) * 1.5 * 10) / 10
    ticks = np.arange(-half, half + 1e-9, 0.1)
    z = float(low[2]) - 0.05
    segments = [[(x, -half, z), (x, half, z)] for x in ticks] + [[(-half, y, z), (half, y, z)] for y in ticks]
    points = np.array(segments, dtype=np.float32).reshape(-1, 3).T
    vis[f"{ROOT}/floor"].set_object(mg.LineSegments(mg.PointsGeometry(points), mg.LineBasicMaterial(color=0xB0B0B0)))
    eye = 1.9 * radius * direction / np.linalg.norm(direction)
    vis["/Cameras/default/rotated/<object>"].set_property("position", [float(eye[0]), float(eye[2]), float(-eye[1])])
    vis["/Background"].set_property("top_color", BACKGROUND[0])
    vis["/Background"].set_property("bottom_color", BACKGROUND[1])


# --------------------------------------------------------------------------- static HTML


# fixed namespace of the UUIDs written to static pages (uuid5 of "<meshcat path>/<role>/<index>")
_UUID_NAMESPACE = uuid.UUID("6f1d3c2a-5b8e-5d4f-9a7c-2e0b1c4d8f36")


class _SceneRecorder:
    """Stands in for meshcat's ``ViewerWindow``: keeps the scene tree as meshcat's server does.

    ``meshcat.Visualizer(window=_SceneRecorder())`` then works offline (no
    server, no ports) and its ``static_html()`` returns one self-contained file.

    Deterministic output: meshcat gives every scene element (geometry, material,
    texture, image, object) a time-based ``uuid.uuid1()`` when the Python object
    is created (``meshcat.geometry.SceneElement``), and ``set_object`` commands
    carry those UUIDs, so two exports of the same result would differ byte for
    byte. The recorder replaces them, as each ``set_object`` command is
    recorded, by :meth:`_stable_uuids`: UUIDs derived from the node's path and
    the element's role. This also covers elements made outside our code
    (Pinocchio's visualizer, meshcat's shared default ``MeshPhongMaterial``
    created at import time), which a patch at creation time would miss. The
    replacement is one-to-one: an element shared by several objects keeps one
    UUID, distinct elements keep distinct UUIDs; what is drawn is unchanged
    (the live server path, :func:`serve_live`, keeps meshcat's UUIDs).
    """

    def __init__(self, caption: str = "", speed: float = 1.0, t_start: float = 0.0):
        from meshcat.servers.tree import SceneTree

        self.tree = SceneTree()
        self.caption = caption
        self.speed = speed
        self.t_start = t_start
        self.web_url = None
        self._uuids: dict[str, str] = {}  # meshcat's uuid -> the one written
        self._issued: set[str] = set()

    def _stable_uuids(self, data: dict) -> None:
        """Replace, in place, meshcat's UUIDs in a lowered ``set_object`` command by deterministic ones.

        Elements defined in the command (dicts with a ``"uuid"``) are named
        ``uuid5(_UUID_NAMESPACE, "<path>/<role>/<i>")``, role being the list they
        are in (``geometries``, ``materials``, ``textures``, ``images``) or
        ``object``; an element seen before (shared) keeps its first name. Then
        every string equal to a replaced UUID (definitions and references such
        as ``geometry``, ``material``, ``map``, ``image``) is rewritten.
        """
        path = str(data.get("path", ""))
        counts: dict[str, int] = {}

        def define(value, role: str) -> None:
            if isinstance(value, dict):
                own = value.get("uuid")
                if isinstance(own, str) and own not in self._uuids:
                    i = counts.get(role, 0)
                    counts[role] = i + 1
                    name = str(uuid.uuid5(_UUID_NAMESPACE, f"{path}/{role}/{i}"))
                    while name in self._issued:  # a node set twice: keep the new elements distinct
                        name = str(uuid.uuid5(_UUID_NAMESPACE, name))
                    self._issued.add(name)
                    self._uuids[own] = name
                for key, item in value.items():
                    define(item, key)
            elif isinstance(value, list):
                for item in value:
                    define(item, role)

        def rewrite(value):
            if isinstance(value, dict):
                return {key: rewrite(item) for key, item in value.items()}
            if isinstance(value, list):
                return [rewrite(item) for item in value]
            if isinstance(value, str):
                return self._uuids.get(value, value)
            return value

        define(data.get("object"), "object")
        data["object"] = rewrite(data.get("object"))

    def send(self, command) -> None:
        import umsgpack
        from meshcat.servers.tree import SceneTree, find_node

        data = command.lower()
        if data.get("type") == "set_object":
            self._stable_uuids(data)
        path = [p for p in data["path"].split("/") if p]
        packed = umsgpack.packb(data)
        kind = data["type"]
        if kind == "set_transform":
            find_node(self.tree, path).transform = packed
        elif kind == "set_object":
            node = find_node(self.tree, path)
            node.object, node.properties = packed, []
        elif kind == "set_property":
            find_node(self.tree, path).properties.append(packed)
        elif kind == "set_animation":
            find_node(self.tree, path).animation = packed
        elif kind == "delete":
            if path:
                parent = find_node(self.tree, path[:-1])
                parent.pop(path[-1], None)
            else:
                self.tree = SceneTree()
        else:
            raise AnimationError(f"meshcat command {kind!r} cannot be recorded in a static file")

    def get_scene(self) -> str:
        from meshcat.servers.tree import walk

        blobs = []
        for node in walk(self.tree):
            if node.object is not None:
                blobs.append(node.object)
            blobs.extend(node.properties)
            for blob in (node.transform, node.animation):
                if blob is not None:
                    blobs.append(blob)
        commands = "\n".join(f'meshcatCommand("{base64.b64encode(b).decode("ascii")}");' for b in blobs)
        bundle = (Path(_meshcat()[0].__file__).parent / "viewer" / "dist" / "main.min.js").read_text(encoding="utf-8")
        bundle = bundle.replace("</script", "<\\/script")
        return _HTML.format(
            title=html_lib.escape(self.caption.split(":")[0] or "animation"),
            bundle=bundle,
            commands=commands,
            caption=html_lib.escape(self.caption),
            speed=repr(float(self.speed)),
            t_start=repr(float(self.t_start)),
        )


_HTML = """<!DOCTYPE html>
<html>
<head><meta charset="utf-8"><title>{title}</title>
<style>
body {{ margin: 0; }}
#meshcat-pane {{ width: 100vw; height: 100vh; overflow: hidden; }}
#caption {{ position: absolute; left: 8px; top: 6px; font: 13px sans-serif; color: #222;
           background: rgba(255,255,255,0.75); padding: 3px 6px; pointer-events: none; }}
</style></head>
<body>
<div id="meshcat-pane"></div>
<div id="caption"><span>{caption}</span> &middot; t = <span id="sim-time">0</span> s</div>
<script>
{bundle}
</script>
<script>
var viewer = new MeshCat.Viewer(document.getElementById("meshcat-pane"));
function meshcatCommand(b64) {{
  var s = atob(b64), bytes = new Uint8Array(s.length);
  for (var i = 0; i < s.length; i++) bytes[i] = s.charCodeAt(i);
  viewer.handle_command_bytearray(bytes);
}}
{commands}
window.animationSpeed = {speed};
window.animationStart = {t_start};
setInterval(function () {{
  var t = window.animationStart + viewer.animator.time * window.animationSpeed;
  document.getElementById("sim-time").textContent = t.toFixed(5);
}}, 50);
window.meshcatReady = true;
</script>
</body>
</html>
"""

def external_references(html: str) -> list[str]:
    """What a page could load from elsewhere; empty if it is self-contained.

    Looks for absolute URLs with a host (http, https, ws, wss, ftp; XML namespace
    names such as ``http://www.w3.org/1999/xhtml`` are identifiers, not loads) and,
    in the markup outside scripts, for ``src``/``href`` attributes that are not
    ``data:``/``blob:``/``#`` and for ``<link>``, ``<iframe>``, ``<img>`` or
    ``<script src>`` tags. (meshcat's bundle also holds ``ws://${location.host}``,
    used only by ``viewer.connect()``, which the static page never calls.)
    """
    found = []
    for match in re.finditer(r"\b(?:https?|wss?|ftp)://[A-Za-z0-9][^\s\"'`<>)\\]*", html):
        if not match.group(0).startswith("http://www.w3.org/"):
            found.append(match.group(0))
    markup = re.sub(r"(<script\b[^>]*>).*?</script>", r"\1</script>", html, flags=re.DOTALL | re.IGNORECASE)
    for match in re.finditer(r"""\b(?:src|href)\s*=\s*["']?([^"'\s>]*)""", markup, flags=re.IGNORECASE):
        if not match.group(1).startswith(("data:", "#", "blob:")):
            found.append(match.group(0))
    found += re.findall(r"<(?:link|iframe|img|embed|object)\b[^>]*>", markup, flags=re.IGNORECASE)
    return found


def check_not_the_result(result: str | Path | SimulationResult, html_path: str | Path, option: str = "html_path") -> None:
    """Refuse to write the page over the result file it is made from (the result would be lost)."""
    if isinstance(result, SimulationResult):
        return
    source, target = Path(result), Path(html_path)
    same = source.resolve() == target.resolve() or (source.exists() and target.exists() and source.samefile(target))
    if same:
        raise AnimationError(
            f"{option}={str(html_path)!r} is the result file being animated; writing the page there would replace "
            f"the result: give another file name, e.g. {str(target.with_suffix('.html'))!r}",
            key=option, value=str(html_path),
        )


def _check_focus(mechanism: Mechanism, options: AnimationOptions) -> None:
    if options.focus is not None and options.focus not in mechanism.clearance_names:
        raise AnimationError(
            f"focus={options.focus!r} is not a clearance joint of this result; clearance joints: {', '.join(mechanism.clearance_names) or 'none'}"
        )


def _caption(result: SimulationResult, options: AnimationOptions) -> str:
    parts = [f"{result.scene}: clearance motion x{options.exaggerate:g}" if options.exaggerate != 1 else f"{result.scene}: true scale"]
    parts.append(f"playback speed x{options.speed:g}")
    return ", ".join(parts)


def export_html(
    result: str | Path | SimulationResult,
    html_path: str | Path,
    *,
    urdf: str | Path | None = None,
    exaggerate: float = 1.0,
    speed: float = 1.0,
    fps: float = 30.0,
    **options: Any,
) -> AnimationSummary:
    """Write the animation of a result as one self-contained HTML file (no server, no network).

    ``result``: a result file path or a :class:`SimulationResult`. Other keyword
    arguments are fields of :class:`AnimationOptions`. Raises
    :class:`ResultFileError` (missing, malformed or foreign result) or
    :class:`AnimationError` (bad options).
    """
    meshcat, _ = _meshcat()
    opts = AnimationOptions(speed=speed, exaggerate=exaggerate, fps=fps, **options)
    opts.check()
    check_not_the_result(result, html_path)
    mechanism, result = load_for_animation(result, urdf)
    _check_focus(mechanism, opts)
    recorder = _SceneRecorder(_caption(result, opts), opts.speed)
    vis = meshcat.Visualizer(window=recorder)
    animation, summary = build_scene(vis, mechanism, result, opts)
    recorder.t_start = summary.t_start
    vis.set_animation(animation, play=True, repetitions=10**9 if opts.loop else 1)
    page = vis.static_html()
    leaks = external_references(page)
    if leaks:
        raise AnimationError(f"the static page would load external resources: {leaks[:5]}")
    encoded = page.encode("utf-8")

    def write(tmp: Path) -> None:
        tmp.write_bytes(encoded)
        tmp.chmod(0o644)  # a page to share, not a private temporary file

    summary.html_path = atomic_write(Path(html_path), write)
    summary.html_bytes = len(encoded)
    return summary


def animate(result: "str | Path | SimulationResult", html_path: str | Path, **options: Any) -> AnimationSummary:
    """Write a result's animation to a self-contained HTML file (the public API name of :func:`export_html`)."""
    return export_html(result, html_path, **options)


def serve_live(
    result: str | Path | SimulationResult,
    *,
    urdf: str | Path | None = None,
    exaggerate: float = 1.0,
    speed: float = 1.0,
    fps: float = 30.0,
    zmq_url: str | None = None,
    **options: Any,
):
    """Send the animation to a meshcat server (started here unless ``zmq_url`` is given); return (visualizer, summary).

    The server lives as long as this process; open ``summary.url`` in a browser.
    """
    meshcat, _ = _meshcat()
    opts = AnimationOptions(speed=speed, exaggerate=exaggerate, fps=fps, **options)
    opts.check()
    mechanism, result = load_for_animation(result, urdf)
    _check_focus(mechanism, opts)
    vis = meshcat.Visualizer(zmq_url=zmq_url)
    vis.delete()
    animation, summary = build_scene(vis, mechanism, result, opts)
    vis.set_animation(animation, play=True, repetitions=10**9 if opts.loop else 1)
    summary.url = vis.url()
    return vis, summary


def wait_forever() -> None:
    """Keep the live server up until Ctrl-C or SIGTERM (both exit normally, so meshcat stops its server)."""
    import signal

    def stop(signum, frame):  # noqa: ARG001
        raise KeyboardInterrupt

    previous = signal.signal(signal.SIGTERM, stop)
    try:
        while True:
            time.sleep(3600)
    except KeyboardInterrupt:
        pass
    finally:
        signal.signal(signal.SIGTERM, previous)
