"""Orbits of clearance joints: the inner element's centre in the outer element's frame.

For a clearance joint with outer element (bearing, socket) at world position
p_o and rotation R_o (columns: the outer frame's axes in world coordinates) and
inner element (journal, ball) centre p_i, the eccentricity vector in the outer
frame is (Flores & Ambrosio, "Revolute joints with clearance in multibody
systems", Comput. Struct. 82 (2004) 1359-1369, Sec. 2, their e = r_journal - r_bearing written
here in the bearing frame)

    e = R_o^T (p_i - p_o).

It is invariant under any rigid motion of the whole mechanism (p -> G p + d,
R_o -> G R_o for both bodies, G in SO(3)), which is why orbits are drawn in the
outer frame. The radial eccentricity about the bearing axis a (a unit vector of
the outer frame; revolute joints) is |e - (e . a) a|; for a spherical joint the
whole |e| (``axis=None``). Normalised by the radial clearance c, the
eccentricity ratio epsilon = |e_r| / c is 1 when the elements touch (rigid
contact; > 1 while penetrating).

Note: the simulator's result holds this vector as ``J_centre_in_outer`` ((n, 3),
every joint type; ``robot/io/results.py``), not as ``J_eccentricity``, the
contact law's per contact row ((n, 2, 3) for revolute and translational joints);
this module computes it from any body poses (e.g. of another engine, or measured).
"""

from __future__ import annotations

import numpy as np

from .errors import AnalysisError, require_array, require_positive
from .registry import Field, register


def relative_position(outer_rotation, outer_position, inner_position) -> np.ndarray:
    """(n, 3) e = R_o^T (p_i - p_o) per record; rotations (n, 3, 3), positions (n, 3)."""
    rotation = require_array("outer_rotation", outer_rotation, 3)
    n = rotation.shape[0]
    outer = require_array("outer_position", outer_position, 2, length=n)
    inner = require_array("inner_position", inner_position, 2, length=n)
    if rotation.shape[1:] != (3, 3) or outer.shape[1] != 3 or inner.shape[1] != 3:
        raise AnalysisError(
            f"outer_rotation must be (n, 3, 3) and positions (n, 3); got {rotation.shape}, {outer.shape}, {inner.shape}"
        )
    orthogonality = np.max(np.abs(np.einsum("nji,njk->nik", rotation, rotation) - np.eye(3)))
    if orthogonality > 1e-6:
        raise AnalysisError(f"outer_rotation must hold rotation matrices; max |R^T R - I| = {orthogonality:.3g} > 1e-6")
    return np.einsum("nji,nj->ni", rotation, inner - outer)


def radial_component(eccentricity: np.ndarray, axis) -> np.ndarray:
    """(n,) |e - (e . a) a| for the unit axis ``a`` (normalised here), or |e| for ``axis=None``."""
    if axis is None:
        return np.linalg.norm(eccentricity, axis=1)
    a = require_array("axis", axis, 1)
    norm = np.linalg.norm(a)
    if a.shape != (3,) or norm == 0.0:
        raise AnalysisError(f"axis must be a non-zero 3-vector of the outer frame, got {a.tolist()}")
    a = a / norm
    return np.linalg.norm(eccentricity - np.outer(eccentricity @ a, a), axis=1)


@register(
    "orbit",
    inputs=(
        Field("outer_rotation", ("time", "row", "column"), "1", "rotation of the outer element (bearing/socket) frame"),
        Field("outer_position", ("time", "xyz"), "m", "world position of the outer element's centre"),
        Field("inner_position", ("time", "xyz"), "m", "world position of the inner element's centre"),
    ),
    outputs=(
        Field("eccentricity", ("time", "xyz"), "m", "inner centre in the outer frame, e = R_o^T (p_i - p_o)"),
        Field("eccentricity_ratio", ("time",), "1", "radial eccentricity / clearance"),
        Field("max_eccentricity_ratio", (), "1", "max over the records (> 1: penetration)"),
        Field("mean_eccentricity_ratio", (), "1", "mean over the records (unweighted)"),
    ),
    sizes=lambda **_: {"xyz": 3},
    source="Flores & Ambrosio, Comput. Struct. 82 (2004) 1359-1369",
)
def orbit(
    outer_rotation, outer_position, inner_position, *, clearance: float, axis=(0.0, 0.0, 1.0)
) -> dict[str, np.ndarray]:
    """Eccentricity vector and ratio of one clearance joint (``axis=None`` for a spherical joint)."""
    clearance = require_positive("clearance", clearance)
    eccentricity = relative_position(outer_rotation, outer_position, inner_position)
    ratio = radial_component(eccentricity, axis) / clearance
    return {
        "eccentricity": eccentricity,
        "eccentricity_ratio": ratio,
        "max_eccentricity_ratio": np.float64(ratio.max()),
        "mean_eccentricity_ratio": np.float64(ratio.mean()),
    }
