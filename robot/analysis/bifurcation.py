"""Bifurcation diagrams: Poincare samples of one coordinate against a swept parameter.

For each value mu_j of the swept parameter, the (post-transient) Poincare
samples of one coordinate, x_j = {P_k(mu_j)_c}, are plotted above mu_j
(Guckenheimer & Holmes 1983, Sec. 1.5; Strogatz, *Nonlinear Dynamics and
Chaos*, 1994, Sec. 10.2 for the logistic map). A period-m response shows m
points, so the number of distinct samples tracks period doubling:

    n_distinct(mu) = number of clusters of {x_k} whose members differ by more than ``tolerance``

(single-linkage clustering along the sorted samples: two samples farther
apart than ``tolerance`` start a new cluster). Points are stored NaN-padded,
one row per parameter value, as :func:`robot.analysis.poincare.stroboscopic_section`
returns them, so a sweep's ``points`` variable is a diagram as it stands.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import numpy as np

from .errors import AnalysisError, require_array, require_positive


def distinct_points(samples, tolerance: float) -> int:
    """Number of clusters of the finite entries of ``samples`` (1-D) separated by more than ``tolerance``."""
    tolerance = require_positive("tolerance", tolerance)
    values = np.asarray(samples, dtype=float).ravel()
    values = np.sort(values[np.isfinite(values)])
    if values.size == 0:
        return 0
    return int(1 + np.count_nonzero(np.diff(values) > tolerance))


@dataclass(frozen=True)
class BifurcationDiagram:
    """``points[j]``: the Poincare samples (NaN-padded) at ``parameter[j]``."""

    parameter: np.ndarray
    points: np.ndarray
    parameter_label: str = "parameter"
    coordinate_label: str = "x"

    def __post_init__(self) -> None:
        parameter = require_array("parameter", self.parameter, 1)
        points = np.asarray(self.points, dtype=float)
        if points.ndim != 2 or points.shape[0] != len(parameter):
            raise AnalysisError(f"points must be (n_parameters={len(parameter)}, max_points), got shape {points.shape}")
        if np.any(np.isinf(points)):
            raise AnalysisError("points must be finite or NaN (padding); got an infinite value")
        object.__setattr__(self, "parameter", parameter)
        object.__setattr__(self, "points", points)

    @classmethod
    def from_samples(
        cls, parameter, samples: Sequence[np.ndarray], *, parameter_label: str = "parameter", coordinate_label: str = "x"
    ) -> "BifurcationDiagram":
        """Diagram from one 1-D array of samples per parameter value (ragged, padded here with NaN)."""
        rows = [np.asarray(s, dtype=float).ravel() for s in samples]
        width = max((len(r) for r in rows), default=0)
        points = np.full((len(rows), max(width, 1)), np.nan)
        for j, row in enumerate(rows):
            points[j, : len(row)] = row
        return cls(np.asarray(parameter, dtype=float), points, parameter_label, coordinate_label)

    def distinct_counts(self, tolerance: float) -> np.ndarray:
        """(n_parameters,) number of distinct samples per parameter value (:func:`distinct_points`)."""
        return np.array([distinct_points(row, tolerance) for row in self.points], dtype=int)

    def scatter_data(self) -> tuple[np.ndarray, np.ndarray]:
        """Flat ``(parameter, sample)`` pairs of the valid samples, for plotting."""
        mu = np.broadcast_to(self.parameter[:, None], self.points.shape)
        valid = np.isfinite(self.points)
        return mu[valid], self.points[valid]
