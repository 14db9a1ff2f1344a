"""How the kernels run: from the kernel library, numba's just-in-time compiler, or plain Python.

Why numba: the contact laws are short, branchy *scalar* float code (a few hundred
multiply-adds on 3-vectors per call).  Run as Python, every one of those operations is
an interpreted bytecode on a boxed float (6 us for the spherical joint, 16-30 us for the
revolute joint); numba compiles exactly the same source to machine code (LLVM), about
20x faster, with no hand-written C/C++ extension to build and maintain.  Numpy
vectorisation does not help here: the arrays are 3-vectors, and numpy's per-call
overhead is larger than the arithmetic.

Three ways to run the same source (:data:`KERNEL_MODE`), chosen once at import from the
environment variable ``CLEARANCE_CONTACT_JIT``:

* ``"library"`` (the default when it is fresh): the kernels declared with ``exports``
  come from the ahead-of-time kernel library (:mod:`clearance_contact.kernel_library`),
  each behind a guard that checks its arguments; numba is not imported. A call the
  library cannot take (other argument types, a kernel without ``exports``) switches
  the process to ``"numba"`` first (:func:`switch_to_numba`).
* ``"numba"`` (``CLEARANCE_CONTACT_JIT=numba``, or no fresh library): ``jit`` is
  ``numba.njit(cache=True)``.
* ``"python"`` (``CLEARANCE_CONTACT_JIT=0``, or numba not installed): ``jit`` is the
  identity and the *same* code runs as plain Python (slower, identical results to
  rounding).

Every mode keeps a kernel's Python version as ``.py_func``.

A ``jit``-decorated function is registered in :data:`KERNELS` (its source, its
exported signatures, what ``jit`` returned): what the library is built from and what
:func:`switch_to_numba` rebinds. :mod:`clearance_contact.compiled` re-exports this
module's names; read the mode there or here as ``module.KERNEL_MODE`` (it changes when
a process switches).
"""

from __future__ import annotations

import hashlib
import os
import sys
import warnings
from pathlib import Path
from typing import Callable

__all__ = [
    "jit", "JIT_ENABLED", "KERNEL_MODE", "SWITCHED_BY", "KERNELS", "Kernel", "KernelSwitchWarning", "switch_to_numba",
    "watch_numba_cache", "drop_stale_caches",
]  # fmt: skip


class KernelSwitchWarning(RuntimeWarning):
    """A call the kernel library has no compiled version of switched the process to numba's JIT (slower, same results)."""


class Kernel:
    """One ``jit``-decorated function: its Python source, exported signatures and what ``jit`` returned."""

    __slots__ = ("function", "exports", "compiled", "dispatcher")

    def __init__(self, function, exports: tuple[str, ...]) -> None:
        self.function = function
        self.exports = exports
        self.compiled = function  # what jit returned: a guard, a deferred call, a dispatcher or the function
        self.dispatcher = None  # numba's dispatcher, once the process runs numba


KERNELS: dict[str, Kernel] = {}
"""Every ``jit``-decorated function by qualified name (``module.qualname``): what the library is built from."""

KERNEL_MODE: str = "python"
"""``"library"``, ``"numba"`` or ``"python"`` (module docstring)."""

_numba = None
_LIBRARY = None  # the loaded kernel_library.Library in "library" mode


def jit(function=None, *, exports: tuple[str, ...] = ()):
    """Compile ``function`` the way :data:`KERNEL_MODE` says; ``@jit`` or ``@jit(exports=(signature, ...))``.

    ``exports``: numba signatures (``"i8(f8[::1], f8[:, ::1], f8)"``) of the calls Python
    makes to the function; the kernel library compiles one version per signature.
    Functions only other kernels call need none (they are compiled into their callers).
    """
    if function is None:
        return lambda decorated: jit(decorated, exports=exports)
    kernel = Kernel(function, tuple(exports))
    KERNELS[f"{function.__module__}.{function.__qualname__}"] = kernel
    if KERNEL_MODE == "numba":
        kernel.compiled = kernel.dispatcher = _numba.njit(cache=True)(function)
    elif KERNEL_MODE == "library":
        kernel.compiled = _library_entry(kernel)
    return kernel.compiled


def _library_entry(kernel: Kernel):
    """The guarded export of ``kernel`` from the library, or (not exported) a call that switches to numba first."""

    def call_numba(*arguments, **keywords):
        if kernel.dispatcher is None:
            switch_to_numba(f"{function.__module__}.{function.__qualname__}{_argument_types(arguments)}")
            if kernel.dispatcher is None:  # a kernel no longer in KERNELS (its module was reloaded)
                kernel.dispatcher = _start_numba()(kernel.function)
        return kernel.dispatcher(*arguments, **keywords)

    function = kernel.function
    guarded = _LIBRARY.entry(function, call_numba)
    if guarded is not None:
        return guarded
    call_numba.__name__, call_numba.__qualname__, call_numba.__doc__ = function.__name__, function.__qualname__, function.__doc__
    call_numba.__module__, call_numba.py_func = function.__module__, function
    return call_numba


def _argument_types(arguments) -> str:
    """``(float64[2d, F], int, ...)``: what a call passed, for :data:`SWITCHED_BY`."""

    def name(value) -> str:
        if hasattr(value, "dtype") and hasattr(value, "flags"):
            layout = "C" if value.flags.c_contiguous else "F" if value.flags.f_contiguous else "A"
            return f"{value.dtype}[{value.ndim}d, {layout}{'' if value.flags.writeable else ', readonly'}]"
        if isinstance(value, tuple):
            return "(" + ", ".join(name(item) for item in value) + ")"
        return type(value).__name__

    return "(" + ", ".join(name(value) for value in arguments) + ")"


SWITCHED_BY: str | None = None
"""The call that made a ``"library"`` process switch to numba (kernel and argument types), else None."""


def switch_to_numba(reason: str = "asked") -> None:
    """From here on, every kernel runs as numba's dispatcher (plain Python if numba is missing).

    Called on the first call the kernel library cannot take. Every module attribute
    that holds a kernel's guard or deferred call is rebound to the dispatcher, so that
    numba, compiling a caller, finds dispatchers among its globals; a reference kept
    elsewhere (a class attribute, a dict, ``from ... import``) keeps its object, whose
    calls then go to the dispatcher (a guard's ``fallback`` is set to it), so that
    identities (``LAW_IDS``) hold.
    """
    global KERNEL_MODE, SWITCHED_BY
    if KERNEL_MODE != "library":
        return
    SWITCHED_BY = reason
    warnings.warn(
        f"kernel library: no compiled version of {reason}; this process now runs numba's just-in-time kernels "
        "(the same results, ~0.5 s and ~130 MiB more; the kernel's `exports` can declare these types)",
        KernelSwitchWarning,
        stacklevel=3,
    )
    compile_ = _start_numba()
    replacements = {}
    for kernel in KERNELS.values():
        kernel.dispatcher = compile_(kernel.function)
        replacements[id(kernel.compiled)] = (kernel.compiled, kernel.dispatcher)
        if hasattr(kernel.compiled, "fallback"):  # a guard: what no export takes goes straight to the dispatcher
            kernel.compiled.fallback = kernel.dispatcher
    for module in list(sys.modules.values()):
        namespace = getattr(module, "__dict__", None)
        if not isinstance(namespace, dict):
            continue
        for name, value in list(namespace.items()):
            replacement = replacements.get(id(value))
            if replacement is not None and replacement[0] is value:
                namespace[name] = replacement[1]
    KERNEL_MODE = "numba" if _numba is not None else "python"


def __getattr__(name: str):
    """``JIT_ENABLED``: whether the kernels run compiled (``KERNEL_MODE`` is ``"library"`` or ``"numba"``)."""
    if name == "JIT_ENABLED":
        return KERNEL_MODE != "python"
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


_PACKAGE = Path(__file__).resolve().parent
# (sources, cache folder): numba's caches to drop when their sources change; the sources as a callable,
# listed only when numba starts (a library process never lists nor hashes them)
_WATCHED_CACHES: list[tuple[Callable[[], list], Path]] = [(lambda: list(_PACKAGE.glob("*.py")), _PACKAGE / "__pycache__")]


def watch_numba_cache(sources: Callable[[], list], cache_directory) -> None:
    """Have numba's cache in ``cache_directory`` dropped if the files ``sources()`` lists changed
    (:func:`drop_stale_caches`): now if numba runs, else when it starts."""
    _WATCHED_CACHES.append((sources, Path(cache_directory)))
    if KERNEL_MODE == "numba":
        drop_stale_caches(sources(), cache_directory)


def _start_numba():
    """Import numba (drop its stale caches); the decorator to use: ``njit(cache=True)``, or the identity without numba."""
    global _numba
    try:
        import numba
    except ImportError:  # numba not installed (or blocked): plain Python
        return _identity
    _numba = numba
    for sources, folder in _WATCHED_CACHES:
        drop_stale_caches(sources(), folder)
    return numba.njit(cache=True)


def write_text_atomically(path: Path, text: str) -> None:
    """Write ``text`` to ``path`` through a temporary file and a rename (readers never see a partial file;
    the temporary file is removed if the write fails)."""
    partial = path.with_name(f"{path.name}.{os.getpid()}")
    try:
        partial.write_text(text)
        os.replace(partial, path)
    except BaseException:
        partial.unlink(missing_ok=True)
        raise


def _identity(function):
    return function


def drop_stale_caches(sources, cache_directory) -> bool:
    """Delete numba's cache files in ``cache_directory`` if any file of ``sources`` changed.

    numba keys a cached function on its own source file only: a compiled function
    that calls a law kernel defined in another file keeps its old machine code
    when that file changes. So a package whose compiled code spans files keeps a
    digest of all of them (``numba_sources.sha256`` in the cache folder) and drops
    every ``*.nbi``/``*.nbc`` there when it differs; they are compiled again on
    first use. Returns True if it dropped them. A folder it cannot write is left
    alone (numba then caches elsewhere or not at all).
    """
    digest = hashlib.sha256()
    for source in sorted(Path(p) for p in sources):
        digest.update(source.name.encode())
        digest.update(source.read_bytes())
    folder = Path(cache_directory)
    stamp = folder / "numba_sources.sha256"
    try:
        if stamp.is_file() and stamp.read_text() == digest.hexdigest():
            return False
        folder.mkdir(parents=True, exist_ok=True)
        for cached in list(folder.glob("*.nbi")) + list(folder.glob("*.nbc")):
            cached.unlink(missing_ok=True)
        write_text_atomically(stamp, digest.hexdigest())
    except OSError:
        return False
    return True


def _choose_mode() -> None:
    """Set :data:`KERNEL_MODE` from ``CLEARANCE_CONTACT_JIT``, the library's freshness and numba's presence."""
    global KERNEL_MODE, _LIBRARY
    from clearance_contact import kernel_library

    requested = kernel_library.requested_mode()
    if requested == "python":
        return
    if requested == "library":
        _LIBRARY = kernel_library.load()
    if _LIBRARY is not None:
        KERNEL_MODE = "library"
    elif _start_numba() is not _identity:
        KERNEL_MODE = "numba"


_choose_mode()
