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

The logic lives in ``robot/analysis/studies``; ``docs/work-precision.md`` reports.
"""

from __future__ import annotations

import argparse
import json
import math
import platform
import time
from pathlib import Path

import numpy as np
import scipy

from robot.io.atomic import atomic_write_text
from robot.cli.common import EXIT_OK, UsageError, number_list, positive_int, positive_number, positive_seconds, writable_folder
from robot.integration.solvers import JACOBIAN_METHODS, METHODS
from robot.run import build_run
from robot.integration.simulation import SolverOptions
from robot.integration.options import STRUCTURED
from robot.scene.loader import shipped_scenes
from robot.analysis.studies import speed, stability
from robot.analysis.studies.common import simulate
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
        "to time over the real-time horizon ('' for none)",
    )
    parser.add_argument(
        "--long-horizon", action="store_true",
        help="also compare the scene's solver and the candidates over the real-time horizon against DOP853 rtol 1e-10 "
        "(peak forces, impulses, energy balance, drift: statistics, the trajectories separate)",
    )
    parser.add_argument("--methods", default=None, help=f"comma-separated subset of {', '.join(METHODS)}")
    parser.add_argument("--steps", type=number_list, default=None, help="comma-separated step sizes of the fixed-step methods (default: per method)")
    parser.add_argument("--tolerances", type=number_list, default=None, help="comma-separated rtol values of the variable-step methods")
    parser.add_argument("--max-step", type=positive_number, default=1e-3, help="max_step of the variable-step methods in the sweep (s)")
    parser.add_argument("--output-step", type=positive_number, default=1e-4, help="common output grid for pointwise errors (s)")


class _Phases:
    """One invocation's state: the run, the report being written, the output folder, the log."""

    def __init__(self, args: argparse.Namespace, run, out: Path):
        self.args, self.run, self.out = args, run, out
        self.started = time.perf_counter()
        self.json_path = out / "work_precision.json"
        # phases can be run separately (--skip-*): what this invocation computes replaces the
        # same keys of an existing report of the scene, the rest is kept
        self.report: dict = json.loads(self.json_path.read_text()) if self.json_path.is_file() else {}

    def say(self, text: str) -> None:
        print(f"[{time.perf_counter() - self.started:7.1f} s] {text}", flush=True)

    def save(self) -> None:
        atomic_write_text(self.json_path, json.dumps(_clean(self.report), indent=1, default=_json_default))

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
        self.save()

    def sweep(self, methods: list[str]) -> None:
        args, report, say = self.args, self.report, self.say
        report["t_end"] = args.t_end
        report["output_step"] = args.output_step
        say(f"reference solutions over [0, {args.t_end}] s")
        ref = wp.reference(self.run, args.t_end, args.output_step)
        report["reference"] = ref.summary()
        say(f"  comparable window [0, {ref.window:.4g}] s; check vs reference: {ref.agreement}")
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

        rows = wp.run_sweep(self.run, ref, cases, args.t_end, args.output_step, progress)
        report["runs"] = rows
        best = wp.cheapest_accurate(rows)
        report["cheapest_accurate"] = best and {k: best[k] for k in ("label", "options", "cpu_time", "steps", "rhs_calls", "errors")}
        wp.plot(rows, report["reference"], args.t_end, self.out / "work_precision.png", f"Work-precision, scene {self.run.scene.name}")
        say(f"cheapest at engineering accuracy: {best and best['label']}")
        self.save()

    def contact_stability(self) -> None:
        args, run, say = self.args, self.run, self.say
        say("stability: step size against contact stiffness")
        if args.quick:
            stiff = stability.stiffness_map(args.scene, scales=(0.1, 1.0, 10.0), steps=(5e-5, 1e-5, 2e-6), t_end=0.015, progress=say)
        else:
            stiff = stability.stiffness_map(args.scene, progress=say)
        stability.plot_stiffness(stiff, self.out / "stability_stiffness.png")
        say("stability: hidden contact onsets")
        hidden_t = 0.1 if not args.quick else 0.03
        # peaks and onsets of a tight run over the same horizon (DOP853, rtol 1e-10)
        tight = simulate(run, wp.CHECK, hidden_t, label="hidden-contact reference")
        hidden = stability.hidden_contact_map(
            run,
            methods=("RK23", "RK45", "DOP853", "LSODA", "BDF") if not args.quick else ("RK45", "LSODA"),
            tolerances=(1e-2, 1e-3, 1e-4, 1e-5, 1e-6) if not args.quick else (1e-2, 1e-4),
            t_end=hidden_t,
            reference_peaks=tight.peaks,
            reference_onsets=tight.n_events,
            progress=say,
        )
        stability.plot_hidden(hidden, self.out / "stability_hidden_contacts.png")
        self.report.setdefault("stability", {})["stiffness"] = stiff
        self.report["stability"]["hidden_contacts"] = hidden
        self.save()

    def baumgarte_stability(self) -> None:
        self.say("stability: Baumgarte gains (ideal mechanism)")
        if self.args.quick:
            gains = stability.baumgarte_map(
                alphas=(0.0, 5.0, 100.0), betas=(0.0, 5.0, 100.0), cases=(("RK45", 1e-6, None), ("RK4", None, 2e-3)), t_end=0.3, progress=self.say
            )
        else:
            grid = (0.0, 1.0, 5.0, 20.0, 100.0, 1000.0)
            gains = stability.baumgarte_map(alphas=grid, betas=grid, t_end=0.5, progress=self.say)
        stability.plot_baumgarte(gains, self.out / "stability_baumgarte.png")
        self.report.setdefault("stability", {})["baumgarte"] = gains
        self.save()

    def realtime(self, candidates: list[SolverOptions]) -> None:
        args, run, report, say = self.args, self.run, self.report, self.say
        say(f"real-time run: the scene's solver over [0, {args.realtime_t_end}] s")
        # first a short run that compiles what the run needs (numba kernels compiled on first use
        # in a process, the contact laws' Jacobian kernels when not yet in numba's disk cache)
        warm_up = speed.realtime(run, run.scene.solver, min(0.05, args.realtime_t_end))
        say(f"  warm-up over {warm_up['t_reached']:.3g} s: {warm_up['wall_time']:.1f} s wall")
        # repeated: the machine is shared and noisy; the median run is reported, every factor kept
        repeats = [speed.realtime(run, run.scene.solver, args.realtime_t_end) for _ in range(max(1, args.realtime_repeats))]
        real = sorted(repeats, key=lambda r: r["realtime_factor"])[len(repeats) // 2]
        real["realtime_factors_of_repeats"] = [r["realtime_factor"] for r in repeats]
        report["realtime"] = real
        report["realtime_factor"] = real["realtime_factor"]
        report["rhs_us_in_run"] = real["rhs_us_in_run"]
        say(
            f"  wall {real['wall_time']:.1f} s for {real['t_reached']:.3g} s simulated: factor {real['realtime_factor']:.2f} "
            f"(median of {real['realtime_factors_of_repeats']}), {real['rhs_us_in_run']:.1f} us per rhs in the run"
        )
        timed = []
        for options in candidates:
            other = speed.realtime(run, options, args.realtime_t_end)
            timed.append(other)
            say(f"  {_label(options)}: factor {other['realtime_factor']:.2f} ({other['rhs_calls']} rhs, {other['status'] == 0 and 'ok' or other['cause']})")
        report["realtime_candidates"] = timed
        self.save()

    def long_horizon(self, candidates: list[SolverOptions]) -> None:
        t_end, run = self.args.realtime_t_end, self.run
        self.say(f"long horizon: statistics over [0, {t_end}] s against DOP853 rtol 1e-10")
        tight = simulate(run, SolverOptions("DOP853", rtol=1e-10, atol=1e-12, max_step=1e-3), t_end, label="DOP853 rtol 1e-10")
        rows = {}
        for options in [run.scene.solver] + candidates:
            outcome = simulate(run, options, t_end, label=_label(options))
            row = outcome.counts()
            row["peak_force_relative_to_tight"] = {j: outcome.peaks[j] / tight.peaks[j] - 1.0 for j in tight.peaks}
            row["impulse_relative_to_tight"] = {j: outcome.impulses[j] / tight.impulses[j] - 1.0 for j in tight.impulses}
            rows[outcome.label] = row
            self.say(f"  {outcome.label}: energy {outcome.energy_error:.2e} J, drift {outcome.max_residual:.2e}, impulses {row['impulse_relative_to_tight']}")
        self.report["long_horizon"] = {"t_end": t_end, "tight": tight.counts(), "runs": rows}
        self.save()


def _checked_methods(args: argparse.Namespace) -> list[str]:
    if not (args.realtime_t_end >= 0 and math.isfinite(args.realtime_t_end)):
        raise UsageError(f"--realtime-t-end={args.realtime_t_end!r} must be a finite number of seconds >= 0")
    methods = args.methods.split(",") if args.methods else list(METHODS)
    unknown = [m for m in methods if m not in METHODS]
    if unknown:
        raise UsageError(f"--methods: {', '.join(map(repr, unknown))} not on offer; choose from {', '.join(METHODS)}")
    return methods


def execute(args: argparse.Namespace) -> int:
    methods = _checked_methods(args)
    candidates = _candidates(args.candidates)  # checked before any run
    run = build_run(args.scene)
    phases = _Phases(args, run, writable_folder(args.out or Path("results") / "work_precision" / run.scene.file_stem))
    phases.header()
    phases.rhs_benchmark()
    if not args.skip_sweep:
        phases.sweep(methods)
    if not args.skip_stability and run.dynamics.contacts:
        phases.contact_stability()
    if not args.skip_stability:
        phases.baumgarte_stability()
    if args.realtime_t_end > 0:
        phases.realtime(candidates)
        if args.long_horizon:
            phases.long_horizon(candidates)
    phases.save()
    phases.say(f"wrote {phases.json_path}")
    return EXIT_OK


def _candidates(text: str) -> list[SolverOptions]:
    """``--candidates METHOD:RTOL[:JACOBIAN],...`` as solver options (checked before any run)."""
    candidates = []
    for spec in filter(None, text.split(",")):
        method, rtol, *jacobian = spec.split(":")
        if method not in METHODS:
            raise UsageError(f"--candidates {spec!r}: method {method!r} is not on offer; choose from {', '.join(METHODS)}")
        try:
            tolerance = number_list(rtol)[0]
            options = SolverOptions(method, rtol=tolerance, atol=tolerance * 1e-2, max_step=1e-3, jacobian=jacobian[0] if jacobian else STRUCTURED)
        except (ValueError, TypeError, argparse.ArgumentTypeError) as exc:
            raise UsageError(f"--candidates {spec!r}: expected METHOD:RTOL[:JACOBIAN] ({exc})") from None
        candidates.append(options)
    return candidates
