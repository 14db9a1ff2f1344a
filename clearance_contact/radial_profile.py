"""Radial contact of the revolute joint from the exact penetration profile along the journal.

Geometry (:mod:`~clearance_contact.revolute`, module docstring): in the bearing frame the
journal axis meets the plane z at the eccentricity e(z) = m + z t (exactly linear in z),
and the slice penetration is::

    delta(z) = f(e(z), t),   f(e, t) = |e| + R_j sqrt(1 + x) - R_b1,
    x = (s^2 + beta^2 T) / (E + beta^2),   s = t.e,  T = |t|^2,  E = |e|^2,  beta = R_j T.

delta(z) is convex in z (up to the ellipse blend, < 3e-9 m), so over the bearing length
[-l, l] (l = L_b / 2) the *dry* set {delta <= 0} is one interval [z_a, z_b] (possibly
empty or outside) and the wetted set is [-l, z_a) U (z_b, l].

Elastic energy (a Winkler-type distributed law, Johnson, Contact Mechanics 1985, Ch. 5)
-------------------------------------------------------------------------------------
With q(delta) the force per unit length of the radial law (``radial_laws``: e.g.
K_line / L_b delta^n) and Phi(delta) = int_0^delta q, the elastic energy of the joint's
radial contact is::

    U = int_{-l}^{l} Phi(max(delta(z), 0)) dz

and the elastic wrench on the journal is exactly -grad U.  The pose enters through
a = R_b^T (o_j - o_b) and d = R_b^T u_j: m = a_xy - a_z t, t = d_xy / d_z.  For a journal
translation eps and rotation theta about o_j (bearing axes), delta a = eps,
delta d = theta x d, so with g_e = df/de, g_t = df/dt (at fixed e)::

    d delta / d a = (g_e, -g_e.t),
    d delta / d d = (G, -G.t) / d_z,       G = (z - a_z) g_e + g_t

    F = -int q grad_a delta dz = (-S_g, S_g.t),            S_g = int q g_e dz
    M = -d x int q grad_d delta dz = -d x (S_G, -S_G.t) / d_z,  S_G = S_zg - a_z S_g + S_gt

(force on the journal and moment about o_j, bearing axes; S_zg = int q z g_e,
S_gt = int q g_t).  With::

    dx/de = 2 (s t - x e) / D,    dx/dt = [2 s e + (4 R_j beta T + 2 beta^2 - 4 x R_j beta) t] / D,
    g_e = e/|e| + R_j/(2 sqrt(1 + x)) dx/de,   g_t = R_j/(2 sqrt(1 + x)) dx/dt,  D = E + beta^2.

The rate of each slice is delta_dot(z) = g_e.(m_dot + z t_dot) + g_t.t_dot, exact.

Damping is pointwise: q is multiplied by the dissipation model's factor at each slice,
max(1 + chi delta_dot(z) / delta_dot_0, 0) (:mod:`~clearance_contact.dissipation`): the
integrated law is the pointwise law, and it adds nothing with chi = 0 (restitution 1).

Quadrature and its error
------------------------
Each half [h0, h1] of the bearing ([0, l] top, [-l, 0] bottom) is split at the dry
interval (or, if there is none, at the minimiser z_e of |e(z)|) into two pieces, each
with one *inner* end (towards the dry interval) and one *outer* end (the half's end).
On each piece z = inner + (outer - inner) u^2 (u in [0, 1]) and an N-point
Gauss-Legendre rule in u (``RADIAL_NODES``).  The substitution turns the root behaviour
(z - z_a)^n of q into u^(2n+1) (u^4 for n = 1.5), so the integrand is smooth; for a
uniform or linear profile (aligned axes, tilt in the plane of the eccentricity) and
n = 1 the rule is exact (degree <= 2N - 1).  Otherwise delta(z) is analytic with its
nearest singularities at the complex zeros of |e(z)|^2, z_e +- i e_min / |t|; on a piece
of length h their distance in units of h/2 is >= 2 c_r / (|t| h) >= 1 (a wetted piece
lies where |e| >= c_r - delta), so the Gauss-Legendre error is below
C rho^(-2N), rho >= 1 + sqrt(2) (Bernstein ellipse through the singularity): 7.5e-7
relative for N = 8, measured < 1e-7 against adaptive quadrature (tests).

The dry interval: |e(z)|^2 = T (z - z_e)^2 + e_min^2 exactly, so delta(z) = 0 is
sqrt(T (z - z_e)^2 + e_min^2) = rho(z), rho = R_b1 - R_j sqrt(1 + x(z)); rho varies by
less than R_j T / 2 along the journal, and three fixed-point iterations
z = z_e +- sqrt(rho(z)^2 - e_min^2) / |t| give the roots to rounding (the map's
contraction factor is ~ R_j |t| T / c_r < 1e-5).  An error eps in an end of a wetted
piece changes the integrals by O(q' eps^2) since q vanishes there.

Split points move continuously with the pose (the roots merge into z_e when the dry
interval vanishes), so the wrench is continuous through every change of contact kind.
"""

from __future__ import annotations

import math

import numpy as np

from .compiled import jit
from .dissipation import encoded_damping_factor
from .radial_laws import encoded_line_density

__all__ = ["RADIAL_POINTS", "RADIAL_NODES", "slice_gradient", "dry_interval", "half_integrals"]

RADIAL_POINTS: int = 8
"""Gauss-Legendre points per wetted piece (two pieces per half of the bearing)."""


def _radial_nodes(points: int) -> np.ndarray:
    """Rows (u_i, 2 u_i w_i) of the Gauss-Legendre rule on [0, 1] for z = inner + (outer - inner) u^2."""
    x, w = np.polynomial.legendre.leggauss(points)
    u = 0.5 * (x + 1.0)
    return np.ascontiguousarray(np.stack([u, 2.0 * u * 0.5 * w], axis=1))


RADIAL_NODES: np.ndarray = _radial_nodes(RADIAL_POINTS)
"""(RADIAL_POINTS, 2): u_i and the weight 2 u_i w_i (times |outer - inner| = dz weight)."""

_FIXED_POINT_ITERATIONS = 3
_MIN_TILT2 = 1.0e-30
"""|t|^2 below which the profile is taken as uniform (aligned axes)."""


@jit
def slice_gradient(ex: float, ey: float, tx: float, ty: float, r_j: float, r_b1: float):
    """(delta, g_ex, g_ey, g_tx, g_ty) of the slice with eccentricity e and axis slope t (module docstring).

    At e = 0 (the journal axis on the bearing axis) g_e is taken along t (or x if t = 0):
    the cone's right derivative; such a slice is never in contact below a tilt of
    acos(R_j / R_b1).
    """
    tt = tx * tx + ty * ty
    beta = r_j * tt
    bb = beta * beta
    ee = ex * ex + ey * ey
    e = math.sqrt(ee)
    d = ee + bb
    s = tx * ex + ty * ey
    if d > 0.0:
        x = (s * s + bb * tt) / d
        inv_d = 1.0 / d
    else:
        x = 0.0
        inv_d = 0.0
    root = math.sqrt(1.0 + x)
    half = 0.5 * r_j / root
    if e > 0.0:
        hx = ex / e
        hy = ey / e
    elif tt > 0.0:
        ta = math.sqrt(tt)
        hx = tx / ta
        hy = ty / ta
    else:
        hx = 1.0
        hy = 0.0
    gex = hx + half * 2.0 * (s * tx - x * ex) * inv_d
    gey = hy + half * 2.0 * (s * ty - x * ey) * inv_d
    coef = 4.0 * r_j * beta * tt + 2.0 * bb - 4.0 * x * r_j * beta
    gtx = half * (2.0 * s * ex + coef * tx) * inv_d
    gty = half * (2.0 * s * ey + coef * ty) * inv_d
    return e + r_j * root - r_b1, gex, gey, gtx, gty


@jit
def _rho(z: float, mx: float, my: float, tx: float, ty: float, r_j: float, r_b1: float) -> float:
    """R_b1 - R_j sqrt(1 + x(z)): the |e| at which the slice z just touches (delta = |e| - rho)."""
    ex = mx + z * tx
    ey = my + z * ty
    return math.sqrt(ex * ex + ey * ey) - slice_gradient(ex, ey, tx, ty, r_j, r_b1)[0]


@jit
def dry_interval(mx: float, my: float, tx: float, ty: float, r_j: float, r_b1: float):
    """(z_a, z_b, dry): the interval of the journal axis line where delta(z) <= 0 (module docstring).

    ``dry`` False: delta > 0 everywhere; then z_a = z_b = z_e (the minimiser of |e(z)|,
    0 for parallel axes), where the halves are split.
    """
    tt = tx * tx + ty * ty
    if tt < _MIN_TILT2:
        delta = slice_gradient(mx, my, tx, ty, r_j, r_b1)[0]
        return 0.0, 0.0, delta <= 0.0
    z_e = -(mx * tx + my * ty) / tt
    ex = mx + z_e * tx
    ey = my + z_e * ty
    e_min2 = ex * ex + ey * ey
    rho = _rho(z_e, mx, my, tx, ty, r_j, r_b1)
    if rho * rho <= e_min2:
        return z_e, z_e, False
    t_abs = math.sqrt(tt)
    z_a = z_b = z_e
    rho_a = rho_b = rho
    for _ in range(_FIXED_POINT_ITERATIONS):
        z_a = z_e - math.sqrt(max(rho_a * rho_a - e_min2, 0.0)) / t_abs
        z_b = z_e + math.sqrt(max(rho_b * rho_b - e_min2, 0.0)) / t_abs
        rho_a = _rho(z_a, mx, my, tx, ty, r_j, r_b1)
        rho_b = _rho(z_b, mx, my, tx, ty, r_j, r_b1)
    return z_a, z_b, True


@jit
def half_integrals(
    h0, h1, z_a, z_b, mx, my, tx, ty, mdx, mdy, tdx, tdy, r_j, r_b1, onset_rate, parameters, law_offset,
    dissipation_offset, nodes
):
    """Integrals over the wetted part of the half [h0, h1] (h0 < h1) of the bearing.

    The wetted pieces are [h0, clip(z_a)] and [clip(z_b), h1] (clip to [h0, h1]).
    The pressure is weighted by max(factor, 0), the damping factor of the dissipation model
    encoded at ``parameters[dissipation_offset:]`` at the node's rate and ``onset_rate``
    (:func:`~.dissipation.encoded_damping_factor`); the radial law is encoded at
    ``parameters[law_offset:]`` (:func:`~.radial_laws.encoded_line_density`).
    Returns (S_gx, S_gy, S_zgx, S_zgy, S_gtx, S_gty) of the damped pressure and
    (S_0, S_z, S_zz, S_delta) of the elastic one (module docstring).
    """
    sgx = sgy = szgx = szgy = sgtx = sgty = 0.0
    s0 = s1 = s2 = sd = 0.0
    lo = min(max(z_a, h0), h1)
    hi = min(max(z_b, h0), h1)
    for piece in range(2):
        if piece == 0:
            inner = lo
            outer = h0
        else:
            inner = hi
            outer = h1
        span = outer - inner
        length = abs(span)
        if length <= 0.0:
            continue
        for i in range(nodes.shape[0]):
            u = nodes[i, 0]
            z = inner + span * u * u
            wz = nodes[i, 1] * length
            ex = mx + z * tx
            ey = my + z * ty
            delta, gex, gey, gtx, gty = slice_gradient(ex, ey, tx, ty, r_j, r_b1)
            if delta <= 0.0:
                continue
            q = wz * encoded_line_density(parameters, law_offset, delta)
            s0 += q
            s1 += q * z
            s2 += q * z * z
            sd += q * delta
            rate = gex * (mdx + z * tdx) + gey * (mdy + z * tdy) + gtx * tdx + gty * tdy
            factor = encoded_damping_factor(parameters, dissipation_offset, rate, onset_rate)
            q = q * factor if factor > 0.0 else 0.0
            sgx += q * gex
            sgy += q * gey
            szgx += q * z * gex
            szgy += q * z * gey
            sgtx += q * gtx
            sgty += q * gty
    return sgx, sgy, szgx, szgy, sgtx, sgty, s0, s1, s2, sd
