"""Contact events inside a step: which candidates need attention, and when their contact begins.

A step ``[t_old, t_new]`` is scanned from the penetrations ``delta_k`` and their
rates at its two ends (:func:`step_flags`, one compiled call for all
candidates). An **onset** is ``delta_k`` crossing zero upward; its time is the
root of ``delta_k(t)`` on the step's dense output (Brent's method,
:func:`first_contact_time`). An impact can also start and end inside one step
(out of contact at both ends, approaching at the start and receding at the
end): the dense output is then sampled for a positive penetration
(:func:`hidden_contact`), so no step jumps over a contact.
"""

from __future__ import annotations

import math
from typing import Callable

import numpy as np

from clearance_contact.compiled import jit

from robot.integration.brent import RTOL, brentq

# what an accepted step needs beyond the routine checks (bit flags of step_flags)
ONSET, HIDDEN, OVER_BOUND, PEAK = 1, 2, 4, 8
#: samples of the dense output per step in the search for a hidden contact
HIDDEN_SAMPLES = 8


@jit(exports=("b1(f8[::1])",))
def all_finite(values) -> bool:
    for x in values:
        if not math.isfinite(x):
            return False
    return True


@jit(exports=("i8(f8[::1], f8[::1], f8[::1], f8[::1], f8[::1])",))
def step_flags(pen_old, rate_old, pen_new, rate_new, bounds) -> int:
    """Bit flags over the contact candidates, from the step's end points.

    ``ONSET``: penetration crossed zero upward; ``HIDDEN``: approaching then
    receding while out of contact at both ends (an impact may hide inside);
    ``OVER_BOUND``: penetration beyond its physical bound; ``PEAK``: penetration
    maximum passed while in contact. Most steps have none: one compiled call
    instead of a dozen small numpy operations.
    """
    flags = 0
    for k in range(pen_new.shape[0]):
        if pen_old[k] <= 0.0 and pen_new[k] > 0.0:
            flags |= ONSET
        if pen_old[k] <= 0.0 and pen_new[k] <= 0.0 and rate_old[k] > 0.0 and rate_new[k] < 0.0:
            flags |= HIDDEN
        if pen_new[k] > bounds[k]:
            flags |= OVER_BOUND
        if pen_new[k] > 0.0 and rate_old[k] > 0.0 and rate_new[k] <= 0.0:
            flags |= PEAK
    return flags


def first_contact_time(function: Callable[[float], float], a: float, b: float) -> float:
    """Time in [a, b] where ``function`` (a penetration) crosses zero upward (Brent's method)."""
    fa, fb = function(a), function(b)
    if fa > 0:
        return a
    if fb <= 0:
        return b
    return brentq(function, a, b, xtol=1e-15, rtol=RTOL, maxiter=200)


def hidden_contact(penetration: Callable[[float], float], t_old: float, t_new: float, samples: int = HIDDEN_SAMPLES) -> float | None:
    """First time a contact that starts and ends inside the step becomes active, if any (``penetration(t)`` on the dense output)."""
    previous = t_old
    for tt in np.linspace(t_old, t_new, samples + 2)[1:-1]:
        if penetration(tt) > 0:
            return first_contact_time(penetration, previous, tt)
        previous = tt
    return None
