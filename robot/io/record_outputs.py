"""The derived arrays of a result: the equations of motion evaluated once more at every record.

At each recorded state ``(t, q, v)`` with its onset rates the result holds the
driving forces (``-lambda`` of the driving rows, paper eq. (24)), the largest
constraint residual ``max |Phi|``, the actuator and contact powers, the
end-effector position, velocity and classical acceleration (world axes), the
kinetic and potential energies, and per clearance joint what its type records
(:meth:`clearance_contact.ClearanceJoint.result_arrays`). Two paths compute the
same equations:

With force elements (:mod:`robot.dynamics.forces`) also ``force_energy`` (energy
stored in them) and per element ``force_NAME`` (its scalar force or torque).

* :func:`reference_outputs`: per record :func:`robot.dynamics.equations.evaluate`
  (the Python constraint kernel, every contact law's ``evaluate``, the KKT solve)
  and Pinocchio's kinematics and energies: any mechanism, and the oracle of the
  other path (``tests/test_record_outputs.py``: agreement to ~1e-12 relative);
* :func:`compiled_outputs`: per record the integrator's compiled right-hand side
  (:func:`robot.dynamics.equations.state_derivative`), whose by-products are the
  outputs: ``qdd``, Pinocchio's multipliers of the driving rows (= the driving
  forces, :mod:`robot.dynamics.equations`), the two powers, every law's flat
  output (read in one vectorised pass per joint and chunk of :data:`CHUNK` records,
  :meth:`~clearance_contact.ClearanceJoint.record_outputs`); then one
  ``forwardKinematics(q, v, qdd)`` gives the end-effector kinematics and both
  energies. About 5 x cheaper a record; it applies where the compiled right-hand
  side does (every closure spherical, every law a shipped compiled law:
  :func:`compiled_applies`).
"""

from __future__ import annotations

from typing import Callable

import numpy as np
import pinocchio as pin

from robot.dynamics import equations as D
from robot.dynamics import rhs_kernels as K

LWA = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
#: records whose laws' outputs and element poses :func:`compiled_outputs` buffers before writing them (1.5 MB for the 4-UPS/RPS)
CHUNK = 1024


def allocate(dynamics: D.DynamicsModel, n: int) -> tuple[dict[str, np.ndarray], dict[str, dict[str, np.ndarray]]]:
    """Empty derived arrays for ``n`` records, and per clearance joint its type's arrays."""
    arrays = {
        "driving_force": np.empty((n, dynamics.mechanism.n_actuators)),
        "ee_position": np.empty((n, 3)),
        "ee_velocity": np.empty((n, 3)),
        "ee_acceleration": np.empty((n, 3)),
        "constraint_residual": np.empty(n),
        "kinetic_energy": np.empty(n),
        "potential_energy": np.empty(n),
        "actuator_power": np.empty(n),
        "contact_power": np.empty(n),
    }
    if dynamics.forces is not None:  # force elements: energy stored, each element's scalar force or torque
        arrays["force_energy"] = np.empty(n)
        arrays["force_scalars"] = np.empty((n, len(dynamics.forces.elements)))
    per_site = {contact.site.name: contact.law.result_arrays(n) for contact in dynamics.contacts}
    return arrays, per_site


def compiled_applies(dynamics: D.DynamicsModel, workspace: D.DynamicsWorkspace) -> bool:
    """Whether :func:`compiled_outputs` can evaluate this model (its right-hand side is compiled, laws fused)."""
    compiled = workspace.compiled
    return compiled is not None and compiled.sites_fused


def _end_effector_writer(
    model: pin.Model, data: pin.Data, frame: int, arrays: dict[str, np.ndarray]
) -> Callable[[int, np.ndarray, np.ndarray, np.ndarray], None]:
    """``write(i, q, v, qdd)``: end-effector kinematics and the energies of record ``i`` (one forward kinematics pass).

    Pinocchio's functions and the arrays are bound once (~0.3 us a record less
    than looking them up at every record).
    """
    position, velocity, acceleration = arrays["ee_position"], arrays["ee_velocity"], arrays["ee_acceleration"]
    kinetic, potential = arrays["kinetic_energy"], arrays["potential_energy"]
    forward_kinematics, update_placement = pin.forwardKinematics, pin.updateFramePlacement
    frame_velocity, frame_acceleration = pin.getFrameVelocity, pin.getFrameClassicalAcceleration
    kinetic_energy, potential_energy = pin.computeKineticEnergy, pin.computePotentialEnergy

    def write(i: int, q: np.ndarray, v: np.ndarray, qdd: np.ndarray) -> None:
        forward_kinematics(model, data, q, v, qdd)
        position[i] = update_placement(model, data, frame).translation
        velocity[i] = frame_velocity(model, data, frame, LWA).linear
        acceleration[i] = frame_acceleration(model, data, frame, LWA).linear
        kinetic[i] = kinetic_energy(model, data)
        potential[i] = potential_energy(model, data)

    return write


def reference_outputs(
    dynamics: D.DynamicsModel, t: np.ndarray, y: np.ndarray, onset: np.ndarray, workspace: D.DynamicsWorkspace | None = None
) -> dict[str, np.ndarray]:
    """The derived arrays by :func:`robot.dynamics.equations.evaluate` at every record (module docstring)."""
    mechanism = dynamics.mechanism
    model, nq, nv = mechanism.model, dynamics.nq, dynamics.nv
    workspace = workspace or D.make_workspace(dynamics)
    data = workspace.data
    arrays, per_site = allocate(dynamics, len(t))
    act = mechanism.actuator_v_index
    forces = workspace.forces
    end_effector = _end_effector_writer(model, data, dynamics.end_effector_frame, arrays)
    for i in range(len(t)):
        q = D.normalise_quaternions(mechanism, y[i, :nq])
        v = y[i, nq : nq + nv]
        evaluation = D.evaluate(dynamics, workspace, float(t[i]), q, v, onset[i])
        force = evaluation.driving_force(dynamics.constraints)
        arrays["driving_force"][i] = force
        arrays["constraint_residual"][i] = np.max(np.abs(evaluation.residual)) if evaluation.residual.size else 0.0
        arrays["actuator_power"][i] = force @ v[act] + (0.0 if forces is None else forces.powers[0])
        if forces is not None:
            arrays["force_scalars"][i], arrays["force_energy"][i] = evaluation.force_scalars, forces.potential_energy(q)
        arrays["contact_power"][i] = evaluation.generalized_contact_force @ v
        # the contact laws' poses first: the end-effector pass below moves data to the acceleration's kinematics
        for contact, result in zip(dynamics.contacts, evaluation.contacts):
            outer, inner = data.oMf[contact.site.outer_frame], data.oMf[contact.site.inner_frame]
            contact.law.record(per_site[contact.site.name], i, result, outer.rotation, outer.translation, inner.translation)
        end_effector(i, q, v, evaluation.qdd)
    return _with_sites(dynamics, arrays, per_site)


def compiled_outputs(
    dynamics: D.DynamicsModel, t: np.ndarray, y: np.ndarray, onset: np.ndarray, workspace: D.DynamicsWorkspace | None = None
) -> dict[str, np.ndarray]:
    """The derived arrays through the compiled right-hand side (module docstring); :func:`compiled_applies` must hold.

    The laws' flat outputs and the element poses are gathered per chunk of
    :data:`CHUNK` records and written per chunk (:func:`_record_sites`), so their
    buffers stay small whatever the number of records.
    """
    mechanism = dynamics.mechanism
    model, nq, nv = mechanism.model, dynamics.nq, dynamics.nv
    workspace = workspace or D.make_workspace(dynamics)
    if not compiled_applies(dynamics, workspace):
        raise ValueError("compiled_outputs needs the compiled right-hand side (every closure spherical, every law a shipped compiled law)")
    data, compiled = workspace.data, workspace.compiled
    n = len(t)
    arrays, per_site = allocate(dynamics, n)
    driving, residual = arrays["driving_force"], arrays["constraint_residual"]
    actuator_power, contact_power = arrays["actuator_power"], arrays["contact_power"]
    forces, buffer, drive_values = workspace.forces, compiled.site_outputs_buffer, compiled.drive_values
    frames_a, frames_b, actuator_q, placements = compiled.frames_a, compiled.frames_b, compiled.actuator_q, compiled.placements
    closure_rows = compiled.closure_rows
    # per record the placements (rotation, then translation) of every clearance joint's two element frames
    site_frames = np.array([[c.site.outer_frame, c.site.inner_frame] for c in dynamics.contacts], dtype=np.int64).reshape(-1)
    chunk = min(n, CHUNK)
    site_outputs, poses = np.empty((chunk, buffer.shape[0])), np.empty((chunk, site_frames.shape[0], K.SE3_FLOATS))
    end_effector = _end_effector_writer(model, data, dynamics.end_effector_frame, arrays)
    state_derivative, normalize, largest_residual = D.state_derivative, pin.normalize, K.largest_residual
    positions, velocities, work = y[:, :nq], y[:, nq : nq + nv], nq + nv
    for i, time in enumerate(t.tolist()):
        rate = state_derivative(dynamics, workspace, time, y[i], onset[i])
        q, v = normalize(model, positions[i]), velocities[i]
        # Pinocchio's multipliers of the driving rows are the driving forces (equations module docstring)
        driving[i] = data.lambda_c[workspace.rows.n_closure_kept :]
        # the actuator power of the right-hand side includes the force-driven actuators' (as the reference)
        actuator_power[i], contact_power[i] = rate[work], rate[work + 1]
        if forces is not None:
            arrays["force_scalars"][i], arrays["force_energy"][i] = forces.scalars, forces.potential_energy(q)
        # the drive's values at this time, as the right-hand side just wrote them (not evaluated twice)
        residual[i] = largest_residual(placements, frames_a, frames_b, closure_rows, q, drive_values, actuator_q)
        row = i % chunk
        site_outputs[row] = buffer
        placements.take(site_frames, axis=0, out=poses[row], mode="clip")  # the indices are valid: no bounds check
        end_effector(i, q, v, rate[nq:work])
        if row == chunk - 1 or i == n - 1:
            _record_sites(dynamics, compiled, per_site, np.arange(i - row, i + 1), site_outputs[: row + 1], poses[: row + 1])
    return _with_sites(dynamics, arrays, per_site)


def _record_sites(
    dynamics: D.DynamicsModel,
    compiled: D.CompiledTerms,
    per_site: dict[str, dict[str, np.ndarray]],
    rows: np.ndarray,
    site_outputs: np.ndarray,
    poses: np.ndarray,
) -> None:
    """Each clearance joint's arrays at the records ``rows`` from the laws' flat outputs and the element poses there."""
    m = rows.shape[0]
    for index, contact in enumerate(dynamics.contacts):
        first, end = compiled.site_table[index, K.SITE_OUT], compiled.site_table[index, K.SITE_OUT_END]
        outer, inner = poses[:, 2 * index], poses[:, 2 * index + 1]
        # a placement row holds the rotation column-major: its 3 x 3 reshape is the rotation's transpose
        rotation = outer[:, 0:9].reshape(m, 3, 3).transpose(0, 2, 1)
        contact.law.record_outputs(per_site[contact.site.name], rows, site_outputs[:, first:end], rotation, outer[:, 9:12], inner[:, 9:12])


def _with_sites(dynamics: D.DynamicsModel, arrays: dict[str, np.ndarray], per_site: dict[str, dict[str, np.ndarray]]) -> dict[str, np.ndarray]:
    """The result's names: ``NAME_<key>`` per clearance joint, ``force_NAME`` per force element."""
    for name, site_arrays in per_site.items():
        for key, value in site_arrays.items():
            arrays[f"{name}_{key}"] = value
    scalars = arrays.pop("force_scalars", None)
    for k, element in enumerate(() if dynamics.forces is None else dynamics.forces.elements):
        arrays[f"force_{element.name}"] = scalars[:, k]
    return arrays


def derived_outputs(dynamics: D.DynamicsModel, t: np.ndarray, y: np.ndarray, onset: np.ndarray) -> dict[str, np.ndarray]:
    """The derived arrays at the records ``(t, y, onset)``: the compiled path where it applies, else the reference."""
    workspace = D.make_workspace(dynamics)
    if compiled_applies(dynamics, workspace):
        return compiled_outputs(dynamics, t, y, onset, workspace)
    return reference_outputs(dynamics, t, y, onset, workspace)
