"""Normal dissipation models: the hysteresis damping factor chi(c_e) of each published law.

All of them damp the elastic force F_el = K delta^n (or the distributed pressure, point by
point) in the Hunt-Crossley form::

    F = max(F_el [1 + chi(c_e) delta_dot / max(delta_dot_0, ONSET_RATE_FLOOR)], 0)

(:func:`~clearance_contact.normal_force.hysteresis_damping_factor`) and differ by chi:

==========================  =========================  ===============================================
name                        chi(c_e)                   source
==========================  =========================  ===============================================
``lankarani_nikravesh``     3 (1 - c_e^2) / 4          Lankarani & Nikravesh, J. Mech. Des. 112 (1990)
                                                       369-376 (energy loss of a Hertz impact, c_e ~ 1)
``hunt_crossley``           3 (1 - c_e) / 2            Hunt & Crossley, J. Appl. Mech. 42 (1975) 440-445
                                                       (lambda = 3 (1 - c_e) K / (2 v_0))
``gonthier``                (1 - c_e^2) / c_e          Gonthier, McPhee, Lange, Piedboeuf, Multibody
                                                       Syst. Dyn. 11 (2004) 209-233
``flores``                  8 (1 - c_e) / (5 c_e)      Flores, Machado, Silva, Martins, Multibody Syst.
                                                       Dyn. 25 (2011) 357-375
``hu_guo``                  3 (1 - c_e) / (2 c_e)      Hu & Guo, Multibody Syst. Dyn. 35 (2015) 131-151
==========================  =========================  ===============================================

The coefficient of restitution the model actually produces does not depend on K, n or the
mass: integrating m v dv / (1 + a v) = -K delta^n d delta over an impact (a = chi / v_0)
from v_0 to -v_out at delta = 0 gives (Marhefka & Orin, IEEE Trans. SMC A 29 (1999)
566-572, who give the same relation for the Hunt-Crossley law)::

    chi - ln(1 + chi) = -chi e - ln(1 - chi e),     e = v_out / v_0

solved by :func:`rebound_ratio`.  ``docs/contact-laws.md`` tabulates it for each model
against the c_e asked for (measured by integrating impacts: ``clearance contact-laws``).

Encoding for the compiled kernels (like the friction laws): a code and
``DISSIPATION_PARAMETERS`` floats, dispatched by :func:`encoded_damping_factor`;
``DISSIPATION_HYSTERESIS`` (chi, 0) covers all the models above, so a new model of this
form is one entry of :data:`DISSIPATION_MODELS`; a model of another form adds a code and
a branch there, and nothing in the joints' geometry.
"""

from __future__ import annotations

import math
from typing import Callable

import numpy as np

from .compiled import jit
from .errors import ContactParameterError, require_in_range
from .normal_force import hysteresis_damping_factor, hysteresis_factor

__all__ = [
    "DISSIPATION_HYSTERESIS",
    "DISSIPATION_PARAMETERS",
    "DISSIPATION_MODELS",
    "DEFAULT_DISSIPATION",
    "dissipation_factor",
    "dissipation_encoding",
    "encoded_damping_factor",
    "rebound_ratio",
]

DISSIPATION_HYSTERESIS: int = 1
"""F = F_el [1 + chi delta_dot / max(delta_dot_0, floor)]; parameters (chi, 0)."""
DISSIPATION_PARAMETERS: int = 2

DEFAULT_DISSIPATION = "lankarani_nikravesh"


def _hunt_crossley(ce: float) -> float:
    return 1.5 * (1.0 - ce)


def _gonthier(ce: float) -> float:
    return (1.0 - ce * ce) / ce


def _flores(ce: float) -> float:
    return 8.0 * (1.0 - ce) / (5.0 * ce)


def _hu_guo(ce: float) -> float:
    return 1.5 * (1.0 - ce) / ce


DISSIPATION_MODELS: dict[str, Callable[[float], float]] = {
    "lankarani_nikravesh": hysteresis_factor,
    "hunt_crossley": _hunt_crossley,
    "gonthier": _gonthier,
    "flores": _flores,
    "hu_guo": _hu_guo,
}
"""Registry: name -> chi(c_e) (module docstring's table)."""


def dissipation_factor(name: str, restitution: float) -> float:
    """chi of the model ``name`` at the coefficient of restitution c_e in (0, 1]."""
    model = DISSIPATION_MODELS.get(name) if isinstance(name, str) else None
    if model is None:
        raise ContactParameterError(
            f"dissipation={name!r} is not known; valid: {', '.join(DISSIPATION_MODELS)}", key="dissipation", value=name
        )
    ce = require_in_range("restitution", restitution, 0.0, 1.0, low_inclusive=False)
    return float(model(ce))


def dissipation_encoding(name: str, restitution: float) -> np.ndarray:
    """[code, DISSIPATION_PARAMETERS floats] of the model for the kernels' parameters."""
    return np.array((DISSIPATION_HYSTERESIS, dissipation_factor(name, restitution), 0.0), dtype=np.float64)


@jit
def encoded_damping_factor(parameters, offset: int, rate: float, onset_rate: float) -> float:
    """The factor multiplying the elastic force (not clamped) of the model at ``parameters[offset:]``."""
    if int(parameters[offset]) == DISSIPATION_HYSTERESIS:
        return hysteresis_damping_factor(rate, onset_rate, parameters[offset + 1])
    return 1.0


def rebound_ratio(chi: float) -> float:
    """Exact coefficient of restitution e of an impact under F = K delta^n (1 + chi v / v_0).

    Root in (0, 1/chi) of chi - ln(1 + chi) = -chi e - ln(1 - chi e) (module docstring),
    by bisection on y = chi e (the right side, y^2/2 + y^3/3 + ..., increases from 0 to
    inf on [0, 1)); 1 for chi = 0.
    """
    chi = float(chi)
    if chi < 0.0 or not math.isfinite(chi):
        raise ContactParameterError(f"chi={chi!r} must be finite and >= 0")
    if chi == 0.0:
        return 1.0
    target = chi - math.log1p(chi)
    lo, hi = 0.0, 1.0
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        if -mid - math.log1p(-mid) < target:
            lo = mid
        else:
            hi = mid
    return 0.5 * (lo + hi) / chi
