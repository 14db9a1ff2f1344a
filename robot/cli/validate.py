"""Cross-check the Lagrange model against Newton-Euler and Exudyn (docs/validation.md).

Writes OUT/validation.json (maximum deviations per quantity and scene, statistics,
wall time of each engine, the solver settings used) and OUT/validation_<scene>.png,
OUT/deviation_<scene>.png. A scene runs over --duration SCENE=T, else the default
study's horizon (ideal 1 s; spherical, compound, compound_misaligned 0.5 s), else
its own duration. Before any run, each scene is built and checked against each
engine: a joint, closure, actuator, force element or body an engine does not model
is refused (exit status 2, naming the scene, the engine and the feature). The
Lagrange and Newton-Euler runs use the validation's own pinned integrator
(robot.validation.settings.VALIDATION_SOLVER), never the scenes' [solver] tables;
--method/--rtol/--atol/--max-step/--first-step override it.

examples:
  clearance validate                                         # every default scene, both engines
  clearance validate --scenes ideal --engines newton_euler --no-figures
  clearance validate --scenes compound --duration compound=0.1 --out /tmp/validation

--rtol, --atol, --max-step and --first-step take the ranges a scene's [solver]
table allows (robot/scene/loader.py); --first-step may not exceed the largest
step. A failed engine run does not stop the study: the command ends with exit
status 1 and names each failed run, the time it reached and the cause. Ctrl-C or
SIGTERM stops a Lagrange or Newton-Euler integration at once (an Exudyn run under
way finishes first) and the study before its next run; what was computed is
kept (validation.json, rewritten after every scene, and the figures), exit status 1.
"""

from __future__ import annotations

import argparse
import importlib.util
import math
import sys
from pathlib import Path

from robot.cli.common import EXIT_INTERRUPTED, EXIT_OK, EXIT_RUN_FAILED, UsageError, writable_folder
from robot.cli.interrupts import Phase, clean_stops
from robot.errors import RobotError


def add_arguments(parser: argparse.ArgumentParser) -> None:
    from robot.validation.study import add_arguments as study_arguments

    study_arguments(parser)


def execute(args: argparse.Namespace) -> int:
    """Check every scene, duration and number before the (long) study starts; then run it, stoppable."""
    from robot.validation.study import run_validation

    _check_options(args)
    out = writable_folder(Path(args.out))
    if "exudyn" in args.engines and importlib.util.find_spec("exudyn") is None:
        raise UsageError("--engines exudyn: the exudyn package is not installed (pip install exudyn); or leave it out: --engines newton_euler")
    with clean_stops(f"saving the finished runs to {out}") as stops:
        stops.phase = Phase.RUNNING
        results = run_validation(args, stop_reason=lambda: stops.received[0] if stops.received else None, checked=True)
    if results["success"]:
        return EXIT_OK
    if not results["scenes"]:
        print(f"{stops.received[0]}: stopped before any engine run; nothing to save", file=sys.stderr)
        return EXIT_INTERRUPTED
    return EXIT_RUN_FAILED


def _check_options(args: argparse.Namespace) -> None:
    """``UsageError`` naming the first bad scene, ``--duration``, solver option or ``--exudyn-step``; then the engines' scope.

    Last, :func:`robot.validation.study.check_scenes` builds every scene and
    raises ``UnsupportedFeatureError`` (exit 2) for a scene an engine does not
    model. Nothing is run or written yet.
    """
    from robot.scene.loader import load_scene
    from robot.validation.study import check_scenes, solver_from_options

    for scene in args.scenes:
        load_scene(scene)
    for item in args.duration:
        scene, _, value = item.partition("=")
        try:
            seconds = float(value)
        except ValueError:
            seconds = math.nan
        if scene not in args.scenes or not (math.isfinite(seconds) and seconds > 0):
            raise UsageError(f"--duration {item!r}: expected SCENE=SECONDS with SCENE one of --scenes and SECONDS > 0")
    try:
        solver_from_options(args)
    except ValueError as exc:
        raise UsageError(str(exc)) from None
    step = args.exudyn_step
    if step is not None and not (math.isfinite(step) and step > 0):
        raise UsageError(f"--exudyn-step={step!r} must be a finite number > 0")
    try:
        check_scenes(args)
    except ValueError as exc:
        if isinstance(exc, RobotError):  # UnsupportedFeatureError: exit 2 with its own message
            raise
        raise UsageError(str(exc)) from None  # a solver option against a scene's limits
