"""``clearance sweep`` / ``python scripts/sweep.py``: run a sweep file on dask.

Exit codes: 0 every run reached its end; 1 some runs failed (each recorded in
the store with its cause; the sweep went on); 2 bad input (the sweep file, a
key path or value the scene refuses, an unusable store), reported before any
run starts.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

EXIT_OK, EXIT_RUNS_FAILED, EXIT_BAD_INPUT = 0, 1, 2


def add_arguments(parser: argparse.ArgumentParser) -> argparse.ArgumentParser:
    parser.add_argument("sweep_file", type=Path, help="the sweep file (TOML; docs/sweep.md)")
    parser.add_argument("--scheduler", metavar="ADDRESS", help="a running dask scheduler (tcp://host:8786); default: a local cluster")
    parser.add_argument("--workers", type=int, metavar="N", help="local cluster: worker processes (default: the CPU count)")
    parser.add_argument("--out", type=Path, metavar="DIR", help="output folder (default: out/sweeps/NAME); the store is DIR/sweep.zarr")
    parser.add_argument("--overwrite", action="store_true", help="replace a store written by a sweep of another layout")
    parser.add_argument("--retry-failed", action="store_true", help="run the failed runs of a resumed sweep again")
    parser.add_argument("--no-figures", action="store_true", help="do not draw the PNG figures and the HTML report")
    parser.add_argument("--progress", action=argparse.BooleanOptionalAction, default=None, help="progress bar (default: on a terminal)")
    return parser


def plan(args: argparse.Namespace):
    """The checked sweep file and the output folder of the options (bad input raises :class:`SweepError`)."""
    from robot.sweep.errors import SweepError
    from robot.sweep.spec import load_sweep

    if args.workers is not None and args.workers < 1:
        raise SweepError(f"--workers={args.workers} must be >= 1", key="workers", value=args.workers)
    spec = load_sweep(args.sweep_file)
    return spec, args.out if args.out is not None else Path("out") / "sweeps" / spec.name


def sweep(args: argparse.Namespace, spec, out: Path, stop=None):
    """Run the sweep of ``spec`` into ``out`` as the options say (``stop``: :func:`robot.sweep.engine.run_sweep`)."""
    from robot.sweep.engine import run_sweep

    return run_sweep(
        spec, out, scheduler=args.scheduler, workers=args.workers, progress=args.progress, overwrite=args.overwrite, retry_failed=args.retry_failed, stop=stop
    )


def report(args: argparse.Namespace, spec, outcome, out: Path) -> int:
    """Print the outcome, draw the figures (unless ``--no-figures``); the exit code."""
    print(outcome)
    if not args.no_figures:
        from robot.sweep.report import draw_all

        for path in draw_all(spec, outcome.store, out):
            print(f"wrote {path}")
    return EXIT_RUNS_FAILED if outcome.exit_code else EXIT_OK


def run(args: argparse.Namespace) -> int:
    from robot.errors import RobotError

    try:
        spec, out = plan(args)
        outcome = sweep(args, spec, out)
    except RobotError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    return report(args, spec, outcome, out)


def main(argv: list[str] | None = None) -> int:
    """The command (``clearance sweep``): returns the exit code."""
    parser = add_arguments(argparse.ArgumentParser(prog="sweep", description=__doc__.splitlines()[0]))
    return run(parser.parse_args(argv))
