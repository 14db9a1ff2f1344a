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


def existing_layout_key(path: str | Path) -> str | None:
    """The layout key of the sweep stored at ``path`` (None if there is no store)."""
    import zarr

    if not (Path(path) / "zarr.json").is_file():
        return None
    try:
        return zarr.open_group(str(path), mode="r").attrs.get("layout_key")
    except Exception as exc:  # an unreadable folder is not a store this tool wrote
        raise SweepError(f"{str(path)!r} exists but is not a readable sweep store ({exc}); choose another --out", key="out", value=str(path)) from None


def remove_store(path: str | Path) -> None:
    if Path(path).exists():
        shutil.rmtree(path)


def finished_runs(path: str | Path) -> tuple[np.ndarray, np.ndarray]:
    """``done`` and ``run_key`` of every run (flat, C order)."""
    import zarr

    group = zarr.open_group(str(path), mode="r")
    return np.asarray(group["done"][...]).ravel(), np.asarray(group["run_key"][...], dtype=object).ravel()


_OPEN: dict[str, dict[str, Any]] = {}


def _arrays(path: str) -> dict[str, Any]:
    """The store's arrays, opened once per process (workers keep them between runs)."""
    if path not in _OPEN:
        import zarr

        group = zarr.open_group(path, mode="r+")
        _OPEN[path] = {name: group[name] for name in group.array_keys()}
    return _OPEN[path]


def write_run(layout: Layout, index: tuple[int, ...], record: dict[str, Any]) -> None:
    """Write one run's values into its region; ``done`` last (a run is done only once complete)."""
    arrays = _arrays(layout.path)
    for name, value in record.items():
        arrays[name][index] = value
    arrays["done"][index] = True


def open_sweep(path: str | Path):
    """The sweep store as an ``xarray.Dataset``: packed ``counts``, ``timings`` and ``statistics``
    unpacked into one variable per name, the axes as coordinates."""
    import xarray as xr

    if not (Path(path) / "zarr.json").is_file():
        raise SweepError(f"{str(path)!r} is not a sweep store (no zarr.json)", key="store", value=str(path))
    dataset = xr.open_zarr(str(path), consolidated=False)
    if dataset.attrs.get("format") != FORMAT:
        raise SweepError(f"{str(path)!r} is not a sweep store of this tool (format {dataset.attrs.get('format')!r})", key="store", value=str(path))
    dataset = dataset.set_coords([c for c in dataset.attrs.get("coordinates", []) if c in dataset])
    for packed, dim in PACKED.items():
        names = [str(n) for n in dataset[dim].values]
        for i, name in enumerate(names):
            dataset[name] = dataset[packed].isel({dim: i}, drop=True)
        dataset = dataset.drop_vars([packed, dim])
    return dataset
