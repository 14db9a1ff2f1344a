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
form is one call of :func:`register_dissipation_model`; a model of another form adds a code
and a branch there, and nothing in the joints' geometry.

Registry: :func:`register_dissipation_model` ``(name, chi)`` adds a model (from any module:
``dissipation = "NAME"`` in a scene then selects it) and refuses a name already taken, so
that no module can replace a shipped model.  :data:`DISSIPATION_MODELS` stays readable as
before (name -> chi: ``in``, ``[name]``, iteration in registration order) but is read-only:
writing into it raises :class:`~clearance_contact.errors.ContactParameterError` pointing
to :func:`register_dissipation_model`.  A model's value is checked wherever it is used
(:func:`dissipation_factor`, so when a joint is built): chi(c_e) must be a finite real
number >= 0, else ContactParameterError naming the model, c_e and the value.
"""

from __future__ import annotations

import inspect
import math
from collections.abc import Mapping
from typing import Callable, Iterator

import numpy as np

from .compiled import jit
from .errors import ContactParameterError, real_number, require_in_range, require_unregistered
from .normal_force import hysteresis_damping_factor, hysteresis_factor

__all__ = [
    "DISSIPATION_HYSTERESIS",
    "DISSIPATION_PARAMETERS",
    "DISSIPATION_MODELS",
    "DEFAULT_DISSIPATION",
    "register_dissipation_model",
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


class _ReadOnlyModels(Mapping):
    """A read-only view of the registered models (name -> chi(c_e)); writes say how to register."""

    __slots__ = ("_models",)

    def __init__(self, models: dict[str, Callable[[float], float]]) -> None:
        self._models = models

    def __getitem__(self, name: str) -> Callable[[float], float]:
        return self._models[name]

    def __iter__(self) -> Iterator[str]:
        return iter(self._models)

    def __len__(self) -> int:
        return len(self._models)

    def __repr__(self) -> str:
        return f"DISSIPATION_MODELS({', '.join(self._models)})"

    def __setitem__(self, name, chi) -> None:
        raise ContactParameterError(
            f"DISSIPATION_MODELS is read-only (writing {name!r} into it): register a model with "
            "clearance_contact.register_dissipation_model(name, chi), which refuses a name already taken",
            key="dissipation", value=name,
        )  # fmt: skip

    def __delitem__(self, name) -> None:
        self.__setitem__(name, None)


_MODELS: dict[str, Callable[[float], float]] = {}

DISSIPATION_MODELS: Mapping[str, Callable[[float], float]] = _ReadOnlyModels(_MODELS)
"""Registry: name -> chi(c_e) (module docstring's table); read-only, add with :func:`register_dissipation_model`."""


def register_dissipation_model(name: str, chi: Callable[[float], float]) -> Callable[[float], float]:
    """Register the hysteresis damping factor ``chi(c_e)`` as model ``name``; return ``chi``.

    ``name``: an identifier not registered yet (ContactParameterError naming the model
    that holds it otherwise: shipped models cannot be replaced); ``chi``: a callable
    taking c_e in (0, 1] as its one positional argument and returning a finite real
    number >= 0 (checked whenever a joint is built with the model).
    """
    if not isinstance(name, str) or not name.isidentifier():
        raise ContactParameterError(f"dissipation model name {name!r} must be a non-empty identifier", key="dissipation", value=name)
    require_unregistered("dissipation model", name, _MODELS.get(name), chi, _MODELS, key="dissipation")
    _require_one_argument(name, chi)
    _MODELS[name] = chi
    return chi


def _require_one_argument(name: str, chi) -> None:
    """ContactParameterError unless ``chi`` is callable as ``chi(c_e)``."""
    if not callable(chi):
        raise ContactParameterError(
            f"dissipation model {name!r}: chi={chi!r} must be a callable chi(c_e) -> float", key="dissipation", value=name
        )
    try:
        inspect.signature(getattr(chi, "py_func", chi)).bind(0.5)  # a compiled kernel: its Python source
    except TypeError as exc:
        raise ContactParameterError(
            f"dissipation model {name!r}: {chi!r} cannot be called as chi(c_e) ({exc}); it must take c_e as its one argument",
            key="dissipation", value=name,
        ) from None  # fmt: skip
    except ValueError:  # no signature to inspect (some builtins): the call itself is checked on use
        pass


for _name, _chi in (
    ("lankarani_nikravesh", hysteresis_factor),
    ("hunt_crossley", _hunt_crossley),
    ("gonthier", _gonthier),
    ("flores", _flores),
    ("hu_guo", _hu_guo),
):
    register_dissipation_model(_name, _chi)
del _name, _chi


def dissipation_factor(name: str, restitution: float) -> float:
    """chi of the model ``name`` at the coefficient of restitution c_e in (0, 1].

    ContactParameterError if ``name`` is not registered, c_e is outside (0, 1], or the
    model fails: it raises, or returns anything but a finite real number >= 0 (the
    message names the model, c_e and the value).
    """
    model = _MODELS.get(name) if isinstance(name, str) else None
    if model is None:
        raise ContactParameterError(
            f"dissipation={name!r} is not known; valid: {', '.join(_MODELS)}", key="dissipation", value=name
        )
    ce = require_in_range("restitution", restitution, 0.0, 1.0, low_inclusive=False)
    try:  # (its signature was checked when it was registered: _MODELS is written only there)
        chi = model(ce)
    except Exception as exc:  # noqa: BLE001 - the user's model: its failure is reported as bad input
        raise ContactParameterError(
            f"dissipation model {name!r} raised {type(exc).__name__} at c_e={ce!r}: {exc}", key="dissipation", value=name
        ) from exc
    value = real_number(chi)
    if value is None or not (math.isfinite(value) and value >= 0.0):
        raise ContactParameterError(
            f"dissipation model {name!r} gives chi={chi!r} at c_e={ce!r}: chi must be a finite real number in the valid "
            "range [0, inf) (a negative chi adds energy at each impact); fix the model's formula",
            key="dissipation", value=name,
        )  # fmt: skip
    return value


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
