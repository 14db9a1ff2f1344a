"""``python scripts/simulate.py ARGS`` = ``clearance run ARGS`` (kept for users and checks; see ``clearance run --help``)."""

import sys
from pathlib import Path

if __name__ == "__main__":
    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # this checkout's robot/, installed or not
    from robot.cli.main import main, exit_process

    exit_process(main(["run", *sys.argv[1:]]))
