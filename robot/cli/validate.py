"""Cross-check the Lagrange model against Newton-Euler and Exudyn (docs/validation.md).

Writes OUT/validation.json (maximum deviations per quantity and scene, statistics,
wall time of each engine, the solver settings used) and OUT/validation_<scene>.png,
OUT/deviation_<scene>.png. The Lagrange and Newton-Euler runs use the validation's
own pinned integrator (robot.validation.settings.VALIDATION_SOLVER), never the
scenes' [solver] tables; --method/--rtol/--atol/--max-step/--first-step override it.

examples:
  clearance validate                                         # every default scene, both engines
  clearance validate --scenes ideal --engines newton_euler --no-figures
  clearance validate --scenes compound --duration compound=0.1 --out /tmp/validation
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path

from robot.cli.common import UsageError, writable_folder


def add_arguments(parser: argparse.ArgumentParser) -> None:
    from robot.validation.study import add_arguments as study_arguments

    study_arguments(parser)


def execute(args: argparse.Namespace) -> int:
    """Check every scene, duration and number before the (long) study starts."""
    from robot.scene.loader import load_scene
    from robot.validation.study import run_validation

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
    for option in ("rtol", "atol", "max_step", "first_step", "exudyn_step"):
        value = getattr(args, option)
        if value is not None and not (math.isfinite(value) and value > 0):
            raise UsageError(f"--{option.replace('_', '-')}={value!r} must be a finite number > 0")
    writable_folder(Path(args.out))
    return run_validation(args)
