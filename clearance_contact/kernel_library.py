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
(:func:`clearance_contact.kernel_mode.switch_to_numba`): a call is never wrong, at worst
slower.

Freshness: the manifest records a digest of every source file in the folders of the
kernels' sources (the same files numba's cache is checked against:
:func:`clearance_contact.kernel_mode.drop_stale_caches`), of the interpreter and of this
CPU (the library is compiled for the host CPU, like numba's JIT). A library whose
digest differs is not used; :func:`build` replaces it.
"""

from __future__ import annotations

import contextlib
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

__all__ = ["MANIFEST", "library_folder", "source_files", "digest", "is_fresh", "import_extension", "load", "guard", "build", "KernelLibraryError"]

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

#: numba settings that change the code it generates (its optimisation level, bounds checks, target CPU)
_NUMBA_SETTINGS = ("NUMBA_OPT", "NUMBA_BOUNDSCHECK", "NUMBA_CPU_NAME", "NUMBA_CPU_FEATURES", "NUMBA_FASTMATH")


class KernelLibraryError(RuntimeError):
    """The kernel library could not be built (numba.pycc or the C compiler failed); the message says why."""


def library_folder() -> Path:
    """Where this environment's library lives: ``$CLEARANCE_KERNEL_DIR`` as given, else a folder named by
    :func:`environment_key` under ``clearance_contact/__pycache__/kernel_library`` (beside numba's own cache
    of the same kernels; under ``$XDG_CACHE_HOME``/``~/.cache`` when the package's folder is read-only).

    One folder per environment: virtual environments, interpreters or machines sharing a
    checkout keep their own libraries instead of rebuilding each other's.
    """
    configured = os.environ.get("CLEARANCE_KERNEL_DIR")
    if configured:
        return Path(configured)
    package = Path(__file__).resolve().parent
    base = package / "__pycache__" / "kernel_library"
    if not os.access(base if base.is_dir() else package, os.W_OK):
        base = Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "clearance" / "kernel_library"
    return base / environment_key()[:16]


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


def environment_key() -> str:
    """sha256 of what the compiled code depends on besides the sources: interpreter, numpy, numba and
    llvmlite, numba's code-generation settings, this CPU (the library is compiled for the host CPU)."""
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


def _read_record(path: Path) -> dict | None:
    """A manifest or failure record of this format with its ``digest`` and ``sources``, else None."""
    try:
        record = json.loads(path.read_text())
    except (OSError, ValueError):
        return None
    if not isinstance(record, dict) or record.get("format") != FORMAT or not isinstance(record.get("sources"), list):
        return None
    return record


def _fresh_record(path: Path) -> dict | None:
    """The record at ``path`` if its digest is that of today's sources and environment."""
    record = _read_record(path)
    if record is None or record.get("digest") != digest(record["sources"]):
        return None
    return record


def _fresh_manifest(folder: Path) -> dict | None:
    return _fresh_record(folder / MANIFEST)


def failed_build(folder: Path | None = None) -> str | None:
    """Why the last build in ``folder`` failed, if it was tried on today's sources and environment; else None."""
    record = _fresh_record((library_folder() if folder is None else Path(folder)) / FAILURE)
    return None if record is None else str(record.get("reason", "unknown"))


def is_fresh(folder: Path | None = None) -> bool:
    """A library built from today's sources is in ``folder`` (default :func:`library_folder`); nothing is loaded."""
    return _fresh_manifest(library_folder() if folder is None else Path(folder)) is not None


def import_extension(name: str, path: Path):
    """Import the extension module file ``path`` as ``name`` (not entered in ``sys.modules``)."""
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
    try:
        paths = [folder / manifest["filename"], folder / manifest["guard_filename"]]
        if not all(path.is_file() for path in paths):  # (an extension this process loaded before would still import)
            return None
        kernels = import_extension(manifest["module"], paths[0])
        guards = import_extension("kernel_guard", paths[1])
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

    Every kernel of the process goes in ``kernels``: those with signatures are
    exported, and all of them name the sources the digest covers (a kernel without
    exports is compiled into its callers). Nothing is done when the folder already
    holds a fresh library (unless ``force``). The library is written under a temporary
    name and the manifest last, each atomically: a reader sees the old library, no
    library, or the new one. Returns the manifest's path. Raises
    :class:`KernelLibraryError` when numba.pycc or the C compiler fails, after recording
    why (:func:`failed_build`).
    """
    import inspect

    folder = library_folder() if folder is None else Path(folder)
    try:
        sources = source_files(inspect.getsourcefile(dispatcher.py_func) for dispatcher, _ in kernels.values())
    except ValueError as exc:  # a kernel outside the packages
        raise KernelLibraryError(f"a kernel's source is outside {ANCHOR}: {exc}") from exc
    folder.mkdir(parents=True, exist_ok=True)
    with _locked(folder):
        current = digest(sources)
        manifest = _fresh_manifest(folder)
        if not force and manifest is not None and manifest["digest"] == current and load(folder) is not None:
            return folder / MANIFEST
        try:
            manifest = _build_into(folder, {name: entry for name, entry in kernels.items() if entry[1]}, current)
        except KernelLibraryError as exc:
            _write_json(folder / FAILURE, {"format": FORMAT, "digest": current, "sources": sources, "reason": " ".join(str(exc).split())})
            raise
        _write_json(folder / MANIFEST, dict(manifest, sources=sources))
        (folder / FAILURE).unlink(missing_ok=True)
        for old in [*folder.glob("clearance_kernels_*"), *folder.glob("kernel_guard_*")]:
            if old.name not in (manifest["filename"], manifest["guard_filename"]):
                old.unlink(missing_ok=True)
    return folder / MANIFEST


def _build_into(folder: Path, exported: dict, current: str) -> dict:
    """Compile the guards and the exports in a scratch folder, move both into ``folder``; the manifest (no sources)."""
    import shutil
    import tempfile

    work = Path(tempfile.mkdtemp(dir=folder, prefix="build-"))
    try:
        module_name = f"clearance_kernels_{current[:16]}"
        guards = _compile_guards(work / "guards", f"kernel_guard_{current[:16]}")  # seconds; the kernels take 15-40
        exports = _compile(exported, module_name, work)
        (built,) = work.glob(module_name + "*")
        for path in (built, guards):
            os.replace(path, folder / path.name)
    finally:
        shutil.rmtree(work, ignore_errors=True)
    return {"format": FORMAT, "digest": current, "module": module_name, "filename": built.name, "guard_filename": guards.name, "exports": exports}


def _write_json(path: Path, record: dict) -> None:
    """Write ``record`` to ``path`` atomically (a temporary file, then a rename)."""
    partial = path.with_name(f"{path.name}.{os.getpid()}")
    partial.write_text(json.dumps(record, indent=1))
    os.replace(partial, path)


def _compile(kernels: dict, module_name: str, output: Path) -> dict:
    """numba.pycc: one extension module with every signature of every kernel; the manifest's ``exports``."""
    import inspect

    try:
        from numba.core import sigutils
        from numba.pycc import CC
    except ImportError as exc:
        raise KernelLibraryError(f"numba.pycc is not available ({exc}); the kernels stay just-in-time compiled") from exc
    compiler = CC(module_name)
    compiler.output_dir, compiler.target_cpu, compiler.verbose = str(output), "host", False
    exports: dict[str, list[dict]] = {}
    for number, (qualified, (dispatcher, signatures)) in enumerate(sorted(kernels.items())):
        code = dispatcher.py_func.__code__
        if code.co_kwonlyargcount or code.co_flags & (inspect.CO_VARARGS | inspect.CO_VARKEYWORDS):
            raise KernelLibraryError(f"{qualified}: an exported kernel takes positional parameters only")
        for k, signature in enumerate(signatures):
            arguments, _ = sigutils.normalize_signature(signature)
            symbol = f"k{number}_{k}_{dispatcher.py_func.__name__}"
            compiler.export(symbol, signature)(dispatcher.py_func)
            exports.setdefault(qualified, []).append({"symbol": symbol, "signature": signature, "arguments": [describe(a) for a in arguments]})
    try:
        with _host_cpu_features():
            compiler.compile()
    except Exception as exc:  # numba's typing errors, LLVM's, the C compiler's (distutils): all mean "no library"
        raise KernelLibraryError(f"compiling the kernel library failed: {type(exc).__name__}: {exc}") from exc
    return exports


@contextlib.contextmanager
def _host_cpu_features():
    """Compile for the features this CPU reports, as numba's JIT does.

    numba.pycc's "host" target names the CPU model only and lets LLVM assume every
    feature of that model; a virtual machine that hides some (AVX-512 on a server
    model, say) would then run instructions it lacks. numba's JIT passes the features
    LLVM detects (or ``NUMBA_CPU_FEATURES``): the same here, so the library's code is
    the JIT's.
    """
    from numba.core.codegen import AOTCPUCodegen

    original = AOTCPUCodegen._customize_tm_features
    AOTCPUCodegen._customize_tm_features = lambda codegen: codegen._get_host_cpu_features()
    try:
        yield
    finally:
        AOTCPUCodegen._customize_tm_features = original


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
