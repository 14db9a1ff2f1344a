"""Run a parameter sweep of a scene on dask and store it in zarr (docs/sweep.md).

examples:
  clearance sweep robot/sweep/examples/ups_rps_r1_clearance.toml --workers 2
  clearance sweep SWEEP.toml --scheduler tcp://127.0.0.1:8786 --out out/my_sweep
  clearance sweep SWEEP.toml --retry-failed      # resume: finished runs are kept

The output folder is checked writable and the scheduler reachable before any run.
Ctrl-C or SIGTERM stops the sweep: the runs finished are kept in the store (the
runs in flight are dropped) and the same command resumes it.

exit codes: 0 every run reached its end; 1 some runs failed (each recorded with
its cause, the sweep went on), or the sweep was interrupted with runs finished
(kept in the store; the message says where); 2 bad input (a sweep file, an
analysis parameter, a store of another sweep or a damaged one: --overwrite
replaces it), reported before any run starts; 130 interrupted before any run
finished.
"""

from __future__ import annotations

import argparse
import sys

from robot.cli.common import EXIT_INTERRUPTED, EXIT_RUN_FAILED, writable_folder
from robot.cli.interrupts import Phase, clean_stops

HELP = "run a parameter sweep on dask, stored as an xarray dataset in zarr"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    from robot.sweep.cli import add_arguments as sweep_arguments

    sweep_arguments(parser)


def execute(args: argparse.Namespace) -> int:
    from robot.sweep.cli import plan, report, sweep

    with clean_stops() as stops:
        spec, out = plan(args)  # bad input (exit 2) and a stop here (130) come before any run
        writable_folder(out)
        stops.saving = f"keeping the finished runs in {out / 'sweep.zarr'}"
        stops.phase = Phase.RUNNING
        outcome = sweep(args, spec, out, stop=lambda: stops.requested)
        if outcome.interrupted:
            return interrupted_exit(outcome, stops.received)
        stops.phase = Phase.SAVING  # every run is done: the figures are drawn whatever arrives
        stops.saving = "drawing the figures and the report"
        return report(args, spec, outcome, out)


def interrupted_exit(outcome, signals: list[str]) -> int:
    """Say what an interrupted sweep kept and how to resume it; exit 1 if runs are kept, else 130."""
    cause = signals[0] if signals else "interrupted"
    if not outcome.finished:
        print(f"{cause}: the sweep stopped before any run finished; nothing to keep", file=sys.stderr)
        return EXIT_INTERRUPTED
    failed = f", {outcome.failed} of them failed" if outcome.failed else ""
    print(
        f"{cause}: the sweep stopped with {outcome.finished} of {outcome.total} runs finished{failed}; they are kept in "
        f"{outcome.store} (the runs in flight were dropped). Run the same command again to resume: the finished runs are kept.",
        file=sys.stderr,
    )
    return EXIT_RUN_FAILED
