"""What the step loop measures after every accepted step: the contact probe (no Pinocchio here, so the
step loop and the independent engines of ``robot.validation`` share it)."""

from __future__ import annotations

from typing import NamedTuple

import numpy as np


class Probe(NamedTuple):
    """Per contact candidate at one state: penetration (m), its rate (m/s), normal force (N); and max |Phi|."""

    penetration: np.ndarray
    penetration_rate: np.ndarray
    residual: float  # constraint residual checked against FailureLimits.max_residual (NaN: not checked)
    normal_force: np.ndarray
