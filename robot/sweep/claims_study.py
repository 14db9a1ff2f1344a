"""The seed paper's claims against the reconstruction's free parameters (issue 18).

The unit of this study is a **triple** of runs: ``ideal``, ``compound`` and
``compound_misaligned`` with the same parameter set; :func:`robot.analysis.claims.evaluate_claims`
measures the five claims on each triple. The parameter sets come from sweep
files (``docs/sweep.md``) whose base scene is ``compound`` (the aligned case):
each design point's key paths (plus the file's ``[overrides]``) are applied to
both clearance scenes (``compound_misaligned`` extends ``compound``, so every
key of one is a key of the other). The ideal run does not depend on clearance
parameters: one per horizon serves every triple.

Runs are saved as result files under ``OUT/runs/`` named by a hash of (scene,
overrides, horizon), so an interrupted study resumes where it stopped; the
table is ``OUT/claims_study.json`` (one entry per parameter set: the overrides,
each claim's verdict and numbers) and ``OUT/claims_study.md``.

    python -m robot.sweep.claims_study robot/sweep/examples/claims_*.toml --out out/claims_study --workers 2

Exit codes: 0 the table is written; 1 interrupted (Ctrl-C) with runs saved (the
same command resumes); 2 bad input (a sweep file, ``--workers``, an output
folder that cannot be written), reported before any run; 130 interrupted before
any run was saved.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import signal
import sys
import tempfile
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable, Sequence

from robot.analysis.claims import ALIGNED, IDEAL, MISALIGNED, claims_json, evaluate_claims
from robot.analysis.studies.common import INTERRUPTED
from robot.errors import RobotError
from robot.io.atomic import atomic_write_text
from robot.sweep.errors import SweepError

CLEARANCE_SCENES = (ALIGNED, MISALIGNED)
#: robot.cli.common's exit codes (robot/sweep does not import robot/cli)
EXIT_OK, EXIT_INTERRUPTED_WITH_RUNS, EXIT_BAD_INPUT, EXIT_INTERRUPTED = 0, 1, 2, 130


@dataclass(frozen=True)
class ParameterSet:
    """One point of the study: a label, the scene key paths changed, the simulated horizon."""

    label: str
    overrides: dict[str, Any]
    t_end: float


def parameter_sets(sweep_files: Sequence[str | Path]) -> list[ParameterSet]:
    """Every design point of the sweep files (base scene ``compound``), in file order, duplicates dropped."""
    from robot.sweep.spec import load_sweep

    out, seen = [], set()
    for path in sweep_files:
        spec = load_sweep(path)
        if spec.base.name != ALIGNED:
            raise SweepError(f"sweep {spec.name}: a claims study varies scene {ALIGNED!r}, not {spec.base.name!r}", key="sweep.scene", value=spec.base.name)
        for point in spec.design.points:
            overrides = {**spec.overrides, **point}
            key = json.dumps([overrides, spec.t_end], sort_keys=True)
            if key in seen:
                continue
            seen.add(key)
            label = ", ".join(f"{k.split('.')[-1]}={v}" for k, v in point.items()) or "default"
            out.append(ParameterSet(f"{spec.name}: {label}", overrides, spec.t_end))
    return out


def run_file(out: Path, scene: str, overrides: dict[str, Any], t_end: float) -> Path:
    """Where the run of ``scene`` with ``overrides`` over ``t_end`` is saved: a hash of the resolved
    scene document (so a default given explicitly and the default itself share one run) and ``t_end``."""
    from robot.scene.loader import load_scene

    document = load_scene(scene).with_changes(overrides).document if overrides else load_scene(scene).document
    key = hashlib.sha256(json.dumps([document, t_end], sort_keys=True, default=str).encode()).hexdigest()[:16]
    return out / "runs" / f"{scene}_{key}.npz"


def _simulate(job: tuple[str, dict[str, Any], float, str]) -> tuple[str, str | None]:
    """Run one scene and save it (top level: runs in a worker process); an existing file is kept.

    Returns the path and, if the run could not start (the library's own error), its message."""
    from robot.errors import Error
    from robot.io.results import save_result
    from robot.run import simulate

    scene, overrides, t_end, path = job
    if not Path(path).exists():
        try:
            result = simulate(scene, overrides, t_end=t_end)
        except Error as exc:
            return path, f"{type(exc).__name__}: {exc}"
        if result.cause == INTERRUPTED:  # not the run of these parameters: not saved, so a resumed study makes it
            raise KeyboardInterrupt
        save_result(result, path)
    return path, None


def _outcomes(todo: list, workers: int):
    """(path, error) of each job as it finishes (in order), in worker processes when workers > 1.

    A stop (Ctrl-C) drops the jobs not started; the runs in progress finish (and are saved) first."""
    if workers > 1 and len(todo) > 1:
        pool = ProcessPoolExecutor(max_workers=workers)
        try:
            yield from pool.map(_simulate, todo)
        finally:
            pool.shutdown(wait=True, cancel_futures=True)
    else:
        yield from map(_simulate, todo)


def run_study(sets: Sequence[ParameterSet], out: Path, workers: int = 1, log: Callable[[str], None] = print) -> list[dict]:
    """Simulate every triple (missing runs only) and measure the claims on each; returns the table's entries."""
    from robot.io.results import load_result

    (out / "runs").mkdir(parents=True, exist_ok=True)
    jobs = {}
    for parameters in sets:
        jobs[str(run_file(out, IDEAL, {}, parameters.t_end))] = (IDEAL, {}, parameters.t_end)
        for scene in CLEARANCE_SCENES:
            jobs[str(run_file(out, scene, parameters.overrides, parameters.t_end))] = (scene, parameters.overrides, parameters.t_end)
    todo = [(*job, path) for path, job in jobs.items() if not Path(path).exists()]
    log(f"{len(sets)} parameter sets, {len(jobs)} runs, {len(todo)} to simulate")
    errors = {}
    for path, error in _outcomes(todo, workers):
        log(f"{'FAILED' if error else 'done'} {Path(path).name}{': ' + error if error else ''}")
        if error:
            errors[path] = error
    entries = []
    for parameters in sets:
        paths = {scene: run_file(out, scene, parameters.overrides if scene != IDEAL else {}, parameters.t_end) for scene in (IDEAL, *CLEARANCE_SCENES)}
        not_started = {scene: errors[str(path)] for scene, path in paths.items() if str(path) in errors}
        if not_started:
            entries.append({"label": parameters.label, "overrides": parameters.overrides, "t_end": parameters.t_end, "failed_runs": not_started, "claims": []})
            continue
        results = {scene: load_result(path) for scene, path in paths.items()}
        failed = {scene: r.message for scene, r in results.items() if not r.success}
        claims = claims_json(evaluate_claims(results, _period(parameters)))
        entries.append({"label": parameters.label, "overrides": parameters.overrides, "t_end": parameters.t_end, "failed_runs": failed, "claims": claims})
    return entries


def _period(parameters: ParameterSet) -> float:
    """The trajectory period of the parameter set's aligned scene (the claims' cycle)."""
    from robot.scene.loader import load_scene

    return float(load_scene(ALIGNED).with_changes(parameters.overrides).trajectory.period)


def headline(claim: dict) -> str:
    """The one or two numbers of a claim that decide its verdict, as table text."""
    numbers = claim["numbers"]
    label = claim["label"]
    if label == "a":
        return "; ".join(f"{k.removesuffix('_peak_N')} {v['aligned']:.0f}/{v['misaligned']:.0f}" for k, v in numbers.items() if isinstance(v, dict))
    if label == "b" and "contact_fraction" in numbers:
        low = min(numbers["contact_fraction"].values())
        return f"contact >= {low:.0%}; diff {numbers['ee_rms_difference_between_cases_m'] * 1e3:.3f} mm vs dev {numbers['ee_rms_deviation_from_ideal_m'] * 1e3:.3f} mm"
    if label == "c" and ALIGNED in numbers:
        return f"R1/S1 {numbers[ALIGNED]['R1_over_S1']:.2f} / {numbers[MISALIGNED]['R1_over_S1']:.2f}"
    if label == "d":
        return f"out-of-plane {numbers['S1_out_of_plane_peak_to_peak_m'] * 1e3:.3f} mm; ecc z {numbers['S1_eccentricity_z_range_m'] * 1e3:.3f} mm"
    if label == "e":
        return f"pos {numbers['ee_position']['relative']:.3g}, acc {numbers['ee_acceleration']['relative']:.3g}; y wander {numbers['ee_y_wander_m'] * 1e3:.2f} mm"
    return ""


def table_markdown(entries: list[dict]) -> str:
    """One row per parameter set: each claim's verdict (Y/N) and its deciding numbers."""
    mark = {"holds": "Y", "does not hold": "N"}
    lines = [
        "| parameter set | (a) | (b) | (c) | (d) | (e) |",
        "| --- | --- | --- | --- | --- | --- |",
    ]
    for entry in entries:
        cells = [f"{mark.get(c['verdict'], '-')} {headline(c)}" for c in entry["claims"]]
        failed = f" (failed: {', '.join(entry['failed_runs'])})" if entry["failed_runs"] else ""
        lines.append(f"| {entry['label']}{failed} | " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def workers_count(text: str) -> int:
    """argparse type of ``--workers``: an integer >= 1."""
    try:
        value = int(text)
    except ValueError:
        value = 0
    if value < 1:
        raise argparse.ArgumentTypeError(f"{text!r} is not an integer >= 1")
    return value


def writable_runs_folder(out: Path) -> Path:
    """``OUT/runs``, created and checked writable before any run (:class:`SweepError` otherwise)."""
    runs = out / "runs"
    try:
        runs.mkdir(parents=True, exist_ok=True)
        with tempfile.TemporaryFile(dir=runs):
            pass
    except OSError as exc:
        raise SweepError(f"--out={str(out)!r} cannot be written ({exc.strerror or exc}); choose another folder", key="out", value=str(out)) from None
    return runs


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m robot.sweep.claims_study", description=__doc__.split("\n\n")[0])
    parser.add_argument("sweeps", nargs="+", type=Path, help="sweep files whose base scene is 'compound'")
    parser.add_argument("--out", type=Path, default=Path("out/claims_study"))
    parser.add_argument("--workers", type=workers_count, default=1, help="processes running the simulations (default 1)")
    args = parser.parse_args(argv)
    try:
        sets = parameter_sets(args.sweeps)
        runs = writable_runs_folder(args.out)
    except RobotError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    # SIGTERM (a batch system's stop, `kill`) stops the study as Ctrl-C does: the runs saved are kept
    previous = signal.signal(signal.SIGTERM, _raise_interrupt)
    try:
        entries = run_study(sets, args.out, args.workers)
    except KeyboardInterrupt:
        return interrupted_exit(runs)
    finally:
        signal.signal(signal.SIGTERM, previous)
    atomic_write_text(args.out / "claims_study.json", json.dumps(entries, indent=2, default=float))
    atomic_write_text(args.out / "claims_study.md", table_markdown(entries))
    print(table_markdown(entries))
    return EXIT_OK


def _raise_interrupt(signum, frame) -> None:
    raise KeyboardInterrupt


def interrupted_exit(runs: Path) -> int:
    """Say where the saved runs are and how to resume; 1 if runs are saved, else 130."""
    saved = sum(not path.name.startswith(".") for path in runs.glob("*.npz"))  # not a killed write's temporary file
    if not saved:
        print("interrupted before any run was saved", file=sys.stderr)
        return EXIT_INTERRUPTED
    print(f"interrupted: the runs finished ({saved}) are saved in {runs}; run the same command again to resume (saved runs are kept)", file=sys.stderr)
    return EXIT_INTERRUPTED_WITH_RUNS


if __name__ == "__main__":
    sys.exit(main())
