"""Joint constraint equations in absolute coordinates (Nikravesh's basic constraints), vectorised.

Each body i has the position ``r_i`` of its centre of mass (world), the rotation
``A_i`` (body -> world) and the angular velocity ``w'_i`` in body axes. A virtual
displacement of body i is ``(dr_i, dpi'_i)`` (world translation, body-axes
rotation), so a body-fixed vector ``a = A a'`` varies as ``da = A (dpi' x a')``
and moves as ``a_dot = A (w' x a')``. The constraint Jacobian therefore has six
columns per body, ``[dr_i, dpi'_i]``, in the order of the bodies. The ground has
``A = I``, ``r = 0``, ``w' = 0`` and no columns.

Every joint of the mechanism is a combination of three basic constraints
(P. E. Nikravesh, *Computer-Aided Analysis of Mechanical Systems*, 1988, ch. 7
and 11; Haug 1989), each written with its Jacobian blocks and its
acceleration right-hand side ``gamma = -(d/dt Phi_q) qd - Phi_tt`` (so that
``Phi_q [a; w'_dot] = gamma``). Notation: ``s_i = A_i s'_i`` is a body-fixed point
relative to the COM, ``~x`` the skew matrix, ``W(x') = A (w' x (w' x x'))`` the
centripetal term of a body-fixed vector.

* **spherical** (3 rows; point P_i on body i coincides with point P_j on body j)::

      Phi   = r_j + s_j - r_i - s_i
      Phi_q = [ -I,  A_i ~s'_i | I, -A_j ~s'_j ]
      gamma = W_i(s'_i) - W_j(s'_j)

* **dot-1** (1 row; vectors h_i, f_j stay perpendicular)::

      Phi   = h_i . f_j
      Phi_q = [ 0, (h'_i x A_i^T f_j)^T | 0, (f'_j x A_j^T h_i)^T ]
      gamma = -( f_j . W_i(h'_i) + h_i . W_j(f'_j) + 2 h_i_dot . f_j_dot )

* **dot-2** (1 row; vector h_i stays perpendicular to d = P_j - P_i), and the
  **driving constraint** ``h_i . d - s(t) = 0`` (the actuator length along the
  prismatic axis h_i; ``d = r_j + s_j - r_i - s_i``)::

      Phi   = h_i . d - s(t)
      Phi_q = [ -h_i^T, (h'_i x A_i^T d - s'_i x A_i^T h_i)^T | h_i^T, (s'_j x A_j^T h_i)^T ]
      gamma = -( d . W_i(h'_i) + 2 h_i_dot . d_dot + h_i . (W_j(s'_j) - W_i(s'_i)) ) + s_ddot
      Phi_t = -s_dot

Joints (all in absolute coordinates, none of them built into a tree):
revolute = spherical + 2 dot-1 (the parent's axis perpendicular to two
vectors normal to the child's axis); universal = two revolutes through the
cross body; prismatic = 3 dot-1 (relative rotation locked) + 2 dot-2 (the child
origin stays on the parent's axis) + the driving dot-2 along the axis.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


_EPS = np.zeros((3, 3, 3))
_EPS[0, 1, 2] = _EPS[1, 2, 0] = _EPS[2, 0, 1] = 1.0
_EPS[0, 2, 1] = _EPS[2, 1, 0] = _EPS[1, 0, 2] = -1.0


def cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Row-wise cross products of (..., 3) arrays (one einsum: cheaper than ``np.cross`` on small batches)."""
    return np.einsum("ijk,...j,...k->...i", _EPS, a, b)


def skew(x: np.ndarray) -> np.ndarray:
    """Skew matrices of a batch of vectors (k, 3) -> (k, 3, 3): ``skew(x) @ y = x x y``."""
    return -np.einsum("ijk,...k->...ij", _EPS, x)


def _rotate(A: np.ndarray, x: np.ndarray) -> np.ndarray:
    return np.einsum("kij,kj->ki", A, x)


def _rotate_t(A: np.ndarray, x: np.ndarray) -> np.ndarray:
    return np.einsum("kji,kj->ki", A, x)


def _dot(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return np.einsum("ki,ki->k", a, b)


def _centripetal(A: np.ndarray, w: np.ndarray, x: np.ndarray) -> np.ndarray:
    """W(x') = A (w' x (w' x x'))."""
    return _rotate(A, cross(w, cross(w, x)))


@dataclass
class BodyStates:
    """Positions, rotations and velocities of the n bodies plus the ground (index n, i.e. -1)."""

    r: np.ndarray  # (n+1, 3) COM position
    A: np.ndarray  # (n+1, 3, 3) body -> world
    v: np.ndarray  # (n+1, 3) COM velocity
    w: np.ndarray  # (n+1, 3) angular velocity, body axes

    @property
    def n(self) -> int:
        return self.r.shape[0] - 1


@dataclass(frozen=True)
class ConstraintRows:
    """Phi, the compact Jacobian, gamma and Phi_t of a constraint set at one state.

    ``jacobian[row, slot]`` (rows x 2 x 6) is the block of ``Phi_q`` for the body
    ``ConstraintSet.bodies[row, slot]`` (slot 0: body i, slot 1: body j;
    columns ``[dr, dpi']``); every other block of the row is zero.
    """

    phi: np.ndarray
    jacobian: np.ndarray
    gamma: np.ndarray
    phi_t: np.ndarray


class ConstraintSet:
    """Spherical, dot-1 and dot-2 (optionally driven) constraints between bodies.

    Rows, in order: every spherical (3 each), every dot-1, every dot-2; a dot-2
    with ``driver = k >= 0`` subtracts the prescribed value ``s_k(t)``.
    Body index -1 is the ground. Each row involves two bodies, so the
    Jacobian is kept in compact form (:class:`ConstraintRows`); :meth:`dense`
    expands it, :meth:`times`, :meth:`transpose_times` and :meth:`weighted_gram`
    apply it without forming the dense matrix.
    """

    def __init__(self) -> None:
        self._sph: list = []
        self._dot1: list = []
        self._dot2: list = []
        self.labels: list[str] = []

    # -- building ------------------------------------------------------------------
    def spherical(self, i: int, s_i, j: int, s_j, label: str) -> None:
        self._sph.append((i, np.asarray(s_i, float), j, np.asarray(s_j, float), label))

    def dot1(self, i: int, h_i, j: int, f_j, label: str) -> None:
        self._dot1.append((i, np.asarray(h_i, float), j, np.asarray(f_j, float), label))

    def dot2(self, i: int, h_i, s_i, j: int, s_j, label: str, driver: int = -1) -> None:
        self._dot2.append((i, np.asarray(h_i, float), np.asarray(s_i, float), j, np.asarray(s_j, float), driver, label))

    def freeze(self, n_bodies: int) -> "ConstraintSet":
        """Pack the constraints into arrays (called once, before evaluation)."""
        n = self.n_bodies = n_bodies

        def index(values):
            return np.array([n if k < 0 else k for k in values], dtype=int)

        sph, d1, d2 = self._sph, self._dot1, self._dot2
        self.sph_i = index([c[0] for c in sph])
        self.sph_si = np.array([c[1] for c in sph]).reshape(-1, 3)
        self.sph_j = index([c[2] for c in sph])
        self.sph_sj = np.array([c[3] for c in sph]).reshape(-1, 3)
        self.d1_i = index([c[0] for c in d1])
        self.d1_h = np.array([c[1] for c in d1]).reshape(-1, 3)
        self.d1_j = index([c[2] for c in d1])
        self.d1_f = np.array([c[3] for c in d1]).reshape(-1, 3)
        self.d2_i = index([c[0] for c in d2])
        self.d2_h = np.array([c[1] for c in d2]).reshape(-1, 3)
        self.d2_si = np.array([c[2] for c in d2]).reshape(-1, 3)
        self.d2_j = index([c[3] for c in d2])
        self.d2_sj = np.array([c[4] for c in d2]).reshape(-1, 3)
        self.d2_driver = np.array([c[5] for c in d2], dtype=int)
        self.labels = [f"{c[4]}[{a}]" for c in sph for a in "xyz"] + [c[4] for c in d1] + [c[6] for c in d2]
        self.n_sph_rows = 3 * len(sph)
        self.n_rows = self.n_sph_rows + len(d1) + len(d2)
        start = self.n_sph_rows + len(d1)
        self.driving_rows = start + np.flatnonzero(self.d2_driver >= 0)
        self.driving_order = self.d2_driver[self.d2_driver >= 0]
        self.bodies = np.concatenate(
            [
                np.repeat(np.column_stack([self.sph_i, self.sph_j]), 3, axis=0),
                np.column_stack([self.d1_i, self.d1_j]),
                np.column_stack([self.d2_i, self.d2_j]),
            ]
        ).astype(int).reshape(-1, 2)
        # constant part of the spherical rows: -I for body i, +I for body j
        k = len(sph)
        self._sph_translation = np.zeros((k, 3, 2, 3))
        self._sph_translation[:, :, 0, :] = -np.eye(3)
        self._sph_translation[:, :, 1, :] = np.eye(3)
        # pairs of (row, slot) entries sharing a moving body, for Phi_q M^-1 Phi_q^T
        entries: dict[int, list] = {}
        for row in range(self.n_rows):
            for slot in range(2):
                body = int(self.bodies[row, slot])
                if body < n:
                    entries.setdefault(body, []).append((row, slot))
        pairs = [(a, sa, c, sc) for items in entries.values() for a, sa in items for c, sc in items]
        pairs = np.array(pairs, dtype=int).reshape(-1, 4)
        self._pair_a, self._pair_sa, self._pair_c, self._pair_sc = pairs.T
        self._pair_flat = pairs[:, 0] * self.n_rows + pairs[:, 2]
        return self

    # -- evaluation ----------------------------------------------------------------
    def evaluate(self, state: BodyStates, drive: tuple[np.ndarray, np.ndarray, np.ndarray] | None) -> ConstraintRows:
        """Phi, Phi_q (compact), gamma and Phi_t at ``state``; ``drive = (s, s_dot, s_ddot)`` of the drivers."""
        jac = np.zeros((self.n_rows, 2, 6))
        phi = np.empty(self.n_rows)
        gam = np.empty(self.n_rows)
        phi_t = np.zeros(self.n_rows)
        r, A, v, w = state.r, state.A, state.v, state.w

        # spherical: Phi = r_j + A_j s'_j - r_i - A_i s'_i
        k = len(self.sph_i)
        if k:
            i, j = self.sph_i, self.sph_j
            Ai, Aj = A[i], A[j]
            rows = slice(0, 3 * k)
            phi[rows] = (r[j] + _rotate(Aj, self.sph_sj) - r[i] - _rotate(Ai, self.sph_si)).ravel()
            gam[rows] = (_centripetal(Ai, w[i], self.sph_si) - _centripetal(Aj, w[j], self.sph_sj)).ravel()
            block = np.empty((k, 3, 2, 6))
            block[..., :3] = self._sph_translation
            block[:, :, 0, 3:] = Ai @ skew(self.sph_si)  # A_i ~s'_i
            block[:, :, 1, 3:] = -(Aj @ skew(self.sph_sj))  # -A_j ~s'_j
            jac[rows] = block.reshape(3 * k, 2, 6)
        offset = 3 * k

        # dot-1: Phi = h_i . f_j
        k = len(self.d1_i)
        if k:
            i, j = self.d1_i, self.d1_j
            Ai, Aj = A[i], A[j]
            hi, fj = _rotate(Ai, self.d1_h), _rotate(Aj, self.d1_f)
            rows = slice(offset, offset + k)
            phi[rows] = _dot(hi, fj)
            jac[rows, 0, 3:] = cross(self.d1_h, _rotate_t(Ai, fj))
            jac[rows, 1, 3:] = cross(self.d1_f, _rotate_t(Aj, hi))
            hi_dot = _rotate(Ai, cross(w[i], self.d1_h))
            fj_dot = _rotate(Aj, cross(w[j], self.d1_f))
            gam[rows] = -(
                _dot(fj, _centripetal(Ai, w[i], self.d1_h)) + _dot(hi, _centripetal(Aj, w[j], self.d1_f)) + 2.0 * _dot(hi_dot, fj_dot)
            )
            offset += k

        # dot-2 / driving: Phi = h_i . (r_j + A_j s'_j - r_i - A_i s'_i) - s(t)
        k = len(self.d2_i)
        if k:
            i, j = self.d2_i, self.d2_j
            Ai, Aj = A[i], A[j]
            hi = _rotate(Ai, self.d2_h)
            d = r[j] + _rotate(Aj, self.d2_sj) - r[i] - _rotate(Ai, self.d2_si)
            d_dot = v[j] + _rotate(Aj, cross(w[j], self.d2_sj)) - v[i] - _rotate(Ai, cross(w[i], self.d2_si))
            hi_dot = _rotate(Ai, cross(w[i], self.d2_h))
            rows = slice(offset, offset + k)
            phi[rows] = _dot(hi, d)
            gam[rows] = -(
                _dot(d, _centripetal(Ai, w[i], self.d2_h))
                + 2.0 * _dot(hi_dot, d_dot)
                + _dot(hi, _centripetal(Aj, w[j], self.d2_sj) - _centripetal(Ai, w[i], self.d2_si))
            )
            jac[rows, 0, :3] = -hi
            jac[rows, 1, :3] = hi
            jac[rows, 0, 3:] = cross(self.d2_h, _rotate_t(Ai, d)) - cross(self.d2_si, _rotate_t(Ai, hi))
            jac[rows, 1, 3:] = cross(self.d2_sj, _rotate_t(Aj, hi))
            driven = self.driving_rows
            if driven.size:
                if drive is None:
                    raise ValueError("driving constraints need the drive values (s, s_dot, s_ddot)")
                s, sd, sdd = drive
                order = self.driving_order
                phi[driven] -= s[order]
                phi_t[driven] = -sd[order]
                gam[driven] += sdd[order]
        jac[self.bodies == self.n_bodies] = 0.0  # the ground carries no unknowns
        return ConstraintRows(phi, jac, gam, phi_t)

    # -- linear algebra with the compact Jacobian ------------------------------------
    def dense(self, jacobian: np.ndarray) -> np.ndarray:
        """The dense Phi_q (rows x 6 n)."""
        n = self.n_bodies
        out = np.zeros((self.n_rows, 6 * (n + 1)))
        rows = np.arange(self.n_rows)[:, None]
        for slot in range(2):
            out[rows, 6 * self.bodies[:, slot : slot + 1] + np.arange(6)] = jacobian[:, slot]
        return out[:, : 6 * n]

    def times(self, jacobian: np.ndarray, x: np.ndarray) -> np.ndarray:
        """Phi_q x for x (n, 6) per body."""
        padded = np.vstack([x, np.zeros((1, 6))])
        return np.einsum("rsk,rsk->r", jacobian, padded[self.bodies])

    def transpose_times(self, jacobian: np.ndarray, lam: np.ndarray) -> np.ndarray:
        """Phi_q^T lambda as (n, 6) per body."""
        n = self.n_bodies
        contributions = (jacobian * lam[:, None, None]).reshape(-1, 6)
        flat = (self.bodies.reshape(-1, 1) * 6 + np.arange(6)).ravel()
        return np.bincount(flat, weights=contributions.ravel(), minlength=6 * (n + 1))[: 6 * n].reshape(n, 6)

    def weighted_gram(self, jacobian: np.ndarray, weighted: np.ndarray) -> np.ndarray:
        """Phi_q W Phi_q^T for block-diagonal W, given ``weighted = jacobian`` with W applied per block."""
        values = np.einsum(
            "pk,pk->p", weighted[self._pair_a, self._pair_sa], jacobian[self._pair_c, self._pair_sc]
        )
        m = self.n_rows
        return np.bincount(self._pair_flat, weights=values, minlength=m * m).reshape(m, m)
