"""Print a summary of a mechanism: bodies, joints, closures, actuators, clearance sites, mobility, mass.

examples:
  clearance describe                                   # the shipped ups_rps.urdf, ideal joints
  clearance describe --clearance R1,S1                 # R1 and S1 as clearance joints
  clearance describe --urdf tests/data/rssr.urdf --clearance Sb
"""

from __future__ import annotations

import argparse
from pathlib import Path

from robot.cli.common import EXIT_OK


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--urdf", type=Path, default=None, help="URDF file with <closures> (default: the shipped ups_rps.urdf)")
    parser.add_argument("--clearance", default="", help="comma-separated joints/closures with clearance, e.g. R1,S1")


def execute(args: argparse.Namespace) -> int:
    from robot.data import shipped_urdf
    from robot.model.mechanism import build_mechanism
    from robot.model.summary import describe

    urdf = args.urdf if args.urdf is not None else shipped_urdf("ups_rps.urdf")
    mechanism = build_mechanism(urdf, clearance=args.clearance or None)
    print(describe(mechanism), end="")
    return EXIT_OK
