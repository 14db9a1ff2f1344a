"""robot.model.lapack: scipy's LAPACK routines without importing scipy.linalg, identical to scipy's functions.

* Cholesky factor and solve, pivoted QR: the same bits as ``scipy.linalg.cho_factor``,
  ``cho_solve`` and ``qr(pivoting=True)`` on random, ill-conditioned and rank-deficient
  matrices of several shapes and memory orders, and on a mechanism's mass matrix;
* a matrix that is not positive definite raises ``LinAlgError`` as scipy does;
* a process that uses them does not import ``scipy.linalg``, and importing it later reuses
  the very module they loaded.
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
from scipy.linalg import cho_factor, cho_solve, qr

from robot.model.lapack import cholesky_factor, cholesky_solve, pivoted_qr
from robot.model.redundancy import REDUNDANCY_TOLERANCE

ROOT = Path(__file__).resolve().parents[1]


def _spd(rng, n: int, condition: float) -> np.ndarray:
    basis, _ = np.linalg.qr(rng.normal(size=(n, n)))
    return (basis * np.geomspace(1.0, 1.0 / condition, n)) @ basis.T


@pytest.mark.parametrize("order", ["C", "F"])
@pytest.mark.parametrize("n, condition", [(1, 1.0), (3, 10.0), (25, 1e8), (54, 1e12)])
def test_cholesky_is_scipys_bit_for_bit(n, condition, order):
    rng = np.random.default_rng(n)
    matrix = np.asarray(_spd(rng, n, condition), order=order)
    rhs = rng.normal(size=(n, 2 * n + 3))
    factor = cholesky_factor(matrix)
    expected_factor, lower = cho_factor(matrix, lower=False, check_finite=False)
    assert not lower and factor.tobytes() == expected_factor.tobytes()
    solution = cholesky_solve(factor, rhs)
    assert solution.tobytes() == cho_solve((expected_factor, False), rhs, check_finite=False).tobytes()
    # backward stable (Higham, Accuracy and Stability of Numerical Algorithms, 10.1): per column the residual is
    # of the order of rounding in M x, ~n eps |M| |x|, whatever the condition number
    residual = np.abs(matrix @ solution - rhs).max(axis=0)
    assert np.all(residual <= 10 * n * np.finfo(float).eps * np.linalg.norm(matrix, np.inf) * np.abs(solution).max(axis=0))


def test_cholesky_of_a_mass_matrix_is_scipys():
    """Pinocchio's M (column-major, upper triangle filled by CRBA) at random configurations."""
    from robot.data import shipped_urdf
    from robot.model.mechanism import build_mechanism

    model = build_mechanism(shipped_urdf("ups_rps.urdf")).model
    data = model.createData()
    rng = np.random.default_rng(7)
    for _ in range(3):
        q = pin.randomConfiguration(model, -np.ones(model.nq), np.ones(model.nq))
        pin.crba(model, data, q)
        rhs = rng.normal(size=(model.nv, 7))
        factor = cholesky_factor(data.M)
        expected = cho_factor(data.M, lower=False, check_finite=False)
        assert factor.tobytes() == expected[0].tobytes()
        assert cholesky_solve(factor, rhs).tobytes() == cho_solve(expected, rhs, check_finite=False).tobytes()


def test_a_matrix_that_is_not_positive_definite_raises_as_scipy_does():
    matrix = np.diag([1.0, -1.0, 2.0])
    with pytest.raises(np.linalg.LinAlgError, match="2-th leading minor"):
        cholesky_factor(matrix)
    with pytest.raises(np.linalg.LinAlgError, match="2-th leading minor"):
        cho_factor(matrix, lower=False, check_finite=False)


@pytest.mark.parametrize("order", ["C", "F"])
@pytest.mark.parametrize("shape, rank", [((1, 1), 1), ((5, 3), 3), ((3, 5), 3), ((30, 12), 7), ((12, 30), 12), ((54, 25), 20)])
def test_pivoted_qr_is_scipys_bit_for_bit(shape, rank, order):
    """Rank-deficient matrices too: the pivots and R's diagonal, which rank the closure rows."""
    rng = np.random.default_rng(shape[0] * 100 + shape[1])
    matrix = np.asarray(rng.normal(size=(shape[0], rank)) @ rng.normal(size=(rank, shape[1])), order=order)
    triangle, pivots = pivoted_qr(matrix)
    _, expected_triangle, expected_pivots = qr(matrix, mode="economic", pivoting=True, check_finite=False)
    assert triangle.tobytes() == expected_triangle.tobytes()
    assert pivots.dtype == expected_pivots.dtype and pivots.tobytes() == expected_pivots.tobytes()
    diagonal = np.abs(np.diag(triangle))
    assert np.sum(diagonal > REDUNDANCY_TOLERANCE * diagonal[0]) == rank  # what robot.model.redundancy reads


_SCRIPT = """
import sys, numpy as np
from robot.model import lapack
lapack.cholesky_factor(np.eye(3)); lapack.pivoted_qr(np.eye(3))
assert "scipy.linalg" not in sys.modules, "scipy.linalg imported"
loaded = sys.modules["scipy.linalg._flapack"]
import scipy.linalg
assert scipy.linalg.lapack._flapack is loaded and scipy.linalg.cho_factor(np.eye(2))[0][0, 0] == 1.0
print("ok")
"""


def test_no_scipy_linalg_import_and_scipy_linalg_later_reuses_the_module():
    done = subprocess.run([sys.executable, "-c", _SCRIPT], cwd=ROOT, capture_output=True, text=True, timeout=300)
    assert done.returncode == 0 and done.stdout.strip() == "ok", done.stderr[-3000:]
