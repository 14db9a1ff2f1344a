"""The event-driven step loop: one accepted solver step at a time, with contact events and failure checks.

:class:`EventDrivenIntegrator` steps a solver with the contract of
``scipy.integrate.OdeSolver`` (:mod:`robot.integration.solver_base`; any method
of the registry, :mod:`robot.integration.methods`) over a system that
implements the narrow :class:`EventSystem` protocol: the Lagrange model
(:class:`robot.integration.simulation.LagrangeSystem`) and the Newton-Euler
cross-check (:class:`robot.validation.newton_euler.NewtonEulerSystem`) both run
through it. Like ``OdeSolver.step()``, :meth:`EventDrivenIntegrator.step` is one
small overridable unit; it is made of these steps, each its own method:

1. :meth:`~EventDrivenIntegrator.advance`: the solver's step (a fixed-step
   method's with the approach rates as onset rates of the candidates out of
   contact, :meth:`~EventDrivenIntegrator.set_step_onset_rates`); a failed step,
   a step-size collapse (variable-step methods) or a non-finite state stops the
   run (``_Failure``); the system is probed at the step's end (penetrations,
   their rates, normal forces, constraint residual);
2. :meth:`~EventDrivenIntegrator.find_onsets`: the candidates whose penetration
   crossed zero upward, located on the step's dense output (Brent's method; a
   fixed-step method's states redone as steps from the step's start,
   :meth:`~EventDrivenIntegrator.onset_dense_output`), and the impacts hidden
   inside the step (:mod:`robot.integration.events`);
3. :meth:`~EventDrivenIntegrator.restart_at_onset`: the step is cut at the
   earliest onset, the state there checked as in 4., the approach rate is stored
   as that candidate's onset rate ``ddelta0`` (Lankarani-Nikravesh, MODEL-NOTES 4;
   floored by ``clearance_contact.ONSET_RATE_FLOOR``) and the solver restarted there;
4. :meth:`~EventDrivenIntegrator.check_failures`: penetration beyond its physical
   bound, constraint drift, wall time;
5. :meth:`~EventDrivenIntegrator.locate_peaks`: penetration maxima (rate crossing
   zero downward in contact) and with each the candidate's force maximum
   (:mod:`robot.integration.force_peaks`);
6. :meth:`~EventDrivenIntegrator.accept`: output times, the step's record.

What a run writes is described in :mod:`robot.integration.records`. A failure
never raises: the run returns its :class:`~robot.integration.records.Trajectory`
with ``status`` -1, the ``cause`` and the records so far.
"""

from __future__ import annotations

import math
import time
from typing import Callable, NamedTuple, Protocol

import numpy as np

from clearance_contact import ONSET_RATE_FLOOR, ContactError, ContactLawError

from robot.dynamics.probe import Probe as ContactProbe  # the step loop's name for it (robot.validation imports it)
from robot.integration import methods as registry
from robot.integration.brent import NoSignChange, brentq
from robot.integration.events import HIDDEN, ONSET, OVER_BOUND, PEAK, all_finite, first_contact_time, hidden_contact, step_flags
from robot.integration.force_peaks import ForcePeaks, derivative_or_refused, refused_stage_value
from robot.integration.options import STALL_WINDOW, FailureLimits, SolverOptions
from robot.integration.records import FAILED, SUCCESS, OutputTimes, Records, Trajectory
from robot.integration import records as R
from robot.integration.solvers import SecondOrderStructure, StepFailure, make_solver

#: restarts at one instant before the run is declared failed (contact events that make no progress)
MAX_STALLED_RESTARTS = 20
#: consecutive STALL_WINDOWs too slow for FailureLimits.max_steps before the run is declared stalled
STALLED_WINDOWS = 2
#: a step below FailureLimits.min_step but above this fraction of the run's span is short because the span is
#: (LSODA's first step on a 1e-10 s span is 1e-13 s): the collapse message then says to lower min_step. The
#: user's limit itself is kept: a run that must not take steps below it fails there.
SHORT_SPAN_STEP_FRACTION = 1e-6
_NONE = np.zeros(0, dtype=np.intp)


class EventSystem(Protocol):
    """What the step loop needs from a mechanism model.

    The loop owns the onset rates (one per contact candidate, the contact state of
    the Lankarani-Nikravesh law) and passes them in. ``derivative`` and ``probe``
    raise ``clearance_contact.ContactError`` in a pose the contact laws refuse
    (the loop answers a trial stage with ``inf`` or NaN, an accepted state with the
    failure "unphysical pose").
    """

    size: int  # state dimension
    n_candidates: int
    penetration_bounds: np.ndarray  # per candidate: a deeper penetration fails the run (inf: no bound)
    structure: SecondOrderStructure | None  # for the methods that need it (second_order_structure)
    #: ``jacobian(t, y, onset, out=None) -> df/dy`` for the methods that take one; None: the solver differences
    jacobian: Callable[..., np.ndarray] | None

    @property
    def rhs_calls(self) -> int:
        """Right-hand sides evaluated so far (counts ``derivative`` and any done for the Jacobian)."""

    def derivative(self, t: float, y: np.ndarray, onset: np.ndarray) -> np.ndarray: ...

    def probe(self, t: float, y: np.ndarray, onset: np.ndarray, residual: bool = True) -> ContactProbe: ...

    def penetrations(self, t: float, y: np.ndarray) -> np.ndarray: ...

    def normalise(self, y: np.ndarray) -> np.ndarray:
        """The state with unit quaternions (applied to every restart and located event state)."""

    def replica(self) -> "EventSystem":
        """The same system on its own work data (the force-peak search replays steps with it)."""


def onset_rate(approach_rate):
    """The onset rate ``ddelta0`` of an impact starting at ``approach_rate`` (m/s): floored, Lankarani-Nikravesh divides by it."""
    return np.maximum(approach_rate, ONSET_RATE_FLOOR)


def distinct_texts(value: float, limit: float) -> tuple[str, str]:
    """``value`` and ``limit`` printed with the fewest digits (at least 4) that tell them apart (1.000e-13 below 1.0e-13 reads false)."""
    for digits in range(3, 17):
        texts = f"{value:.{digits}e}", f"{limit:.{digits}e}"
        if texts[0] != texts[1]:
            break
    return texts


class _Failure(Exception):
    def __init__(self, cause: str, message: str):
        super().__init__(message)
        self.cause = cause


class _Step(NamedTuple):
    """An accepted solver step: its interval, end state and the probe there."""

    t_old: float
    t_new: float
    y_new: np.ndarray
    probe: ContactProbe


class EventDrivenIntegrator:
    """One run of the step loop (module docstring): :meth:`run` returns a :class:`Trajectory`.

    ``outputs``: times also recorded from the dense output (``RECORD_OUTPUT``);
    ``locate_force_peaks``: search each impact's force maximum
    (``RECORD_FORCE_PEAK``); ``progress(t)`` after every accepted step;
    ``onset_rates``: the contact state of a continued run (one per candidate): a
    candidate in contact at the start keeps its given onset rate (NaN: its current
    penetration rate, as for a fresh start), see :meth:`start`.
    """

    def __init__(
        self,
        system: EventSystem,
        y0: np.ndarray,
        t_span: tuple[float, float],
        options: SolverOptions,
        limits: FailureLimits = FailureLimits(),
        *,
        outputs: OutputTimes | None = None,
        locate_force_peaks: bool = True,
        progress: Callable[[float], None] | None = None,
        onset_rates: np.ndarray | None = None,
    ):
        self.system, self.options, self.limits = system, options, limits
        self.initial_onset_rates = None if onset_rates is None else np.asarray(onset_rates, dtype=float).reshape(system.n_candidates)
        self.traits = registry.traits(options.method)
        self.t0, self.t_final = map(float, t_span)
        self.t, self.y = self.t0, system.normalise(np.asarray(y0, dtype=float))
        self.onset = np.full(system.n_candidates, ONSET_RATE_FLOOR)
        # the onset rates the solver's right-hand sides read (in place): the contact state itself, except
        # for the fixed-step methods (set_step_onset_rates)
        self.step_onset = self.onset.copy() if self.traits.fixed_step else self.onset
        self.fun = derivative_or_refused(system, self.step_onset, refused_stage_value(self.traits))
        self.records, self.events = Records(system.n_candidates), []
        self.outputs, self.progress = outputs, progress
        self.force_peaks = ForcePeaks(system, options, self.records) if locate_force_peaks else None
        self.counts = dict(steps=0, rejected=0, rhs=0, restarts=0, hidden=0, jacobians=0)
        self.max_onset_overshoot = 0.0
        self.first_step = options.first_step
        self.stalled = 0
        self.pace_mark = self.t0  # time at the start of the current STALL_WINDOW of steps
        self.slow_windows = 0  # consecutive windows whose pace would exceed max_steps
        self.solver = None
        self.pen = self.rate = None  # penetrations and rates at (self.t, self.y)

    # --- the run -------------------------------------------------------------------------------
    def run(self) -> Trajectory:
        """Integrate over ``t_span``; never raises on divergence (see the trajectory's ``status``)."""
        started_cpu, started_wall = time.process_time(), time.perf_counter()
        self.started_wall = started_wall
        self.start()
        status, cause, message = SUCCESS, None, "the integration reached the end of the time span"
        try:
            while self.t < self.t_final:
                self.start_solver()
                restarted = False
                while self.solver.status == "running" and not restarted:
                    restarted = self.step()
                if restarted:
                    self.counts["restarts"] += 1
                    self.first_step = self.options.first_step if self.traits.fixed_step else self._step_size()
                    self.y = self.system.normalise(self.y)
                self.end_solver()
                if not restarted:
                    break
        except _Failure as failure:
            status, cause, message = FAILED, failure.cause, str(failure)
        except ContactLawError as exc:
            status, cause, message = FAILED, "contact law error", f"t={self.t:.9g} s: {exc}"
        except StepFailure as exc:  # a solver's own failure met outside its step (restepping to locate an onset)
            status, cause, message = FAILED, exc.failure_cause, f"t={self.t:.9g} s: {exc}"
        except (np.linalg.LinAlgError, RuntimeError, ValueError, ArithmeticError) as exc:
            status, cause, message = FAILED, "solver error", f"t={self.t:.9g} s: {self.options.method}: {type(exc).__name__}: {exc}"
        except KeyboardInterrupt:
            status, cause, message = FAILED, "interrupted", f"t={self.t:.9g} s: interrupted by the user"
        if status == FAILED:
            self.end_solver(count_rejected=False)
        return self.trajectory(status, cause, message, time.process_time() - started_cpu, time.perf_counter() - started_wall)

    def start(self) -> None:
        """Probe and record the initial state; candidates already in contact start with their current rate.

        A continued run (``onset_rates`` given) keeps, for a candidate in contact,
        the onset rate of the impact in progress: Lankarani-Nikravesh damping
        depends on the approach speed at the impact's onset, not on the current
        rate (NaN entries: the current rate).
        """
        try:
            start = self.probe(self.t, self.y)
        except _Failure as failure:
            raise ValueError(f"the initial state is not a valid pose ({failure})") from None
        self.record(self.t, self.y, R.RECORD_START, forces=start.normal_force)
        self.pen, self.rate = start.penetration, start.penetration_rate
        if self.outputs is not None:
            for t_out in self.outputs.take(self.t, self.t):
                self.record(t_out, self.y, R.RECORD_OUTPUT)
        given = self.initial_onset_rates
        for k in np.flatnonzero(self.pen > 0):
            continued = given is not None and np.isfinite(given[k])
            self.onset[k] = onset_rate(given[k] if continued else self.rate[k])

    def start_solver(self) -> None:
        """A new solver from the current state (at the start and after every onset)."""
        system, options = self.system, self.options
        self.solver = None
        self.calls_at_start = system.rhs_calls
        self.dense_calls = 0
        self.accepted_here = 0
        if self.traits.fixed_step:
            self.set_step_onset_rates()  # the new solver evaluates its first derivative with them
        jacobian = None
        if self.traits.takes_jacobian and system.jacobian is not None:
            onset = self.step_onset
            jacobian = lambda t, y, out=None: system.jacobian(t, y, onset, out)  # noqa: E731
        self.solver = make_solver(
            options.method, self.fun, self.t, self.y, self.t_final, options.rtol, options.atol, options.max_step, self.first_step, system.structure, jacobian
        )
        self.calls_after_init = system.rhs_calls

    def end_solver(self, count_rejected: bool = True) -> None:
        """Add the solver's right-hand sides, Jacobians and rejected steps to the run's counts."""
        counts, solver = self.counts, self.solver
        calls = self.system.rhs_calls
        counts["rhs"] += calls - self.calls_at_start
        self.calls_at_start = calls
        counts["jacobians"] += int(getattr(solver, "njev", 0) or 0)
        self.solver = None  # counted
        if not count_rejected or solver is None:
            return
        stages = self.traits.stages
        if stages is not None:
            # an explicit Runge-Kutta attempt costs `stages` calls (FSAL); the dense outputs' extra stages and
            # the steps redone to locate contact onsets (restep dense outputs) are not attempts
            restep_calls = getattr(solver, "n_restep_calls", 0)
            attempts = (calls - self.calls_after_init - self.dense_calls - restep_calls) / stages
            counts["rejected"] += max(0, int(round(attempts)) - self.accepted_here)
        elif getattr(solver, "n_rejected", None) is not None and counts["rejected"] >= 0:
            counts["rejected"] += solver.n_rejected
        else:
            counts["rejected"] = -1

    def _step_size(self) -> float | None:
        h = self.solver.step_size if self.solver.step_size else None
        return None if h is None or h <= 0 else h

    # --- one step --------------------------------------------------------------------------------
    def step(self) -> bool:
        """One accepted solver step and what happened in it; True if the run restarts at a contact onset."""
        step = self.advance()
        self.dense = self.onset_dense = None
        probe = step.probe
        flags = step_flags(self.pen, self.rate, probe.penetration, probe.penetration_rate, self.system.penetration_bounds)
        if flags & (ONSET | HIDDEN):
            found = self.find_onsets(step, flags)
            if found:
                self.restart_at_onset(step, found)
                return True
        self.check_failures(step.t_new, probe, bool(flags & OVER_BOUND))
        if flags & PEAK:
            self.locate_peaks(self.dense_output(), step.t_old, step.t_new, probe.penetration_rate)
        self.accept(step)
        return False

    def advance(self) -> _Step:
        """The solver's next accepted step, checked and probed at its end."""
        solver = self.solver
        if self.traits.fixed_step:
            self.set_step_onset_rates()
        message = solver.step()
        if solver.status == "failed":
            raise _Failure(getattr(solver, "failure_cause", None) or "step size collapse", f"t={solver.t:.9g} s: {message}")
        t_new, y_new = solver.t, solver.y
        self.accepted_here += 1
        steps = self.counts["steps"] = self.counts["steps"] + 1
        if not self.traits.fixed_step and t_new < self.t_final:
            h = solver.step_size
            if h is not None and h < self.limits.min_step:
                raise _Failure("step size collapse", self.collapse_message(t_new, h))
        if not all_finite(y_new):
            raise _Failure("non-finite state", f"t={t_new:.9g} s: the state is not finite")
        if steps % STALL_WINDOW == 0:
            self.check_pace(t_new)
        return _Step(solver.t_old, t_new, y_new, self.probe(t_new, y_new))

    def set_step_onset_rates(self) -> None:
        """Before a fixed-step method's step: a candidate out of contact gets its approach rate as onset rate.

        A candidate that comes into contact during the step meets it in the late
        stages, with the onset rate the right-hand side reads: the stored one is
        the floor or the last impact's, and Lankarani-Nikravesh damping divides by
        it, so with the floor (1e-4 m/s) it is ~1e4 times too large: it throws the
        bodies apart or stalls the Newton iterations of the implicit methods. An
        adaptive method rejects such a step by its error control; a fixed-step
        method accepts it. The approach rate at the step's start is the coming
        impact's to O(h). The candidates in contact keep their impact's onset rate.
        """
        out_of_contact = self.pen <= 0
        self.step_onset[:] = self.onset
        self.step_onset[out_of_contact] = onset_rate(self.rate[out_of_contact])

    def collapse_message(self, t_new: float, h: float) -> str:
        """Why a step of size ``h`` is a collapse; for a run so short that its steps are short, what to change."""
        size, limit = distinct_texts(h, self.limits.min_step)
        message = f"t={t_new:.9g} s: step size {size} s below {limit} s ([limits] min_step)"
        span = self.t_final - self.t0
        if h >= SHORT_SPAN_STEP_FRACTION * span:
            message += f"; the run spans only {span:.3g} s, so its steps are short: lower [limits] min_step for a run this short"
        return message

    def check_pace(self, t_new: float) -> None:
        """Every ``STALL_WINDOW`` steps: the steps taken plus those the last window's pace needs to the end.

        Two windows in a row must be that slow: one window of chattering early in a long
        run (a burst of impacts) is not a stall.
        """
        steps, advance = self.counts["steps"], t_new - self.pace_mark
        self.pace_mark = t_new
        remaining = self.t_final - t_new
        needed = steps + (STALL_WINDOW * remaining / advance if advance > 0 else math.inf) if remaining > 0 else steps
        self.slow_windows = self.slow_windows + 1 if needed > self.limits.max_steps else 0
        if self.slow_windows >= STALLED_WINDOWS:
            raise _Failure(
                "integration stalled",
                f"t={t_new:.9g} s: the last {STALL_WINDOW} steps advanced {advance:.3e} s (the {STALL_WINDOW} before "
                f"were as slow); at that pace the run needs "
                f"{needed:.2e} steps (limit max_steps = {self.limits.max_steps:.2e}): a singular configuration or a "
                "right-hand side that is not smooth (e.g. constraint rows switching near a rank loss)",
            )

    def find_onsets(self, step: _Step, flags: int) -> list[tuple[float, int]]:
        """(time, candidate) of every contact onset inside the step: zero crossings and hidden impacts."""
        pen_old, rate_old = self.pen, self.rate
        pen_new, rate_new = step.probe.penetration, step.probe.penetration_rate
        crossing = np.flatnonzero((pen_old <= 0) & (pen_new > 0)) if flags & ONSET else _NONE
        if self.options.hidden_contacts and flags & HIDDEN:
            hidden = np.flatnonzero((pen_old <= 0) & (pen_new <= 0) & (rate_old > 0) & (rate_new < 0))
        else:
            hidden = _NONE
        found = []
        if not (crossing.size or hidden.size):
            return found
        dense = self.onset_dense_output()
        for k in crossing:
            found.append((first_contact_time(self._penetration_on(dense, k), step.t_old, step.t_new), k))
        for k in hidden:
            t_k = hidden_contact(self._penetration_on(dense, k), step.t_old, step.t_new)
            if t_k is not None:
                found.append((t_k, k))
                self.counts["hidden"] += 1
        if crossing.size:
            self.max_onset_overshoot = max(self.max_onset_overshoot, float(np.max(pen_new[crossing])))
        return found

    def restart_at_onset(self, step: _Step, found: list[tuple[float, int]]) -> None:
        """Cut the step at the earliest onset: records up to it, the onset rates, the restart state.

        The restart state is checked as an accepted step's end is (it is where the run goes on from).
        """
        t_event = min(found)[0]
        dense = self.onset_dense_output()
        y_event = self.system.normalise(dense(t_event))
        at_event = self.probe(t_event, y_event)
        pen_e, rate_e = at_event.penetration, at_event.penetration_rate
        self.check_failures(t_event, at_event, bool(np.any(pen_e > self.system.penetration_bounds)))
        self.locate_peaks(dense, step.t_old, t_event, rate_e)
        # every candidate touching at the event starts its impact now (simultaneous
        # onsets are common: a tilting bearing meets both flanges at once)
        starting = sorted({k for t_k, k in found if t_k <= t_event} | set(np.flatnonzero((self.pen <= 0) & (pen_e >= 0))))
        for k in starting:
            self.onset[k] = onset_rate(rate_e[k])
            self.events.append((t_event, int(k), "onset", float(self.onset[k])))
        self.record_outputs(dense, step.t_old, t_event)
        self.record(t_event, y_event, R.RECORD_ONSET, forces=at_event.normal_force)
        if t_event <= self.t:
            self.stalled += 1
            if self.stalled > MAX_STALLED_RESTARTS:
                raise _Failure("event chattering", f"t={t_event:.9g} s: {self.stalled} contact events without progress in time")
        else:
            self.stalled = 0
        # the restart begins on the contact surface: count the starting candidates as
        # touching so the same onsets are not detected a second time; at the instant of the
        # previous restart, the candidates it started (marked touching, probed at exactly 0
        # now) keep their mark, or two simultaneous onsets would start each other in turn
        touching = starting if t_event > self.t else sorted(set(starting) | set(np.flatnonzero(self.pen > 0)))
        pen_e[touching] = np.maximum(pen_e[touching], np.finfo(float).tiny)
        self.t, self.y = t_event, y_event
        self.pen, self.rate = pen_e, rate_e

    def check_failures(self, t: float, probe: ContactProbe, over_bound: bool) -> None:
        """At a state the run goes on from (a step's end, a restart at an onset): penetration beyond its physical
        bound (``over_bound``: some candidate's), constraint drift, wall time."""
        limits = self.limits
        if over_bound:
            bounds = self.system.penetration_bounds
            pen = probe.penetration
            k = np.flatnonzero(pen > bounds)[0]
            raise _Failure(
                "penetration beyond physical bound",
                f"t={t:.9g} s: penetration {pen[k]:.3e} m of contact candidate {k} exceeds "
                f"{bounds[k]:.3e} m ({limits.penetration_ratio} x clearance)",
            )
        if probe.residual > limits.max_residual:
            raise _Failure("constraint drift", f"t={t:.9g} s: constraint residual {probe.residual:.3e} exceeds {limits.max_residual:.1e}")
        if time.perf_counter() - self.started_wall > limits.max_wall_time:
            raise _Failure("wall time", f"t={t:.9g} s: wall time limit {limits.max_wall_time} s reached")

    def locate_peaks(self, dense, t_old: float, t_to: float, rate_to: np.ndarray) -> None:
        """Record the penetration maxima inside (t_old, t_to), and with each its candidate's force maximum."""
        for k in np.flatnonzero((self.rate > 0) & (rate_to <= 0)):
            rate = lambda tt: float(self.probe(tt, dense(tt), residual=False).penetration_rate[k])  # noqa: E731
            try:
                t_peak = brentq(rate, t_old, t_to, xtol=1e-15, maxiter=200)
            except NoSignChange:  # the rate's sign change was not inside (t_old, t_to) after all
                continue
            y_peak = self.system.normalise(dense(t_peak))
            pen_peak = self.probe(t_peak, y_peak, residual=False).penetration[k]
            if not (pen_peak > 0 and t_old < t_peak < t_to):
                continue
            self.events.append((t_peak, int(k), "peak", float(pen_peak)))
            self.record(t_peak, y_peak, R.RECORD_PEAK)
            found = None if self.force_peaks is None else self.force_peaks.locate(int(k), dense, t_old, t_peak, t_to, self.onset)
            if found is not None:
                t_force, y_force, force, onset_rates = found
                self.events.append((t_force, int(k), "force_peak", force))
                self.record(t_force, y_force, R.RECORD_FORCE_PEAK, onset_rates)

    def accept(self, step: _Step) -> None:
        """Output times inside the step, the step's record; the step's end becomes the current state."""
        if self.outputs is not None and self.outputs.due(step.t_new):
            self.record_outputs(self.dense_output(), step.t_old, step.t_new)
        self.record(step.t_new, step.y_new, R.RECORD_STEP, forces=step.probe.normal_force)
        self.t, self.y = step.t_new, step.y_new
        self.pen, self.rate = step.probe.penetration, step.probe.penetration_rate
        if self.progress is not None:
            self.progress(self.t)

    # --- helpers ---------------------------------------------------------------------------------
    def dense_output(self):
        """The current step's dense output (made once per step; its extra stages are not counted as attempts)."""
        if self.dense is None:
            before = self.system.rhs_calls
            self.dense = self.solver.dense_output()
            self.dense_calls += self.system.rhs_calls - before
        return self.dense

    def onset_dense_output(self):
        """The dense output the current step's contact onsets are located on and its restart state taken from.

        A fixed-step method's step that crosses into a contact is accepted with
        late stages in contact (:meth:`set_step_onset_rates`): the states before
        the onset are taken as steps of the method from the step's start
        (``restep_dense_output``, :class:`robot.integration.dense.RestepDense`),
        out of contact and as accurate as the method. An adaptive method's
        accepted step is accurate to its tolerance over the whole step: its own
        dense output.
        """
        if self.onset_dense is None:
            restep = getattr(self.solver, "restep_dense_output", None) if self.traits.fixed_step else None
            self.onset_dense = self.dense_output() if restep is None else restep()
        return self.onset_dense

    def probe(self, t: float, y: np.ndarray, onset: np.ndarray | None = None, residual: bool = True) -> ContactProbe:
        """The system's probe at an accepted (or located) state: a refused pose means the run has blown up."""
        try:
            return self.system.probe(t, y, self.onset if onset is None else onset, residual)
        except ContactLawError:
            raise  # not the pose: a user-defined law broke its contract (run(): "contact law error")
        except ContactError as exc:
            # an accepted state (a fixed-step method accepts every step) in an absurd pose,
            # e.g. a journal turned half round in its bearing
            raise _Failure("unphysical pose", f"t={t:.9g} s: {exc}") from None

    def _penetration_on(self, dense, k: int) -> Callable[[float], float]:
        """Candidate ``k``'s penetration along the dense output (positions only: the onset root-finding)."""
        system = self.system

        def penetration(t: float) -> float:
            try:
                return float(system.penetrations(t, dense(t))[k])
            except ContactError as exc:
                raise _Failure("unphysical pose", f"t={t:.9g} s: {exc}") from None

        return penetration

    def record(self, t: float, y: np.ndarray, kind: int, onset_rates: np.ndarray | None = None, forces: np.ndarray | None = None) -> None:
        self.records.add(t, y, kind, self.onset if onset_rates is None else onset_rates, forces)

    def record_outputs(self, dense, t_from: float, t_to: float) -> None:
        """Record the output times in [t_from, t_to] not yet recorded, from the step's dense output."""
        if self.outputs is None:
            return
        for t_out in self.outputs.take(t_from, t_to):
            self.record(t_out, self.system.normalise(dense(t_out)), R.RECORD_OUTPUT)

    def trajectory(self, status: int, cause: str | None, message: str, cpu_time: float, wall_time: float) -> Trajectory:
        t, y, onset_rates, kind = self.records.arrays()
        counts = self.counts
        return Trajectory(
            status=status, message=message, cause=cause, t_end=float(t[-1]), t=t, y=y, onset_rates=onset_rates, kind=kind,
            n_steps=counts["steps"], n_rejected=counts["rejected"], n_rhs=counts["rhs"], n_events=len(self.events),
            n_restarts=counts["restarts"], n_jacobians=counts["jacobians"], cpu_time=cpu_time, wall_time=wall_time,
            events=self.events, n_hidden_contacts=counts["hidden"], max_onset_overshoot=self.max_onset_overshoot,
        )
