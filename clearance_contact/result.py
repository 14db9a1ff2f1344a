"""Result of one evaluation of a clearance joint: :class:`JointContact`."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["JointContact", "KIND_NONE", "KIND_POINT", "KIND_LINE", "KIND_PLANE"]

KIND_NONE: int = 0
"""``kind`` code: no contact."""
KIND_POINT: int = 1
"""``kind`` code: point contact."""
KIND_LINE: int = 2
"""``kind`` code: line contact (radial, parallel axes)."""
KIND_PLANE: int = 3
"""``kind`` code: plane contact (axial, parallel faces)."""


@dataclass(slots=True)
class JointContact:
    """Contact state and wrenches of one clearance joint (k candidates), world axes, SI.

    Attributes
    ----------
    penetration : (k,)
        Penetration depth (m) of each candidate; > 0 means contact.
    penetration_rate : (k,)
        d(penetration)/dt (m/s); > 0 while approaching / compressing.
    normal : (k, 3)
        World unit vector from the inner element outward toward the outer element's
        wall.  Normal force on the inner element: ``-normal_force * normal``; on the
        outer element: ``+normal_force * normal``.
    point_outer, point_inner : (k, 3)
        Candidate contact points on the outer and inner element surfaces (world).
    normal_force : (k,)
        Normal force magnitude (N), >= 0; 0 out of contact.
    friction_force : (k, 3)
        Friction force on the inner element (N), opposed to the inner element's slip
        relative to the outer one; the outer element gets the opposite.
    kind : (k,) int
        0 no contact, 1 point, 2 line, 3 plane (``KIND_*`` constants).
    eccentricity : (r, 3)
        Spherical joint (r = 1): ball centre minus socket centre in the socket frame.
        Revolute joint (r = 2): centre of the bearing rings (top, bottom) relative to
        the journal axis origin, in the journal frame.
    wrench_outer, wrench_inner : (6,)
        [force, moment about the element's frame origin] on the outer / inner element
        (world axes, N and N m).  They cancel about any common point.
    """

    penetration: np.ndarray
    penetration_rate: np.ndarray
    normal: np.ndarray
    point_outer: np.ndarray
    point_inner: np.ndarray
    normal_force: np.ndarray
    friction_force: np.ndarray
    kind: np.ndarray
    eccentricity: np.ndarray
    wrench_outer: np.ndarray
    wrench_inner: np.ndarray

    @classmethod
    def from_output(cls, law, out: np.ndarray) -> "JointContact":
        """Views of a law kernel's flat output ``out``, laid out by the offsets on ``law``.

        ``law`` gives ``N_CANDIDATES`` (k), ``N_ECCENTRICITY`` (r) and the offsets
        ``PENETRATION``, ``PENETRATION_RATE``, ``NORMAL_FORCE``, ``NORMAL`` (then
        point_outer, point_inner, friction_force and eccentricity, 3 floats each per
        row), ``WRENCH_OUTER``, ``WRENCH_INNER``, ``KIND`` (k kinds as floats).
        """
        k, r = law.N_CANDIDATES, law.N_ECCENTRICITY
        vectors = out[law.NORMAL : law.NORMAL + 3 * (4 * k + r)].reshape(-1, 3)
        return cls(
            out[law.PENETRATION : law.PENETRATION + k],
            out[law.PENETRATION_RATE : law.PENETRATION_RATE + k],
            vectors[0:k],
            vectors[k : 2 * k],
            vectors[2 * k : 3 * k],
            out[law.NORMAL_FORCE : law.NORMAL_FORCE + k],
            vectors[3 * k : 4 * k],
            out[law.KIND : law.KIND + k].astype(np.int64),
            vectors[4 * k : 4 * k + r],
            out[law.WRENCH_OUTER : law.WRENCH_OUTER + 6],
            out[law.WRENCH_INNER : law.WRENCH_INNER + 6],
        )

    @property
    def in_contact(self) -> np.ndarray:
        """(k,) bool: penetration > 0."""
        return self.penetration > 0.0
