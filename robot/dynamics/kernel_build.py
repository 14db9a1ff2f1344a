"""This project's kernel library: which modules it is built from, and making it ready before a command runs.

The library (:mod:`clearance_contact.kernel_library`) holds every kernel whose ``jit``
declares ``exports``: the contact laws and penetrations of ``clearance_contact`` and
the right-hand side, probe, Jacobian and event kernels of ``robot``. A command that
calls them first makes sure it is fresh (:func:`ensure_library`); a stale or missing
library is compiled once, in a separate process (numba must be imported to compile,
and the command's own process should never import it), so the command itself then
runs on the library. Where that cannot be done (numba.pycc or a C compiler missing,
a read-only folder) the command runs with numba's just-in-time kernels, as before,
after saying why once.

``python -m robot.dynamics.kernel_build [--force]`` builds it (what ``clearance
build-kernels`` runs).
"""

from __future__ import annotations

import importlib
import subprocess
import sys
from pathlib import Path

#: modules whose ``jit(exports=...)`` kernels go into the library (their callees come with them)
KERNEL_MODULES: tuple[str, ...] = (
    "clearance_contact.normal_force",
    "clearance_contact.radial_laws",
    "clearance_contact.spherical",
    "clearance_contact.revolute",
    "clearance_contact.translational",
    "robot.dynamics.rhs_kernels",
    "robot.dynamics.jacobian_kernels",
    "robot.integration.events",
)

def build_library(force: bool = False) -> Path:
    """Compile the library (this process must run numba: ``CLEARANCE_CONTACT_JIT=numba``); the manifest's path."""
    from clearance_contact import compiled, kernel_compiler, kernel_library

    if compiled.KERNEL_MODE != "numba":
        raise kernel_library.KernelLibraryError(
            f"building the kernel library needs numba's kernels in this process (kernel mode is {compiled.KERNEL_MODE!r}); "
            f"run it with {kernel_library.MODE_VARIABLE}=numba, as `clearance build-kernels` does"
        )
    for name in KERNEL_MODULES:
        importlib.import_module(name)
    kernels = {name: (kernel.dispatcher, kernel.exports) for name, kernel in compiled.KERNELS.items()}
    return kernel_compiler.build(kernels, force=force)


def ensure_library(force: bool = False, announce=None, wanted: bool | None = None, retry_failed: bool = False) -> str:
    """Make the library ready before this process imports any kernel; return what happened.

    ``"fresh"`` (nothing to do), ``"built"``, ``"off"`` (the environment asks for
    another mode; ``wanted=True`` builds anyway), or ``"unavailable: <why>"`` (the
    command then runs numba's just-in-time kernels). A build that failed on the same
    sources and environment is not tried again (``force`` or ``retry_failed`` do). ``announce(text)`` is
    told before a build starts (15-40 s) and why one failed (default: standard error).
    """
    from clearance_contact.kernel_library import child_environment, failed_build, is_fresh, requested_mode

    if not (requested_mode() == "library" if wanted is None else wanted):
        return "off"
    if not force and is_fresh():
        return "fresh"

    say = announce or (lambda text: print(text, file=sys.stderr, flush=True))
    earlier = None if force or retry_failed else failed_build()
    if earlier is not None:  # tried on these sources with these compilers: not again at every command
        say(f"note: numba's just-in-time kernels: the kernel library failed to build ({earlier[:300]}); "
            "`clearance build-kernels` tries again")  # fmt: skip
        return f"unavailable: {earlier}"
    say("compiling the kernel library (once per version of the sources; 15-40 s)...")
    command = [sys.executable, "-m", "robot.dynamics.kernel_build", *(["--force"] if force else [])]
    try:  # the child builds this process's packages, with numba's kernels
        done = subprocess.run(command, env=child_environment("numba"), capture_output=True, text=True)
    except OSError as exc:  # the interpreter cannot be started again (a frozen or sandboxed process)
        done = subprocess.CompletedProcess(command, 1, "", str(exc))
    if done.returncode != 0:
        lines = (done.stderr or done.stdout).strip().splitlines()
        why = lines[-1] if lines else f"exit code {done.returncode}"
    elif not is_fresh():
        why = f"the build wrote {done.stdout.strip()}, which this process does not find fresh"
    else:
        return "built"
    say(f"warning: the kernel library was not built ({why}); runs use numba's just-in-time kernels until it is")
    return f"unavailable: {why}"


def main(argv: list[str] | None = None) -> int:
    """Build the library in this process (``--force``: even when it is fresh); print the manifest's path."""
    from clearance_contact.kernel_library import KernelLibraryError

    argv = sys.argv[1:] if argv is None else argv
    try:
        path = build_library(force="--force" in argv)
    except (KernelLibraryError, OSError) as exc:
        print("error: " + " ".join(str(exc).split()), file=sys.stderr)  # one line: ensure_library reports the last
        return 1
    print(path)
    return 0


if __name__ == "__main__":
    sys.exit(main())
