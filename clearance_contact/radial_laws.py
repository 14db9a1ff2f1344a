"""Radial contact laws of the revolute joint: force per unit length q(delta) of a slice.

Each law gives the force F(delta) of an aligned journal pressed uniformly by delta over
the whole bearing length L_b; the joint distributes it per unit length,
q(delta) = F(delta) / L_b, over the exact penetration profile
(:mod:`~clearance_contact.radial_profile`), so that aligned contact gives exactly
F(delta).  E* is the combined modulus (:func:`~clearance_contact.materials.combined_modulus`),
Delta R = R_b1 - R_j the radial clearance, all SI units.

* ``"linear"`` (default): F = K delta^n, K = pi/4 E* L_b and n = 1 unless given
  (:func:`~clearance_contact.materials.cylinder_line_stiffness`; seed paper eq. (12)).
  Independent of the radii and the clearance: the stiffest of the published laws.
* ``"johnson"``: Johnson, Contact Mechanics (1985), Sec. 5.6, pin in a conforming hole,
  as quoted by Pereira, Ramalho & Ambrosio, Nonlinear Dyn. 63 (2011) 681-697, eq. (9)::

      delta = (F / (pi L_b E*)) [ln(4 pi L_b E* Delta R / F) - 1]

  inverted per slice in closed form of the line load P = F / L_b: with
  s = P / (4 pi E* Delta R) and D = delta / (4 Delta R), D = s (-ln s - 1), solved for
  u = ln s by Newton's method on u + ln(-u - 1) = ln D (increasing and concave for
  u < -2: monotone convergence to rounding in <= 6 steps from u_0 = ln D - ln(-ln D - 1),
  more only within ~1e-6 of the maximum, where h' -> 0).
  The relation has a maximum D = e^-2 (delta = 0.54 Delta R) where its stiffness is
  infinite; beyond it the force continues as F_max delta / delta_max (no physical
  meaning; a run stops at penetration_ratio 0.5 of the clearance by default).
* ``"pereira"``: Pereira, Ramalho & Ambrosio (2011), internal contact::

      F = (a Delta R + b) L_b E* delta^n / Delta R,   a = 0.965, b = 0.0965 mm,
      n = Y (Delta R / 1 mm)^-0.005,   Y = 0.0158 ln(R_j / 1 mm) + 1.152

  fit range R_j in [5, 50] mm.  An empirical fit with n != 1 holds in the units it was
  fitted in, and those are millimetres (b, R_j and Delta R are in mm): the force is
  F [N] = K_mm (delta / 1 mm)^n with L_b in mm and E* in N/mm^2, i.e. in SI
  F = K_SI delta^n with K_SI = (a Delta R + b) L_b E* 1000^(n-1) / Delta R.  So evaluated,
  the law is as compliant as Johnson's within a factor 0.8-1.6 over 100 N-10 kN for
  R_j 10-40 mm with clearances of 0.05-0.5 mm (at the R1 geometry 1.2x at 100 N, 1.00x at
  10 kN; tested), in line with the paper's finding that Johnson's law describes this
  contact; tighter clearances depart more (0.4x at R_j 10 mm, Delta R 0.01 mm).  Evaluating the same
  expression with delta in m and E* in Pa (what issue 14's ratios, 10x at 100 N and 4.5x
  at 10 kN against the linear law, correspond to) makes it 1000^(n-1) ~ 4.4 times
  softer.  The constants could not be checked here against the paper's text itself:
  treat them as "Pereira et al. 2011 as commonly quoted".
* ``"hertz_point"``: F = K delta^1.5, K = 4/3 E* sqrt(R_j R_b1 / Delta R) (internal
  Hertz contact of spheres of the journal and bore radii,
  :func:`~clearance_contact.materials.hertz_sphere_stiffness`), the law of planar
  revolute clearance studies (Flores, Ambrosio, Claro, Lankarani, Proc. IMechE K 220
  (2006) 21-34, eq. (2)).

Encoding for the compiled kernel: a code and ``RADIAL_LAW_PARAMETERS`` floats,
``RADIAL_POWER`` (K / L_b, n) or ``RADIAL_JOHNSON`` (pi E*, 4 Delta R); a new law adds a
code and a branch of :func:`encoded_line_density`, nothing in the geometry.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable

import numpy as np

from .compiled import jit
from .errors import ContactParameterError, require_in_range, require_positive
from .materials import Material, combined_modulus, cylinder_line_stiffness, hertz_sphere_stiffness

__all__ = [
    "RADIAL_POWER",
    "RADIAL_JOHNSON",
    "RADIAL_LAW_PARAMETERS",
    "RADIAL_LAWS",
    "RadialLaw",
    "radial_law",
    "encoded_line_density",
    "johnson_line_load",
]

RADIAL_POWER: int = 0
"""q = k delta^n; parameters (k = K / L_b in N/m^(n+1), n)."""
RADIAL_JOHNSON: int = 1
"""Johnson's conforming-cylinder law; parameters (pi E*, 4 Delta R)."""
RADIAL_LAW_PARAMETERS: int = 2
"""Floats after the code in the kernel parameters."""

_E2 = math.exp(-2.0)
_NEWTON_STEPS = 60  # <= 6 used except within ~1e-6 of the maximum, where h' -> 0 slows it

PEREIRA_A = 0.965
PEREIRA_B = 0.0965e-3  # m
PEREIRA_RADIUS_RANGE = (0.005, 0.050)  # m, fit range of Y(R)
MM_PER_M = 1.0e3  # the Pereira fit's length unit is the millimetre


@jit
def johnson_line_load(delta: float, pi_modulus: float, four_clearance: float) -> float:
    """Line load P (N/m) of Johnson's law at the approach delta > 0 (module docstring)."""
    big_d = delta / four_clearance
    p_scale = pi_modulus * four_clearance  # P = p_scale * s
    if big_d >= _E2:
        return p_scale * big_d  # F_max delta / delta_max: s_max = e^-2 at D = e^-2
    log_d = math.log(big_d)
    # h(u) = u + ln(-u - 1) - ln D: increasing, concave for u < -2; h(u_0) > 0, so the first
    # step lands left of the root and the next ones climb to it monotonically
    u = log_d - math.log(-log_d - 1.0)
    for _ in range(_NEWTON_STEPS):
        step = (u + math.log(-u - 1.0) - log_d) * (u + 1.0) / (u + 2.0)
        u -= step
        if abs(step) <= 1.0e-15 * -u:
            break
    return p_scale * math.exp(u)


@jit(exports=("f8(f8[::1], i8, f8)",))  # RadialLaw.line_density's call (clearance contact-laws)
def encoded_line_density(parameters, offset: int, delta: float) -> float:
    """q(delta) in N/m of the law encoded at ``parameters[offset:offset + 1 + RADIAL_LAW_PARAMETERS]``; 0 if delta <= 0."""
    if delta <= 0.0:
        return 0.0
    code = int(parameters[offset])
    if code == RADIAL_JOHNSON:
        return johnson_line_load(delta, parameters[offset + 1], parameters[offset + 2])
    n = parameters[offset + 2]
    if n == 1.0:
        return parameters[offset + 1] * delta
    if n == 1.5:  # Hertz: a square root is ~5x cheaper than a general power
        return parameters[offset + 1] * delta * math.sqrt(delta)
    return parameters[offset + 1] * delta**n


@dataclass(frozen=True)
class RadialLaw:
    """A radial law, ready for the kernel: ``name``, ``code``, ``parameters`` (module docstring)."""

    name: str
    code: int
    parameters: tuple[float, float]
    bearing_length: float
    stiffness: float | None = None
    exponent: float | None = None

    def encoding(self) -> np.ndarray:
        return np.array((self.code, *self.parameters), dtype=np.float64)

    def line_density(self, delta: float) -> float:
        """q(delta) in N/m (Python entry to the kernel's function)."""
        return float(encoded_line_density(self.encoding(), 0, float(delta)))

    def aligned_force(self, delta: float) -> float:
        """F(delta) = L_b q(delta): the force of an aligned journal pressed by delta (N)."""
        return self.bearing_length * self.line_density(delta)


def _power(name: str, stiffness: float, exponent: float, bearing_length: float) -> RadialLaw:
    return RadialLaw(name, RADIAL_POWER, (stiffness / bearing_length, exponent), bearing_length, stiffness, exponent)


def _no_override(name: str, stiffness: float | None, exponent: float | None) -> None:
    if stiffness is not None or exponent not in (None, 1.0):
        raise ContactParameterError(
            f"radial_law={name!r} sets its own stiffness and exponent: leave radial_stiffness "
            f"(got {stiffness!r}) and radial_exponent (got {exponent!r}) unset; they are for radial_law='linear'"
        )


def _linear(journal_radius, bore_radius, bearing_length, outer, inner, stiffness, exponent) -> RadialLaw:
    n = 1.0 if exponent is None else require_in_range("radial_exponent", exponent, 1.0, 1.5)
    if stiffness is None:
        if n != 1.0:
            raise ContactParameterError(
                f"radial_exponent={exponent!r} needs an explicit radial_stiffness: the default "
                "line stiffness pi/4 E* L_b (N/m) is valid for radial_exponent 1 only"
            )
        stiffness = cylinder_line_stiffness(bearing_length, outer, inner)
    return _power("linear", require_positive("radial_stiffness", stiffness), n, bearing_length)


def _hertz_point(journal_radius, bore_radius, bearing_length, outer, inner, stiffness, exponent) -> RadialLaw:
    _no_override("hertz_point", stiffness, exponent)
    k = hertz_sphere_stiffness(bore_radius, journal_radius, outer, inner, internal=True)
    return _power("hertz_point", k, 1.5, bearing_length)


def pereira_stiffness_exponent(journal_radius: float, radial_clearance: float, modulus: float, bearing_length: float):
    """(K, n) of Pereira et al. (2011), internal contact, with F = K delta^n in SI units (N, m).

    The fit's own units are N, mm and N/mm^2 (module docstring): with delta in m,
    K = (a Delta R + b) L_b E* / Delta R times MM_PER_M^(n-1), so that
    K delta^n equals the fit's force at the same penetration.
    """
    r = require_in_range("journal_radius (pereira fit range, m)", journal_radius, *PEREIRA_RADIUS_RANGE)
    y = 0.0158 * math.log(r * MM_PER_M) + 1.152
    n = y * (radial_clearance * MM_PER_M) ** -0.005
    k = (PEREIRA_A * radial_clearance + PEREIRA_B) * bearing_length * modulus / radial_clearance * MM_PER_M ** (n - 1.0)
    return k, n


def _pereira(journal_radius, bore_radius, bearing_length, outer, inner, stiffness, exponent) -> RadialLaw:
    _no_override("pereira", stiffness, exponent)
    k, n = pereira_stiffness_exponent(
        journal_radius, bore_radius - journal_radius, combined_modulus(outer, inner), bearing_length
    )
    return _power("pereira", k, n, bearing_length)


def _johnson(journal_radius, bore_radius, bearing_length, outer, inner, stiffness, exponent) -> RadialLaw:
    _no_override("johnson", stiffness, exponent)
    modulus = combined_modulus(outer, inner)
    return RadialLaw("johnson", RADIAL_JOHNSON, (math.pi * modulus, 4.0 * (bore_radius - journal_radius)), bearing_length)


RADIAL_LAWS: dict[str, Callable[..., RadialLaw]] = {
    "linear": _linear,
    "johnson": _johnson,
    "pereira": _pereira,
    "hertz_point": _hertz_point,
}
"""Registry name -> builder(journal_radius, bore_radius, bearing_length, outer, inner, stiffness, exponent)."""


def radial_law(
    name: str,
    journal_radius: float,
    bore_radius: float,
    bearing_length: float,
    outer: Material,
    inner: Material,
    stiffness: float | None = None,
    exponent: float | None = None,
) -> RadialLaw:
    """The radial law ``name`` (a key of :data:`RADIAL_LAWS`) for this geometry and these materials."""
    builder = RADIAL_LAWS.get(name) if isinstance(name, str) else None
    if builder is None:
        raise ContactParameterError(
            f"radial_law={name!r} is not known; valid: {', '.join(RADIAL_LAWS)}", key="radial_law", value=name
        )
    return builder(journal_radius, bore_radius, bearing_length, outer, inner, stiffness, exponent)
