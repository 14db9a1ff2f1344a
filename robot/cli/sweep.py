"""Run a parameter sweep of a scene on dask and store it in zarr (docs/sweep.md).

examples:
  clearance sweep robot/sweep/examples/ups_rps_r1_clearance.toml --workers 2
  clearance sweep SWEEP.toml --scheduler tcp://127.0.0.1:8786 --out out/my_sweep
  clearance sweep SWEEP.toml --retry-failed      # resume: finished runs are kept

exit codes: 0 every run reached its end; 1 some runs failed (each recorded with
its cause, the sweep went on); 2 bad input, reported before any run starts.
"""

from __future__ import annotations

import argparse

HELP = "run a parameter sweep on dask, stored as an xarray dataset in zarr"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    from robot.sweep.cli import add_arguments as sweep_arguments

    sweep_arguments(parser)


def execute(args: argparse.Namespace) -> int:
    from robot.sweep.cli import run

    return run(args)
