"""Reproduce the seed paper's study: ideal vs compound clearance, aligned vs misaligned.

Writes OUT/{ideal,compound,compound_misaligned}.npz, figure7/8/9 PNGs,
figure 10 (Newton-Euler against Lagrange, end-effector X and Y, over
--figure10-t-end: the Newton-Euler engine costs ~1 min of CPU per 0.5 s),
summary.json, claims.md and the animation of the misaligned case (HTML). summary.json's
cpu_time is the integration's; compiling the kernels on first use is
compile_cpu_time.

examples:
  clearance paper                                  # two periods (2 s) into results/paper
  clearance paper --t-end 0.2 --out /tmp/paper --no-animation
  clearance paper --workers 1                      # one process (less memory)
  clearance paper --figure10-t-end 2               # figure 10 over the whole run (~4 min more)
  clearance paper --figure10-t-end 0               # no figure 10

Ctrl-C or SIGTERM stops every scene's integration; the partial results are
saved and the figures drawn from them (exit status 1).
"""

from __future__ import annotations

import argparse
import multiprocessing
from pathlib import Path

from robot.cli.common import EXIT_OK, EXIT_RUN_FAILED, positive_int, positive_seconds, writable_folder
from robot.cli.interrupts import Phase, clean_stops, install_in_worker


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--out", type=Path, default=Path("results/paper"), help="output folder (default: results/paper)")
    parser.add_argument("--t-end", type=positive_seconds, default=None, help="simulated time in s (default: the scenes', two periods)")
    parser.add_argument("--workers", type=positive_int, default=2, help="parallel processes, >= 1 (default 2)")
    parser.add_argument("--no-animation", action="store_true", help="skip the HTML animation")
    parser.add_argument(
        "--figure10-t-end", type=_non_negative_seconds, default=None,
        help="horizon of figure 10, Newton-Euler against Lagrange, in s (default 0.25, capped at --t-end; 0: no figure 10)",
    )


def _worker_ids() -> list[int]:
    return [child.pid for child in multiprocessing.active_children() if child.pid is not None]


def _non_negative_seconds(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        value = float("nan")
    if not (0.0 <= value < float("inf")):
        raise argparse.ArgumentTypeError(f"{text!r} must be a finite number of seconds >= 0")
    return value


def _figure10_horizon(requested: float | None, t_end: float | None) -> float:
    """Figure 10's horizon: the option (default FIGURE10_T_END), never past the study's --t-end."""
    from robot.analysis.paper import FIGURE10_T_END

    horizon = FIGURE10_T_END if requested is None else requested
    return min(horizon, t_end) if t_end is not None else horizon


def execute(args: argparse.Namespace) -> int:
    from robot.analysis.paper import figure10_series, run_study, write_outputs

    out = writable_folder(args.out)
    with clean_stops(f"saving the partial results to {out}", forward=_worker_ids) as stops:
        stops.phase = Phase.RUNNING
        results = run_study(out, args.t_end, args.workers, worker_setup=install_in_worker)
        figure10 = None
        horizon = _figure10_horizon(args.figure10_t_end, args.t_end)
        if horizon > 0.0 and not stops.requested:
            figure10 = figure10_series(horizon)
            print(f"figure 10: Lagrange {figure10['lagrange_cpu_s']:.1f} s cpu, Newton-Euler {figure10['newton_euler_cpu_s']:.1f} s cpu over {horizon:g} s")
        stops.phase = Phase.SAVING
        for path in write_outputs(results, out, figure10):
            print(f"wrote {path}")
        if not args.no_animation and not stops.requested:
            from robot.viz.animation import export_html

            # clearance motion is sub-millimetre: magnify it 150x and play at a tenth of real time
            summary = export_html(out / "compound_misaligned.npz", out / "compound_misaligned.html", exaggerate=150.0, speed=0.1)
            print(f"wrote {summary.html_path} ({summary.n_frames} frames, clearance motion x{summary.exaggerate:g})")
    failed = [name for name, result in results.items() if not result.success]
    return EXIT_RUN_FAILED if failed or stops.requested else EXIT_OK
