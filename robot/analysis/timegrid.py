"""Signals on the simulator's non-uniform time grid: checks, cubic interpolant, uniform resampling.

The recorded time grid is non-uniform (step ends, contact onsets, penetration
and force maxima interleaved, ``robot.results``) and may repeat a time (an
onset record and the step end it cut). :func:`time_series` checks a grid and
drops repeated times (keeping the last record: after an event, the state the
solver restarted from). The interpolant between records is the C2 cubic spline
with not-a-knot ends (``scipy.interpolate.CubicSpline``; de Boor, *A Practical
Guide to Splines*, 1978, ch. IV): error O(h^4) for smooth signals, where h is
the local record spacing. Every analysis that needs values between records
(stroboscopic Poincare samples, hyperplane crossings, uniform resampling for the
spectra and the Rosenstein estimator) goes through :func:`cubic_interpolant`.
"""

from __future__ import annotations

import numpy as np
from scipy.interpolate import CubicSpline

from .errors import AnalysisError, require_array, require_positive


def time_series(t, values, *, name: str = "signal", ndim: tuple[int, ...] = (1, 2, 3)) -> tuple[np.ndarray, np.ndarray]:
    """``(t, values)`` checked, sorted in time, with repeated times dropped (last record kept).

    ``t``: (n,) non-decreasing seconds, at least 2 distinct times; ``values``:
    (n, ...) finite, with one of the ``ndim`` numbers of dimensions. AnalysisError
    names the first decreasing time.
    """
    times = require_array("t", t, 1)
    data = require_array(name, values, ndim, length=len(times))
    steps = np.diff(times)
    if np.any(steps < 0.0):
        i = int(np.flatnonzero(steps < 0.0)[0])
        raise AnalysisError(f"t must be non-decreasing; t[{i + 1}]={float(times[i + 1])!r} < t[{i}]={float(times[i])!r}")
    keep = np.append(steps > 0.0, True)  # of equal times, keep the last
    times, data = times[keep], data[keep]
    if len(times) < 2:
        raise AnalysisError(f"t must hold at least 2 distinct times, got {len(times)}")
    return times, data


def cubic_interpolant(t: np.ndarray, values: np.ndarray) -> CubicSpline:
    """C2 cubic spline through the records along axis 0 (not-a-knot ends), of a checked series."""
    if len(t) < 4:
        # not-a-knot needs 4 points; with 2-3 the spline degrades to a lower-degree polynomial
        return CubicSpline(t, values, axis=0, bc_type="natural")
    return CubicSpline(t, values, axis=0)


def window(t: np.ndarray, t_start: float | None, t_end: float | None) -> tuple[float, float]:
    """The analysis window ``[t_start, t_end]`` (defaults: the series' ends), checked against ``t``."""
    start = float(t[0]) if t_start is None else float(t_start)
    end = float(t[-1]) if t_end is None else float(t_end)
    if not t[0] <= start < end <= t[-1]:
        raise AnalysisError(
            f"window [t_start={t_start!r}, t_end={t_end!r}] must satisfy "
            f"t[0]={float(t[0])!r} <= t_start < t_end <= t[-1]={float(t[-1])!r}"
        )
    return start, end


def uniform_grid(start: float, end: float, sample_rate: float, *, n_samples: int | None = None) -> np.ndarray:
    """Times ``start + k / fs``: ``n_samples`` of them if given, else all up to ``end`` inclusive."""
    fs = require_positive("sample_rate", sample_rate)
    n = int(np.floor((end - start) * fs * (1.0 + 1e-12))) + 1 if n_samples is None else n_samples
    if n < 2:
        raise AnalysisError(f"sample_rate={sample_rate!r} gives {n} sample(s) in a window of {end - start:g} s; need >= 2")
    return start + np.arange(n) / fs


def resample_uniform(
    t, values, sample_rate: float, *, t_start: float | None = None, t_end: float | None = None, name: str = "signal",
    ndim: tuple[int, ...] = (1, 2, 3),
) -> tuple[np.ndarray, np.ndarray]:
    """``values`` at ``t_start + k / sample_rate`` (k = 0, 1, ... up to ``t_end``) from the cubic interpolant."""
    times, data = time_series(t, values, name=name, ndim=ndim)
    start, end = window(times, t_start, t_end)
    grid = uniform_grid(start, end, sample_rate)
    return grid, cubic_interpolant(times, data)(grid)
