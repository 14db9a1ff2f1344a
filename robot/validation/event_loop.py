"""The Newton-Euler cross-check's use of the step loop, and a function-based front end to it.

The validation integrates its Newton-Euler model with the same step loop as the
Lagrange model (:class:`robot.integration.event_loop.EventDrivenIntegrator`:
contact onsets located on the dense output and restarted at, hidden impacts
found, penetration maxima recorded); the check's independence lies in its
equations of motion, not in the loop. This module adds what the validation
needs on top:

* the methods it offers, :data:`SOLVERS`: the registry's explicit
  variable-step methods (RK45, RK23, DOP853; :mod:`robot.integration.methods`),
  on which the cross-engine thresholds are calibrated
  (:data:`robot.validation.settings.VALIDATION_SOLVER`); any other method is
  refused with a ``ValueError`` naming it and the supported set;
* output times ``t_eval`` filled from the dense output of the step that
  contains them, returned apart from the records (:class:`EventRun`);
* :func:`integrate_with_events`: the loop for any ``rhs(t, y, onset)`` and
  ``probe(t, y, onset) -> (penetration, penetration_rate)``.

The validation's runs do not locate force maxima (their records are the
Lagrange loop's but for ``RECORD_FORCE_PEAK``), do not check a step-size floor
and have no penetration bound or residual check (the Newton-Euler state carries
no such limit): failures are a solver failure, a non-finite state, an
unphysical pose or event chattering.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from clearance_contact import ONSET_RATE_FLOOR

from robot.integration import methods as registry
from robot.integration.event_loop import ContactProbe, EventDrivenIntegrator, EventSystem
from robot.integration.options import FailureLimits, SolverOptions
from robot.integration.records import RECORD_OUTPUT, OutputTimes

#: the methods the validation offers: the registry's explicit variable-step methods (a live view)
SOLVERS = registry.TraitView(registry.IntegratorTraits.solver_class, lambda t: t.explicit and not t.fixed_step)
#: no step-size floor, no residual check: the validation's loop stops only on real failures
VALIDATION_LIMITS = FailureLimits(min_step=0.0, max_residual=math.inf)


@dataclass
class EventRun:
    """Records of an event-driven run (like ``robot.integration.records.Trajectory``), and the ``t_eval`` outputs."""

    success: bool
    message: str
    t: np.ndarray
    y: np.ndarray
    onset_rates: np.ndarray
    kind: np.ndarray
    t_eval: np.ndarray
    y_eval: np.ndarray
    onset_eval: np.ndarray
    events: list = field(default_factory=list)  # (t, candidate, "onset" | "peak")
    n_steps: int = 0
    n_rhs: int = 0
    n_restarts: int = 0
    wall_time: float = 0.0
    settings: dict = field(default_factory=dict)  # method, rtol, atol, max_step actually used


def check_settings(method: str, rtol, atol, max_step, first_step) -> None:
    """``ValueError`` naming the parameter, its value and what is valid."""
    if method not in SOLVERS:
        raise ValueError(
            f"integrate_with_events: method={method!r} is not supported; supported methods: {', '.join(SOLVERS)} "
            "(explicit Runge-Kutta with dense output)"
        )
    for name, value in (("rtol", rtol), ("atol", atol), ("max_step", max_step)) + ((("first_step", first_step),) if first_step is not None else ()):
        if not (isinstance(value, (int, float)) and not isinstance(value, bool) and value > 0):
            raise ValueError(f"integrate_with_events: {name}={value!r} must be a positive number")


def run_events(system: EventSystem, y0: np.ndarray, t_span: tuple[float, float], options: SolverOptions, t_eval: np.ndarray | None = None) -> EventRun:
    """Run the step loop over ``system`` with the validation's settings (see the module docstring)."""
    check_settings(options.method, options.rtol, options.atol, options.max_step, options.first_step)
    t_eval = np.array([] if t_eval is None else t_eval, dtype=float)
    outputs = OutputTimes.at(t_eval)
    trajectory = EventDrivenIntegrator(system, y0, t_span, options, VALIDATION_LIMITS, outputs=outputs, locate_force_peaks=False).run()
    is_output = trajectory.kind == RECORD_OUTPUT
    y_eval = np.full((len(t_eval), system.size), np.nan)
    onset_eval = np.full((len(t_eval), system.n_candidates), np.nan)
    taken = outputs.taken[: int(np.count_nonzero(is_output))]
    y_eval[taken] = trajectory.y[is_output]
    onset_eval[taken] = trajectory.onset_rates[is_output]
    kept = ~is_output
    order = np.argsort(trajectory.t[kept], kind="stable")
    return EventRun(
        trajectory.success,
        trajectory.message,
        trajectory.t[kept][order],
        trajectory.y[kept][order],
        trajectory.onset_rates[kept][order],
        trajectory.kind[kept][order],
        t_eval,
        y_eval,
        onset_eval,
        [(t, k, kind) for t, k, kind, _ in trajectory.events],
        trajectory.n_steps,
        trajectory.n_rhs,
        trajectory.n_restarts,
        trajectory.wall_time,
        dict(method=options.method, rtol=float(options.rtol), atol=float(options.atol), max_step=float(options.max_step), first_step=options.first_step),
    )


class FunctionSystem:
    """An :class:`~robot.integration.event_loop.EventSystem` from plain functions (no normal forces, no residual)."""

    structure = None
    jacobian = None

    def __init__(self, rhs, probe, size: int, n_candidates: int, normalise: Callable[[np.ndarray], np.ndarray]):
        self._rhs, self._probe, self._normalise = rhs, probe, normalise
        self.size, self.n_candidates = size, n_candidates
        self.penetration_bounds = np.full(n_candidates, np.inf)
        self.rhs_calls = 0
        self._floor = np.full(n_candidates, ONSET_RATE_FLOOR)  # penetrations do not depend on the onset rates

    def derivative(self, t: float, y: np.ndarray, onset: np.ndarray) -> np.ndarray:
        self.rhs_calls += 1
        return self._rhs(t, y, onset)

    def probe(self, t: float, y: np.ndarray, onset: np.ndarray, residual: bool = True) -> ContactProbe:
        penetration, rate = self._probe(t, y, onset)
        return ContactProbe(penetration, rate, math.nan, np.full(self.n_candidates, math.nan))

    def penetrations(self, t: float, y: np.ndarray) -> np.ndarray:
        return self._probe(t, y, self._floor)[0]

    def normalise(self, y: np.ndarray) -> np.ndarray:
        return self._normalise(y)

    def replica(self) -> "FunctionSystem":
        return self


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
    check_settings(method, rtol, atol, max_step, first_step)
    system = FunctionSystem(rhs, probe, len(y0), n_candidates, normalise)
    options = SolverOptions(method, rtol=rtol, atol=atol, max_step=max_step, first_step=first_step)
    return run_events(system, y0, t_span, options, t_eval)
