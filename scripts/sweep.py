"""Run a parameter sweep: python scripts/sweep.py SWEEP.toml [--scheduler ADDRESS] [--workers N] [--out DIR].

The logic is in robot.sweep (docs/sweep.md); exit codes: 0 all runs ok, 1 some
runs failed (recorded), 2 bad input.
"""

import sys

from robot.sweep.cli import main

if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
