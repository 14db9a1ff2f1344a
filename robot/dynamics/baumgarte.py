"""Baumgarte stabilisation gains (plain data: no Pinocchio, scenes import it)."""

from __future__ import annotations

import math
from dataclasses import dataclass


@dataclass(frozen=True)
class Baumgarte:
    """Baumgarte gains: ``Phidd + 2 alpha Phid + beta^2 Phi = 0`` (paper ref. 35)."""

    alpha: float = 5.0
    beta: float = 5.0

    def __post_init__(self) -> None:
        for name in ("alpha", "beta"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value >= 0.0):
                raise ValueError(f"Baumgarte {name}={value!r} must be a finite number >= 0")
