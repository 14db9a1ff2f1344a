"""Time integration of the stabilised equations of motion with contact events (the Lagrange model).

The state is ``y = [q, v, W_act, W_contact]`` (``dq/dt`` from ``v`` through
:func:`robot.dynamics.equations.configuration_rate`; quaternions renormalised at every
restart). The two work accumulators integrate the actuator power
``sum_k F_k qd_k`` and the contact power ``Q_contact . qd`` with the same error
control as the motion, so the energy balance
``Delta(T + V) = W_act + W_contact`` can be audited to integration accuracy.

:class:`LagrangeSystem` is this model behind the step loop's protocol
(:class:`robot.integration.event_loop.EventSystem`): the right-hand side
:func:`robot.dynamics.equations.state_derivative`, the structured Jacobian of the
implicit methods (:mod:`robot.dynamics.state_jacobian`, finite differences where a
contact law refuses a perturbed state), the contact probe, the penetration bounds
(``FailureLimits.penetration_ratio`` x clearance) and the quaternion
normalisation. :func:`integrate` runs the loop
(:class:`robot.integration.event_loop.EventDrivenIntegrator`: onsets located and
restarted at, penetration and force maxima located, failures reported with
their cause) and returns a :class:`Trajectory`; :mod:`robot.io.results` turns it
into the result file.
"""

from __future__ import annotations

import math
from typing import Callable

import numpy as np
import pinocchio as pin

from clearance_contact import ONSET_RATE_FLOOR, ContactError

from robot.dynamics import equations as D
from robot.dynamics import state_jacobian as SJ
from robot.integration import methods as registry
from robot.integration.event_loop import MAX_STALLED_RESTARTS, EventDrivenIntegrator  # noqa: F401 (re-exported)
from robot.integration.events import all_finite, first_contact_time  # noqa: F401 (re-exported)
from robot.integration.force_peaks import derivative_or_refused
from robot.integration.options import STRUCTURED, FailureLimits, SolverOptions  # noqa: F401 (re-exported)
from robot.integration.records import (  # noqa: F401 (re-exported: the record kinds and the trajectory)
    FAILED,
    RECORD_FORCE_PEAK,
    RECORD_ONSET,
    RECORD_OUTPUT,
    RECORD_PEAK,
    RECORD_START,
    RECORD_STEP,
    SUCCESS,
    OutputTimes,
    Trajectory,
)
from robot.integration.solvers import SecondOrderStructure

#: relative step of the finite-difference fallback of the structured Jacobian (sqrt of machine epsilon)
FORWARD_STEP = math.sqrt(np.finfo(float).eps)


def initial_onset_rates(dynamics: D.DynamicsModel) -> np.ndarray:
    return np.full(dynamics.n_candidates, ONSET_RATE_FLOOR)


class LagrangeSystem:
    """The Lagrange model (:class:`robot.dynamics.equations.DynamicsModel`) behind the step loop's protocol."""

    def __init__(self, dynamics: D.DynamicsModel, penetration_bounds: np.ndarray, structured_jacobian: bool = False):
        self.dynamics = dynamics
        self.mechanism = dynamics.mechanism
        self.nq, self.nv = dynamics.nq, dynamics.nv
        self.size = dynamics.state_size  # q, v and the work accumulators
        self.n_candidates = dynamics.n_candidates
        self.penetration_bounds = penetration_bounds
        self.workspace = D.make_workspace(dynamics)
        self._probe_workspace: D.DynamicsWorkspace | None = None
        self.structure = SecondOrderStructure(self.nq, self.nv, lambda q, dq: pin.integrate(self.mechanism.model, q, dq))
        self._state_jacobian = SJ.for_workspace(dynamics, self.workspace) if structured_jacobian else None
        self.jacobian = None if self._state_jacobian is None else self._jacobian

    @property
    def rhs_calls(self) -> int:
        return self.workspace.rhs_calls

    @property
    def probe_workspace(self) -> D.DynamicsWorkspace:
        """Pinocchio data for the probes (kept apart from the right-hand side's)."""
        if self._probe_workspace is None:
            self._probe_workspace = D.make_workspace(self.dynamics)
        return self._probe_workspace

    def replica(self) -> "LagrangeSystem":
        replica = LagrangeSystem(self.dynamics, self.penetration_bounds)
        # the rows in use (an immutable selection): a fresh detection off the manifold could keep a dependent one
        replica.workspace.rows = self.workspace.rows
        return replica

    def derivative(self, t: float, y: np.ndarray, onset: np.ndarray) -> np.ndarray:
        return D.state_derivative(self.dynamics, self.workspace, t, y, onset)

    def _jacobian(self, t: float, y: np.ndarray, onset: np.ndarray, out: np.ndarray | None = None) -> np.ndarray:
        out = np.empty((self.size, self.size)) if out is None else out
        try:
            return self._state_jacobian(t, y, onset, out)
        except (ContactError, np.linalg.LinAlgError):
            # a contact law refused a perturbed input, or a factorisation failed: difference the
            # right-hand side instead, as the solver would (forward, sqrt(eps) steps)
            fun = derivative_or_refused(self, onset)
            base = fun(t, y)
            if all_finite(base):
                out[:] = SJ.finite_difference_jacobian(fun, t, y, relative_step=FORWARD_STEP, base=base)
            else:
                out[:] = 0.0  # an absurd trial state: the step is rejected anyway on its inf derivative
            return out

    def probe(self, t: float, y: np.ndarray, onset: np.ndarray, residual: bool = True) -> D.Probe:
        """Penetration, its rate and the normal force per candidate, and the constraint residual, at (t, y)."""
        nq = self.nq
        q = D.normalise_quaternions(self.mechanism, y[:nq])
        return D.contact_probe(self.dynamics, self.probe_workspace, t, q, np.asarray(y[nq : nq + self.nv]), onset, residual=residual)

    def penetrations(self, t: float, y: np.ndarray) -> np.ndarray:
        """Penetration per candidate only (positions: cheaper), for the onset root-finding."""
        return D.penetrations(self.dynamics, self.probe_workspace, D.normalise_quaternions(self.mechanism, y[: self.nq]))

    def normalise(self, y: np.ndarray) -> np.ndarray:
        y = np.array(y, dtype=float)
        y[: self.nq] = D.normalise_quaternions(self.mechanism, y[: self.nq])
        return y


def penetration_bounds(dynamics: D.DynamicsModel, limits: FailureLimits) -> np.ndarray:
    """Per candidate: ``limits.penetration_ratio`` x its joint's clearance (radial or axial)."""
    bounds = np.empty(dynamics.n_candidates)
    for contact in dynamics.contacts:
        bounds[contact.candidates] = limits.penetration_ratio * contact.law.candidate_clearances()
    return bounds


def integrate(
    dynamics: D.DynamicsModel,
    y0: np.ndarray,
    t_span: tuple[float, float],
    options: SolverOptions = SolverOptions(),
    limits: FailureLimits = FailureLimits(),
    progress: Callable[[float], None] | None = None,
    *,
    onset_rates: np.ndarray | None = None,
    locate_force_peaks: bool = True,
) -> Trajectory:
    """Integrate from ``y0`` over ``t_span``; never raises on divergence (see ``status``).

    ``y0``: ``[q, v]`` (the work accumulators start at zero) or the whole state.
    ``onset_rates``: the contact state when continuing a run from one of its
    records (its ``onset_rates`` row; see ``EventDrivenIntegrator.start``);
    ``locate_force_peaks``: search each impact's force maximum (off when only the
    final state matters).
    """
    nq, nv = dynamics.nq, dynamics.nv
    y0 = np.asarray(y0, dtype=float)
    if y0.shape == (nq + nv,):
        y0 = np.concatenate([y0, np.zeros(dynamics.n_work)])  # work accumulators start at zero
    if y0.shape != (dynamics.state_size,):
        raise ValueError(f"y0 has shape {y0.shape}; expected ({nq + nv},) or ({dynamics.state_size},) for this model")
    structured = options.jacobian == STRUCTURED and registry.traits(options.method).takes_jacobian
    system = LagrangeSystem(dynamics, penetration_bounds(dynamics, limits), structured_jacobian=structured)
    outputs = None if options.output_step is None else OutputTimes.grid(options.output_step)
    return EventDrivenIntegrator(
        system, y0, t_span, options, limits, outputs=outputs, locate_force_peaks=locate_force_peaks, progress=progress, onset_rates=onset_rates
    ).run()
