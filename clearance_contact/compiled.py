"""The kernels' status codes and shared compiled helpers; ``jit`` and the kernel mode (from :mod:`.kernel_mode`).

The kernels (``SphericalClearanceJoint.kernel``, ``RevoluteClearanceJoint.kernel``, their
``penetration_kernel``) return an int status instead of raising (numba cannot raise
exceptions with formatted messages): ``STATUS_OK`` or one of the codes below; the
joints' ``evaluate`` / ``penetration`` turn a nonzero status into
:class:`~clearance_contact.errors.ContactError` with an informative message.

``jit``, ``KERNELS``, ``switch_to_numba``, ``watch_numba_cache``, ``drop_stale_caches``
come from :mod:`clearance_contact.kernel_mode` (how the kernels run: the kernel library,
numba's JIT or plain Python); ``KERNEL_MODE``, ``JIT_ENABLED`` and ``SWITCHED_BY`` are read
from it when asked for, since a process may switch.
"""

from __future__ import annotations

import math

from clearance_contact import kernel_mode
from clearance_contact.kernel_mode import KERNELS, Kernel, drop_stale_caches, jit, switch_to_numba, watch_numba_cache

__all__ = [
    "jit",
    "JIT_ENABLED",
    "KERNEL_MODE",
    "SWITCHED_BY",
    "KERNELS",
    "Kernel",
    "switch_to_numba",
    "watch_numba_cache",
    "drop_stale_caches",
    "STATUS_OK",
    "STATUS_NONFINITE_INPUT",
    "STATUS_NONFINITE_PENETRATION",
    "STATUS_AXIS_TILT",
    "STATUS_EXTERNAL_FRICTION",
    "STATUS_MESSAGES",
]

STATUS_OK: int = 0
"""The kernel's output is complete and valid."""
STATUS_NONFINITE_INPUT: int = 1
"""A pose, twist or onset rate is NaN or infinite (nothing useful was written)."""
STATUS_NONFINITE_PENETRATION: int = 2
"""A penetration came out non-finite (e.g. overflow of huge but finite poses)."""
STATUS_AXIS_TILT: int = 3
"""Revolute joint: journal axis at >= 90 deg (within 1e-6 in cosine) from the bearing axis."""
STATUS_EXTERNAL_FRICTION: int = 4
"""The joint's friction law is a user-defined ``FrictionLaw`` that compiled code cannot
call: everything but friction was written (``friction_force`` holds the slip velocities,
the wrenches are incomplete); ``evaluate`` finishes the job in Python."""

STATUS_MESSAGES: dict[int, str] = {
    STATUS_OK: "ok",
    STATUS_NONFINITE_INPUT: "non-finite input (NaN or inf in a pose, twist or onset rate)",
    STATUS_NONFINITE_PENETRATION: "non-finite penetration",
    STATUS_AXIS_TILT: "journal axis tilted by 90 deg or more from the bearing axis",
    STATUS_EXTERNAL_FRICTION: "user-defined friction law: friction not applied by the kernel",
}


def __getattr__(name: str):
    """``KERNEL_MODE``, ``JIT_ENABLED``, ``SWITCHED_BY``: today's values in :mod:`.kernel_mode` (a process may switch)."""
    if name in ("KERNEL_MODE", "JIT_ENABLED", "SWITCHED_BY"):
        return getattr(kernel_mode, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


class KernelAttribute:
    """Class attribute holding a law's compiled kernel (a descriptor).

    ``Law.kernel`` (on the class) is always the kernel function.  ``law.kernel`` (on
    an instance) is the same function, or ``None`` when the instance's friction law is
    user-defined (``law.friction_in_kernel`` False): the kernel alone cannot apply it
    (it returns ``STATUS_EXTERNAL_FRICTION``), so compiled callers must use
    ``law.evaluate`` for that law.
    """

    __slots__ = ("function",)

    def __init__(self, function) -> None:
        self.function = function

    def __get__(self, instance, owner=None):
        if instance is None or instance.friction_in_kernel:
            return self.function
        return None


@jit
def finite_state(outer_rotation, outer_position, outer_twist, inner_rotation, inner_position, inner_twist, onset_rates):
    """True if every value of a joint state (the kernels' inputs) is finite."""
    for i in range(3):
        for j in range(3):
            if not (math.isfinite(outer_rotation[i, j]) and math.isfinite(inner_rotation[i, j])):
                return False
        if not (math.isfinite(outer_position[i]) and math.isfinite(inner_position[i])):
            return False
    for i in range(6):
        if not (math.isfinite(outer_twist[i]) and math.isfinite(inner_twist[i])):
            return False
    for i in range(onset_rates.shape[0]):
        if not math.isfinite(onset_rates[i]):
            return False
    return True


_DBL_MIN = 2.2250738585072014e-308
"""Smallest normal float64."""


@jit
def _two_product(x: float, y: float) -> tuple[float, float]:
    """(x y rounded, exact error) by Dekker's splitting (no FMA needed; |x|, |y| < 1e150)."""
    p = x * y
    c = 134217729.0 * x  # 2^27 + 1
    xh = c - (c - x)
    xl = x - xh
    c = 134217729.0 * y
    yh = c - (c - y)
    yl = y - yh
    return p, ((xh * yh - p) + xh * yl + xl * yh) + xl * yl


@jit
def _norm_scaled(a: float, b: float, c: float, largest: float) -> float:
    # CPython's vector_norm (Modules/mathmodule.c, 3.10+): squares of the inputs scaled to
    # [0.5, 1) by a power of two, summed with exact error terms, a square root and one
    # differential correction: correctly rounded in all but rare cases.
    max_e = math.frexp(largest)[1]
    scale = math.ldexp(1.0, -max_e)
    csum = 1.0
    frac1 = 0.0
    frac2 = 0.0
    for x in (a, b, c):
        x *= scale
        hi, lo = _two_product(x, x)
        total = csum + hi  # |csum| >= |hi|: fast two-sum
        frac2 += (csum - total) + hi
        csum = total
        frac1 += lo
    h = math.sqrt(csum - 1.0 + (frac1 + frac2))
    hi, lo = _two_product(-h, h)
    total = csum + hi
    frac2 += (csum - total) + hi
    csum = total
    frac1 += lo
    x = csum - 1.0 + (frac1 + frac2)
    h += x / (2.0 * h)
    return h / scale


@jit
def norm3(x: float, y: float, z: float) -> float:
    """Euclidean norm sqrt(x^2 + y^2 + z^2), as CPython's ``math.hypot(x, y, z)`` computes it.

    The same algorithm as CPython's (so compiled and plain-Python runs, and this code and
    the earlier pure-Python laws, agree to the last bit: penetrations are differences of
    nearly equal lengths, where one ulp of |e| is 1e-12 of delta, and adaptive
    integrators amplify such differences).  Nearly correctly rounded; no overflow or
    underflow.
    """
    ax = abs(x)
    ay = abs(y)
    az = abs(z)
    largest = max(ax, ay, az)
    if not math.isfinite(largest):
        return math.inf if (math.isinf(ax) or math.isinf(ay) or math.isinf(az)) else math.nan
    if largest == 0.0:
        return 0.0
    if largest < _DBL_MIN:  # subnormals: rescaled to normal numbers first (as CPython)
        return _DBL_MIN * _norm_scaled(ax / _DBL_MIN, ay / _DBL_MIN, az / _DBL_MIN, largest / _DBL_MIN)
    return _norm_scaled(ax, ay, az, largest)


@jit
def norm2(x: float, y: float) -> float:
    """sqrt(x^2 + y^2) as CPython's ``math.hypot(x, y)`` (see :func:`norm3`)."""
    ax = abs(x)
    ay = abs(y)
    largest = max(ax, ay)
    if not math.isfinite(largest):
        return math.inf if (math.isinf(ax) or math.isinf(ay)) else math.nan
    if largest == 0.0:
        return 0.0
    if largest < _DBL_MIN:
        return _DBL_MIN * _norm_scaled(ax / _DBL_MIN, ay / _DBL_MIN, 0.0, largest / _DBL_MIN)
    return _norm_scaled(ax, ay, 0.0, largest)
