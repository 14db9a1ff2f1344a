"""Peak, RMS and mean of a signal over a time window, on a non-uniform grid.

Over the window [t_s, t_e] (defaults: the whole record), with the records
inside it plus the signal linearly interpolated at t_s and t_e:

    peak          max |x(t_i)|, and the time t_i where it occurs (first if tied),
    minimum/maximum  min x(t_i), max x(t_i),
    mean          (1 / (t_e - t_s)) * integral x dt,
    rms           sqrt( (1 / (t_e - t_s)) * integral x^2 dt ),

the integrals by the trapezoid rule on the records (time-weighted: a plain
average of the samples would over-weight the densely recorded contact phases).
The extremes are taken over the records, not interpolated: the simulator
records located penetration and force maxima (``RECORD_PEAK``,
``RECORD_FORCE_PEAK`` in ``robot.results``), so the recorded maximum of a
contact force is its located peak.
"""

from __future__ import annotations

import numpy as np

from .registry import Field, register
from .timegrid import time_series, window


def window_records(t, signal, t_start: float | None, t_end: float | None) -> tuple[np.ndarray, np.ndarray]:
    """Records inside ``[t_start, t_end]`` with linearly interpolated end points added."""
    times, values = time_series(t, signal, ndim=(1,))
    start, end = window(times, t_start, t_end)
    inside = (times > start) & (times < end)
    ends = np.interp([start, end], times, values)
    return (
        np.concatenate([[start], times[inside], [end]]),
        np.concatenate([[ends[0]], values[inside], [ends[1]]]),
    )


@register(
    "peak_rms",
    inputs=(
        Field("t", ("time",), "s", "record times, non-decreasing (non-uniform allowed)"),
        Field("signal", ("time",), "[signal]", "the recorded signal"),
    ),
    outputs=(
        Field("peak", (), "[signal]", "max |x| over the window's records"),
        Field("time_of_peak", (), "s", "time of the peak"),
        Field("minimum", (), "[signal]", "min x"),
        Field("maximum", (), "[signal]", "max x"),
        Field("mean", (), "[signal]", "time-weighted mean (trapezoid)"),
        Field("rms", (), "[signal]", "time-weighted root mean square (trapezoid)"),
    ),
    source="trapezoid rule; definitions in the module docstring",
)
def peak_rms(t, signal, *, t_start: float | None = None, t_end: float | None = None) -> dict[str, np.ndarray]:
    """Peak, extremes, mean and RMS of ``signal`` over ``[t_start, t_end]`` (module docstring)."""
    times, values = window_records(t, signal, t_start, t_end)
    duration = times[-1] - times[0]
    peak_index = int(np.argmax(np.abs(values)))
    return {
        "peak": np.float64(abs(values[peak_index])),
        "time_of_peak": np.float64(times[peak_index]),
        "minimum": np.float64(values.min()),
        "maximum": np.float64(values.max()),
        "mean": np.float64(np.trapezoid(values, times) / duration),
        "rms": np.float64(np.sqrt(np.trapezoid(values**2, times) / duration)),
    }
