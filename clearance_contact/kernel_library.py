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
are compiled into the library with it. :func:`build` writes the library and its
manifest into a folder; :func:`load` finds it fresh or returns None.

Safety: an exported function converts its arguments without checking them (a
float32 array crashes the process; a strided view is read as if contiguous). So an
export is only ever reached through a *guard*, generated here from the manifest's
argument descriptions, that checks every argument as numba's dispatcher would
(class, dtype, dimensions, layout, writeable, aligned; the scalars' types) and hands
any other call to numba's just-in-time compiler
(:func:`clearance_contact.compiled.switch_to_numba`): a call is never wrong, at worst
slower.

Freshness: the manifest records a digest of every source file in the folders of the
kernels' sources (the same files numba's cache is checked against:
:func:`clearance_contact.compiled.drop_stale_caches`), of the interpreter and of this
CPU (the library is compiled for the host CPU, like numba's JIT). A library whose
digest differs is not used; :func:`build` replaces it.
"""

from __future__ import annotations

import hashlib
import importlib.machinery
import importlib.util
import json
import os
import platform
import sys
import sysconfig
from pathlib import Path
from typing import Any, Callable

import numpy as np

__all__ = ["MANIFEST", "library_folder", "source_files", "digest", "is_fresh", "load", "guard", "build", "KernelLibraryError"]

MANIFEST = "manifest.json"
"""The manifest's file name in the library folder (written last: its presence completes a build)."""

FORMAT = 1
"""Manifest format; a manifest of another format is not read."""

ANCHOR = Path(__file__).resolve().parents[1]
"""Sources are recorded relative to this folder (the one holding ``clearance_contact`` and ``robot``)."""

GUARD_SOURCE = "kernel_guard.c"
"""The C version of the guards (beside this file), compiled with the library when a C compiler is there."""
"""Sources are recorded relative to this folder (the one holding ``clearance_contact`` and ``robot``)."""


class KernelLibraryError(RuntimeError):
    """The kernel library could not be built (numba.pycc or the C compiler failed); the message says why."""


def library_folder() -> Path:
    """Where the library lives: ``$CLEARANCE_KERNEL_DIR``, else ``clearance_contact/__pycache__/kernel_library``
    (beside numba's own cache of the same kernels)."""
    configured = os.environ.get("CLEARANCE_KERNEL_DIR")
    return Path(configured) if configured else Path(__file__).resolve().parent / "__pycache__" / "kernel_library"


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
    """sha256 of the files ``sources`` (relative to :data:`ANCHOR`), the interpreter and this CPU."""
    hasher = hashlib.sha256()
    for relative in sources:
        hasher.update(relative.encode() + b"\0")
        try:
            hasher.update((ANCHOR / relative).read_bytes())
        except OSError:  # a source went away: the digest cannot match
            hasher.update(b"missing")
    hasher.update(sys.version.encode() + (sysconfig.get_config_var("EXT_SUFFIX") or "").encode() + np.__version__.encode())
    hasher.update((Path(__file__).resolve().parent / GUARD_SOURCE).read_bytes())
    hasher.update(_cpu_identity().encode())
    return hasher.hexdigest()


def _read_manifest(folder: Path) -> dict | None:
    try:
        manifest = json.loads((folder / MANIFEST).read_text())
    except (OSError, ValueError):
        return None
    if not isinstance(manifest, dict) or manifest.get("format") != FORMAT:
        return None
    return manifest


def _fresh_manifest(folder: Path) -> dict | None:
    """The folder's manifest if its digest is that of today's sources, interpreter and CPU."""
    manifest = _read_manifest(folder)
    if manifest is None or manifest.get("digest") != digest(manifest.get("sources", [])):
        return None
    return manifest


def is_fresh(folder: Path | None = None) -> bool:
    """A library built from today's sources is in ``folder`` (default :func:`library_folder`); nothing is loaded."""
    return _fresh_manifest(library_folder() if folder is None else Path(folder)) is not None


def _import_extension(name: str, path: Path):
    loader = importlib.machinery.ExtensionFileLoader(name, str(path))
    module = importlib.util.module_from_spec(importlib.util.spec_from_file_location(name, path, loader=loader))
    loader.exec_module(module)
    return module


def load(folder: Path | None = None) -> Library | None:
    """The fresh library in ``folder`` (default :func:`library_folder`), else None.

    Fresh: its manifest's digest is that of today's sources, interpreter, numpy and
    CPU. Never raises: a missing, stale or unloadable library is None (the caller
    falls back to numba's just-in-time compilation).
    """
    folder = library_folder() if folder is None else Path(folder)
    manifest = _fresh_manifest(folder)
    if manifest is None:
        return None
    paths = [folder / manifest["filename"], folder / manifest["guard_filename"]]
    if not all(path.is_file() for path in paths):  # (an extension this process loaded before would still import)
        return None
    try:
        kernels = _import_extension(manifest["module"], paths[0])
        guards = _import_extension("kernel_guard", paths[1])
    except (ImportError, OSError):
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
    code = function.__code__
    if code.co_kwonlyargcount or code.co_flags & 0x0C:  # *args, **kwargs or keyword-only: not exported
        raise KernelLibraryError(f"{function.__qualname__}: an exported kernel takes positional parameters only")
    versions = tuple((tuple(guard_spec(d) for d in export["arguments"]), getattr(module, export["symbol"])) for export in exports)
    guarded = guards.Guard(versions, fallback)
    guarded.__name__, guarded.__qualname__, guarded.__module__ = function.__name__, function.__qualname__, function.__module__
    guarded.__doc__, guarded.py_func = function.__doc__, function
    return guarded


# ---------------------------------------------------------------------------------------------
# build (needs numba, numba.pycc and a C compiler; the run that uses the library needs none of them)


def describe(numba_type) -> dict:
    """The guard's description of one argument type of an exported signature."""
    from numba.core import types

    if isinstance(numba_type, types.Array):
        return {"kind": "array", "dtype": str(numba_type.dtype), "ndim": numba_type.ndim, "layout": numba_type.layout, "mutable": bool(numba_type.mutable)}
    if isinstance(numba_type, types.BaseTuple):
        return {"kind": "tuple", "items": [describe(item) for item in numba_type.types]}
    for kind in ("float64", "int64"):
        if numba_type == getattr(types, kind):
            return {"kind": kind}
    if numba_type == types.boolean:
        return {"kind": "bool"}
    raise KernelLibraryError(f"exported argument type {numba_type} is not supported (arrays, tuples of them, float64, int64, bool)")


def _locked(folder: Path):
    """An exclusive lock on ``folder`` (one build at a time; the others wait, then find it built)."""
    handle = open(folder / "build.lock", "a+")  # noqa: SIM115 (closed with the lock)
    try:
        import fcntl

        fcntl.flock(handle, fcntl.LOCK_EX)
    except ImportError:  # no fcntl (Windows): builds are not serialised
        pass
    return handle


def build(kernels: dict[str, tuple[Callable, tuple[str, ...]]], folder: Path | None = None, force: bool = False) -> Path:
    """Compile ``kernels`` (qualified name -> (numba dispatcher, exported signatures)) into ``folder``.

    Nothing is done when the folder already holds a fresh library (unless ``force``).
    The library is written under a temporary name and the manifest last, each
    atomically: a reader sees the old library, no library, or the new one. Returns
    the manifest's path. Raises :class:`KernelLibraryError` when numba.pycc or the C
    compiler fails.
    """
    import inspect
    import shutil
    import tempfile

    folder = library_folder() if folder is None else Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    sources = source_files(inspect.getsourcefile(dispatcher.py_func) for dispatcher, _ in kernels.values())
    with _locked(folder):
        current = digest(sources)
        manifest = _fresh_manifest(folder)
        if not force and manifest is not None and manifest["digest"] == current and load(folder) is not None:
            return folder / MANIFEST
        work = Path(tempfile.mkdtemp(dir=folder, prefix="build-"))
        try:
            module_name = f"clearance_kernels_{current[:16]}"
            guards = _compile_guards(work / "guards", f"kernel_guard_{current[:16]}")  # seconds; the kernels take 30
            exports = _compile(kernels, module_name, work)
            (built,) = work.glob(module_name + "*")
            for path in (built, guards):
                os.replace(path, folder / path.name)
            manifest = {
                "format": FORMAT, "digest": current, "module": module_name, "filename": built.name,
                "guard_filename": guards.name, "sources": sources, "exports": exports,
            }  # fmt: skip
            partial = folder / f"{MANIFEST}.{os.getpid()}"
            partial.write_text(json.dumps(manifest, indent=1))
            os.replace(partial, folder / MANIFEST)
        finally:
            shutil.rmtree(work, ignore_errors=True)
        for old in [*folder.glob("clearance_kernels_*"), *folder.glob("kernel_guard_*")]:
            if old.name not in (manifest["filename"], manifest["guard_filename"]):
                old.unlink(missing_ok=True)
    return folder / MANIFEST


def _compile(kernels: dict, module_name: str, output: Path) -> dict:
    """numba.pycc: one extension module with every signature of every kernel; the manifest's ``exports``."""
    try:
        from numba.core import sigutils
        from numba.pycc import CC
    except ImportError as exc:
        raise KernelLibraryError(f"numba.pycc is not available ({exc}); the kernels stay just-in-time compiled") from exc
    compiler = CC(module_name)
    compiler.output_dir, compiler.target_cpu, compiler.verbose = str(output), "host", False
    exports: dict[str, list[dict]] = {}
    for number, (qualified, (dispatcher, signatures)) in enumerate(sorted(kernels.items())):
        for k, signature in enumerate(signatures):
            arguments, _ = sigutils.normalize_signature(signature)
            symbol = f"k{number}_{k}_{dispatcher.py_func.__name__}"
            compiler.export(symbol, signature)(dispatcher.py_func)
            exports.setdefault(qualified, []).append({"symbol": symbol, "signature": signature, "arguments": [describe(a) for a in arguments]})
    try:
        compiler.compile()
    except Exception as exc:  # numba's typing errors, LLVM's, the C compiler's (distutils): all mean "no library"
        raise KernelLibraryError(f"compiling the kernel library failed: {type(exc).__name__}: {exc}") from exc
    return exports


def _compile_guards(output: Path, stem: str) -> Path:
    """Compile :file:`kernel_guard.c` (numba.pycc's toolchain: the C compiler and flags of this Python)."""
    from numba.pycc.platform import Toolchain

    output.mkdir()
    try:
        toolchain = Toolchain()
        objects = toolchain.compile_objects([str(Path(__file__).resolve().parent / GUARD_SOURCE)], str(output), include_dirs=toolchain.get_python_include_dirs())
        library = output / (stem + (sysconfig.get_config_var("EXT_SUFFIX") or ".so"))
        toolchain.link_shared(str(library), objects, toolchain.get_python_libraries(), toolchain.get_python_library_dirs())
    except Exception as exc:  # distutils' CompileError/LinkError, a missing compiler (RuntimeError)
        raise KernelLibraryError(f"compiling {GUARD_SOURCE} failed: {type(exc).__name__}: {exc}") from exc
    return library
