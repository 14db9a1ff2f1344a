"""One run of a scene with chosen solver options, summarised for the studies.

:func:`simulate` integrates a built :class:`robot.run.Run` (optionally with
another dynamics model, e.g. other Baumgarte gains) and returns an
:class:`Outcome`: the run's status, cause, counts and CPU time, the outputs on a
common output grid (end-effector position, driving forces) and the statistics
that survive the separation of trajectories after impacts (peak contact force
and impulse per clearance joint, RMS driving forces), plus the run's own
constraint drift and energy-balance error.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, field
from typing import Callable, TypeVar

import numpy as np

from robot.io.atomic import atomic_write_png
from robot.io.results import make_result
from robot.run import Run
from robot.integration.simulation import RECORD_OUTPUT, FailureLimits, SolverOptions, integrate


@dataclass
class Outcome:
    """What a study keeps of one run."""

    label: str
    options: dict
    status: int
    cause: str | None
    message: str
    t_reached: float
    cpu_time: float
    wall_time: float
    n_steps: int
    n_rejected: int
    n_rhs: int
    n_jacobians: int
    n_events: int
    n_hidden_contacts: int
    max_onset_overshoot: float
    max_residual: float = math.nan
    energy_error: float = math.nan  # max |Delta(T + V) - W_act - W_contact - W_force| (J)
    actuator_work_scale: float = math.nan  # max |W_act| (J), to make energy_error relative
    energy_scale: float = math.nan  # max(max T, max V - min V) (J): energy_error's scale without actuator work
    peaks: dict = field(default_factory=dict)  # joint -> peak normal force (N) over the run
    impulses: dict = field(default_factory=dict)  # joint -> integral of the normal forces (N s)
    grid_t: np.ndarray | None = None
    grid_ee: np.ndarray | None = None
    grid_force: np.ndarray | None = None
    peak_times: dict = field(default_factory=dict)

    @property
    def success(self) -> bool:
        return self.status == 0

    def counts(self) -> dict:
        """JSON-ready summary (no arrays)."""
        return {
            "label": self.label,
            "options": self.options,
            "status": self.status,
            "cause": self.cause,
            "message": self.message,
            "t_reached": self.t_reached,
            "cpu_time": self.cpu_time,
            "wall_time": self.wall_time,
            "steps": self.n_steps,
            "rejected": self.n_rejected,
            "rhs_calls": self.n_rhs,
            "jacobians": self.n_jacobians,
            "events": self.n_events,
            "hidden_contacts": self.n_hidden_contacts,
            "max_onset_overshoot": self.max_onset_overshoot,
            "max_constraint_residual": self.max_residual,
            "energy_error": self.energy_error,
            "peak_force": self.peaks,
            "impulse": self.impulses,
        }


def options_dict(options: SolverOptions) -> dict:
    return {
        "method": options.method,
        "rtol": options.rtol,
        "atol": options.atol,
        "max_step": options.max_step if math.isfinite(options.max_step) else None,
        "first_step": options.first_step,
        "hidden_contacts": options.hidden_contacts,
        "jacobian": options.jacobian,
    }


def simulate(
    run: Run,
    options: SolverOptions,
    t_end: float,
    *,
    label: str | None = None,
    limits: FailureLimits | None = None,
    dynamics=None,
    outputs: bool = True,
) -> Outcome:
    """Integrate ``run`` over [0, t_end] and summarise it (never raises on divergence)."""
    dynamics = dynamics or run.dynamics
    limits = limits or run.scene.limits
    with warnings.catch_warnings():
        # trial stages answered with inf (absurd poses, see robot.integration.simulation) make scipy warn
        warnings.simplefilter("ignore", RuntimeWarning)
        trajectory = integrate(dynamics, run.y0, (0.0, t_end), options, limits)
    outcome = Outcome(
        label=label or options.method,
        options=options_dict(options),
        status=trajectory.status,
        cause=trajectory.cause,
        message=trajectory.message,
        t_reached=trajectory.t_end,
        cpu_time=trajectory.cpu_time,
        wall_time=trajectory.wall_time,
        n_steps=trajectory.n_steps,
        n_rejected=trajectory.n_rejected,
        n_rhs=trajectory.n_rhs,
        n_jacobians=trajectory.n_jacobians,
        n_events=sum(1 for e in trajectory.events if e[2] == "onset"),
        n_hidden_contacts=trajectory.n_hidden_contacts,
        max_onset_overshoot=trajectory.max_onset_overshoot,
    )
    if not outputs:
        return outcome
    result = make_result(run.scene.name, dynamics, trajectory, {})
    t = result["t"]
    outcome.max_residual = float(np.max(result["constraint_residual"]))
    energy = result["kinetic_energy"] + result["potential_energy"]
    work = result["actuator_work"] + result["contact_work"]
    if "force_work" in result.keys():  # force elements: their work (springs' included, = -their energy change)
        work = work + result["force_work"]
    balance = (energy - energy[0]) - work
    outcome.energy_error = float(np.max(np.abs(balance)))
    outcome.actuator_work_scale = float(np.max(np.abs(result["actuator_work"])))
    outcome.energy_scale = float(max(np.max(result["kinetic_energy"]), np.ptp(result["potential_energy"])))
    for joint in result.clearance_joints or [c.site.name for c in dynamics.contacts]:
        force = np.atleast_2d(result[f"{joint}_normal_force"].T).T
        total = force.sum(axis=1)
        i = int(np.argmax(force.max(axis=1))) if len(t) else 0
        outcome.peaks[joint] = float(force.max()) if force.size else 0.0
        outcome.peak_times[joint] = float(t[i]) if len(t) else 0.0
        outcome.impulses[joint] = float(np.trapezoid(total, t)) if len(t) > 1 else 0.0
    grid = result["record_kind"] == RECORD_OUTPUT
    outcome.grid_t = t[grid]
    outcome.grid_ee = result["ee_position"][grid]
    outcome.grid_force = result["driving_force"][grid]
    return outcome


INTERRUPTED = "interrupted"

Result = TypeVar("Result")


class StudyStopped(RuntimeError):
    """A study that stopped before its end: the user stopped it, or a run it depends on failed.

    ``finished``: what the study completed (its rows, or its map filled so far),
    for the caller to save; ``stopped_run``: the counts of the run it stopped in
    (``None`` when it stopped between runs); ``reason``: ``"interrupted"`` or
    why a needed run failed.
    """

    def __init__(self, message: str, finished=None, stopped_run: dict | None = None, reason: str = INTERRUPTED):
        super().__init__(message)
        self.finished, self.stopped_run, self.reason = finished, stopped_run, reason


def run_or_stop(simulate_run: Callable[[], Result], label: str, finished=None, stop: Callable[[], bool] | None = None) -> Result:
    """``simulate_run()`` (an :class:`Outcome` or a dict of counts), unless the user stops the study.

    Raises :class:`StudyStopped` with ``finished`` when ``stop()`` is true before
    the run (a stop asked for between runs), when the run was interrupted (cause
    ``interrupted``) or when it let a ``KeyboardInterrupt`` through.
    """
    if stop is not None and stop():
        raise StudyStopped(f"stopped before {label}", finished)
    try:
        result = simulate_run()
    except KeyboardInterrupt:
        raise StudyStopped(f"{label}: interrupted by the user", finished) from None
    counts = result.counts() if isinstance(result, Outcome) else result
    if counts.get("cause") == INTERRUPTED:
        message = counts.get("message") or f"t={counts.get('t_reached', math.nan):.9g} s: interrupted by the user"
        raise StudyStopped(f"{label}: {message}", finished, counts)
    return result


def save_png(fig, path, **options) -> None:
    """Write ``fig`` as a PNG (110 dpi) to ``path`` atomically (a reader never sees half a file), then close it."""
    atomic_write_png(fig, path, dpi=110, close=True, **options)
