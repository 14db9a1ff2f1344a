"""Compile the kernel library: the compiled kernels ahead of time, so that runs load them without numba.

examples:
  clearance build-kernels            # build it if the sources changed since the last build (else say it is fresh)
  clearance build-kernels --force    # build it again
  clearance build-kernels --status   # say whether it is fresh, where it is, what it holds; build nothing

Commands that run kernels (run, paper, sweep, ...) build it themselves when it is
missing or stale, so this is needed only to build it ahead of time (an image, a
cluster's shared environment) or to see its state. It takes 15-40 s (numba.pycc, a C and a
C++ compiler, the Python headers) and goes to a folder of this environment (Python,
numpy, numba, CPU) under clearance_contact/__pycache__/kernel_library, else under
~/.cache/clearance/kernel_library, or under $CLEARANCE_KERNEL_DIR. Runs then import
no numba: ~0.5 s and ~130 MiB less per process, the same results bit for bit
(docs/performance.md, "Fourth pass").
CLEARANCE_CONTACT_JIT=numba runs numba's just-in-time kernels instead;
CLEARANCE_CONTACT_JIT=0 plain Python. Exit 1 if the build fails (the reason is
printed; runs then use numba's just-in-time kernels).
"""

from __future__ import annotations

import argparse
import time

from robot.cli.common import EXIT_OK, EXIT_RUN_FAILED


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--force", action="store_true", help="build even when the library is fresh")
    parser.add_argument("--status", action="store_true", help="only report the library's state (exit 0 fresh, 1 not)")


def execute(args: argparse.Namespace) -> int:
    from clearance_contact.kernel_library import failed_build, fresh_library, library_folder, requested_mode
    from robot.dynamics.kernel_build import ensure_library

    if args.status:
        found = fresh_library()
        note = "" if requested_mode() == "library" else " (not used: CLEARANCE_CONTACT_JIT asks for another mode)"
        if found is None:
            failure = failed_build()
            print(f"kernel library: missing or stale in {library_folder()}{note}" + (f"; the last build failed: {failure}" if failure else ""))
            return EXIT_RUN_FAILED
        folder, manifest = found
        exports = manifest["exports"]
        print(f"kernel library in {folder}: fresh{note}")
        print(f"{len(exports)} kernels, {sum(len(entries) for entries in exports.values())} exported signatures")
        return EXIT_OK
    start = time.perf_counter()
    outcome = ensure_library(force=args.force, wanted=True, retry_failed=True)
    if outcome.startswith("unavailable"):
        return EXIT_RUN_FAILED
    found = fresh_library()
    where = found[0] if found is not None else library_folder()
    print(f"kernel library in {where}: {outcome}" + (f" in {time.perf_counter() - start:.0f} s" if outcome == "built" else ""))
    return EXIT_OK
