"""QR factorisation with column pivoting (Businger-Golub), in numpy: ``A P = Q R``.

The rank decision of :mod:`robot.model.redundancy` needs the column order and
``|diag R|`` of a rank-revealing QR of a small matrix (the scaled closure rows'
transpose: a few dozen entries, once per model build). ``scipy.linalg.qr``
would import ``scipy.linalg`` (~0.1 s) for it; this is the same algorithm as the
LAPACK routine scipy calls (``dgeqp3``, which for matrices this small runs its
unblocked kernel ``dlaqp2``), written with numpy (issue 16, import time).

**Algorithm** (Golub and Van Loan, *Matrix Computations*, 4th ed., Alg. 5.4.1;
LAPACK ``dlaqp2`` with the norm downdating of Drmac and Bujanovic, LAPACK
Working Note 176). For ``i = 0, 1, ..., min(m, n) - 1``:

1. pivot: the remaining column of largest partial norm
   ``||A[i:, j]||`` (the first of equal ones) is swapped into column ``i``;
2. a Householder reflector ``H = I - tau v v^T`` (``v_0 = 1``, LAPACK ``dlarfg``:
   ``beta = -sign(alpha) sqrt(alpha^2 + ||x||^2)``, ``tau = (beta - alpha)/beta``,
   ``v = x / (alpha - beta)``) maps ``A[i:, i]`` to ``beta e_1`` and is applied to the
   columns right of it;
3. the partial norms are downdated, ``vn_j <- vn_j sqrt(1 - (r_ij/vn_j)^2)``, and
   recomputed from the column when cancellation has eaten more than half the
   digits (``(1 - (r_ij/vn_j)^2)(vn_j/vn_j^0)^2 <= sqrt(eps)``, ``vn_j^0`` the norm
   at the last recomputation).

``|R_00| >= |R_11| >= ...`` (the pivoting's invariant), and the first ``k``
pivoted columns are well conditioned when ``|R_kk|`` drops: the numerical rank is
the number of ``|R_kk|`` above a tolerance relative to ``|R_00|``. The pivots and
``|diag R|`` agree with ``scipy.linalg.qr(a, pivoting=True)`` (``tests/test_pivoted_qr.py``),
the signs of R's rows may differ. Sub-normal columns (norm below ~1e-292,
which LAPACK rescales) are not expected here and are not rescaled.
"""

from __future__ import annotations

import math

import numpy as np

#: the downdated norm is recomputed below this fraction (squared) of its last computed value
_RECOMPUTE = math.sqrt(np.finfo(float).eps)


def pivoted_qr(matrix: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(R, pivots)`` of ``matrix[:, pivots] = Q R`` (``R``: min(m, n) x n, upper triangular; ``pivots``: a permutation)."""
    a = np.array(matrix, dtype=float, order="F")  # a copy, worked in place
    if a.ndim != 2:
        raise ValueError(f"pivoted_qr needs a 2-D matrix, got shape {a.shape}")
    m, n = a.shape
    steps = min(m, n)
    pivots = np.arange(n)
    norms = np.linalg.norm(a, axis=0) if m else np.zeros(n)  # partial column norms (LAPACK vn1)
    reference = norms.copy()  # the norms at their last computation (vn2)
    for i in range(steps):
        p = i + int(np.argmax(norms[i:]))  # the first largest, as LAPACK's idamax
        if p != i:
            a[:, [i, p]] = a[:, [p, i]]
            pivots[[i, p]] = pivots[[p, i]]
            norms[p], reference[p] = norms[i], reference[i]
        _reflect(a, i)
        _downdate_norms(a, i, norms, reference)
    return np.triu(a[:steps]), pivots


def _reflect(a: np.ndarray, i: int) -> None:
    """Householder reflector of column ``i`` below the diagonal (LAPACK ``dlarfg``), applied to the columns right of it (``dlarf``)."""
    m = a.shape[0]
    if i >= m - 1:  # one entry: H = I (tau = 0)
        return
    alpha = a[i, i]
    below = a[i + 1 :, i]
    tail = float(np.linalg.norm(below))
    if tail == 0.0:
        return
    beta = -math.copysign(math.hypot(alpha, tail), alpha)
    tau = (beta - alpha) / beta
    below *= 1.0 / (alpha - beta)
    a[i, i] = beta
    if i + 1 < a.shape[1]:
        v = np.empty(m - i)
        v[0] = 1.0
        v[1:] = below
        rest = a[i:, i + 1 :]
        rest -= tau * np.outer(v, v @ rest)


def _downdate_norms(a: np.ndarray, i: int, norms: np.ndarray, reference: np.ndarray) -> None:
    """The partial norms of the columns right of ``i`` without row ``i`` (``dlaqp2``'s update)."""
    m = a.shape[0]
    for j in range(i + 1, a.shape[1]):
        if norms[j] == 0.0:
            continue
        remaining = max(0.0, 1.0 - (abs(a[i, j]) / norms[j]) ** 2)
        if remaining * (norms[j] / reference[j]) ** 2 <= _RECOMPUTE:
            norms[j] = float(np.linalg.norm(a[i + 1 :, j])) if i + 1 < m else 0.0
            reference[j] = norms[j]
        else:
            norms[j] *= math.sqrt(remaining)
