"""Benchmark of the sweep engine: runs per minute, parallel efficiency, per-run overhead.

clearance bench-sweep [--runs N] [--t-end S] [--out results/bench_sweep.json]  (= python scripts/bench_sweep.py)

The same sweep (the spherical scene over its S1 clearance, N runs of t_end s)
runs on a local cluster of 1 and of 2 workers. Timed: the run phase only (first
submission to last completion; the cluster start and the probe that warms
every worker are excluded), so the numbers are those of warm workers.

* runs per minute = N / run phase * 60;
* parallel efficiency = (rate with 2 workers) / (2 x rate with 1 worker);
* per-run overhead = a run's task wall time (model build, the result's outputs
  evaluated at every record, analyses, writes into the store) minus its
  integration wall time; median and 90th percentile over the runs of the
  1-worker sweep. ``median_sweep_machinery_s`` is the part the sweep adds to
  ``robot.simulate`` (scene check, analyses, store writes).
"""

from __future__ import annotations

import json
import os
import platform
import tempfile
from pathlib import Path

import numpy as np

SWEEP = """
[sweep]
name = "bench"
scene = "spherical"
t_end = {t_end}

[[axis]]
key = "clearance.S1.clearance"
name = "clearance"
log = {{ start = 5e-5, stop = 2e-4, num = {runs} }}

[[analysis]]
name = "amplitude_spectrum"
label = "force_spectrum"
signal = "S1_normal_force:sum"
n_samples = 256

[keep]
arrays = ["ee_position"]
samples = 101
"""


def measure(spec, workers: int, folder: Path) -> dict:
    from robot.sweep.engine import run_sweep

    outcome = run_sweep(spec, folder / f"w{workers}", workers=workers, progress=False)
    overhead = np.array([s["wall_time"] - s["integration_wall_time"] for s in outcome.summaries])
    machinery = np.array([s["wall_time"] - s["simulate_wall_time"] for s in outcome.summaries])
    integration = np.array([s["integration_wall_time"] for s in outcome.summaries])
    return {
        "workers": workers,
        "runs": outcome.ran,
        "failed": outcome.failed,
        "run_phase_s": outcome.run_phase_time,
        "runs_per_minute": 60.0 * outcome.ran / outcome.run_phase_time,
        "median_integration_s": float(np.median(integration)),
        "median_overhead_s": float(np.median(overhead)),
        "p90_overhead_s": float(np.percentile(overhead, 90)),
        "median_sweep_machinery_s": float(np.median(machinery)),
        "total_with_cluster_start_s": outcome.wall_time,
    }


def benchmark(runs: int, t_end: float, out: Path) -> dict:
    """Run the benchmark sweep on 1 and on 2 workers; write and return the report."""
    from robot.io.atomic import atomic_write_text
    from robot.sweep.spec import load_sweep

    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        (folder / "bench.toml").write_text(SWEEP.format(t_end=t_end, runs=runs))
        spec = load_sweep(folder / "bench.toml")
        one, two = measure(spec, 1, folder), measure(spec, 2, folder)
    report = {
        "sweep": f"spherical scene, {runs} runs of t_end={t_end} s (S1 clearance 50-200 um), spectrum + kept array",
        "machine": {"cpus": os.cpu_count(), "platform": platform.platform(), "load_average_1min_at_end": os.getloadavg()[0]},
        "note": "the machine is shared with other jobs: the load average says how busy it was",
        "one_worker": one,
        "two_workers": two,
        "parallel_efficiency": two["runs_per_minute"] / (2.0 * one["runs_per_minute"]),
        "per_run_overhead_median_s": one["median_overhead_s"],
        "per_run_sweep_machinery_median_s": one["median_sweep_machinery_s"],
    }
    atomic_write_text(out, json.dumps(report, indent=2) + "\n")
    return report
