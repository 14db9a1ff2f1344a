"""``clearance sweep`` / ``python scripts/sweep.py``: run a sweep file on dask.

Exit codes: 0 every run reached its end; 1 some runs failed (each recorded in
the store with its cause; the sweep went on); 2 bad input (the sweep file, a
key path or value the scene refuses, an analysis parameter it refuses, an
unusable store: one of another sweep, or a damaged one whose array or value
cannot be read, the message naming it), reported before any run starts (a
value found damaged when the figures are drawn: after them, drawn as missing).
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
    parser.add_argument(
        "--overwrite",
        action="store_true",
        help="replace a store of another sweep (other axes, values, outputs, scene, t_end or overrides) or a damaged one; it is deleted only once the new sweep's probe run succeeded",
    )
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
        from robot.sweep.report import draw_report
        from robot.sweep.store import damaged

        written, damage = draw_report(spec, outcome.store, out)
        for path in written:
            print(f"wrote {path}")
        if damage:
            print(f"error: {damaged(outcome.store, 'these values cannot be read (drawn as missing): ' + '; '.join(damage))}", file=sys.stderr)
            return EXIT_BAD_INPUT
    return EXIT_RUNS_FAILED if outcome.exit_code else EXIT_OK


def run(args: argparse.Namespace) -> int:
    from robot.errors import RobotError

    try:
        spec, out = plan(args)
        outcome = sweep(args, spec, out)
        return report(args, spec, outcome, out)
    except RobotError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT


def main(argv: list[str] | None = None) -> int:
    """The command (``clearance sweep``): returns the exit code."""
    parser = add_arguments(argparse.ArgumentParser(prog="sweep", description=__doc__.splitlines()[0]))
    return run(parser.parse_args(argv))
