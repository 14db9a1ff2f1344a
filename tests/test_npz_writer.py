"""The result file's writer: a standard .npz (numpy.load reads it back exactly), deflated where that pays."""

from __future__ import annotations

import io
import zipfile

import numpy as np

from robot.io.npz_writer import worth_deflating, write_npz


def test_round_trip_is_exact_and_only_repetitive_arrays_are_deflated():
    rng = np.random.default_rng(7)
    force = np.zeros((5000, 4))
    force[1200:1300] = rng.random((100, 4)) * 1e4  # one impact: zeros elsewhere
    arrays = {
        "q": rng.standard_normal((5000, 27)),
        "q32": rng.standard_normal((5000, 3)).astype(np.float32),
        "force": force,
        "onset_rates": np.full((5000, 5), 1e-3),
        "kind": rng.integers(0, 3, 5000).astype(np.int8),
        "flag": np.array([True, False]),
        "scalar": np.array(3.5),
        "text": np.array('{"a": 1}'),
        "empty": np.zeros((0, 3)),
    }
    buffer = io.BytesIO()
    write_npz(buffer, arrays)
    buffer.seek(0)
    with np.load(buffer, allow_pickle=False) as archive:
        assert sorted(archive.files) == sorted(arrays)
        for key, value in arrays.items():
            assert archive[key].dtype == value.dtype and np.array_equal(archive[key], value), key
    buffer.seek(0)
    deflated = {info.filename[:-4] for info in zipfile.ZipFile(buffer).infolist() if info.compress_type == zipfile.ZIP_DEFLATED}
    assert deflated == {"force", "onset_rates", "kind", "flag", "text"}


def test_worth_deflating_counts_repeats_along_the_first_axis():
    assert not worth_deflating(np.arange(100.0))
    assert worth_deflating(np.repeat(np.arange(10.0), 10))
    assert not worth_deflating(np.array([1.0]))
    assert worth_deflating(np.arange(4, dtype=np.int64))
