"""Spectra on a non-uniform grid: known sines recovered, Parseval for the Welch PSD."""

from __future__ import annotations

import numpy as np
import pytest

from robot.analysis import ANALYSES, AnalysisError
from robot.analysis.spectra import amplitude_spectrum, power_spectral_density

# (frequency Hz, amplitude, phase) of the test signal; frequencies are multiples of 1/DURATION
SINES = [(3.0, 1.25, 0.3), (11.5, 0.4, -1.1), (47.0, 0.07, 2.0)]
OFFSET = 0.8
DURATION = 4.0


def non_uniform_grid(duration: float, n: int, seed: int) -> np.ndarray:
    """Sorted times with spacing varying by a factor ~10 (like the simulator's steps)."""
    rng = np.random.default_rng(seed)
    steps = rng.uniform(0.2, 2.0, n)
    t = np.concatenate([[0.0], np.cumsum(steps)])
    return t * duration / t[-1]


def sines(t: np.ndarray) -> np.ndarray:
    return OFFSET + sum(a * np.sin(2 * np.pi * f * t + p) for f, a, p in SINES)


def test_amplitude_spectrum_recovers_the_sines():
    t = non_uniform_grid(DURATION, 20000, seed=4)
    out = amplitude_spectrum(t, sines(t), n_samples=2048)
    assert float(out["resolution"]) == pytest.approx(1 / DURATION)
    assert float(out["sample_rate"]) == pytest.approx(2048 / DURATION)
    frequency, amplitude = out["frequency"], out["amplitude"]
    assert amplitude[0] == pytest.approx(OFFSET, rel=1e-6)  # the mean
    for f, a, _ in SINES:
        j = int(np.argmin(np.abs(frequency - f)))
        assert frequency[j] == pytest.approx(f)
        assert amplitude[j] == pytest.approx(a, rel=1e-5)
    # away from the lines (Hann: a line occupies its bin and the two neighbours) nothing is left
    lines = np.zeros_like(frequency, dtype=bool)
    for f in [0.0] + [f for f, _, _ in SINES]:
        lines |= np.abs(frequency - f) <= 1.01 * float(out["resolution"])
    assert np.max(amplitude[~lines]) < 1e-5


def test_a_large_mean_does_not_leak_into_the_low_bins():
    """A slider's position: mean 0.137 m, a 0.05 m line at 83.3 Hz. Windowed as it is, Hann spreads the mean into
    bin 1 at the mean's own amplitude (a false 20.8 Hz line larger than the real one); the mean is removed first."""
    t = non_uniform_grid(0.048, 6000, seed=9)
    f_drive = 2 / 0.024  # two drive periods in the window
    position = 0.137 + 0.05 * np.cos(2 * np.pi * f_drive * t)
    out = amplitude_spectrum(t, position, n_samples=256)
    amplitude, frequency = out["amplitude"], out["frequency"]
    assert amplitude[0] == pytest.approx(0.137, rel=1e-6)  # the mean, as the DC amplitude
    assert frequency[int(np.argmax(amplitude[1:])) + 1] == pytest.approx(f_drive)
    assert amplitude[1] < 1e-6 and amplitude[int(round(f_drive / float(out["resolution"])))] == pytest.approx(0.05, rel=1e-5)
    windowed_as_is = amplitude_spectrum(t, position, n_samples=256, remove_mean=False)["amplitude"]
    assert windowed_as_is[1] == pytest.approx(0.137, rel=1e-3)  # the leak the default removes
    with pytest.raises(AnalysisError, match="remove_mean='yes' must be true or false"):
        amplitude_spectrum(t, position, remove_mean="yes")


def test_amplitude_between_bins_within_the_hann_scalloping_loss():
    t = np.linspace(0.0, DURATION, 8001)
    f = 10.125  # between bins (bin spacing 0.25 Hz): half-way is the worst case, 1.42 dB (Harris 1978)
    out = amplitude_spectrum(t, 2.0 * np.sin(2 * np.pi * f * t), n_samples=1024)
    peak = np.max(out["amplitude"])
    assert 2.0 * 10 ** (-1.43 / 20) < peak < 2.0


def windowed_segment_power(samples: np.ndarray, length: int) -> float:
    """Mean over the half-overlapping segments of sum(w^2 (x - mean)^2) / sum(w^2), Hann w: what the
    one-sided Welch PSD integrates to exactly (discrete Parseval per segment)."""
    w = np.hanning(length + 1)[:-1]  # periodic Hann
    step = length // 2
    starts = range(0, len(samples) - length + 1, step)
    return float(np.mean([np.sum(w**2 * (s - s.mean()) ** 2) / np.sum(w**2) for s in (samples[i : i + length] for i in starts)]))


# segments hold 12 and 7.7 cycles of the slowest sine (3 Hz): the windowed power is then the variance to < 1 %
@pytest.mark.parametrize("segment_length, sample_rate", [(1024, 256.0), (1024, 400.0)])
def test_welch_psd_parseval_and_line_powers(segment_length, sample_rate):
    t = non_uniform_grid(40.0, 120000, seed=5)
    out = power_spectral_density(t, sines(t), sample_rate=sample_rate, segment_length=segment_length)
    df = float(out["resolution"])
    assert df == pytest.approx(sample_rate / segment_length)
    assert float(out["noise_bandwidth"]) == pytest.approx(1.5 * df, rel=1e-3)  # Hann
    assert int(out["n_segments"]) == 1 + (int(40.0 * sample_rate) + 1 - segment_length) // (segment_length // 2)
    psd, frequency = out["psd"], out["frequency"]
    total_power = sum(a**2 / 2 for _, a, _ in SINES)
    assert float(out["variance"]) == pytest.approx(total_power, rel=1e-3)
    samples = sines(np.arange(int(40.0 * sample_rate) + 1) / sample_rate)
    assert np.sum(psd) * df == pytest.approx(windowed_segment_power(samples, segment_length), rel=1e-6)
    assert np.sum(psd) * df == pytest.approx(float(out["variance"]), rel=0.01)
    # each line's power a^2 / 2 is the integral of the PSD over its peak
    for f, a, _ in SINES:
        near = np.abs(frequency - f) <= 3 * df
        assert np.sum(psd[near]) * df == pytest.approx(a**2 / 2, rel=0.02)


def test_welch_psd_of_white_noise_is_flat_at_the_variance_over_the_bandwidth():
    rng = np.random.default_rng(6)
    t = np.arange(200000) / 1000.0
    sigma = 0.3
    out = power_spectral_density(t, sigma * rng.standard_normal(t.size), sample_rate=1000.0, segment_length=256)
    level = sigma**2 / 500.0  # one-sided: sigma^2 spread over [0, fs/2]
    assert np.median(out["psd"][1:-1]) == pytest.approx(level, rel=0.05)
    assert np.sum(out["psd"]) * float(out["resolution"]) == pytest.approx(sigma**2, rel=0.02)


def test_registry_shapes_are_fixed_by_the_parameters():
    spectrum = ANALYSES["amplitude_spectrum"]
    for seed, n in [(7, 3000), (8, 9000)]:
        t = non_uniform_grid(DURATION, n, seed)
        out = spectrum(t=t, signal=sines(t), n_samples=512)
        assert spectrum.output_shapes({"time": n + 1}, n_samples=512) == {k: v.shape for k, v in out.items()}
    psd = ANALYSES["power_spectral_density"]
    t = non_uniform_grid(10.0, 5000, 9)
    out = psd(t=t, signal=sines(t), sample_rate=200.0, segment_length=128)
    assert psd.output_shapes({"time": t.size}, sample_rate=200.0, segment_length=128) == {k: v.shape for k, v in out.items()}


def test_bad_arguments_raise():
    t = np.linspace(0, 1, 101)
    with pytest.raises(AnalysisError, match="segment_length=512 exceeds the 101 samples"):
        power_spectral_density(t, np.sin(t), sample_rate=100.0, segment_length=512)
    with pytest.raises(AnalysisError, match=r"overlap=1.0 is outside the valid range \[0, 1\)"):
        power_spectral_density(t, np.sin(t), sample_rate=100.0, segment_length=16, overlap=1.0)
    with pytest.raises(AnalysisError, match="window='nonsense' is not a scipy.signal window name"):
        amplitude_spectrum(t, np.sin(t), n_samples=64, window_name="nonsense")
    with pytest.raises(AnalysisError, match="signal must be one-dimensional"):
        amplitude_spectrum(t, np.zeros((101, 2)), n_samples=64)
    with pytest.raises(AnalysisError, match=r"window \[t_start=0.5, t_end=2.0\]"):
        amplitude_spectrum(t, np.sin(t), t_start=0.5, t_end=2.0)
