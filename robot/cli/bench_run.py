"""Time each phase of ``clearance run --scene NAME`` over repeated fresh processes; JSON and a table.

examples:
  clearance bench-run                                       # compound_misaligned, 5 repeats, results/bench_run.json
  clearance bench-run --scene revolute --repeats 7 --out /tmp/bench_run.json
  clearance bench-run --compare results/bench_run_before.json   # also a before/after table
  clearance bench-run --kernels numba --out /tmp/numba.json      # numba's just-in-time kernels instead of the library

Per repeat, the command itself in a fresh process (wall time, CPU time, peak
memory) and a worker process that does what the command does and times each
phase in CPU seconds (imports, build, compile, integrate, outputs, write), then
the step loop's parts (right-hand side, Jacobian, probe, solver step, onset and
peak location, ...) and the floor: the right-hand side plus the Jacobian replayed
at the run's states, times the run's counts of calls. With --rounding-band, also
the scene's rounding band (peak forces, impulses and steps under 1-ulp
perturbations: how close "unchanged" can be short of bit identity). Medians over the repeats
(CPU time is robust on a shared machine; wall time is not). Writes OUT (JSON,
atomically) and OUT with the suffix .md (the table), prints the table.
The measurement is robot.analysis.studies.run_phases.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from robot.analysis.studies.run_phases import KERNEL_MODES
from robot.cli.common import EXIT_OK, UsageError, positive_int, writable_file

DEFAULT_OUT = Path("results") / "bench_run.json"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--scene", default="compound_misaligned", help="shipped scene name or path to a .toml file (default: compound_misaligned)")
    parser.add_argument("--repeats", type=positive_int, default=5, help="fresh-process runs of each measurement (default: 5)")
    parser.add_argument("--out", type=Path, default=DEFAULT_OUT, help=f"JSON report (default: {DEFAULT_OUT}); the table beside it (.md)")
    parser.add_argument("--compare", type=Path, default=None, help="an earlier report of this command: add a before/after table")
    parser.add_argument(
        "--kernels",
        choices=KERNEL_MODES,
        default="library",
        help="the kernel library (default, what a run uses) or numba's just-in-time kernels (CLEARANCE_CONTACT_JIT=numba)",
    )
    parser.add_argument(
        "--rounding-band",
        action="store_true",
        help="also measure the scene's rounding band: how far peak forces, impulses and the step count move under 1-ulp "
        "perturbations (up to 7 more runs; robot.analysis.studies.rounding_band); the yardstick for 'physics unchanged'",
    )


def execute(args: argparse.Namespace) -> int:
    from robot.analysis.studies.run_phases import benchmark, comparison_table, table
    from robot.io.atomic import atomic_write_text
    from robot.scene.loader import load_scene

    load_scene(args.scene)  # a bad scene is bad input (exit 2) before any process is started
    out = writable_file(args.out, "--out")
    before = None
    if args.compare is not None:
        try:
            before = json.loads(Path(args.compare).read_text())
        except (OSError, ValueError) as exc:
            raise UsageError(f"--compare={str(args.compare)!r} is not a report of this command ({exc})") from None
    report = benchmark(str(args.scene), args.repeats, progress=lambda line: print(line, file=sys.stderr, flush=True), kernels=args.kernels)
    if args.rounding_band:
        report["rounding_band"] = _rounding_band(str(args.scene))
    report["table"] = table(report)
    if before is not None:
        report["table"] += "\n\nbefore / after (medians):\n\n" + comparison_table(before, report)
    atomic_write_text(out, json.dumps(report, indent=1))
    atomic_write_text(out.with_suffix(".md"), report["table"] + "\n")
    print(report["table"])
    print(f"wrote {out} and {out.with_suffix('.md')}")
    return EXIT_OK


def _rounding_band(scene: str) -> dict:
    from robot.analysis.studies.rounding_band import rounding_band
    from robot.run import build_run, compile_kernels

    run = build_run(scene)
    compile_kernels(run)
    return rounding_band(run, progress=lambda line: print(f"rounding band: {line}", file=sys.stderr, flush=True))
