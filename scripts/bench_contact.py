"""``python scripts/bench_contact.py ARGS`` = ``clearance bench ARGS`` (kept for users and checks; see ``clearance bench --help``)."""

import sys
from pathlib import Path

if __name__ == "__main__":
    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # this checkout's robot/, installed or not
    from robot.cli.main import main, exit_process

    exit_process(main(["bench", *sys.argv[1:]]))
