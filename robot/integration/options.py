"""Run configuration of the integration: solver choice and tolerances, failure limits.

Plain data (no Pinocchio, no solver import), so that scenes can be parsed and
validated without the heavy libraries (:mod:`robot.scene`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

#: ``SolverOptions.jacobian`` values
STRUCTURED, FINITE_DIFFERENCE = "structured", "finite-difference"
JACOBIAN_CHOICES = (STRUCTURED, FINITE_DIFFERENCE)


@dataclass(frozen=True)
class SolverOptions:
    """Integrator choice and tolerances (``first_step`` is the step of fixed-step methods).

    ``hidden_contacts``: scan each step's dense output for contacts that start and
    end inside the step (the guard against steps that jump over a whole impact);
    on by default, off only to study what it guards against
    (``scripts/work_precision.py``). ``output_step``: also record the state at every
    multiple of it, from the steps' dense output (record kind 4), so that runs can
    be compared at common times. ``jacobian``: the iteration matrix of the implicit
    methods (``robot.integration.solvers.JACOBIAN_METHODS``): ``"structured"`` (default;
    :mod:`robot.dynamics.state_jacobian`, where the compiled right-hand side applies) or
    ``"finite-difference"`` (the solver differences the right-hand side itself).
    """

    method: str = "RK45"
    rtol: float = 1e-7
    atol: float = 1e-9
    max_step: float = 1e-3
    first_step: float | None = None
    hidden_contacts: bool = True
    output_step: float | None = None
    jacobian: str = STRUCTURED

    def __post_init__(self) -> None:
        if self.jacobian not in JACOBIAN_CHOICES:
            raise ValueError(f"jacobian={self.jacobian!r} is not on offer; choose one of {', '.join(JACOBIAN_CHOICES)}")


@dataclass(frozen=True)
class FailureLimits:
    """When a run is declared failed rather than returning garbage.

    ``penetration_ratio``: a penetration above this fraction of the joint's
    clearance is unphysical for hard metal contact (the force would crush the
    parts); ``max_residual``: constraint drift (m or rad); ``min_step``: step-size
    collapse; ``max_wall_time``: seconds (``inf``: none); ``max_steps``: accepted
    steps, counting those still needed to reach the end at the pace of the last
    ``STALL_WINDOW`` steps, in two windows in a row (a run creeping forward at 1e-10 s a step has not
    collapsed below ``min_step`` but will never finish).
    """

    penetration_ratio: float = 0.5
    max_residual: float = 1e-4
    min_step: float = 1e-13
    max_wall_time: float = math.inf
    max_steps: float = 1e8


#: accepted steps over which the pace of a run is measured for ``FailureLimits.max_steps``
STALL_WINDOW = 10_000
