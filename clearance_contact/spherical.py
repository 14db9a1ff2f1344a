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

Forces (seed paper eqs. (11), (14), (15)): normal force magnitude
F_N = max(K delta^n [1 + chi(c_e) delta_dot / max(delta_dot_0, floor)], 0), chi of the
joint's dissipation model (:mod:`~clearance_contact.dissipation`; default
Lankarani-Nikravesh, :func:`~clearance_contact.normal_force.lankarani_nikravesh`),
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

Compiled kernel (``docs/contact-api.md``)
----------------------------------------
:func:`spherical_kernel` (``SphericalClearanceJoint.kernel``) computes all of the above
into a flat float64 array ``out`` of ``SphericalClearanceJoint.output_size = 31``
values; offsets (class attributes, k = 1 candidate, r = 1 eccentricity row)::

    PENETRATION 0 (k)   PENETRATION_RATE 1 (k)   NORMAL_FORCE 2 (k)   NORMAL 3 (3k)
    POINT_OUTER 6 (3k)  POINT_INNER 9 (3k)       FRICTION_FORCE 12 (3k)
    ECCENTRICITY 15 (3r)  WRENCH_OUTER 18 (6)  WRENCH_INNER 24 (6)  KIND 30 (k, as float)

``kernel_parameters`` (float64, built once per joint)::

    [R_b, R_s, c, K, n, c_e, friction code, 5 friction parameters, dissipation code, 2 parameters]

It returns a status (:mod:`~clearance_contact.compiled`): 0 ok,
``STATUS_NONFINITE_INPUT``, ``STATUS_NONFINITE_PENETRATION``, or
``STATUS_EXTERNAL_FRICTION`` for a user-defined friction law (every call): then
``friction_force`` holds the slip v_t where F_N > 0 (zeros elsewhere), the wrenches are
not written, and
:meth:`SphericalClearanceJoint.evaluate` applies the law and calls
:func:`spherical_wrenches` (the same code the kernel uses).
"""



from __future__ import annotations

import math

import numpy as np

from .compiled import (
    STATUS_EXTERNAL_FRICTION,
    STATUS_NONFINITE_INPUT,
    STATUS_NONFINITE_PENETRATION,
    STATUS_OK,
    KernelAttribute,
    finite_state,
    norm3,
    jit,
)
from .errors import ContactParameterError, require_positive
from .friction import (
    FRICTION_EXTERNAL,
    FRICTION_PARAMETERS,
    FrictionLaw,
    NoFriction,
    encoded_force_over_speed,
    user_friction,
)
from .joint import ClearanceJoint, Shape, output_layout
from .materials import Material, hertz_sphere_stiffness, require_material
from .dissipation import DEFAULT_DISSIPATION, DISSIPATION_PARAMETERS, dissipation_encoding, encoded_damping_factor
from .normal_force import validate_normal_law
from .registry import register_joint_type
from .result import KIND_NONE, KIND_POINT

__all__ = ["SphericalClearanceJoint", "spherical_kernel", "spherical_penetration_kernel", "spherical_wrenches"]

# -- kernel_parameters layout --------------------------------------------------------
_P_BALL_RADIUS = 0
_P_SOCKET_RADIUS = 1
_P_CLEARANCE = 2
_P_STIFFNESS = 3
_P_EXPONENT = 4
_P_RESTITUTION = 5
_P_FRICTION = 6  # kind code, then FRICTION_PARAMETERS values
_P_DISSIPATION = _P_FRICTION + 1 + FRICTION_PARAMETERS  # code, then DISSIPATION_PARAMETERS values
_N_PARAMETERS = _P_DISSIPATION + 1 + DISSIPATION_PARAMETERS

# -- out layout (k = 1 candidate, r = 1 eccentricity row): joint.output_layout ------------
_K = 1
_LAYOUT = output_layout(_K, 1)
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
OUTPUT_SIZE = _LAYOUT["OUTPUT_SIZE"]


@jit(exports=("void(f8[::1], f8[::1])",))  # _apply_external_friction's call (a user-defined friction law)
def spherical_wrenches(parameters, out):
    """Write ``out[WRENCH_OUTER:WRENCH_INNER + 6]`` from the normal and friction forces in ``out``.

    On the ball ``f_b = -F_N n + F_t``, ``m_b = (R_b - delta/2) n x F_t``; on the socket
    ``-f_b`` and ``-(R_s + delta/2) n x F_t`` (module docstring); zeros when F_N = 0.
    """
    force_n = out[NORMAL_FORCE]
    if force_n > 0.0:
        delta = out[PENETRATION]
        arm_s = parameters[_P_SOCKET_RADIUS] + 0.5 * delta
        arm_b = parameters[_P_BALL_RADIUS] - 0.5 * delta
        nx = out[NORMAL]
        ny = out[NORMAL + 1]
        nz = out[NORMAL + 2]
        fx = out[FRICTION_FORCE]
        fy = out[FRICTION_FORCE + 1]
        fz = out[FRICTION_FORCE + 2]
        # n x F_t
        mx = ny * fz - nz * fy
        my = nz * fx - nx * fz
        mz = nx * fy - ny * fx
        fbx = fx - force_n * nx
        fby = fy - force_n * ny
        fbz = fz - force_n * nz
        out[WRENCH_INNER] = fbx
        out[WRENCH_INNER + 1] = fby
        out[WRENCH_INNER + 2] = fbz
        out[WRENCH_INNER + 3] = arm_b * mx
        out[WRENCH_INNER + 4] = arm_b * my
        out[WRENCH_INNER + 5] = arm_b * mz
        out[WRENCH_OUTER] = -fbx
        out[WRENCH_OUTER + 1] = -fby
        out[WRENCH_OUTER + 2] = -fbz
        out[WRENCH_OUTER + 3] = -arm_s * mx
        out[WRENCH_OUTER + 4] = -arm_s * my
        out[WRENCH_OUTER + 5] = -arm_s * mz
    else:
        for i in range(12):
            out[WRENCH_OUTER + i] = 0.0


@jit(exports=(
        "i8(f8[::1], f8[::1, :], f8[::1], f8[::1], f8[:, ::1], f8[::1], f8[::1], f8[::1], f8[::1])",
        "i8(f8[::1], f8[::1, :], f8[::1], f8[::1], f8[::1, :], f8[::1], f8[::1], f8[::1], f8[::1])",
        # rotations as numpy makes them (C order): the public evaluate() and the Newton-Euler engine
        "i8(f8[::1], f8[:, ::1], f8[::1], f8[::1], f8[:, ::1], f8[::1], f8[::1], f8[::1], f8[::1])",
        "i8(f8[::1], f8[:, ::1], f8[::1], f8[::1], f8[::1, :], f8[::1], f8[::1], f8[::1], f8[::1])",
    ))
def spherical_kernel(
    parameters, outer_rotation, outer_position, outer_twist, inner_rotation, inner_position, inner_twist, onset_rates, out
):
    """Compiled contact law of the spherical joint (module docstring): state in, ``out`` written, status returned.

    ``parameters``: ``SphericalClearanceJoint.kernel_parameters``; rotations (3, 3)
    (C or Fortran order), positions (3,), twists (6,) = [v, w], ``onset_rates`` (1,),
    all float64; ``out``: float64 (31,), layout in the module docstring.  Returns
    ``STATUS_OK`` (0) or a nonzero ``STATUS_*`` code of :mod:`~clearance_contact.compiled`.
    """
    if not finite_state(
        outer_rotation, outer_position, outer_twist, inner_rotation, inner_position, inner_twist, onset_rates
    ):
        return STATUS_NONFINITE_INPUT
    sx = outer_position[0]
    sy = outer_position[1]
    sz = outer_position[2]
    bx = inner_position[0]
    by = inner_position[1]
    bz = inner_position[2]
    vsx = outer_twist[0]
    vsy = outer_twist[1]
    vsz = outer_twist[2]
    wsx = outer_twist[3]
    wsy = outer_twist[4]
    wsz = outer_twist[5]
    vbx = inner_twist[0]
    vby = inner_twist[1]
    vbz = inner_twist[2]
    wbx = inner_twist[3]
    wby = inner_twist[4]
    wbz = inner_twist[5]

    ex = bx - sx
    ey = by - sy
    ez = bz - sz
    dist = norm3(ex, ey, ez)
    delta = dist - parameters[_P_CLEARANCE]
    if not math.isfinite(delta):
        return STATUS_NONFINITE_PENETRATION
    if dist > 0.0:
        nx = ex / dist
        ny = ey / dist
        nz = ez / dist
    else:  # centred ball: no contact (delta = -c); any unit vector, the socket z axis
        nx = outer_rotation[0, 2]
        ny = outer_rotation[1, 2]
        nz = outer_rotation[2, 2]
    # eccentricity in the socket frame: R_s^T e
    for i in range(3):
        out[ECCENTRICITY + i] = outer_rotation[0, i] * ex + outer_rotation[1, i] * ey + outer_rotation[2, i] * ez
    # penetration rate d|e|/dt = n . (v_b - v_s)
    rate = nx * (vbx - vsx) + ny * (vby - vsy) + nz * (vbz - vsz)

    r_s = parameters[_P_SOCKET_RADIUS]
    r_b = parameters[_P_BALL_RADIUS]
    out[PENETRATION] = delta
    out[PENETRATION_RATE] = rate
    out[NORMAL] = nx
    out[NORMAL + 1] = ny
    out[NORMAL + 2] = nz
    out[POINT_OUTER] = sx + r_s * nx
    out[POINT_OUTER + 1] = sy + r_s * ny
    out[POINT_OUTER + 2] = sz + r_s * nz
    out[POINT_INNER] = bx + r_b * nx
    out[POINT_INNER + 1] = by + r_b * ny
    out[POINT_INNER + 2] = bz + r_b * nz
    out[KIND] = KIND_POINT if delta > 0.0 else KIND_NONE

    force_n = 0.0
    if delta > 0.0:
        force_n = parameters[_P_STIFFNESS] * delta ** parameters[_P_EXPONENT] * encoded_damping_factor(
            parameters, _P_DISSIPATION, rate, onset_rates[0]
        )
        force_n = force_n if force_n > 0.0 else 0.0
    out[NORMAL_FORCE] = force_n
    fx = fy = fz = 0.0
    external = int(parameters[_P_FRICTION]) == FRICTION_EXTERNAL
    if force_n > 0.0:
        # lever arms from each centre to the force point P, along n
        arm_s = r_s + 0.5 * delta
        arm_b = r_b - 0.5 * delta
        # slip of the ball's material point at P relative to the socket's:
        # (v_b + w_b x arm_b n) - (v_s + w_s x arm_s n), tangential part
        ux = vbx - vsx + arm_b * (wby * nz - wbz * ny) - arm_s * (wsy * nz - wsz * ny)
        uy = vby - vsy + arm_b * (wbz * nx - wbx * nz) - arm_s * (wsz * nx - wsx * nz)
        uz = vbz - vsz + arm_b * (wbx * ny - wby * nx) - arm_s * (wsx * ny - wsy * nx)
        un = ux * nx + uy * ny + uz * nz
        tx = ux - un * nx
        ty = uy - un * ny
        tz = uz - un * nz
        if external:  # the slip, for Python to apply the law
            fx = tx
            fy = ty
            fz = tz
        else:
            gain = encoded_force_over_speed(parameters, _P_FRICTION, force_n, norm3(tx, ty, tz))
            fx = -gain * tx
            fy = -gain * ty
            fz = -gain * tz
    out[FRICTION_FORCE] = fx
    out[FRICTION_FORCE + 1] = fy
    out[FRICTION_FORCE + 2] = fz
    if external:
        return STATUS_EXTERNAL_FRICTION
    spherical_wrenches(parameters, out)
    return STATUS_OK


@jit(exports=(
        "i8(f8[::1], f8[:, ::1], f8[::1], f8[:, ::1], f8[::1], f8[::1])",
        "i8(f8[::1], f8[::1, :], f8[::1], f8[:, ::1], f8[::1], f8[::1])",
        "i8(f8[::1], f8[::1, :], f8[::1], f8[::1, :], f8[::1], f8[::1])",
        "i8(f8[::1], f8[:, ::1], f8[::1], f8[::1, :], f8[::1], f8[::1])",
    ))
def spherical_penetration_kernel(parameters, outer_rotation, outer_position, inner_rotation, inner_position, out):
    """``out[0]`` = delta = |b - s| - c (m); returns ``STATUS_OK`` or ``STATUS_NONFINITE_PENETRATION``."""
    ex = inner_position[0] - outer_position[0]
    ey = inner_position[1] - outer_position[1]
    ez = inner_position[2] - outer_position[2]
    delta = norm3(ex, ey, ez) - parameters[_P_CLEARANCE]
    out[0] = delta
    if not math.isfinite(delta):
        return STATUS_NONFINITE_PENETRATION
    return STATUS_OK


@register_joint_type
class SphericalClearanceJoint(ClearanceJoint):
    """Ball (inner element) in a spherical socket (outer element) with clearance.

    Parameters
    ----------
    ball_radius, socket_radius:
        R_b, R_s in m; both > 0 and ``socket_radius > ball_radius`` (clearance > 0).
    ball_material, socket_material:
        :class:`~clearance_contact.materials.Material` of each element.
    restitution:
        Coefficient of restitution c_e of the damping, range (0, 1].
    dissipation:
        Normal dissipation model, a name of
        :data:`~clearance_contact.dissipation.DISSIPATION_MODELS`; default
        ``"lankarani_nikravesh"`` (seed paper eq. (11)).
    exponent:
        Force exponent n, range [1, 1.5] (1.5: Hertz point contact).
    friction:
        A :class:`~clearance_contact.friction.FrictionLaw`; default no friction.
    stiffness:
        K in N/m^n, range (0, inf).  ``None``: Hertz internal sphere stiffness from
        the radii and materials, which requires ``exponent == 1.5``.

    Joint type ``"spherical"`` (:mod:`~clearance_contact.registry`); scene keys
    ``ball_radius``, ``clearance`` (c = R_s - R_b), ``exponent``, ``stiffness``, ``dissipation`` (a name).
    Compiled interface (module docstring, ``docs/contact-api.md``): ``kernel``,
    ``penetration_kernel``, ``kernel_parameters``, ``output_size`` and the offsets
    ``PENETRATION, PENETRATION_RATE, NORMAL_FORCE, NORMAL, POINT_OUTER, POINT_INNER,
    FRICTION_FORCE, ECCENTRICITY, WRENCH_OUTER, WRENCH_INNER, KIND`` (and
    ``N_CANDIDATES = 1``, ``N_ECCENTRICITY = 1``) from :class:`~clearance_contact.joint.ClearanceJoint`.
    """

    __slots__ = ("_ball_radius", "_socket_radius", "_clearance", "_ball_material", "_socket_material", "_exponent", "_stiffness")

    type_name = "spherical"
    N_CANDIDATES = _K
    N_ECCENTRICITY = 1
    SITE_KINDS = ("spherical",)
    SCENE_KEYS = ("ball_radius", "clearance", "exponent", "stiffness", "dissipation")
    NAME_KEYS = ("dissipation",)
    REQUIRED_KEYS = ("ball_radius", "clearance")
    GEOMETRY_KEYS = ("ball_radius", "clearance")
    GAP_KEYS = ("clearance",)
    FORCE_GROUPS = {"radial": (0,)}  # the normal force
    DEFAULT_GEOMETRY = {"ball_radius": 0.015, "clearance": 1.0e-4}
    KERNEL_ID = 0
    PENETRATION_USES_ROTATIONS = False  # delta = |b - s| - c
    kernel = KernelAttribute(spherical_kernel)
    penetration_kernel = staticmethod(spherical_penetration_kernel)

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
        dissipation: str = DEFAULT_DISSIPATION,
    ) -> None:
        r_b = require_positive("ball_radius", ball_radius)
        r_s = require_positive("socket_radius", socket_radius)
        if not r_s > r_b:
            raise ContactParameterError(
                f"socket_radius={socket_radius!r} must be larger than ball_radius={ball_radius!r} "
                "(clearance must be > 0)"
            )
        require_material("ball_material", ball_material)
        require_material("socket_material", socket_material)
        code, friction_parameters = self._wire_friction(friction)
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
        parameters = np.zeros(_N_PARAMETERS)
        parameters[_P_BALL_RADIUS] = r_b
        parameters[_P_SOCKET_RADIUS] = r_s
        parameters[_P_CLEARANCE] = self._clearance
        parameters[_P_STIFFNESS] = k
        parameters[_P_EXPONENT] = n
        parameters[_P_RESTITUTION] = ce
        parameters[_P_FRICTION] = code
        parameters[_P_FRICTION + 1 : _P_DISSIPATION] = friction_parameters
        parameters[_P_DISSIPATION:] = dissipation_encoding(dissipation, ce)
        self._dissipation = dissipation
        self.kernel_parameters = parameters

    @classmethod
    def _from_scene(cls, parameters: dict, outer_material: Material, inner_material: Material, restitution: float, friction: FrictionLaw):
        ball = parameters["ball_radius"]
        return cls(
            ball, ball + parameters["clearance"], inner_material, outer_material, restitution,
            parameters.get("exponent", 1.5), friction, parameters.get("stiffness"),
            parameters.get("dissipation", DEFAULT_DISSIPATION),
        )  # fmt: skip

    # -- parameters -----------------------------------------------------------------
    @property
    def clearance(self) -> float:
        """Radial clearance c = R_s - R_b (m); as given when built from scene keys."""
        return self.given("clearance", self._clearance)

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
    def exponent(self) -> float:
        return self._exponent

    @property
    def stiffness(self) -> float:
        """Contact stiffness K (N/m^n)."""
        return self._stiffness

    def candidate_clearances(self) -> np.ndarray:
        """(1,) the clearance c."""
        return np.array([self.clearance])

    def __repr__(self) -> str:
        return (
            f"SphericalClearanceJoint(ball_radius={self._ball_radius!r}, socket_radius={self._socket_radius!r}, "
            f"ball_material={self._ball_material!r}, socket_material={self._socket_material!r}, "
            f"restitution={self._restitution!r}, exponent={self._exponent!r}, friction={self._friction!r}, "
            f"stiffness={self._stiffness!r}, dissipation={self._dissipation!r})"
        )

    # -- evaluation (ClearanceJoint.evaluate / penetration run the kernels) ---------------
    def _apply_external_friction(self, state: tuple, out: np.ndarray) -> None:
        """Finish :func:`spherical_kernel`'s ``STATUS_EXTERNAL_FRICTION`` output: the user's law on the slip v_t.

        Through :func:`~clearance_contact.friction.user_friction` (checked: ContactError for a
        law that raises or gives NaN, a negative g or a force along the slip).
        """
        force_n = float(out[NORMAL_FORCE])
        if force_n > 0.0:  # friction_force holds the slip v_t
            out[FRICTION_FORCE : FRICTION_FORCE + 3] = user_friction(self._friction, force_n, out[FRICTION_FORCE : FRICTION_FORCE + 3].copy())
        spherical_wrenches(self.kernel_parameters, out)

    # -- drawing ----------------------------------------------------------------------
    @classmethod
    def drawing(cls, geometry) -> tuple[Shape, ...]:
        """Translucent socket of radius R_b + c around the ball."""
        ball = geometry["ball_radius"]
        return (
            Shape("outer", "socket", "sphere", radius=ball + geometry["clearance"], opacity=0.3),
            Shape("inner", "ball", "sphere", radius=ball),
        )

    @classmethod
    def inner_radius(cls, geometry) -> float:
        return float(geometry["ball_radius"])

    @classmethod
    def geometry_from_result(cls, eccentricity: np.ndarray, penetration: np.ndarray) -> dict[str, float]:
        """The clearance |e| - delta (median over the finite records), if positive."""
        if np.ndim(eccentricity) != 2 or np.shape(eccentricity)[1] != 3:
            return {}
        values = np.linalg.norm(eccentricity, axis=1) - np.asarray(penetration).reshape(len(eccentricity), -1)[:, 0]
        values = values[np.isfinite(values)]
        return {"clearance": float(np.median(values))} if values.size and np.median(values) > 0 else {}
