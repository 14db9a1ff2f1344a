"""Time integration of the stabilised equations of motion with contact events.

The state is ``y = [q, v, W_act, W_contact]`` (``dq/dt`` from ``v`` through
:func:`robot.dynamics.configuration_rate`; quaternions renormalised at every
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
   while in contact) as extra output points, so force peaks are not lost to
   output sampling.

The run returns a :class:`Trajectory` (raw states and event log with status,
message and counts, like ``scipy.integrate.solve_ivp``);
:mod:`robot.results` turns it into the result file.
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

from . import dynamics as D
from .integrators import FIXED_STEP_METHODS, STAGES, SecondOrderStructure, make_solver

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


@dataclass(frozen=True)
class SolverOptions:
    """Integrator choice and tolerances (``first_step`` is the step of fixed-step methods).

    ``hidden_contacts``: scan each step's dense output for contacts that start and
    end inside the step (the guard against steps that jump over a whole impact);
    on by default, off only to study what it guards against
    (``scripts/work_precision.py``). ``output_step``: also record the state at every
    multiple of it, from the steps' dense output (record kind 4), so that runs can
    be compared at common times.
    """

    method: str = "RK45"
    rtol: float = 1e-7
    atol: float = 1e-9
    max_step: float = 1e-3
    first_step: float | None = None
    hidden_contacts: bool = True
    output_step: float | None = None


@dataclass(frozen=True)
class FailureLimits:
    """When a run is declared failed rather than returning garbage.

    ``penetration_ratio``: a penetration above this fraction of the joint's
    clearance is unphysical for hard metal contact (the force would crush the
    parts); ``max_residual``: constraint drift (m or rad); ``min_step``: step-size
    collapse; ``max_wall_time``: seconds (``inf``: none).
    """

    penetration_ratio: float = 0.5
    max_residual: float = 1e-4
    min_step: float = 1e-13
    max_wall_time: float = math.inf


@dataclass
class Trajectory:
    """Raw result of :func:`integrate`: recorded states, event log, status and counts."""

    status: int
    message: str
    cause: str | None
    t_end: float
    t: np.ndarray
    y: np.ndarray  # (n, nq + nv + 2): q, v, actuator work, contact work
    onset_rates: np.ndarray  # (n, n_candidates): contact state used at each record
    kind: np.ndarray  # (n,) 0 step, 1 contact onset, 2 penetration maximum, 3 start, 4 output grid
    n_steps: int = 0
    n_rejected: int = 0
    n_rhs: int = 0
    n_events: int = 0
    n_restarts: int = 0
    cpu_time: float = 0.0
    wall_time: float = 0.0
    events: list = field(default_factory=list)  # (t, candidate, kind, value)
    n_hidden_contacts: int = 0  # onsets found inside a step whose ends are both out of contact
    max_onset_overshoot: float = 0.0  # deepest penetration (m) at the end of a step cut back to a contact onset

    @property
    def success(self) -> bool:
        return self.status == SUCCESS


class _Failure(Exception):
    def __init__(self, cause: str, message: str):
        super().__init__(message)
        self.cause = cause


RECORD_STEP, RECORD_ONSET, RECORD_PEAK, RECORD_START, RECORD_OUTPUT = 0, 1, 2, 3, 4


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
    events: list = []
    counts = dict(steps=0, rejected=0, rhs_start=0, restarts=0, hidden=0)
    overshoot = [0.0]
    structure = SecondOrderStructure(nq, nv, lambda q, dq: pin.integrate(mechanism.model, q, dq))

    def record(t: float, y: np.ndarray, kind: int) -> None:
        records_t.append(t)
        records_y.append(np.array(y))
        records_onset.append(onset.copy())
        records_kind.append(kind)

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
            return np.full(nq + nv + 2, np.inf)

    def probe(t: float, y: np.ndarray) -> tuple[np.ndarray, np.ndarray, float]:
        """Penetration and its rate per candidate, and the constraint residual, at (t, y)."""
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

    started_cpu, started_wall = time.process_time(), time.perf_counter()
    y0 = np.asarray(y0, dtype=float)
    if y0.shape == (nq + nv,):
        y0 = np.concatenate([y0, [0.0, 0.0]])  # work accumulators start at zero
    if y0.shape != (nq + nv + 2,):
        raise ValueError(f"y0 has shape {y0.shape}; expected ({nq + nv},) or ({nq + nv + 2},) for this model")
    t, y = t0, _normalised_state(mechanism, y0, nq)
    status, cause, message = SUCCESS, None, "the integration reached the end of the time span"
    record(t, y, RECORD_START)
    try:
        pen_old, rate_old, _ = probe(t, y)
    except _Failure as failure:
        raise ValueError(f"the initial state is not a valid pose ({failure})") from None
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

    try:
        while t < t_final:
            workspace.rhs_calls = 0
            dense_calls[0] = 0
            solver = make_solver(options.method, rhs, t, y, t_final, options.rtol, options.atol, options.max_step, first_step, structure)
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
                pen_new, rate_new, residual = probe(t_new, y_new)
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
                    pen_e, rate_e, _ = probe(t_event, y_event)
                    _record_peaks(dense, probe, pen_old, rate_old, t_old, t_event, record, events, mechanism, nq)
                    # every candidate touching at the event starts its impact now (simultaneous
                    # onsets are common: a tilting bearing meets both flanges at once)
                    starting = sorted({k for tk, k in candidates_t if tk <= t_event} | set(np.flatnonzero((pen_old <= 0) & (pen_e >= 0))))
                    for k in starting:
                        onset[k] = max(rate_e[k], ONSET_RATE_FLOOR)
                        events.append((t_event, int(k), "onset", float(onset[k])))
                    record_outputs(dense, t_old, t_event)
                    record(t_event, y_event, RECORD_ONSET)
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
                    _record_peaks(dense, probe, pen_old, rate_old, t_old, t_new, record, events, mechanism, nq, rate_new)
                if output_step is not None and next_output[0] * output_step <= t_new + 1e-12 * output_step:
                    record_outputs(dense or dense_output(solver), t_old, t_new)
                record(t_new, y_new, RECORD_STEP)
                t, y = t_new, y_new
                pen_old, rate_old = pen_new, rate_new
                if progress is not None:
                    progress(t)
            n_rhs_total += workspace.rhs_calls
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
    except (np.linalg.LinAlgError, RuntimeError, ValueError) as exc:
        status, cause, message = FAILED, "solver error", f"t={t:.9g} s: {type(exc).__name__}: {exc}"
        n_rhs_total += workspace.rhs_calls
    except KeyboardInterrupt:
        status, cause, message = FAILED, "interrupted", f"t={t:.9g} s: interrupted by the user"
        n_rhs_total += workspace.rhs_calls
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
        cpu_time=time.process_time() - started_cpu,
        wall_time=time.perf_counter() - started_wall,
        events=events,
        n_hidden_contacts=counts["hidden"],
        max_onset_overshoot=overshoot[0],
    )


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


def _record_peaks(dense, probe, pen_old, rate_old, t_old, t_new, record, events, mechanism, nq, rate_new=None) -> None:
    """Record the penetration maxima inside (t_old, t_new] as extra output points."""
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


def _next_first_step(solver, options: SolverOptions) -> float | None:
    if options.method in FIXED_STEP_METHODS:
        return options.first_step
    h = solver.step_size if solver.step_size else None
    return None if h is None or h <= 0 else h
