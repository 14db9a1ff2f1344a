"""Print a summary of a mechanism: bodies, joints, closures, actuators, clearance sites, mobility, mass.

    python scripts/describe_model.py                      # urdf/ups_rps.urdf, ideal joints
    python scripts/describe_model.py --clearance R1,S1    # R1 and S1 as clearance joints
    python scripts/describe_model.py --urdf tests/data/rssr.urdf --clearance Sb
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:  # run as a file from a checkout without installing the package
    sys.path.insert(0, str(ROOT))

from robot.errors import RobotError  # noqa: E402
from robot.model.mechanism import build_mechanism  # noqa: E402
from robot.model.summary import describe  # noqa: E402

DEFAULT_URDF = ROOT / "urdf" / "ups_rps.urdf"


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--urdf", type=Path, default=DEFAULT_URDF, help="URDF file with <closures> (default: %(default)s)")
    parser.add_argument("--clearance", default="", help="comma-separated joints/closures with clearance, e.g. R1,S1")
    args = parser.parse_args(argv)
    try:
        mechanism = build_mechanism(args.urdf, clearance=args.clearance or None)
    except RobotError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    print(describe(mechanism), end="")
    return 0


if __name__ == "__main__":
    sys.exit(main())
