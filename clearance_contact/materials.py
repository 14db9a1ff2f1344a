"""Elastic materials and Hertz-type contact stiffnesses.

A :class:`Material` is the pair (Young's modulus E, Poisson ratio nu).  Two bodies
in contact enter Hertz theory only through their compliances

    s_k = (1 - nu_k^2) / E_k          (MODEL-NOTES 4; Lankarani & Nikravesh 1990, sigma_k)

or, equivalently, through the combined (effective) modulus

    E* = 1 / (s_i + s_j)              (Johnson, Contact Mechanics, 1985, Sec. 4.2).

Stiffnesses (force law F = K delta^n, SI units):

* point contact of spheres (Hertz; Johnson 1985 Sec. 4.2; seed paper eq. (11)),
  n = 3/2, K in N/m^1.5::

      K = 4/3 E* sqrt(R*),   R* = R_i R_j / (R_i - R_j)   internal (ball in socket)
                             R* = R_i R_j / (R_i + R_j)   external

  which is the MODEL-NOTES 4 form K = 4 / (3 (s_i + s_j)) sqrt(R_i R_j / (R_i -/+ R_j)).
* line contact of parallel cylinders of contact length L (radial contact of a
  revolute joint with parallel axes; seed paper eqs. (12)-(13)), n = 1, K in N/m::

      K = pi/4 E* L

  From the 2-D Hertz solution (Johnson 1985 Sec. 4.2), a line load P = F/L gives the
  half-width a^2 = 4 P R*/(pi E*), so F = pi/4 E* L (a^2 / R*).  Taking as
  approach delta = a^2 / R*, the same relation as in 3-D Hertz point contact, gives
  the linear law above.  The 2-D approach is not unique (it depends on where the
  displacement is measured, Johnson 1985 Sec. 5.6); this linear form is a
  modelling choice of this library, independent of the radii, documented as such.
* plane contact of a flat annular face (axial contact, flange against bearing end
  face, parallel faces), n = 1, K in N/m: rigid flat circular punch of radius a on an
  elastic half-space (Boussinesq; Johnson 1985 Sec. 3.8; Sneddon 1965)::

      K = 2 E* a

  For an annulus a_1 < r < a_2 the full disc of radius a_2 is an upper bound of the
  stiffness (the annular punch is slightly softer); pass a_2.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from .errors import ContactParameterError, require_in_range, require_positive

__all__ = [
    "Material",
    "STEEL",
    "combined_modulus",
    "hertz_sphere_stiffness",
    "cylinder_line_stiffness",
    "flat_punch_stiffness",
]


@dataclass(frozen=True, slots=True)
class Material:
    """Linear elastic isotropic material.

    Parameters
    ----------
    youngs_modulus:
        E in Pa, valid range (0, inf).
    poisson_ratio:
        nu, valid range (-1, 0.5) (thermodynamic bounds for isotropic solids;
        0.5 itself, incompressible, is excluded).
    """

    youngs_modulus: float
    poisson_ratio: float

    def __post_init__(self) -> None:
        object.__setattr__(self, "youngs_modulus", require_positive("youngs_modulus", self.youngs_modulus))
        object.__setattr__(
            self,
            "poisson_ratio",
            require_in_range("poisson_ratio", self.poisson_ratio, -1.0, 0.5, low_inclusive=False, high_inclusive=False),
        )

    @property
    def compliance(self) -> float:
        """Hertz compliance s = (1 - nu^2) / E in 1/Pa."""
        return (1.0 - self.poisson_ratio**2) / self.youngs_modulus


STEEL = Material(youngs_modulus=200e9, poisson_ratio=0.3)
"""Steel as in MODEL-NOTES 2 (E = 200 GPa, nu = 0.3)."""


def _require_material(name: str, value: object) -> Material:
    if not isinstance(value, Material):
        raise ContactParameterError(f"{name}={value!r} must be a clearance_contact.Material")
    return value


def combined_modulus(first: Material, second: Material) -> float:
    """Effective modulus E* = 1 / ((1 - nu_1^2)/E_1 + (1 - nu_2^2)/E_2) in Pa."""
    return 1.0 / (_require_material("first", first).compliance + _require_material("second", second).compliance)


def hertz_sphere_stiffness(
    outer_radius: float,
    inner_radius: float,
    outer: Material,
    inner: Material,
    internal: bool = True,
) -> float:
    """Hertz point-contact stiffness K (N/m^1.5) of two spheres, F = K delta^1.5.

    ``K = 4 / (3 (s_i + s_j)) * sqrt(R_i R_j / (R_i - R_j))`` for internal contact
    (ball of radius ``inner_radius`` = R_j inside a spherical socket of radius
    ``outer_radius`` = R_i), ``R_i + R_j`` in the denominator for external contact
    (MODEL-NOTES 4; Lankarani & Nikravesh 1990; Johnson 1985 Sec. 4.2).

    For internal contact ``outer_radius`` must exceed ``inner_radius``; as the
    clearance tends to zero the conformity makes K tend to infinity.
    """
    r_i = require_positive("outer_radius", outer_radius)
    r_j = require_positive("inner_radius", inner_radius)
    if internal:
        if not r_i > r_j:
            raise ContactParameterError(
                f"outer_radius={outer_radius!r} must be larger than inner_radius={inner_radius!r} "
                "for internal contact (valid range (inner_radius, inf))"
            )
        r_eff = r_i * r_j / (r_i - r_j)
    else:
        r_eff = r_i * r_j / (r_i + r_j)
    return 4.0 / 3.0 * combined_modulus(outer, inner) * math.sqrt(r_eff)


def cylinder_line_stiffness(length: float, outer: Material, inner: Material) -> float:
    """Linear line-contact stiffness K = pi/4 E* L (N/m) of parallel cylinders.

    See the module docstring for the derivation from 2-D Hertz theory and its
    status (a modelling choice: the 2-D approach is not uniquely defined).
    ``length`` is the contact length L in m, valid range (0, inf).
    """
    l_c = require_positive("length", length)
    return 0.25 * math.pi * combined_modulus(outer, inner) * l_c


def flat_punch_stiffness(radius: float, outer: Material, inner: Material) -> float:
    """Stiffness K = 2 E* a (N/m) of a rigid flat circular punch of radius a.

    Boussinesq / Sneddon solution (Johnson 1985 Sec. 3.8), used for plane (axial)
    contact of parallel annular faces with a = the outer radius of the annulus (an
    upper bound for the annulus).  ``radius`` valid range (0, inf).
    """
    a = require_positive("radius", radius)
    return 2.0 * combined_modulus(outer, inner) * a


def require_material(name: str, value) -> Material:
    """``value`` if it is a :class:`Material`, else ContactParameterError naming ``name``."""
    if not isinstance(value, Material):
        raise ContactParameterError(f"{name}={value!r} must be a clearance_contact.Material")
    return value


def sphere_plane_stiffness(radius: float, plane: Material, sphere: Material) -> float:
    """Hertz point-contact stiffness K = 4/3 E* sqrt(R) (N/m^1.5) of a sphere of radius R on a flat face.

    The external sphere-sphere stiffness with the second radius infinite (R* = R;
    Johnson 1985 Sec. 4.2): e.g. a rounded corner of radius R against a plane.
    ``radius`` valid range (0, inf).
    """
    r = require_positive("radius", radius)
    return 4.0 / 3.0 * combined_modulus(plane, sphere) * math.sqrt(r)
