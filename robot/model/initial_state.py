"""Consistent initial positions and velocities from the kinematic analysis.

The free bodies of clearance joints start **centred**: the ball centre on the
socket centre, the journal axis on the bearing axis with the journal midpoint on
the bearing midpoint, moving with the velocities the ideal joint would give
them. An optional misalignment rotates the bearing about its local x axis (for
the R1 joint of the 4-UPS/RPS: the limb's x6 axis) before assembly: the rest of
the mechanism assembles around it (seed paper, second case: "the bearing
rotated 0.035 deg clockwise around coordinate axis x6").

This is done by imposing, for the initial analysis only, the equations of the
ideal joints the clearance joints replace (``constraint_set(...,
centre_clearance=True)``): with them the mechanism is the ideal one (mobility 0
when driven), so positions and velocities are unique near the guess.
"""

from __future__ import annotations

import numpy as np

from robot.model import constraints as C
from robot.model.kinematics import assemble, velocity_analysis
from robot.model.mechanism import Mechanism


def initial_state(
    mechanism: Mechanism,
    q_guess: np.ndarray,
    drive: tuple[np.ndarray, np.ndarray, np.ndarray],
    misalignment: dict[str, np.ndarray] | None = None,
) -> np.ndarray:
    """``y0 = [q0, v0]`` consistent with the closures and the drive at the initial time."""
    s, sd, _ = drive
    constraints = C.constraint_set(mechanism, driven=True, centre_clearance=True, misalignment=misalignment)
    q0 = assemble(constraints, q_guess, s).q
    v0 = velocity_analysis(constraints, q0, sd)
    return np.concatenate([q0, v0])
