"""The simulator as a :class:`~robot.analysis.lyapunov_benettin.Flow`: Benettin's exponent of a mechanism.

:class:`SimulatorFlow` advances a built :class:`robot.run.Run` with the
simulator itself (:func:`robot.integration.simulation.integrate`, the scene's
solver options and failure limits), so the largest Lyapunov exponent of
:func:`~robot.analysis.lyapunov_benettin.benettin_exponent` is that of the
simulated model: constraint stabilisation, contact events, force elements and
all.

**State.** A flow state is ``[y, onset_rates, t]``: the integrator's state
``y = [q, v, work accumulators]`` (``q`` with Pinocchio's unit quaternions),
the Lankarani-Nikravesh onset rate of every contact candidate (the contact
state the step loop carries, MODEL-NOTES 4) and the time (the closures of a
driven mechanism depend on it, so :meth:`SimulatorFlow.perturb` needs it).
:meth:`SimulatorFlow.state` packs one; :meth:`SimulatorFlow.from_result` takes
a record of a result.

**Contact state across renormalisations.** ``advance`` continues the given
onset rates: a candidate in contact at ``t0`` keeps the onset rate of its
impact in progress, exactly as an uninterrupted run would. A perturbed copy
inherits its reference's onset rates, except for a candidate that is in
contact in the copy but not in the reference: its impact starts at the
perturbation, so its onset rate is re-derived from its current penetration
rate (stored as NaN, see ``EventDrivenIntegrator.start``). The work
accumulators are carried along and play no part in the distance.

**Distance** (the norm on the tangent space of the state manifold). With
``dq = difference(q_ref, q)`` (Pinocchio's log map: quaternions handled on
SO(3)/SE(3), not across their normalisation) and ``dv = v - v_ref``, each
tangent coordinate ``i`` is made dimensionless by its kind: rotations (rad) by
1, translations (m) by a length scale ``L``; velocities additionally by a time
scale ``T``::

    z = [w * dq, T w * dv],    w_i = 1 (rotation) or 1 / L (translation),
    distance = |z|.

So a position offset ``dq`` weighs like a velocity offset ``dq / T``. Defaults:
``L`` the mechanism's characteristic length, the largest joint offset or
centre-of-mass lever arm of the model (1 m if all are zero); ``T = sqrt(L /
|g|)`` with gravity (a pendulum's ``1 / omega_0``), otherwise the drive's
``period / (2 pi)``. The exponent does not depend on this choice (all norms on
a finite-dimensional space are equivalent: the ratio of two norms is bounded,
its logarithm divided by the horizon vanishes); the scales set the meaning of
the ``separation`` d0 and the size of the bounded start-up term.

**Perturbation on the constraint manifold.** A closed-loop mechanism's states
lie on ``Phi(q, t) = 0``, ``Phi_q v = -Phi_t``. A companion off that manifold
would be pulled back by the Baumgarte terms in a spurious transient, so
:meth:`SimulatorFlow.perturb` projects: ``q`` by the assembly's Newton
iteration (:func:`robot.model.kinematics.assemble`, minimum-norm corrections),
``v`` by its minimum-norm correction onto ``Phi_q v = -Phi_t``
(``v + Phi_q^+ (-Phi_t - Phi_q v)``). The projection shortens the offset, so it
is done twice: the second time along the projected direction (tangent to the
manifold to first order), which leaves the distance equal to the requested
size up to ``O(size^2)``. Clearance joints' free bodies are not constrained:
their offsets are kept.
"""

from __future__ import annotations

import dataclasses
import math
from typing import TYPE_CHECKING

import numpy as np
import pinocchio as pin

from robot.analysis.errors import AnalysisError, require_positive
from robot.dynamics import equations as D
from robot.integration.simulation import integrate
from robot.model import constraints as C
from robot.model.kinematics import assemble, update_kinematics

if TYPE_CHECKING:  # pragma: no cover
    from robot.run import Run

#: per Pinocchio joint type: the kind of each velocity (tangent) coordinate, "r" rotation, "t" translation
TANGENT_KINDS = {
    **{f"JointModelR{axis}": "r" for axis in "XYZ"},
    **{f"JointModelRUB{axis}": "r" for axis in "XYZ"},
    "JointModelRevoluteUnaligned": "r",
    "JointModelRevoluteUnboundedUnaligned": "r",
    **{f"JointModelP{axis}": "t" for axis in "XYZ"},
    "JointModelPrismaticUnaligned": "t",
    "JointModelFreeFlyer": "tttrrr",  # Pinocchio's motion order: linear, then angular
    "JointModelSpherical": "rrr",
    "JointModelSphericalZYX": "rrr",
    "JointModelPlanar": "ttr",
    "JointModelTranslation": "ttt",
}


def translational_coordinates(model: pin.Model) -> np.ndarray:
    """(nv,) bool: True for the tangent coordinates that are translations (m), False for rotations (rad)."""
    mask = np.zeros(model.nv, dtype=bool)
    for joint in range(1, model.njoints):
        kinds = TANGENT_KINDS.get(model.joints[joint].shortname())
        if kinds is None or len(kinds) != model.nvs[joint]:
            raise AnalysisError(
                f"joint {model.names[joint]!r} of type {model.joints[joint].shortname()} has no known split of its "
                f"velocity into rotations and translations; known types: {', '.join(sorted(TANGENT_KINDS))}"
            )
        start = model.idx_vs[joint]
        mask[start : start + model.nvs[joint]] = [kind == "t" for kind in kinds]
    return mask


def characteristic_length(model: pin.Model) -> float:
    """The largest joint offset or centre-of-mass lever arm of the model (m); 1 m if all are zero."""
    offsets = [np.linalg.norm(model.jointPlacements[j].translation) for j in range(1, model.njoints)]
    levers = [np.linalg.norm(model.inertias[j].lever) for j in range(1, model.njoints)]
    length = max(offsets + levers, default=0.0)
    return float(length) if length > 0.0 else 1.0


def characteristic_time(run: "Run", length: float) -> float:
    """``sqrt(L / |g|)`` with gravity, else the drive's ``period / (2 pi)`` (s)."""
    gravity = float(np.linalg.norm(run.mechanism.model.gravity.linear))
    if gravity > 0.0:
        return math.sqrt(length / gravity)
    return run.scene.trajectory.period / (2.0 * math.pi)


class SimulatorFlow:
    """A built run's mechanism as a Benettin flow (module docstring); ``length_scale`` (m) and
    ``time_scale`` (s) default to :func:`characteristic_length` and :func:`characteristic_time`."""

    def __init__(self, run: "Run", *, length_scale: float | None = None, time_scale: float | None = None) -> None:
        self.run, self.dynamics = run, run.dynamics
        model = run.mechanism.model
        self.model, self.data = model, model.createData()
        self.nq, self.nv, self.size, self.n_candidates = model.nq, model.nv, self.dynamics.state_size, self.dynamics.n_candidates
        self.length_scale = characteristic_length(model) if length_scale is None else require_positive("length_scale", length_scale)
        self.time_scale = characteristic_time(run, self.length_scale) if time_scale is None else require_positive("time_scale", time_scale)
        self.position_weight = np.where(translational_coordinates(model), 1.0 / self.length_scale, 1.0)
        # only the final state matters: no output grid, no force-maximum search
        self.options = dataclasses.replace(run.scene.solver, output_step=None)
        self.limits = run.scene.limits
        self.workspace = D.make_workspace(self.dynamics) if self.n_candidates else None

    # --- states ------------------------------------------------------------------------------
    def state(self, y: np.ndarray, t: float, onset_rates: np.ndarray | None = None) -> np.ndarray:
        """Pack ``[y, onset_rates, t]``; ``y`` is ``[q, v]`` or the whole integrator state; onset rates NaN if not given."""
        y = np.asarray(y, dtype=float)
        if y.shape == (self.nq + self.nv,):
            y = np.concatenate([y, np.zeros(self.size - y.size)])
        if y.shape != (self.size,):
            raise AnalysisError(f"y has shape {y.shape}; expected ({self.nq + self.nv},) or ({self.size},) for this run")
        onset = np.full(self.n_candidates, np.nan) if onset_rates is None else np.asarray(onset_rates, dtype=float).reshape(self.n_candidates)
        return np.concatenate([y, onset, [float(t)]])

    def from_result(self, t: np.ndarray, q: np.ndarray, v: np.ndarray, onset_rates: np.ndarray | None = None, index: int = -1) -> np.ndarray:
        """The flow state of record ``index`` of a result's arrays (default: the last, the run's final state)."""
        onset = None if onset_rates is None or self.n_candidates == 0 else np.asarray(onset_rates)[index]
        return self.state(np.concatenate([np.asarray(q)[index], np.asarray(v)[index]]), float(np.asarray(t)[index]), onset)

    def split(self, state: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, float]:
        """``(q, v, onset_rates, t)`` of a flow state (views)."""
        state = np.asarray(state, dtype=float)
        if state.shape != (self.size + self.n_candidates + 1,):
            raise AnalysisError(f"a flow state of this run has {self.size + self.n_candidates + 1} entries; got shape {state.shape}")
        nq, nv = self.nq, self.nv
        return state[:nq], state[nq : nq + nv], state[self.size : self.size + self.n_candidates], float(state[-1])

    # --- the flow ----------------------------------------------------------------------------
    def advance(self, state: np.ndarray, t0: float, t1: float) -> np.ndarray:
        """Integrate the mechanism from ``state`` at ``t0`` to ``t1`` with the scene's solver; AnalysisError if the run fails."""
        _, _, onset, t_state = self.split(state)
        if abs(t_state - t0) > 1e-9 * max(1.0, abs(t0)):
            raise AnalysisError(f"the state is at t={t_state!r}, not at t0={t0!r}")
        y0 = np.asarray(state, dtype=float)[: self.size]
        run = integrate(self.dynamics, y0, (t0, t1), self.options, self.limits, onset_rates=onset, locate_force_peaks=False)
        if not run.success:
            raise AnalysisError(f"the simulator stopped advancing from t={t0:g} s to t={t1:g} s ({run.cause}): {run.message}")
        return self.state(run.y[-1], t1, run.onset_rates[-1])

    def separation(self, reference: np.ndarray, other: np.ndarray) -> np.ndarray:
        """The scaled tangent vector ``[w dq, T w dv]`` at ``reference`` pointing to ``other`` (module docstring)."""
        q_ref, v_ref, _, _ = self.split(reference)
        q, v, _, _ = self.split(other)
        dq = pin.difference(self.model, q_ref, q)
        return np.concatenate([self.position_weight * dq, self.time_scale * self.position_weight * (v - v_ref)])

    def distance(self, reference: np.ndarray, other: np.ndarray) -> float:
        return float(np.linalg.norm(self.separation(reference, other)))

    def perturb(self, state: np.ndarray, direction: np.ndarray, size: float) -> np.ndarray:
        """The state at distance ``size`` along the scaled tangent ``direction``, projected on the constraints (module docstring)."""
        direction = np.asarray(direction, dtype=float)
        if direction.shape != (2 * self.nv,):
            raise AnalysisError(f"direction has shape {direction.shape}; expected ({2 * self.nv},): [dq, dv] scaled")
        q, v, onset, t = self.split(state)
        other = np.array(state, dtype=float)
        for _ in range(2):  # the second pass along the projected (tangent) direction restores the size
            norm = np.linalg.norm(direction)
            if not (np.isfinite(norm) and norm > 0.0):
                raise AnalysisError("the perturbation direction is zero (or not finite) on the constraint manifold")
            step = size * direction / norm
            q_new = pin.integrate(self.model, q, step[: self.nv] / self.position_weight)
            v_new = v + step[self.nv :] / (self.time_scale * self.position_weight)
            other[: self.nq], other[self.nq : self.nq + self.nv] = self.project(q_new, v_new, t)
            direction = self.separation(state, other)
        other[self.size : self.size + self.n_candidates] = self._inherited_onset_rates(q, other[: self.nq], onset)
        return other

    # --- helpers -----------------------------------------------------------------------------
    def project(self, q: np.ndarray, v: np.ndarray, t: float) -> tuple[np.ndarray, np.ndarray]:
        """``(q, v)`` moved onto ``Phi(q, t) = 0`` (assembly) and ``Phi_q v = -Phi_t`` (minimum-norm correction)."""
        constraints = self.dynamics.constraints
        if constraints.n_rows == 0:
            return pin.normalize(self.model, q), np.array(v, dtype=float)
        s, sd, _ = self.dynamics.drive.drive(t)
        q = assemble(constraints, q, s, data=self.data).q
        update_kinematics(self.model, self.data, q)
        phi_q = C.jacobian(constraints, self.model, self.data)
        correction, *_ = np.linalg.lstsq(phi_q, C.velocity_rhs(constraints, sd) - phi_q @ v, rcond=None)
        return q, v + correction

    def _inherited_onset_rates(self, q_reference: np.ndarray, q_other: np.ndarray, onset: np.ndarray) -> np.ndarray:
        """The reference's onset rates; NaN (re-derive at the start) where only the copy is in contact."""
        if self.n_candidates == 0:
            return onset.copy()
        touching_reference = D.penetrations(self.dynamics, self.workspace, q_reference) > 0
        touching_other = D.penetrations(self.dynamics, self.workspace, q_other) > 0
        return np.where(touching_other & ~touching_reference, np.nan, onset)
