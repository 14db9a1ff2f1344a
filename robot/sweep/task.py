"""What a worker does for one run: simulate, analyse, write the run's region of the store.

Workers are long-lived processes: the compiled kernels (numba), the analysis
registry and the opened store stay loaded between runs, so a run costs its
integration plus the model build, the outputs' evaluation and the writes
(``scripts/bench_sweep.py`` measures that overhead).
"""

from __future__ import annotations

import dataclasses
import time
import traceback
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from robot.sweep.spec import AnalysisSpec, KeepSpec, resolve_parameters
from robot.sweep.store import COUNTS, Layout, write_run

#: a probe run's horizon (s): enough for a few records, to learn the arrays' shapes
PROBE_HORIZON = 1e-4
#: record kinds of the uniform output grid (robot.integration.simulation)
_START, _OUTPUT = 3, 4


@dataclass(frozen=True)
class RunTask:
    """One run: its place in the dataset, its key and its resolved scene document."""

    flat: int
    index: tuple[int, ...]
    key: str
    document: dict[str, Any]
    scene_path: str
    base_dir: str
    analyses: tuple[AnalysisSpec, ...]
    keep: KeepSpec | None


def scene_of(task: RunTask, horizon: float | None = None):
    """The task's scene (validated again here, cheaply); with the keep grid's output step."""
    from robot.scene.loader import scene_from_document

    scene = scene_from_document(task.document, Path(task.scene_path), Path(task.base_dir))
    if horizon is not None:
        scene = dataclasses.replace(scene, duration=horizon)
    if task.keep is not None:
        step = scene.duration / (task.keep.samples - 1)
        scene = dataclasses.replace(scene, solver=dataclasses.replace(scene.solver, output_step=step))
    return scene


def _simulate(task: RunTask, horizon: float | None = None):
    from robot.run import build_run, run_scene
    from robot.sweep.signals import RunSignals

    run = build_run(scene_of(task, horizon))
    result = run_scene(run)
    return result, RunSignals(result, run)


def probe(task: RunTask) -> dict[str, Any]:
    """Shapes of every selected signal, from a run of :data:`PROBE_HORIZON` s (also warms the worker)."""
    result, signals = _simulate(task, PROBE_HORIZON)
    shapes = {}
    selectors = [s for a in task.analyses for s in a.inputs.values()] + list(task.keep.arrays if task.keep else ())
    for selector in selectors:
        shapes[selector.text] = selector(signals).shape
    return {"shapes": shapes, "records": len(result.t)}


def kept_values(selector, signals, t: np.ndarray, kind: np.ndarray, keep: KeepSpec, t_end: float) -> np.ndarray:
    """The signal at the uniform grid ``k t_end / (samples - 1)`` (the output records), NaN past a stop."""
    values = selector(signals)
    rows = (kind == _OUTPUT) | (kind == _START)
    step = t_end / (keep.samples - 1)
    slots = np.rint(t[rows] / step).astype(int)
    out = np.full((keep.samples, *values.shape[1:]), np.nan)
    ok = slots < keep.samples
    out[slots[ok]] = values[rows][ok]
    return out


def analyse(task: RunTask, signals, layout: Layout) -> tuple[np.ndarray, dict[str, np.ndarray], list[str]]:
    """Every analysis of the run: the packed scalar statistics, the array outputs, and one message per
    analysis that failed (its outputs stay NaN; the others' are kept)."""
    from robot.analysis import ANALYSES

    statistics = np.full(len(layout.statistics), np.nan)
    position = {name: i for i, name in enumerate(layout.statistics)}
    series, failures = {}, []
    for spec in task.analyses:
        analysis = ANALYSES[spec.name]
        try:
            arguments = {name: selector(signals) for name, selector in spec.inputs.items()}
            if analysis.needs_run:
                arguments["run"] = signals.run
            outputs = analysis(**arguments, **resolve_parameters(spec, task.document))
        except Exception as exc:  # this analysis cannot handle this run: the run is recorded as failed, naming it
            failures.append(f"analysis {spec.label!r} ({spec.name}): {type(exc).__name__}: {exc}")
            continue
        for output, value in outputs.items():
            name = f"{spec.label}_{output}"
            if name in position:
                statistics[position[name]] = float(value)
            elif name in layout.series:
                series[name] = value
    return statistics, series, failures


def blank_record(task: RunTask, layout: Layout) -> dict[str, Any]:
    """A run's values before it is made: NaN outputs, uncounted counts. Written under the run's own values,
    so a run made again never keeps a value of its former make that it did not produce (a fill value
    is stored as no chunk: a run that produces every value is written as before, byte for byte)."""
    record: dict[str, Any] = {"run_key": task.key, "t_reached": np.nan, "counts": np.full(len(COUNTS), -1, dtype=np.int64)}
    record["statistics"] = np.full(len(layout.statistics), np.nan)
    record.update({name: np.full(variable.shape, np.nan) for name, variable in {**layout.series, **layout.kept}.items()})
    return record


def _counts(result) -> np.ndarray:
    values = [getattr(result, name) if name != "nrestarts" else result.counts.get("n_restarts") for name in COUNTS]
    return np.array([-1 if v is None else int(v) for v in values], dtype=np.int64)


#: the ``cause`` stored for a run that reached its end (zarr string arrays hold no None)
NO_CAUSE = ""


def execute(task: RunTask, layout: Layout) -> dict[str, Any]:
    """Run, analyse and write one run; never raises for a failed run (it is recorded).

    Returns a summary for the driver's progress bar; its ``wall_time`` includes the
    writes (the stored ``timings`` cannot: they are written with the run).
    """
    started_wall, started_cpu = time.perf_counter(), time.process_time()
    record = blank_record(task, layout)
    integration = (np.nan, np.nan, np.nan)
    try:
        result, signals = _simulate(task)
        simulated = time.perf_counter() - started_wall
        integration = (simulated, result.counts.get("wall_time", np.nan), result.counts.get("cpu_time", np.nan))
        record.update(status=result.status, cause=result.cause or NO_CAUSE, message=result.message or "", t_reached=result.t_end, counts=_counts(result))
        if result.success:
            record["statistics"], series, failures = analyse(task, signals, layout)
            record.update(series)
            if failures:  # the other analyses' outputs are kept
                record.update(status=-1, cause="analysis error", message="; ".join(failures))
        if task.keep is not None:
            kind, t = result["record_kind"], result.t
            for selector in task.keep.arrays:
                record[selector.name] = kept_values(selector, signals, t, kind, task.keep, float(task.document["duration"]))
    except Exception as exc:  # the model could not be built or integrated: recorded, the sweep goes on
        last = traceback.extract_tb(exc.__traceback__)[-1]
        record.update(status=-1, cause="exception", message=f"{type(exc).__name__}: {exc} ({Path(last.filename).name}:{last.lineno})")
    wall, cpu = time.perf_counter() - started_wall, time.process_time() - started_cpu
    record["timings"] = np.array([wall, cpu, *integration])
    write_run(layout, task.index, record)
    written = time.perf_counter() - started_wall
    return {
        "flat": task.flat,
        "status": int(record["status"]),
        "cause": record["cause"],
        "wall_time": written,
        "simulate_wall_time": integration[0],
        "integration_wall_time": integration[1],
    }
