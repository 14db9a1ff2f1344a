"""Running a sweep on dask.distributed: a local cluster or an existing scheduler.

The driver (this module) loads and validates the sweep, creates or reopens the
store, starts the workers (a ``LocalCluster`` of ``--workers`` processes with
one thread each and single-threaded BLAS, or ``Client(ADDRESS)`` of a running
scheduler: dask-jobqueue, dask-kubernetes, ``dask scheduler`` + ``dask
worker``), probes one run on every worker (which learns the arrays' shapes and
warms the compiled kernels), submits every run that is not yet done and follows
them with a progress bar. Workers write their runs into the store themselves,
so the store must be reachable from every worker (a shared filesystem path).

Resuming: runs whose stored ``run_key`` equals the key of their resolved scene
and whose ``done`` flag is set are skipped; failed runs are redone only with
``retry_failed``. A store is resumed only by the sweep its attributes describe
(:func:`store_differences`: layout, scene, t_end, overrides, ...) and only if
every array of it can be read; another one is refused naming what differs (or
what is damaged) unless ``overwrite``, which deletes it only once the new
sweep's probe run succeeded (:func:`_prepare_store`).

Stopping: ``run_sweep(..., stop=...)`` asks ``stop()`` while it waits for the
runs; once true, the runs not finished are cancelled (those in flight are not
recorded, so a resumed sweep makes them) and the outcome is ``interrupted``,
with the number of runs the store holds (``finished``).
"""

from __future__ import annotations

import json
import logging
import os
import sys
import time
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Iterator

import numpy as np

from robot.sweep.errors import SweepError
from robot.sweep.spec import SweepSpec
from robot.sweep.design import python_value
from robot.sweep.store import (
    COUNTS, PACKED, RUN_ARRAYS, TIMING, Layout, Variable, check_store, create_store, existing_attrs, finished_runs, open_store, read_array, remove_store, run_ndim, write_run,
)  # fmt: skip
from robot.sweep.task import RunTask, blank_record, execute, probe, resolve_parameters

#: environment of every local worker: one thread for every numeric library (processes give the parallelism)
SINGLE_THREADED = {"OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1", "MKL_NUM_THREADS": "1", "NUMBA_NUM_THREADS": "1"}
#: module every local worker preloads: it leaves Ctrl-C to the sweep process (no worker tracebacks)
WORKER_SETUP = "robot.sweep.worker_setup"
#: how long the driver tries to reach a running scheduler (``scheduler=ADDRESS``) before it gives up
CONNECT_TIMEOUT_S = 10.0
#: how often the driver looks for a stop request while it waits for runs (s; a run's end is seen this late at most)
STOP_POLL_S = 0.05


@dataclass
class SweepOutcome:
    """What a sweep did: runs in total, skipped (already done), run now, failed (stored), the store."""

    store: Path
    total: int
    skipped: int = 0
    ran: int = 0
    #: failed runs in the whole store (this execution's and earlier ones), by cause
    causes: dict[str, int] = field(default_factory=dict)
    wall_time: float = 0.0
    #: seconds from the first submission to the last run's completion (no cluster start, no probe)
    run_phase_time: float = 0.0
    #: the workers' summaries of the runs made now (status, cause, wall and integration times)
    summaries: list[dict[str, Any]] = field(default_factory=list)
    #: the sweep was stopped (``stop``) before every run was made; the runs in flight were dropped
    interrupted: bool = False
    #: runs the store holds for this sweep (done, current key; failed ones included): set when interrupted
    finished: int = 0

    @property
    def failed(self) -> int:
        return sum(self.causes.values())

    @property
    def exit_code(self) -> int:
        """0: every run reached its end; 1: some runs failed (recorded with their cause)."""
        return 1 if self.failed else 0

    def __str__(self) -> str:
        causes = ", ".join(f"{n} {cause}" for cause, n in sorted(self.causes.items()))
        return (
            f"sweep: {self.total} runs ({self.skipped} already done, {self.ran} run now, {self.total - self.failed} ok, "
            f"{self.failed} failed{': ' + causes if causes else ''}) in {self.wall_time:.1f} s; store {self.store}"
        )


def make_tasks(spec: SweepSpec) -> list[RunTask]:
    base_dir = str(spec.base.base_dir)
    return [
        RunTask(i, spec.design.index(i), key, scene.document, str(scene.path), base_dir, spec.analyses, spec.keep)
        for i, (scene, key) in enumerate(zip(spec.scenes, spec.run_keys))
    ]


def _field_sizes(fields, shapes: dict[str, tuple[int, ...]], spec, selectors: dict) -> dict[str, int]:
    sizes: dict[str, int] = {}
    for f in fields:
        if f.name not in selectors:
            continue
        shape = shapes[selectors[f.name].text]
        if len(shape) != len(f.dims):
            raise SweepError(
                f"analysis {spec.label!r}: input {f.name} = {selectors[f.name].text!r} has shape (records, ...) {shape}, the analysis needs dims {f.dims}",
                key=f"{spec.label}.{f.name}",
                value=selectors[f.name].text,
            )
        sizes.update({d: n for d, n in zip(f.dims, shape) if d != "time"})
    return sizes


def stored_fields(spec: SweepSpec) -> Iterator[tuple[Any, Any, str]]:
    """(analysis spec, output field, stored name) of every analysis output the store keeps (not those along ``time``)."""
    from robot.analysis import ANALYSES

    for a in spec.analyses:
        for f in ANALYSES[a.name].outputs:
            if "time" not in f.dims:  # per-record outputs vary in length: keep the signal instead ([keep])
                yield a, f, f"{a.label}_{f.name}"


def stored_arrays(spec: SweepSpec) -> tuple[str, ...]:
    """Every run array of the store of ``spec`` (the packed ones, the array outputs, the kept signals)."""
    series = [name for _, f, name in stored_fields(spec) if f.dims]
    kept = [s.name for s in spec.keep.arrays] if spec.keep is not None else []
    return (*RUN_ARRAYS, *series, *kept)


def _output_shapes(a, shapes: dict[str, tuple[int, ...]], document: dict) -> dict[str, tuple[int, ...]]:
    """The analysis's output shapes for the probe's input shapes; SweepError unless every size is an integer >= 0."""
    from robot.analysis import ANALYSES, AnalysisError

    analysis = ANALYSES[a.name]
    sizes = _field_sizes(analysis.inputs, shapes, a, a.inputs)
    try:
        output_shapes = analysis.output_shapes({"time": 0, **sizes}, **resolve_parameters(a, document))
    except (AnalysisError, TypeError, ValueError) as exc:
        raise SweepError(f"analysis {a.label!r}: {exc}", key=a.label, value=a.parameters) from None
    bad = {name: shape for name, shape in output_shapes.items() if not all(isinstance(n, (int, np.integer)) and n >= 0 for n in shape)}
    if bad:
        raise SweepError(
            f"analysis {a.label!r} ({a.name}): its parameters {a.parameters} give the output shape(s) {bad}; every size must be an integer >= 0: change the parameters",
            key=a.label,
            value=a.parameters,
        )
    return output_shapes


def plan_layout(spec: SweepSpec, path: Path, shapes: dict[str, tuple[int, ...]]) -> Layout:
    """Names, dimensions and sizes of every stored output (from the probe's signal shapes)."""
    statistics, series, kept = [], {}, {}
    first = spec.scenes[0].document
    output_shapes = {a.label: _output_shapes(a, shapes, first) for a in spec.analyses}
    for a, f, name in stored_fields(spec):
        if not f.dims:
            statistics.append(name)
        else:
            series[name] = Variable(tuple(f"{a.label}_{d}" for d in f.dims), output_shapes[a.label][f.name])
    if spec.keep is not None:
        for selector in spec.keep.arrays:
            extra = shapes[selector.text][1:]
            kept[selector.name] = Variable(("time", *(f"{selector.name}_dim{i + 1}" for i in range(len(extra)))), (spec.keep.samples, *extra))
    names = [*statistics, *series, *kept, *COUNTS, *TIMING, *spec.design.coords]
    clash = sorted({n for n in names if names.count(n) > 1} | (set(names) & {*RUN_ARRAYS, *PACKED.values()}))
    if clash:
        raise SweepError(f"sweep {spec.name}: output name(s) {clash} are used twice; change a label or an axis name", key="label", value=clash[0])
    return Layout(str(path), spec.design.dims, spec.design.shape, tuple(statistics), series, kept)


#: store attributes that say which runs a store holds: a store is resumed only by a sweep of the same values
RUN_ATTRIBUTES = ("scene", "t_end", "overrides", "design", "axes", "coordinates", "analyses")
#: store attributes that only name the sweep (file): brought up to date when a store is resumed
DESCRIPTIVE = ("sweep", "sweep_file")


def store_attrs(spec: SweepSpec) -> dict[str, Any]:
    return {
        "sweep": spec.name,
        "layout_key": spec.layout_key,
        "design": spec.design.kind,
        "scene": spec.base.name,
        "t_end": spec.t_end,
        "axes": {a.name: a.key if not a.linked else list(a.keys) for a in spec.axes},
        "coordinates": list(spec.design.coords),
        "overrides": {k: v for k, v in spec.overrides.items()},
        "analyses": [a.canonical() for a in spec.analyses],
        "sweep_file": str(spec.path) if spec.path else None,
    }


def scheduler_client(scheduler: str):
    """A client of the running scheduler at ``scheduler``; a malformed or unreachable address is bad input."""
    from distributed import Client

    try:
        return Client(scheduler, timeout=CONNECT_TIMEOUT_S)
    except (ValueError, TypeError) as exc:
        raise SweepError(
            f"--scheduler={scheduler!r} is not a dask scheduler address ({exc}); give one such as tcp://127.0.0.1:8786",
            key="scheduler",
            value=scheduler,
        ) from None
    except OSError as exc:
        raise SweepError(
            f"--scheduler={scheduler!r}: no dask scheduler could be reached at that address ({exc}); start one there or give another address",
            key="scheduler",
            value=scheduler,
        ) from None


@contextmanager
def dask_client(scheduler: str | None, workers: int | None) -> Iterator[Any]:
    """A client of the scheduler at ``scheduler``, or of a local cluster of ``workers`` processes."""
    import dask
    from distributed import Client, LocalCluster

    if scheduler is not None:
        with scheduler_client(scheduler) as client:
            yield client
        return
    n = workers or os.cpu_count() or 1
    environ = {**dask.config.get("distributed.nanny.pre-spawn-environ", {}), **SINGLE_THREADED}
    preload = [*dask.config.get("distributed.worker.preload", []), WORKER_SETUP]
    with dask.config.set({"distributed.nanny.pre-spawn-environ": environ, "distributed.worker.daemon": False, "distributed.worker.preload": preload}):
        with LocalCluster(n_workers=n, threads_per_worker=1, processes=True, dashboard_address=None, silence_logs=logging.ERROR) as cluster:
            with Client(cluster) as client:
                yield client


def _todo(spec: SweepSpec, path: Path, retry_failed: bool) -> list[int]:
    done, keys, status = finished_runs(path)
    valid = done & (keys.astype(object) == np.array(spec.run_keys, dtype=object))
    if retry_failed:
        valid &= status == 0
    return [i for i in range(spec.design.size) if not valid[i]]


def _canonical(value: Any) -> Any:
    """``value`` as its JSON text reads back (as stored attributes do): tuples are lists, numbers exact."""
    return json.loads(json.dumps(value, sort_keys=True, default=python_value))


def _shown(value: Any, limit: int = 120) -> str:
    text = json.dumps(value, sort_keys=True, default=python_value)
    return text if len(text) <= limit else text[: limit - 3] + "..."


def store_differences(spec: SweepSpec, attrs: dict[str, Any]) -> list[str]:
    """Why the store of attributes ``attrs`` holds other runs than those of ``spec`` (empty: it holds this sweep's).

    Compared: the layout key (axes, values, outputs, the analyses' output fields) and every attribute
    that describes the runs (:data:`RUN_ATTRIBUTES`): a store is only ever resumed by the sweep its
    attributes describe, so they never describe runs other than those it holds.
    """
    wanted = store_attrs(spec)
    differences = []
    if attrs.get("layout_key") != wanted["layout_key"]:
        differences.append("the layout (axes, values, outputs or an analysis's output fields)")
    for name in RUN_ATTRIBUTES:
        if _canonical(attrs.get(name)) != _canonical(wanted[name]):
            differences.append(f"{name}: stored {_shown(attrs.get(name))}, this sweep {_shown(wanted[name])}")
    return differences


def store_refusal(spec: SweepSpec, path: Path) -> SweepError | None:
    """Why the store at ``path`` cannot be resumed by ``spec`` (it holds other runs, or it is damaged), or None
    (no store, or one this sweep resumes: every array of it there and readable)."""
    try:
        attrs = existing_attrs(path)
        if attrs is None:
            return None
        differences = store_differences(spec, attrs)
        if not differences:
            check_store(path, stored_arrays(spec), (*spec.design.coords, *PACKED.values()))
            return None
    except SweepError as exc:  # damaged: --overwrite replaces it
        return exc
    return SweepError(
        f"{str(path)!r} holds the runs of another sweep ({'; '.join(differences)}): choose another --out, or pass --overwrite "
        "to replace it (deleted once the new sweep's probe run succeeded; all its runs are made again)",
        key="out",
        value=str(path.parent),
    )


def _describe(spec: SweepSpec, path: Path) -> None:
    """Bring the attributes that only name the sweep file (:data:`DESCRIPTIVE`) up to date in a store it resumes."""
    wanted = {k: v for k, v in store_attrs(spec).items() if k in DESCRIPTIVE}
    group = open_store(path)
    if any(_canonical(group.attrs.get(k)) != _canonical(v) for k, v in wanted.items()):
        open_store(path, mode="r+").attrs.update(wanted)


def _prepare_store(spec: SweepSpec, path: Path, client, tasks: list[RunTask], replace: bool) -> Layout:
    """Probe the first run on every worker (warm-up; the arrays' shapes), plan the layout, then create the store:
    an old one (``replace``) is deleted only now, once the new sweep is known to start."""
    try:
        probes = client.run(probe, tasks[0])
    except SweepError:
        raise
    except Exception as exc:
        raise SweepError(f"sweep {spec.name}: the probe run of the first point failed: {type(exc).__name__}: {exc}", key="probe", value=spec.design.points[0]) from None
    shapes = next(iter(probes.values()))["shapes"]
    layout = plan_layout(spec, path, shapes)
    if replace:
        remove_store(path)
    try:
        create_store(layout, spec.design.coords, store_attrs(spec))
    except Exception as exc:  # noqa: BLE001 - a store half created is no store: removed
        remove_store(path)
        raise SweepError(f"sweep {spec.name}: the store at {str(path)!r} could not be created ({type(exc).__name__}: {exc}); check --out", key="out", value=str(path.parent)) from None
    return layout


def _layout_of_store(spec: SweepSpec, path: Path) -> Layout:
    group = open_store(path)
    statistics = tuple(str(n) for n in read_array(path, group, "statistic"))
    fixed = {*RUN_ARRAYS, *PACKED.values(), *spec.design.coords}
    series, kept = {}, {}
    kept_names = {s.name for s in spec.keep.arrays} if spec.keep else set()
    for name in group.array_keys():
        if name in fixed:
            continue
        array = group[name]
        variable = Variable(tuple(array.metadata.dimension_names[len(spec.design.dims):]), tuple(array.shape[len(spec.design.dims):]))
        (kept if name in kept_names else series)[name] = variable
    return Layout(str(path), spec.design.dims, spec.design.shape, statistics, series, kept)


def _progress(total: int, enabled: bool | None):
    from tqdm import tqdm

    enabled = sys.stderr.isatty() if enabled is None else enabled
    return tqdm(total=total, unit="run", desc="sweep", disable=not enabled, dynamic_ncols=True)


def _never() -> bool:
    return False


def _completed(futures: dict, stop: Callable[[], bool]) -> Iterator[Any]:
    """The futures as they finish; ends early, leaving the rest in ``futures``, once ``stop()`` is true."""
    from distributed import as_completed

    pending = as_completed(futures)
    while not pending.is_empty() and not stop():
        batch = pending.next_batch(block=False)
        if not batch:
            time.sleep(STOP_POLL_S)
        for future in batch:
            if stop():
                return
            yield future


def _run_tasks(client, tasks: list[RunTask], layout: Layout, bar, stop: Callable[[], bool] = _never) -> list[dict[str, Any]]:
    """Submit the tasks, follow them; a task that raised (a worker lost) is recorded as failed.

    Once ``stop()`` is true the runs not finished are cancelled (a run in flight is not
    recorded: a resumed sweep makes it again) and the summaries so far are returned.
    """
    if stop():
        return []
    futures = {client.submit(execute, task, layout, key=f"run-{task.flat}-{task.key[:12]}", pure=False): task for task in tasks}
    summaries, failed = [], 0
    for future in _completed(futures, stop):
        task = futures.pop(future)
        try:
            summary = future.result()
        except Exception as exc:  # the worker died or the task could not run: the driver records it
            message = f"{type(exc).__name__}: {exc}"
            write_run(layout, task.index, {**blank_record(task, layout), "status": -1, "cause": "worker error", "message": message})
            summary = {"flat": task.flat, "status": -1, "cause": "worker error", "message": message}
        failed += summary["status"] != 0
        summaries.append(summary)
        bar.set_postfix(failed=failed, refresh=False)
        bar.update(1)
    if futures:
        client.cancel(list(futures))
    return summaries


def store_causes(path: Path) -> dict[str, int]:
    """Failed runs of the store, by cause."""
    group = open_store(path)
    ndim = run_ndim(path, group)
    status = read_array(path, group, "status", ndim).ravel()
    causes = np.asarray(read_array(path, group, "cause", ndim), dtype=object).ravel()
    out: dict[str, int] = {}
    for cause in causes[status == -1]:
        out[str(cause)] = out.get(str(cause), 0) + 1
    return out


def _holds(spec: SweepSpec, path: Path) -> bool:
    """There is a store at ``path`` and it is the one of ``spec`` (an interrupted ``--overwrite`` may have kept the old one)."""
    try:
        attrs = existing_attrs(path)
    except SweepError:  # a damaged root, not replaced
        return False
    return attrs is not None and not store_differences(spec, attrs)


def run_sweep(
    spec: SweepSpec,
    out: str | Path,
    *,
    scheduler: str | None = None,
    workers: int | None = None,
    progress: bool | None = None,
    overwrite: bool = False,
    retry_failed: bool = False,
    stop: Callable[[], bool] | None = None,
) -> SweepOutcome:
    """Run every run of ``spec`` that the store at ``out`` does not hold yet (module docstring).

    ``stop``: asked while the runs are waited for; once it returns true the sweep ends
    early (``interrupted``; the finished runs stay in the store, a resumed sweep skips them).
    """
    stop = stop or _never
    started = time.perf_counter()
    path = Path(out) / "sweep.zarr"
    refusal = store_refusal(spec, path)
    if refusal is not None and not overwrite:
        raise refusal
    replace = refusal is not None  # deleted by _prepare_store once the probe run succeeded
    create = replace or not (path / "zarr.json").is_file()
    tasks = make_tasks(spec)
    todo = list(range(len(tasks))) if create else _todo(spec, path, retry_failed)
    outcome = SweepOutcome(path, len(tasks), skipped=len(tasks) - len(todo))
    if not create:
        _describe(spec, path)
    if todo:
        path.parent.mkdir(parents=True, exist_ok=True)
        try:
            with dask_client(scheduler, workers) as client:
                layout = _prepare_store(spec, path, client, tasks, replace) if create else _layout_of_store(spec, path)
                with _progress(len(todo), progress) as bar:
                    submitted = time.perf_counter()
                    outcome.summaries = _run_tasks(client, [tasks[i] for i in todo], layout, bar, stop)
                    outcome.run_phase_time = time.perf_counter() - submitted
        except Exception:
            if not stop():
                raise
            # a terminal's Ctrl-C reaches the local workers too: one starting then fails; the stop is what happened
        outcome.ran = len(outcome.summaries)
        outcome.interrupted = outcome.ran < len(todo)
    holds = _holds(spec, path)  # an interrupted --overwrite may have kept the old store
    if outcome.interrupted:  # runs of spec the store holds (done with their current key, failed ones included)
        outcome.finished = spec.design.size - len(_todo(spec, path, retry_failed=False)) if holds else 0
    outcome.causes = store_causes(path) if holds else {}
    outcome.wall_time = time.perf_counter() - started
    return outcome
