"""Translational (prismatic) clearance joint: a rectangular slider in a rectangular guide, contact at the corners.

Published treatments: Flores, Ambrosio, Claro, Lankarani, "Translational joints with
clearance in rigid multibody systems", J. Comput. Nonlinear Dyn. 3 (2008) 011007
(planar slider in a guide; contact of the slider's corners with the guide surfaces:
no contact, one corner, two adjacent corners on one surface, two opposite corners on
opposite surfaces; continuous Lankarani-Nikravesh normal force and friction per
corner); Flores, Leine, Glocker, "Modeling and analysis of planar rigid multibody
systems with translational clearance joints based on the non-smooth dynamics
approach", Multibody Syst. Dyn. 23 (2010) 165-190 (the same four corner-against-
surface gaps as unilateral constraints).  Both papers: the slider is a rectangle whose
corners are the only points that can touch the (long) guide's surfaces.  Here the same
model, with the papers' normal gap of a corner (its signed distance to a guide surface,
minus nothing: the clearance is in the surface's position), generalised to 3-D: a box
slider in a rectangular channel, 8 corners against the 4 guide faces.
(The equation numbers of the papers could not be checked against their text here:
the formulas are stated in full below.)

Elements and frames
-------------------
* **Guide** (outer element): a rectangular channel, long along its axis (the slider
  never reaches its ends).  Frame origin on the channel's centre line, local z = the
  guide axis (the sliding direction), local x = the *width* direction, y = the
  *height* direction.  Inner faces at x = +-h_x, y = +-h_y::

      h_x = a + c_x,   h_y = b + c_y     (c_x, c_y: clearance per side when centred)

* **Slider** (inner element): a box of length L_s along its local z, width 2a along
  its local x, height 2b along its local y; frame origin at its centre.  Its corners
  (slider frame) s = (+-a, +-b, +-L_s/2).

Candidates (the corner-against-face pairs that can touch: a corner only reaches the
faces on its own side)::

    spatial ("translational"):  16 = 8 corners x {its width face, its height face},
        candidate 2 i + f, corner i = (sx a, sy b, sz L_s/2) with
        sz = +1 for i < 4, sy = +1 for i mod 4 < 2, sx = +1 for i even;
        f = 0: the width face x = sx h_x, f = 1: the height face y = sy h_y.
    planar ("planar_translational"): 4 = the 4 corners of the slider's mid-plane
        y = 0 against the width faces (the slider moves in the guide's x-z plane;
        its corners are edges along y):  candidate i = corner (sx a, 0, sz L_s/2),
        sz = +1 for i < 2, sx = +1 for i even.

Geometry (exact for any pose)
-----------------------------
With R_g, o_g the guide's rotation and origin, R_s, o_s the slider's, corner i in
the world ``P = o_s + R_s s_i`` and in the guide frame ``p = R_g^T (P - o_g)``.
Against the face (axis j, side sigma = +-1) its penetration is *exactly linear* in
its position::

    delta = sigma p_j - h_j          (> 0: the corner is beyond the face)

The normal (from the slider outward toward the guide wall) is n = sigma g_j (g_j =
R_g e_j, the guide's axis j in world).  Contact points: the corner itself
(point_inner = P) and its foot on the face (point_outer = P - delta n); the forces
act half-way, at X = P - delta/2 n (the same point for both bodies: action =
reaction exactly).  Rate: with u_k(Y) = v_k + w_k x (Y - o_k) the velocity of the
material point of body k at Y::

    delta_dot = n . (u_s(P) - u_g(P))      (exact: d/dt of sigma g_j . (P - o_g))

which is also n . (u_s(X) - u_g(X)) (X - P is along n).

Hand cases (tests): slider centred: every delta = -c_x or -c_y; offset by e along
x: the 4 corners (planar: 2) on that side penetrate by e - c_x; tilted by theta about
the guide's y axis (in the plane of motion): the two diagonally opposite corners
(+a, +L_s/2) and (-a, -L_s/2) penetrate by (L_s/2) sin(theta) + a cos(theta) - h_x.

Forces (per candidate; Flores et al. 2008)
------------------------------------------
Normal force: K delta^n times the joint's dissipation factor (scene key
``dissipation``, :mod:`~clearance_contact.dissipation`), clamped at >= 0, through
:func:`corner_normal_force`; by default Lankarani-Nikravesh (Lankarani & Nikravesh,
J. Mech. Des. 112 (1990) 369; seed paper eq. (11))::

    F_N = K delta^n [1 + 3 (1 - c_e^2)/4 delta_dot / delta_dot0]   (delta > 0)

Stiffness: a given ``stiffness`` K (N/m^n) and ``exponent`` n, or by default the Hertz
point contact of a rounded corner of radius r on a flat face (sphere on a plane,
Johnson 1985 Sec. 4.2), :func:`~clearance_contact.materials.sphere_plane_stiffness`,
n = 3/2::

    K = 4/3 E* sqrt(r)

The corner radius only sets the stiffness: the geometry uses the sharp corner (a
modelling choice, as in both papers; r must be small against a and b).  Friction
(Brown-McPhee / Coulomb / none, :mod:`~clearance_contact.friction`): the slip of the
slider's material point at X relative to the guide's, tangential part v_t, and
F_t = -g(|v_t|) v_t.  On the slider f = -F_N n + F_t at X; on the guide -f at X.
Wrenches: sums over the candidates of [force, moment about the element's frame
origin], world axes.  ``kind``: 1 (point) when delta > 0, else 0.

``eccentricity`` (r = 2 rows): the centres of the slider's end faces
o_s +- (L_s/2) R_s e_z (front, rear) in the guide frame: x, y = transverse offsets
(|x| <= c_x, |y| <= c_y without penetration), z = axial position.

Kernel (``docs/contact-api.md``)
--------------------------------
:func:`translational_kernel`, numba-compiled through :data:`~clearance_contact.compiled.jit`
(``KERNEL_ID = 2``: the simulator's compiled dispatcher calls it directly).
``kernel_parameters`` (float64)::

    [K, n, c_e, friction code, 5 friction parameters, dissipation code, 2 parameters,
     h_x, h_y, L_s/2, k, k rows (s_x, s_y, s_z, axis j, side sigma)]

Status: 0 ok, ``STATUS_NONFINITE_INPUT``, ``STATUS_NONFINITE_PENETRATION``, or
``STATUS_EXTERNAL_FRICTION`` for a user-defined friction law (every call): then
``friction_force`` holds the slip v_t where F_N > 0, the wrenches are not written and
:meth:`ClearanceJoint.evaluate` applies the law and calls :func:`translational_wrenches`.
"""

from __future__ import annotations

import math
from typing import Mapping

import numpy as np

from .compiled import (
    STATUS_EXTERNAL_FRICTION,
    STATUS_NONFINITE_INPUT,
    STATUS_NONFINITE_PENETRATION,
    STATUS_OK,
    KernelAttribute,
    finite_state,
    jit,
    norm3,
)
from .errors import ContactParameterError, require_positive
from .friction import FRICTION_EXTERNAL, FRICTION_NONE, FRICTION_PARAMETERS, FrictionLaw, NoFriction, encoded_force_over_speed, user_friction
from .joint import ClearanceJoint, Shape
from .materials import Material, require_material, sphere_plane_stiffness
from .dissipation import DEFAULT_DISSIPATION, DISSIPATION_PARAMETERS, dissipation_encoding, encoded_damping_factor
from .normal_force import validate_normal_law
from .registry import register_joint_type
from .result import KIND_NONE, KIND_POINT

__all__ = [
    "TranslationalClearanceJoint",
    "PlanarTranslationalClearanceJoint",
    "translational_kernel",
    "translational_penetration_kernel",
    "translational_wrenches",
    "corner_normal_force",
]

# -- kernel_parameters layout -----------------------------------------------------------
_P_STIFFNESS = 0
_P_EXPONENT = 1
_P_RESTITUTION = 2
_P_FRICTION = 3  # kind code, then FRICTION_PARAMETERS values
_P_DISSIPATION = _P_FRICTION + 1 + FRICTION_PARAMETERS  # dissipation code, then DISSIPATION_PARAMETERS values
_P_HALF_WIDTH = _P_DISSIPATION + 1 + DISSIPATION_PARAMETERS  # h_x
_P_HALF_HEIGHT = _P_HALF_WIDTH + 1  # h_y
_P_HALF_LENGTH = _P_HALF_WIDTH + 2  # L_s / 2
_P_COUNT = _P_HALF_WIDTH + 3  # k
_P_TABLE = _P_HALF_WIDTH + 4  # k rows of _ROW values
_ROW = 5  # s_x, s_y, s_z, axis j, side sigma

_N_ECCENTRICITY = 2
# one kernel serves k = 16 (spatial) and k = 4 (planar): it reads k from its parameters and
# the offsets of its output from _offsets(k), the same sections as joint.output_layout(k, 2)


@jit
def _offsets(k):
    """(PENETRATION_RATE, NORMAL_FORCE, NORMAL, POINT_OUTER, POINT_INNER, FRICTION_FORCE, ECCENTRICITY, WRENCH_OUTER, WRENCH_INNER, KIND).

    The same sections as :func:`~clearance_contact.joint.output_layout` (k candidates,
    2 eccentricity rows, no extras); PENETRATION is at 0.
    """
    rate = k
    force = 2 * k
    normal = 3 * k
    outer = 6 * k
    inner = 9 * k
    friction = 12 * k
    eccentricity = 15 * k
    wrench_outer = eccentricity + 3 * _N_ECCENTRICITY
    wrench_inner = wrench_outer + 6
    kind = wrench_inner + 6
    return rate, force, normal, outer, inner, friction, eccentricity, wrench_outer, wrench_inner, kind


@jit
def corner_normal_force(parameters, penetration, penetration_rate, onset_rate):
    """Normal force (N) of one corner: K delta^n times the joint's dissipation factor, clamped at >= 0.

    The one place where the type's normal law is applied: the dissipation model is the
    joint's (:mod:`~clearance_contact.dissipation`, code and parameters packed in
    ``kernel_parameters``; Lankarani-Nikravesh by default).
    """
    if penetration <= 0.0:
        return 0.0
    force = parameters[_P_STIFFNESS] * penetration ** parameters[_P_EXPONENT] * encoded_damping_factor(
        parameters, _P_DISSIPATION, penetration_rate, onset_rate
    )
    return force if force > 0.0 else 0.0


@jit(exports=("void(f8[::1], f8[::1], f8[::1], f8[::1])",))  # _apply_external_friction's call (a user-defined friction law)
def translational_wrenches(parameters, outer_position, inner_position, out):
    """Write the two wrenches from the normal and friction forces in ``out`` (module docstring).

    Each candidate with F_N > 0: f = -F_N n + F_t on the slider at X = point_inner -
    delta/2 n, -f on the guide at X; moments about each element's frame origin.
    """
    k = int(parameters[_P_COUNT])
    _, force_at, normal_at, _, inner_at, friction_at, _, wrench_outer, wrench_inner, _ = _offsets(k)
    fx = fy = fz = mox = moy = moz = mix = miy = miz = 0.0
    for c in range(k):
        force_n = out[force_at + c]
        if force_n > 0.0:
            half = 0.5 * out[c]
            nx = out[normal_at + 3 * c]
            ny = out[normal_at + 3 * c + 1]
            nz = out[normal_at + 3 * c + 2]
            xx = out[inner_at + 3 * c] - half * nx
            xy = out[inner_at + 3 * c + 1] - half * ny
            xz = out[inner_at + 3 * c + 2] - half * nz
            gx = out[friction_at + 3 * c] - force_n * nx
            gy = out[friction_at + 3 * c + 1] - force_n * ny
            gz = out[friction_at + 3 * c + 2] - force_n * nz
            fx += gx
            fy += gy
            fz += gz
            rx = xx - inner_position[0]
            ry = xy - inner_position[1]
            rz = xz - inner_position[2]
            mix += ry * gz - rz * gy
            miy += rz * gx - rx * gz
            miz += rx * gy - ry * gx
            rx = xx - outer_position[0]
            ry = xy - outer_position[1]
            rz = xz - outer_position[2]
            mox -= ry * gz - rz * gy
            moy -= rz * gx - rx * gz
            moz -= rx * gy - ry * gx
    out[wrench_inner] = fx
    out[wrench_inner + 1] = fy
    out[wrench_inner + 2] = fz
    out[wrench_inner + 3] = mix
    out[wrench_inner + 4] = miy
    out[wrench_inner + 5] = miz
    out[wrench_outer] = -fx
    out[wrench_outer + 1] = -fy
    out[wrench_outer + 2] = -fz
    out[wrench_outer + 3] = mox
    out[wrench_outer + 4] = moy
    out[wrench_outer + 5] = moz


@jit
def _corner_in_guide(parameters, c, outer_rotation, outer_position, inner_rotation, inner_position):
    """World corner P of candidate c, its penetration delta, the face's axis j and side sigma."""
    row = _P_TABLE + _ROW * c
    sx = parameters[row]
    sy = parameters[row + 1]
    sz = parameters[row + 2]
    j = int(parameters[row + 3])
    side = parameters[row + 4]
    px = inner_position[0] + inner_rotation[0, 0] * sx + inner_rotation[0, 1] * sy + inner_rotation[0, 2] * sz
    py = inner_position[1] + inner_rotation[1, 0] * sx + inner_rotation[1, 1] * sy + inner_rotation[1, 2] * sz
    pz = inner_position[2] + inner_rotation[2, 0] * sx + inner_rotation[2, 1] * sy + inner_rotation[2, 2] * sz
    # p_j = g_j . (P - o_g)
    along = (
        outer_rotation[0, j] * (px - outer_position[0])
        + outer_rotation[1, j] * (py - outer_position[1])
        + outer_rotation[2, j] * (pz - outer_position[2])
    )
    delta = side * along - parameters[_P_HALF_WIDTH + j]
    return px, py, pz, delta, j, side


@jit(exports=(
        "i8(f8[::1], f8[:, ::1], f8[::1], f8[:, ::1], f8[::1], f8[::1])",
        "i8(f8[::1], f8[::1, :], f8[::1], f8[:, ::1], f8[::1], f8[::1])",
        "i8(f8[::1], f8[::1, :], f8[::1], f8[::1, :], f8[::1], f8[::1])",
        "i8(f8[::1], f8[:, ::1], f8[::1], f8[::1, :], f8[::1], f8[::1])",
    ))
def translational_penetration_kernel(parameters, outer_rotation, outer_position, inner_rotation, inner_position, out):
    """``out[c]`` = delta of every candidate (m); returns ``STATUS_OK`` or ``STATUS_NONFINITE_PENETRATION``."""
    k = int(parameters[_P_COUNT])
    total = 0.0
    for c in range(k):
        delta = _corner_in_guide(parameters, c, outer_rotation, outer_position, inner_rotation, inner_position)[3]
        out[c] = delta
        total += delta
    if not math.isfinite(total):
        return STATUS_NONFINITE_PENETRATION
    return STATUS_OK


@jit(exports=(
        "i8(f8[::1], f8[::1, :], f8[::1], f8[::1], f8[:, ::1], f8[::1], f8[::1], f8[::1], f8[::1])",
        "i8(f8[::1], f8[::1, :], f8[::1], f8[::1], f8[::1, :], f8[::1], f8[::1], f8[::1], f8[::1])",
        # rotations as numpy makes them (C order): the public evaluate() and the Newton-Euler engine
        "i8(f8[::1], f8[:, ::1], f8[::1], f8[::1], f8[:, ::1], f8[::1], f8[::1], f8[::1], f8[::1])",
        "i8(f8[::1], f8[:, ::1], f8[::1], f8[::1], f8[::1, :], f8[::1], f8[::1], f8[::1], f8[::1])",
    ))
def translational_kernel(
    parameters, outer_rotation, outer_position, outer_twist, inner_rotation, inner_position, inner_twist, onset_rates, out
):
    """Contact law of the translational joint (module docstring): state in, ``out`` written, status returned."""
    if not finite_state(outer_rotation, outer_position, outer_twist, inner_rotation, inner_position, inner_twist, onset_rates):
        return STATUS_NONFINITE_INPUT
    k = int(parameters[_P_COUNT])
    rate_at, force_at, normal_at, outer_at, inner_at, friction_at, eccentricity_at, _, _, kind_at = _offsets(k)
    ogx = outer_position[0]
    ogy = outer_position[1]
    ogz = outer_position[2]
    osx = inner_position[0]
    osy = inner_position[1]
    osz = inner_position[2]
    vgx = outer_twist[0]
    vgy = outer_twist[1]
    vgz = outer_twist[2]
    wgx = outer_twist[3]
    wgy = outer_twist[4]
    wgz = outer_twist[5]
    vsx = inner_twist[0]
    vsy = inner_twist[1]
    vsz = inner_twist[2]
    wsx = inner_twist[3]
    wsy = inner_twist[4]
    wsz = inner_twist[5]
    code = int(parameters[_P_FRICTION])
    external = code == FRICTION_EXTERNAL
    total = 0.0
    for c in range(k):
        px, py, pz, delta, j, side = _corner_in_guide(parameters, c, outer_rotation, outer_position, inner_rotation, inner_position)
        total += delta
        nx = side * outer_rotation[0, j]
        ny = side * outer_rotation[1, j]
        nz = side * outer_rotation[2, j]
        # u_s(P) - u_g(P): material velocities of slider and guide at the corner
        ax = px - osx
        ay = py - osy
        az = pz - osz
        bx = px - ogx
        by = py - ogy
        bz = pz - ogz
        ux = vsx + wsy * az - wsz * ay - vgx - (wgy * bz - wgz * by)
        uy = vsy + wsz * ax - wsx * az - vgy - (wgz * bx - wgx * bz)
        uz = vsz + wsx * ay - wsy * ax - vgz - (wgx * by - wgy * bx)
        rate = nx * ux + ny * uy + nz * uz
        force_n = corner_normal_force(parameters, delta, rate, onset_rates[c])
        out[c] = delta
        out[rate_at + c] = rate
        out[force_at + c] = force_n
        out[normal_at + 3 * c] = nx
        out[normal_at + 3 * c + 1] = ny
        out[normal_at + 3 * c + 2] = nz
        out[inner_at + 3 * c] = px
        out[inner_at + 3 * c + 1] = py
        out[inner_at + 3 * c + 2] = pz
        out[outer_at + 3 * c] = px - delta * nx
        out[outer_at + 3 * c + 1] = py - delta * ny
        out[outer_at + 3 * c + 2] = pz - delta * nz
        out[kind_at + c] = KIND_POINT if delta > 0.0 else KIND_NONE
        tx = ty = tz = 0.0
        if force_n > 0.0 and code != FRICTION_NONE:
            # slip at X = P - delta/2 n: u + (w_s - w_g) x (X - P)
            half = -0.5 * delta
            dwx = wsx - wgx
            dwy = wsy - wgy
            dwz = wsz - wgz
            sx_ = ux + half * (dwy * nz - dwz * ny)
            sy_ = uy + half * (dwz * nx - dwx * nz)
            sz_ = uz + half * (dwx * ny - dwy * nx)
            sn = sx_ * nx + sy_ * ny + sz_ * nz
            tx = sx_ - sn * nx
            ty = sy_ - sn * ny
            tz = sz_ - sn * nz
            if not external:
                gain = encoded_force_over_speed(parameters, _P_FRICTION, force_n, norm3(tx, ty, tz))
                tx = -gain * tx
                ty = -gain * ty
                tz = -gain * tz
        out[friction_at + 3 * c] = tx
        out[friction_at + 3 * c + 1] = ty
        out[friction_at + 3 * c + 2] = tz
    if not math.isfinite(total):
        return STATUS_NONFINITE_PENETRATION
    # eccentricity: the end-face centres o_s +- L_s/2 z_s in the guide frame
    half_length = parameters[_P_HALF_LENGTH]
    for row in range(2):
        sign = 1.0 if row == 0 else -1.0
        ex = osx + sign * half_length * inner_rotation[0, 2] - ogx
        ey = osy + sign * half_length * inner_rotation[1, 2] - ogy
        ez = osz + sign * half_length * inner_rotation[2, 2] - ogz
        for i in range(3):
            out[eccentricity_at + 3 * row + i] = outer_rotation[0, i] * ex + outer_rotation[1, i] * ey + outer_rotation[2, i] * ez
    if external:
        return STATUS_EXTERNAL_FRICTION
    translational_wrenches(parameters, outer_position, inner_position, out)
    return STATUS_OK


def corner_table(half_length: float, half_width: float, half_height: float, planar: bool) -> np.ndarray:
    """(k, 5) rows (s_x, s_y, s_z, axis j, side sigma) of the candidates, in the module docstring's order."""
    rows = []
    if planar:
        for i in range(4):
            sx, sz = (1.0 if i % 2 == 0 else -1.0), (1.0 if i < 2 else -1.0)
            rows.append((sx * half_width, 0.0, sz * half_length, 0.0, sx))
        return np.array(rows)
    for i in range(8):
        sx, sy, sz = (1.0 if i % 2 == 0 else -1.0), (1.0 if i % 4 < 2 else -1.0), (1.0 if i < 4 else -1.0)
        corner = (sx * half_width, sy * half_height, sz * half_length)
        rows.append((*corner, 0.0, sx))
        rows.append((*corner, 1.0, sy))
    return np.array(rows)


class _SliderInGuide(ClearanceJoint):
    """What the spatial and planar translational joints share (not a registered type itself)."""

    __slots__ = ("_length", "_width", "_height", "_guide_width", "_guide_height", "_slider_material", "_guide_material", "_exponent", "_stiffness", "_corner_radius")

    N_ECCENTRICITY = _N_ECCENTRICITY
    SITE_KINDS = ("prismatic",)
    PLANAR = False
    KERNEL_ID = 2

    def _build(
        self,
        length: float,
        width: float,
        height: float,
        guide_width: float,
        guide_height: float,
        slider_material: Material,
        guide_material: Material,
        restitution: float,
        exponent: float,
        friction: FrictionLaw,
        stiffness: float | None,
        corner_radius: float | None,
        dissipation: str = DEFAULT_DISSIPATION,
    ) -> None:
        length = require_positive("slider_length", length)
        width = require_positive("slider_width", width)
        guide_width = require_positive("guide_width", guide_width)
        if not guide_width > width:
            raise ContactParameterError(
                f"guide_width={guide_width!r} must be larger than slider_width={width!r} (width clearance > 0; valid range ({width:g}, inf))",
                key="guide_width", value=guide_width,
            )  # fmt: skip
        if not self.PLANAR:
            height = require_positive("slider_height", height)
            guide_height = require_positive("guide_height", guide_height)
            if not guide_height > height:
                raise ContactParameterError(
                    f"guide_height={guide_height!r} must be larger than slider_height={height!r} (height clearance > 0; valid range ({height:g}, inf))",
                    key="guide_height", value=guide_height,
                )  # fmt: skip
        require_material("slider_material", slider_material)
        require_material("guide_material", guide_material)
        code, friction_parameters = self._wire_friction(friction)
        stiffness = self._default_stiffness(stiffness, corner_radius, exponent, slider_material, guide_material)
        k, n, ce = validate_normal_law(stiffness, exponent, restitution)
        self._length, self._width, self._height = length, width, height
        self._guide_width, self._guide_height = guide_width, guide_height
        self._slider_material, self._guide_material = slider_material, guide_material
        self._restitution, self._exponent, self._stiffness = ce, n, k
        table = corner_table(0.5 * length, 0.5 * width, 0.5 * height, self.PLANAR)
        parameters = np.zeros(_P_TABLE + _ROW * table.shape[0])
        parameters[_P_STIFFNESS] = k
        parameters[_P_EXPONENT] = n
        parameters[_P_RESTITUTION] = ce
        parameters[_P_FRICTION] = code
        parameters[_P_FRICTION + 1 : _P_DISSIPATION] = friction_parameters
        parameters[_P_DISSIPATION:_P_HALF_WIDTH] = dissipation_encoding(dissipation, ce)
        self._dissipation = dissipation
        parameters[_P_HALF_WIDTH] = 0.5 * guide_width
        parameters[_P_HALF_HEIGHT] = 0.5 * guide_height
        parameters[_P_HALF_LENGTH] = 0.5 * length
        parameters[_P_COUNT] = table.shape[0]
        parameters[_P_TABLE:] = table.ravel()
        self.kernel_parameters = parameters

    def _default_stiffness(self, stiffness, corner_radius, exponent, slider_material, guide_material) -> float:
        """The given stiffness, or the Hertz stiffness of the rounded corner (exponent 1.5); exactly one of them."""
        self._corner_radius = None if corner_radius is None else require_positive("corner_radius", corner_radius)
        if stiffness is not None and corner_radius is not None:
            raise ContactParameterError(
                f"give either stiffness={stiffness!r} or corner_radius={corner_radius!r} (the Hertz stiffness of the rounded corner), not both",
                key="stiffness", value=stiffness,
            )  # fmt: skip
        if stiffness is not None:
            return stiffness
        if corner_radius is None:
            raise ContactParameterError(
                "the corner stiffness needs stiffness (N/m^exponent, range (0, inf)) or corner_radius (m, range (0, inf))",
                key="corner_radius", value=None,
            )  # fmt: skip
        if exponent != 1.5:
            raise ContactParameterError(
                f"exponent={exponent!r} needs an explicit stiffness: the Hertz corner stiffness (N/m^1.5) from corner_radius "
                "is valid for exponent 1.5 only",
                key="exponent", value=exponent,
            )  # fmt: skip
        return sphere_plane_stiffness(self._corner_radius, guide_material, slider_material)

    # -- parameters ------------------------------------------------------------------
    @property
    def slider_length(self) -> float:
        return self._length

    @property
    def slider_width(self) -> float:
        return self._width

    @property
    def guide_width(self) -> float:
        return self._guide_width

    @property
    def width_clearance(self) -> float:
        """c_x = (guide_width - slider_width) / 2, per side (m); as given when built from scene keys."""
        return self.given("width_clearance", 0.5 * (self._guide_width - self._width))

    @property
    def stiffness(self) -> float:
        return self._stiffness

    @property
    def exponent(self) -> float:
        return self._exponent

    @property
    def corner_radius(self) -> float | None:
        return self._corner_radius

    @property
    def slider_material(self) -> Material:
        return self._slider_material

    @property
    def guide_material(self) -> Material:
        return self._guide_material

    def candidate_clearances(self) -> np.ndarray:
        """(k,) the clearance of each candidate's face (c_x for width faces, c_y for height faces)."""
        axes = self.kernel_parameters[_P_TABLE + 3 :: _ROW]
        return np.where(axes == 0.0, self.width_clearance, getattr(self, "height_clearance", 0.0))

    # -- evaluation ------------------------------------------------------------------
    def _apply_external_friction(self, state: tuple, out: np.ndarray) -> None:
        """Apply the user's friction law to the slips the kernel left in ``friction_force``, then the wrenches.

        Through :func:`~clearance_contact.friction.user_friction` (checked: ContactError for a
        law that raises or gives NaN, a negative g or a force along the slip).
        """
        for c in range(self.N_CANDIDATES):
            force_n = float(out[self.NORMAL_FORCE + c])
            i = self.FRICTION_FORCE + 3 * c
            if force_n > 0.0:
                out[i : i + 3] = user_friction(self._friction, force_n, out[i : i + 3].copy())
        translational_wrenches(self.kernel_parameters, state[1], state[4], out)

    # -- drawing ---------------------------------------------------------------------
    @classmethod
    def exaggerated_offset(cls, offset: np.ndarray, factor: float) -> np.ndarray:
        """Transverse offsets times ``factor``; the slide along the guide axis (z) true."""
        return np.array([factor * offset[0], factor * offset[1], offset[2]])

    @classmethod
    def inner_radius(cls, geometry: Mapping[str, float]) -> float:
        return 0.5 * float(geometry["slider_width"])


@register_joint_type
class TranslationalClearanceJoint(_SliderInGuide):
    """Box slider (inner element) in a rectangular guide (outer element) with clearance: 8 corners, 4 faces.

    See the module docstring for the geometry and the force law.

    Parameters
    ----------
    slider_length, slider_width, slider_height:
        L_s, 2a, 2b in m, range (0, inf).
    guide_width, guide_height:
        Inner width 2 h_x and height 2 h_y of the channel (m): range (slider_width, inf)
        and (slider_height, inf).
    slider_material, guide_material:
        :class:`~clearance_contact.materials.Material` of each element.
    restitution:
        c_e of the L-N law, range (0, 1].
    exponent:
        n, range [1, 1.5]; default 1.5 (Hertz point contact).
    friction:
        A :class:`~clearance_contact.friction.FrictionLaw`; default no friction.
    stiffness, corner_radius:
        Exactly one: K in N/m^n, range (0, inf); or the corner radius r (m, range (0,
        inf)) of the Hertz stiffness 4/3 E* sqrt(r) (requires exponent 1.5).

    Joint type ``"translational"``: scene keys ``slider_length``, ``slider_width``,
    ``slider_height``, ``width_clearance``, ``height_clearance`` (c_x, c_y: per side,
    guide = slider + 2 c), ``corner_radius``, ``stiffness``, ``exponent``; it replaces a
    prismatic joint (``SITE_KINDS``), whose axis is the guide's z.
    """

    type_name = "translational"
    N_CANDIDATES = 16
    SCENE_KEYS = ("slider_length", "slider_width", "slider_height", "width_clearance", "height_clearance", "corner_radius", "stiffness", "exponent", "dissipation")
    NAME_KEYS = ("dissipation",)
    REQUIRED_KEYS = ("slider_length", "slider_width", "slider_height", "width_clearance", "height_clearance")
    GEOMETRY_KEYS = REQUIRED_KEYS
    GAP_KEYS = ("width_clearance", "height_clearance")
    DEFAULT_GEOMETRY = {"slider_length": 0.04, "slider_width": 0.02, "slider_height": 0.02, "width_clearance": 1.0e-4, "height_clearance": 1.0e-4}
    FORCE_GROUPS = {"lateral": tuple(range(16))}
    kernel = KernelAttribute(translational_kernel)
    penetration_kernel = staticmethod(translational_penetration_kernel)

    def __init__(
        self,
        slider_length: float,
        slider_width: float,
        slider_height: float,
        guide_width: float,
        guide_height: float,
        slider_material: Material,
        guide_material: Material,
        restitution: float = 0.9,
        exponent: float = 1.5,
        friction: FrictionLaw = NoFriction(),
        stiffness: float | None = None,
        corner_radius: float | None = None,
        dissipation: str = DEFAULT_DISSIPATION,
    ) -> None:
        self._build(
            slider_length, slider_width, slider_height, guide_width, guide_height, slider_material, guide_material,
            restitution, exponent, friction, stiffness, corner_radius, dissipation,
        )  # fmt: skip

    @classmethod
    def _from_scene(cls, parameters: dict, outer_material: Material, inner_material: Material, restitution: float, friction: FrictionLaw):
        width, height = parameters.pop("slider_width"), parameters.pop("slider_height")
        return cls(
            slider_length=parameters.pop("slider_length"),
            slider_width=width,
            slider_height=height,
            guide_width=width + 2.0 * parameters.pop("width_clearance"),
            guide_height=height + 2.0 * parameters.pop("height_clearance"),
            slider_material=inner_material,
            guide_material=outer_material,
            restitution=restitution,
            friction=friction,
            **parameters,  # stiffness or corner_radius, exponent
        )

    @property
    def slider_height(self) -> float:
        return self._height

    @property
    def guide_height(self) -> float:
        return self._guide_height

    @property
    def height_clearance(self) -> float:
        """c_y = (guide_height - slider_height) / 2, per side (m); as given when built from scene keys."""
        return self.given("height_clearance", 0.5 * (self._guide_height - self._height))

    @classmethod
    def drawing(cls, geometry: Mapping[str, float]) -> tuple[Shape, ...]:
        """The slider box, and the guide as four translucent walls around the channel (3 slider lengths long)."""
        length, width, height = geometry["slider_length"], geometry["slider_width"], geometry["slider_height"]
        inner_w = width + 2.0 * geometry["width_clearance"]
        inner_h = height + 2.0 * geometry["height_clearance"]
        wall, guide_length = 0.25 * min(width, height), 3.0 * length
        outer_w = inner_w + 2.0 * wall
        return (
            Shape("inner", "slider", "box", size=(width, height, length)),
            Shape("outer", "wall_width_plus", "box", size=(wall, inner_h, guide_length), centre=(0.5 * (inner_w + wall), 0.0, 0.0), opacity=0.35),
            Shape("outer", "wall_width_minus", "box", size=(wall, inner_h, guide_length), centre=(-0.5 * (inner_w + wall), 0.0, 0.0), opacity=0.35),
            Shape("outer", "wall_height_plus", "box", size=(outer_w, wall, guide_length), centre=(0.0, 0.5 * (inner_h + wall), 0.0), opacity=0.35),
            Shape("outer", "wall_height_minus", "box", size=(outer_w, wall, guide_length), centre=(0.0, -0.5 * (inner_h + wall), 0.0), opacity=0.35),
        )


@register_joint_type
class PlanarTranslationalClearanceJoint(_SliderInGuide):
    """Rectangular slider in a guide, moving in the guide's x-z plane: 4 corners against the 2 width faces.

    As :class:`TranslationalClearanceJoint` without the height direction (the planar
    model of Flores et al. 2008): parameters ``slider_length``, ``slider_width``,
    ``guide_width``, materials, ``restitution``, ``exponent``, ``friction``,
    ``stiffness`` or ``corner_radius``.  The mechanism keeps the slider in the plane
    (e.g. a planar linkage with parallel revolute axes); nothing limits its motion
    along y.  Joint type ``"planar_translational"``, scene keys ``slider_length``,
    ``slider_width``, ``width_clearance`` (c_x per side), ``corner_radius``,
    ``stiffness``, ``exponent``.
    """

    type_name = "planar_translational"
    N_CANDIDATES = 4
    PLANAR = True
    SCENE_KEYS = ("slider_length", "slider_width", "width_clearance", "corner_radius", "stiffness", "exponent", "dissipation")
    NAME_KEYS = ("dissipation",)
    REQUIRED_KEYS = ("slider_length", "slider_width", "width_clearance")
    GEOMETRY_KEYS = REQUIRED_KEYS
    GAP_KEYS = ("width_clearance",)
    DEFAULT_GEOMETRY = {"slider_length": 0.04, "slider_width": 0.02, "width_clearance": 1.0e-4}
    FORCE_GROUPS = {"lateral": (0, 1, 2, 3)}
    kernel = KernelAttribute(translational_kernel)
    penetration_kernel = staticmethod(translational_penetration_kernel)

    def __init__(
        self,
        slider_length: float,
        slider_width: float,
        guide_width: float,
        slider_material: Material,
        guide_material: Material,
        restitution: float = 0.9,
        exponent: float = 1.5,
        friction: FrictionLaw = NoFriction(),
        stiffness: float | None = None,
        corner_radius: float | None = None,
        dissipation: str = DEFAULT_DISSIPATION,
    ) -> None:
        self._build(
            slider_length, slider_width, 0.0, guide_width, 0.0, slider_material, guide_material,
            restitution, exponent, friction, stiffness, corner_radius, dissipation,
        )  # fmt: skip

    @classmethod
    def _from_scene(cls, parameters: dict, outer_material: Material, inner_material: Material, restitution: float, friction: FrictionLaw):
        width = parameters.pop("slider_width")
        return cls(
            slider_length=parameters.pop("slider_length"),
            slider_width=width,
            guide_width=width + 2.0 * parameters.pop("width_clearance"),
            slider_material=inner_material,
            guide_material=outer_material,
            restitution=restitution,
            friction=friction,
            **parameters,
        )

    @classmethod
    def drawing(cls, geometry: Mapping[str, float]) -> tuple[Shape, ...]:
        """The slider (as deep as it is wide) and the two width walls of the guide (3 slider lengths long)."""
        length, width = geometry["slider_length"], geometry["slider_width"]
        inner_w = width + 2.0 * geometry["width_clearance"]
        wall, guide_length = 0.25 * width, 3.0 * length
        return (
            Shape("inner", "slider", "box", size=(width, width, length)),
            Shape("outer", "wall_width_plus", "box", size=(wall, width, guide_length), centre=(0.5 * (inner_w + wall), 0.0, 0.0), opacity=0.35),
            Shape("outer", "wall_width_minus", "box", size=(wall, width, guide_length), centre=(-0.5 * (inner_w + wall), 0.0, 0.0), opacity=0.35),
        )
