"""Largest Lyapunov exponent of a scalar time series (Rosenstein, Collins & De Luca 1993).

Rosenstein, Collins & De Luca, "A practical method for calculating largest
Lyapunov exponents from small data sets", Physica D 65 (1993) 117-134:

1. resample the signal on a uniform grid of step dt (cubic interpolant,
   :mod:`.timegrid`) and embed it with dimension m and delay J (Takens):
   Y_i = (x_i, x_{i+J}, ..., x_{i+(m-1)J}),  i = 0 .. M-1;
2. for each reference point Y_i its nearest neighbour Y_j, excluding temporal
   neighbours |i - j| <= w (Theiler window; Rosenstein: the mean period, the
   reciprocal of the mean frequency of the power spectrum, Sec. 3);
3. the mean log divergence of the pairs after k steps,

       y(k) = < ln |Y_{i+k} - Y_{j+k}| >_i ,      k = 0 .. n_steps,

4. the exponent is the slope of y against k dt over the linear (exponential
   growth) region, fitted by least squares on steps [fit_start, fit_end]:
   y(k) ~ lambda_1 k dt + const.

Defaults follow the paper: J from the autocorrelation's drop below 1 - 1/e
(Sec. 3), w from the mean period. The fit range must lie inside the linear
region, before y(k) saturates at the attractor size; inspect ``divergence``
(returned for that purpose) when choosing it. The result is an estimate: the
paper reports errors of a few per cent on its test systems with short series.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from .errors import AnalysisError, require_count, require_positive
from .registry import Field, register
from .timegrid import resample_uniform

_CHUNK = 4096  # reference points per neighbour query


def autocorrelation_delay(samples: np.ndarray) -> int:
    """First lag (samples) where the autocorrelation falls below 1 - 1/e (Rosenstein 1993, Sec. 3)."""
    x = samples - samples.mean()
    spectrum = np.fft.rfft(x, 2 * len(x))
    correlation = np.fft.irfft(np.abs(spectrum) ** 2)[: len(x)]
    below = np.flatnonzero(correlation < (1.0 - 1.0 / np.e) * correlation[0])
    if below.size == 0:
        raise AnalysisError("the autocorrelation never falls below 1 - 1/e: give delay explicitly")
    return int(max(below[0], 1))


def mean_period(samples: np.ndarray) -> float:
    """Reciprocal of the power-weighted mean frequency, in samples (Rosenstein 1993, Sec. 3)."""
    power = np.abs(np.fft.rfft(samples - samples.mean())) ** 2
    frequency = np.fft.rfftfreq(len(samples))
    return float(power.sum() / np.sum(power * frequency)) if np.any(power[1:]) else float(len(samples))


def embed(samples: np.ndarray, dimension: int, delay: int) -> np.ndarray:
    """(M, dimension) delay vectors, M = N - (dimension - 1) delay."""
    count = len(samples) - (dimension - 1) * delay
    if count < 2:
        raise AnalysisError(f"embedding_dimension={dimension} with delay={delay} leaves {count} vectors of {len(samples)} samples")
    return np.column_stack([samples[i * delay : i * delay + count] for i in range(dimension)])


def nearest_neighbours(points: np.ndarray, theiler_window: int) -> tuple[np.ndarray, np.ndarray]:
    """For each point, the nearest other point with |i - j| > theiler_window and non-zero distance: (j, distance)."""
    n = len(points)
    k = min(n, 2 * theiler_window + 2)  # at most 2 w + 1 temporal neighbours can be closer
    tree = cKDTree(points)
    neighbour = np.full(n, -1)
    distance = np.full(n, np.inf)
    for start in range(0, n, _CHUNK):
        rows = np.arange(start, min(start + _CHUNK, n))
        d, j = tree.query(points[rows], k=k)
        d, j = d.reshape(len(rows), k), j.reshape(len(rows), k)
        valid = (np.abs(j - rows[:, None]) > theiler_window) & (d > 0.0) & (j < n)
        first = np.argmax(valid, axis=1)
        found = valid[np.arange(len(rows)), first]
        neighbour[rows[found]] = j[found, first[found]]
        distance[rows[found]] = d[found, first[found]]
    return neighbour, distance


def mean_log_divergence(points: np.ndarray, theiler_window: int, n_steps: int) -> tuple[np.ndarray, int]:
    """y(k), k = 0 .. n_steps (module docstring, step 3) and the number of pairs averaged."""
    usable = len(points) - n_steps
    if usable < 2 * theiler_window + 3:
        raise AnalysisError(
            f"n_steps={n_steps} and theiler_window={theiler_window} leave {usable} reference points; need a longer series"
        )
    neighbour, _ = nearest_neighbours(points[:usable], theiler_window)
    reference = np.flatnonzero(neighbour >= 0)
    steps = np.arange(n_steps + 1)
    separation = points[reference[:, None] + steps] - points[neighbour[reference][:, None] + steps]
    distance = np.linalg.norm(separation, axis=2)
    with np.errstate(divide="ignore"):
        logs = np.log(distance)
    logs[~np.isfinite(logs)] = np.nan  # a pair that coincides later carries no information
    return np.nanmean(logs, axis=0), len(reference)


@register(
    "lyapunov_rosenstein",
    inputs=(
        Field("t", ("time",), "s", "record times, non-decreasing (non-uniform allowed)"),
        Field("signal", ("time",), "[signal]", "one observed coordinate"),
    ),
    outputs=(
        Field("exponent", (), "1/s", "largest Lyapunov exponent estimate"),
        Field("divergence", ("lag",), "1", "mean log divergence y(k) (ln of [signal])"),
        Field("lag_time", ("lag",), "s", "k * sample_interval"),
        Field("delay", (), "1", "embedding delay used (samples)"),
        Field("theiler_window", (), "1", "temporal exclusion used (samples)"),
        Field("n_pairs", (), "1", "number of averaged neighbour pairs"),
    ),
    sizes=lambda *, n_steps=200, **_: {"lag": n_steps + 1},
    source="Rosenstein, Collins & De Luca, Physica D 65 (1993) 117-134",
)
def rosenstein_exponent(
    t,
    signal,
    *,
    sample_interval: float,
    embedding_dimension: int = 5,
    delay: int | None = None,
    theiler_window: int | None = None,
    n_steps: int = 200,
    fit_start: int = 0,
    fit_end: int = 100,
    t_start: float | None = None,
    t_end: float | None = None,
) -> dict[str, np.ndarray]:
    """Rosenstein estimate of the largest Lyapunov exponent of ``signal`` (module docstring)."""
    dt = require_positive("sample_interval", sample_interval)
    m = require_count("embedding_dimension", embedding_dimension)
    n_steps = require_count("n_steps", n_steps)
    if not 0 <= fit_start < fit_end <= n_steps:
        raise AnalysisError(f"fit range [fit_start={fit_start}, fit_end={fit_end}] must satisfy 0 <= fit_start < fit_end <= n_steps={n_steps}")
    _, samples = resample_uniform(t, signal, 1.0 / dt, t_start=t_start, t_end=t_end, ndim=(1,))
    lag = autocorrelation_delay(samples) if delay is None else require_count("delay", delay)
    window = int(np.ceil(mean_period(samples))) if theiler_window is None else require_count("theiler_window", theiler_window, 0)
    divergence, n_pairs = mean_log_divergence(embed(samples, m, lag), window, n_steps)
    lag_time = np.arange(n_steps + 1) * dt
    fit = slice(fit_start, fit_end + 1)
    slope = np.polyfit(lag_time[fit], divergence[fit], 1)[0]
    return {
        "exponent": np.float64(slope),
        "divergence": divergence,
        "lag_time": lag_time,
        "delay": np.int64(lag),
        "theiler_window": np.int64(window),
        "n_pairs": np.int64(n_pairs),
    }
