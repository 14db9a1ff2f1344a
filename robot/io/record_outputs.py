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
  output (read in one vectorised pass per joint after the loop,
  :meth:`~clearance_contact.ClearanceJoint.record_outputs`); then one
  ``forwardKinematics(q, v, qdd)`` gives the end-effector kinematics and both
  energies. About 5 x cheaper a record; it applies where the compiled right-hand
  side does (every closure spherical, every law a shipped compiled law:
  :func:`compiled_applies`).
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from robot.dynamics import equations as D
from robot.dynamics import rhs_kernels as K

LWA = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED


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
    return compiled is not None and (compiled.fused is not None or not dynamics.contacts)


def _end_effector(model: pin.Model, data: pin.Data, frame: int, q, v, qdd, arrays: dict, i: int) -> None:
    """End-effector kinematics and the energies of record ``i`` (Pinocchio: one forward kinematics pass)."""
    pin.forwardKinematics(model, data, q, v, qdd)
    arrays["ee_position"][i] = pin.updateFramePlacement(model, data, frame).translation
    arrays["ee_velocity"][i] = pin.getFrameVelocity(model, data, frame, LWA).linear
    arrays["ee_acceleration"][i] = pin.getFrameClassicalAcceleration(model, data, frame, LWA).linear
    arrays["kinetic_energy"][i] = pin.computeKineticEnergy(model, data)
    arrays["potential_energy"][i] = pin.computePotentialEnergy(model, data)


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
        _end_effector(model, data, dynamics.end_effector_frame, q, v, evaluation.qdd, arrays, i)
    return _with_sites(dynamics, arrays, per_site)


def compiled_outputs(
    dynamics: D.DynamicsModel, t: np.ndarray, y: np.ndarray, onset: np.ndarray, workspace: D.DynamicsWorkspace | None = None
) -> dict[str, np.ndarray]:
    """The derived arrays through the compiled right-hand side (module docstring); :func:`compiled_applies` must hold."""
    mechanism = dynamics.mechanism
    model, nq, nv = mechanism.model, dynamics.nq, dynamics.nv
    workspace = workspace or D.make_workspace(dynamics)
    if not compiled_applies(dynamics, workspace):
        raise ValueError("compiled_outputs needs the compiled right-hand side (every closure spherical, every law a shipped compiled law)")
    data, compiled = workspace.data, workspace.compiled
    n = len(t)
    arrays, per_site = allocate(dynamics, n)
    site_outputs = np.empty((n, compiled.site_outputs_buffer.shape[0]))
    driving, residual = arrays["driving_force"], arrays["constraint_residual"]
    actuator_power, contact_power = arrays["actuator_power"], arrays["contact_power"]
    frame, drive = dynamics.end_effector_frame, workspace.drive
    frames_a, frames_b, actuator_q, placements = compiled.frames_a, compiled.frames_b, compiled.actuator_q, compiled.placements
    closure_rows = compiled.closure_rows
    # per record the placements (rotation, then translation) of every clearance joint's two element frames
    site_frames = np.array([[c.site.outer_frame, c.site.inner_frame] for c in dynamics.contacts], dtype=np.int64).reshape(-1)
    poses = np.empty((n, site_frames.shape[0], K.SE3_FLOATS))
    forces = workspace.forces
    for i in range(n):
        time = float(t[i])
        rate = D.state_derivative(dynamics, workspace, time, y[i], onset[i])
        q = pin.normalize(model, y[i, :nq])
        v = y[i, nq : nq + nv]
        # Pinocchio's multipliers of the driving rows are the driving forces (equations module docstring)
        driving[i] = data.lambda_c[workspace.rows.n_closure_kept :]
        # the actuator power of the right-hand side includes the force-driven actuators' (as the reference)
        actuator_power[i], contact_power[i] = rate[nq + nv], rate[nq + nv + 1]
        if forces is not None:
            arrays["force_scalars"][i], arrays["force_energy"][i] = forces.scalars, forces.potential_energy(q)
        residual[i] = K.largest_residual(placements, frames_a, frames_b, closure_rows, q, drive.values(time), actuator_q)
        site_outputs[i] = compiled.site_outputs_buffer
        poses[i] = placements[site_frames]
        _end_effector(model, data, frame, q, v, rate[nq : nq + nv], arrays, i)
    rows = np.arange(n)
    for index, contact in enumerate(dynamics.contacts):
        first, end = compiled.site_table[index, K.SITE_OUT], compiled.site_table[index, K.SITE_OUT_END]
        outer, inner = poses[:, 2 * index], poses[:, 2 * index + 1]
        # a placement row holds the rotation column-major: its 3 x 3 reshape is the rotation's transpose
        rotation = outer[:, 0:9].reshape(n, 3, 3).transpose(0, 2, 1)
        contact.law.record_outputs(per_site[contact.site.name], rows, site_outputs[:, first:end], rotation, outer[:, 9:12], inner[:, 9:12])
    return _with_sites(dynamics, arrays, per_site)


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
