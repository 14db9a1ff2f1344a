"""Spherical clearance joint: a ball inside a spherical socket (one point contact).

Geometry (MODEL-NOTES 3; seed paper eqs. (1)-(3)); s is the socket centre (outer
element frame origin), b the ball centre (inner element frame origin), world axes::

    c     = R_s - R_b                  radial clearance            (eq. 1)
    e     = b - s                      eccentricity vector         (eq. 2)
    delta = |e| - c                    penetration, contact if > 0 (eq. 3)
    n     = e / |e|                    normal, from the ball outward to the socket wall

Contact points on the two surfaces, and the point P where the contact forces act
(half-way between them, the same point for both bodies so that the two wrenches
are exactly opposite about any point)::

    point_outer = s + R_s n,   point_inner = b + R_b n = point_outer + delta n
    P = s + (R_s + delta/2) n = b + (R_b - delta/2) n

Kinematics, from the twists (v_k, w_k) of the two frames (origin velocity and
angular velocity, world axes).  Velocity of the material point of body k at P:
u_k = v_k + w_k x (P - origin_k).  Then::

    delta_dot = n . (v_b - v_s)  (= d|e|/dt exactly; also = n . (u_b - u_s))
    v_rel     = u_b - u_s                        slip of the ball relative to the socket
    v_t       = v_rel - (n . v_rel) n            tangential slip

Forces (seed paper eqs. (11), (14), (15)): normal force magnitude F_N from the
Lankarani-Nikravesh law (:func:`~clearance_contact.normal_force.lankarani_nikravesh`),
friction F_t = -g(|v_t|) v_t from the friction law (finite at zero slip).  On the ball::

    f_b = -F_N n + F_t,     m_b = (R_b - delta/2) n x F_t     (about b)

on the socket (action = reaction)::

    f_s = -f_b,             m_s = -(R_s + delta/2) n x F_t    (about s)

The normal force passes through both centres and produces no moment.

``kind`` is 1 (point) whenever delta > 0, also when the L-N force is clamped to 0
(fast separation); 0 otherwise.

If |e| = 0 (ball exactly centred) the normal is undefined; then delta = -c < 0 (no
contact) and the socket's local z axis is reported as ``normal`` (finite output).

Stiffness: Hertz internal sphere contact by default
(:func:`~clearance_contact.materials.hertz_sphere_stiffness`, exponent 1.5).
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike

from .errors import ContactParameterError, require_positive
from .friction import FrictionLaw, NoFriction
from .materials import Material, hertz_sphere_stiffness
from .normal_force import lankarani_nikravesh, validate_normal_law
from .result import KIND_NONE, KIND_POINT, JointContact

__all__ = ["SphericalClearanceJoint"]

_ONE_KIND_NONE = (KIND_NONE,)
_ONE_KIND_POINT = (KIND_POINT,)


def _floats(x: ArrayLike) -> list:
    """Plain Python floats of a numpy array (fast path) or any sequence."""
    try:
        return x.tolist()  # type: ignore[union-attr]
    except AttributeError:
        return np.asarray(x, dtype=float).tolist()


class SphericalClearanceJoint:
    """Ball (inner element) in a spherical socket (outer element) with clearance.

    Parameters
    ----------
    ball_radius, socket_radius:
        R_b, R_s in m; both > 0 and ``socket_radius > ball_radius`` (clearance > 0).
    ball_material, socket_material:
        :class:`~clearance_contact.materials.Material` of each element.
    restitution:
        Coefficient of restitution c_e of the L-N law, range (0, 1].
    exponent:
        Force exponent n, range [1, 1.5] (1.5: Hertz point contact).
    friction:
        A :class:`~clearance_contact.friction.FrictionLaw`; default no friction.
    stiffness:
        K in N/m^n, range (0, inf).  ``None``: Hertz internal sphere stiffness from
        the radii and materials, which requires ``exponent == 1.5``.
    """

    __slots__ = (
        "_ball_radius",
        "_socket_radius",
        "_clearance",
        "_ball_material",
        "_socket_material",
        "_restitution",
        "_exponent",
        "_stiffness",
        "_friction",
        "_force_over_speed",
    )

    n_candidates: int = 1

    def __init__(
        self,
        ball_radius: float,
        socket_radius: float,
        ball_material: Material,
        socket_material: Material,
        restitution: float = 0.9,
        exponent: float = 1.5,
        friction: FrictionLaw = NoFriction(),
        stiffness: float | None = None,
    ) -> None:
        r_b = require_positive("ball_radius", ball_radius)
        r_s = require_positive("socket_radius", socket_radius)
        if not r_s > r_b:
            raise ContactParameterError(
                f"socket_radius={socket_radius!r} must be larger than ball_radius={ball_radius!r} "
                "(clearance must be > 0)"
            )
        for name, material in (("ball_material", ball_material), ("socket_material", socket_material)):
            if not isinstance(material, Material):
                raise ContactParameterError(f"{name}={material!r} must be a clearance_contact.Material")
        if not isinstance(friction, FrictionLaw):
            raise ContactParameterError(
                f"friction={friction!r} must implement FrictionLaw (coefficient(slip_speed), "
                "force(normal_force, slip_velocity))"
            )
        if stiffness is None:
            if exponent != 1.5:
                raise ContactParameterError(
                    f"exponent={exponent!r} needs an explicit stiffness: the default Hertz sphere "
                    "stiffness (N/m^1.5) is valid for exponent 1.5 only"
                )
            stiffness = hertz_sphere_stiffness(r_s, r_b, socket_material, ball_material, internal=True)
        k, n, ce = validate_normal_law(stiffness, exponent, restitution)

        self._ball_radius = r_b
        self._socket_radius = r_s
        self._clearance = r_s - r_b
        self._ball_material = ball_material
        self._socket_material = socket_material
        self._restitution = ce
        self._exponent = n
        self._stiffness = k
        self._friction = friction
        self._force_over_speed = getattr(friction, "force_over_speed", None)

    # -- parameters -----------------------------------------------------------------
    @property
    def clearance(self) -> float:
        """Radial clearance c = R_s - R_b (m)."""
        return self._clearance

    @property
    def ball_radius(self) -> float:
        return self._ball_radius

    @property
    def socket_radius(self) -> float:
        return self._socket_radius

    @property
    def ball_material(self) -> Material:
        return self._ball_material

    @property
    def socket_material(self) -> Material:
        return self._socket_material

    @property
    def restitution(self) -> float:
        return self._restitution

    @property
    def exponent(self) -> float:
        return self._exponent

    @property
    def stiffness(self) -> float:
        """Contact stiffness K (N/m^n)."""
        return self._stiffness

    @property
    def friction(self) -> FrictionLaw:
        return self._friction

    def __repr__(self) -> str:
        return (
            f"SphericalClearanceJoint(ball_radius={self._ball_radius!r}, socket_radius={self._socket_radius!r}, "
            f"ball_material={self._ball_material!r}, socket_material={self._socket_material!r}, "
            f"restitution={self._restitution!r}, exponent={self._exponent!r}, friction={self._friction!r}, "
            f"stiffness={self._stiffness!r})"
        )

    # -- evaluation -----------------------------------------------------------------
    def penetration(
        self,
        outer_rotation: ArrayLike,
        outer_position: ArrayLike,
        inner_rotation: ArrayLike,
        inner_position: ArrayLike,
    ) -> np.ndarray:
        """(1,) penetration delta = |b - s| - c (m), > 0 in contact.  Cheap (events)."""
        return np.array((math.dist(_floats(inner_position), _floats(outer_position)) - self._clearance,))

    def evaluate(
        self,
        outer_rotation: ArrayLike,
        outer_position: ArrayLike,
        outer_twist: ArrayLike,
        inner_rotation: ArrayLike,
        inner_position: ArrayLike,
        inner_twist: ArrayLike,
        onset_rates: ArrayLike,
    ) -> JointContact:
        """Contact state and wrenches (see the module docstring for the equations).

        ``outer_*`` is the socket, ``inner_*`` the ball; rotations (3, 3) frame ->
        world, positions (3,), twists (6,) = [v, w] of the frame origin in world
        axes; ``onset_rates`` (1,) is the approach rate recorded at the onset of
        the current impact (floored by the L-N law).
        """
        sx, sy, sz = _floats(outer_position)
        bx, by, bz = _floats(inner_position)
        vsx, vsy, vsz, wsx, wsy, wsz = _floats(outer_twist)
        vbx, vby, vbz, wbx, wby, wbz = _floats(inner_twist)
        (r0, r1, r2) = _floats(outer_rotation)

        ex = bx - sx
        ey = by - sy
        ez = bz - sz
        dist = math.hypot(ex, ey, ez)
        delta = dist - self._clearance
        if dist > 0.0:
            nx = ex / dist
            ny = ey / dist
            nz = ez / dist
        else:  # centred ball: no contact (delta = -c); any unit vector, the socket z axis
            nx = r0[2]
            ny = r1[2]
            nz = r2[2]
        # eccentricity in the socket frame: R_s^T e
        ecc = (
            r0[0] * ex + r1[0] * ey + r2[0] * ez,
            r0[1] * ex + r1[1] * ey + r2[1] * ez,
            r0[2] * ex + r1[2] * ey + r2[2] * ez,
        )
        # penetration rate d|e|/dt = n . (v_b - v_s)
        rate = nx * (vbx - vsx) + ny * (vby - vsy) + nz * (vbz - vsz)

        r_s = self._socket_radius
        r_b = self._ball_radius
        point_outer = (sx + r_s * nx, sy + r_s * ny, sz + r_s * nz)
        point_inner = (bx + r_b * nx, by + r_b * ny, bz + r_b * nz)

        force_n = lankarani_nikravesh(
            delta, rate, float(onset_rates[0]), self._stiffness, self._exponent, self._restitution  # type: ignore[index]
        )
        if force_n > 0.0:
            # lever arms from each centre to the force point P, along n
            arm_s = r_s + 0.5 * delta
            arm_b = r_b - 0.5 * delta
            # slip of the ball's material point at P relative to the socket's:
            # (v_b + w_b x arm_b n) - (v_s + w_s x arm_s n)
            ux = vbx - vsx + arm_b * (wby * nz - wbz * ny) - arm_s * (wsy * nz - wsz * ny)
            uy = vby - vsy + arm_b * (wbz * nx - wbx * nz) - arm_s * (wsz * nx - wsx * nz)
            uz = vbz - vsz + arm_b * (wbx * ny - wby * nx) - arm_s * (wsx * ny - wsy * nx)
            un = ux * nx + uy * ny + uz * nz
            tx = ux - un * nx
            ty = uy - un * ny
            tz = uz - un * nz
            g = self._force_over_speed
            if g is not None:
                gain = g(force_n, math.hypot(tx, ty, tz))
                fx = -gain * tx
                fy = -gain * ty
                fz = -gain * tz
            else:  # a FrictionLaw without the scalar fast path
                fx, fy, fz = _floats(self._friction.force(force_n, np.array((tx, ty, tz))))
            # n x F_t
            mx = ny * fz - nz * fy
            my = nz * fx - nx * fz
            mz = nx * fy - ny * fx
            fbx = fx - force_n * nx
            fby = fy - force_n * ny
            fbz = fz - force_n * nz
            wrench_inner = (fbx, fby, fbz, arm_b * mx, arm_b * my, arm_b * mz)
            wrench_outer = (-fbx, -fby, -fbz, -arm_s * mx, -arm_s * my, -arm_s * mz)
            friction = (fx, fy, fz)
            kind = _ONE_KIND_POINT
        else:
            wrench_inner = wrench_outer = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
            friction = (0.0, 0.0, 0.0)
            kind = _ONE_KIND_POINT if delta > 0.0 else _ONE_KIND_NONE

        return JointContact(
            penetration=np.array((delta,)),
            penetration_rate=np.array((rate,)),
            normal=np.array(((nx, ny, nz),)),
            point_outer=np.array((point_outer,)),
            point_inner=np.array((point_inner,)),
            normal_force=np.array((force_n,)),
            friction_force=np.array((friction,)),
            kind=np.array(kind),
            eccentricity=np.array((ecc,)),
            wrench_outer=np.array(wrench_outer),
            wrench_inner=np.array(wrench_inner),
        )
