"""SUNDIALS CVODE driven through its C interface (``ctypes``): one internal step per call, interpolation, counts.

The simulator steps CVODE one internal step at a time (``CV_ONE_STEP`` with a
stop time at the end of the span) and reads its interpolant (``CVodeGetDky``)
for output times and event location. scikit-sundae's binding does the same
through ``CVODE.step``, but each call builds a result object, sets and clears
the stop time and copies the state, ~10 us of Python per step, more than
CVODE's own work on this problem size; and an interpolation through
``step(t, "normal")`` makes the next one-step call return the current state
(a wasted call). :class:`DirectCVODE` calls the library scikit-sundae ships
(``scikit_sundae.libs``) directly, with exactly the options scikit-sundae sets
(BDF order 5 or Adams order 12, dense direct linear solver, at most 3 Newton
iterations and 10 convergence failures per step, scalar tolerances, first /
minimum / maximum step, maximum number of steps): the same library with the
same options takes the same steps (``tests/test_cvode_direct.py`` compares both
step by step). The right-hand side and the Jacobian are Python callables called
back from C; an exception raised in them stops ``CVode`` (an unrecoverable
callback failure) and is raised again from :meth:`DirectCVODE.one_step`.

:func:`available` says whether the libraries were found (otherwise
:mod:`robot.integration.solvers` keeps scikit-sundae's binding).
"""

from __future__ import annotations

import ctypes
import functools
import importlib.util
from pathlib import Path
from typing import Callable

import numpy as np

CV_ADAMS, CV_BDF = 1, 2
CV_NORMAL, CV_ONE_STEP = 1, 2
#: CVODE's return flags that mean the step size collapsed (error or convergence test failures at the minimum step)
STEP_SIZE_FLAGS = (-3, -4)
MESSAGES = {
    -1: "could not reach the end point within max_num_steps",
    -2: "could not satisfy the demanded accuracy for an internal step",
    -3: "error tests failed too many times, or the minimum step size was reached",
    -4: "convergence tests failed too many times, or the minimum step size was reached",
    -5: "the linear solver's initialisation failed",
    -6: "the linear solver's setup failed unrecoverably",
    -7: "the linear solver's solve failed unrecoverably",
    -8: "the right-hand side failed unrecoverably",
    -9: "the right-hand side failed at the first call",
    -10: "the right-hand side had repeated recoverable errors",
    -11: "the right-hand side had a recoverable error the solver cannot recover from",
    -16: "the nonlinear solver failed unrecoverably",
    -25: "the time is not within the last step interval",
}

_real, _index, _pointer = ctypes.c_double, ctypes.c_int64, ctypes.c_void_p
_RHS = ctypes.CFUNCTYPE(ctypes.c_int, _real, _pointer, _pointer, _pointer)
_JACOBIAN = ctypes.CFUNCTYPE(ctypes.c_int, _real, _pointer, _pointer, _pointer, _pointer, _pointer, _pointer, _pointer)


class _Library:
    """The SUNDIALS functions used, with their C signatures (SUNDIALS 7, double precision, 64-bit indices)."""

    def __init__(self, folder: Path):
        def load(stem: str) -> ctypes.CDLL:
            (path,) = sorted(folder.glob(f"libsundials_{stem}-*.so*"))[-1:]
            return ctypes.CDLL(str(path))

        core, cvode, nvec = load("core"), load("cvode"), load("nvecserial")
        matrix, linear = load("sunmatrixdense"), load("sunlinsoldense")
        signatures = {
            (core, "SUNContext_Create"): (ctypes.c_int, [ctypes.c_int, ctypes.POINTER(_pointer)]),
            (core, "SUNContext_Free"): (ctypes.c_int, [ctypes.POINTER(_pointer)]),
            (core, "SUNContext_ClearErrHandlers"): (ctypes.c_int, [_pointer]),
            (nvec, "N_VNew_Serial"): (_pointer, [_index, _pointer]),
            (nvec, "N_VGetArrayPointer"): (ctypes.POINTER(_real), [_pointer]),
            (core, "N_VDestroy"): (None, [_pointer]),
            (matrix, "SUNDenseMatrix"): (_pointer, [_index, _index, _pointer]),
            (matrix, "SUNDenseMatrix_Data"): (ctypes.POINTER(_real), [_pointer]),
            (core, "SUNMatDestroy"): (None, [_pointer]),
            (linear, "SUNLinSol_Dense"): (_pointer, [_pointer, _pointer, _pointer]),
            (core, "SUNLinSolFree"): (ctypes.c_int, [_pointer]),
            (cvode, "CVodeCreate"): (_pointer, [ctypes.c_int, _pointer]),
            (cvode, "CVodeInit"): (ctypes.c_int, [_pointer, _RHS, _real, _pointer]),
            (cvode, "CVodeSStolerances"): (ctypes.c_int, [_pointer, _real, _real]),
            (cvode, "CVodeSetLinearSolver"): (ctypes.c_int, [_pointer, _pointer, _pointer]),
            (cvode, "CVodeSetJacFn"): (ctypes.c_int, [_pointer, _JACOBIAN]),
            (cvode, "CVodeSetMaxNonlinIters"): (ctypes.c_int, [_pointer, ctypes.c_int]),
            (cvode, "CVodeSetMaxConvFails"): (ctypes.c_int, [_pointer, ctypes.c_int]),
            (cvode, "CVodeSetInitStep"): (ctypes.c_int, [_pointer, _real]),
            (cvode, "CVodeSetMinStep"): (ctypes.c_int, [_pointer, _real]),
            (cvode, "CVodeSetMaxStep"): (ctypes.c_int, [_pointer, _real]),
            (cvode, "CVodeSetMaxOrd"): (ctypes.c_int, [_pointer, ctypes.c_int]),
            (cvode, "CVodeSetMaxNumSteps"): (ctypes.c_int, [_pointer, ctypes.c_long]),
            (cvode, "CVodeSetStopTime"): (ctypes.c_int, [_pointer, _real]),
            (cvode, "CVode"): (ctypes.c_int, [_pointer, _real, _pointer, ctypes.POINTER(_real), ctypes.c_int]),
            (cvode, "CVodeGetDky"): (ctypes.c_int, [_pointer, _real, ctypes.c_int, _pointer]),
            (cvode, "CVodeGetNumRhsEvals"): (ctypes.c_int, [_pointer, ctypes.POINTER(ctypes.c_long)]),
            (cvode, "CVodeGetNumJacEvals"): (ctypes.c_int, [_pointer, ctypes.POINTER(ctypes.c_long)]),
            (cvode, "CVodeFree"): (None, [ctypes.POINTER(_pointer)]),
        }
        for (library, name), (result, arguments) in signatures.items():
            function = getattr(library, name)
            function.restype, function.argtypes = result, arguments
            setattr(self, name, function)


_LIBRARY: _Library | None = None
_LOAD_ERROR: str | None = None


def _library() -> _Library | None:
    """The SUNDIALS libraries scikit-sundae ships, loaded once (None if they cannot be found or loaded)."""
    global _LIBRARY, _LOAD_ERROR
    if _LIBRARY is None and _LOAD_ERROR is None:
        try:
            spec = importlib.util.find_spec("sksundae")
            if spec is None or spec.origin is None:
                raise OSError("scikit-sundae is not installed")
            _LIBRARY = _Library(Path(spec.origin).resolve().parents[1] / "scikit_sundae.libs")
        except (OSError, AttributeError, ValueError) as exc:
            _LOAD_ERROR = f"{type(exc).__name__}: {exc}"
    return _LIBRARY


def available() -> bool:
    """Whether :class:`DirectCVODE` can run here (the libraries were found and loaded)."""
    return _library() is not None


@functools.cache
def scikit_sundae_cvode() -> type | None:
    """scikit-sundae's ``CVODE`` binding class, or None without the package.

    Imported on first use only, where the direct C interface is not available:
    importing ``sksundae`` imports ``scipy.sparse`` and ``scipy.optimize``
    (0.3-0.6 s), which a run through :class:`DirectCVODE` never uses.
    """
    try:  # SUNDIALS CVODE through scikit-sundae (a dependency; guarded so the rest works without it)
        from sksundae.cvode import CVODE
    except ImportError:  # pragma: no cover - depends on the environment
        return None
    return CVODE


class CVODEError(RuntimeError):
    """A SUNDIALS set-up call failed (not a failed step: :meth:`DirectCVODE.one_step` returns those as flags)."""


class DirectCVODE:
    """One CVODE integration of ``dy/dt = rhs(t, y)`` (module docstring).

    ``rhs(t, y, ydot)`` writes ``ydot`` (``y`` is read during the call only);
    ``jacobian(t, y, out)`` writes ``df/dy`` into ``out`` (n x n), or None for
    CVODE's difference quotients. After :meth:`one_step`, ``y`` is the state at
    ``t`` (overwritten by the next step: copy it to keep it).
    """

    def __init__(
        self,
        rhs: Callable[[float, np.ndarray, np.ndarray], None],
        t0: float,
        y0: np.ndarray,
        *,
        method: str,
        rtol: float,
        atol: float,
        max_step: float,
        min_step: float,
        first_step: float = 0.0,
        max_num_steps: int = 100000,
        jacobian: Callable[[float, np.ndarray, np.ndarray], None] | None = None,
        stop_time: float | None = None,
    ):
        lib = _library()
        if lib is None:
            raise CVODEError(f"the SUNDIALS libraries of scikit-sundae cannot be loaded ({_LOAD_ERROR})")
        self._lib = lib
        y0 = np.asarray(y0, dtype=float)
        n = self.size = y0.shape[0]
        self._error: BaseException | None = None
        self._arrays: dict[int, np.ndarray] = {}  # N_Vector address -> numpy view of its data
        self._context = _pointer()
        self._check(lib.SUNContext_Create(0, ctypes.byref(self._context)), "SUNContext_Create")
        lib.SUNContext_ClearErrHandlers(self._context)  # failures are returned as flags, not printed
        self._y_vector = lib.N_VNew_Serial(n, self._context)
        self._dky_vector = lib.N_VNew_Serial(n, self._context)
        self.y = self._view(self._y_vector)
        self._dky = self._view(self._dky_vector)
        self.y[:] = y0
        self._memory = _pointer(lib.CVodeCreate(CV_ADAMS if method.lower() == "adams" else CV_BDF, self._context))
        self._matrix = lib.SUNDenseMatrix(n, n, self._context)
        self._solver = lib.SUNLinSol_Dense(self._y_vector, self._matrix, self._context)
        if not (self._memory.value and self._matrix and self._solver):
            raise CVODEError("CVODE: memory allocation failed")
        self._rhs_user, self._jacobian_user = rhs, jacobian
        self._rhs_callback = _RHS(self._rhs)  # kept referenced: C holds the pointer
        memory = self._memory
        self._check(lib.CVodeInit(memory, self._rhs_callback, float(t0), self._y_vector), "CVodeInit")
        self._check(lib.CVodeSStolerances(memory, float(rtol), float(atol)), "CVodeSStolerances")
        self._check(lib.CVodeSetLinearSolver(memory, self._solver, self._matrix), "CVodeSetLinearSolver")
        if jacobian is not None:
            data = lib.SUNDenseMatrix_Data(self._matrix)
            # column-major storage: the transpose of a C-order view is the matrix
            self._jacobian_matrix = np.ctypeslib.as_array(data, shape=(n, n)).T
            self._jacobian_callback = _JACOBIAN(self._jacobian)
            self._check(lib.CVodeSetJacFn(memory, self._jacobian_callback), "CVodeSetJacFn")
        self._check(lib.CVodeSetMaxNonlinIters(memory, 3), "CVodeSetMaxNonlinIters")
        self._check(lib.CVodeSetMaxConvFails(memory, 10), "CVodeSetMaxConvFails")
        self._check(lib.CVodeSetInitStep(memory, float(first_step)), "CVodeSetInitStep")
        self._check(lib.CVodeSetMinStep(memory, float(min_step)), "CVodeSetMinStep")
        self._check(lib.CVodeSetMaxStep(memory, float(max_step)), "CVodeSetMaxStep")
        self._check(lib.CVodeSetMaxOrd(memory, 12 if method.lower() == "adams" else 5), "CVodeSetMaxOrd")
        self._check(lib.CVodeSetMaxNumSteps(memory, int(max_num_steps)), "CVodeSetMaxNumSteps")
        if stop_time is not None:
            self._check(lib.CVodeSetStopTime(memory, float(stop_time)), "CVodeSetStopTime")
        self.t = float(t0)
        self._t_return = _real()
        self._count = ctypes.c_long()

    # --- callbacks (from C: never raise) -------------------------------------------------------
    def _view(self, vector) -> np.ndarray:
        """A numpy view of an N_Vector's data (CVODE's vectors live as long as the integration: cached)."""
        key = vector if isinstance(vector, int) else ctypes.cast(vector, _pointer).value
        array = self._arrays.get(key)
        if array is None:
            array = np.ctypeslib.as_array(self._lib.N_VGetArrayPointer(key), shape=(self.size,))
            self._arrays[key] = array
        return array

    def _rhs(self, t, y, ydot, user_data) -> int:
        try:
            arrays = self._arrays
            # CVODE calls back with a handful of vectors: after the first calls, their views are cached
            self._rhs_user(t, arrays[y] if y in arrays else self._view(y), arrays[ydot] if ydot in arrays else self._view(ydot))
            return 0
        except BaseException as exc:  # noqa: BLE001 - raised again by one_step (C cannot unwind Python)
            self._error = exc
            return -1

    def _jacobian(self, t, y, fy, matrix, user_data, tmp1, tmp2, tmp3) -> int:
        try:
            self._jacobian_user(t, self._view(y), self._jacobian_matrix)
            return 0
        except BaseException as exc:  # noqa: BLE001 - raised again by one_step
            self._error = exc
            return -1

    # --- stepping -------------------------------------------------------------------------------
    def one_step(self, t_bound: float) -> int:
        """One internal step toward ``t_bound``: CVODE's flag (>= 0 success); ``t`` and ``y`` updated."""
        flag = self._lib.CVode(self._memory, t_bound, self._y_vector, ctypes.byref(self._t_return), CV_ONE_STEP)
        if self._error is not None:
            error, self._error = self._error, None
            raise error
        if flag >= 0:
            self.t = self._t_return.value
        return flag

    def interpolate(self, t: float) -> np.ndarray:
        """The state at ``t`` inside the last step, from CVODE's interpolant (a new array)."""
        flag = self._lib.CVodeGetDky(self._memory, t, 0, self._dky_vector)
        if flag < 0:
            raise RuntimeError(f"CVODE interpolation at t={t!r}: {MESSAGES.get(flag, f'flag {flag}')}")
        return self._dky.copy()

    def _counter(self, function) -> int:
        function(self._memory, ctypes.byref(self._count))
        return int(self._count.value)

    @property
    def n_rhs(self) -> int:
        return self._counter(self._lib.CVodeGetNumRhsEvals)

    @property
    def n_jacobians(self) -> int:
        return self._counter(self._lib.CVodeGetNumJacEvals)

    @staticmethod
    def message(flag: int) -> str:
        return MESSAGES.get(flag, f"CVODE flag {flag}")

    def _check(self, flag: int, call: str) -> None:
        if flag < 0:
            raise CVODEError(f"{call} failed with flag {flag}")

    def __del__(self):
        lib = getattr(self, "_lib", None)
        if lib is None:
            return
        if getattr(self, "_memory", None) is not None and self._memory.value:
            lib.CVodeFree(ctypes.byref(self._memory))
        for name, free in (("_solver", lib.SUNLinSolFree), ("_matrix", lib.SUNMatDestroy), ("_y_vector", lib.N_VDestroy), ("_dky_vector", lib.N_VDestroy)):
            handle = getattr(self, name, None)
            if handle:
                free(handle)
        if getattr(self, "_context", None) is not None and self._context.value:
            lib.SUNContext_Free(ctypes.byref(self._context))
