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

**Registry of laws by name** (what ``friction = {law = "NAME", ...}`` in a scene selects):
:func:`register_friction_law` ``(name, factory, keys=...)`` from any module, or as a
decorator on a law class; a name already taken is refused.  The built-ins are registered
the same way (``none``, ``brown_mcphee``, ``coulomb``).  :func:`friction_law_from_scene`
validates a scene's friction table against the law's :class:`FrictionKey` s (unknown key,
missing key, or a value outside its range: ContactParameterError naming the key, the value
and the valid range) and builds the law; :func:`friction_scene_table` describes a law
back as such a table (what results record).

**User-defined laws** (any :class:`FrictionLaw` but the three built-in classes) are applied
in Python by the joints, every call checked in one place (:func:`user_friction`,
:func:`user_friction_gain`, :func:`user_friction_force`): a law that raises, returns NaN /
inf, a negative g (friction along the slip: it would create energy) or a force with a
component along the slip gives :class:`~clearance_contact.errors.ContactError` naming the
law, the value and the valid range.  :func:`require_friction_law` checks the methods'
signatures and samples the law once when a joint is built (ContactParameterError then).
"""

from __future__ import annotations

import inspect
import math
import numbers
from dataclasses import dataclass
from typing import Any, Callable, Mapping, Protocol, Sequence, runtime_checkable

import numpy as np
from numpy.typing import ArrayLike

from .compiled import jit
from .errors import ClearanceMechanismsError, ContactError, ContactLawError, ContactParameterError, real_number, require_non_negative, require_positive, require_unregistered

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
    "FrictionKey",
    "FrictionLawType",
    "register_friction_law",
    "friction_law_type",
    "friction_law_names",
    "friction_law_from_scene",
    "friction_scene_table",
    "require_friction_law",
    "user_friction",
    "user_friction_gain",
    "user_friction_force",
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


@jit(exports=("f8(f8, f8, f8, f8, f8, f8, f8)",))  # BrownMcPheeFriction.force_over_speed's call
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


@jit(exports=("f8(f8, f8, f8, f8)",))  # CoulombFriction.force_over_speed's call
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


# -- checks of user-defined laws ---------------------------------------------------------
#: (normal force N, slip speed m/s) at which a user-defined law is sampled when a joint is built
_SAMPLES = ((1.0, 0.0), (1.0, 1.0e-4), (1.0, 1.0e-2), (1.0, 1.0), (1.0e3, 1.0e-2))
#: relative tolerance of the check that a force opposes the slip (rounding of a law's own direction)
_ALONG_SLIP_TOLERANCE = 1.0e-9


def _law_name(law) -> str:
    return f"{type(law).__module__}.{type(law).__qualname__}"


def _call_law(law, method: str, *arguments):
    """``law.method(*arguments)``; any exception of the law becomes ContactError naming it."""
    try:
        return getattr(law, method)(*arguments)
    except ClearanceMechanismsError:
        raise
    except Exception as exc:  # noqa: BLE001 - the user's law: its failure is reported, not a raw exception
        raise ContactLawError(
            f"friction law {_law_name(law)}: {method}{arguments!r} raised {type(exc).__name__}: {exc}; fix the law",
            key="friction", value=law,
        ) from exc  # fmt: skip


def user_friction_gain(law, normal_force: float, slip_speed: float) -> float:
    """g = f / v (N s/m) of a user-defined law's ``force_over_speed``, checked: a finite real number >= 0.

    ContactError (naming the law, the arguments, the value and the valid range [0, inf))
    for anything else, or when the law raises.
    """
    g = _call_law(law, "force_over_speed", normal_force, slip_speed)
    value = real_number(g)
    if value is None or not (math.isfinite(value) and value >= 0.0):
        raise ContactLawError(
            f"friction law {_law_name(law)}: force_over_speed(normal_force={normal_force!r}, slip_speed={slip_speed!r}) "
            f"= {g!r} is outside the valid range [0, inf) of g = f/v (a real number; a negative g pushes along the "
            "slip and creates energy)",
            key="friction", value=g,
        )  # fmt: skip
    return value


def user_friction_force(law, normal_force: float, slip_velocity: np.ndarray) -> np.ndarray:
    """F_t (3,) of a user-defined law's ``force``, checked: finite, of shape (3,), not along the slip.

    ``F_t . v_t <= 0`` (to a relative 1e-9) is required: friction dissipates.  ContactError
    naming the law, the slip, the force and the valid range otherwise, or when the law raises.
    """
    slip = np.asarray(slip_velocity, dtype=float)
    raw = _call_law(law, "force", normal_force, slip.copy())
    try:
        force = np.asarray(raw, dtype=float)
    except (TypeError, ValueError):
        force = None
    if force is None or force.shape != (3,) or not np.all(np.isfinite(force)):
        raise ContactLawError(
            f"friction law {_law_name(law)}: force(normal_force={normal_force!r}, slip_velocity={slip.tolist()!r}) = "
            f"{raw!r} must be 3 finite numbers (N)",
            key="friction", value=raw,
        )  # fmt: skip
    power = float(force @ slip)
    if power > _ALONG_SLIP_TOLERANCE * float(np.linalg.norm(force)) * float(np.linalg.norm(slip)):
        raise ContactLawError(
            f"friction law {_law_name(law)}: force(normal_force={normal_force!r}, slip_velocity={slip.tolist()!r}) = "
            f"{force.tolist()!r} pushes along the slip (power F_t . v_t = {power!r} W, valid range (-inf, 0]): "
            "friction must oppose the slip",
            key="friction", value=force.tolist(),
        )  # fmt: skip
    return force


def user_friction(law, normal_force: float, slip_velocity: np.ndarray) -> np.ndarray:
    """F_t (3,) of a user-defined law on the slip v_t: ``-g(|v_t|) v_t`` through ``force_over_speed`` if the
    law has it (:func:`user_friction_gain`; |v_t| as ``math.hypot``, as the kernels' ``norm3``), else its
    ``force`` (:func:`user_friction_force`).  The one path of the joints' Python friction (checked)."""
    slip = np.asarray(slip_velocity, dtype=float)
    if getattr(law, "force_over_speed", None) is not None:
        return -user_friction_gain(law, normal_force, math.hypot(*slip.tolist())) * slip
    return user_friction_force(law, normal_force, slip)


def _require_signature(law, method: str, arguments: tuple) -> None:
    """ContactParameterError unless ``law.method`` can be called with ``arguments`` (when it has a signature)."""
    function = getattr(law, method)
    try:
        inspect.signature(function).bind(*arguments)
    except TypeError as exc:
        raise ContactParameterError(
            f"friction law {_law_name(law)}: {method} cannot be called as {method}"
            f"({', '.join(_PROTOCOL_ARGUMENTS[method])}) ({exc}); see the FrictionLaw protocol",
            key="friction", value=law,
        ) from None  # fmt: skip
    except ValueError:  # no signature to inspect: the calls are checked on use
        pass


_PROTOCOL_ARGUMENTS = {"coefficient": ("slip_speed",), "force": ("normal_force", "slip_velocity"), "force_over_speed": ("normal_force", "slip_speed")}


def require_friction_law(value) -> FrictionLaw:
    """``value`` if it implements :class:`FrictionLaw`, else ContactParameterError.

    A user-defined law (not one of the three built-in classes) is also checked: its
    methods' signatures, and its friction (:func:`user_friction`) at a few normal forces
    and slips (:data:`_SAMPLES`): finite, g >= 0, opposed to the slip, no exception
    (ContactParameterError naming the law, the value and the valid range).
    """
    if not isinstance(value, FrictionLaw):
        raise ContactParameterError(
            f"friction={value!r} must implement FrictionLaw (coefficient(slip_speed), force(normal_force, slip_velocity))"
        )
    if type(value) in (BrownMcPheeFriction, CoulombFriction, NoFriction):
        return value
    for method, arguments in _PROTOCOL_ARGUMENTS.items():
        if getattr(value, method, None) is not None:
            _require_signature(value, method, (0.0,) * len(arguments))
    for normal_force, slip_speed in _SAMPLES:
        try:
            user_friction(value, normal_force, np.array((slip_speed, 0.0, 0.0)))
        except ContactParameterError:
            raise
        except ContactError as exc:
            raise ContactParameterError(f"{exc} (checked when the joint is built)", key="friction", value=value) from exc.__cause__
    return value


# -- registry of laws by name (scenes) ------------------------------------------------------------
@dataclass(frozen=True)
class FrictionKey:
    """A number key of a friction law's scene table: ``name``, valid range and default.

    The range is [low, high] (``low_open``: (low, high]); ``default`` None: the key is required.
    """

    name: str
    low: float = 0.0
    high: float = math.inf
    low_open: bool = False
    default: float | None = None

    @property
    def interval(self) -> str:
        """The valid range in the usual notation, e.g. ``(0, inf)``."""
        return f"{'(' if self.low_open else '['}{self.low:g}, {self.high:g}{')' if math.isinf(self.high) else ']'}"

    def value(self, table: Mapping[str, Any]) -> float | None:
        """The key's value in ``table`` (its default if absent), checked; ContactParameterError naming key, value, range."""
        if self.name not in table:
            if self.default is None:
                raise ContactParameterError(f"missing required key {self.name!r} (valid range {self.interval})", key=self.name)
            return self.default
        value = table[self.name]
        number = isinstance(value, numbers.Real) and not isinstance(value, bool) and math.isfinite(value)
        inside = number and (value > self.low if self.low_open else value >= self.low) and value <= self.high
        if not inside:
            raise ContactParameterError(
                f"{self.name}={value!r} is outside the valid range {self.interval} (a finite number)", key=self.name, value=value
            )
        return float(value)


@dataclass(frozen=True)
class FrictionLawType:
    """A registered friction law: its scene ``name``, ``factory(**values) -> FrictionLaw`` and scene ``keys``.

    ``law_class``: the class the factory builds (its instances are described as this law,
    :func:`friction_scene_table`); ``describe(law) -> {key: value}``: their key values, if known.
    """

    name: str
    factory: Callable[..., FrictionLaw]
    keys: tuple[FrictionKey, ...]
    law_class: type | None = None
    describe: Callable[[Any], Mapping[str, float]] | None = None

    def build(self, table: Mapping[str, Any]) -> tuple[FrictionLaw, dict[str, Any]]:
        """(the law, its table with defaults filled) from a scene table (``law`` and the keys)."""
        unknown = sorted(set(table) - {"law"} - {key.name for key in self.keys})
        if unknown:
            valid = ", ".join(["law", *(key.name for key in self.keys)])
            raise ContactParameterError(
                f"unknown key(s) {', '.join(unknown)} of friction law {self.name!r}; valid keys: {valid}", key=unknown[0], value=table[unknown[0]]
            )
        given = {key.name: key.value(table) for key in self.keys}
        try:
            law = self.factory(**given)
        except ClearanceMechanismsError:
            raise
        except (TypeError, ValueError) as exc:  # the user's factory refusing its values
            raise ContactParameterError(f"friction law {self.name!r} refused {given!r}: {exc}", key="friction", value=given) from exc
        return require_friction_law(law), {"law": self.name, **given}


_LAWS: dict[str, FrictionLawType] = {}


def register_friction_law(
    name: str, factory: Callable[..., FrictionLaw] | None = None, keys: Sequence[FrictionKey] | None = None, *, law_class=None, describe=None
):
    """Register a friction law as ``name`` for scenes: ``friction = {law = "NAME", key = value, ...}``.

    ``factory(**values)`` builds the law (a :class:`FrictionLaw`) from the validated scene
    keys ``keys`` (:class:`FrictionKey` s; default: one key per parameter of ``factory``,
    any finite number, required unless the parameter has a default: the factory checks
    its own ranges).  Without ``factory``, returns a decorator: ``@register_friction_law("NAME")``
    on a law class.  ``law_class`` (default: ``factory`` if it is a class) and ``describe(law)
    -> {key: value}`` (optional): how results record an instance of that class.  ContactParameterError if ``name`` is taken (naming it and its
    holder), is not an identifier, or the keys do not fit the factory.  Returns ``factory``.
    """
    if factory is None:
        return lambda decorated: register_friction_law(name, decorated, keys, law_class=law_class, describe=describe)
    if not isinstance(name, str) or not name.isidentifier():
        raise ContactParameterError(f"friction law name {name!r} must be a non-empty identifier", key="law", value=name)
    require_unregistered("friction law", name, _LAWS[name].factory if name in _LAWS else None, factory, _LAWS, key="law")
    if not callable(factory):
        raise ContactParameterError(f"friction law {name!r}: factory={factory!r} must be callable", key="law", value=name)
    keys = _factory_keys(name, factory) if keys is None else tuple(keys)
    names = [key.name for key in keys]
    if "law" in names or len(set(names)) != len(names) or not all(isinstance(key, FrictionKey) for key in keys):
        raise ContactParameterError(f"friction law {name!r}: keys must be distinct FrictionKey s other than 'law', got {names!r}", key="law", value=name)
    try:
        inspect.signature(factory).bind(**{key: 1.0 for key in names})
    except TypeError as exc:
        raise ContactParameterError(f"friction law {name!r}: factory cannot take the keys {names!r} ({exc})", key="law", value=name) from None
    except ValueError:
        pass
    if law_class is None and isinstance(factory, type):
        law_class = factory
    _LAWS[name] = FrictionLawType(name, factory, keys, law_class, describe)
    return factory


def _factory_keys(name: str, factory) -> tuple[FrictionKey, ...]:
    """One key per parameter of ``factory`` (no range but finite; required unless it has a default)."""
    try:
        parameters = inspect.signature(factory).parameters.values()
    except ValueError:
        raise ContactParameterError(f"friction law {name!r}: give keys= (the factory {factory!r} has no signature to read)") from None
    keys = []
    for parameter in parameters:
        if parameter.kind in (parameter.VAR_POSITIONAL, parameter.VAR_KEYWORD, parameter.POSITIONAL_ONLY):
            raise ContactParameterError(f"friction law {name!r}: give keys= (the factory's parameter {parameter.name!r} is not a keyword)")
        default = None if parameter.default is parameter.empty else parameter.default
        if default is not None and (isinstance(default, bool) or not isinstance(default, numbers.Real)):
            raise ContactParameterError(
                f"friction law {name!r}: give keys= (the factory's parameter {parameter.name}={default!r} is not a number)", key="law", value=name
            )
        keys.append(FrictionKey(parameter.name, low=-math.inf, default=None if default is None else float(default)))
    return tuple(keys)


def friction_law_type(name: str) -> FrictionLawType:
    """The law registered as ``name``; ContactParameterError naming the registered ones otherwise."""
    try:
        return _LAWS[name]
    except (KeyError, TypeError):
        raise ContactParameterError(
            f"friction law={name!r} is not registered; registered laws: {', '.join(_LAWS)} "
            "(a law of your own: clearance_contact.register_friction_law, imported before the scene is read)",
            key="law", value=name,
        ) from None  # fmt: skip


def friction_law_names() -> tuple[str, ...]:
    """The registered law names, in registration order (the built-ins first)."""
    return tuple(_LAWS)


def friction_law_from_scene(table: Mapping[str, Any] | None) -> tuple[FrictionLaw, dict[str, Any]]:
    """(law, table as validated with defaults) of a scene's friction table; None: no friction.

    ``law`` defaults to ``"none"``.  ContactParameterError (key, value, valid range) for an
    unregistered law, an unknown or missing key, or a value out of range.
    """
    if table is None:
        table = {}
    if not isinstance(table, Mapping):
        raise ContactParameterError(f"friction must be a table {{law = NAME, ...}}, got {table!r}", key="friction", value=table)
    return friction_law_type(table.get("law", "none")).build(table)


def friction_scene_table(law: FrictionLaw) -> dict[str, Any]:
    """A law as a scene's friction table: ``{"law": name, key: value...}`` for a registered class
    (the values if its entry can ``describe`` them); ``{"class": "module.qualname"}`` for any other law."""
    for entry in _LAWS.values():
        if entry.law_class is not None and type(law) is entry.law_class:
            return {"law": entry.name, **(dict(entry.describe(law)) if entry.describe else {})}
    return {"class": _law_name(law)}


def _brown_mcphee_from_scene(static, dynamic, transition_velocity, viscous, reference_force) -> BrownMcPheeFriction:
    """The scene's ``brown_mcphee`` table: its own key names in the message when static < dynamic."""
    if static < dynamic:
        raise ContactParameterError(
            f"static={static!r} must be >= dynamic={dynamic!r} (valid range [dynamic, inf): the static coefficient "
            "bounds the dynamic one)",
            key="static", value=static,
        )  # fmt: skip
    return BrownMcPheeFriction(static, dynamic, transition_velocity, viscous, reference_force)


register_friction_law("none", NoFriction, (), describe=lambda law: {})
register_friction_law(
    "brown_mcphee",
    _brown_mcphee_from_scene,
    (
        FrictionKey("static"),
        FrictionKey("dynamic"),
        FrictionKey("transition_velocity", low_open=True),
        FrictionKey("viscous", default=0.0),
        FrictionKey("reference_force", low_open=True, default=1.0),
    ),
    law_class=BrownMcPheeFriction,
    describe=lambda law: {
        "static": law.static_coefficient,
        "dynamic": law.dynamic_coefficient,
        "transition_velocity": law.transition_velocity,
        "viscous": law.viscous_coefficient,
        "reference_force": law.reference_force,
    },
)
register_friction_law(
    "coulomb",
    lambda coefficient, regularisation_velocity: CoulombFriction(coefficient, regularisation_velocity),
    (FrictionKey("coefficient"), FrictionKey("regularisation_velocity", default=0.0)),
    law_class=CoulombFriction,
    describe=lambda law: {"coefficient": law.friction_coefficient, "regularisation_velocity": law.regularisation_velocity},
)
