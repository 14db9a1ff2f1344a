"""Speed against accuracy of every integrator on offer, failure boundaries, RHS speed.

examples:
  clearance work-precision --scene compound_misaligned           # the full study (tens of minutes)
  clearance work-precision --scene compound --quick --skip-stability
  clearance work-precision --scene ideal --methods RK45,LSODA --tolerances 1e-6,1e-8 --realtime-t-end 0

Writes to DIR (default results/work_precision/SCENE):

* ``work_precision.json``: reference and its convergence check, every run (CPU
  time, steps, rejected steps, right-hand-side calls, events, errors), the
  cheapest run at engineering accuracy, ``rhs_us`` (microseconds per
  right-hand side, out of contact and in contact, against the reference
  implementation), ``realtime_factor`` (wall time over simulated time of the
  scene's default solver over ``--realtime-t-end``, and of the ``--candidates``),
  with ``--long-horizon`` their statistics against a tight run over that
  horizon, the stability maps;
* ``work_precision.png``: error against CPU time, one line per method;
* ``stability_stiffness.png``, ``stability_baumgarte.png``,
  ``stability_hidden_contacts.png``: the failure maps.

Ctrl-C or SIGTERM stops the study after the benchmark: the run in progress
stops, and ``work_precision.json`` keeps every run finished so far, marked
``incomplete`` (the step stopped in, the cause, the simulated time the stopped
run reached, when); exit status 1. A stop during the benchmark ends the command
with nothing written (130). A reference run that fails stops the study the same
way.

The logic lives in ``robot/analysis/studies``; ``docs/work-precision.md`` reports.
"""

from __future__ import annotations

import argparse
import json
import math
import platform
import sys
import time
from functools import partial
from pathlib import Path
from typing import Callable

import numpy as np
import scipy

from robot.io.atomic import atomic_write_text
from robot.cli.common import (
    EXIT_INTERRUPTED, EXIT_OK, EXIT_RUN_FAILED, UsageError, number_list, positive_int, positive_number, positive_seconds, writable_folder,
)
from robot.cli.interrupts import Phase, clean_stops
from robot.integration.solvers import FIXED_STEP_METHODS, JACOBIAN_METHODS, METHODS
from robot.run import build_run
from robot.integration.simulation import SolverOptions
from robot.integration.options import STRUCTURED
from robot.scene.loader import RTOL_RANGE, rtol_floor_reason, shipped_scenes, smallest_step
from robot.analysis.studies import speed, stability
from robot.analysis.studies.common import INTERRUPTED, StudyStopped, run_or_stop, simulate
from robot.analysis.studies import work_precision as wp


def _json_default(value):
    if isinstance(value, (np.floating, np.integer)):
        return value.item()
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, np.bool_):
        return bool(value)
    raise TypeError(f"not JSON serialisable: {type(value)}")


def _clean(value):
    """NaN and inf as null (strict JSON)."""
    if isinstance(value, float) and not math.isfinite(value):
        return None
    if isinstance(value, dict):
        return {k: _clean(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_clean(v) for v in value]
    return value


def _label(options: SolverOptions) -> str:
    jacobian = " (finite-difference Jacobian)" if options.jacobian != STRUCTURED and options.method in JACOBIAN_METHODS else ""
    return f"{options.method} rtol {options.rtol:g}{jacobian}"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--scene", default="compound_misaligned", help=f"shipped scene ({', '.join(shipped_scenes())}) or path")
    parser.add_argument("--t-end", type=positive_seconds, default=0.2, help="horizon of the sweep in s (default 0.2)")
    parser.add_argument("--out", type=Path, default=None, help="output folder (default results/work_precision/SCENE)")
    parser.add_argument("--quick", action="store_true", help="a small sweep and small maps (minutes, not tens of minutes)")
    parser.add_argument("--skip-sweep", action="store_true", help="no work-precision sweep")
    parser.add_argument("--skip-stability", action="store_true", help="no stability maps")
    parser.add_argument("--realtime-t-end", type=float, default=2.0, help="horizon of the real-time run (0: skip)")
    parser.add_argument("--realtime-repeats", type=positive_int, default=3, help="repeats of the scene solver's real-time run (median reported)")
    parser.add_argument(
        "--candidates",
        default="LSODA:1e-6,LSODA:1e-5,RK45:1e-7,CVODE_BDF:1e-6,CVODE_BDF:1e-6:finite-difference,CVODE_Adams:1e-5",
        help="other METHOD:RTOL[:JACOBIAN] (atol = rtol/100, max_step 1e-3; JACOBIAN structured or finite-difference) "
        f"to time over the real-time horizon ('' for none); variable-step methods only, RTOL in [{RTOL_RANGE[0]:g}, {RTOL_RANGE[1]:g}]",
    )
    parser.add_argument(
        "--long-horizon", action="store_true",
        help="also compare the scene's solver and the candidates over the real-time horizon against DOP853 rtol 1e-10 "
        "(peak forces, impulses, energy balance, drift: statistics, the trajectories separate)",
    )
    parser.add_argument("--methods", default=None, help=f"comma-separated subset of {', '.join(METHODS)}")
    parser.add_argument(
        "--steps", type=number_list, default=None,
        help="comma-separated step sizes of the fixed-step methods (default: per method; each >= the scene's limits.min_step)",
    )
    parser.add_argument(
        "--tolerances", type=number_list, default=None,
        help=f"comma-separated rtol values of the variable-step methods, each in [{RTOL_RANGE[0]:g}, {RTOL_RANGE[1]:g}] (a scene's rtol range)",
    )
    parser.add_argument(
        "--max-step", type=positive_number, default=1e-3,
        help="max_step of the variable-step methods in the sweep (s; >= the scene's limits.min_step, CVODE >= 1e-12)",
    )
    parser.add_argument("--output-step", type=positive_number, default=1e-4, help="common output grid for pointwise errors (s)")


#: the report's keys each step writes ("a/b": key b of a); a step that starts drops those of an earlier
#: report, so that a stopped step never leaves its finished runs mixed with an earlier invocation's
STEP_KEYS = {
    "sweep": ("t_end", "output_step", "reference", "runs", "cheapest_accurate", "sweep_max_step"),
    "stability: stiffness": ("stability/stiffness",),
    "stability: hidden contacts": ("stability/hidden_contacts",),
    "stability: Baumgarte gains": ("stability/baumgarte",),
    "realtime": ("realtime", "realtime_factor", "rhs_us_in_run", "realtime_candidates"),
    "long horizon": ("long_horizon",),
}


class _Phases:
    """One invocation's state: the run, the report being written, the output folder, the log."""

    def __init__(self, args: argparse.Namespace, run, out: Path, stop: Callable[[], bool] | None = None):
        self.args, self.run, self.out, self.stop = args, run, out, stop
        self.started = time.perf_counter()
        self.json_path = out / "work_precision.json"
        self.step = "right-hand side benchmark"  # what runs now (named in the report of a stopped study)
        # phases can be run separately (--skip-*): what this invocation computes replaces the
        # same keys of an existing report of the scene, the rest is kept
        self.report: dict = json.loads(self.json_path.read_text()) if self.json_path.is_file() else {}

    def say(self, text: str) -> None:
        print(f"[{time.perf_counter() - self.started:7.1f} s] {text}", flush=True)

    def save(self) -> None:
        atomic_write_text(self.json_path, json.dumps(_clean(self.report), indent=1, default=_json_default))

    def begin(self, step: str) -> None:
        """Start ``step``: named in the report if the study stops in it; an earlier report's keys of it dropped."""
        self.step = step
        for path in STEP_KEYS.get(step, ()):
            parent, _, key = path.rpartition("/")
            container = self.report.get(parent) if parent else self.report
            if isinstance(container, dict):
                container.pop(key, None)

    def header(self) -> None:
        solver = self.run.scene.solver
        self.report |= {
            "scene": self.run.scene.name,
            "machine": {
                "python": platform.python_version(),
                "numpy": np.__version__,
                "scipy": scipy.__version__,
                "processor": platform.processor() or platform.machine(),
                "note": "shared 2-core machine: CPU times are process_time of the integration only; medians where repeated",
            },
            "scene_solver": {  # the scene's [solver] table when this report was written
                "method": solver.method, "rtol": solver.rtol, "atol": solver.atol,
                "max_step": solver.max_step, "first_step": solver.first_step, "jacobian": solver.jacobian,
            },
        }  # fmt: skip

    def rhs_benchmark(self) -> None:
        args, report, say = self.args, self.report, self.say
        say("right-hand side benchmark")
        bench = speed.rhs_benchmark(self.run, repeats=7 if not args.quick else 3, number=2000 if not args.quick else 500)
        report["rhs_benchmark"] = bench
        # rhs_us: out of contact (the glue's cost); in contact the contact laws add their own
        quiet = bench.get("no contact", bench["initial"])
        report["rhs_us"] = quiet["fast"]["median_us"]
        report["rhs_us_reference_implementation"] = quiet["reference"]["median_us"]
        if "all joints in contact" in bench:
            report["rhs_us_all_joints_in_contact"] = bench["all joints in contact"]["fast"]["median_us"]
        for key, value in bench.items():
            say(f"  {key}: {value['fast']['median_us']:.1f} us (reference implementation {value['reference']['median_us']:.1f} us)")

    def studies(self, methods: list[str], candidates: list[SolverOptions]) -> None:
        """Every step the options ask for, after the benchmark (each saves the report when done)."""
        args, run = self.args, self.run
        if not args.skip_sweep:
            self.sweep(methods)
        if not args.skip_stability and run.dynamics.contacts:
            self.contact_stability()
        if not args.skip_stability:
            self.baumgarte_stability()
        if args.realtime_t_end > 0:
            self.realtime(candidates)
            if args.long_horizon:
                self.long_horizon(candidates)

    def sweep(self, methods: list[str]) -> None:
        args, report, say = self.args, self.report, self.say
        self.begin("sweep")
        report["t_end"] = args.t_end
        report["output_step"] = args.output_step
        ref = self.sweep_reference()
        tolerances = args.tolerances or (wp.TOLERANCES if not args.quick else (1e-4, 1e-6, 1e-8))
        steps = wp.STEP_SIZES if not args.quick else {k: v[:2] for k, v in wp.STEP_SIZES.items()}
        if args.steps:
            steps = {k: args.steps for k in wp.STEP_SIZES}
        cases = wp.sweep_cases(methods, tolerances, steps, max_step=args.max_step)
        report["sweep_max_step"] = args.max_step

        def progress(row):
            e = row["errors"]
            say(
                f"  {row['label']:28s} {('ok' if row['status'] == 0 else row['cause']):>22s} cpu {row['cpu_time']:7.2f} s "
                f"steps {row['steps']:7d} rhs {row['rhs_calls']:8d} ee {e['ee']:.2e} peak {e['peak_force']:.2e} energy {e['energy']:.2e}"
            )

        try:
            rows = wp.run_sweep(self.run, ref, cases, args.t_end, args.output_step, progress, stop=self.stop)
        except StudyStopped as stopped:
            self.sweep_rows(stopped.finished, finished=False)
            raise
        self.sweep_rows(rows)
        self.save()

    def sweep_reference(self) -> wp.Reference:
        """The sweep's reference and check runs (those that finished are kept if the study stops in them)."""
        args = self.args
        self.say(f"reference solutions over [0, {args.t_end}] s")
        self.step = "sweep (its reference solutions)"
        try:
            ref = wp.reference(self.run, args.t_end, args.output_step, stop=self.stop)
        except StudyStopped as stopped:
            if stopped.finished:
                self.report["reference"] = stopped.finished
            raise
        self.report["reference"] = ref.summary()
        self.step = "sweep"
        self.say(f"  comparable window [0, {ref.window:.4g}] s; check vs reference: {ref.agreement}")
        return ref

    def sweep_rows(self, rows: list[dict], finished: bool = True) -> None:
        """The runs of the sweep (all, or those done before a stop), the cheapest accurate one, the figure."""
        report = self.report
        report["runs"] = rows
        best = wp.cheapest_accurate(rows)
        report["cheapest_accurate"] = best and {k: best[k] for k in ("label", "options", "cpu_time", "steps", "rhs_calls", "errors")}
        if rows:
            wp.plot(rows, report["reference"], self.args.t_end, self.out / "work_precision.png", f"Work-precision, scene {self.run.scene.name}")
        self.say(f"cheapest at engineering accuracy{'' if finished else ' (of the runs done)'}: {best and best['label']}")

    def contact_stability(self) -> None:
        args, run, say = self.args, self.run, self.say
        stability_report = self.report.setdefault("stability", {})
        self.begin("stability: stiffness")
        say("stability: step size against contact stiffness")
        options = dict(scales=(0.1, 1.0, 10.0), steps=(5e-5, 1e-5, 2e-6), t_end=0.015) if args.quick else {}
        stiff = self.keep_partial(stability_report, "stiffness", partial(stability.stiffness_map, args.scene, progress=say, stop=self.stop, **options))
        stability.plot_stiffness(stiff, self.out / "stability_stiffness.png")
        self.begin("stability: hidden contacts")
        say("stability: hidden contact onsets")
        hidden_t = 0.1 if not args.quick else 0.03
        # peaks and onsets of a tight run over the same horizon (DOP853, rtol 1e-10)
        tight = run_or_stop(partial(simulate, run, wp.CHECK, hidden_t, label="hidden-contact reference"), "hidden-contact reference", stop=self.stop)
        hidden_map = partial(
            stability.hidden_contact_map,
            run,
            methods=("RK23", "RK45", "DOP853", "LSODA", "BDF") if not args.quick else ("RK45", "LSODA"),
            tolerances=(1e-2, 1e-3, 1e-4, 1e-5, 1e-6) if not args.quick else (1e-2, 1e-4),
            t_end=hidden_t,
            reference_peaks=tight.peaks,
            reference_onsets=tight.n_events,
            progress=say,
            stop=self.stop,
        )
        hidden = self.keep_partial(stability_report, "hidden_contacts", hidden_map)
        stability.plot_hidden(hidden, self.out / "stability_hidden_contacts.png")
        self.save()

    def keep_partial(self, where: dict, key: str, study: Callable[[], dict]) -> dict:
        """``where[key] = study()``; a stopped study's partial map is stored there too before the stop goes on."""
        try:
            where[key] = study()
        except StudyStopped as stopped:
            where[key] = stopped.finished
            raise
        return where[key]

    def baumgarte_stability(self) -> None:
        self.begin("stability: Baumgarte gains")
        self.say("stability: Baumgarte gains (ideal mechanism)")
        if self.args.quick:
            options = dict(alphas=(0.0, 5.0, 100.0), betas=(0.0, 5.0, 100.0), cases=(("RK45", 1e-6, None), ("RK4", None, 2e-3)), t_end=0.3)
        else:
            grid = (0.0, 1.0, 5.0, 20.0, 100.0, 1000.0)
            options = dict(alphas=grid, betas=grid, t_end=0.5)
        study = partial(stability.baumgarte_map, progress=self.say, stop=self.stop, **options)
        gains = self.keep_partial(self.report.setdefault("stability", {}), "baumgarte", study)
        stability.plot_baumgarte(gains, self.out / "stability_baumgarte.png")
        self.save()

    def realtime(self, candidates: list[SolverOptions]) -> None:
        args, run, say = self.args, self.run, self.say
        self.begin("realtime")
        say(f"real-time run: the scene's solver over [0, {args.realtime_t_end}] s")
        # first a short run that compiles what the run needs (numba kernels compiled on first use
        # in a process, the contact laws' Jacobian kernels when not yet in numba's disk cache)
        warm_up = self.timed(run.scene.solver, min(0.05, args.realtime_t_end), "warm-up", None)
        say(f"  warm-up over {warm_up['t_reached']:.3g} s: {warm_up['wall_time']:.1f} s wall")
        # repeated: the machine is shared and noisy; the median run is reported, every factor kept
        repeats: list[dict] = []
        try:
            for i in range(max(1, args.realtime_repeats)):
                repeats.append(self.timed(run.scene.solver, args.realtime_t_end, f"real-time run {i + 1}", repeats))
        finally:  # a stop keeps the repeats done (their median)
            if repeats:
                self.realtime_median(repeats)
        self.realtime_candidates(candidates)
        self.save()

    def realtime_candidates(self, candidates: list[SolverOptions]) -> None:
        timed: list[dict] = []
        self.report["realtime_candidates"] = timed  # filled as the candidates run
        for options in candidates:
            other = self.timed(options, self.args.realtime_t_end, _label(options), timed)
            timed.append(other)
            self.say(
                f"  {_label(options)}: factor {other['realtime_factor']:.2f} ({other['rhs_calls']} rhs, {other['status'] == 0 and 'ok' or other['cause']})"
            )

    def timed(self, options: SolverOptions, t_end: float, label: str, finished) -> dict:
        """:func:`speed.realtime` of ``options`` over ``t_end``, stoppable (``finished``: what a stop keeps)."""
        return run_or_stop(partial(speed.realtime, self.run, options, t_end), label, finished, self.stop)

    def realtime_median(self, repeats: list[dict]) -> None:
        real = sorted(repeats, key=lambda r: r["realtime_factor"])[len(repeats) // 2]
        real["realtime_factors_of_repeats"] = [r["realtime_factor"] for r in repeats]
        self.report["realtime"] = real
        self.report["realtime_factor"] = real["realtime_factor"]
        self.report["rhs_us_in_run"] = real["rhs_us_in_run"]
        self.say(
            f"  wall {real['wall_time']:.1f} s for {real['t_reached']:.3g} s simulated: factor {real['realtime_factor']:.2f} "
            f"(median of {real['realtime_factors_of_repeats']}), {real['rhs_us_in_run']:.1f} us per rhs in the run"
        )

    def long_horizon(self, candidates: list[SolverOptions]) -> None:
        t_end, run = self.args.realtime_t_end, self.run
        self.begin("long horizon")
        self.say(f"long horizon: statistics over [0, {t_end}] s against DOP853 rtol 1e-10")
        label = "DOP853 rtol 1e-10"
        tight = run_or_stop(partial(simulate, run, SolverOptions("DOP853", rtol=1e-10, atol=1e-12, max_step=1e-3), t_end, label=label), label, stop=self.stop)
        rows: dict = {}
        self.report["long_horizon"] = {"t_end": t_end, "tight": tight.counts(), "runs": rows}  # filled as the runs end
        for options in [run.scene.solver] + candidates:
            outcome = run_or_stop(partial(simulate, run, options, t_end, label=_label(options)), _label(options), rows, self.stop)
            row = outcome.counts()
            row["peak_force_relative_to_tight"] = {j: outcome.peaks[j] / tight.peaks[j] - 1.0 for j in tight.peaks}
            row["impulse_relative_to_tight"] = {j: outcome.impulses[j] / tight.impulses[j] - 1.0 for j in tight.impulses}
            rows[outcome.label] = row
            self.say(f"  {outcome.label}: energy {outcome.energy_error:.2e} J, drift {outcome.max_residual:.2e}, impulses {row['impulse_relative_to_tight']}")
        self.save()

    def finish(self) -> int:
        """Save the whole report (no longer ``incomplete``)."""
        self.report.pop("incomplete", None)
        self.save()
        self.say(f"wrote {self.json_path}")
        return EXIT_OK

    def stopped(self, stopped: StudyStopped, signals: list[str]) -> int:
        """Save what finished, marked ``incomplete`` (step, cause, time); say where; exit status 1."""
        # why the study stopped (a study's reason, not a run's failure cause: docs/dynamics.md lists those)
        reason = stopped.reason
        if reason == INTERRUPTED:
            reason = f"interrupted by the user ({signals[0]})" if signals else "interrupted by the user"
        self.report["incomplete"] = {
            "step": self.step,
            "cause": reason,
            "message": str(stopped),
            "stopped_run": stopped.stopped_run,  # its counts (label, t_reached, ...), None if stopped between runs
            "elapsed_s": time.perf_counter() - self.started,
            "at": time.strftime("%Y-%m-%dT%H:%M:%S%z"),
        }
        self.save()
        print(
            f"work-precision stopped in step '{self.step}' after {self.report['incomplete']['elapsed_s']:.1f} s: {stopped}; "
            f"the runs finished so far are saved in {self.json_path} (marked incomplete)",
            file=sys.stderr,
        )
        return EXIT_RUN_FAILED


def _checked_methods(args: argparse.Namespace) -> list[str]:
    if not (args.realtime_t_end >= 0 and math.isfinite(args.realtime_t_end)):
        raise UsageError(f"--realtime-t-end={args.realtime_t_end!r} must be a finite number of seconds >= 0")
    methods = args.methods.split(",") if args.methods else list(METHODS)
    unknown = [m for m in methods if m not in METHODS]
    if unknown:
        raise UsageError(f"--methods: {', '.join(map(repr, unknown))} not on offer; choose from {', '.join(METHODS)}")
    for tolerance in args.tolerances or ():
        _check_rtol(tolerance, f"--tolerances={','.join(f'{t:g}' for t in args.tolerances)}")
    return methods


def _check_rtol(rtol: float, option: str) -> None:
    """``UsageError`` if ``rtol`` is outside a scene's ``[solver] rtol`` range (:data:`robot.scene.loader.RTOL_RANGE`)."""
    low, high = RTOL_RANGE
    if not low <= rtol <= high:
        raise UsageError(f"{option}: rtol {rtol:g} is out of range [{low:g}, {high:g}] (the range of a scene's [solver] rtol){rtol_floor_reason(rtol)}")


def _check_steps(args: argparse.Namespace, methods: list[str], limits) -> None:
    """``--max-step`` not below the smallest step the scene's variable-step runs can take (checked before any run;
    ``min_step`` is no limit of the fixed-step methods' ``--steps``)."""
    if args.skip_sweep:
        return
    for method in methods:
        if method in FIXED_STEP_METHODS:
            continue
        floor = smallest_step(method, limits)
        if args.max_step < floor:
            whose = f"the smallest step {method} takes" if floor > limits.min_step else "the scene's limits.min_step"
            raise UsageError(
                f"--max-step={args.max_step:g} is out of range [{floor:g}, inf) for {method}: it must be >= {whose} "
                f"({floor:g} s); a run with a smaller largest step can never proceed"
            )


def execute(args: argparse.Namespace) -> int:
    methods = _checked_methods(args)
    candidates = _candidates(args.candidates)  # checked before any run
    with clean_stops() as stops:
        run = build_run(args.scene)  # a stop before the benchmark has ended: exit 130, nothing written
        _check_steps(args, methods, run.scene.limits)
        if not args.skip_stability and run.dynamics.contacts:
            stability.scaled_stiffness(run.scene)  # a law the stiffness map cannot scale: exit 2 now, not after the sweep
        out = writable_folder(args.out or Path("results") / "work_precision" / run.scene.file_stem)
        phases = _Phases(args, run, out, stop=lambda: stops.requested)
        stops.saving = f"saving the finished runs to {phases.json_path}"
        phases.header()
        phases.rhs_benchmark()
        if stops.requested:  # stopped in the benchmark's sample run: its numbers are not kept
            print(f"{stops.received[0]}: stopped during the right-hand side benchmark; nothing written", file=sys.stderr)
            return EXIT_INTERRUPTED
        stops.phase = Phase.SAVING
        phases.save()
        stops.phase = Phase.RUNNING
        try:
            phases.studies(methods, candidates)
        except StudyStopped as stopped:
            stops.phase = Phase.SAVING
            return phases.stopped(stopped, stops.received)
        stops.phase = Phase.SAVING
        return phases.finish()


def _candidates(text: str) -> list[SolverOptions]:
    """``--candidates METHOD:RTOL[:JACOBIAN],...`` as solver options (checked before any run)."""
    candidates = []
    variable_step = [m for m in METHODS if m not in FIXED_STEP_METHODS]
    for spec in filter(None, text.split(",")):
        parts = spec.split(":")
        if len(parts) not in (2, 3):
            raise UsageError(f"--candidates {spec!r}: expected METHOD:RTOL[:JACOBIAN] (e.g. RK45:1e-7 or CVODE_BDF:1e-6:finite-difference)")
        method, rtol, *jacobian = parts
        if method not in METHODS:
            raise UsageError(f"--candidates {spec!r}: method {method!r} is not on offer; choose from {', '.join(METHODS)}")
        if method in FIXED_STEP_METHODS:
            raise UsageError(
                f"--candidates {spec!r}: {method} is a fixed-step method: it takes a step size (--steps in the sweep), not a tolerance; "
                f"candidates are variable-step methods: {', '.join(variable_step)}"
            )
        try:
            tolerance = number_list(rtol)[0]
            options = SolverOptions(method, rtol=tolerance, atol=tolerance * 1e-2, max_step=1e-3, jacobian=jacobian[0] if jacobian else STRUCTURED)
        except (ValueError, TypeError, argparse.ArgumentTypeError) as exc:
            raise UsageError(f"--candidates {spec!r}: expected METHOD:RTOL[:JACOBIAN] ({exc})") from None
        _check_rtol(tolerance, f"--candidates {spec!r}")
        candidates.append(options)
    return candidates
