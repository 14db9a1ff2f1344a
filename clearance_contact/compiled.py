"""Compilation of the kernels (numba: ahead of time in the kernel library, or just in time), and their status codes.

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

The kernels (``SphericalClearanceJoint.kernel``, ``RevoluteClearanceJoint.kernel``, their
``penetration_kernel``) return an int status instead of raising (numba cannot raise
exceptions with formatted messages): ``STATUS_OK`` or one of the codes below; the
joints' ``evaluate`` / ``penetration`` turn a nonzero status into
:class:`~clearance_contact.errors.ContactError` with an informative message.
"""

from __future__ import annotations

import hashlib
import math
import os
import sys
from pathlib import Path

__all__ = [
    "jit",
    "JIT_ENABLED",
    "KERNEL_MODE",
    "KERNELS",
    "Kernel",
    "switch_to_numba",
    "watch_numba_cache",
    "drop_stale_caches",
    "STATUS_OK",
    "STATUS_NONFINITE_INPUT",
    "STATUS_NONFINITE_PENETRATION",
    "STATUS_AXIS_TILT",
    "STATUS_EXTERNAL_FRICTION",
    "STATUS_MESSAGES",
]

STATUS_OK: int = 0
"""The kernel's output is complete and valid."""
STATUS_NONFINITE_INPUT: int = 1
"""A pose, twist or onset rate is NaN or infinite (nothing useful was written)."""
STATUS_NONFINITE_PENETRATION: int = 2
"""A penetration came out non-finite (e.g. overflow of huge but finite poses)."""
STATUS_AXIS_TILT: int = 3
"""Revolute joint: journal axis at >= 90 deg (within 1e-6 in cosine) from the bearing axis."""
STATUS_EXTERNAL_FRICTION: int = 4
"""The joint's friction law is a user-defined ``FrictionLaw`` that compiled code cannot
call: everything but friction was written (``friction_force`` holds the slip velocities,
the wrenches are incomplete); ``evaluate`` finishes the job in Python."""

STATUS_MESSAGES: dict[int, str] = {
    STATUS_OK: "ok",
    STATUS_NONFINITE_INPUT: "non-finite input (NaN or inf in a pose, twist or onset rate)",
    STATUS_NONFINITE_PENETRATION: "non-finite penetration",
    STATUS_AXIS_TILT: "journal axis tilted by 90 deg or more from the bearing axis",
    STATUS_EXTERNAL_FRICTION: "user-defined friction law: friction not applied by the kernel",
}


class Kernel:
    """One ``jit``-decorated function: its Python source, exported signatures and what ``jit`` returned."""

    __slots__ = ("function", "exports", "compiled", "dispatcher")

    def __init__(self, function, exports: tuple[str, ...]) -> None:
        self.function = function
        self.exports = exports
        self.compiled = function  # what the module holds: a guard, a deferred call, a dispatcher or the function
        self.dispatcher = None  # numba's dispatcher, once the process runs numba


KERNELS: dict[str, Kernel] = {}
"""Every ``jit``-decorated function by qualified name (``module.qualname``): what the library is built from."""

KERNEL_MODE: str = "python"
"""``"library"``, ``"numba"`` or ``"python"`` (module docstring)."""

JIT_ENABLED: bool = False
"""True when the kernels run compiled (``KERNEL_MODE`` is ``"library"`` or ``"numba"``)."""

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
    elsewhere (a class attribute, ``from ... import``) still works: the guard hands
    such calls on.
    """
    global KERNEL_MODE, SWITCHED_BY
    if KERNEL_MODE != "library":
        return
    SWITCHED_BY = reason
    compile_ = _start_numba()
    replacements = {}
    for kernel in KERNELS.values():
        kernel.dispatcher = compile_(kernel.function)
        replacements[id(kernel.compiled)] = (kernel.compiled, kernel.dispatcher)
    for module in list(sys.modules.values()):
        namespace = getattr(module, "__dict__", None)
        if not isinstance(namespace, dict):
            continue
        for name, value in list(namespace.items()):
            replacement = replacements.get(id(value))
            if replacement is not None and replacement[0] is value:
                namespace[name] = replacement[1]
    KERNEL_MODE = "numba" if _numba is not None else "python"


_WATCHED_CACHES: list[tuple[list, Path]] = []


def watch_numba_cache(sources, cache_directory) -> None:
    """Have numba's cache in ``cache_directory`` dropped if ``sources`` changed (:func:`drop_stale_caches`):
    now if numba runs, else when it starts (a library process never hashes them)."""
    _WATCHED_CACHES.append((list(sources), Path(cache_directory)))
    if KERNEL_MODE == "numba":
        drop_stale_caches(*_WATCHED_CACHES[-1])


def _start_numba():
    """Import numba (drop its stale caches); the decorator to use: ``njit(cache=True)``, or the identity without numba."""
    global _numba
    try:
        import numba
    except ImportError:  # numba not installed (or blocked): plain Python
        return _identity
    _numba = numba
    package = Path(__file__).resolve().parent
    for sources, folder in [(list(package.glob("*.py")), package / "__pycache__"), *_WATCHED_CACHES]:
        drop_stale_caches(sources, folder)
    return numba.njit(cache=True)


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
        partial = folder / f"numba_sources.sha256.{os.getpid()}"
        partial.write_text(digest.hexdigest())
        os.replace(partial, stamp)
    except OSError:
        return False
    return True


def _choose_mode() -> None:
    """Set :data:`KERNEL_MODE` from ``CLEARANCE_CONTACT_JIT``, the library's freshness and numba's presence."""
    global KERNEL_MODE, JIT_ENABLED, _LIBRARY
    setting = os.environ.get("CLEARANCE_CONTACT_JIT", "1")
    if setting == "0":
        return
    if setting != "numba":
        from clearance_contact import kernel_library

        _LIBRARY = kernel_library.load()
    if _LIBRARY is not None:
        KERNEL_MODE = "library"
    elif _start_numba() is not _identity:
        KERNEL_MODE = "numba"
    JIT_ENABLED = KERNEL_MODE != "python"


_choose_mode()


class KernelAttribute:
    """Class attribute holding a law's compiled kernel (a descriptor).

    ``Law.kernel`` (on the class) is always the kernel function.  ``law.kernel`` (on
    an instance) is the same function, or ``None`` when the instance's friction law is
    user-defined (``law.friction_in_kernel`` False): the kernel alone cannot apply it
    (it returns ``STATUS_EXTERNAL_FRICTION``), so compiled callers must use
    ``law.evaluate`` for that law.
    """

    __slots__ = ("function",)

    def __init__(self, function) -> None:
        self.function = function

    def __get__(self, instance, owner=None):
        if instance is None or instance.friction_in_kernel:
            return self.function
        return None


@jit
def finite_state(outer_rotation, outer_position, outer_twist, inner_rotation, inner_position, inner_twist, onset_rates):
    """True if every value of a joint state (the kernels' inputs) is finite."""
    for i in range(3):
        for j in range(3):
            if not (math.isfinite(outer_rotation[i, j]) and math.isfinite(inner_rotation[i, j])):
                return False
        if not (math.isfinite(outer_position[i]) and math.isfinite(inner_position[i])):
            return False
    for i in range(6):
        if not (math.isfinite(outer_twist[i]) and math.isfinite(inner_twist[i])):
            return False
    for i in range(onset_rates.shape[0]):
        if not math.isfinite(onset_rates[i]):
            return False
    return True


_DBL_MIN = 2.2250738585072014e-308
"""Smallest normal float64."""


@jit
def _two_product(x: float, y: float) -> tuple[float, float]:
    """(x y rounded, exact error) by Dekker's splitting (no FMA needed; |x|, |y| < 1e150)."""
    p = x * y
    c = 134217729.0 * x  # 2^27 + 1
    xh = c - (c - x)
    xl = x - xh
    c = 134217729.0 * y
    yh = c - (c - y)
    yl = y - yh
    return p, ((xh * yh - p) + xh * yl + xl * yh) + xl * yl


@jit
def _norm_scaled(a: float, b: float, c: float, largest: float) -> float:
    # CPython's vector_norm (Modules/mathmodule.c, 3.10+): squares of the inputs scaled to
    # [0.5, 1) by a power of two, summed with exact error terms, a square root and one
    # differential correction: correctly rounded in all but rare cases.
    max_e = math.frexp(largest)[1]
    scale = math.ldexp(1.0, -max_e)
    csum = 1.0
    frac1 = 0.0
    frac2 = 0.0
    for x in (a, b, c):
        x *= scale
        hi, lo = _two_product(x, x)
        total = csum + hi  # |csum| >= |hi|: fast two-sum
        frac2 += (csum - total) + hi
        csum = total
        frac1 += lo
    h = math.sqrt(csum - 1.0 + (frac1 + frac2))
    hi, lo = _two_product(-h, h)
    total = csum + hi
    frac2 += (csum - total) + hi
    csum = total
    frac1 += lo
    x = csum - 1.0 + (frac1 + frac2)
    h += x / (2.0 * h)
    return h / scale


@jit
def norm3(x: float, y: float, z: float) -> float:
    """Euclidean norm sqrt(x^2 + y^2 + z^2), as CPython's ``math.hypot(x, y, z)`` computes it.

    The same algorithm as CPython's (so compiled and plain-Python runs, and this code and
    the earlier pure-Python laws, agree to the last bit: penetrations are differences of
    nearly equal lengths, where one ulp of |e| is 1e-12 of delta, and adaptive
    integrators amplify such differences).  Nearly correctly rounded; no overflow or
    underflow.
    """
    ax = abs(x)
    ay = abs(y)
    az = abs(z)
    largest = max(ax, ay, az)
    if not math.isfinite(largest):
        return math.inf if (math.isinf(ax) or math.isinf(ay) or math.isinf(az)) else math.nan
    if largest == 0.0:
        return 0.0
    if largest < _DBL_MIN:  # subnormals: rescaled to normal numbers first (as CPython)
        return _DBL_MIN * _norm_scaled(ax / _DBL_MIN, ay / _DBL_MIN, az / _DBL_MIN, largest / _DBL_MIN)
    return _norm_scaled(ax, ay, az, largest)


@jit
def norm2(x: float, y: float) -> float:
    """sqrt(x^2 + y^2) as CPython's ``math.hypot(x, y)`` (see :func:`norm3`)."""
    ax = abs(x)
    ay = abs(y)
    largest = max(ax, ay)
    if not math.isfinite(largest):
        return math.inf if (math.isinf(ax) or math.isinf(ay)) else math.nan
    if largest == 0.0:
        return 0.0
    if largest < _DBL_MIN:
        return _DBL_MIN * _norm_scaled(ax / _DBL_MIN, ay / _DBL_MIN, 0.0, largest / _DBL_MIN)
    return _norm_scaled(ax, ay, 0.0, largest)
