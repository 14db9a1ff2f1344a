"""Normal contact force: the Lankarani-Nikravesh law and its Hertz limit.

Lankarani & Nikravesh, "A contact force model with hysteresis damping for impact
analysis of multibody systems", J. Mech. Des. 112 (1990) 369-376; seed paper
eq. (11) (point contact), reused for line and plane contact with another
stiffness and exponent (seed paper eqs. (12)-(13))::

    F = K delta^n [1 + 3 (1 - c_e^2) / 4 * delta_dot / delta_dot0]    delta > 0
    F = 0                                                             delta <= 0

delta: penetration (m, > 0 in contact), delta_dot its rate (m/s, > 0 while
compressing), delta_dot0 the approach rate at the onset of the current impact,
K the stiffness (N/m^n), n the exponent, c_e the coefficient of restitution.
The hysteresis term was derived for c_e close to 1 (energy loss of the impact
equated to the kinetic-energy loss (1 - c_e^2) m v^2 / 2, with the
approximation that the loading and unloading Hertz curves are close).

Two guards, both documented here and applied nowhere else:

* ``delta_dot0 = max(onset_rate, ONSET_RATE_FLOOR)``: the caller keeps the onset
  rate (set at a contact-onset event); an onset at grazing incidence (rate ~ 0)
  would make the damping term blow up.
* ``F = max(F, 0)``: during restitution the damping term can exceed the elastic
  term (e.g. onset rate floored); a contact cannot pull (no adhesion).
"""

from __future__ import annotations

import math
from typing import NamedTuple

from .compiled import jit
from .errors import require_in_range, require_positive

__all__ = [
    "ONSET_RATE_FLOOR",
    "EXPONENT_RANGE",
    "lankarani_nikravesh",
    "hysteresis_factor",
    "hysteresis_damping_factor",
    "validate_normal_law",
    "HertzImpactMaximum",
    "hertz_impact_maximum",
]

ONSET_RATE_FLOOR: float = 1.0e-4
"""Lower bound (m/s) of the onset approach rate delta_dot0 in the L-N damping term.

0.1 mm/s: below it an impact is a resting/grazing contact, and the damping
coefficient 3 K (1 - c_e^2) delta^n / (4 delta_dot0) is capped at its value for
this rate instead of growing without bound."""

EXPONENT_RANGE: tuple[float, float] = (1.0, 1.5)
"""Valid range of the force exponent n (seed paper: "n ranges from 1 to 3/2")."""


@jit(exports=("f8(f8)",))
def hysteresis_factor(restitution: float) -> float:
    """Return the L-N damping factor 3 (1 - c_e^2) / 4 (dimensionless)."""
    return 0.75 * (1.0 - restitution * restitution)


def validate_normal_law(stiffness: float, exponent: float, restitution: float) -> tuple[float, float, float]:
    """Check L-N parameters; return them as floats.

    stiffness in (0, inf), exponent in [1, 1.5], restitution in (0, 1].
    Raises :class:`~clearance_contact.errors.ContactParameterError`.
    """
    k = require_positive("stiffness", stiffness)
    n = require_in_range("exponent", exponent, *EXPONENT_RANGE)
    ce = require_in_range("restitution", restitution, 0.0, 1.0, low_inclusive=False)
    return k, n, ce


@jit
def lankarani_nikravesh(
    penetration: float,
    penetration_rate: float,
    onset_rate: float,
    stiffness: float,
    exponent: float,
    restitution: float,
) -> float:
    """Lankarani-Nikravesh normal force magnitude (N), seed paper eq. (11).

    ``F = K delta^n [1 + 3 (1 - c_e^2)/4 * delta_dot / max(delta_dot0, ONSET_RATE_FLOOR)]``,
    clamped at >= 0, and exactly 0 when ``penetration <= 0``.

    Hot-path function: plain floats, no validation (the joints validate their
    parameters once at construction with :func:`validate_normal_law`).  Compiled by
    :data:`~clearance_contact.compiled.jit` and called as is by the joints' compiled
    kernels: this is the one implementation of the law.
    """
    if penetration <= 0.0:
        return 0.0
    force = stiffness * penetration**exponent * hysteresis_damping_factor(
        penetration_rate, onset_rate, hysteresis_factor(restitution)
    )
    return force if force > 0.0 else 0.0


@jit
def hysteresis_damping_factor(penetration_rate: float, onset_rate: float, chi: float) -> float:
    """1 + chi delta_dot / max(delta_dot0, ONSET_RATE_FLOOR): the Hunt-Crossley-form factor on the
    elastic force, not clamped (every model of :mod:`~clearance_contact.dissipation`; L-N: chi
    = :func:`hysteresis_factor`).  The one implementation of the damping term and its floor."""
    rate0 = onset_rate if onset_rate > ONSET_RATE_FLOOR else ONSET_RATE_FLOOR
    return 1.0 + chi * penetration_rate / rate0


class HertzImpactMaximum(NamedTuple):
    """Peak of an undamped (c_e = 1) impact: penetration (m) and force (N)."""

    penetration: float
    force: float


def hertz_impact_maximum(
    stiffness: float,
    effective_mass: float,
    impact_speed: float,
    exponent: float = 1.5,
) -> HertzImpactMaximum:
    """Analytic maximum penetration and force of an elastic impact, F = K delta^n.

    The kinetic energy at contact onset is fully stored at maximum compression::

        m v^2 / 2 = K delta_max^(n+1) / (n + 1)
        delta_max = ((n + 1) m v^2 / (2 K))^(1/(n+1)),    F_max = K delta_max^n

    For Hertz (n = 3/2): delta_max = (5 m v^2 / (4 K))^(2/5) (MODEL-NOTES 4;
    Johnson 1985 Ch. 11, quasi-static Hertz impact).  ``effective_mass`` m = m_1 m_2 / (m_1 + m_2) for two
    free bodies; ``impact_speed`` is the normal approach speed at onset.
    """
    k = require_positive("stiffness", stiffness)
    m = require_positive("effective_mass", effective_mass)
    v = require_positive("impact_speed", impact_speed)
    n = require_in_range("exponent", exponent, *EXPONENT_RANGE)
    delta_max = ((n + 1.0) * m * v * v / (2.0 * k)) ** (1.0 / (n + 1.0))
    return HertzImpactMaximum(penetration=delta_max, force=k * math.pow(delta_max, n))
