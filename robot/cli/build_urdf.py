"""Write the URDF of the 4-UPS/RPS from the design parameters in robot/model/ups_rps_design.py.

examples:
  clearance build-urdf                        # regenerate the shipped urdf/ups_rps.urdf (in a checkout)
  clearance build-urdf --out /tmp/ups_rps.urdf
"""

from __future__ import annotations

import argparse
from pathlib import Path

from robot.cli.common import EXIT_OK, writable_file


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--out", type=Path, default=None, help="URDF file to write (default: the shipped urdf/ups_rps.urdf)")


def execute(args: argparse.Namespace) -> int:
    from robot.data import shipped_urdf
    from robot.io.atomic import atomic_write_text
    from robot.model.ups_rps_design import ups_rps_urdf

    path = writable_file(args.out if args.out is not None else shipped_urdf("ups_rps.urdf"), "--out")
    atomic_write_text(path, ups_rps_urdf())
    print(f"wrote {path}")
    return EXIT_OK
