"""``python scripts/reproduce_paper.py ARGS`` = ``clearance paper ARGS`` (kept for users and checks; see ``clearance paper --help``)."""

import sys
from pathlib import Path

if __name__ == "__main__":
    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # this checkout's robot/, installed or not
    from robot.cli.main import main, exit_process

    exit_process(main(["paper", *sys.argv[1:]]))
