"""Simulate one scene and write OUT/NAME.npz (NAME: the scene's name made safe as a file name).

examples:
  clearance run --scene compound_misaligned                 # shipped scene, its duration, into results/
  clearance run --scene compound --t-end 0.2 --out /tmp/r   # shorter run elsewhere
  clearance run --scene ./my_scene.toml --check             # validate the scene and build its model only

Shipped scenes (robot/scene/scenes/, docs/scenes.md): ideal, spherical, revolute,
compound, compound_misaligned (the 4-UPS/RPS of the seed paper); four_bar,
four_bar_revolute, slider_crank_revolute, slider_crank_translational (planar
linkages with clearance); free_two_link_spring (a torque-driven arm with force
elements). A scene file of your own works by path (docs/scenes.md documents the keys).
Ctrl-C or SIGTERM stops the integration and saves the partial result.
The output folder is checked writable before the run; if the write still fails,
the result goes to a temporary folder named in the message.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from robot.cli.common import (
    EXIT_INTERRUPTED, EXIT_OK, EXIT_RUN_FAILED, collector_spared_setup, count_text, positive_seconds, progress_bar, writable_folder,
)
from robot.cli.interrupts import Phase, clean_stops




def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--scene", required=True, help="shipped scene name or path to a .toml file")
    parser.add_argument("--t-end", type=positive_seconds, default=None, help="simulated duration in s (default: the scene's duration)")
    parser.add_argument("--out", type=Path, default=Path("results"), help="output folder (default: results)")
    parser.add_argument("--check", action="store_true", help="validate the scene and build its model and initial state; run nothing")


def execute(args: argparse.Namespace) -> int:
    out = None if args.check else writable_folder(args.out)
    with collector_spared_setup() as set_up, clean_stops() as stops:
        from robot.cli.outputs import save_or_fallback
        from robot.run import build_run, compile_kernels, run_scene

        run = build_run(args.scene, duration=args.t_end)
        set_up()  # the imports and the model live until the end: out of the garbage collector's walks
        if args.check:
            print(f"{run.scene.name}: scene valid; mechanism {run.scene.mechanism_path.name}, nq {run.mechanism.model.nq}, "
                  f"clearance joints {list(run.scene.clearance_joints) or 'none'}, duration {run.scene.duration:g} s")
            if run.scene.description:
                print(f"  {run.scene.description}")
            return EXIT_OK
        path = out / f"{run.scene.file_stem}.npz"
        stops.saving = f"saving the result to {path}"
        stops.phase = Phase.RUNNING
        compile_time = compile_kernels(run)
        if stops.requested:
            return EXIT_INTERRUPTED
        with progress_bar(run.scene.duration, run.scene.name) as update:
            # outputs only at the records the file keeps (robot.io.results.kept_rows)
            result = run_scene(run, progress=update, output=run.scene.output)
        result.counts["compile_cpu_time"] = compile_time
        stops.phase = Phase.SAVING
        path, where_asked = save_or_fallback(result, path, run.scene.output)
    print(f"{run.scene.name}: {result.message}\n{counts_line(result.counts, finished=result.success)}\n  wrote {path}")
    return EXIT_OK if result.success and where_asked else EXIT_RUN_FAILED


def counts_line(counts: dict, finished: bool = True) -> str:
    """The run's counters for people (``n/a`` where a solver does not count).

    ``finished``: the run reached its end. A failed or interrupted run's rejected
    steps are not counted (the step loop leaves out its last solver's), so they are ``n/a``.
    """
    compile_time = counts.get("compile_cpu_time")
    compiled = f" (+ {compile_time:.2f} s compiling the kernels)" if compile_time is not None else ""
    rejected = counts.get("n_rejected") if finished else None
    return (
        f"  steps {count_text(counts.get('n_steps'))}, rejected {count_text(rejected)}, "
        f"rhs calls {count_text(counts.get('n_rhs'))}, events {count_text(counts.get('n_events'))}, "
        f"cpu {count_text(counts.get('cpu_time'), '.2f')} s{compiled}"
    )
