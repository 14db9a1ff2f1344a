"""The sweep's store: one xarray Dataset in a zarr (v3) folder, written run by run.

Layout (``docs/sweep.md``): the run dimensions are the grid axes (one per axis,
coordinate = the axis values) or ``sample`` (sampled designs, each axis a
coordinate along it). Per run:

* ``run_key`` (hash of the fully resolved scene and the outputs asked for),
  ``done``, ``status`` (0 reached the end, -1 failed, -2 not run yet),
  ``cause``, ``message``, ``t_reached``;
* ``counts`` (..., ``count``): nfev, njev, nsteps, nrejected, nevents, nrestarts
  (-1 where the method does not count);
* ``timings`` (..., ``timing``): measured seconds (the only values that differ
  between two executions of the same sweep);
* ``statistics`` (..., ``statistic``): every scalar output of the analyses,
  named ``LABEL_OUTPUT`` (``R1_force_peak``);
* ``LABEL_OUTPUT`` (..., ``LABEL_DIM``...): array outputs of the analyses
  (NaN-padded Poincare points, spectra), ``time`` outputs excepted;
* ``KEPT`` (..., ``time``, ...): the ``[keep]`` arrays on the uniform grid.

Every run variable is chunked one run per chunk, so each run's values are
separate files: a run is written (by the worker that computed it) into its own
region as soon as it finishes, ``done`` last; a killed sweep loses only the runs
in flight, and a run is never half-recorded as done. The packed ``counts``,
``timings`` and ``statistics`` arrays keep the number of files per run small;
:func:`open_sweep` unpacks them into one variable per name.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
import shutil
from typing import Any

import numpy as np

from robot.sweep.errors import SweepError

FORMAT = "robot.sweep/1"
COUNTS = ("nfev", "njev", "nsteps", "nrejected", "nevents", "nrestarts")
TIMING = ("wall_time", "cpu_time", "simulate_wall_time", "integration_wall_time", "integration_cpu_time")
NOT_RUN = -2
#: packed run variables and the dimension that names their entries
PACKED = {"counts": "count", "timings": "timing", "statistics": "statistic"}


@dataclass(frozen=True)
class Variable:
    """An array output of every run: its extra dimensions and their sizes."""

    dims: tuple[str, ...]
    shape: tuple[int, ...]


@dataclass(frozen=True)
class Layout:
    """Where and how each run's values are stored (sent to the workers with each run)."""

    path: str
    dims: tuple[str, ...]
    shape: tuple[int, ...]
    statistics: tuple[str, ...]
    series: dict[str, Variable] = field(default_factory=dict)
    kept: dict[str, Variable] = field(default_factory=dict)


def _array(group, name: str, run_dims: tuple[str, ...], run_shape: tuple[int, ...], extra: Variable, dtype, fill) -> None:
    group.create_array(
        name,
        shape=(*run_shape, *extra.shape),
        chunks=(*(1 for _ in run_shape), *extra.shape),
        dtype=dtype,
        fill_value=fill,
        dimension_names=(*run_dims, *extra.dims),
    )


def _coordinate(group, name: str, dims: tuple[str, ...], values: np.ndarray) -> None:
    values = np.asarray(values)
    dtype = str if values.dtype.kind in "UO" else values.dtype
    array = group.create_array(name, shape=values.shape, chunks=values.shape, dtype=dtype, dimension_names=dims)
    array[...] = values


def create_store(layout: Layout, coords: dict, attrs: dict[str, Any]) -> None:
    """Create the (empty) dataset: coordinates, every run variable filled with 'not run'."""
    import zarr

    group = zarr.open_group(layout.path, mode="w", zarr_format=3)
    for name, (dims, values) in coords.items():
        _coordinate(group, name, dims, values)
    _coordinate(group, "count", ("count",), np.array(COUNTS))
    _coordinate(group, "timing", ("timing",), np.array(TIMING))
    _coordinate(group, "statistic", ("statistic",), np.array(layout.statistics))
    dims, shape = layout.dims, layout.shape
    scalar = Variable((), ())
    _array(group, "run_key", dims, shape, scalar, str, "")
    _array(group, "status", dims, shape, scalar, "i1", NOT_RUN)
    _array(group, "cause", dims, shape, scalar, str, "")
    _array(group, "message", dims, shape, scalar, str, "")
    _array(group, "t_reached", dims, shape, scalar, "f8", np.nan)
    _array(group, "counts", dims, shape, Variable(("count",), (len(COUNTS),)), "i8", -1)
    _array(group, "timings", dims, shape, Variable(("timing",), (len(TIMING),)), "f8", np.nan)
    _array(group, "statistics", dims, shape, Variable(("statistic",), (len(layout.statistics),)), "f8", np.nan)
    for name, variable in {**layout.series, **layout.kept}.items():
        _array(group, name, dims, shape, variable, "f8", np.nan)
    _array(group, "done", dims, shape, scalar, bool, False)
    group.attrs.update({"format": FORMAT, **attrs})


def damaged(path: str | Path, what: str, exc: BaseException | None = None) -> SweepError:
    """The error of a store that cannot be read as written: names the store and the array, says how to recover."""
    reason = f" ({type(exc).__name__}: {exc})" if exc is not None else ""
    return SweepError(
        f"the sweep store at {str(path)!r} is damaged: {what}{reason}; rerun with --overwrite (its runs are made again) or delete it",
        key="store",
        value=str(path),
    )


def open_store(path: str | Path, mode: str = "r"):
    """The store's zarr group; a root that cannot be read is a damaged store (:func:`damaged`)."""
    import zarr

    try:
        return zarr.open_group(str(path), mode=mode)
    except Exception as exc:  # noqa: BLE001 - zarr raises many kinds for a bad root: all mean the same here
        raise damaged(path, "its root metadata (zarr.json) cannot be read", exc) from None


def existing_attrs(path: str | Path) -> dict[str, Any] | None:
    """The attributes of the store at ``path`` (None if there is none; SweepError if it cannot be read)."""
    if not (Path(path) / "zarr.json").is_file():
        return None
    return dict(open_store(path).attrs)


def remove_store(path: str | Path) -> None:
    if Path(path).exists():
        shutil.rmtree(path)


def read_array(path: str | Path, group, name: str, run_ndim: int = 0) -> np.ndarray:
    """The whole array ``name`` of the store at ``path`` (``group``: opened); SweepError (a damaged store)
    naming the array, and the runs (its first ``run_ndim`` dimensions) whose chunk cannot be read."""
    try:
        array = group[name]
    except Exception as exc:  # noqa: BLE001 - a missing or unreadable zarr.json
        raise damaged(path, f"array {name!r} is missing or its metadata cannot be read", exc) from None
    try:
        return np.asarray(array[...])
    except Exception as exc:  # noqa: BLE001 - a truncated or corrupt chunk (decompression, decoding, shape)
        where = f" at run(s) {shown_runs(damaged_runs(array, run_ndim))}" if run_ndim else ""
        raise damaged(path, f"array {name!r} cannot be read{where}", exc) from None


def damaged_runs(array, run_ndim: int) -> list[tuple[int, ...]]:
    """The run indices (the first ``run_ndim`` dimensions) whose chunk of ``array`` cannot be read."""
    bad = []
    for index in np.ndindex(*array.shape[:run_ndim]):
        try:
            array[index]
        except Exception:  # noqa: BLE001 - any failure to read the chunk
            bad.append(index)
    return bad


def shown_runs(runs: list[tuple[int, ...]], limit: int = 10) -> str:
    text = ", ".join(str(r) for r in runs[:limit])
    return text + (f" and {len(runs) - limit} more" if len(runs) > limit else "")


def finished_runs(path: str | Path) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``done``, ``run_key`` and ``status`` of every run (flat, C order)."""
    group = open_store(path)
    ndim = run_ndim(path, group)
    return tuple(np.asarray(read_array(path, group, name, ndim)).ravel() for name in ("done", "run_key", "status"))


def run_ndim(path: str | Path, group) -> int:
    """The number of run dimensions of the store (those of ``done``)."""
    try:
        return len(group["done"].shape)
    except Exception as exc:  # noqa: BLE001 - a missing or unreadable zarr.json
        raise damaged(path, "array 'done' is missing or its metadata cannot be read", exc) from None


#: the arrays every store has besides its coordinates and the outputs of its analyses and [keep]
RUN_ARRAYS = ("run_key", "status", "cause", "message", "t_reached", *PACKED, "done")


def check_store(path: str | Path, arrays: tuple[str, ...], coordinates: tuple[str, ...]) -> None:
    """SweepError (a damaged store) unless each of the run ``arrays`` and ``coordinates`` is there and every
    chunk of it can be read (every value is read once: a resumed sweep trusts what it keeps)."""
    group = open_store(path)
    ndim = run_ndim(path, group)
    for name in coordinates:
        read_array(path, group, name)
    for name in arrays:
        read_array(path, group, name, ndim)


_OPEN: dict[str, dict[str, Any]] = {}


def _arrays(layout: Layout) -> dict[str, Any]:
    """The store's arrays, opened once per process and layout (workers keep them between runs; a store
    replaced by one of another layout at the same path is opened again)."""
    token = repr(layout)
    if token not in _OPEN:
        group = open_store(layout.path, mode="r+")
        _OPEN[token] = {name: group[name] for name in group.array_keys()}
    return _OPEN[token]


def write_run(layout: Layout, index: tuple[int, ...], record: dict[str, Any]) -> None:
    """Write one run's values into its region; ``done`` last (a run is done only once complete)."""
    arrays = _arrays(layout)
    for name, value in record.items():
        arrays[name][index] = value
    arrays["done"][index] = True


def _raw_dataset(path: str | Path):
    """The store as xarray reads it (packed, lazy); SweepError if it is no store of this tool or its metadata is damaged."""
    import xarray as xr

    if not (Path(path) / "zarr.json").is_file():
        raise SweepError(f"{str(path)!r} is not a sweep store (no zarr.json)", key="store", value=str(path))
    try:
        dataset = xr.open_zarr(str(path), consolidated=False)
    except Exception as exc:  # noqa: BLE001 - metadata or a coordinate that cannot be read
        raise damaged(path, "its metadata or coordinates cannot be read", exc) from None
    if dataset.attrs.get("format") != FORMAT:
        raise SweepError(f"{str(path)!r} is not a sweep store of this tool (format {dataset.attrs.get('format')!r})", key="store", value=str(path))
    missing = [name for name in RUN_ARRAYS if name not in dataset]
    if missing:
        raise damaged(path, f"array(s) {missing} are missing")
    return dataset


def _unpacked(dataset):
    """The axes as coordinates; packed ``counts``, ``timings`` and ``statistics`` as one variable per name."""
    dataset = dataset.set_coords([c for c in dataset.attrs.get("coordinates", []) if c in dataset])
    for packed, dim in PACKED.items():
        names = [str(n) for n in dataset[dim].values]
        for i, name in enumerate(names):
            dataset[name] = dataset[packed].isel({dim: i}, drop=True)
        dataset = dataset.drop_vars([packed, dim])
    return dataset


def open_sweep(path: str | Path):
    """The sweep store as an ``xarray.Dataset``: packed ``counts``, ``timings`` and ``statistics``
    unpacked into one variable per name, the axes as coordinates."""
    return _unpacked(_raw_dataset(path))


def _readable_values(array, ndim: int, bad: list[tuple[int, ...]]) -> np.ndarray:
    """The array's values, its fill value in the runs ``bad`` (whose chunk cannot be read)."""
    skipped = set(bad)
    good = [index for index in np.ndindex(*array.shape[:ndim]) if index not in skipped]
    first = np.asarray(array[good[0]]) if good else np.asarray(array.fill_value)
    values = np.full(array.shape, array.fill_value, dtype=first.dtype if first.dtype.kind != "U" else object)
    for index in good:
        values[index] = array[index]
    return values


def load_dataset(path: str | Path):
    """:func:`open_sweep`'s dataset read into memory, for reports: a run's value whose chunk cannot be read
    is its array's fill value (NaN, 'not run') and is listed in ``attrs["damaged"]`` ("ARRAY at run(s) ...")."""
    dataset = _raw_dataset(path)
    group = open_store(path)
    ndim = run_ndim(path, group)
    damage = []
    for name in list(dataset.data_vars):
        try:
            dataset[name] = dataset[name].load()
        except Exception:  # noqa: BLE001 - a chunk that cannot be read: find the runs, keep the rest
            bad = damaged_runs(group[name], ndim)
            dataset[name] = (dataset[name].dims, _readable_values(group[name], ndim, bad), dataset[name].attrs)
            damage.append(f"{name} at run(s) {shown_runs(bad)}")
    dataset = _unpacked(dataset.load())
    dataset.attrs["damaged"] = damage
    return dataset
