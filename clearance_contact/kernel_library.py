"""The kernel library: the compiled kernels ahead of time, as one extension module loaded without numba.

Why: numba compiles the kernels just in time, and even when every kernel comes from
its disk cache a process pays numba's start-up before the first one runs: importing
numba (0.15 s, 53 MiB) and building its typing and target contexts and LLVM
(0.3 s, 58 MiB), measured on the 4-UPS/RPS run of issue 16: about a fifth of that
run's 2.4 s and 110 of its 280 MiB. ``numba.pycc`` compiles the *same source* with
the same LLVM into a plain CPython extension module ahead of time; importing it
takes under a millisecond and numba is never loaded. The results are those of the
just-in-time kernels bit for bit (same code generator, same CPU target, no
fast-math in either; ``tests/test_kernel_library.py`` compares whole runs).

A kernel is exported when its ``jit`` declares ``exports``: the numba signatures of
the calls Python makes to it (``@jit(exports=("i8(f8[::1], f8)",))``). Its callees
are compiled into the library with it. :func:`clearance_contact.kernel_compiler.build`
writes the library and its manifest into a folder; :func:`load` (this module, which
imports no numba) finds it fresh or returns None.

Safety: an exported function converts its arguments without checking them (a
float32 array crashes the process; a strided view is read as if contiguous). So an
export is only ever reached through a *guard* (:file:`kernel_guard.c`, built from the
manifest's argument descriptions) that checks every argument as numba's dispatcher
would (dtype, dimensions, layout, writeable, aligned; the scalars' types) and hands
any other call to numba's just-in-time compiler
(:func:`clearance_contact.kernel_mode.switch_to_numba`): a call is never wrong, at worst
slower.

Freshness: the manifest records a digest of every source file in the folders of the
kernels' sources (the same files numba's cache is checked against:
:func:`clearance_contact.kernel_mode.drop_stale_caches`), the guards' C source and
:func:`environment_key` (interpreter, numpy, numba, llvmlite, numba's settings, CPU).
A library whose digest differs is not used; a build replaces it.
"""

from __future__ import annotations

import functools
import hashlib
import json
import os
import platform
import shutil
import sys
import sysconfig
from pathlib import Path
from typing import Any, Callable

import numpy as np

from clearance_contact.extension import import_extension

__all__ = [
    "MANIFEST", "FAILURE", "MODE_VARIABLE", "MODE_VALUES", "requested_mode", "child_environment", "KernelLibraryError", "Library", "library_folder", "library_folders", "environment_key", "toolchain",
    "source_files", "digest", "read_record", "fresh_record", "failed_build", "fresh_library", "is_fresh", "load", "guard", "guard_spec",
]  # fmt: skip

MANIFEST = "manifest.json"
"""The manifest's file name in the library folder (written last: its presence completes a build)."""

FORMAT = 1
"""Manifest format; a manifest of another format is not read."""

ANCHOR = Path(__file__).resolve().parents[1]
"""Sources are recorded relative to this folder (the one holding ``clearance_contact`` and ``robot``)."""

GUARD_SOURCE = "kernel_guard.c"
"""The guards' C source (beside this file), compiled with the library."""

FAILURE = "build_failed.json"
"""Written where a build failed (its digest and why): later commands do not try again until the sources change."""

MODE_VARIABLE = "CLEARANCE_CONTACT_JIT"
"""The environment variable that chooses how kernels run: ``0`` plain Python, ``numba`` numba's JIT, else the library."""


MODE_VALUES = {"python": "0", "numba": "numba", "library": "1"}
"""The value of :data:`MODE_VARIABLE` that asks for each kernel mode."""


def requested_mode() -> str:
    """What :data:`MODE_VARIABLE` asks for: ``"python"``, ``"numba"``, or ``"library"`` (the default; numba's JIT
    where no fresh library is found)."""
    return {"0": "python", "numba": "numba"}.get(os.environ.get(MODE_VARIABLE, "1"), "library")


def child_environment(mode: str) -> dict:
    """This process's environment for a child Python process that runs kernels in ``mode`` (a key of
    :data:`MODE_VALUES`) from this process's packages (their folder, :data:`ANCHOR`, first on ``PYTHONPATH``:
    a script may have put a checkout first on ``sys.path``)."""
    environment = dict(os.environ, **{MODE_VARIABLE: MODE_VALUES[mode]})
    environment["PYTHONPATH"] = os.pathsep.join(filter(None, [str(ANCHOR), environment.get("PYTHONPATH", "")]))
    return environment


#: numba settings that change the code it generates (its optimisation level, bounds checks, target CPU)
_NUMBA_SETTINGS = ("NUMBA_OPT", "NUMBA_BOUNDSCHECK", "NUMBA_CPU_NAME", "NUMBA_CPU_FEATURES", "NUMBA_FASTMATH")


class KernelLibraryError(RuntimeError):
    """The kernel library could not be built (numba.pycc or the C compiler failed); the message says why."""


def library_folders() -> list[Path]:
    """Where this environment's library may be, in the order they are read.

    ``$CLEARANCE_KERNEL_DIR/<key>`` alone when that variable is set; else
    ``clearance_contact/__pycache__/kernel_library/<key>`` (beside numba's own cache of
    the same kernels; what an installation built ahead of time) and then
    ``$XDG_CACHE_HOME`` (or ``~/.cache``)``/clearance/kernel_library/<key>``. ``<key>``:
    :func:`environment_key`, so that virtual environments, interpreters or machines
    sharing a folder keep their own libraries instead of rebuilding each other's.
    """
    key = environment_key()[:16]
    configured = os.environ.get("CLEARANCE_KERNEL_DIR")
    if configured:
        return [Path(configured) / key]
    package = Path(__file__).resolve().parent / "__pycache__" / "kernel_library"
    cache = Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "clearance" / "kernel_library"
    return [package / key, cache / key]


def library_folder() -> Path:
    """Where a build writes: the first of :func:`library_folders` that can be written (or made)."""
    folders = library_folders()
    for folder in folders:
        existing = next(path for path in (folder, *folder.parents) if path.exists())
        if os.access(existing, os.W_OK):
            return folder
    return folders[-1]


def toolchain() -> str:
    """The C and C++ compilers (``$CC``/``$CXX`` or gcc/g++) and Python headers a build finds: a failure
    recorded under other ones is tried again (installing the compilers is the usual fix)."""
    parts = []
    for variable, default in (("CC", "gcc"), ("CXX", "g++")):
        command = (os.environ.get(variable) or default).split()
        parts.append(f"{variable}={shutil.which(command[0]) if command else None}")
    parts.append(f"Python.h={(Path(sysconfig.get_paths()['include']) / 'Python.h').is_file()}")
    return " ".join(parts)


def _distribution(name: str) -> str:
    """``name``'s installed version: the name of its ``.dist-info`` folder on ``sys.path``.

    Read off the file system (not importlib.metadata, 15 ms to import, nor the import
    system, which a process that blocks numba would refuse): "numba: none" if absent.
    """
    for entry in sys.path:
        folder = Path(entry or ".")
        if folder.is_dir():
            found = sorted(path.name for path in folder.glob(f"{name}-*.dist-info"))
            if found:
                return " ".join(found)
    return f"{name}: none"


@functools.lru_cache(maxsize=1)
def environment_key() -> str:
    """sha256 of what the compiled code depends on besides the sources: interpreter, numpy, numba and
    llvmlite, numba's code-generation settings, this CPU (the library is compiled for the host CPU).
    Computed once a process (``/proc/cpuinfo`` is slow to read on many-core machines)."""
    parts = [sys.version, sysconfig.get_config_var("EXT_SUFFIX") or "", np.__version__, _distribution("numba"), _distribution("llvmlite")]
    parts += [f"{name}={os.environ.get(name, '')}" for name in _NUMBA_SETTINGS] + [_cpu_identity()]
    return hashlib.sha256("\n".join(parts).encode()).hexdigest()


def source_files(kernel_sources) -> list[str]:
    """Every ``*.py`` beside the kernels' source files, relative to :data:`ANCHOR` (sorted).

    Compiled code reads the module globals of its own file and calls kernels of other
    files, whose constants come from further imports: the folders, not the files alone.
    """
    files = set()
    for source in kernel_sources:
        folder = Path(source).resolve().parent
        files.update(path.relative_to(ANCHOR).as_posix() for path in folder.glob("*.py"))
    return sorted(files)


def _cpu_identity() -> str:
    """This CPU's model and instruction-set flags (the library is compiled for the host CPU)."""
    try:
        with open("/proc/cpuinfo", encoding="utf-8", errors="replace") as cpuinfo:
            lines = [line for line in cpuinfo if line.startswith(("model name", "flags", "Features", "CPU part"))]
        return "".join(sorted(set(lines)))
    except OSError:
        return f"{platform.machine()} {platform.processor()}"


def digest(sources: list[str]) -> str:
    """sha256 of the files ``sources`` (relative to :data:`ANCHOR`), the guards' C source and :func:`environment_key`."""
    hasher = hashlib.sha256()
    for relative in [*sources, f"clearance_contact/{GUARD_SOURCE}"]:
        hasher.update(relative.encode() + b"\0")
        try:
            hasher.update((ANCHOR / relative).read_bytes())
        except OSError:  # a source went away: the digest cannot match
            hasher.update(b"missing")
    hasher.update(environment_key().encode())
    return hasher.hexdigest()


def read_record(path: Path) -> dict | None:
    """A manifest or failure record of this format, with its ``digest`` and ``sources``, else None."""
    try:
        record = json.loads(path.read_text())
    except (OSError, ValueError):
        return None
    if not isinstance(record, dict) or record.get("format") != FORMAT or not isinstance(record.get("sources"), list):
        return None
    return record


def fresh_record(path: Path) -> dict | None:
    """The record at ``path`` if its digest is that of today's sources and environment."""
    record = read_record(path)
    if record is None or record.get("digest") != digest(record["sources"]):
        return None
    return record


def _complete(folder: Path) -> dict | None:
    """The folder's manifest if it is fresh and both extension files it names are there."""
    manifest = fresh_record(folder / MANIFEST)
    try:
        if manifest is None or not all((folder / manifest[key]).is_file() for key in ("filename", "guard_filename")):
            return None
    except (KeyError, TypeError):
        return None
    return manifest


def failed_build(folder: Path | None = None) -> str | None:
    """Why the last build in ``folder`` (default :func:`library_folder`) failed, if it was tried on today's
    sources, environment and :func:`toolchain`; else None."""
    record = fresh_record((library_folder() if folder is None else Path(folder)) / FAILURE)
    if record is None or record.get("toolchain") != toolchain():
        return None
    return str(record.get("reason", "unknown"))


def fresh_library(folder: Path | None = None) -> tuple[Path, dict] | None:
    """``(folder, manifest)`` of the first complete library of today's sources in ``folder`` (default: in
    :func:`library_folders`), else None; nothing is loaded."""
    for candidate in [Path(folder)] if folder is not None else library_folders():
        manifest = _complete(candidate)
        if manifest is not None:
            return candidate, manifest
    return None


def is_fresh(folder: Path | None = None) -> bool:
    """A complete library of today's sources is in ``folder`` (default: one of :func:`library_folders`)."""
    return fresh_library(folder) is not None


def load(folder: Path | None = None) -> Library | None:
    """The fresh library in ``folder`` (default: the first of :func:`library_folders` that has one), else None.

    Never raises: a missing, stale or unloadable library is None (the caller falls
    back to numba's just-in-time compilation).
    """
    found = fresh_library(folder)
    if found is None:
        return None
    folder, manifest = found
    try:
        kernels = import_extension(manifest["module"], folder / manifest["filename"])
        guards = import_extension("kernel_guard", folder / manifest["guard_filename"])
    except (ImportError, OSError, KeyError, TypeError):
        return None
    return Library(manifest, kernels, guards)


class Library:
    """A loaded library: its ``manifest``, the ``kernels`` extension module and the ``guards`` (:file:`kernel_guard.c`)."""

    __slots__ = ("manifest", "kernels", "guards")

    def __init__(self, manifest: dict, kernels: Any, guards: Any) -> None:
        self.manifest, self.kernels, self.guards = manifest, kernels, guards

    def entry(self, function: Callable, fallback: Callable) -> Callable | None:
        """``function``'s guarded exports (:func:`guard`), or None when the library has none of it."""
        exports = self.manifest["exports"].get(f"{function.__module__}.{function.__qualname__}")
        return guard(function, exports, self.kernels, fallback, self.guards) if exports else None


# ---------------------------------------------------------------------------------------------
# guards: argument checks generated from the manifest's argument descriptions


#: NPY_ARRAY_* bits of ``ndarray.flags.num``; numba types an unaligned or read-only array differently
_C_CONTIGUOUS, _F_CONTIGUOUS, _ALIGNED, _WRITEABLE = 0x1, 0x2, 0x100, 0x400


_KINDS = {"float64": 0, "int64": 1, "bool": 2, "array": 3, "tuple": 4}  # kernel_guard.c's KIND_*


def guard_spec(description: dict) -> tuple:
    """``description`` as :file:`kernel_guard.c` reads it (its header comment)."""
    kind = description["kind"]
    if kind == "array":
        dtype = np.dtype(description["dtype"])
        return (_KINDS[kind], ord(dtype.kind), dtype.itemsize, description["ndim"], _required_flags(description))
    if kind == "tuple":
        return (_KINDS[kind], *(guard_spec(item) for item in description["items"]))
    return (_KINDS[kind],)


def _required_flags(description: dict) -> int:
    required = _ALIGNED | (_WRITEABLE if description["mutable"] else 0)
    return required | {"C": _C_CONTIGUOUS, "F": _F_CONTIGUOUS, "A": 0}[description["layout"]]


def guard(function: Callable, exports: list[dict], module: Any, fallback: Callable, guards: Any) -> Callable:
    """A ``kernel_guard.Guard``: calls the first export whose argument types match, else ``fallback``.

    ``exports``: the manifest's entries for ``function`` (``symbol``, ``arguments``);
    ``module``: the library's extension module; ``guards``: the compiled
    :file:`kernel_guard.c`. A call with keywords goes to ``fallback``. The guard keeps
    ``function`` as ``py_func`` (as numba's dispatchers do), and its name and docstring.
    """
    versions = tuple((tuple(guard_spec(d) for d in export["arguments"]), getattr(module, export["symbol"])) for export in exports)
    guarded = guards.Guard(versions, fallback)
    guarded.__name__, guarded.__qualname__, guarded.__module__ = function.__name__, function.__qualname__, function.__module__
    guarded.__doc__, guarded.py_func = function.__doc__, function
    return guarded
