"""A generic event-driven integration loop for penalty contact with onset state.

``robot.integration.simulation.integrate`` is written for the Pinocchio model (it takes a
``DynamicsModel``), so the Newton-Euler formulation has its own loop, doing the
same thing for any ``rhs(t, y, onset)``:

* a ``scipy.integrate`` explicit Runge-Kutta solver (:data:`SOLVERS`: RK45, RK23
  or DOP853; the validation passes its pinned setting,
  :data:`robot.validation.settings.VALIDATION_SOLVER`, the same as the Lagrange
  run's) is stepped one accepted step at a time; any other method is refused
  with a ``ValueError`` naming it and the supported set (the loop needs the
  explicit solvers' ``step``/``dense_output`` and FSAL restarts);
* after each step the contact candidates are probed; a penetration crossing
  zero upward (**onset**) is located on the step's dense output with Brent's
  method, the step is cut there, the approach rate at that instant is stored as
  the Lankarani-Nikravesh onset rate ``ddelta0`` (floored by
  ``clearance_contact.ONSET_RATE_FLOOR``) and the solver is restarted;
  an impact that starts and ends inside one step (approaching at the start,
  receding at the end, out of contact at both) is found by sampling the dense
  output, so no step jumps over a contact;
* penetration maxima (rate crossing zero downward while in contact) are located
  and recorded, so force peaks are not lost to output sampling;
* optional output times ``t_eval`` are filled from the dense output of the
  step that contains them (no interpolation between records).

``scipy.integrate.solve_ivp`` with terminal events would locate the onsets too,
but it only tests event functions at step ends, so impacts shorter than a step
would be missed; hence this loop (the same design as ``robot.integration.simulation``).
A right-hand side that raises ``clearance_contact.ContactError`` (a trial stage
of a too-large step in an absurd pose) answers with ``inf``: the step's error
estimate is then infinite and the solver rejects and shrinks the step.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Callable

import numpy as np
from scipy.integrate import DOP853, RK23, RK45
from scipy.optimize import brentq

from clearance_contact import ONSET_RATE_FLOOR, ContactError
from robot.integration.simulation import RECORD_ONSET, RECORD_PEAK, RECORD_START, RECORD_STEP, first_contact_time

#: the methods this loop supports (explicit Runge-Kutta with dense output)
SOLVERS = {"RK45": RK45, "RK23": RK23, "DOP853": DOP853}
MAX_STALLED_RESTARTS = 20


@dataclass
class EventRun:
    """Records of an event-driven run (like ``robot.integration.simulation.Trajectory``)."""

    success: bool
    message: str
    t: np.ndarray
    y: np.ndarray
    onset_rates: np.ndarray
    kind: np.ndarray
    t_eval: np.ndarray
    y_eval: np.ndarray
    onset_eval: np.ndarray
    events: list = field(default_factory=list)
    n_steps: int = 0
    n_rhs: int = 0
    n_restarts: int = 0
    wall_time: float = 0.0
    settings: dict = field(default_factory=dict)  # method, rtol, atol, max_step actually used


def integrate_with_events(
    rhs: Callable[[float, np.ndarray, np.ndarray], np.ndarray],
    probe: Callable[[float, np.ndarray, np.ndarray], tuple[np.ndarray, np.ndarray]],
    y0: np.ndarray,
    t_span: tuple[float, float],
    n_candidates: int,
    *,
    normalise: Callable[[np.ndarray], np.ndarray] = lambda y: y,
    method: str = "RK45",
    rtol: float = 1e-7,
    atol: float = 1e-9,
    max_step: float = 1e-3,
    t_eval: np.ndarray | None = None,
    first_step: float | None = None,
) -> EventRun:
    """Integrate ``y' = rhs(t, y, onset)`` with contact-onset events.

    ``probe(t, y, onset) -> (penetration, penetration_rate)`` per candidate.
    ``normalise`` is applied to every restart state (e.g. unit quaternions).
    ``first_step``: the first step (``None``: scipy's estimate); later restarts
    start with the step size reached before the event.
    ``method`` must be one of :data:`SOLVERS` and the tolerances positive
    (``ValueError`` otherwise, naming the parameter, its value and what is valid).
    """
    if method not in SOLVERS:
        raise ValueError(
            f"integrate_with_events: method={method!r} is not supported; supported methods: {', '.join(SOLVERS)} "
            "(explicit Runge-Kutta with dense output)"
        )
    for name, value in (("rtol", rtol), ("atol", atol), ("max_step", max_step)) + ((("first_step", first_step),) if first_step is not None else ()):
        if not (isinstance(value, (int, float)) and not isinstance(value, bool) and value > 0):
            raise ValueError(f"integrate_with_events: {name}={value!r} must be a positive number")
    settings = dict(method=method, rtol=float(rtol), atol=float(atol), max_step=float(max_step), first_step=first_step)
    started = time.perf_counter()
    onset = np.full(n_candidates, ONSET_RATE_FLOOR)
    counter = [0]

    def f(t, y):
        counter[0] += 1
        try:
            return rhs(t, y, onset)
        except ContactError:
            return np.full_like(y, np.inf)

    rec_t, rec_y, rec_on, rec_kind, events = [], [], [], [], []
    t_eval = np.array([] if t_eval is None else t_eval, dtype=float)
    y_eval = np.full((len(t_eval), len(y0)), np.nan)
    on_eval = np.full((len(t_eval), n_candidates), np.nan)
    next_eval = 0

    def record(t, y, kind):
        rec_t.append(t)
        rec_y.append(np.array(y))
        rec_on.append(onset.copy())
        rec_kind.append(kind)

    def fill_eval(dense, t_lo, t_hi):
        nonlocal next_eval
        while next_eval < len(t_eval) and t_eval[next_eval] <= t_hi:
            if t_eval[next_eval] >= t_lo:
                y_eval[next_eval] = dense(t_eval[next_eval]) if dense is not None else y
                on_eval[next_eval] = onset
            next_eval += 1

    def pen_at(dense, tt, k):
        return float(probe(tt, dense(tt), onset)[0][k])

    root = first_contact_time

    def hidden(dense, k, t_old, t_new, samples=8):
        previous = t_old
        for tt in np.linspace(t_old, t_new, samples + 2)[1:-1]:
            if pen_at(dense, tt, k) > 0:
                return root(lambda s: pen_at(dense, s, k), previous, tt)
            previous = tt
        return None

    def peaks(dense, rate_old, rate_new, t_old, t_new):
        for k in np.flatnonzero((rate_old > 0) & (rate_new <= 0)):
            fun = lambda tt: float(probe(tt, dense(tt), onset)[1][k])  # noqa: E731
            try:
                t_peak = brentq(fun, t_old, t_new, xtol=1e-15, maxiter=200)
            except ValueError:
                continue
            y_peak = normalise(dense(t_peak))
            if probe(t_peak, y_peak, onset)[0][k] > 0 and t_old < t_peak < t_new:
                events.append((t_peak, int(k), "peak"))
                record(t_peak, y_peak, RECORD_PEAK)

    t0, t1 = map(float, t_span)
    t, y = t0, normalise(np.asarray(y0, dtype=float))
    record(t, y, RECORD_START)
    fill_eval(None, t0, t0)
    pen_old, rate_old = probe(t, y, onset)
    for k in np.flatnonzero(pen_old > 0):
        onset[k] = max(rate_old[k], ONSET_RATE_FLOOR)
    solver_class = SOLVERS[method]
    n_steps = n_restarts = stalled = 0
    success, message = True, "the integration reached the end of the time span"
    try:
        while t < t1:
            kwargs = dict(rtol=rtol, atol=atol, max_step=max_step)
            if first_step:
                kwargs["first_step"] = min(first_step, t1 - t)
            solver = solver_class(f, t, y, t1, **kwargs)
            restarted = False
            while solver.status == "running":
                solver.step()
                if solver.status == "failed":
                    raise RuntimeError(f"t={solver.t:.9g} s: step size collapse")
                n_steps += 1
                t_old, t_new, y_new = solver.t_old, solver.t, solver.y
                if not np.all(np.isfinite(y_new)):
                    raise RuntimeError(f"t={t_new:.9g} s: non-finite state")
                pen_new, rate_new = probe(t_new, y_new, onset)
                dense = None
                crossing = np.flatnonzero((pen_old <= 0) & (pen_new > 0))
                quiet = np.flatnonzero((pen_old <= 0) & (pen_new <= 0) & (rate_old > 0) & (rate_new < 0))
                found = []
                if crossing.size or quiet.size:
                    dense = solver.dense_output()
                    for k in crossing:
                        found.append((root(lambda tt: pen_at(dense, tt, k), t_old, t_new), k))
                    for k in quiet:
                        tk = hidden(dense, k, t_old, t_new)
                        if tk is not None:
                            found.append((tk, k))
                if found:
                    t_event = min(found)[0]
                    y_event = normalise(dense(t_event))
                    pen_e, rate_e = probe(t_event, y_event, onset)
                    peaks(dense, rate_old, rate_e, t_old, t_event)
                    fill_eval(dense, t_old, t_event)
                    starting = sorted({k for tk, k in found if tk <= t_event} | set(np.flatnonzero((pen_old <= 0) & (pen_e >= 0))))
                    for k in starting:
                        onset[k] = max(rate_e[k], ONSET_RATE_FLOOR)
                        events.append((t_event, int(k), "onset"))
                    record(t_event, y_event, RECORD_ONSET)
                    stalled = stalled + 1 if t_event <= t else 0
                    if stalled > MAX_STALLED_RESTARTS:
                        raise RuntimeError(f"t={t_event:.9g} s: contact events without progress in time")
                    t, y = t_event, y_event
                    pen_old, rate_old = pen_e, rate_e
                    pen_old[starting] = np.maximum(pen_old[starting], np.finfo(float).tiny)
                    restarted = True
                    break
                if np.any((pen_new > 0) & (rate_old > 0) & (rate_new <= 0)):
                    dense = dense or solver.dense_output()
                    peaks(dense, rate_old, rate_new, t_old, t_new)
                if next_eval < len(t_eval) and t_eval[next_eval] <= t_new:
                    dense = dense or solver.dense_output()
                    fill_eval(dense, t_old, t_new)
                record(t_new, y_new, RECORD_STEP)
                t, y = t_new, y_new
                pen_old, rate_old = pen_new, rate_new
            if restarted:
                n_restarts += 1
                first_step = solver.step_size
                y = normalise(y)
            else:
                break
    except (RuntimeError, np.linalg.LinAlgError, ValueError) as exc:
        success, message = False, str(exc)
    order = np.argsort(rec_t, kind="stable")
    return EventRun(
        success,
        message,
        np.array(rec_t)[order],
        np.array(rec_y)[order],
        np.array(rec_on).reshape(len(rec_t), n_candidates)[order],
        np.array(rec_kind, dtype=np.int8)[order],
        t_eval,
        y_eval,
        on_eval,
        events,
        n_steps,
        counter[0],
        n_restarts,
        time.perf_counter() - started,
        settings,
    )
