"""Work-precision: every integrator on offer, error against CPU time.

Reference
    DOP853 at ``rtol = 1e-11`` (``atol = 1e-13``), checked against DOP853 at
    ``rtol = 1e-10``: the two agree on the end-effector position to better than
    ``window_tolerance`` (1e-8 m) up to a time ``t_c``. Impacts amplify every
    perturbation (two tight references separate exponentially after a few
    impacts), so *pointwise* errors are measured only over the comparable window
    [0, t_c]; over the whole horizon [0, T] the runs are compared by statistics
    that do not need aligned trajectories: peak contact force and normal-force
    impulse per clearance joint, RMS driving force per actuator.

Error measures (``errors``)
    * ``ee``: max |p_ee - p_ee,ref| over the output grid in [0, t_c] (m);
    * ``driving``: max |F - F_ref| / max |F_ref| over [0, t_c] (relative);
    * ``peak_force``: max over joints of |peak - peak_ref| / peak_ref over [0, T];
    * ``impulse``: the same for the normal-force impulses;
    * ``driving_rms``: max over actuators of |rms F - rms F_ref| / rms F_ref over [0, T];
    * ``drift``: the run's own max |Phi| (m);
    * ``energy``: the run's own max |Delta(T + V) - W_act - W_contact - W_force| (J; ``W_force``:
      the force elements' work, where there are any), and ``energy_relative``: relative to
      the reference's max |W_act|, or, for a reference without actuator work (a passive
      mechanism), to its largest mechanical energy :attr:`Reference.energy_scale` (the larger
      of its peak kinetic energy and its potential-energy range);
    * ``driving_n``: the ``driving`` error in N (max |F - F_ref|).

    Not applicable (``None``): ``driving``, ``driving_n`` and ``driving_rms`` of a mechanism without
    actuators, ``energy_relative`` of a reference that neither works nor moves. Applicable but not
    measured (NaN: the run did not get there): counts as beyond every threshold
    (:func:`beyond`). ``peak_force`` and ``impulse`` of a scene without clearance joints are 0.

Sweep
    variable-step methods over tolerances (``atol = rtol / 100``), fixed-step
    methods over step sizes; CPU time (``time.process_time`` of the integration
    only), steps, rejected steps (-1: the method does not tell), right-hand-side
    calls, events.

Stops
    Ctrl-C (or SIGTERM, through ``robot.cli.interrupts``) stops the run in
    progress with cause ``interrupted``; the study then raises
    :class:`StudyStopped` carrying what it finished (:func:`run_or_stop`, which
    the stability maps use too), so that the caller can save it. A reference
    run that fails stops the study the same way (nothing can be measured
    without it).
"""

from __future__ import annotations

import math
import textwrap
from dataclasses import dataclass, field, replace
from functools import partial
from typing import Callable

import numpy as np

from robot.integration import methods as registry
from robot.integration.methods import FIXED_STEP_METHODS, METHODS
from robot.run import Run
from robot.integration.simulation import SolverOptions
from robot.analysis.studies.common import Outcome, StudyStopped, run_or_stop, save_png, simulate

#: tolerances (variable step) and step sizes (fixed step) of the default sweep
TOLERANCES = (1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9)
#: step sizes of the fixed-step methods: each method's registered ``step_sizes`` (robot.integration.methods; a live view)
STEP_SIZES = registry.STEP_SIZES
REFERENCE = SolverOptions("DOP853", rtol=1e-11, atol=1e-13, max_step=1e-3)
CHECK = SolverOptions("DOP853", rtol=1e-10, atol=1e-12, max_step=1e-3)
#: engineering accuracy: end-effector within 1 um (comparable window), peak contact forces within 1 %
EE_TARGET = 1e-6
PEAK_TARGET = 1e-2
#: engineering accuracy: constraint drift (max |Phi|, m)
DRIFT_TARGET = 1e-6
#: the engineering accuracy as thresholds of :func:`errors` (each measure within, i.e. <=, its threshold)
ENGINEERING = {"ee": EE_TARGET, "peak_force": PEAK_TARGET, "drift": DRIFT_TARGET}


@dataclass
class Reference:
    outcome: Outcome
    check: Outcome
    window: float  # t_c: the references agree to window_tolerance on [0, t_c]
    window_tolerance: float
    agreement: dict = field(default_factory=dict)  # errors of the check run against the reference

    @property
    def energy_scale(self) -> float:
        """J: the reference's largest mechanical energy, max(max T, max V - min V), what ``energy_relative`` is
        relative to when the reference has no actuator work (NaN when the actuators work: their work is the scale)."""
        return math.nan if self.outcome.actuator_work_scale > 0 else self.outcome.energy_scale

    def summary(self) -> dict:
        return {
            "reference": self.outcome.counts(),
            "check": self.check.counts(),
            "comparable_window_s": self.window,
            "window_tolerance_m": self.window_tolerance,
            "check_against_reference": self.agreement,
            "energy_scale_J": self.energy_scale,
        }


def comparable_window(a: Outcome, b: Outcome, tolerance: float) -> float:
    """Last output time up to which the end-effector positions of a and b agree to ``tolerance``."""
    n = min(len(a.grid_t), len(b.grid_t))
    if n == 0:
        return 0.0
    gap = np.linalg.norm(a.grid_ee[:n] - b.grid_ee[:n], axis=1)
    over = np.flatnonzero(gap > tolerance)
    if over.size == 0:
        return float(a.grid_t[n - 1])
    return float(a.grid_t[over[0] - 1]) if over[0] > 0 else 0.0


def reference(run: Run, t_end: float, output_step: float, window_tolerance: float = 1e-8, stop: Callable[[], bool] | None = None) -> Reference:
    """The reference and its check run; :class:`StudyStopped` if either is stopped or fails (``finished``: the runs done)."""
    labels = ("reference DOP853 rtol 1e-11", "check DOP853 rtol 1e-10")
    ref = run_or_stop(partial(simulate, run, replace(REFERENCE, output_step=output_step), t_end, label=labels[0]), labels[0], stop=stop)
    done = {"reference": ref.counts()}
    check = run_or_stop(partial(simulate, run, replace(CHECK, output_step=output_step), t_end, label=labels[1]), labels[1], done, stop)
    if not (ref.success and check.success):
        done["check"] = check.counts()
        raise StudyStopped(f"reference runs failed: {ref.message}; {check.message}", done, reason="reference failed")
    window = comparable_window(ref, check, window_tolerance)
    reference = Reference(ref, check, window, window_tolerance)
    reference.agreement = errors(check, reference)
    return reference


def relative_error(value: float, ref: float) -> float:
    """|value - ref| / |ref| (|value| if ref is 0)."""
    return abs(value - ref) / abs(ref) if ref else abs(value)


def beyond(errors: dict, thresholds: dict) -> list[str]:
    """The measures of ``thresholds`` beyond (>) their threshold in ``errors``: NaN counts as beyond, None
    (not applicable) and a missing key do not."""
    return [key for key, limit in thresholds.items() if errors.get(key) is not None and not errors[key] <= limit]


def errors(outcome: Outcome, ref: Reference) -> dict:
    """The error measures of the module docstring (NaN where the run did not get there, None where a measure
    does not apply), and ``engineering_accuracy`` (:data:`ENGINEERING`). The stability maps use them too."""
    r = ref.outcome
    out: dict = {"drift": outcome.max_residual, "energy": outcome.energy_error}
    scale = r.actuator_work_scale if r.actuator_work_scale > 0 else ref.energy_scale
    out["energy_relative"] = outcome.energy_error / scale if scale > 0 else (math.nan if math.isnan(scale) else None)
    actuated = r.grid_force is not None and r.grid_force.ndim == 2 and r.grid_force.shape[1] > 0
    n = min(len(outcome.grid_t), len(r.grid_t)) if outcome.grid_t is not None else 0
    window = (r.grid_t[:n] <= ref.window + 1e-12) if n else np.zeros(0, bool)
    out["ee"] = out["driving"] = out["driving_n"] = math.nan
    if n and np.allclose(outcome.grid_t[:n], r.grid_t[:n]) and window.any():
        out["ee"] = float(np.linalg.norm(outcome.grid_ee[:n][window] - r.grid_ee[:n][window], axis=1).max())
        if actuated:
            out["driving_n"] = float(np.abs(outcome.grid_force[:n][window] - r.grid_force[:n][window]).max())
            f_max = float(np.max(np.abs(r.grid_force[:n][window])))
            out["driving"] = out["driving_n"] / f_max if f_max > 0 else (math.inf if out["driving_n"] > 0 else 0.0)
    if not actuated:
        out["driving"] = out["driving_n"] = None
    complete = outcome.success and n == len(r.grid_t)
    if complete:
        by_joint = {j: relative_error(outcome.peaks.get(j, math.nan), r.peaks[j]) for j in r.peaks}
        out["peak_force"] = max(by_joint.values(), default=0.0)
        out["peak_force_by_joint"] = by_joint
        out["impulse"] = max((relative_error(outcome.impulses.get(j, math.nan), r.impulses[j]) for j in r.impulses), default=0.0)
        if actuated:
            rms = np.sqrt(np.mean(outcome.grid_force**2, axis=0))
            rms_ref = np.sqrt(np.mean(r.grid_force**2, axis=0))
            out["driving_rms"] = float(np.max(np.abs(rms - rms_ref) / rms_ref))
        else:
            out["driving_rms"] = None
    else:
        out["peak_force"] = out["impulse"] = math.nan
        out["driving_rms"] = math.nan if actuated else None
        out["peak_force_by_joint"] = {}
    out["engineering_accuracy"] = bool(complete and not beyond(out, ENGINEERING))
    return out


def sweep_cases(methods=None, tolerances=TOLERANCES, step_sizes=None, max_step: float = 1e-3) -> list[tuple[str, SolverOptions]]:
    """(label, options) of every run of the sweep."""
    methods = list(methods or METHODS)
    step_sizes = step_sizes or STEP_SIZES
    cases = []
    for method in methods:
        if method in FIXED_STEP_METHODS:
            for h in step_sizes.get(method, ()):
                cases.append((f"{method} h={h:g}", SolverOptions(method, rtol=1e-8, atol=1e-10, max_step=max_step, first_step=h)))
        else:
            for tol in tolerances:
                cases.append((f"{method} rtol={tol:g}", SolverOptions(method, rtol=tol, atol=tol * 1e-2, max_step=max_step)))
    return cases


def run_sweep(run: Run, ref: Reference, cases, t_end: float, output_step: float, progress=None, stop: Callable[[], bool] | None = None) -> list[dict]:
    """One row per case; :class:`StudyStopped` with the rows finished if the user stops the sweep."""
    rows: list[dict] = []
    for label, options in cases:
        outcome = run_or_stop(partial(simulate, run, replace(options, output_step=output_step), t_end, label=label), label, rows, stop)
        row = outcome.counts()
        row["errors"] = errors(outcome, ref)
        rows.append(row)
        if progress is not None:
            progress(row)
    return rows


def cheapest_accurate(rows: list[dict]) -> dict | None:
    """The run of least CPU time that meets the engineering accuracy."""
    good = [r for r in rows if r["status"] == 0 and r["errors"].get("engineering_accuracy")]
    return min(good, key=lambda r: r["cpu_time"]) if good else None


def _positive(value) -> bool:
    """A measured, finite, positive error (None: not applicable; NaN: not measured)."""
    return value is not None and bool(np.isfinite(value)) and value > 0


def plot(rows: list[dict], ref: dict, t_end: float, path, title: str) -> None:
    """Error against CPU time, one line per method (four error measures); ``ref`` is :meth:`Reference.summary`."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    panels = [
        ("ee", f"end-effector position error (m), pointwise on [0, {ref['comparable_window_s']:.3g}] s", EE_TARGET),
        ("peak_force", f"peak contact force error (relative), max over joints, [0, {t_end:g}] s", PEAK_TARGET),
        ("driving", f"driving force error (relative), pointwise on [0, {ref['comparable_window_s']:.3g}] s", None),
        ("energy", f"energy balance error (J), [0, {t_end:g}] s", None),
    ]
    methods = []
    for row in rows:
        if row["options"]["method"] not in methods:
            methods.append(row["options"]["method"])
    colours = [plt.get_cmap("tab20")(i) for i in range(0, 20, 2)] + [plt.get_cmap("tab20")(i) for i in range(1, 20, 2)]
    markers = "osD^v<>phX*"
    fig, axes = plt.subplots(2, 2, figsize=(14, 10.5))
    for ax, (key, ylabel, target) in zip(axes.flat, panels):
        floor = []
        for i, method in enumerate(methods):
            mine = [r for r in rows if r["options"]["method"] == method]
            ok = [r for r in mine if r["status"] == 0 and _positive(r["errors"].get(key))]
            style = "--" if method in FIXED_STEP_METHODS else "-"
            colour = colours[i % len(colours)]
            if ok:
                # in order of the tolerance (or step size), loosest first: the usual work-precision line
                ok.sort(key=lambda r: -(r["options"]["first_step"] if method in FIXED_STEP_METHODS else r["options"]["rtol"]))
                ax.loglog(
                    [r["cpu_time"] for r in ok], [max(r["errors"][key], 1e-16) for r in ok], style,
                    marker=markers[i % len(markers)], color=colour, label=method, markersize=5,
                )
            for r in mine:
                if r["status"] != 0:
                    floor.append((r["cpu_time"], colour))
        if floor:
            y = ax.get_ylim()[0] if ax.lines else 1e-12
            for x, color in floor:
                ax.plot([x], [y], "x", color=color, markersize=9)
        if not ax.lines:
            ax.text(0.5, 0.5, "no data (no clearance joint in the scene)" if key == "peak_force" else "no data", ha="center", va="center", transform=ax.transAxes)
        elif target is not None:
            ax.axhline(target, color="k", lw=0.8, ls=":")
        ax.set_xlabel("CPU time of the integration (s)")
        ax.set_ylabel(ylabel, fontsize=9)
        ax.grid(True, which="both", alpha=0.3)
    axes[0, 0].legend(fontsize=8, ncol=2)
    note = (
        f"Pointwise errors only while the trajectories are comparable: on [0, {ref['comparable_window_s']:.3g}] s the two reference "
        f"solutions agree to {ref['window_tolerance_m']:g} m; after that impacts separate any two solutions, and runs are compared by "
        f"peak contact forces and the energy balance over [0, {t_end:g}] s. Lines join tolerances (or step sizes), loosest first; "
        "dashed: fixed step; x: failed run; dotted: engineering target (1 um, 1 %)."
    )
    fig.suptitle(title + "\n" + "\n".join(textwrap.wrap(note, 150)), fontsize=9)
    fig.tight_layout(rect=(0, 0, 1, 0.92))
    save_png(fig, path)
