"""Peak / RMS / mean over a window on a non-uniform grid, against the analytic values for sines."""

from __future__ import annotations

import numpy as np
import pytest

from robot.analysis import ANALYSES, AnalysisError
from robot.analysis.statistics import peak_rms


def clustered_grid(t_end: float, n: int) -> np.ndarray:
    """Dense records in [0.2, 0.25] t_end (like a contact phase), sparse elsewhere."""
    sparse = np.linspace(0.0, t_end, n // 4)
    dense = np.linspace(0.2 * t_end, 0.25 * t_end, 3 * n // 4)
    return np.unique(np.concatenate([sparse, dense]))


@pytest.mark.parametrize("amplitude, offset, omega", [(2.0, 0.5, 3.0), (0.01, -0.004, 40.0)])
def test_sine_over_whole_periods(amplitude, offset, omega):
    t_end = 6 * 2 * np.pi / omega
    t = clustered_grid(t_end, 40000)
    x = offset + amplitude * np.sin(omega * t)
    out = peak_rms(t, x)
    assert float(out["mean"]) == pytest.approx(offset, abs=1e-6 * amplitude)
    assert float(out["rms"]) == pytest.approx(np.sqrt(offset**2 + amplitude**2 / 2), rel=1e-6)
    # the plain mean of the samples over-weights the dense phase: the grid matters
    assert abs(np.mean(x) - offset) > 0.1 * amplitude
    assert float(out["peak"]) == pytest.approx(amplitude + abs(offset), rel=1e-5)
    # the peak is at a crest of the larger sign (all crests are equal: any one of them)
    crest_phase = np.sin(omega * float(out["time_of_peak"]))
    assert crest_phase == pytest.approx(np.sign(offset) if offset else 1.0, abs=1e-5)
    assert float(out["maximum"]) == pytest.approx(offset + amplitude, rel=1e-5)
    assert float(out["minimum"]) == pytest.approx(offset - amplitude, rel=1e-5)


def test_single_pulse_peak_time():
    t = np.sort(np.random.default_rng(3).uniform(0.0, 1.0, 5000))
    out = peak_rms(t, -4.0 * np.exp(-(((t - 0.6180) / 0.01) ** 2)))
    assert float(out["time_of_peak"]) == pytest.approx(0.6180, abs=2e-3)
    assert float(out["peak"]) == pytest.approx(4.0, rel=1e-3) and float(out["minimum"]) == -float(out["peak"])


def test_window_between_records_is_cut_exactly():
    t = np.array([0.0, 0.1, 0.45, 0.5, 0.9, 1.0])
    out = peak_rms(t, 3.0 * t, t_start=0.3, t_end=0.7)  # linear: trapezoid is exact
    assert float(out["mean"]) == pytest.approx(1.5)
    # trapezoid of x^2 on the records inside plus the cut ends 0.3 and 0.7
    nodes = np.array([0.3, 0.45, 0.5, 0.7])
    assert float(out["rms"]) == pytest.approx(np.sqrt(np.trapezoid((3.0 * nodes) ** 2, nodes) / 0.4))
    assert float(out["peak"]) == pytest.approx(2.1) and float(out["time_of_peak"]) == pytest.approx(0.7)


def test_registry_call_and_errors():
    t = np.linspace(0, 1, 11)
    out = ANALYSES["peak_rms"](t=t, signal=-t)
    assert float(out["peak"]) == 1.0 and float(out["minimum"]) == -1.0
    with pytest.raises(AnalysisError, match=r"window \[t_start=0.5, t_end=0.2\]"):
        peak_rms(t, t, t_start=0.5, t_end=0.2)
    with pytest.raises(AnalysisError, match="needs the input"):
        ANALYSES["peak_rms"](t=t)
    with pytest.raises(AnalysisError, match="has no input or parameter"):
        ANALYSES["peak_rms"](t=t, signal=t, start=0.1)
    with pytest.raises(AnalysisError, match="signal has a non-finite value"):
        peak_rms(t, np.where(t > 0.5, np.nan, t))
