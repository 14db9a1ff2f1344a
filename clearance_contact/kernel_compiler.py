"""Building the kernel library (:mod:`clearance_contact.kernel_library`): numba.pycc, the guards' C, the manifest.

Needs numba, numba.pycc and a C and a C++ compiler with the Python headers (numba's
toolchain checks both); a run that uses the library needs none of them. The build
goes into one folder per environment (:func:`~clearance_contact.kernel_library.library_folder`),
under a lock, writes the extension modules under temporary names and the manifest
last, atomically; a failure is recorded there with its reason, the sources' digest
and the compilers found (:func:`~clearance_contact.kernel_library.failed_build`), so
that commands do not try again until one of them changes.
"""

from __future__ import annotations

import contextlib
import inspect
import json
import os
import shutil
import sysconfig
import tempfile
from pathlib import Path
from typing import Callable

from clearance_contact.kernel_library import (
    ANCHOR,
    FAILURE,
    FORMAT,
    GUARD_SOURCE,
    MANIFEST,
    KernelLibraryError,
    digest,
    fresh_record,
    library_folder,
    load,
    source_files,
    toolchain,
)
from clearance_contact.kernel_mode import write_text_atomically

__all__ = ["build", "describe"]


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
    why (:func:`~clearance_contact.kernel_library.failed_build`).
    """
    folder = library_folder() if folder is None else Path(folder)
    try:
        sources = source_files(inspect.getsourcefile(dispatcher.py_func) for dispatcher, _ in kernels.values())
    except ValueError as exc:  # a kernel outside the packages
        raise KernelLibraryError(f"a kernel's source is outside {ANCHOR}: {exc}") from exc
    folder.mkdir(parents=True, exist_ok=True)
    with _locked(folder):
        current = digest(sources)
        manifest = fresh_record(folder / MANIFEST)
        if not force and manifest is not None and manifest["digest"] == current and load(folder) is not None:
            return folder / MANIFEST
        try:
            manifest = _build_into(folder, {name: entry for name, entry in kernels.items() if entry[1]}, current)
        except KernelLibraryError as exc:
            reason = " ".join(str(exc).split())
            _write_json(folder / FAILURE, {"format": FORMAT, "digest": current, "sources": sources, "toolchain": toolchain(), "reason": reason})
            raise
        _write_json(folder / MANIFEST, dict(manifest, sources=sources))
        (folder / FAILURE).unlink(missing_ok=True)
        for old in [*folder.glob("clearance_kernels_*"), *folder.glob("kernel_guard_*")]:
            if old.name not in (manifest["filename"], manifest["guard_filename"]):
                old.unlink(missing_ok=True)
    return folder / MANIFEST


def _build_into(folder: Path, exported: dict, current: str) -> dict:
    """Compile the guards and the exports in a scratch folder, move both into ``folder``; the manifest (no sources)."""
    work = Path(tempfile.mkdtemp(dir=folder, prefix="build-"))
    try:
        module_name = f"clearance_kernels_{current[:16]}"
        guards = _compile_guards(work / "guards", f"kernel_guard_{current[:16]}")  # seconds; the kernels take 15-40
        exports = _compile(exported, module_name, work)
        built = next(work.glob(module_name + "*"), None)
        if built is None:
            raise KernelLibraryError(f"numba.pycc wrote no {module_name} extension module in {work}")
        for path in (built, guards):
            os.replace(path, folder / path.name)
    finally:
        shutil.rmtree(work, ignore_errors=True)
    return {"format": FORMAT, "digest": current, "module": module_name, "filename": built.name, "guard_filename": guards.name, "exports": exports}


def _write_json(path: Path, record: dict) -> None:
    """Write ``record`` to ``path`` atomically (:func:`~.kernel_mode.write_text_atomically`)."""
    write_text_atomically(path, json.dumps(record, indent=1))


def _compile(kernels: dict, module_name: str, output: Path) -> dict:
    """numba.pycc: one extension module with every signature of every kernel; the manifest's ``exports``.

    Any failure (numba.pycc missing, a signature numba rejects, typing, LLVM, the C
    compiler) raises :class:`KernelLibraryError` with its cause.
    """
    try:
        from numba.core import sigutils
        from numba.pycc import CC

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
        with _host_cpu_features():
            compiler.compile()
    except KernelLibraryError:
        raise
    except Exception as exc:  # ImportError (no numba.pycc), numba's typing errors, LLVM's, the C compiler's
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
    """Compile :file:`kernel_guard.c` (numba.pycc's toolchain: the compilers and flags of this Python)."""
    output.mkdir()
    try:
        from numba.pycc.platform import Toolchain, external_compiler_works

        if not external_compiler_works():  # numba's own check: a C and a C++ compiler (its message suggests conda)
            raise KernelLibraryError(f"no working C and C++ compilers ({toolchain()}): install gcc and g++ (or set CC/CXX) and the Python headers")
        compilers = Toolchain()
        source = str(Path(__file__).resolve().parent / GUARD_SOURCE)
        objects = compilers.compile_objects([source], str(output), include_dirs=compilers.get_python_include_dirs())
        library = output / (stem + (sysconfig.get_config_var("EXT_SUFFIX") or ".so"))
        compilers.link_shared(str(library), objects, compilers.get_python_libraries(), compilers.get_python_library_dirs())
    except KernelLibraryError:
        raise
    except Exception as exc:  # ImportError (no numba.pycc), distutils' CompileError/LinkError
        raise KernelLibraryError(f"compiling {GUARD_SOURCE} failed: {type(exc).__name__}: {exc}") from exc
    return library
