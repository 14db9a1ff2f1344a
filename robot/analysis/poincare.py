"""Poincare sections of a recorded trajectory: stroboscopic samples and hyperplane crossings.

Stroboscopic section (periodically driven systems; Guckenheimer & Holmes,
*Nonlinear Oscillations, Dynamical Systems, and Bifurcations of Vector Fields*,
1983, Sec. 1.5; Moon, *Chaotic Vibrations*, 1987, Sec. 2.3): the state sampled
once per drive period T at the drive phase t0,

    P_k = x(t0 + k T),   k such that t[0] + transient <= t0 + k T <= t[-1],

from the C2 cubic interpolant of the records (:mod:`.timegrid`), since the
simulator's time grid does not hit the sample times. A periodic response of
period m T gives m distinct points; a quasi-periodic one a closed curve, a
chaotic one a fractal set.

Hyperplane section (autonomous systems; Parker & Chua, *Practical Numerical
Algorithms for Chaotic Systems*, 1989, Sec. 6.2): the points where

    g(t) = n . x(t) - c

changes sign in the chosen ``direction`` (+1: g from negative to non-negative,
-1: from positive to non-positive, 0: both). Each crossing time is the root of
the cubic interpolant of g on the bracketing record interval (Brent's method,
``scipy.optimize.brentq``, to 1e-12 of the interval), and the point is the
interpolated state there, so it lies on the hyperplane up to rounding.

Outputs are NaN-padded to ``max_points`` rows (fixed shape for sweeps); if
more samples exist, the *last* ``max_points`` are kept (the most settled ones).
"""

from __future__ import annotations

import math

import numpy as np
from scipy.optimize import brentq

from .errors import AnalysisError, require_array, require_count, require_finite, require_non_negative, require_positive
from .registry import Field, register
from .timegrid import cubic_interpolant, time_series

_STATE_INPUTS = (
    Field("t", ("time",), "s", "record times, non-decreasing (non-uniform allowed)"),
    Field("state", ("time", "component"), "[state]", "recorded state (or any signals), one row per record"),
)
_SECTION_OUTPUTS = (
    Field("points", ("point", "component"), "[state]", "section points, oldest first, NaN-padded after `count` rows"),
    Field("times", ("point",), "s", "time of each section point, NaN-padded"),
    Field("count", (), "1", "number of valid rows in `points`"),
)


def _section_sizes(*, max_points: int = 256, **_) -> dict[str, int]:
    return {"point": max_points}


def _padded(times: np.ndarray, points: np.ndarray, max_points: int) -> dict[str, np.ndarray]:
    """Keep the last ``max_points`` samples, pad with NaN to ``max_points`` rows."""
    times, points = times[-max_points:], points[-max_points:]
    count = len(times)
    padded_points = np.full((max_points, points.shape[1]), np.nan)
    padded_times = np.full(max_points, np.nan)
    padded_points[:count], padded_times[:count] = points, times
    return {"points": padded_points, "times": padded_times, "count": np.int64(count)}


def _state_series(t, state) -> tuple[np.ndarray, np.ndarray]:
    times, values = time_series(t, state, name="state", ndim=(1, 2))
    return times, (values[:, None] if values.ndim == 1 else values)


@register(
    "poincare_stroboscopic",
    inputs=_STATE_INPUTS,
    outputs=_SECTION_OUTPUTS,
    sizes=_section_sizes,
    source="Guckenheimer & Holmes 1983 Sec. 1.5; Moon 1987 Sec. 2.3",
)
def stroboscopic_section(
    t, state, *, period: float, phase: float = 0.0, transient: float = 0.0, max_points: int = 256
) -> dict[str, np.ndarray]:
    """State at ``phase + k * period`` (s) after ``t[0] + transient`` (module docstring)."""
    period = require_positive("period", period)
    phase = require_finite("phase", phase)
    transient = require_non_negative("transient", transient)
    max_points = require_count("max_points", max_points)
    times, values = _state_series(t, state)
    first = times[0] + transient
    if first > times[-1]:
        raise AnalysisError(f"transient={transient!r} leaves nothing of the record [{float(times[0])!r}, {float(times[-1])!r}] s")
    # a relative slack so that a sample time equal to a record end is not lost to rounding
    slack = 1e-9
    k_first = math.ceil((first - phase) / period - slack)
    k_last = math.floor((times[-1] - phase) / period + slack)
    k = np.arange(k_first, k_last + 1)
    sample_times = np.clip(phase + k * period, times[0], times[-1])
    points = cubic_interpolant(times, values)(sample_times) if len(k) else np.empty((0, values.shape[1]))
    return _padded(sample_times, points, max_points)


def _crossing_intervals(g: np.ndarray, direction: int) -> np.ndarray:
    """Indices i with a crossing of g in [t_i, t_{i+1}] in ``direction`` (module docstring)."""
    upward = (g[:-1] < 0.0) & (g[1:] >= 0.0)
    downward = (g[:-1] > 0.0) & (g[1:] <= 0.0)
    chosen = {1: upward, -1: downward, 0: upward | downward}[direction]
    return np.flatnonzero(chosen)


@register(
    "poincare_crossing",
    inputs=_STATE_INPUTS,
    outputs=_SECTION_OUTPUTS,
    sizes=_section_sizes,
    source="Parker & Chua 1989 Sec. 6.2",
)
def hyperplane_section(
    t, state, *, normal, offset: float = 0.0, direction: int = 1, transient: float = 0.0, max_points: int = 256
) -> dict[str, np.ndarray]:
    """Crossings of ``normal . x = offset`` in ``direction`` (+1, -1, 0) after ``t[0] + transient``."""
    times, values = _state_series(t, state)
    n = require_array("normal", normal, 1)
    if len(n) != values.shape[1] or not np.any(n):
        raise AnalysisError(f"normal must be a non-zero vector of {values.shape[1]} components, got {n.tolist()}")
    offset = require_finite("offset", offset)
    if direction not in (-1, 0, 1):
        raise AnalysisError(f"direction={direction!r} must be +1 (upward), -1 (downward) or 0 (both)")
    transient = require_non_negative("transient", transient)
    max_points = require_count("max_points", max_points)
    spline = cubic_interpolant(times, values)
    g = values @ n - offset
    g_spline = cubic_interpolant(times, g)  # = n . spline - offset (the spline is linear in the data)
    crossing_times = []
    for i in _crossing_intervals(g, direction):
        if g[i + 1] == 0.0:
            root = times[i + 1]
        else:
            root = brentq(g_spline, times[i], times[i + 1], xtol=1e-12 * (times[i + 1] - times[i]) + 1e-300)
        if root >= times[0] + transient:
            crossing_times.append(root)
    crossing_times = np.asarray(crossing_times, dtype=float)
    points = spline(crossing_times) if len(crossing_times) else np.empty((0, values.shape[1]))
    return _padded(crossing_times, points, max_points)
