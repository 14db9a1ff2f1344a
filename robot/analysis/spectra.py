"""Spectra of a signal recorded on a non-uniform time grid: FFT amplitude spectrum and Welch PSD.

Both first resample the signal on a uniform grid from the C2 cubic interpolant
of the records (:mod:`.timegrid`); the sampling rate, window, segment length and
frequency resolution used are returned with the spectrum.

Amplitude spectrum (one-sided, window-corrected; Harris, "On the use of windows
for harmonic analysis with the discrete Fourier transform", Proc. IEEE 66 (1978)
51-83): ``n_samples`` points x_k = x(t_s + k / f_s), f_s = n / (t_e - t_s)
(window end excluded, so a signal periodic in the window is periodic in the
samples), window w_k (periodic Hann by default),

    X_j = sum_k w_k x_k exp(-2 pi i j k / n),   f_j = j f_s / n = j / (t_e - t_s),
    A_0 = |X_0| / sum(w),   A_j = 2 |X_j| / sum(w)  (0 < j < n/2),   A_{n/2} = |X_{n/2}| / sum(w).

A sine of amplitude A at a bin frequency f_j gives A_j = A exactly (coherent
gain correction); between bins the Hann window loses at most 1.42 dB (15 %,
Harris 1978 Table I), so take ``t_e - t_s`` a whole number of drive periods.
With ``remove_mean`` (the default) the samples' mean m is subtracted before the
window and reported as ``A_0 = |m|``: a window spreads a constant over its main
lobe (Hann: a line of amplitude m in bin 1 too), which would hide or imitate a
low-frequency line of a signal with a large mean (a position, a preloaded force).

Power spectral density (Welch, "The use of fast Fourier transform for the
estimation of power spectra", IEEE Trans. Audio Electroacoust. 15 (1967) 70-73;
``scipy.signal.welch``): the uniform samples at ``sample_rate`` are cut into
segments of ``segment_length`` samples overlapping by ``overlap``, each
mean-removed and windowed, and the modified periodograms averaged:

    S(f_j) = mean over segments of  c |sum_k w_k x_k exp(-2 pi i j k / L)|^2 / (f_s sum_k w_k^2),

c = 2 except at f = 0 and the Nyquist frequency (one-sided density, [signal]^2/Hz).
Frequency spacing f_s / L; Parseval: sum_j S(f_j) f_s / L equals the mean-removed
signal's variance (up to the segment averaging). The window's equivalent noise
bandwidth f_s sum(w^2) / (sum w)^2 (1.5 f_s / L for Hann) is the resolution of a peak.
"""

from __future__ import annotations

import numpy as np
from scipy import signal as scipy_signal

from .errors import AnalysisError, require_count, require_positive
from .registry import Field, register
from .timegrid import cubic_interpolant, resample_uniform, time_series, uniform_grid, window

_SIGNAL_INPUTS = (
    Field("t", ("time",), "s", "record times, non-decreasing (non-uniform allowed)"),
    Field("signal", ("time",), "[signal]", "the recorded signal"),
)


def _window(name: str, length: int) -> np.ndarray:
    try:
        return scipy_signal.get_window(name, length, fftbins=True)
    except (ValueError, TypeError) as error:
        raise AnalysisError(f"window={name!r} is not a scipy.signal window name ({error})") from None


@register(
    "amplitude_spectrum",
    inputs=_SIGNAL_INPUTS,
    outputs=(
        Field("frequency", ("frequency",), "Hz", "bin frequencies j / (t_end - t_start)"),
        Field("amplitude", ("frequency",), "[signal]", "one-sided amplitude (a sine of amplitude A on a bin gives A)"),
        Field("sample_rate", (), "Hz", "rate of the uniform resampling"),
        Field("resolution", (), "Hz", "bin spacing 1 / (t_end - t_start)"),
    ),
    sizes=lambda *, n_samples=1024, **_: {"frequency": n_samples // 2 + 1},
    source="Harris, Proc. IEEE 66 (1978) 51-83",
)
def amplitude_spectrum(
    t,
    signal,
    *,
    n_samples: int = 1024,
    t_start: float | None = None,
    t_end: float | None = None,
    window_name: str = "hann",
    remove_mean: bool = True,
) -> dict[str, np.ndarray]:
    """One-sided amplitude spectrum of ``signal`` over ``[t_start, t_end)`` (module docstring)."""
    n = require_count("n_samples", n_samples, minimum=4)
    if not isinstance(remove_mean, (bool, np.bool_)):
        raise AnalysisError(f"remove_mean={remove_mean!r} must be true or false", key="remove_mean", value=remove_mean)
    times, values = time_series(t, signal, ndim=(1,))
    start, end = window(times, t_start, t_end)
    sample_rate = n / (end - start)
    samples = cubic_interpolant(times, values)(uniform_grid(start, end, sample_rate, n_samples=n))
    mean = float(np.mean(samples)) if remove_mean else 0.0
    weights = _window(window_name, n)
    amplitude = np.abs(np.fft.rfft(weights * (samples - mean))) / weights.sum()
    amplitude[1 : (n + 1) // 2] *= 2.0  # one-sided: fold negative frequencies (not DC, not Nyquist)
    if remove_mean:
        amplitude[0] = abs(mean)
    return {
        "frequency": np.fft.rfftfreq(n, d=1.0 / sample_rate),
        "amplitude": amplitude,
        "sample_rate": np.float64(sample_rate),
        "resolution": np.float64(sample_rate / n),
    }


@register(
    "power_spectral_density",
    inputs=_SIGNAL_INPUTS,
    outputs=(
        Field("frequency", ("frequency",), "Hz", "frequencies j sample_rate / segment_length"),
        Field("psd", ("frequency",), "[signal]^2/Hz", "one-sided power spectral density"),
        Field("sample_rate", (), "Hz", "rate of the uniform resampling"),
        Field("resolution", (), "Hz", "frequency spacing sample_rate / segment_length"),
        Field("noise_bandwidth", (), "Hz", "equivalent noise bandwidth of the window"),
        Field("segment_duration", (), "s", "segment_length / sample_rate"),
        Field("n_segments", (), "1", "number of averaged segments"),
        Field("variance", (), "[signal]^2", "variance of the resampled signal (Parseval: integral of psd)"),
    ),
    sizes=lambda *, segment_length=256, **_: {"frequency": segment_length // 2 + 1},
    source="Welch, IEEE Trans. Audio Electroacoust. 15 (1967) 70-73",
)
def power_spectral_density(
    t,
    signal,
    *,
    sample_rate: float,
    segment_length: int = 256,
    overlap: float = 0.5,
    t_start: float | None = None,
    t_end: float | None = None,
    window_name: str = "hann",
) -> dict[str, np.ndarray]:
    """Welch PSD of ``signal`` resampled at ``sample_rate`` over ``[t_start, t_end]`` (module docstring)."""
    fs = require_positive("sample_rate", sample_rate)
    length = require_count("segment_length", segment_length, minimum=4)
    if not 0.0 <= overlap < 1.0:
        raise AnalysisError(f"overlap={overlap!r} is outside the valid range [0, 1)")
    _, samples = resample_uniform(t, signal, fs, t_start=t_start, t_end=t_end, ndim=(1,))
    if length > len(samples):
        raise AnalysisError(
            f"segment_length={length} exceeds the {len(samples)} samples of the window at sample_rate={fs!r} Hz"
        )
    step = length - int(overlap * length)
    weights = _window(window_name, length)
    frequency, psd = scipy_signal.welch(
        samples, fs=fs, window=weights, nperseg=length, noverlap=length - step, detrend="constant", scaling="density"
    )
    return {
        "frequency": frequency,
        "psd": psd,
        "sample_rate": np.float64(fs),
        "resolution": np.float64(fs / length),
        "noise_bandwidth": np.float64(fs * np.sum(weights**2) / np.sum(weights) ** 2),
        "segment_duration": np.float64(length / fs),
        "n_segments": np.int64(1 + (len(samples) - length) // step),
        "variance": np.float64(np.var(samples)),
    }
