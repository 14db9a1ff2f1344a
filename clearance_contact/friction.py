"""Tangential friction laws: Brown-McPhee (continuous), Coulomb, none.

Every law gives the friction force on a body from its slip velocity v_t (the
tangential velocity of its material point at the contact, relative to the other
body) and the normal force F_N >= 0::

    F_t = -f(|v_t|) v_t / |v_t| = -g(|v_t|) v_t,       g(v) = f(v) / v

The joints use the second form: for the continuous laws g(v) has a finite limit
at v = 0, so the force is finite and continuous through zero slip without any
division by |v_t| (no NaN, no jump).  Each law exposes

* ``coefficient(slip_speed)``: f / F_N without the viscous part (dimensionless);
* ``force_over_speed(normal_force, slip_speed)``: g in N s/m (hot path, floats);
* ``force(normal_force, slip_velocity)``: the vector F_t, shape (3,).

Brown & McPhee, "A continuous velocity-based friction model for dynamics and
control with physically meaningful parameters", J. Comput. Nonlinear Dyn. 11(5)
(2016) 054502; seed paper eq. (14); in the form of MODEL-NOTES 4::

    f(v) = F_N [mu_k tanh(4 v / v_s) + (mu_s - mu_k) (v / v_s) / ((v/v_s)^2 / 4 + 3/4)^2]
           + mu_v v tanh(4 F_N / F_ref)

The Stribeck term peaks at exactly v = v_s with value mu_s - mu_k, where
tanh(4) = 0.99933, so the coefficient peaks at ~mu_s near v_s; it decays as
16 (mu_s - mu_k) (v_s / v)^3 and the coefficient tends to mu_k at high slip.
At v -> 0, g -> F_N [4 mu_k + 16/9 (mu_s - mu_k)] / v_s + mu_v tanh(4 F_N / F_ref).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Protocol, runtime_checkable

import numpy as np
from numpy.typing import ArrayLike

from .compiled import jit
from .errors import ContactParameterError, require_non_negative, require_positive

__all__ = [
    "FrictionLaw",
    "ScalarFrictionLaw",
    "BrownMcPheeFriction",
    "CoulombFriction",
    "NoFriction",
    "FRICTION_NONE",
    "FRICTION_BROWN_MCPHEE",
    "FRICTION_COULOMB",
    "FRICTION_EXTERNAL",
    "FRICTION_PARAMETERS",
    "friction_encoding",
    "brown_mcphee_force_over_speed",
    "coulomb_force_over_speed",
    "encoded_force_over_speed",
]

# -- encoding of the built-in laws for the compiled kernels ----------------------------
FRICTION_NONE: int = 0
"""Kind code of :class:`NoFriction` (parameters unused)."""
FRICTION_BROWN_MCPHEE: int = 1
"""Kind code of :class:`BrownMcPheeFriction`; parameters (mu_s, mu_k, v_s, mu_v, F_ref)."""
FRICTION_COULOMB: int = 2
"""Kind code of :class:`CoulombFriction`; parameters (mu, v_r, 0, 0, 0)."""
FRICTION_EXTERNAL: int = 3
"""Kind code of any other :class:`FrictionLaw` (user-defined): applied in Python by ``evaluate``."""
FRICTION_PARAMETERS: int = 5
"""Number of float parameters after the kind code in a kernel parameter array."""


@runtime_checkable
class FrictionLaw(Protocol):
    """What a joint needs from a friction law (see the module docstring)."""

    def coefficient(self, slip_speed: float) -> float:
        """Friction coefficient f / F_N at the given slip speed (m/s)."""
        ...

    def force(self, normal_force: float, slip_velocity: ArrayLike) -> np.ndarray:
        """Friction force (3,) opposed to ``slip_velocity``, finite at zero slip."""
        ...


@runtime_checkable
class ScalarFrictionLaw(FrictionLaw, Protocol):
    """A friction law with the scalar fast path used by the joints."""

    def force_over_speed(self, normal_force: float, slip_speed: float) -> float:
        """g = f(v) / v (N s/m), finite at v = 0 for continuous laws."""
        ...


_ZERO_SLIP = 1.0e-300
"""Slip speeds (m/s) at or below which the Coulomb sign law's g = mu F_N / v is
returned as 0 (zero slip), so that g stays finite in floating point."""


@jit
def _tanh_over(y: float) -> float:
    """tanh(y) / y for y >= 0, with its limit 1 at y = 0 (series below 1e-4)."""
    if y < 1.0e-4:
        return 1.0 - y * y / 3.0
    return math.tanh(y) / y


def _vector_force(law: ScalarFrictionLaw, normal_force: float, slip_velocity: ArrayLike) -> np.ndarray:
    v = np.asarray(slip_velocity, dtype=float)
    if v.shape != (3,):
        raise ValueError(f"slip_velocity must have shape (3,), got {v.shape}")
    g = law.force_over_speed(float(normal_force), math.hypot(*v.tolist()))
    return -g * v


@jit
def brown_mcphee_force_over_speed(
    normal_force: float,
    slip_speed: float,
    static_coefficient: float,
    dynamic_coefficient: float,
    transition_velocity: float,
    viscous_coefficient: float,
    reference_force: float,
) -> float:
    """Brown-McPhee g(v) = f(v) / v in N s/m (seed paper eq. (14), module docstring).

    ``g = F_N [4 mu_k tanh(4x)/(4x) + (mu_s - mu_k) / (x^2/4 + 3/4)^2] / v_s
    + mu_v tanh(4 F_N / F_ref)``, x = v / v_s; finite at v = 0; 0 if F_N <= 0.
    The one implementation, used by :meth:`BrownMcPheeFriction.force_over_speed`
    and by the joints' compiled kernels.
    """
    if normal_force <= 0.0:
        return 0.0
    x = slip_speed / transition_velocity
    d = 0.25 * x * x + 0.75
    g = (
        normal_force
        * (4.0 * dynamic_coefficient * _tanh_over(4.0 * x) + (static_coefficient - dynamic_coefficient) / (d * d))
        / transition_velocity
    )
    if viscous_coefficient > 0.0:
        g += viscous_coefficient * math.tanh(4.0 * normal_force / reference_force)
    return g


@jit
def coulomb_force_over_speed(
    normal_force: float, slip_speed: float, coefficient: float, regularisation_velocity: float
) -> float:
    """Coulomb g = mu F_N / v (sign law, 0 at v <= 1e-300) or mu F_N tanh(v/v_r) / v (N s/m).

    0 if F_N <= 0.  The one implementation, used by
    :meth:`CoulombFriction.force_over_speed` and by the joints' compiled kernels.
    """
    if normal_force <= 0.0:
        return 0.0
    v_r = regularisation_velocity
    if v_r > 0.0:
        return coefficient * normal_force * _tanh_over(slip_speed / v_r) / v_r
    if slip_speed <= _ZERO_SLIP:
        return 0.0
    return coefficient * normal_force / slip_speed


@jit
def encoded_force_over_speed(parameters, offset: int, normal_force: float, slip_speed: float) -> float:
    """g of the built-in law encoded at ``parameters[offset:offset + 1 + FRICTION_PARAMETERS]``.

    ``parameters[offset]`` is the kind code (``FRICTION_*``), followed by the law's
    parameters (:func:`friction_encoding`).  Returns 0 for ``FRICTION_NONE`` and for
    ``FRICTION_EXTERNAL`` (which the kernels handle before calling this).
    """
    code = int(parameters[offset])
    if code == FRICTION_BROWN_MCPHEE:
        return brown_mcphee_force_over_speed(
            normal_force,
            slip_speed,
            parameters[offset + 1],
            parameters[offset + 2],
            parameters[offset + 3],
            parameters[offset + 4],
            parameters[offset + 5],
        )
    if code == FRICTION_COULOMB:
        return coulomb_force_over_speed(normal_force, slip_speed, parameters[offset + 1], parameters[offset + 2])
    return 0.0


def friction_encoding(law: FrictionLaw) -> tuple[int, tuple[float, ...]]:
    """(kind code, FRICTION_PARAMETERS floats) of a friction law for the compiled kernels.

    Exactly :class:`BrownMcPheeFriction`, :class:`CoulombFriction` and
    :class:`NoFriction` are encoded (not subclasses, which may override the law);
    anything else is ``FRICTION_EXTERNAL`` (zeros), applied in Python.
    """
    kind = type(law)
    if kind is BrownMcPheeFriction:
        return FRICTION_BROWN_MCPHEE, (
            law.static_coefficient,
            law.dynamic_coefficient,
            law.transition_velocity,
            law.viscous_coefficient,
            law.reference_force,
        )
    if kind is CoulombFriction:
        return FRICTION_COULOMB, (law.friction_coefficient, law.regularisation_velocity, 0.0, 0.0, 0.0)
    if kind is NoFriction:
        return FRICTION_NONE, (0.0,) * FRICTION_PARAMETERS
    return FRICTION_EXTERNAL, (0.0,) * FRICTION_PARAMETERS


@dataclass(frozen=True, slots=True)
class BrownMcPheeFriction:
    """Continuous velocity-based friction of Brown & McPhee (2016), seed paper eq. (14).

    Parameters
    ----------
    static_coefficient:
        mu_s, peak coefficient (at the transition velocity), range [dynamic_coefficient, inf).
    dynamic_coefficient:
        mu_k, coefficient at high slip, range [0, inf).
    transition_velocity:
        v_s in m/s, slip speed of the peak, range (0, inf).
    viscous_coefficient:
        mu_v in N s/m, range [0, inf); default 0 (no viscous friction).
    reference_force:
        F_ref in N, range (0, inf): the viscous term is faded in with
        tanh(4 F_N / F_ref) so that it vanishes with the normal force.  Default
        1 N; only used when ``viscous_coefficient > 0``.
    """

    static_coefficient: float
    dynamic_coefficient: float
    transition_velocity: float
    viscous_coefficient: float = 0.0
    reference_force: float = 1.0

    def __post_init__(self) -> None:
        mu_s = require_non_negative("static_coefficient", self.static_coefficient)
        mu_k = require_non_negative("dynamic_coefficient", self.dynamic_coefficient)
        if mu_s < mu_k:
            raise ContactParameterError(
                f"static_coefficient={self.static_coefficient!r} must be >= "
                f"dynamic_coefficient={self.dynamic_coefficient!r} (valid range [dynamic_coefficient, inf))"
            )
        object.__setattr__(self, "static_coefficient", mu_s)
        object.__setattr__(self, "dynamic_coefficient", mu_k)
        object.__setattr__(
            self, "transition_velocity", require_positive("transition_velocity", self.transition_velocity)
        )
        object.__setattr__(
            self, "viscous_coefficient", require_non_negative("viscous_coefficient", self.viscous_coefficient)
        )
        object.__setattr__(self, "reference_force", require_positive("reference_force", self.reference_force))

    def coefficient(self, slip_speed: float) -> float:
        """mu(v) = mu_k tanh(4 v/v_s) + (mu_s - mu_k)(v/v_s) / ((v/v_s)^2/4 + 3/4)^2 (odd in v)."""
        x = slip_speed / self.transition_velocity
        d = 0.25 * x * x + 0.75
        return self.dynamic_coefficient * math.tanh(4.0 * x) + (
            self.static_coefficient - self.dynamic_coefficient
        ) * x / (d * d)

    def force_over_speed(self, normal_force: float, slip_speed: float) -> float:
        """g(v) = f(v) / v in N s/m for v = slip_speed >= 0; finite at v = 0; 0 if F_N <= 0."""
        return brown_mcphee_force_over_speed(
            float(normal_force),
            float(slip_speed),
            self.static_coefficient,
            self.dynamic_coefficient,
            self.transition_velocity,
            self.viscous_coefficient,
            self.reference_force,
        )

    def force(self, normal_force: float, slip_velocity: ArrayLike) -> np.ndarray:
        """F_t = -g(|v_t|) v_t, shape (3,)."""
        return _vector_force(self, normal_force, slip_velocity)


class CoulombFriction:
    """Coulomb friction f = mu F_N, for comparison.

    ``regularisation_velocity = 0`` (default): the sign law, F_t = -mu F_N v_t/|v_t|
    for |v_t| > 0 and 0 at |v_t| = 0: discontinuous at zero slip by construction
    (a stiff integrator will chatter there).  ``regularisation_velocity = v_r > 0``:
    f = mu F_N tanh(|v_t| / v_r), continuous, with g(0) = mu F_N / v_r.

    Parameters: ``coefficient`` mu, range [0, inf); ``regularisation_velocity`` in
    m/s, range [0, inf).  (The value of mu is stored as ``friction_coefficient``
    since ``coefficient`` is the method of the :class:`FrictionLaw` protocol.)
    """

    __slots__ = ("friction_coefficient", "regularisation_velocity")

    def __init__(self, coefficient: float, regularisation_velocity: float = 0.0) -> None:
        self.friction_coefficient = require_non_negative("coefficient", coefficient)
        self.regularisation_velocity = require_non_negative("regularisation_velocity", regularisation_velocity)

    def __repr__(self) -> str:
        return (
            f"CoulombFriction(coefficient={self.friction_coefficient!r}, "
            f"regularisation_velocity={self.regularisation_velocity!r})"
        )

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, CoulombFriction):
            return NotImplemented
        return (self.friction_coefficient, self.regularisation_velocity) == (
            other.friction_coefficient,
            other.regularisation_velocity,
        )

    def __hash__(self) -> int:
        return hash((CoulombFriction, self.friction_coefficient, self.regularisation_velocity))

    def coefficient(self, slip_speed: float) -> float:
        """mu sign(v) (sign law) or mu tanh(v / v_r) (regularised); odd in v."""
        if self.regularisation_velocity > 0.0:
            return self.friction_coefficient * math.tanh(slip_speed / self.regularisation_velocity)
        if slip_speed == 0.0:
            return 0.0
        return math.copysign(self.friction_coefficient, slip_speed)

    def force_over_speed(self, normal_force: float, slip_speed: float) -> float:
        """g = mu F_N / v (sign law, 0 at v = 0) or mu F_N tanh(v/v_r) / v."""
        return coulomb_force_over_speed(
            float(normal_force), float(slip_speed), self.friction_coefficient, self.regularisation_velocity
        )

    def force(self, normal_force: float, slip_velocity: ArrayLike) -> np.ndarray:
        """F_t = -mu F_N v_t / |v_t| (sign law) or -g(|v_t|) v_t (regularised), shape (3,)."""
        if self.regularisation_velocity > 0.0:
            return _vector_force(self, normal_force, slip_velocity)
        v = np.asarray(slip_velocity, dtype=float)
        if v.shape != (3,):
            raise ValueError(f"slip_velocity must have shape (3,), got {v.shape}")
        largest = float(np.max(np.abs(v)))
        if normal_force <= 0.0 or largest == 0.0:
            return np.zeros(3)
        direction = v / largest  # scaled first: exact unit vector even for subnormal slips
        return (-self.friction_coefficient * float(normal_force) / math.hypot(*direction.tolist())) * direction


class NoFriction:
    """Frictionless contact: zero tangential force."""

    __slots__ = ()

    def __repr__(self) -> str:
        return "NoFriction()"

    def __eq__(self, other: object) -> bool:
        return isinstance(other, NoFriction)

    def __hash__(self) -> int:
        return hash(NoFriction)

    def coefficient(self, slip_speed: float) -> float:
        """Always 0."""
        return 0.0

    def force_over_speed(self, normal_force: float, slip_speed: float) -> float:
        """Always 0."""
        return 0.0

    def force(self, normal_force: float, slip_velocity: ArrayLike) -> np.ndarray:
        """Always the zero vector (3,)."""
        return np.zeros(3)


def require_friction_law(value) -> FrictionLaw:
    """``value`` if it implements :class:`FrictionLaw`, else ContactParameterError."""
    if not isinstance(value, FrictionLaw):
        raise ContactParameterError(
            f"friction={value!r} must implement FrictionLaw (coefficient(slip_speed), force(normal_force, slip_velocity))"
        )
    return value
