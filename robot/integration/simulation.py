"""Time integration of the stabilised equations of motion with contact events.

The state is ``y = [q, v, W_act, W_contact]`` (``dq/dt`` from ``v`` through
:func:`robot.dynamics.equations.configuration_rate`; quaternions renormalised at every
restart). The two work accumulators integrate the actuator power
``sum_k F_k qd_k`` and the contact power ``Q_contact . qd`` with the same error
control as the motion, so the energy balance
``Delta(T + V) = W_act + W_contact`` can be audited to integration accuracy. The loop steps a ``scipy.integrate.OdeSolver`` one accepted step at a
time and, after each step:

1. checks for failure (non-finite accepted state, penetration beyond its physical bound,
   unphysical pose (e.g. a journal turned half round), constraint drift beyond
   tolerance, step-size collapse, Newton divergence of an implicit fixed-step
   method, event chattering, wall time) and stops with the time and the cause,
   keeping every step already computed;
2. scans the contact candidates for **onset** (penetration crossing zero
   upward). The earliest onset in the step is located on the step's dense output
   (Brent's method), the step is cut there and the solver restarted, after
   storing the approach velocity ``ddelta0`` that the Lankarani-Nikravesh law
   needs for that impact (MODEL-NOTES 4). An impact that starts and ends inside
   one step (both ends out of contact, approaching then receding) is caught by
   sampling the dense output, so no step jumps over a contact;
3. records the penetration maxima (penetration rate crossing zero downward
   while in contact) as extra output points, and with each the maximum of that
   candidate's normal force over the compression phase (``dF/dt = 0``; with
   Lankarani-Nikravesh damping it comes slightly before the penetration maximum,
   possibly in an earlier step, see :class:`_ForcePeaks`), so force peaks are
   located, not sampled.

The run returns a :class:`Trajectory` (raw states and event log with status,
message and counts, like ``scipy.integrate.solve_ivp``);
:mod:`robot.io.results` turns it into the result file.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from typing import Callable

import numpy as np
import pinocchio as pin
from scipy.optimize import brentq

from clearance_contact import ONSET_RATE_FLOOR, ContactError
from clearance_contact.compiled import jit

from robot.dynamics import equations as D
from robot.dynamics import state_jacobian as SJ
from robot.integration.solvers import FIXED_STEP_METHODS, JACOBIAN_METHODS, STAGES, SecondOrderStructure, make_solver
from robot.integration.options import STRUCTURED, FailureLimits, SolverOptions

SUCCESS, FAILED = 0, -1
#: restarts at one instant before the run is declared failed (contact events that make no progress)
MAX_STALLED_RESTARTS = 20

# what an accepted step needs beyond the routine checks (bit flags of _step_flags)
_ONSET, _HIDDEN, _OVER_BOUND, _PEAK = 1, 2, 4, 8
_NONE = np.zeros(0, dtype=np.intp)


@jit
def _all_finite(values) -> bool:
    for x in values:
        if not math.isfinite(x):
            return False
    return True


@jit
def _step_flags(pen_old, rate_old, pen_new, rate_new, bounds) -> int:
    """Bit flags over the contact candidates, from the step's end points (same tests as the loop's numpy ones).

    ``_ONSET``: penetration crossed zero upward; ``_HIDDEN``: approaching then
    receding while out of contact at both ends (an impact may hide inside);
    ``_OVER_BOUND``: penetration beyond its physical bound; ``_PEAK``: penetration
    maximum passed while in contact. Most steps have none: one compiled call
    instead of a dozen small numpy operations.
    """
    flags = 0
    for k in range(pen_new.shape[0]):
        if pen_old[k] <= 0.0 and pen_new[k] > 0.0:
            flags |= _ONSET
        if pen_old[k] <= 0.0 and pen_new[k] <= 0.0 and rate_old[k] > 0.0 and rate_new[k] < 0.0:
            flags |= _HIDDEN
        if pen_new[k] > bounds[k]:
            flags |= _OVER_BOUND
        if pen_new[k] > 0.0 and rate_old[k] > 0.0 and rate_new[k] <= 0.0:
            flags |= _PEAK
    return flags


@dataclass
class Trajectory:
    """Raw result of :func:`integrate`: recorded states, event log, status and counts."""

    status: int
    message: str
    cause: str | None
    t_end: float
    t: np.ndarray
    y: np.ndarray  # (n, nq + nv + 2 or 3): q, v, actuator work, contact work(, force-element work)
    onset_rates: np.ndarray  # (n, n_candidates): contact state used at each record
    kind: np.ndarray  # (n,) 0 step, 1 contact onset, 2 penetration maximum, 3 start, 4 output grid, 5 force maximum
    n_steps: int = 0
    n_rejected: int = 0
    n_rhs: int = 0
    n_events: int = 0
    n_restarts: int = 0
    n_jacobians: int = 0  # Jacobians of implicit methods, as each solver counts them (LSODA: its LU factorisations)
    cpu_time: float = 0.0
    wall_time: float = 0.0
    events: list = field(default_factory=list)  # (t, candidate, kind, value): "onset" (approach rate), "peak" (depth), "force_peak" (N)
    n_hidden_contacts: int = 0  # onsets found inside a step whose ends are both out of contact
    max_onset_overshoot: float = 0.0  # deepest penetration (m) at the end of a step cut back to a contact onset

    @property
    def success(self) -> bool:
        return self.status == SUCCESS


class _Failure(Exception):
    def __init__(self, cause: str, message: str):
        super().__init__(message)
        self.cause = cause


#: relative step of the finite-difference fallback of the structured Jacobian (sqrt of machine epsilon)
FORWARD_STEP = math.sqrt(np.finfo(float).eps)

RECORD_STEP, RECORD_ONSET, RECORD_PEAK, RECORD_START, RECORD_OUTPUT = 0, 1, 2, 3, 4
#: the maximum of a candidate's normal force over an impact's compression phase (see _ForcePeaks)
RECORD_FORCE_PEAK = 5


def initial_onset_rates(dynamics: D.DynamicsModel) -> np.ndarray:
    return np.full(dynamics.n_candidates, ONSET_RATE_FLOOR)


def integrate(
    dynamics: D.DynamicsModel,
    y0: np.ndarray,
    t_span: tuple[float, float],
    options: SolverOptions = SolverOptions(),
    limits: FailureLimits = FailureLimits(),
    progress: Callable[[float], None] | None = None,
) -> Trajectory:
    """Integrate from ``y0`` over ``t_span``; never raises on divergence (see ``status``)."""
    mechanism = dynamics.mechanism
    nq, nv = dynamics.nq, dynamics.nv
    workspace = D.make_workspace(dynamics)
    probe_workspace = D.make_workspace(dynamics)
    onset = initial_onset_rates(dynamics)
    bounds = _penetration_bounds(dynamics, limits)
    t0, t_final = map(float, t_span)
    records_t, records_y, records_onset, records_kind = [], [], [], []
    records_force: list = []  # per record: normal force per candidate where the step loop probed it (else None)
    events: list = []
    counts = dict(steps=0, rejected=0, rhs_start=0, restarts=0, hidden=0, jacobians=0)
    overshoot = [0.0]
    structure = SecondOrderStructure(nq, nv, lambda q, dq: pin.integrate(mechanism.model, q, dq))

    def record(t: float, y: np.ndarray, kind: int, onset_rates: np.ndarray | None = None, forces: np.ndarray | None = None) -> None:
        records_t.append(t)
        records_y.append(np.array(y))
        records_onset.append((onset if onset_rates is None else onset_rates).copy())
        records_kind.append(kind)
        records_force.append(forces)

    output_step = options.output_step
    next_output = [1]  # index k of the next output time k * output_step

    def record_outputs(dense, t_from: float, t_to: float) -> None:
        """Record the output grid times in (t_from, t_to] from the step's dense output."""
        if output_step is None:
            return
        while next_output[0] * output_step <= t_to + 1e-12 * output_step:
            t_out = min(next_output[0] * output_step, t_to)
            if t_out > t_from:
                record(t_out, _normalised_state(mechanism, dense(t_out), nq), RECORD_OUTPUT)
            next_output[0] += 1


    def rhs(t: float, y: np.ndarray) -> np.ndarray:
        try:
            return D.state_derivative(dynamics, workspace, t, y, onset)
        except ContactError:
            # a trial stage of a too-large step can land in an absurd pose (e.g. a journal
            # turned half round): answer with a non-finite derivative, which makes the
            # step's error estimate non-finite, so the solver rejects the step and
            # shrinks it. Accepted states are still checked and a real blow-up is reported.
            workspace.rejected_stages += 1
            return np.full(dynamics.state_size, np.inf)

    state_jacobian = None
    if options.jacobian == STRUCTURED and options.method in JACOBIAN_METHODS:
        state_jacobian = SJ.for_workspace(dynamics, workspace)

    def jacobian(t: float, y: np.ndarray, out: np.ndarray | None = None) -> np.ndarray:
        out = np.empty((dynamics.state_size, dynamics.state_size)) if out is None else out
        try:
            return state_jacobian(t, y, onset, out)
        except (ContactError, np.linalg.LinAlgError):
            # a contact law refused a perturbed input, or a factorisation failed: difference the
            # right-hand side instead, as the solver would (forward, sqrt(eps) steps)
            base = rhs(t, y)
            if _all_finite(base):
                out[:] = SJ.finite_difference_jacobian(rhs, t, y, relative_step=FORWARD_STEP, base=base)
            else:
                out[:] = 0.0  # an absurd trial state: the step is rejected anyway on its inf derivative
            return out

    def probe(t: float, y: np.ndarray) -> D.Probe:
        """Penetration, its rate and the normal force per candidate, and the constraint residual, at (t, y)."""
        q = D.normalise_quaternions(mechanism, y[:nq])
        try:
            return D.contact_probe(dynamics, probe_workspace, t, q, y[nq : nq + nv], onset)
        except ContactError as exc:
            # an accepted state (a fixed-step method accepts every step) in an absurd pose,
            # e.g. a journal turned half round in its bearing: the run has blown up
            raise _Failure("unphysical pose", f"t={t:.9g} s: {exc}") from None

    def depth_probe(t: float, y: np.ndarray) -> tuple[np.ndarray]:
        """Penetration per candidate only (positions: cheaper), for the onset root-finding."""
        try:
            return (D.penetrations(dynamics, probe_workspace, D.normalise_quaternions(mechanism, y[:nq])),)
        except ContactError as exc:
            raise _Failure("unphysical pose", f"t={t:.9g} s: {exc}") from None

    force_peaks = _ForcePeaks(dynamics, options, probe_workspace, records_t, records_y, records_onset, records_kind, records_force)

    started_cpu, started_wall = time.process_time(), time.perf_counter()
    y0 = np.asarray(y0, dtype=float)
    if y0.shape == (nq + nv,):
        y0 = np.concatenate([y0, np.zeros(dynamics.n_work)])  # work accumulators start at zero
    if y0.shape != (dynamics.state_size,):
        raise ValueError(f"y0 has shape {y0.shape}; expected ({nq + nv},) or ({dynamics.state_size},) for this model")
    t, y = t0, _normalised_state(mechanism, y0, nq)
    status, cause, message = SUCCESS, None, "the integration reached the end of the time span"
    try:
        pen_old, rate_old, _, force_old = probe(t, y)
    except _Failure as failure:
        raise ValueError(f"the initial state is not a valid pose ({failure})") from None
    record(t, y, RECORD_START, forces=force_old)
    for k in np.flatnonzero(pen_old > 0):  # already in contact at the start
        onset[k] = max(rate_old[k], ONSET_RATE_FLOOR)
    first_step = options.first_step
    n_rhs_total = 0
    stalled = 0
    dense_calls = [0]

    def dense_output(solver):
        # DOP853's dense output evaluates extra stages: keep them out of the rejected-step count
        before = workspace.rhs_calls
        dense = solver.dense_output()
        dense_calls[0] += workspace.rhs_calls - before
        return dense

    solver = None  # the current solver (its counts are added when it ends)
    try:
        while t < t_final:
            workspace.rhs_calls = 0
            dense_calls[0] = 0
            solver = make_solver(
                options.method, rhs, t, y, t_final, options.rtol, options.atol, options.max_step, first_step, structure, None if state_jacobian is None else jacobian
            )
            start_calls = workspace.rhs_calls
            accepted_here = 0
            restarted = False
            while solver.status == "running":
                step_message = solver.step()
                if solver.status == "failed":
                    raise _Failure(getattr(solver, "failure_cause", None) or "step size collapse", f"t={solver.t:.9g} s: {step_message}")
                t_old = solver.t_old
                t_new, y_new = solver.t, solver.y
                accepted_here += 1
                counts["steps"] += 1
                if options.method not in FIXED_STEP_METHODS and solver.step_size is not None and solver.step_size < limits.min_step and t_new < t_final:
                    raise _Failure("step size collapse", f"t={t_new:.9g} s: step size {solver.step_size:.3e} s below {limits.min_step:.1e} s")
                if not _all_finite(y_new):
                    raise _Failure("non-finite state", f"t={t_new:.9g} s: the state is not finite")
                pen_new, rate_new, residual, force_new = probe(t_new, y_new)
                dense = None
                flags = _step_flags(pen_old, rate_old, pen_new, rate_new, bounds)
                # --- contact onset (terminal) ---
                crossing = np.flatnonzero((pen_old <= 0) & (pen_new > 0)) if flags & _ONSET else _NONE
                if options.hidden_contacts and flags & _HIDDEN:
                    hidden = np.flatnonzero((pen_old <= 0) & (pen_new <= 0) & (rate_old > 0) & (rate_new < 0))
                else:
                    hidden = _NONE
                candidates_t = []
                if crossing.size or hidden.size:
                    dense = dense_output(solver)
                    for k in crossing:
                        candidates_t.append((first_contact_time(lambda tt: _pen_at(tt, dense, depth_probe, k), t_old, t_new), k))
                    for k in hidden:
                        found = _hidden_contact(dense, depth_probe, k, t_old, t_new)
                        if found is not None:
                            candidates_t.append((found, k))
                            counts["hidden"] += 1
                    if crossing.size:
                        overshoot[0] = max(overshoot[0], float(np.max(pen_new[crossing])))
                if candidates_t:
                    t_event = min(candidates_t)[0]
                    y_event = _normalised_state(mechanism, dense(t_event), nq)
                    pen_e, rate_e, _, force_e = probe(t_event, y_event)
                    _record_peaks(dense, probe, pen_old, rate_old, t_old, t_event, record, events, mechanism, nq, force_peaks, onset)
                    # every candidate touching at the event starts its impact now (simultaneous
                    # onsets are common: a tilting bearing meets both flanges at once)
                    starting = sorted({k for tk, k in candidates_t if tk <= t_event} | set(np.flatnonzero((pen_old <= 0) & (pen_e >= 0))))
                    for k in starting:
                        onset[k] = max(rate_e[k], ONSET_RATE_FLOOR)
                        events.append((t_event, int(k), "onset", float(onset[k])))
                    record_outputs(dense, t_old, t_event)
                    record(t_event, y_event, RECORD_ONSET, forces=force_e)
                    if t_event <= t:
                        stalled += 1
                        if stalled > MAX_STALLED_RESTARTS:
                            raise _Failure("event chattering", f"t={t_event:.9g} s: {stalled} contact events without progress in time")
                    else:
                        stalled = 0
                    t, y = t_event, y_event
                    pen_old, rate_old = pen_e, rate_e
                    # the restart begins on the contact surface: count the starting candidates as
                    # touching so the same onsets are not detected a second time
                    pen_old[starting] = np.maximum(pen_old[starting], np.finfo(float).tiny)
                    restarted = True
                    break
                # --- failure checks ---
                if flags & _OVER_BOUND:
                    k = np.flatnonzero(pen_new > bounds)[0]
                    raise _Failure(
                        "penetration beyond physical bound",
                        f"t={t_new:.9g} s: penetration {pen_new[k]:.3e} m of contact candidate {k} exceeds "
                        f"{bounds[k]:.3e} m ({limits.penetration_ratio} x clearance)",
                    )
                if residual > limits.max_residual:
                    raise _Failure(
                        "constraint drift",
                        f"t={t_new:.9g} s: constraint residual {residual:.3e} exceeds {limits.max_residual:.1e}",
                    )
                if time.perf_counter() - started_wall > limits.max_wall_time:
                    raise _Failure("wall time", f"t={t_new:.9g} s: wall time limit {limits.max_wall_time} s reached")
                # --- penetration maxima (non-terminal) ---
                if flags & _PEAK:
                    dense = dense or dense_output(solver)
                    _record_peaks(dense, probe, pen_old, rate_old, t_old, t_new, record, events, mechanism, nq, force_peaks, onset, rate_new)
                if output_step is not None and next_output[0] * output_step <= t_new + 1e-12 * output_step:
                    record_outputs(dense or dense_output(solver), t_old, t_new)
                record(t_new, y_new, RECORD_STEP, forces=force_new)
                t, y = t_new, y_new
                pen_old, rate_old = pen_new, rate_new
                if progress is not None:
                    progress(t)
            n_rhs_total += workspace.rhs_calls
            counts["jacobians"] += _jacobians_of(solver)
            stages = STAGES.get(options.method)
            if stages is not None:
                attempts = (workspace.rhs_calls - start_calls - dense_calls[0]) / stages
                counts["rejected"] += max(0, int(round(attempts)) - accepted_here)
            elif getattr(solver, "n_rejected", None) is not None and counts["rejected"] >= 0:
                counts["rejected"] += solver.n_rejected
            else:
                counts["rejected"] = -1
            if restarted:
                counts["restarts"] += 1
                first_step = _next_first_step(solver, options)
                y = _normalised_state(mechanism, y, nq)
            elif solver.status == "finished":
                break
    except _Failure as failure:
        status, cause, message = FAILED, failure.cause, str(failure)
        n_rhs_total += workspace.rhs_calls
        counts["jacobians"] += _jacobians_of(solver)
    except (np.linalg.LinAlgError, RuntimeError, ValueError) as exc:
        status, cause, message = FAILED, "solver error", f"t={t:.9g} s: {type(exc).__name__}: {exc}"
        n_rhs_total += workspace.rhs_calls
        counts["jacobians"] += _jacobians_of(solver)
    except KeyboardInterrupt:
        status, cause, message = FAILED, "interrupted", f"t={t:.9g} s: interrupted by the user"
        n_rhs_total += workspace.rhs_calls
        counts["jacobians"] += _jacobians_of(solver)
    return Trajectory(
        status=status,
        message=message,
        cause=cause,
        t_end=float(records_t[-1]),
        t=np.array(records_t),
        y=np.array(records_y),
        onset_rates=np.array(records_onset).reshape(len(records_t), dynamics.n_candidates),
        kind=np.array(records_kind, dtype=np.int8),
        n_steps=counts["steps"],
        n_rejected=counts["rejected"],
        n_rhs=n_rhs_total,
        n_events=len(events),
        n_restarts=counts["restarts"],
        n_jacobians=counts["jacobians"],
        cpu_time=time.process_time() - started_cpu,
        wall_time=time.perf_counter() - started_wall,
        events=events,
        n_hidden_contacts=counts["hidden"],
        max_onset_overshoot=overshoot[0],
    )


def _jacobians_of(solver) -> int:
    """The Jacobian evaluations a solver counted (0 before any solver was made)."""
    return int(getattr(solver, "njev", 0) or 0)


def _penetration_bounds(dynamics: D.DynamicsModel, limits: FailureLimits) -> np.ndarray:
    bounds = np.empty(dynamics.n_candidates)
    for contact in dynamics.contacts:
        law = contact.law
        clearances = [law.clearance] if law.n_candidates == 1 else [law.radial_clearance, law.axial_clearance] * 2
        bounds[contact.candidates] = limits.penetration_ratio * np.array(clearances)
    return bounds


def _normalised_state(mechanism, y: np.ndarray, nq: int) -> np.ndarray:
    y = np.array(y, dtype=float)
    y[:nq] = D.normalise_quaternions(mechanism, y[:nq])
    return y


def _pen_at(t: float, dense, probe, k: int) -> float:
    return float(probe(t, dense(t))[0][k])


def first_contact_time(function, a: float, b: float) -> float:
    """Time in [a, b] where ``function`` (a penetration) crosses zero upward (Brent's method)."""
    fa, fb = function(a), function(b)
    if fa > 0:
        return a
    if fb <= 0:
        return b
    return brentq(function, a, b, xtol=1e-15, rtol=4 * np.finfo(float).eps, maxiter=200)


def _hidden_contact(dense, probe, k: int, t_old: float, t_new: float, samples: int = 8) -> float | None:
    """First time a contact that starts and ends inside the step becomes active, if any."""
    previous = t_old
    for tt in np.linspace(t_old, t_new, samples + 2)[1:-1]:
        if _pen_at(tt, dense, probe, k) > 0:
            return first_contact_time(lambda s: _pen_at(s, dense, probe, k), previous, tt)
        previous = tt
    return None


def _record_peaks(dense, probe, pen_old, rate_old, t_old, t_new, record, events, mechanism, nq, force_peaks, onset, rate_new=None) -> None:
    """Record the penetration maxima inside (t_old, t_new], and with each its candidate's force maximum."""
    if rate_new is None:
        rate_new = probe(t_new, dense(t_new))[1]
    for k in np.flatnonzero((rate_old > 0) & (rate_new <= 0)):
        rate_fn = lambda tt: float(probe(tt, dense(tt))[1][k])  # noqa: E731
        try:
            t_peak = brentq(rate_fn, t_old, t_new, xtol=1e-15, maxiter=200)
        except ValueError:
            continue
        y_peak = _normalised_state(mechanism, dense(t_peak), nq)
        pen_peak = probe(t_peak, y_peak)[0][k]
        if pen_peak > 0 and t_old < t_peak < t_new:
            events.append((t_peak, int(k), "peak", float(pen_peak)))
            record(t_peak, y_peak, RECORD_PEAK)
            found = force_peaks.locate(int(k), dense, t_old, t_peak, t_new, onset)
            if found is not None:
                t_force, y_force, force, onset_rates = found
                events.append((t_force, int(k), "force_peak", force))
                record(t_force, y_force, RECORD_FORCE_PEAK, onset_rates)


#: record kinds at which a solver step starts or ends (the others lie inside a step)
_BOUNDARY_KINDS = (RECORD_STEP, RECORD_ONSET, RECORD_START)
#: methods whose accepted step is a function of its start state and size only (explicit Runge-Kutta):
#: an earlier step is replayed exactly from its recorded start state
_REPLAYABLE = frozenset({"RK23", "RK45", "DOP853", "RK4"})


class _ForcePeaks:
    """Locates a candidate's normal-force maximum over the compression phase that ends at a penetration maximum.

    With Lankarani-Nikravesh damping the force ``K delta^n (1 + c delta_dot /
    delta_dot0)`` peaks while the penetration still grows (``dF/dt = 0`` at a
    positive rate), so the force at the penetration maximum underestimates the
    peak. Called only for a step that contains a penetration maximum of
    candidate ``k`` at ``t_peak``: the force is maximised (sampled, then
    successive parabolic interpolation) on the step's dense output over ``[t_old, t_new]``;
    if the maximum is at the step's start, it lies in an earlier step: the force
    at the recorded step boundaries, walking back from ``t_old``, brackets it
    (largest sampled value and its two neighbouring steps), and those steps are
    replayed from their recorded start states (explicit Runge-Kutta methods:
    the very same step, so the same dense output; multistep methods, whose step
    cannot be redone alone: the cubic Hermite interpolant of the recorded end
    states and their derivatives) and searched the same way. The
    search never goes back past the candidate's previous penetration maximum
    (nor its onset, where the force is zero); when the force only decreases
    since then, no maximum is recorded. The force is the contact law evaluated
    at the state (on its own Pinocchio data: no right-hand-side call).
    """

    samples = 4  # force samples per searched interval, bracketing the maximum for the parabolic search
    # the maximum's time, relative to the searched interval: the force is flat there, so its value is
    # exact to ~1e-8 (peaks within 2e-9 of xtol 1e-6 with 6 samples on compound_misaligned, 37 % fewer evaluations)
    xtol = 1e-4
    max_walk = 1000  # step boundaries walked back at most

    def __init__(
        self, dynamics: D.DynamicsModel, options: SolverOptions, workspace: D.DynamicsWorkspace, records_t, records_y, records_onset, records_kind, records_force
    ):
        self.dynamics, self.options, self.workspace = dynamics, options, workspace
        self.records_t, self.records_y, self.records_onset, self.records_kind = records_t, records_y, records_onset, records_kind
        self.records_force = records_force
        self.phase_start = np.full(dynamics.n_candidates, -math.inf)  # time of each candidate's last penetration maximum
        self.replay_workspace: D.DynamicsWorkspace | None = None

    def force(self, t: float, y: np.ndarray, onset_rates: np.ndarray, k: int) -> float:
        """Normal force (N) of candidate ``k`` at (t, y) (the contact laws at the state's kinematics, :func:`~robot.dynamics.equations.contact_probe`)."""
        dynamics = self.dynamics
        nq, nv = dynamics.nq, dynamics.nv
        q = D.normalise_quaternions(dynamics.mechanism, y[:nq])
        try:
            return float(D.contact_probe(dynamics, self.workspace, t, q, np.asarray(y[nq : nq + nv]), onset_rates, residual=False).normal_force[k])
        except ContactError:
            return -math.inf

    def _search(self, dense, a: float, b: float, onset_rates: np.ndarray, k: int) -> tuple[float, float, int]:
        """(t, F, edge) of the largest force of candidate ``k`` on ``dense`` over [a, b].

        ``edge``: -1 if the largest sample is the first one (the maximum may lie
        before ``a``), +1 if the last one (after ``b``), else 0.
        """
        times = np.linspace(a, b, self.samples + 1)
        forces = [self.force(float(tt), dense(tt), onset_rates, k) for tt in times]
        i = int(np.argmax(forces))
        fun = lambda s: self.force(a + s, dense(a + s), onset_rates, k)  # noqa: E731 - in the offset from a: rounding relative to the step
        xtol = self.xtol * (b - a)
        bracket = None
        if 0 < i < self.samples:
            bracket = (times[i - 1] - a, times[i] - a, times[i + 1] - a, forces[i - 1], forces[i], forces[i + 1])
        else:
            # the largest sample is at an end: is the force still rising just inside it? (an
            # offset well above the force's rounding, well below the sample spacing)
            inner = times[i] + (1e-4 if i == 0 else -1e-4) * (b - a)
            f_inner = self.force(inner, dense(inner), onset_rates, k)
            if f_inner > forces[i]:
                if i == 0:
                    bracket = (0.0, inner - a, times[1] - a, forces[0], f_inner, forces[1])
                else:
                    bracket = (times[i - 1] - a, inner - a, b - a, forces[i - 1], f_inner, forces[i])
        if bracket is None:
            return float(times[i]), forces[i], (-1 if i == 0 else 1)
        s, f = _parabolic_maximum(fun, *map(float, bracket), xtol=xtol)
        return a + s, f, 0

    def _replay(self, i_a: int, i_b: int) -> list:
        """Dense outputs covering the step between boundary records ``i_a`` and ``i_b``, from the recorded start state."""
        dynamics, options = self.dynamics, self.options
        t_a, t_b = self.records_t[i_a], self.records_t[i_b]
        onset_rates = self.records_onset[i_a]
        if self.replay_workspace is None:
            self.replay_workspace = D.make_workspace(dynamics)
        workspace = self.replay_workspace
        size = dynamics.state_size

        def fun(t, y):
            try:
                return D.state_derivative(dynamics, workspace, t, y, onset_rates)
            except ContactError:
                return np.full(size, np.inf)

        if options.method not in _REPLAYABLE:
            # a multistep method's step cannot be redone alone: the cubic Hermite interpolant of its
            # two accepted end states and their derivatives (two right-hand sides), on the method's
            # own trajectory and as accurate as its steps (error ~ h^4 max|y^(4)| / 384)
            y_a, y_b = self.records_y[i_a], self.records_y[i_b]
            return [_HermiteDense(t_a, t_b, y_a, fun(t_a, y_a), y_b, fun(t_b, y_b))]
        solver = make_solver(options.method, fun, t_a, self.records_y[i_a], t_b, options.rtol, options.atol, math.inf, t_b - t_a)
        dense = []
        for _ in range(10_000):
            if solver.status != "running":
                break
            solver.step()
            if solver.status == "failed":
                break
            dense.append(solver.dense_output())
        return dense

    def locate(self, k: int, dense, t_old: float, t_peak: float, t_new: float, onset_rates: np.ndarray):
        """(t, y, force, onset rates) of candidate ``k``'s force maximum up to just past ``t_peak``, or None.

        The step's part searched runs to its end ``t_new``: an undamped force peaks
        at the penetration maximum itself, and that maximum is then inside the
        searched interval. A force still growing at ``t_new`` (a revolute candidate's
        force also depends on the tilt) or only decreasing since the previous
        penetration maximum has no maximum in view: None.
        """
        t_lo = self.phase_start[k]
        self.phase_start[k] = t_peak
        a = max(t_old, t_lo)
        if not t_new > a:
            return None
        t_best, f_best, edge = self._search(dense, a, t_new, onset_rates, k)
        if edge > 0:
            return None
        best = (t_best, f_best, dense, onset_rates) if edge == 0 else None
        left_end = a
        if t_old > t_lo:
            # the force may have peaked (higher) in an earlier step of the same compression phase
            found = self._earlier(k, t_old, t_lo, f_best if edge < 0 else self.force(t_old, dense(t_old), onset_rates, k), edge < 0)
            if found is not None:
                left_end = found[0]
                if found[1] is not None and (best is None or found[1][1] > best[1]):
                    best = found[1]
        if best is None:
            return None
        t_best, f_best, dense_best, onset_best = best
        if t_best <= left_end or not f_best > 0:
            return None  # the force only decreases over the phase searched: no maximum in it
        y_best = _normalised_state(self.dynamics.mechanism, dense_best(t_best), self.dynamics.nq)
        return float(t_best), y_best, float(f_best), onset_best.copy()

    def _earlier(self, k: int, t_old: float, t_lo: float, f_old: float, falling: bool):
        """The compression phase's earlier steps: (left end searched, best (t, F, dense, onset) or None).

        The force at every step boundary from ``t_old`` back to the phase start
        (the previous penetration maximum, the onset, where the force is zero, or
        the run's start); the largest sampled local maximum (``t_old`` counts when
        the force is ``falling`` after it) is refined on its two neighbouring steps,
        replayed.
        """
        records_t, records_kind = self.records_t, self.records_kind
        chain, forces = [], []
        for i in range(len(records_t) - 1, -1, -1):
            if records_kind[i] not in _BOUNDARY_KINDS:
                continue
            if not chain and records_t[i] != t_old:
                return None  # the records do not end at the step's start: nothing to walk back over
            if not chain:
                f = f_old
            elif self.records_force[i] is not None:  # probed by the step loop (the same contact law, same state)
                f = float(self.records_force[i][k])
            else:
                f = self.force(records_t[i], self.records_y[i], self.records_onset[i], k)
            chain.append(i)
            forces.append(f)
            if records_t[i] <= t_lo or records_kind[i] == RECORD_START or not f > 0 or len(chain) >= self.max_walk:
                break
        left_end = max(records_t[chain[-1]], t_lo)
        peaks = [p for p in range(len(chain) - 1) if forces[p] >= forces[p + 1] and (forces[p] > forces[p - 1] if p > 0 else falling)]
        if not peaks:
            return left_end, None
        p = max(peaks, key=lambda p: forces[p])
        best = None
        intervals = [(chain[p + 1], chain[p])] + ([(chain[p], chain[p - 1])] if p >= 1 else [])
        for i_a, i_b in intervals:
            if not records_t[i_b] > records_t[i_a]:
                continue
            onset_rates = self.records_onset[i_a]
            for segment in self._replay(i_a, i_b):
                lo, hi = max(segment.t_old, t_lo, records_t[i_a]), min(segment.t, records_t[i_b])
                if not hi > lo:
                    continue
                t_found, f_found, _ = self._search(segment, lo, hi, onset_rates, k)
                if t_found <= left_end:
                    continue  # the tail of the previous phase's maximum, not a maximum of this one
                if best is None or f_found > best[1]:
                    best = (t_found, f_found, segment, onset_rates)
        return left_end, best


class _HermiteDense:
    """Cubic Hermite interpolant of a state over [t_old, t] from its end values and derivatives (a dense output)."""

    def __init__(self, t_old: float, t: float, y_old: np.ndarray, f_old: np.ndarray, y_new: np.ndarray, f_new: np.ndarray):
        self.t_old, self.t = float(t_old), float(t)
        h = self.t - self.t_old
        self.y_old, self.y_new = np.asarray(y_old, dtype=float), np.asarray(y_new, dtype=float)
        self.hf_old, self.hf_new = h * np.asarray(f_old, dtype=float), h * np.asarray(f_new, dtype=float)

    def __call__(self, t: float) -> np.ndarray:
        s = (float(t) - self.t_old) / (self.t - self.t_old)
        s2, s3 = s * s, s * s * s
        return (
            (2.0 * s3 - 3.0 * s2 + 1.0) * self.y_old
            + (s3 - 2.0 * s2 + s) * self.hf_old
            + (-2.0 * s3 + 3.0 * s2) * self.y_new
            + (s3 - s2) * self.hf_new
        )


def _parabolic_maximum(f, a: float, m: float, b: float, fa: float, fm: float, fb: float, xtol: float, maxiter: int = 60) -> tuple[float, float]:
    """Maximum of a smooth unimodal ``f`` bracketed by ``a < m < b`` (``f(m) >= f(a), f(b)``): (x, f(x)).

    Successive parabolic interpolation (the vertex of the parabola through the
    bracket's three points), with a golden-section step into the larger part of
    the bracket when the vertex falls outside it; stops when the vertex moves by
    less than ``xtol``. Near a smooth maximum it converges superlinearly: a
    handful of evaluations.
    """
    golden = 0.3819660112501051
    for _ in range(maxiter):
        p = (m - a) * (fm - fb)
        r = (m - b) * (fm - fa)
        denominator = 2.0 * (p - r)
        x = m - ((m - a) * p - (m - b) * r) / denominator if denominator != 0.0 else math.nan
        converged = abs(x - m) < xtol
        if not a < x < b:
            x = m + golden * (b - m) if b - m > m - a else m - golden * (m - a)
            converged = False
        if x == m:
            break
        fx = f(x)
        if x > m:
            if fx >= fm:
                a, fa, m, fm = m, fm, x, fx
            else:
                b, fb = x, fx
        else:
            if fx >= fm:
                b, fb, m, fm = m, fm, x, fx
            else:
                a, fa = x, fx
        if converged or b - a < xtol:
            break
    return m, fm


def _next_first_step(solver, options: SolverOptions) -> float | None:
    if options.method in FIXED_STEP_METHODS:
        return options.first_step
    h = solver.step_size if solver.step_size else None
    return None if h is None or h <= 0 else h
