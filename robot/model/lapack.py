"""scipy's LAPACK without importing ``scipy.linalg``: Cholesky (``dpotrf``, ``dpotrs``) and pivoted QR (``dgeqp3``).

* The structured Jacobian (:mod:`robot.dynamics.state_jacobian`) factorises the
  mass matrix once per call, ``M = U^T U``, and solves ``M X = B`` with that factor
  (Golub & Van Loan, *Matrix Computations*, 4th ed., Alg. 4.2.1).
* The redundancy check of the closure rows (:mod:`robot.model.redundancy`) ranks
  them by QR with column pivoting, ``A P = Q R`` (ibid. Alg. 5.4.1), when a
  mechanism is built.

``scipy.linalg.cho_factor``/``cho_solve``/``qr(pivoting=True)`` are exactly these
routines through scipy's f2py module ``scipy.linalg._flapack``; but importing
``scipy.linalg`` runs its package initialisation, which (through
``array_api_compat``) imports numpy's ``f2py``, ``testing``, ``ma`` and ``random``:
0.13-0.25 s of CPU, a tenth of the whole 4-UPS/RPS run of issue 16 once numba is no
longer imported (numba imports ``scipy.linalg`` itself). Loading ``_flapack`` alone
takes a few milliseconds; the functions below call the same routines with the same
arguments (workspace queries included, which set LAPACK's blocking), so the results
are identical bit for bit (``tests/test_lapack.py`` compares them with scipy's
functions). Where the module cannot be loaded that way (another layout of scipy),
``scipy.linalg`` is imported as before.
"""

from __future__ import annotations

import importlib.util
import sys
import sysconfig
from functools import lru_cache
from pathlib import Path

import numpy as np

__all__ = ["cholesky_factor", "cholesky_solve", "pivoted_qr"]

_FLAPACK = "scipy.linalg._flapack"


@lru_cache(maxsize=1)
def _flapack():
    """scipy's f2py LAPACK module: the one already imported, else loaded from its file, else through scipy.linalg."""
    if _FLAPACK in sys.modules:
        return sys.modules[_FLAPACK]
    from clearance_contact.extension import import_extension

    spec = importlib.util.find_spec("scipy")
    folders = list(spec.submodule_search_locations or []) if spec is not None else []
    for folder in folders:
        path = Path(folder) / "linalg" / ("_flapack" + (sysconfig.get_config_var("EXT_SUFFIX") or ".so"))
        if path.is_file():
            try:
                module = import_extension(_FLAPACK, path)
            except ImportError:
                break
            sys.modules[_FLAPACK] = module  # scipy.linalg, if imported later, takes this very module
            return module
    from scipy.linalg import lapack  # another layout: the package's own import

    return lapack._flapack


def cholesky_factor(matrix: np.ndarray) -> np.ndarray:
    """``U`` with ``matrix = U^T U`` in its upper triangle (the lower one is left as in ``matrix``).

    = ``scipy.linalg.cho_factor(matrix, lower=False, check_finite=False)[0]``; only the
    upper triangle of ``matrix`` is read. Raises ``numpy.linalg.LinAlgError`` if it is
    not positive definite.
    """
    factor, info = _flapack().dpotrf(matrix, lower=False, overwrite_a=False, clean=False)
    if info > 0:
        raise np.linalg.LinAlgError(f"{info}-th leading minor of the array is not positive definite")
    if info < 0:
        raise ValueError(f'LAPACK reported an illegal value in {-info}-th argument on entry to "POTRF".')
    return factor


def cholesky_solve(factor: np.ndarray, rhs: np.ndarray) -> np.ndarray:
    """``X`` with ``U^T U X = rhs`` (``factor`` from :func:`cholesky_factor`).

    = ``scipy.linalg.cho_solve((factor, False), rhs, check_finite=False)``.
    """
    solution, info = _flapack().dpotrs(factor, rhs, lower=False, overwrite_b=False)
    if info != 0:
        raise ValueError(f"illegal value in {-info}th argument of internal potrs")
    return solution


def pivoted_qr(matrix: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(R, pivots)`` of ``matrix[:, pivots] = Q R`` (``R`` economic: min(m, n) rows; ``Q`` not formed).

    = ``scipy.linalg.qr(matrix, mode="economic", pivoting=True, check_finite=False)[1:]``,
    with its workspace query (the workspace size sets LAPACK's blocking, hence the rounding).
    """
    geqp3 = _flapack().dgeqp3
    optimal = geqp3(matrix, lwork=-1, overwrite_a=False)[-2][0].real.astype(np.int_)
    packed, pivots, _, _, info = geqp3(matrix, lwork=optimal, overwrite_a=False)
    if info < 0:
        raise ValueError(f"illegal value in {-info}th argument of internal geqp3")
    rows, columns = matrix.shape
    triangle = np.triu(packed) if rows < columns else np.triu(packed[:columns, :])
    return triangle, pivots - 1  # LAPACK's pivots count from 1
