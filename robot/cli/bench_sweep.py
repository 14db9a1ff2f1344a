"""Benchmark of the sweep engine (not a test): runs per minute on 1 and 2 workers, parallel efficiency, per-run overhead.

examples:
  clearance bench-sweep                         # 16 runs of 0.1 s, results/bench_sweep.json
  clearance bench-sweep --runs 32 --t-end 0.2 --out /tmp/bench_sweep.json

The definitions of the numbers: robot/sweep/bench.py; the figures measured: docs/studies.md.
The output file is checked writable before the benchmark runs.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from robot.cli.common import EXIT_OK, positive_int, positive_seconds, writable_file

HELP = "benchmark of the sweep engine: runs per minute, parallel efficiency, overhead"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--runs", type=positive_int, default=16, help="runs per sweep (default 16)")
    parser.add_argument("--t-end", type=positive_seconds, default=0.1, help="simulated seconds per run (default 0.1)")
    parser.add_argument("--out", type=Path, default=Path("results/bench_sweep.json"), help="JSON report (default results/bench_sweep.json)")


def execute(args: argparse.Namespace) -> int:
    from robot.sweep.bench import benchmark

    out = writable_file(args.out, "--out")  # checked before the benchmark runs (exit 2)
    print(json.dumps(benchmark(args.runs, args.t_end, out), indent=2))
    return EXIT_OK
