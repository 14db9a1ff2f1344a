"""Simulate one scene and write DIR/NAME.npz.

    python scripts/simulate.py --scene NAME_OR_PATH [--t-end T] [--out DIR]

Exit status 0 on success, 1 if the run failed (the partial result is still
written, with the time and the cause), 2 on bad input.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from robot.cli.common import exit_on_error, progress_bar  # noqa: E402
from robot.io.results import save_result  # noqa: E402
from robot.run import build_run, run_scene  # noqa: E402
from robot.scene.loader import shipped_scenes  # noqa: E402


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--scene", required=True, help=f"shipped scene ({', '.join(shipped_scenes())}) or path to a .toml file")
    parser.add_argument("--t-end", type=float, default=None, help="simulated duration in s (default: the scene's)")
    parser.add_argument("--out", type=Path, default=Path("results"), help="output folder (default: results)")
    args = parser.parse_args()
    run = build_run(args.scene, duration=args.t_end)
    with progress_bar(run.scene.duration, run.scene.name) as update:
        result = run_scene(run, progress=update)
    path = save_result(result, args.out / f"{run.scene.name}.npz")
    counts = result.counts
    print(
        f"{run.scene.name}: {result.message}\n"
        f"  steps {counts['n_steps']}, rejected {counts['n_rejected']}, rhs calls {counts['n_rhs']}, "
        f"events {counts['n_events']}, cpu {counts['cpu_time']:.2f} s\n  wrote {path}"
    )
    return 0 if result.success else 1


if __name__ == "__main__":
    exit_on_error(main)
