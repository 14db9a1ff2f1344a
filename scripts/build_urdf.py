"""Write ``urdf/ups_rps.urdf`` from the design parameters in ``robot/ups_rps_design.py``."""

from __future__ import annotations

import argparse
from pathlib import Path

from robot.io.atomic import atomic_write_text
from robot.model.ups_rps_design import ups_rps_urdf

DEFAULT_PATH = Path(__file__).resolve().parents[1] / "urdf" / "ups_rps.urdf"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--out", type=Path, default=DEFAULT_PATH, help="URDF file to write")
    args = parser.parse_args()
    atomic_write_text(args.out, ups_rps_urdf())
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
