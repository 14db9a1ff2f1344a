"""The step loop's bookkeeping gives the very numbers of its straightforward formulation (issue 16).

The force-peak search walks back over the boundary records on arrays
(:meth:`Records.boundaries`, :meth:`ForcePeaks._boundary_forces`,
:func:`largest_local_maximum`), samples without ``np.linspace``
(:func:`sample_times`) and the cubic Hermite dense output evaluates a time in
Python floats: each must give bit for bit what the plain loops and numpy
expressions give (a run is so sensitive to rounding that a last-bit change moves
late force peaks), on random data of many magnitudes, zero forces and ties.
"""

from __future__ import annotations

import numpy as np
import pytest

from robot.integration.dense import HermiteDense
from robot.integration.force_peaks import ForcePeaks, largest_local_maximum, sample_times
from robot.integration.records import RECORD_ONSET, RECORD_OUTPUT, RECORD_PEAK, RECORD_START, RECORD_STEP, OutputTimes, Records


def test_sample_times_are_numpys_linspace_bit_for_bit():
    rng = np.random.default_rng(1)
    for _ in range(20000):
        a = rng.uniform(-1, 1) * 10.0 ** rng.integers(-6, 3)
        b = a + 10.0 ** rng.uniform(-15, 1)
        intervals = int(rng.integers(1, 9))
        assert sample_times(a, b, intervals) == np.linspace(a, b, intervals + 1).tolist()


def _hermite_reference(dense: HermiteDense, t) -> np.ndarray:
    """The interpolant as numpy evaluates the module docstring's formula written out (a time or an array of times)."""
    s = (np.asarray(t) - dense.t_old) / dense.h
    h00, h10, h01, h11 = 2 * s**3 - 3 * s**2 + 1, s**3 - 2 * s**2 + s, -2 * s**3 + 3 * s**2, s**3 - s**2
    if np.ndim(s) == 0:
        return h00 * dense.y_old + h10 * dense.h * dense.f_old + h01 * dense.y + h11 * dense.h * dense.f
    return np.outer(dense.y_old, h00) + np.outer(dense.f_old, h10 * dense.h) + np.outer(dense.y, h01) + np.outer(dense.f, h11 * dense.h)


def test_hermite_dense_is_the_numpy_expression_and_exact_for_cubics():
    rng = np.random.default_rng(2)
    for _ in range(300):
        t_old = rng.uniform(0, 2)
        h = 10.0 ** rng.uniform(-9, -2)
        y_old, f_old, y, f = (rng.normal(size=12) for _ in range(4))
        dense = HermiteDense(t_old, t_old + h, y_old, f_old, y, f)
        times = rng.uniform(t_old - 0.2 * h, t_old + 1.2 * h, 20)  # a little outside the step too
        assert np.array_equal(dense(times), _hermite_reference(dense, times))
        for t in times:
            assert np.array_equal(dense(t), _hermite_reference(dense, t))
            assert np.array_equal(dense(float(t)), _hermite_reference(dense, float(t)))
    # exact (to rounding) for a cubic: y(t) = c0 + c1 t + c2 t^2 + c3 t^3 per component
    c = rng.normal(size=(4, 3))
    value = lambda t: c[0] + c[1] * t + c[2] * t**2 + c[3] * t**3  # noqa: E731
    slope = lambda t: c[1] + 2 * c[2] * t + 3 * c[3] * t**2  # noqa: E731
    dense = HermiteDense(0.3, 0.7, value(0.3), slope(0.3), value(0.7), slope(0.7))
    for t in np.linspace(0.3, 0.7, 9):
        assert dense(t) == pytest.approx(value(t), rel=1e-13, abs=1e-13)


def _random_records(rng, n: int, n_candidates: int) -> Records:
    """Records as a run writes them: a start, steps and onsets with forces (some zero), inner records without."""
    records = Records(n_candidates)
    t = 0.0
    records.add(t, rng.normal(size=5), RECORD_START, rng.random(n_candidates), rng.random(n_candidates))
    for _ in range(n):
        kind = int(rng.choice([RECORD_STEP, RECORD_STEP, RECORD_ONSET, RECORD_PEAK, RECORD_OUTPUT]))
        t += float(rng.choice([0.0, 1e-4 * rng.random()]))  # a restart can repeat an instant
        forces = np.where(rng.random(n_candidates) < 0.1, 0.0, np.round(rng.random(n_candidates), 1)) if kind in (RECORD_STEP, RECORD_ONSET) else None
        records.add(t, rng.normal(size=5), kind, rng.random(n_candidates), forces)
    return records


def _walk_reference(records: Records, k: int, t_old: float, t_lo: float, f_old: float, max_walk: int):
    """The walk back as a plain loop over every record (its formulation before issue 16)."""
    chain, forces = [], []
    for i in range(len(records) - 1, -1, -1):
        if records.kind[i] not in (RECORD_STEP, RECORD_ONSET, RECORD_START):
            continue
        if not chain and records.t[i] != t_old:
            return None
        f = f_old if not chain else float(records.force[i][k])
        chain.append(i)
        forces.append(f)
        if records.t[i] <= t_lo or records.kind[i] == RECORD_START or not f > 0 or len(chain) >= max_walk:
            break
    return chain, forces


class _System:
    n_candidates = 3


def test_walk_back_over_boundary_records_is_the_plain_loop():
    rng = np.random.default_rng(3)
    for trial in range(200):
        records = _random_records(rng, int(rng.integers(1, 400)), _System.n_candidates)
        search = ForcePeaks(_System(), None, records)
        search.max_walk = int(rng.choice([1000, 5, 1]))
        for _ in range(5):  # interleaved with more records: the arrays are extended on demand
            boundary = [i for i in range(len(records)) if records.kind[i] in (RECORD_STEP, RECORD_ONSET, RECORD_START)]
            t_old = records.t[boundary[-1]] if rng.random() < 0.9 else -1.0
            t_lo = float(rng.choice([-np.inf, rng.uniform(0, max(records.t[-1], 1e-9))]))
            k, f_old = int(rng.integers(_System.n_candidates)), float(rng.choice([0.0, rng.random()]))
            expected = _walk_reference(records, k, t_old, t_lo, f_old, search.max_walk)
            walked = search._boundary_forces(k, t_old, t_lo, f_old)
            if expected is None:
                assert walked is None
            else:
                assert walked[0].tolist() == expected[0] and walked[1].tolist() == expected[1]
            extra = _random_records(rng, int(rng.integers(0, 30)), _System.n_candidates)
            for i in range(1, len(extra)):
                records.add(records.t[-1] + extra.t[i], extra.y[i], extra.kind[i], extra.onset[i], extra.force[i])
    index, times, forces = records.boundaries()
    assert index.tolist() == [i for i in range(len(records)) if records.kind[i] in (RECORD_STEP, RECORD_ONSET, RECORD_START)]
    assert times.tolist() == [records.t[i] for i in index] and np.array_equal(forces, np.array([records.force[i] for i in index]))


def test_a_boundary_record_without_forces_is_refused():
    records = Records(2)
    with pytest.raises(ValueError, match="boundary record"):
        records.add(0.0, np.zeros(3), RECORD_STEP, np.zeros(2))


def test_largest_local_maximum_is_the_plain_selection():
    rng = np.random.default_rng(4)
    for _ in range(5000):
        forces = np.round(rng.random(int(rng.integers(1, 12))), 1)  # ties are common
        falling = bool(rng.random() < 0.5)
        peaks = [p for p in range(len(forces) - 1) if forces[p] >= forces[p + 1] and (forces[p] > forces[p - 1] if p > 0 else falling)]
        assert largest_local_maximum(forces, falling) == (max(peaks, key=lambda p: forces[p]) if peaks else None)


def test_output_times_are_taken_once_in_order():
    grid = OutputTimes.grid(0.25)
    assert list(grid.take(0.0, 0.6)) == [0.25, 0.5]
    assert not grid.due(0.7) and grid.due(0.75 - 1e-13)
    assert list(grid.take(0.8, 1.0)) == [1.0]  # 0.75 lies before the interval: skipped
    assert grid.taken == [0, 1, 3]
    given = OutputTimes.at(np.array([-1.0, 0.5, 2.0]))
    assert list(given.take(0.0, 3.0)) == [0.5, 2.0] and not given.due(np.inf) and given.taken == [1, 2]
