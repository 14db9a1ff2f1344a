"""From a scene to a result: build the model the scene needs, set the initial state, integrate.

The data flow is one way: scene (TOML) + URDF -> :class:`Run` (mechanism,
dynamics model, initial state) -> :class:`robot.integration.simulation.Trajectory` ->
:class:`robot.io.results.Result` -> result file.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
import math
from typing import Any, Callable, Mapping

import numpy as np
import pinocchio as pin

from robot.dynamics import equations as D
from robot.dynamics.forces.build import build_force_set
from robot.errors import SceneError
from robot.model.initial_state import initial_state
from robot.model.mechanism import Mechanism, build_mechanism
from robot.model.platform_kinematics import PlatformLayout, inverse_kinematics
from robot.io.results import Result, make_result, mechanism_fingerprint
from robot.scene.loader import OutputSpec, Scene, load_scene, misalignment_rotation
from robot.integration.simulation import integrate
from robot.model.trajectory import POSE_COORDINATES, FourierCoordinate, JointTrajectory, PlatformTrajectory, reference_platform_motion
from robot.model.actuation import with_motion_actuators
from robot.model.description import parse_mechanism
from robot.model.time_functions import Fourier


@dataclass(frozen=True, eq=False)
class Run:
    """Everything needed to integrate one scene."""

    scene: Scene
    mechanism: Mechanism
    dynamics: D.DynamicsModel
    y0: np.ndarray
    layout: PlatformLayout | None

    @property
    def t_span(self) -> tuple[float, float]:
        return 0.0, self.scene.duration


def _coordinate(table: dict) -> FourierCoordinate:
    return FourierCoordinate(
        float(table.get("offset", 0.0)),
        float(table.get("rate", 0.0)),
        tuple(float(a) for a in table.get("amplitudes", ())),
        tuple(float(h) for h in table.get("harmonics", ())),
        tuple(float(p) for p in table.get("phases", ())),
    )


def make_drive(scene: Scene, mechanism: Mechanism) -> tuple[D.Drive, PlatformLayout | None]:
    spec = scene.trajectory
    if spec.kind == "platform":
        if any(a.mode != "motion" for a in scene.actuators.values()):
            raise SceneError(f"scene {scene.name}: a platform trajectory drives every leg; [actuators] modes need type = 'joints'", key="actuators")
        layout = PlatformLayout.from_mechanism(mechanism)
        if spec.preset == "reference":
            return reference_platform_motion(layout, spec.period), layout
        coordinates = tuple(_coordinate(spec.coordinates[name]) for name in POSE_COORDINATES)
        return PlatformTrajectory(layout, spec.period, coordinates), layout
    missing = [j for j in mechanism.actuated_joints if j not in spec.coordinates]
    extra = [j for j in spec.coordinates if j not in mechanism.actuated_joints]
    if missing or extra:
        raise SceneError(
            f"scene {scene.name}: a joint trajectory needs one entry per actuated joint {mechanism.actuated_joints}; "
            f"missing {missing}, not actuated {extra}"
        )
    omega = 2.0 * math.pi / spec.period
    functions = tuple(spec.functions.get(j) or Fourier(_coordinate(spec.coordinates[j]), omega) for j in mechanism.actuated_joints)
    return JointTrajectory(functions), None


def build_run(scene: Scene | str | Path, **overrides) -> Run:
    """Build the mechanism with exactly the scene's clearance joints, its dynamics and initial state."""
    if not isinstance(scene, Scene):
        scene = load_scene(scene, **overrides)
    description = with_motion_actuators(parse_mechanism(scene.mechanism_path), scene.actuators, f"scene {scene.name}")
    mechanism = build_mechanism(description, {c.joint: c.outer_on for c in scene.clearances}, scene.gravity)
    drive, layout = make_drive(scene, mechanism)
    if not mechanism.model.existFrame(scene.end_effector):
        raise SceneError(f"scene {scene.name}: end_effector={scene.end_effector!r} is not a frame of the mechanism")
    dynamics = D.make_dynamics_model(
        mechanism, {c.joint: c.law for c in scene.clearances}, drive, scene.baumgarte, scene.end_effector, forces=build_force_set(scene, mechanism)
    )
    if layout is not None:
        pose, _, _ = drive.pose(0.0)
        q_guess, _ = inverse_kinematics(layout, pose)
    else:
        q_guess = pin.neutral(mechanism.model)
    misalignment = {joint: misalignment_rotation(angle) for joint, angle in scene.misalignment_deg.items()}
    y0 = initial_state(
        mechanism, q_guess, drive.drive(0.0), misalignment, scene.initial_positions, scene.initial_velocities,
        scene.clearance_state, {c.joint: c.law for c in scene.clearances},
    )
    return Run(scene, mechanism, dynamics, y0, layout)


def clearance_geometry(law) -> dict[str, float]:
    """Element dimensions of a clearance joint with the scene file's key names, as given (its type's ``GEOMETRY_KEYS``)."""
    return law.geometry


def run_scene(run: Run, progress: Callable[[float], None] | None = None, output: OutputSpec | None = None) -> Result:
    """Integrate a built run and compute its outputs (never raises on divergence: see ``status``).

    ``output``: compute the outputs only at the records this ``[output]`` selection
    keeps (e.g. ``run.scene.output``: what the result file holds, without the ends
    of the integration steps); None: at every record.
    """
    scene = run.scene
    trajectory = integrate(run.dynamics, run.y0, run.t_span, scene.solver, scene.limits, progress)
    metadata = {
        "mechanism": str(scene.mechanism_path.name),
        "mechanism_path": str(scene.mechanism_path),
        "urdf_sha256": mechanism_fingerprint(run.mechanism.description.urdf_text),
        "clearance": list(scene.clearance_joints),
        "clearance_outer_on": {c.joint: c.outer_on for c in scene.clearances},
        "clearance_type": {c.joint: c.law.type_name for c in scene.clearances},
        "clearance_geometry": {c.joint: clearance_geometry(c.law) for c in scene.clearances},
        "clearance_parameters": {c.joint: c.law.scene_parameters for c in scene.clearances},
        "scene_file": str(scene.path.name) if scene.path else None,
        "method": scene.solver.method,
        "rtol": scene.solver.rtol,
        "atol": scene.solver.atol,
        "max_step": scene.solver.max_step,
        "jacobian": scene.solver.jacobian,
        "baumgarte": [scene.baumgarte.alpha, scene.baumgarte.beta],
        "duration": scene.duration,
        "actuated_joints": list(run.mechanism.actuated_joints),
        "nq": run.mechanism.model.nq,
        "nv": run.mechanism.model.nv,
    }
    return make_result(scene.name, run.dynamics, trajectory, metadata, output)


def simulate(
    scene: Scene | str | Path,
    overrides: Mapping[str, Any] | None = None,
    *,
    t_end: float | None = None,
    progress: Callable[[float], None] | None = None,
) -> Result:
    """Run a scene and return its :class:`~robot.io.results.Result` (the public entry point).

    ``scene``: a :class:`Scene` (from :func:`robot.load_scene`), a shipped scene's
    name or a path to a scene file; ``overrides``: key paths and values applied
    before validation (``{"clearance.R1.radial_clearance": 2e-4}``);
    ``t_end``: simulated seconds (the scene's ``duration`` otherwise).
    Bad input raises :class:`robot.errors.SceneError` (a subclass of
    :class:`robot.Error`) before any integration; a run that stops (divergence,
    interrupt) is returned with ``status`` -1, its ``cause`` and every record up
    to the stop.
    """
    if t_end is not None and not (isinstance(t_end, (int, float)) and math.isfinite(t_end) and t_end > 0):
        raise SceneError(f"t_end={t_end!r} must be a finite number of seconds > 0", key="t_end", value=t_end)
    if not isinstance(scene, Scene):
        scene = load_scene(scene)
    changes = {**(overrides or {}), **({"duration": t_end} if t_end is not None else {})}
    if changes:
        scene = scene.with_changes(changes)
    return run_scene(build_run(scene), progress)


def compile_kernels(run: Run) -> float:
    """Integrate the run over its first microsecond so the kernels are ready (the library's loaded; numba's compiled or loaded from its cache).

    Returns the CPU seconds this took: the first-call compilation that would
    otherwise be counted in the run's ``cpu_time`` (reported apart as
    ``compile_cpu_time``).
    """
    import time

    started = time.process_time()
    integrate(run.dynamics, run.y0, (0.0, min(1e-6, run.scene.duration)), run.scene.solver, run.scene.limits)
    return time.process_time() - started
