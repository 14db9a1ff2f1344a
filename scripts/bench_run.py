"""Time each phase of ``clearance run --scene NAME`` over repeated fresh processes; JSON and a table.

examples:
  python scripts/bench_run.py                                   # compound_misaligned, 5 repeats
  python scripts/bench_run.py --scene revolute --repeats 7 --out results/bench_run_revolute.json

The measurement is :mod:`robot.analysis.studies.run_phases` (CPU time per phase,
medians; the integration against its floor, the right-hand side plus the
Jacobian, measured in the same process).
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

if __name__ == "__main__":
    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # this checkout's robot/, installed or not
    from robot.analysis.studies.run_phases import benchmark, table
    from robot.io.atomic import atomic_write_text

    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--scene", default="compound_misaligned")
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--out", type=Path, default=Path("results") / "bench_run.json")
    args = parser.parse_args()
    report = benchmark(args.scene, args.repeats, progress=lambda line: print(line, file=sys.stderr, flush=True))
    report["table"] = table(report)
    args.out.parent.mkdir(parents=True, exist_ok=True)
    atomic_write_text(args.out, json.dumps(report, indent=1))
    args.out.with_suffix(".md").write_text(report["table"] + "\n")
    print(report["table"])
