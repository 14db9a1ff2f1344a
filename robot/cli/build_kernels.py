"""Compile the kernel library: the compiled kernels ahead of time, so that runs load them without numba.

examples:
  clearance build-kernels            # build it if the sources changed since the last build (else say it is fresh)
  clearance build-kernels --force    # build it again
  clearance build-kernels --status   # say whether it is fresh, where it is, what it holds; build nothing

Commands that run kernels (run, paper, sweep, ...) build it themselves when it is
missing or stale, so this is needed only to build it ahead of time (an image, a
cluster's shared environment) or to see its state. It takes 30-40 s (numba.pycc and a C
compiler) and goes to clearance_contact/__pycache__/kernel_library, or to
$CLEARANCE_KERNEL_DIR. Runs then import no numba: ~0.4 s and ~110 MiB less per
process, the same results bit for bit (docs/performance.md, "Kernel library").
CLEARANCE_CONTACT_JIT=numba runs numba's just-in-time kernels instead;
CLEARANCE_CONTACT_JIT=0 plain Python. Exit 1 if the build fails (the reason is
printed; runs then use numba's just-in-time kernels).
"""

from __future__ import annotations

import argparse
import json
import time

from robot.cli.common import EXIT_OK, EXIT_RUN_FAILED


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--force", action="store_true", help="build even when the library is fresh")
    parser.add_argument("--status", action="store_true", help="only report the library's state (exit 0 fresh, 1 not)")


def execute(args: argparse.Namespace) -> int:
    from clearance_contact.kernel_library import MANIFEST, is_fresh, library_folder
    from robot.dynamics.kernel_build import ensure_library, library_wanted

    folder = library_folder()
    if args.status:
        fresh = is_fresh()
        print(f"kernel library in {folder}: {'fresh' if fresh else 'missing or stale'}"
              + ("" if library_wanted() else " (not used: CLEARANCE_CONTACT_JIT asks for another mode)"))
        if fresh:
            exports = json.loads((folder / MANIFEST).read_text())["exports"]
            print(f"{len(exports)} kernels, {sum(len(v) for v in exports.values())} exported signatures")
        return EXIT_OK if fresh else EXIT_RUN_FAILED
    start = time.perf_counter()
    outcome = ensure_library(force=args.force, wanted=True, retry_failed=True)
    if outcome.startswith("unavailable"):
        return EXIT_RUN_FAILED
    print(f"kernel library in {folder}: {outcome}" + (f" in {time.perf_counter() - start:.0f} s" if outcome == "built" else ""))
    return EXIT_OK
