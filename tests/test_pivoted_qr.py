"""robot.model.pivoted_qr: the numpy column-pivoted QR makes LAPACK's (scipy.linalg.qr) pivot choices.

Compared with ``scipy.linalg.qr(a, pivoting=True)`` on random matrices of
several shapes and scales, on rank-deficient ones (the case the redundancy
detection exists for), on graded columns and on the scaled closure rows of a
planar mechanism; and checked on its own terms: ``A P = Q R`` with ``Q``
orthogonal, ``|diag R|`` non-increasing, the rank revealed.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.linalg import qr as scipy_qr

from robot.model.pivoted_qr import pivoted_qr


def _compare(matrix: np.ndarray, rank: int | None = None) -> None:
    r, pivots = pivoted_qr(matrix)
    _, r_ref, pivots_ref = scipy_qr(matrix, mode="economic", pivoting=True)
    # the pivots that decide the rank are LAPACK's; past the rank the columns are rounding noise
    # (both factorisations then pick among norms ~1e-16 of each other)
    decided = min(matrix.shape) if rank is None else rank
    np.testing.assert_array_equal(pivots[:decided], pivots_ref[:decided])
    scale = max(abs(r_ref[0, 0]), 1e-300)
    np.testing.assert_allclose(np.abs(np.diag(r))[:decided], np.abs(np.diag(r_ref))[:decided], rtol=1e-12, atol=1e-14 * scale)
    # every original column's coordinates on the first `decided` directions of Q (up to the rows' signs)
    in_original_order = np.abs(r[:decided][:, np.argsort(pivots)])
    np.testing.assert_allclose(in_original_order, np.abs(r_ref[:decided][:, np.argsort(pivots_ref)]), rtol=1e-10, atol=1e-13 * scale)
    if rank is not None:
        assert np.all(np.abs(np.diag(r))[rank:] <= 1e-12 * scale)


def _reconstructs(matrix: np.ndarray) -> None:
    r, pivots = pivoted_qr(matrix)
    k = r.shape[0]
    # Q = A P R^-1 on the full-rank leading block; here instead check R^T R = P^T A^T A P (Q orthogonal)
    gram = matrix[:, pivots].T @ matrix[:, pivots]
    np.testing.assert_allclose(r.T @ r, gram, atol=1e-12 * np.abs(gram).max())
    diagonal = np.abs(np.diag(r))
    assert np.all(diagonal[:-1] >= diagonal[1:] * (1 - 1e-12)) or k < 2


@pytest.mark.parametrize("shape", [(3, 5), (5, 3), (6, 6), (24, 10), (10, 24), (1, 4), (4, 1), (30, 29)])
def test_random_matrices_as_lapack(shape):
    rng = np.random.default_rng(sum(shape))
    for _ in range(20):
        matrix = rng.normal(size=shape) * 10.0 ** rng.uniform(-4, 4)
        _compare(matrix)
        _reconstructs(matrix)


@pytest.mark.parametrize("shape, rank", [((6, 5), 2), ((5, 6), 3), ((12, 8), 5), ((3, 5), 1), ((20, 20), 11)])
def test_rank_deficient_matrices_as_lapack(shape, rank):
    rng = np.random.default_rng(rank * 97 + shape[0])
    for _ in range(20):
        matrix = rng.normal(size=(shape[0], rank)) @ rng.normal(size=(rank, shape[1]))
        _compare(matrix, rank)
        _reconstructs(matrix)


def test_graded_and_duplicate_columns_as_lapack():
    rng = np.random.default_rng(5)
    base = rng.normal(size=(7, 4))
    graded = base * np.array([1.0, 1e-3, 1e-6, 1e-9])  # columns of very different norms
    _compare(graded)
    duplicated = np.hstack([base, base[:, :2] * 2.0, np.zeros((7, 1))])  # dependent columns and a zero one
    _compare(duplicated, rank=4)


def test_scaled_closure_rows_of_a_planar_loop():
    """A planar closure's 5 rows in 3 coordinates (transposed): rank 2, the out-of-plane rows ~1e-16."""
    rng = np.random.default_rng(3)
    angle = rng.uniform(0, 2 * np.pi, 3)
    planar = np.array([[-np.sin(angle[0]), -np.sin(angle[1]), -np.sin(angle[2])], [np.cos(angle[0]), np.cos(angle[1]), np.cos(angle[2])]])
    rows = np.vstack([planar / np.linalg.norm(planar), 4e-17 * rng.normal(size=(3, 3))])
    _compare(rows.T, rank=2)


def test_empty_and_one_entry():
    r, pivots = pivoted_qr(np.array([[3.0]]))
    assert r.shape == (1, 1) and abs(r[0, 0]) == 3.0 and list(pivots) == [0]
    r, pivots = pivoted_qr(np.zeros((3, 2)))
    assert np.all(r == 0.0) and sorted(pivots) == [0, 1]
