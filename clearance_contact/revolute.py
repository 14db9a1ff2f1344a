"""Revolute clearance joint: a flanged journal in a bearing, with radial and axial clearance.

Seed paper, section "Mathematical description for 3D revolute clearance joint",
eqs. (4)-(10) (geometry), (12)-(13) (line / plane force law), (14) (friction),
(15) (force and moment on the bearing); MODEL-NOTES 3.  Published treatments of the
same joint: Yan et al., Nonlinear Dyn. (2015), DOI 10.1007/s11071-014-1870-7;
Marques, Isaac, Dourado, Flores, Mech. Mach. Theory 116 (2017) 123-144.

Elements and frames (``docs/contact-api.md``)
---------------------------------------------
* **Bearing** (outer element): hollow cylinder, bore radius ``R_b1``, outer radius
  ``R_b2``, length ``L_b``.  Frame origin at its midpoint, local z = its axis.  The
  *top impact ring* is the end z = +L_b/2, the *bottom* one z = -L_b/2.
* **Journal** (inner element): shaft of radius ``R_j`` between two flanges whose inner
  faces are ``L_j`` apart (frame origin half-way between them, local z = its axis).  The
  flanges are assumed to reach beyond the bearing's outer radius (flange radius >=
  R_b2 + c_r), so an end face of the bearing always meets the flange face, never the
  flange rim.
* Clearances (seed paper eq. (4))::

      c_r = R_b1 - R_j > 0        radial
      c_a = L_j - L_b  > 0        axial (c_a / 2 on each side when centred)

* Both frames' z axes point the same way: the journal's top flange (z = +L_j/2) faces the
  bearing's top ring.  A journal axis at 90 deg or more from the bearing axis is not a
  journal in a bearing and raises :class:`~clearance_contact.errors.ContactError`.

Four candidates (seed paper Fig. 3-4), in the order of the contract::

    0 top_radial      bearing bore near the top ring   vs journal surface (M_b / M_j)
    1 top_axial       bearing top end face (annulus)   vs top flange face  (P_b / P_j)
    2 bottom_radial   bearing bore near the bottom ring vs journal surface (N_b / N_j)
    3 bottom_axial    bearing bottom end face          vs bottom flange    (Q_b / Q_j)

Geometry (exact for any tilt below 90 deg unless stated)
-------------------------------------------------------
Work in the bearing frame.  With a0 = R_b^T (o_j - o_b) (journal origin) and
d = R_b^T u_j (journal axis, d_z = cos(tilt) > 0), the journal axis crosses the plane
z of the bearing at the radial offset (eccentricity, paper eqs. (5)-(7))::

    e(z) = (a0_x, a0_y) + (z - a0_z) t,        t = (d_x, d_y) / d_z   (|t| = tan(tilt))

which is *exactly linear* in z.  The journal's cross-section by that plane is an ellipse
(semi-axes R_j and R_j / cos(tilt)), so the radial penetration of the journal beyond the
bore in the slice z (paper eq. (8), generalised to a tilted journal) is::

    delta(z) = max_n [ e(z).n + R_j sqrt(1 + (t.n)^2) ] - R_b1

(the support function of the ellipse).  It is evaluated as::

    delta(z) = |e| + R_j sqrt(1 + x) - R_b1,
    x = ((t.e)^2 + beta^2 |t|^2) / (|e|^2 + beta^2),     beta = R_j tan^2(tilt)

i.e. the support in the direction e/|e|, with the ellipse term blended so that it is
smooth where the journal axis crosses the bearing axis and exact there (e = 0, e.g. a
journal tilted about the joint centre: delta = R_j / cos(tilt) - R_b1).  Value and rate
are continuous (except the cone of |e| at e = 0 itself), and
|error| <= min(0.3 beta, beta^2 / (4 |e|)): 2.5e-13 m for a slice at |e| >= c_r = 0.1 mm
of a 10 mm journal tilted by 1e-3 rad (the slices that matter for contact), at most
0.3 beta = 3e-9 m anywhere at that tilt (checked in the tests).
The distance is measured radially in the bearing's cross-section; along the journal's
surface normal it differs by a factor 1 - O(tilt^2).  The exact delta(z) is convex in z
(a maximum of functions affine in z), so its maximum over a half of the bearing lies at
an end of that half: the ring (z = +-L_b/2) or the mid-plane (z = 0).

Axial: with F_top = o_j + L_j/2 u_j (top flange face centre) the penetration of the
point x = (x_1, x_2) of the bearing's top end face (radius R_b1 <= |x| <= R_b2) into the
flange (paper eqs. (9)-(10)) is *exactly linear* in x::

    delta(x) = (o_b + L_b/2 u_b + x_1 b_1 + x_2 b_2 - F_top) . u_j = delta_c + g . x
    delta_c  = -a0.d + d_z L_b/2 - L_j/2,     g = (d_x, d_y),  |g| = sin(tilt)

and for the bottom ring delta(x) = a0.d + d_z L_b/2 - L_j/2 - g . x.  The deepest point
is on the outer rim: delta_max = delta_c + R_b2 |g|.

``penetration`` (and ``JointContact.penetration``) is the deepest penetration of each
candidate (radial: max of its two end slices; axial: delta_c + R_b2 |g|), and
``penetration_rate`` is its exact time derivative (from the twists).  Where the deepest
point jumps (two ends equally deep within 1e-14 m, or end faces parallel within
1e-14 rad) the derivative has a kink and the right derivative (the larger one-sided
rate, what the penetration does next) is reported.

Contact law: distributed, continuous from point to line / plane contact
-----------------------------------------------------------------------
The paper uses the L-N law for misaligned (point) contact and K delta^n for line and
plane contact (eqs. (11)-(13)); switching between them makes the force jump when the
tilt crosses zero.  Here the line / plane law is instead *distributed over the contact
region* (a Winkler-type elastic foundation, Johnson, Contact Mechanics 1985, Ch. 5; the
same idea as the slicing technique for misaligned roller contacts, Harris & Kotzalas,
Rolling Bearing Analysis, 5th ed. 2007), so that one formula covers every configuration:

* **Radial**, per ring (its half of the bearing length, z in [0, l] or [-l, 0],
  l = L_b/2): the radial law's force per unit length q(delta) (:mod:`.radial_laws`;
  default K_line / L_b delta^n_r) is applied to the *exact* slice penetration delta(z)
  above, and the wrench is minus the gradient of the elastic energy
  U = int Phi(delta(z)) dz (Phi' = q) with respect to the journal pose, by a fixed
  Gauss-Legendre quadrature over the wetted part of the half
  (:mod:`~clearance_contact.radial_profile`: maths, split points, error bound;
  < 1e-6 relative, exact for aligned axes and for a tilt in the plane of the
  eccentricity with n = 1).  Aligned it gives exactly K_line/2 delta^n_r per ring, i.e.
  K_line delta^n_r for the whole bearing (paper eq. (12), line contact); tilted, the
  contact shrinks continuously to the ring's edge (edge / point contact); under a skew
  tilt the curved profile is integrated as it is (a linear profile between the two
  ends over-estimated the force by up to 94 %, issue 14).  The resultant of each ring
  is a screw: a force -F_N n through a point P of its axis (the point nearest the
  centroid of the pressure, half-way between bore and journal) and a couple along n
  (``NORMAL_COUPLE``, the pitch of the wrench: slices at different heights push in
  different directions under a skew tilt).  n is normal to the journal surface, so
  it leans by the tilt from the bearing's cross-section, and |d delta / d a| =
  1/cos(tilt): a tilted edge contact carries 1/cos(tilt) times the force of the same
  energy pressed radially.
* **Axial**, per ring: the plane law is distributed uniformly over the annulus,
  p(x) = K_plane / (pi (R_b2^2 - R_b1^2)) max(delta(x), 0)^n_a: aligned it gives
  exactly K_plane delta^n_a (paper eq. (13), plane contact); tilted, the contact is the
  part of the annulus beyond a straight line, shrinking to the deepest rim point.
  Force, centroid and second moment are computed as differences of disc integrals.
  For n_a = 1 they are closed form (exact; for a crescent of rim half-angle below
  0.5 rad, where the closed form cancels, the quadrature below is used: relative error
  < 3e-11); for other n_a a 10-point Gauss-Legendre rule in the angle phi of
  v = 1 - y0 cos^2(phi/2) (v the coordinate along g scaled by the radius, contact for
  v > 1 - y0; both endpoint singularities smoothed, the integrand evaluated from the rim
  penetration without cancellation), normalised to integrate a uniform pressure
  exactly: relative error < 4e-6 on the force and < 5e-8 R_b2 on the centroid (worst
  case: contact boundary near the far rim; < 1e-8 elsewhere), a smooth function of the
  configuration (checked against adaptive quadrature in the tests).
* **Damping** (``dissipation``, default L-N, paper eq. (11)): pointwise, the pressure
  at each point is multiplied by [1 + chi(c_e) delta_dot / max(delta_dot_0,
  ONSET_RATE_FLOOR)], clamped at >= 0, chi of the joint's dissipation model
  (:mod:`~clearance_contact.dissipation`; L-N: 3 (1 - c_e^2)/4), with delta_dot the
  rate of that point's penetration.  Radial: at each quadrature node (the
  slice rate is exact, from the twists).  Axial: delta_dot is linear over the face, so
  the elastic resultant times the factor at the centroid rate is the pointwise law
  integrated (exact for the force while the factor stays positive).  delta_dot_0 is the
  caller's onset rate of that candidate.

All four forces are continuous functions of the configuration (no switching between
formulas with different values), with a continuous point of application.

``kind``: 0 no contact; 2 (line) when the whole half-length of a radial candidate is in
contact, 3 (plane) when the whole annulus is, 1 (point) when only a part is (a tilted
edge / rim contact).  Every aligned contact is 2 or 3; the classification is for
reporting only, the force does not depend on it.

Stiffness (defaults from :mod:`~clearance_contact.materials`, n = 1 each)
-------------------------------------------------------------------------
* K_line = pi/4 E* L_b (:func:`~clearance_contact.materials.cylinder_line_stiffness`,
  contact length = bearing length, see its docstring for the derivation and status).
* K_plane = 2 E* R_b2 (:func:`~clearance_contact.materials.flat_punch_stiffness`,
  rigid flat punch of the annulus' outer radius: an upper bound for the annulus).
* Other exponents need an explicit stiffness (N/m^n), as the defaults are linear laws.
* ``point_stiffness`` / ``point_exponent`` are accepted and validated for the
  interface contract but are not used: in the distributed formulation a point (edge /
  rim) contact is the limit of the line / plane law over a shrinking region.

Friction and wrenches (paper eqs. (14)-(15))
--------------------------------------------
Each active candidate's forces act at one point P, half-way between the two contact
points at the centroid (the same point for both bodies: action = reaction exactly).
Slip of the journal's material point at P relative to the bearing's:
v = (v_j + w_j x (P - o_j)) - (v_b + w_b x (P - o_b)), tangential part v_t.  The
contact region also spins about the normal at w_n = (w_j - w_b).n; with r_s the rms
distance of the pressure from P (from the second moment of the distribution) this is
a slip speed w_n r_s, and the friction law is evaluated at the combined speed
sqrt(|v_t|^2 + (w_n r_s)^2) (elliptic limit-surface approximation of coupled
sliding-spinning (Coulomb-Contensou) friction: Contensou, IUTAM Symp. Kreiselprobleme
1962, Springer 1963; Leine & Glocker, Eur. J. Mech. A 22 (2003) 193; Howe & Cutkosky,
Int. J. Robot. Res. 15 (1996) 557).  With g = f(v)/v of the friction law::

    F_t = -g v_t,      T_spin = -g r_s^2 w_n  (about n)

so a flange face turning on the bearing's end face (plane contact, centroid on the
axis) carries a friction torque mu F_N r_s, and a single slip gives the plain law.
(The exact Coulomb torque of a uniform pressure uses the mean radius instead of the rms
one: r_s over-estimates it by 1 % for R_b1/R_b2 = 0.63, 6 % for a full disc.)
On the journal: f = -F_N n + F_t at P, plus T_spin n; on the bearing the opposite.
Wrenches are [force, moment about the element's frame origin], world axes.

Compiled kernel (``docs/contact-api.md``)
----------------------------------------
:func:`revolute_kernel` (``RevoluteClearanceJoint.kernel``) computes all of the above
into a flat float64 array ``out`` of ``RevoluteClearanceJoint.output_size = 102``
values; offsets (class attributes, k = 4 candidates, r = 2 eccentricity rows, (k, 3)
blocks row-major)::

    PENETRATION 0 (k)    PENETRATION_RATE 4 (k)   NORMAL_FORCE 8 (k)    NORMAL 12 (3k)
    POINT_OUTER 24 (3k)  POINT_INNER 36 (3k)      FRICTION_FORCE 48 (3k)
    ECCENTRICITY 60 (3r) WRENCH_OUTER 66 (6)      WRENCH_INNER 72 (6)   KIND 78 (k, as float)
    internal: CENTROID_DEPTH 82 (k, delta at P's slice), SPIN_RADIUS 86 (k, r_s),
              SPIN_SPEED 90 (k, w_n r_s), SPIN_TORQUE 94 (k, T_spin),
              NORMAL_COUPLE 98 (k, couple of the normal pressure about n)

``kernel_parameters`` (float64, built once per joint)::

    [R_j, R_b1, R_b2, L_b/2, L_j/2, K_line, K_plane / annulus area, n_r, n_a, c_e,
     friction code, 5 friction parameters, radial law code, 2 radial law parameters,
     dissipation code, 2 dissipation parameters, 10, disc rule (10 x 4)]

Status (:mod:`~clearance_contact.compiled`): 0 ok, ``STATUS_NONFINITE_INPUT``,
``STATUS_NONFINITE_PENETRATION``, ``STATUS_AXIS_TILT`` (journal at >= 90 deg), or
``STATUS_EXTERNAL_FRICTION`` for a user-defined friction law (every call): then
``friction_force`` holds the tangential slip v_t and ``SPIN_SPEED`` w_n r_s where
F_N > 0, the wrenches are not written, and :meth:`RevoluteClearanceJoint.evaluate`
applies the law and calls :func:`revolute_wrenches` (the kernel's own code).
"""

from __future__ import annotations

import math

import numpy as np

from .compiled import (
    STATUS_AXIS_TILT,
    STATUS_EXTERNAL_FRICTION,
    STATUS_NONFINITE_INPUT,
    STATUS_NONFINITE_PENETRATION,
    STATUS_OK,
    KernelAttribute,
    finite_state,
    norm2,
    jit,
)
from .errors import ContactError, ContactParameterError, require_in_range, require_positive
from .friction import (
    FRICTION_EXTERNAL,
    FRICTION_NONE,
    FRICTION_PARAMETERS,
    FrictionLaw,
    NoFriction,
    encoded_force_over_speed,
    user_friction_force,
    user_friction_gain,
)
from .dissipation import DEFAULT_DISSIPATION, DISSIPATION_PARAMETERS, dissipation_encoding, encoded_damping_factor
from .joint import ClearanceJoint, Shape, output_layout
from .materials import Material, flat_punch_stiffness, require_material
from .normal_force import EXPONENT_RANGE
from . import radial_laws
from .radial_laws import RADIAL_LAW_PARAMETERS, RadialLaw
from .radial_profile import RADIAL_NODES, dry_interval, half_integrals
from .registry import register_joint_type
from .result import KIND_LINE, KIND_NONE, KIND_PLANE, KIND_POINT

__all__ = ["RevoluteClearanceJoint", "revolute_kernel", "revolute_penetration_kernel", "revolute_wrenches"]

_MIN_AXIS_COSINE = 1.0e-6
"""Smallest accepted cos(tilt) = u_b . u_j (tilt < 89.99994 deg)."""

_TIE_DEPTH = 1.0e-14
"""Penetrations (m) closer than this count as equal when choosing the deepest end."""

_TIE_TILT = 1.0e-14
"""|sin(tilt)| below which the end faces count as parallel (rounding of unit vectors)."""

_CLOSED_FORM_MIN_ANGLE = 0.5
"""Rim half-angle (rad) of the contact crescent below which the n = 1 disc integrals
use the quadrature instead of the closed form (whose cancellation grows as angle^-2)."""

_QUAD_POINTS = 10


def _disc_rule(points: int, n: float) -> np.ndarray:
    """Nodes of the disc quadrature for the exponent n, phi = pi x, as rows
    (sin^2(phi/2), cos^2(phi/2), weight * pi/2 sin(phi), sin^2n(phi/2)): float64 (points, 4).

    x, weight: Gauss-Legendre on [0, 1]; pi/2 sin(phi) is d(sin^2(phi/2))/dx.
    """
    x, w = np.polynomial.legendre.leggauss(points)
    x = 0.5 * (x + 1.0)
    w = 0.5 * w
    nodes = []
    for xi, wi in zip(x.tolist(), w.tolist()):
        sh2 = math.sin(0.5 * math.pi * xi) ** 2
        nodes.append((sh2, math.cos(0.5 * math.pi * xi) ** 2, wi * 0.5 * math.pi * math.sin(math.pi * xi), sh2**n))
    return np.array(nodes, dtype=np.float64)


@jit
def _x_minus_sin(x: float) -> float:
    """x - sin(x) without cancellation (Taylor series below x = 1)."""
    if x >= 1.0:
        return x - math.sin(x)
    x2 = x * x
    # x^3/3! - x^5/5! + ... + x^17/17!  (truncation < x^19/19! < 1e-16 x^3/6)
    series = 1.0 - x2 / 272.0
    for k in (210.0, 156.0, 110.0, 72.0, 42.0, 20.0):
        series = 1.0 - x2 / k * series
    return x * x2 / 6.0 * series


@jit
def _disc_moments(dc: float, q: float, r: float, n: float, rule) -> tuple[float, float, float]:
    """Integrals over the disc |x| <= r of p = max(dc + q v, 0)^n, v = x_1 / r, q >= 0.

    Returns (D0, D1, D2) = (int p dA, int p x_1 dA, int p |x|^2 dA).  ``rule``:
    :func:`_disc_rule` for the exponent n, float64 (points, 4).  In the chord
    variable v (chord length 2 r sqrt(1 - v^2)), D_k = 2 r^2 int p m_k sqrt(1 - v^2) dv,
    m = 1, r v, r^2 (1 + 2 v^2)/3, over the contact v in [1 - y0, 1] with
    y0 = (dc + q)/q (partial; dc + q is the rim penetration) or y0 = 2 (full disc).
    """
    rim = dc + q
    if rim <= 0.0:
        return 0.0, 0.0, 0.0
    full = dc >= q
    y0 = 2.0 if full else rim / q
    th0 = math.pi if full else 2.0 * math.asin(math.sqrt(0.5 * y0))  # contact half-angle on the rim
    r2 = r * r
    if n == 1.0 and th0 >= _CLOSED_FORM_MIN_ANGLE:
        c0 = 1.0 - y0
        s02 = y0 * (2.0 - y0)
        s0 = math.sqrt(s02)
        s03 = s02 * s0
        s05 = s03 * s02
        sin2 = 2.0 * s0 * c0
        sin4 = 2.0 * sin2 * (c0 * c0 - s02)
        ia = 0.5 * (th0 - s0 * c0)  # int_0^th0 sin^2
        ib = s03 / 3.0  # int cos sin^2
        ic = th0 / 8.0 - sin4 / 32.0  # int cos^2 sin^2
        id_ = 3.0 * th0 / 8.0 - sin2 / 4.0 + sin4 / 32.0  # int sin^4
        ie = s03 / 3.0 - s05 / 5.0  # int cos^3 sin^2
        if_ = s05 / 5.0  # int cos sin^4
        return (
            2.0 * r2 * (dc * ia + q * ib),
            2.0 * r2 * r * (dc * ib + q * ic),
            2.0 * r2 * r2 * (dc * (ic + id_ / 3.0) + q * (ie + if_ / 3.0)),
        )
    # quadrature in phi: v = 1 - y0 cos^2(phi/2); the integrand p m_k sqrt(1 - v^2) is
    # smooth in phi at both ends (sqrt and p^n endpoint singularities absorbed)
    w_sum = s_0 = s_1 = s_2 = 0.0
    if full:  # p = dc + q v > 0 everywhere
        for i in range(rule.shape[0]):
            ch2 = rule[i, 1]
            wj = rule[i, 2]
            omv = 2.0 * ch2  # 1 - v
            v = 1.0 - omv
            wt = wj * math.sqrt(omv * (2.0 - omv))
            w_sum += wt
            wp = wt * (dc + q * v) ** n
            s_0 += wp
            s_1 += wp * v
            s_2 += wp * v * v
    else:  # crescent: p = dc + q v = rim sin^2(phi/2) exactly, p^n = rim^n sin^2n(phi/2)
        for i in range(rule.shape[0]):
            ch2 = rule[i, 1]
            wj = rule[i, 2]
            sh2n = rule[i, 3]
            omv = y0 * ch2
            v = 1.0 - omv
            wt = wj * math.sqrt(omv * (2.0 - omv))
            w_sum += wt
            wp = wt * sh2n
            s_0 += wp
            s_1 += wp * v
            s_2 += wp * v * v
        rim_n = rim**n
        s_0 *= rim_n
        s_1 *= rim_n
        s_2 *= rim_n
    # normalise to the exact int_{1-y0}^1 sqrt(1 - v^2) dv = (2 th0 - sin(2 th0)) / 4, so a
    # uniform pressure (aligned faces) is integrated exactly
    scale = 2.0 * r2 * 0.25 * _x_minus_sin(2.0 * th0) / w_sum
    return scale * s_0, scale * r * s_1, scale * r2 * (s_0 + 2.0 * s_2) / 3.0


# -- kernel_parameters layout -----------------------------------------------------------
_P_JOURNAL_RADIUS = 0
_P_BORE_RADIUS = 1
_P_OUTER_RADIUS = 2
_P_HALF_BEARING_LENGTH = 3
_P_HALF_JOURNAL_LENGTH = 4
_P_LINE_STIFFNESS = 5
_P_PLANE_DENSITY = 6
_P_RADIAL_EXPONENT = 7
_P_AXIAL_EXPONENT = 8
_P_RESTITUTION = 9
_P_FRICTION = 10  # kind code, then FRICTION_PARAMETERS values
_P_RADIAL_LAW = _P_FRICTION + 1 + FRICTION_PARAMETERS  # code, then RADIAL_LAW_PARAMETERS values
_P_DISSIPATION = _P_RADIAL_LAW + 1 + RADIAL_LAW_PARAMETERS  # code, then DISSIPATION_PARAMETERS values
_P_QUAD_POINTS = _P_DISSIPATION + 1 + DISSIPATION_PARAMETERS
_P_QUAD_RULE = _P_QUAD_POINTS + 1  # _QUAD_POINTS rows of 4 (see _disc_rule)
_N_PARAMETERS = _P_QUAD_RULE + 4 * _QUAD_POINTS

# -- out layout (k = 4 candidates, r = 2 eccentricity rows) -------------------------------
_K = 4
# internal sections (k each, after the common layout): what the wrenches and a Python friction law need:
# CENTROID_DEPTH penetration at the centroid (P = point_outer + CENTROID_DEPTH / 2 * normal), SPIN_RADIUS
# rms radius r_s of the pressure about P (m), SPIN_SPEED spin slip w_n r_s (m/s) where friction was
# evaluated, SPIN_TORQUE friction torque T_spin about the normal on the journal (N m), NORMAL_COUPLE
# couple of the normal pressure about the normal on the journal (N m): the pitch of the radial wrench
# under a skew tilt (module docstring), 0 for the axial candidates
_EXTRA_OUTPUTS = ("CENTROID_DEPTH", "SPIN_RADIUS", "SPIN_SPEED", "SPIN_TORQUE", "NORMAL_COUPLE")
_LAYOUT = output_layout(_K, 2, _EXTRA_OUTPUTS)
PENETRATION = _LAYOUT["PENETRATION"]
PENETRATION_RATE = _LAYOUT["PENETRATION_RATE"]
NORMAL_FORCE = _LAYOUT["NORMAL_FORCE"]
NORMAL = _LAYOUT["NORMAL"]
POINT_OUTER = _LAYOUT["POINT_OUTER"]
POINT_INNER = _LAYOUT["POINT_INNER"]
FRICTION_FORCE = _LAYOUT["FRICTION_FORCE"]
ECCENTRICITY = _LAYOUT["ECCENTRICITY"]
WRENCH_OUTER = _LAYOUT["WRENCH_OUTER"]
WRENCH_INNER = _LAYOUT["WRENCH_INNER"]
KIND = _LAYOUT["KIND"]
CENTROID_DEPTH = _LAYOUT["CENTROID_DEPTH"]
SPIN_RADIUS = _LAYOUT["SPIN_RADIUS"]
SPIN_SPEED = _LAYOUT["SPIN_SPEED"]
SPIN_TORQUE = _LAYOUT["SPIN_TORQUE"]
NORMAL_COUPLE = _LAYOUT["NORMAL_COUPLE"]
OUTPUT_SIZE = _LAYOUT["OUTPUT_SIZE"]


@jit
def _slice_penetration(ex: float, ey: float, tx: float, ty: float, beta: float, r_j: float, r_b1: float) -> float:
    """Radial penetration of the slice with eccentricity (ex, ey); beta = R_j |t|^2 (module docstring)."""
    ee = ex * ex + ey * ey
    d = ee + beta * beta
    s = tx * ex + ty * ey
    x = (s * s + beta * beta * (tx * tx + ty * ty)) / d if d > 0.0 else 0.0
    return math.sqrt(ee) + r_j * math.sqrt(1.0 + x) - r_b1


@jit
def _slice_state(z, mx, my, mdx, mdy, tx, ty, tdx, tdy, t_abs, bb, bbd, bbtt, bbtt_dot, r_j, r_b1):
    """(delta, delta_dot, hx, hy) of the slice z: penetration |e| + R_j sqrt(1 + x) - R_b1,
    its rate, and the unit eccentricity direction (module docstring), e(z) = m + z t."""
    ex = mx + z * tx
    ey = my + z * ty
    edx = mdx + z * tdx
    edy = mdy + z * tdy
    ee = ex * ex + ey * ey
    e = math.sqrt(ee)
    if e > 0.0:
        hx = ex / e
        hy = ey / e
        e_dot = hx * edx + hy * edy
    else:  # on the bearing axis: direction of the tilt, right derivative of |e|
        if t_abs > 0.0:
            hx = tx / t_abs
            hy = ty / t_abs
        else:
            hx = 1.0
            hy = 0.0
        e_dot = norm2(edx, edy)
    d = ee + bb
    if d > 0.0:
        sp = tx * ex + ty * ey
        sp_dot = tdx * ex + tdy * ey + tx * edx + ty * edy
        num = sp * sp + bbtt
        x = num / d
        if d * d >= 2.2250738585072014e-308:  # the smallest normal double: below it d * d loses digits, then underflows
            x_dot = ((2.0 * sp * sp_dot + bbtt_dot) * d - 2.0 * num * (ex * edx + ey * edy + bbd)) / (d * d)
        else:  # d < ~1.5e-154 (a centred journal tilted by rounding): the same quotient, divided by d once
            x_dot = ((2.0 * sp * sp_dot + bbtt_dot) - 2.0 * x * (ex * edx + ey * edy + bbd)) / d
    else:
        x = 0.0
        x_dot = 0.0
    root = math.sqrt(1.0 + x)
    return e + r_j * root - r_b1, e_dot + 0.5 * r_j * x_dot / root, hx, hy


@jit
def _write3(out, offset, x, y, z):
    out[offset] = x
    out[offset + 1] = y
    out[offset + 2] = z


@jit
def _entries(matrix):
    """The 9 entries of a (3, 3) array, row by row, as floats (any memory layout)."""
    return (
        matrix[0, 0], matrix[0, 1], matrix[0, 2],
        matrix[1, 0], matrix[1, 1], matrix[1, 2],
        matrix[2, 0], matrix[2, 1], matrix[2, 2],
    )


@jit
def _transpose_times(r00, r01, r02, r10, r11, r12, r20, r21, r22, x, y, z):
    """R^T (x, y, z): a world vector in the bearing frame (R given row by row)."""
    return (
        r00 * x + r10 * y + r20 * z,
        r01 * x + r11 * y + r21 * z,
        r02 * x + r12 * y + r22 * z,
    )


@jit
def _write_candidate(out, k, nx, ny, nz, ox, oy, oz, delta_c, spin_radius, force_n, couple):
    """Candidate ``k``'s normal, contact points, centroid depth, spin radius, normal force and couple into ``out``."""
    _write3(out, NORMAL + 3 * k, nx, ny, nz)
    _write3(out, POINT_OUTER + 3 * k, ox, oy, oz)
    _write3(out, POINT_INNER + 3 * k, ox + delta_c * nx, oy + delta_c * ny, oz + delta_c * nz)
    out[CENTROID_DEPTH + k] = delta_c
    out[SPIN_RADIUS + k] = spin_radius
    out[NORMAL_FORCE + k] = force_n
    out[NORMAL_COUPLE + k] = couple


@jit
def _force_point_arms(out, k, pjx, pjy, pjz, dpx, dpy, dpz):
    """Candidate ``k``'s normal n and the lever arms P - o_j, P - o_b of its force point
    P = point_outer + delta_c / 2 n (``dp = o_j - o_b``)."""
    nx = out[NORMAL + 3 * k]
    ny = out[NORMAL + 3 * k + 1]
    nz = out[NORMAL + 3 * k + 2]
    half = 0.5 * out[CENTROID_DEPTH + k]
    rjx = out[POINT_OUTER + 3 * k] + half * nx - pjx
    rjy = out[POINT_OUTER + 3 * k + 1] + half * ny - pjy
    rjz = out[POINT_OUTER + 3 * k + 2] + half * nz - pjz
    return nx, ny, nz, rjx, rjy, rjz, rjx + dpx, rjy + dpy, rjz + dpz


@jit(exports=("void(f8[::1], f8[::1], f8[::1])",))  # _apply_external_friction's call (a user-defined friction law)
def revolute_wrenches(outer_position, inner_position, out):
    """Write ``out[WRENCH_OUTER:WRENCH_INNER + 6]`` from the forces in ``out`` (module docstring).

    Each candidate with F_N > 0 acts at P = point_outer + delta_c / 2 n: on the journal
    f = -F_N n + F_t at P plus (T_spin + normal couple) n, on the bearing the opposite;
    moments about each element's frame origin.
    """
    pbx = outer_position[0]
    pby = outer_position[1]
    pbz = outer_position[2]
    pjx = inner_position[0]
    pjy = inner_position[1]
    pjz = inner_position[2]
    dpx = pjx - pbx
    dpy = pjy - pby
    dpz = pjz - pbz
    fix = fiy = fiz = 0.0  # force on the journal
    mix = miy = miz = 0.0  # moment on the journal about o_j
    mox = moy = moz = 0.0  # moment on the bearing about o_b
    for k in range(_K):
        force_n = out[NORMAL_FORCE + k]
        if force_n <= 0.0:
            continue
        nx, ny, nz, rjx, rjy, rjz, rbx, rby, rbz = _force_point_arms(out, k, pjx, pjy, pjz, dpx, dpy, dpz)
        t_spin = out[SPIN_TORQUE + k] + out[NORMAL_COUPLE + k]
        fx = -force_n * nx + out[FRICTION_FORCE + 3 * k]
        fy = -force_n * ny + out[FRICTION_FORCE + 3 * k + 1]
        fz = -force_n * nz + out[FRICTION_FORCE + 3 * k + 2]
        tsx = t_spin * nx
        tsy = t_spin * ny
        tsz = t_spin * nz
        fix += fx
        fiy += fy
        fiz += fz
        mix += rjy * fz - rjz * fy + tsx
        miy += rjz * fx - rjx * fz + tsy
        miz += rjx * fy - rjy * fx + tsz
        mox -= rby * fz - rbz * fy + tsx
        moy -= rbz * fx - rbx * fz + tsy
        moz -= rbx * fy - rby * fx + tsz
    _write3(out, WRENCH_OUTER, -fix, -fiy, -fiz)
    _write3(out, WRENCH_OUTER + 3, mox, moy, moz)
    _write3(out, WRENCH_INNER, fix, fiy, fiz)
    _write3(out, WRENCH_INNER + 3, mix, miy, miz)


@jit(exports=(
        "i8(f8[::1], f8[:, ::1], f8[::1], f8[:, ::1], f8[::1], f8[::1])",
        "i8(f8[::1], f8[::1, :], f8[::1], f8[:, ::1], f8[::1], f8[::1])",
        "i8(f8[::1], f8[::1, :], f8[::1], f8[::1, :], f8[::1], f8[::1])",
        "i8(f8[::1], f8[:, ::1], f8[::1], f8[::1, :], f8[::1], f8[::1])",
    ))
def revolute_penetration_kernel(parameters, outer_rotation, outer_position, inner_rotation, inner_position, out):
    """``out[0:4]`` = deepest penetration (m) of [top_radial, top_axial, bottom_radial, bottom_axial].

    No velocities, no forces (for event functions).  Returns ``STATUS_OK``,
    ``STATUS_NONFINITE_INPUT`` (non-finite rotations) or ``STATUS_AXIS_TILT``; NaN
    positions give NaN penetrations with ``STATUS_OK``.
    """
    r00, r01, r02, r10, r11, r12, r20, r21, r22 = _entries(outer_rotation)
    ujx = inner_rotation[0, 2]
    ujy = inner_rotation[1, 2]
    ujz = inner_rotation[2, 2]
    dpx = inner_position[0] - outer_position[0]
    dpy = inner_position[1] - outer_position[1]
    dpz = inner_position[2] - outer_position[2]
    ax, ay, az = _transpose_times(r00, r01, r02, r10, r11, r12, r20, r21, r22, dpx, dpy, dpz)
    dx, dy, dz = _transpose_times(r00, r01, r02, r10, r11, r12, r20, r21, r22, ujx, ujy, ujz)
    if not dz > _MIN_AXIS_COSINE:
        return STATUS_AXIS_TILT if math.isfinite(dz) else STATUS_NONFINITE_INPUT
    r_j = parameters[_P_JOURNAL_RADIUS]
    r_b1 = parameters[_P_BORE_RADIUS]
    tx = dx / dz
    ty = dy / dz
    hl = parameters[_P_HALF_BEARING_LENGTH]
    mx = ax - az * tx
    my = ay - az * ty
    beta = r_j * (tx * tx + ty * ty)
    d_mid = _slice_penetration(mx, my, tx, ty, beta, r_j, r_b1)
    d_top = _slice_penetration(mx + hl * tx, my + hl * ty, tx, ty, beta, r_j, r_b1)
    d_bot = _slice_penetration(mx - hl * tx, my - hl * ty, tx, ty, beta, r_j, r_b1)
    ad = ax * dx + ay * dy + az * dz
    base = hl * dz - parameters[_P_HALF_JOURNAL_LENGTH]
    gr2 = norm2(dx, dy) * parameters[_P_OUTER_RADIUS]
    out[0] = max(d_mid, d_top)
    out[1] = (base - ad) + gr2
    out[2] = max(d_mid, d_bot)
    out[3] = (base + ad) + gr2
    return STATUS_OK


@jit(exports=(
        "i8(f8[::1], f8[::1, :], f8[::1], f8[::1], f8[:, ::1], f8[::1], f8[::1], f8[::1], f8[::1])",
        "i8(f8[::1], f8[::1, :], f8[::1], f8[::1], f8[::1, :], f8[::1], f8[::1], f8[::1], f8[::1])",
        # rotations as numpy makes them (C order): the public evaluate() and the Newton-Euler engine
        "i8(f8[::1], f8[:, ::1], f8[::1], f8[::1], f8[:, ::1], f8[::1], f8[::1], f8[::1], f8[::1])",
        "i8(f8[::1], f8[:, ::1], f8[::1], f8[::1], f8[::1, :], f8[::1], f8[::1], f8[::1], f8[::1])",
    ))
def revolute_kernel(
    parameters, outer_rotation, outer_position, outer_twist, inner_rotation, inner_position, inner_twist, onset_rates, out
):
    """Compiled contact law of the revolute joint (module docstring): state in, ``out`` written, status returned.

    ``parameters``: ``RevoluteClearanceJoint.kernel_parameters``; rotations (3, 3) (C or
    Fortran order), positions (3,), twists (6,) = [v, w], ``onset_rates`` (4,), all
    float64; ``out``: float64 (``OUTPUT_SIZE``,), layout in the module docstring.
    Returns ``STATUS_OK`` (0) or a nonzero ``STATUS_*`` code of
    :mod:`~clearance_contact.compiled`.
    """
    if not finite_state(
        outer_rotation, outer_position, outer_twist, inner_rotation, inner_position, inner_twist, onset_rates
    ):
        return STATUS_NONFINITE_INPUT
    r00, r01, r02, r10, r11, r12, r20, r21, r22 = _entries(outer_rotation)
    j00, j01, j02, j10, j11, j12, j20, j21, j22 = _entries(inner_rotation)
    pbx = outer_position[0]
    pby = outer_position[1]
    pbz = outer_position[2]
    pjx = inner_position[0]
    pjy = inner_position[1]
    pjz = inner_position[2]
    vbx = outer_twist[0]
    vby = outer_twist[1]
    vbz = outer_twist[2]
    wbx = outer_twist[3]
    wby = outer_twist[4]
    wbz = outer_twist[5]
    vjx = inner_twist[0]
    vjy = inner_twist[1]
    vjz = inner_twist[2]
    wjx = inner_twist[3]
    wjy = inner_twist[4]
    wjz = inner_twist[5]

    r_j = parameters[_P_JOURNAL_RADIUS]
    r_b1 = parameters[_P_BORE_RADIUS]
    r_b2 = parameters[_P_OUTER_RADIUS]
    hl = parameters[_P_HALF_BEARING_LENGTH]
    # journal axis and origin in the bearing frame (a0, d) and their rates
    dpx = pjx - pbx
    dpy = pjy - pby
    dpz = pjz - pbz
    ax, ay, az = _transpose_times(r00, r01, r02, r10, r11, r12, r20, r21, r22, dpx, dpy, dpz)
    dx, dy, dz = _transpose_times(r00, r01, r02, r10, r11, r12, r20, r21, r22, j02, j12, j22)
    if not dz > _MIN_AXIS_COSINE:
        return STATUS_AXIS_TILT
    # d(o_j - o_b)/dt seen from the bearing: dv - w_b x dp
    qx = vjx - vbx - (wby * dpz - wbz * dpy)
    qy = vjy - vby - (wbz * dpx - wbx * dpz)
    qz = vjz - vbz - (wbx * dpy - wby * dpx)
    adx, ady, adz = _transpose_times(r00, r01, r02, r10, r11, r12, r20, r21, r22, qx, qy, qz)
    # d(u_j)/dt seen from the bearing: (w_j - w_b) x u_j
    wrx = wjx - wbx
    wry = wjy - wby
    wrz = wjz - wbz
    ux = wry * j22 - wrz * j12
    uy = wrz * j02 - wrx * j22
    uz = wrx * j12 - wry * j02
    ddx, ddy, ddz = _transpose_times(r00, r01, r02, r10, r11, r12, r20, r21, r22, ux, uy, uz)

    # ---- radial: slices z = 0, +l, -l; e(z) = m + z t ------------------------------
    tx = dx / dz
    ty = dy / dz
    tdx = (ddx * dz - dx * ddz) / (dz * dz)
    tdy = (ddy * dz - dy * ddz) / (dz * dz)
    mx = ax - az * tx
    my = ay - az * ty
    mdx = adx - adz * tx - az * tdx
    mdy = ady - adz * ty - az * tdy
    # slice penetration |e| + R_j sqrt(1 + x) - R_b1 and its rate (module docstring),
    # x = ((t.e)^2 + beta^2 |t|^2) / (|e|^2 + beta^2), beta = R_j |t|^2
    tt = tx * tx + ty * ty
    tt_dot = 2.0 * (tx * tdx + ty * tdy)
    beta = r_j * tt
    bb = beta * beta
    bbd = beta * r_j * tt_dot  # beta d(beta)/dt
    bbtt = bb * tt
    bbtt_dot = 2.0 * bbd * tt + bb * tt_dot
    t_abs = math.sqrt(tt)
    mid = _slice_state(0.0, mx, my, mdx, mdy, tx, ty, tdx, tdy, t_abs, bb, bbd, bbtt, bbtt_dot, r_j, r_b1)
    top = _slice_state(hl, mx, my, mdx, mdy, tx, ty, tdx, tdy, t_abs, bb, bbd, bbtt, bbtt_dot, r_j, r_b1)
    bot = _slice_state(-hl, mx, my, mdx, mdy, tx, ty, tdx, tdy, t_abs, bb, bbd, bbtt, bbtt_dot, r_j, r_b1)

    # ---- axial: delta(x) = delta_c +- g.x on each end face -------------------------
    ad = ax * dx + ay * dy + az * dz
    ad_dot = adx * dx + ady * dy + adz * dz + ax * ddx + ay * ddy + az * ddz
    g = norm2(dx, dy)
    base = hl * dz - parameters[_P_HALF_JOURNAL_LENGTH]
    base_dot = hl * ddz
    if g > _TIE_TILT:
        gx = dx / g
        gy = dy / g
        g_dot = gx * ddx + gy * ddy
    else:  # parallel faces: kink of |g|, right derivative |g_dot| (towards where it tilts)
        g_dot = norm2(ddx, ddy)
        if g_dot > 0.0:
            gx = ddx / g_dot
            gy = ddy / g_dot
        else:
            gx = 1.0
            gy = 0.0

    # axes (world) of both elements
    b1x, b1y, b1z = r00, r10, r20
    b2x, b2y, b2z = r01, r11, r21
    ubx, uby, ubz = r02, r12, r22
    ujx, ujy, ujz = j02, j12, j22

    # ---- radial candidates 0 (top, z in [0, l]) and 2 (bottom, z in [-l, 0]) ------------
    # exact profile: wrench = -grad of the elastic energy, quadrature over the wetted
    # pieces (radial_profile), pointwise damping
    z_a, z_b, dry = dry_interval(mx, my, tx, ty, r_j, r_b1)
    a, a_dot = mid[0], mid[1]
    for k in (0, 2):
        if k == 0:
            end = top
            h0 = 0.0
            h1 = hl
        else:
            end = bot
            h0 = -hl
            h1 = 0.0
        b, b_dot = end[0], end[1]
        deep = b >= a
        delta_max = b if deep else a
        out[PENETRATION + k] = delta_max
        if b - a > _TIE_DEPTH or a - b > _TIE_DEPTH:
            out[PENETRATION_RATE + k] = b_dot if deep else a_dot
        else:  # kink of max(a, b): right derivative
            out[PENETRATION_RATE + k] = b_dot if b_dot > a_dot else a_dot
        s0 = 0.0
        if delta_max > 0.0:
            sgx, sgy, szgx, szgy, sgtx, sgty, s0, s1, s2, sd = half_integrals(
                h0, h1, z_a, z_b, mx, my, tx, ty, mdx, mdy, tdx, tdy, r_j, r_b1, onset_rates[k],
                parameters, _P_RADIAL_LAW, _P_DISSIPATION, RADIAL_NODES,
            )
        if s0 > 0.0:
            z_c = s1 / s0
            var = s2 / s0 - z_c * z_c
            delta_c = sd / s0
            spin_radius = math.sqrt(var) if var > 0.0 else 0.0
            whole = a > 0.0 and b > 0.0 and (not dry or z_b <= h0 or z_a >= h1)
            out[KIND + k] = KIND_LINE if whole else KIND_POINT
            ex = mx + z_c * tx
            ey = my + z_c * ty
            e = norm2(ex, ey)
            if e > 0.0:
                hx = ex / e
                hy = ey / e
            else:
                hx, hy = end[2], end[3]
            # F = (-S_g, S_g.t), M = -d x (S_G, -S_G.t) / d_z (bearing axes, about o_j)
            fbz = sgx * tx + sgy * ty
            sgx_ = szgx - az * sgx + sgtx
            sgy_ = szgy - az * sgy + sgty
            vx = sgx_ / dz
            vy = sgy_ / dz
            vz = -(sgx_ * tx + sgy_ * ty) / dz
            fwx = -(r00 * sgx + r01 * sgy) + r02 * fbz
            fwy = -(r10 * sgx + r11 * sgy) + r12 * fbz
            fwz = -(r20 * sgx + r21 * sgy) + r22 * fbz
            mbx = dz * vy - dy * vz
            mby = dx * vz - dz * vx
            mbz = dy * vx - dx * vy
            mwx = r00 * mbx + r01 * mby + r02 * mbz
            mwy = r10 * mbx + r11 * mby + r12 * mbz
            mwz = r20 * mbx + r21 * mby + r22 * mbz
            force_n = math.sqrt(fwx * fwx + fwy * fwy + fwz * fwz)
        else:
            force_n = spin_radius = 0.0
            out[KIND + k] = KIND_NONE
            z_c = h1 if (deep and k == 0) or (not deep and k == 2) else h0
            delta_c = delta_max
            if deep:
                hx, hy = end[2], end[3]
            else:
                hx, hy = mid[2], mid[3]
        # centroid's point half-way between the bore and the journal, radial direction r
        rx = hx * b1x + hy * b2x
        ry = hx * b1y + hy * b2y
        rz = hx * b1z + hy * b2z
        arm = r_b1 + 0.5 * delta_c
        cx = pbx + z_c * ubx + arm * rx
        cy = pby + z_c * uby + arm * ry
        cz = pbz + z_c * ubz + arm * rz
        couple = 0.0
        if force_n > 0.0:
            # the resultant as a screw: force along -n through P, couple along n
            nx = -fwx / force_n
            ny = -fwy / force_n
            nz = -fwz / force_n
            inv = 1.0 / (force_n * force_n)
            p0x = (fwy * mwz - fwz * mwy) * inv  # point of the axis nearest o_j, relative to o_j
            p0y = (fwz * mwx - fwx * mwz) * inv
            p0z = (fwx * mwy - fwy * mwx) * inv
            along = (cx - pjx - p0x) * nx + (cy - pjy - p0y) * ny + (cz - pjz - p0z) * nz
            cx = pjx + p0x + along * nx
            cy = pjy + p0y + along * ny
            cz = pjz + p0z + along * nz
            couple = mwx * nx + mwy * ny + mwz * nz
        else:  # no force: the radial direction normal to the journal axis
            ru = rx * ujx + ry * ujy + rz * ujz
            nx = rx - ru * ujx
            ny = ry - ru * ujy
            nz = rz - ru * ujz
            nn = math.sqrt(nx * nx + ny * ny + nz * nz)
            nx = nx / nn
            ny = ny / nn
            nz = nz / nn
        half_c = 0.5 * delta_c
        _write_candidate(out, k, nx, ny, nz, cx - half_c * nx, cy - half_c * ny, cz - half_c * nz,
                         delta_c, spin_radius, force_n, couple)

    # ---- axial candidates 1 (top face) and 3 (bottom face) --------------------------------
    n_a = parameters[_P_AXIAL_EXPONENT]
    n_quad = int(parameters[_P_QUAD_POINTS])
    rule = parameters[_P_QUAD_RULE : _P_QUAD_RULE + 4 * n_quad].reshape((n_quad, 4))
    plane_density = parameters[_P_PLANE_DENSITY]
    gr2 = g * r_b2
    gr1 = g * r_b1
    for k in (1, 3):
        if k == 1:
            ring = 1.0
            dcen = base - ad
            dcen_dot = base_dot - ad_dot
        else:
            ring = -1.0
            dcen = base + ad
            dcen_dot = base_dot + ad_dot
        # deepest-point direction on the face (bearing frame): +g at the top, -g at the bottom
        sx = ring * gx
        sy = ring * gy
        delta_max = dcen + gr2
        out[PENETRATION + k] = delta_max
        out[PENETRATION_RATE + k] = dcen_dot + r_b2 * g_dot
        if delta_max > 0.0:
            o0, o1, o2 = _disc_moments(dcen, gr2, r_b2, n_a, rule)
            i0, i1, i2 = _disc_moments(dcen, gr1, r_b1, n_a, rule)
            m0 = o0 - i0
            f_el = plane_density * m0
            out[KIND + k] = KIND_PLANE if dcen - gr2 > 0.0 else KIND_POINT
            if m0 > 0.0 and g > _TIE_TILT:
                xc = (o1 - i1) / m0
                var = (o2 - i2) / m0 - xc * xc
            elif m0 > 0.0:  # parallel faces: centroid on the axis
                xc = 0.0
                var = (o2 - i2) / m0
            else:  # vanishing crescent at the rim
                xc = r_b2
                var = 0.0
            delta_c = dcen + g * xc
            # rate at the centroid: d(delta_c)/dt +- g_dot . x_c (same expression for both faces)
            rate_c = dcen_dot + xc * (ddx * gx + ddy * gy)
            spin_radius = math.sqrt(var) if var > 0.0 else 0.0
        else:
            f_el = rate_c = spin_radius = 0.0
            out[KIND + k] = KIND_NONE
            xc = r_b2
            delta_c = delta_max
        cx = xc * sx
        cy = xc * sy
        # n = -u_j at the top flange, +u_j at the bottom one
        nx = -ring * ujx
        ny = -ring * ujy
        nz = -ring * ujz
        ox = pbx + ring * hl * ubx + cx * b1x + cy * b2x
        oy = pby + ring * hl * uby + cx * b1y + cy * b2y
        oz = pbz + ring * hl * ubz + cx * b1z + cy * b2z
        force_n = 0.0
        if f_el > 0.0:
            force_n = f_el * encoded_damping_factor(parameters, _P_DISSIPATION, rate_c, onset_rates[k])
            force_n = force_n if force_n > 0.0 else 0.0
        _write_candidate(out, k, nx, ny, nz, ox, oy, oz, delta_c, spin_radius, force_n, 0.0)

    if not math.isfinite(out[PENETRATION] + out[PENETRATION + 1] + out[PENETRATION + 2] + out[PENETRATION + 3]):
        return STATUS_NONFINITE_PENETRATION

    # eccentricity: ring centres o_b +- l u_b relative to o_j, in the journal frame
    cx = -(j00 * dpx + j10 * dpy + j20 * dpz)
    cy = -(j01 * dpx + j11 * dpy + j21 * dpz)
    cz = -(ujx * dpx + ujy * dpy + ujz * dpz)
    ux_ = hl * (j00 * ubx + j10 * uby + j20 * ubz)
    uy_ = hl * (j01 * ubx + j11 * uby + j21 * ubz)
    uz_ = hl * dz
    _write3(out, ECCENTRICITY, cx + ux_, cy + uy_, cz + uz_)
    _write3(out, ECCENTRICITY + 3, cx - ux_, cy - uy_, cz - uz_)

    # ---- friction: slip of the journal's material point at P relative to the bearing's ------
    code = int(parameters[_P_FRICTION])
    for k in range(_K):
        force_n = out[NORMAL_FORCE + k]
        ftx = fty = ftz = spin = t_spin = 0.0
        if force_n > 0.0 and code != FRICTION_NONE:
            nx, ny, nz, rjx, rjy, rjz, rbx, rby, rbz = _force_point_arms(out, k, pjx, pjy, pjz, dpx, dpy, dpz)
            sx_ = vjx + (wjy * rjz - wjz * rjy) - vbx - (wby * rbz - wbz * rby)
            sy_ = vjy + (wjz * rjx - wjx * rjz) - vby - (wbz * rbx - wbx * rbz)
            sz_ = vjz + (wjx * rjy - wjy * rjx) - vbz - (wbx * rby - wby * rbx)
            sn = sx_ * nx + sy_ * ny + sz_ * nz
            vtx = sx_ - sn * nx
            vty = sy_ - sn * ny
            vtz = sz_ - sn * nz
            spin_radius = out[SPIN_RADIUS + k]
            spin = (wrx * nx + wry * ny + wrz * nz) * spin_radius
            if code == FRICTION_EXTERNAL:  # the slip, for Python to apply the law
                ftx = vtx
                fty = vty
                ftz = vtz
            else:
                gain = encoded_force_over_speed(
                    parameters, _P_FRICTION, force_n, math.sqrt(vtx * vtx + vty * vty + vtz * vtz + spin * spin)
                )
                ftx = -gain * vtx
                fty = -gain * vty
                ftz = -gain * vtz
                t_spin = -gain * spin * spin_radius
        _write3(out, FRICTION_FORCE + 3 * k, ftx, fty, ftz)
        out[SPIN_SPEED + k] = spin
        out[SPIN_TORQUE + k] = t_spin
    if code == FRICTION_EXTERNAL:
        return STATUS_EXTERNAL_FRICTION
    revolute_wrenches(outer_position, inner_position, out)
    return STATUS_OK


def _checked_geometry(journal_radius, bearing_inner_radius, bearing_outer_radius, journal_length, bearing_length) -> tuple[float, ...]:
    """The five dimensions as floats, checked: all positive, R_j < R_b1 < R_b2, L_j > L_b (else ContactParameterError)."""
    r_j = require_positive("journal_radius", journal_radius)
    r_b1 = require_positive("bearing_inner_radius", bearing_inner_radius)
    r_b2 = require_positive("bearing_outer_radius", bearing_outer_radius)
    l_j = require_positive("journal_length", journal_length)
    l_b = require_positive("bearing_length", bearing_length)
    if not r_b1 > r_j:
        raise ContactParameterError(
            f"journal_radius={journal_radius!r} must be smaller than bearing_inner_radius="
            f"{bearing_inner_radius!r} (radial clearance > 0; valid range (0, {r_b1:g}))",
            key="journal_radius", value=journal_radius,
        )  # fmt: skip
    if not r_b2 > r_b1:
        raise ContactParameterError(
            f"bearing_outer_radius={bearing_outer_radius!r} must be larger than bearing_inner_radius="
            f"{bearing_inner_radius!r} (valid range ({r_b1:g}, inf))",
            key="bearing_outer_radius", value=bearing_outer_radius,
        )  # fmt: skip
    if not l_j > l_b:
        raise ContactParameterError(
            f"journal_length={journal_length!r} must be larger than bearing_length={bearing_length!r} "
            f"(axial clearance > 0; valid range ({l_b:g}, inf))",
            key="journal_length", value=journal_length,
        )  # fmt: skip
    return r_j, r_b1, r_b2, l_j, l_b


@register_joint_type
class RevoluteClearanceJoint(ClearanceJoint):
    """Flanged journal (inner element) in a bearing (outer element) with radial and axial clearance.

    See the module docstring for the geometry, the contact law and their accuracy.

    Parameters
    ----------
    journal_radius:
        R_j in m, range (0, bearing_inner_radius).
    bearing_inner_radius, bearing_outer_radius:
        R_b1, R_b2 in m: bore radius, range (journal_radius, inf); outer radius of the
        bearing's end faces (the annulus R_b1..R_b2 meets the flanges), range
        (bearing_inner_radius, inf).
    journal_length:
        L_j in m, distance between the inner faces of the two flanges, range
        (bearing_length, inf).
    bearing_length:
        L_b in m, range (0, journal_length).
    journal_material, bearing_material:
        :class:`~clearance_contact.materials.Material` of each element.
    restitution:
        c_e of the damping, range (0, 1].
    dissipation:
        Normal dissipation model, a name of
        :data:`~clearance_contact.dissipation.DISSIPATION_MODELS`; default
        ``"lankarani_nikravesh"``.
    radial_law:
        Radial contact law, a name of :data:`~clearance_contact.radial_laws.RADIAL_LAWS`;
        default ``"linear"`` (K_line delta^n_r); the others set their own stiffness and
        exponent (leave ``radial_stiffness`` / ``radial_exponent`` unset).
    radial_exponent, axial_exponent:
        n_r, n_a of the line and plane laws, range [1, 1.5]; default 1 (linear laws of
        the default stiffnesses).
    point_exponent, point_stiffness:
        Accepted and validated (range [1, 1.5]; None or (0, inf)) for the interface
        contract; not used by the distributed formulation (module docstring).
    friction:
        A :class:`~clearance_contact.friction.FrictionLaw`; default no friction.
    radial_stiffness:
        K_line in N/m^n_r for the whole bearing length, range (0, inf); None: pi/4 E* L_b
        (requires n_r = 1).
    axial_stiffness:
        K_plane in N/m^n_a for one whole annular face, range (0, inf); None: 2 E* R_b2
        (requires n_a = 1).

    Joint type ``"revolute"`` (:mod:`~clearance_contact.registry`); scene keys
    ``journal_radius``, ``radial_clearance`` (c_r), ``bearing_outer_radius``,
    ``bearing_length``, ``axial_clearance`` (c_a), the exponents and stiffnesses, and the
    names ``radial_law`` and ``dissipation``.
    """

    __slots__ = (
        "_r_j",
        "_r_b1",
        "_r_b2",
        "_l_j",
        "_l_b",
        "_journal_material",
        "_bearing_material",
        "_n_r",
        "_n_a",
        "_n_p",
        "_k_line",
        "_k_plane",
        "_k_point",
        "_radial_law",
        "_plane_density",
        "_half_l_b",
        "_half_l_j",
        "_disc_rule",
    )

    type_name = "revolute"
    N_CANDIDATES = _K
    N_ECCENTRICITY = 2
    EXTRA_OUTPUTS = _EXTRA_OUTPUTS
    SITE_KINDS = ("revolute",)
    SCENE_KEYS = (
        "journal_radius", "radial_clearance", "bearing_outer_radius", "bearing_length", "axial_clearance",
        "radial_exponent", "axial_exponent", "point_exponent", "radial_stiffness", "axial_stiffness", "point_stiffness",
        "radial_law", "dissipation",
    )  # fmt: skip
    NAME_KEYS = ("radial_law", "dissipation")
    REQUIRED_KEYS = ("journal_radius", "radial_clearance", "bearing_outer_radius", "bearing_length", "axial_clearance")
    GEOMETRY_KEYS = REQUIRED_KEYS
    GAP_KEYS = ("radial_clearance", "axial_clearance")
    FORCE_GROUPS = {"radial": (0, 2), "axial": (1, 3)}
    DEFAULT_GEOMETRY = {
        "journal_radius": 0.02, "radial_clearance": 1.0e-4, "bearing_outer_radius": 0.035, "bearing_length": 0.04, "axial_clearance": 1.0e-4,
    }  # fmt: skip
    KERNEL_ID = 1
    EXAGGERATE_TILT = True
    kernel = KernelAttribute(revolute_kernel)
    penetration_kernel = staticmethod(revolute_penetration_kernel)

    def __init__(
        self,
        journal_radius: float,
        bearing_inner_radius: float,
        bearing_outer_radius: float,
        journal_length: float,
        bearing_length: float,
        journal_material: Material,
        bearing_material: Material,
        restitution: float = 0.9,
        radial_exponent: float = 1.0,
        axial_exponent: float = 1.0,
        point_exponent: float = 1.5,
        friction: FrictionLaw = NoFriction(),
        radial_stiffness: float | None = None,
        axial_stiffness: float | None = None,
        point_stiffness: float | None = None,
        radial_law: str = "linear",
        dissipation: str = DEFAULT_DISSIPATION,
    ) -> None:
        r_j, r_b1, r_b2, l_j, l_b = _checked_geometry(journal_radius, bearing_inner_radius, bearing_outer_radius, journal_length, bearing_length)
        require_material("journal_material", journal_material)
        require_material("bearing_material", bearing_material)
        code, friction_parameters = self._wire_friction(friction)
        n_a = require_in_range("axial_exponent", axial_exponent, *EXPONENT_RANGE)
        n_p = require_in_range("point_exponent", point_exponent, *EXPONENT_RANGE)
        law = radial_laws.radial_law(radial_law, r_j, r_b1, l_b, bearing_material, journal_material, radial_stiffness, radial_exponent)
        if axial_stiffness is None:
            if n_a != 1.0:
                raise ContactParameterError(
                    f"axial_exponent={axial_exponent!r} needs an explicit axial_stiffness: the default "
                    "flat-punch stiffness 2 E* R_b2 (N/m) is valid for axial_exponent 1 only"
                )
            axial_stiffness = flat_punch_stiffness(r_b2, bearing_material, journal_material)
        k_plane = require_positive("axial_stiffness", axial_stiffness)
        k_point = None if point_stiffness is None else require_positive("point_stiffness", point_stiffness)
        ce = require_in_range("restitution", restitution, 0.0, 1.0, low_inclusive=False)

        self._r_j = r_j
        self._r_b1 = r_b1
        self._r_b2 = r_b2
        self._l_j = l_j
        self._l_b = l_b
        self._half_l_b = 0.5 * l_b
        self._half_l_j = 0.5 * l_j
        self._journal_material = journal_material
        self._bearing_material = bearing_material
        self._restitution = ce
        self._radial_law = law
        self._dissipation = dissipation
        self._n_r = law.exponent
        self._n_a = n_a
        self._n_p = n_p
        self._k_line = law.stiffness
        self._k_plane = k_plane
        self._k_point = k_point
        self._plane_density = k_plane / (math.pi * (r_b2 * r_b2 - r_b1 * r_b1))
        self._disc_rule = _disc_rule(_QUAD_POINTS, n_a)
        self.kernel_parameters = self._pack(code, friction_parameters)


    def _pack(self, friction_code: int, friction_parameters: np.ndarray) -> np.ndarray:
        """``kernel_parameters`` (module docstring's layout) from the validated attributes."""
        parameters = np.zeros(_N_PARAMETERS)
        parameters[_P_JOURNAL_RADIUS] = self._r_j
        parameters[_P_BORE_RADIUS] = self._r_b1
        parameters[_P_OUTER_RADIUS] = self._r_b2
        parameters[_P_HALF_BEARING_LENGTH] = self._half_l_b
        parameters[_P_HALF_JOURNAL_LENGTH] = self._half_l_j
        parameters[_P_LINE_STIFFNESS] = self._radial_law.stiffness or 0.0  # informative (the law is at _P_RADIAL_LAW)
        parameters[_P_PLANE_DENSITY] = self._plane_density
        parameters[_P_RADIAL_EXPONENT] = self._radial_law.exponent or 0.0
        parameters[_P_AXIAL_EXPONENT] = self._n_a
        parameters[_P_RESTITUTION] = self._restitution
        parameters[_P_FRICTION] = friction_code
        parameters[_P_FRICTION + 1 : _P_RADIAL_LAW] = friction_parameters
        parameters[_P_RADIAL_LAW:_P_DISSIPATION] = self._radial_law.encoding()
        parameters[_P_DISSIPATION:_P_QUAD_POINTS] = dissipation_encoding(self._dissipation, self._restitution)
        parameters[_P_QUAD_POINTS] = _QUAD_POINTS
        parameters[_P_QUAD_RULE:] = self._disc_rule.ravel()
        return parameters
    @classmethod
    def _from_scene(cls, parameters: dict, outer_material: Material, inner_material: Material, restitution: float, friction: FrictionLaw):
        journal, bearing_length = parameters.pop("journal_radius"), parameters.pop("bearing_length")
        return cls(
            journal_radius=journal,
            bearing_inner_radius=journal + parameters.pop("radial_clearance"),
            bearing_outer_radius=parameters.pop("bearing_outer_radius"),
            journal_length=bearing_length + parameters.pop("axial_clearance"),
            bearing_length=bearing_length,
            journal_material=inner_material,
            bearing_material=outer_material,
            restitution=restitution,
            friction=friction,
            **parameters,  # exponents, stiffnesses, radial_law, dissipation
        )

    # -- parameters -----------------------------------------------------------------
    @property
    def radial_clearance(self) -> float:
        """c_r = R_b1 - R_j (m); as given when built from scene keys."""
        return self.given("radial_clearance", self._r_b1 - self._r_j)

    @property
    def axial_clearance(self) -> float:
        """c_a = L_j - L_b (m), total (c_a / 2 per side when centred); as given when built from scene keys."""
        return self.given("axial_clearance", self._l_j - self._l_b)

    @property
    def scene_parameters(self) -> dict[str, float | str]:
        """As :attr:`ClearanceJoint.scene_parameters`; a radial law other than ``"linear"`` sets its
        own stiffness and exponent, so they are not reported (the joint rebuilds from these keys)."""
        out = super().scene_parameters
        if self._radial_law.name != "linear":
            for key in ("radial_stiffness", "radial_exponent"):
                if key not in self._given_parameters():
                    out.pop(key, None)
        return out

    def candidate_clearances(self) -> np.ndarray:
        """(4,) [c_r, c_a, c_r, c_a] in the candidates' order."""
        return np.array([self.radial_clearance, self.axial_clearance] * 2)

    @property
    def journal_radius(self) -> float:
        return self._r_j

    @property
    def bearing_inner_radius(self) -> float:
        return self._r_b1

    @property
    def bearing_outer_radius(self) -> float:
        return self._r_b2

    @property
    def journal_length(self) -> float:
        return self._l_j

    @property
    def bearing_length(self) -> float:
        return self._l_b

    @property
    def journal_material(self) -> Material:
        return self._journal_material

    @property
    def bearing_material(self) -> Material:
        return self._bearing_material

    @property
    def radial_exponent(self) -> float:
        return self._n_r

    @property
    def axial_exponent(self) -> float:
        return self._n_a

    @property
    def point_exponent(self) -> float:
        """Accepted for the contract; unused (see the module docstring)."""
        return self._n_p

    @property
    def radial_stiffness(self) -> float | None:
        """K (N/m^n_r) of a power radial law for the whole bearing length; None for ``"johnson"``."""
        return self._k_line

    @property
    def radial_law(self) -> RadialLaw:
        """The radial contact law (:mod:`~clearance_contact.radial_laws`)."""
        return self._radial_law

    @property
    def axial_stiffness(self) -> float:
        """K_plane (N/m^n_a), one whole annular end face."""
        return self._k_plane

    @property
    def point_stiffness(self) -> float | None:
        """Accepted for the contract; unused (see the module docstring)."""
        return self._k_point

    def __repr__(self) -> str:
        return (
            f"RevoluteClearanceJoint(journal_radius={self._r_j!r}, bearing_inner_radius={self._r_b1!r}, "
            f"bearing_outer_radius={self._r_b2!r}, journal_length={self._l_j!r}, "
            f"bearing_length={self._l_b!r}, journal_material={self._journal_material!r}, "
            f"bearing_material={self._bearing_material!r}, restitution={self._restitution!r}, "
            f"radial_exponent={self._n_r!r}, axial_exponent={self._n_a!r}, point_exponent={self._n_p!r}, "
            f"friction={self._friction!r}, radial_stiffness={self._k_line!r}, "
            f"axial_stiffness={self._k_plane!r}, point_stiffness={self._k_point!r}, "
            f"radial_law={self._radial_law.name!r}, dissipation={self._dissipation!r})"
        )

    # -- geometry -------------------------------------------------------------------
    def _slice(self, ex: float, ey: float, tx: float, ty: float, beta: float) -> float:
        """Radial penetration of the slice with eccentricity (ex, ey); beta = R_j |t|^2."""
        return _slice_penetration(ex, ey, tx, ty, beta, self._r_j, self._r_b1)

    def _status_error(self, status: int, state: tuple, out: np.ndarray) -> ContactError:
        """Adds ``STATUS_AXIS_TILT``: the angle between the axes; else as :meth:`ClearanceJoint._status_error`."""
        if status != STATUS_AXIS_TILT and not (status == STATUS_NONFINITE_INPUT and state[2] is None):
            return super()._status_error(status, state, out)
        # the penetration kernel reports NaN rotations as a tilt (its only check)
        outer_rotation, inner_rotation = state[0], state[3]
        dz = float(outer_rotation[:, 2] @ inner_rotation[:, 2])
        if not math.isfinite(dz):
            return ContactError(f"non-finite pose (u_b . u_j = {dz!r}): check for NaN or inf in the rotations")
        angle = math.degrees(math.acos(max(-1.0, min(1.0, dz))))
        return ContactError(
            f"journal axis at {angle:.4f} deg from the bearing axis (u_b . u_j = {dz!r}): a journal "
            "cannot turn by 90 deg in its bearing; check that both frames' z axes point the same way"
        )

    # -- evaluation (ClearanceJoint.evaluate / penetration run the kernels) ---------------
    def _apply_external_friction(self, state: tuple, out: np.ndarray) -> None:
        """Finish :func:`revolute_kernel`'s ``STATUS_EXTERNAL_FRICTION`` output with the user's friction law.

        The kernel left the tangential slip v_t in ``friction_force`` and w_n r_s in
        ``SPIN_SPEED``; the law sees the combined slip v_t + w_n r_s n (module docstring):
        its tangential part is F_t, its normal part times r_s the spin torque.  Then the
        wrenches are assembled by :func:`revolute_wrenches` (the kernel's own code).  The law
        is called through the checked :func:`~clearance_contact.friction.user_friction_gain`
        / :func:`~clearance_contact.friction.user_friction_force` (ContactError for a law that
        raises or gives NaN, a negative g or a force along the slip).
        """
        law = self._friction
        has_gain = getattr(law, "force_over_speed", None) is not None
        for k in range(_K):
            force_n = float(out[NORMAL_FORCE + k])
            if force_n <= 0.0:
                continue
            i = FRICTION_FORCE + 3 * k
            vtx, vty, vtz = out[i : i + 3].tolist()
            nx, ny, nz = out[NORMAL + 3 * k : NORMAL + 3 * k + 3].tolist()
            spin = float(out[SPIN_SPEED + k])
            spin_radius = float(out[SPIN_RADIUS + k])
            if has_gain:
                gain = user_friction_gain(law, force_n, math.sqrt(vtx * vtx + vty * vty + vtz * vtz + spin * spin))
                ftx = -gain * vtx
                fty = -gain * vty
                ftz = -gain * vtz
                t_spin = -gain * spin * spin_radius
            else:  # generic FrictionLaw: slip + spin as one (3,) vector
                ff = user_friction_force(law, force_n, np.array((vtx + spin * nx, vty + spin * ny, vtz + spin * nz))).tolist()
                fn_ = ff[0] * nx + ff[1] * ny + ff[2] * nz
                ftx = ff[0] - fn_ * nx
                fty = ff[1] - fn_ * ny
                ftz = ff[2] - fn_ * nz
                t_spin = fn_ * spin_radius
            out[i] = ftx
            out[i + 1] = fty
            out[i + 2] = ftz
            out[SPIN_TORQUE + k] = t_spin
        revolute_wrenches(state[1], state[4], out)

    # -- drawing ----------------------------------------------------------------------
    @classmethod
    def magnified(cls, geometry, factor: float) -> dict[str, float]:
        """Gaps times ``factor``; the bearing's outer radius moves with its bore (wall thickness true)."""
        out = super().magnified(geometry, factor)
        out["bearing_outer_radius"] += out["radial_clearance"] - float(geometry["radial_clearance"])
        return out

    @classmethod
    def drawing(cls, geometry) -> tuple[Shape, ...]:
        """Bearing tube (bore R_j + c_r), journal between two flanges L_b + c_a apart (flange radius R_b2)."""
        journal, bearing_length = geometry["journal_radius"], geometry["bearing_length"]
        bore, outer = journal + geometry["radial_clearance"], geometry["bearing_outer_radius"]
        half = 0.5 * (bearing_length + geometry["axial_clearance"])
        thickness = 0.1 * bearing_length
        shapes = [
            Shape("outer", "bearing", "tube", radius=outer, inner_radius=bore, length=bearing_length, opacity=0.4),
            Shape("inner", "journal", "cylinder", radius=journal, length=2 * half + 2 * thickness),
        ]
        for name, sign in (("flange_top", 1.0), ("flange_bottom", -1.0)):
            centre = (0.0, 0.0, sign * (half + 0.5 * thickness))
            shapes.append(Shape("inner", name, "cylinder", radius=outer, length=thickness, centre=centre, opacity=0.35))
        return tuple(shapes)

    @classmethod
    def inner_radius(cls, geometry) -> float:
        return float(geometry["journal_radius"])
