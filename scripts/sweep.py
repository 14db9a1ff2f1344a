"""``python scripts/sweep.py SWEEP.toml [--scheduler ADDRESS] [--workers N] [--out DIR]`` = ``clearance sweep ...``.

The logic is in robot.sweep (docs/sweep.md); exit codes: 0 all runs ok, 1 some
runs failed (recorded), 2 bad input.
"""

import sys
from pathlib import Path

if __name__ == "__main__":
    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # this checkout's robot/, installed or not
    from robot.cli.main import main, exit_process

    exit_process(main(["sweep", *sys.argv[1:]]))
