"""The validation study: each scene with the Lagrange model, Newton-Euler and Exudyn; JSON and figures.

``clearance validate [--out DIR] [--scenes ...] [--duration SCENE=T ...]
[--method M] [--rtol R] [--atol A] [--max-step H]`` (= ``python scripts/validate.py``;
:mod:`robot.cli.validate`) calls :func:`run_validation`. Horizons (:func:`scene_durations`):
``--duration SCENE=T`` if given; else, for the default study's scenes
(:data:`DEFAULT_DURATIONS`), the ideal mechanism over one period of the
reference motion (1 s) and the clearance scenes over 0.5 s (the first impacts,
the transient of the misaligned bearing and a few tens of impacts), which keeps
the whole study to a few minutes on two cores; any other scene runs over its
own ``duration``.

Before any run, :func:`check_scenes` builds each scene and checks that every
requested engine models it (:func:`robot.validation.newton_euler.check_supported`,
:func:`robot.validation.exudyn_model.check_supported`): a joint, closure,
actuator, load or body an engine does not model is refused with
:class:`robot.validation.bodies.UnsupportedFeatureError` naming the scene, the
engine and the feature, so that no engine silently computes another mechanism.

Settings: the Lagrange model and Newton-Euler both use the validation's pinned
integrator :data:`robot.validation.settings.VALIDATION_SOLVER` (RK45, rtol 1e-7,
atol 1e-9, max_step 1e-3 s), **not** the scene's ``[solver]`` table, so the
study and its thresholds do not change when a scene's production solver does
(``--method``, ``--rtol``, ``--atol``, ``--max-step``, ``--first-step`` override
it for both engines; ``validation.json`` records the setting used and the
scene's own). Exudyn uses generalized-alpha with fixed steps
(:data:`EXUDYN_SETTINGS`: 1e-4 s for the ideal mechanism, 1e-5 s with
clearance, where one impact lasts 0.1-0.3 ms).
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import math
import time
from pathlib import Path
from typing import Callable, Sequence

import numpy as np
import pinocchio as pin

from robot.errors import SceneError
from robot.integration.solvers import METHODS
from robot.io.atomic import atomic_write_text
from robot.model.platform_kinematics import platform_state
from robot.run import Run, build_run, run_scene
from robot.integration.simulation import SolverOptions
from robot.scene.loader import load_scene
from robot.scene.loader import check_steps
from robot.scene.loader import solver_options as scene_solver_table
from robot.validation import comparison as CMP
from robot.validation import exudyn_model as EX
from robot.validation import newton_euler as NE
from robot.validation.bodies import UnsupportedFeatureError, read_geometry
from robot.validation.settings import VALIDATION_SOLVER, check_solver, validation_solver, with_solver

DEFAULT_SCENES = ("ideal", "spherical", "compound", "compound_misaligned")
DEFAULT_DURATIONS = {"ideal": 1.0, "spherical": 0.5, "compound": 0.5, "compound_misaligned": 0.5}
EXUDYN_SETTINGS = {
    "ideal": EX.ExudynSettings(step_size=1e-4, spectral_radius=0.5, newton_relative_tolerance=1e-12, newton_absolute_tolerance=1e-14),
    "clearance": EX.ExudynSettings(step_size=1e-5, spectral_radius=0.5, newton_relative_tolerance=1e-10, newton_absolute_tolerance=1e-12),
}
ENGINES = ("lagrange", "newton_euler", "exudyn")
#: the options that change the validation solver (``--method``, ``--rtol``, ...), named as the [solver] keys
SOLVER_OPTIONS = ("method", "rtol", "atol", "max_step", "first_step")


def _no_stop() -> str | None:
    """The ``stop_reason`` of a study nobody stops (the library's callers, the tests)."""
    return None


def exudyn_settings_for(run) -> EX.ExudynSettings:
    return EXUDYN_SETTINGS["clearance" if run.scene.clearances else "ideal"]


def prescribes_end_effector(run) -> bool:
    """Whether the drive prescribes the end effector's motion: a platform-pose drive does, a joint drive (or none) does not."""
    return run.layout is not None


def ideal_positions(run, t: np.ndarray) -> np.ndarray:
    """Prescribed platform-origin position at the times t (the ideal mechanism's end effector; platform-pose drives only)."""
    out = np.empty((len(t), 3))
    for i, ti in enumerate(t):
        pose, _, _ = run.dynamics.drive.pose(float(ti))
        out[i] = platform_state(run.layout, pose).position
    return out


def _sites(run) -> list[str]:
    return [c.joint for c in run.scene.clearances]


def lagrange_body_origins(run, q: np.ndarray) -> np.ndarray:
    """(records, bodies, 3) world positions of the bodies' link-frame origins (the cross-check engines' bodies, in their order)."""
    model = run.mechanism.model
    data = model.createData()
    frames = [model.getFrameId(body.name, pin.FrameType.BODY) for body in read_geometry(run.mechanism.description).bodies]
    out = np.full((len(q), len(frames), 3), np.nan)
    for i, qi in enumerate(q):
        if np.all(np.isfinite(qi)):
            pin.framesForwardKinematics(model, data, qi)
            out[i] = [data.oMf[frame].translation for frame in frames]
    return out


def lagrange_series(run) -> CMP.EngineSeries:
    started = time.perf_counter()
    result = run_scene(run)
    wall = time.perf_counter() - started
    contact = {site: np.sum(result[f"{site}_normal_force"], axis=1) for site in _sites(run)}
    penetration = {site: np.max(result[f"{site}_penetration"], axis=1) for site in _sites(run)}
    onsets = result["event_t"][result["event_is_onset"]] if "event_t" in result.arrays else np.zeros(0)
    return CMP.EngineSeries(
        "lagrange", result["t"], result["driving_force"], result["ee_position"], contact, np.unique(onsets), wall, result.success, result.message,
        integration_time=float(result.counts["wall_time"]), penetration=penetration,
        solver={key: result.metadata[key] for key in ("method", "rtol", "atol", "max_step")},
        body_origins=lagrange_body_origins(run, result["q"]),
    )


def newton_euler_series(run, t_eval: np.ndarray) -> tuple[CMP.EngineSeries, CMP.EngineSeries]:
    """The Newton-Euler run at its own records, and sampled at ``t_eval`` (dense output)."""
    result = NE.simulate(run, t_eval=t_eval)
    sites = _sites(run)
    onsets = np.unique([t for t, _, kind in result.run.events if kind == "onset"])
    a, e = result.arrays, result.eval_arrays

    def series(arrays):
        contact = {site: np.sum(arrays[f"{site}_normal_force"], axis=1) for site in sites}
        penetration = {site: np.max(arrays[f"{site}_penetration"], axis=1) for site in sites}
        return CMP.EngineSeries(
            "newton_euler", arrays["t"], arrays["driving_force"], arrays["ee_position"], contact, onsets, result.wall_time, result.success, result.run.message,
            integration_time=result.run.wall_time, penetration=penetration, solver=dict(result.run.settings),
            body_origins=arrays["body_origins"],
        )

    return series(a), series(e)


def exudyn_series(run, settings: EX.ExudynSettings) -> CMP.EngineSeries:
    result = EX.simulate(run, settings)
    contact = {site: np.sum(result.contact[site]["normal_force"], axis=1) for site in _sites(run)}
    penetration = {site: np.max(result.contact[site]["penetration"], axis=1) for site in _sites(run)}
    onsets = []
    for site in _sites(run):
        pen = result.contact[site]["penetration"]
        entering = (pen[1:] > 0) & ~(pen[:-1] > 0)
        onsets.extend(result.t[1:][np.any(entering, axis=1)])
    return CMP.EngineSeries(
        "exudyn", result.t, result.driving_force, result.ee_position, contact, np.unique(onsets), result.wall_time, result.success, result.message,
        integration_time=result.solve_time, penetration=penetration,
        solver={"method": "GeneralizedAlpha (Exudyn)", **settings.__dict__}, body_origins=result.body_origins,
    )


def compare_scene(
    scene: str, duration: float, engines=ENGINES, progress=print, solver: SolverOptions = VALIDATION_SOLVER,
    stop_reason: Callable[[], str | None] = _no_stop,
) -> tuple[dict | None, dict]:
    """Run one scene with the engines; returns (metrics for the JSON, series for the figures).

    ``scene``: a shipped scene name or a scene file. The Lagrange and Newton-Euler runs
    both use ``solver`` (default :data:`VALIDATION_SOLVER`), whatever the scene's
    ``[solver]`` says; ``metrics["validation_solver"]`` and ``metrics["scene_solver"]``
    record both. ``stop_reason()``: why the study must stop (``"SIGINT"``, ...) or
    ``None``; asked before every engine run, so that a stop skips the runs not yet
    started but keeps the finished ones (``metrics["engines_not_run"]`` lists the
    skipped engines). Stopped before the first run: ``(None, {})``.
    :func:`run_validation` checks every scene first (:func:`check_scenes`); called
    alone, an engine that does not model the scene raises ``UnsupportedFeatureError``
    when it builds its model, before its own integration.
    """
    check_solver(solver, newton_euler="newton_euler" in engines)
    built = build_run(scene, duration=duration)
    run = with_solver(built, solver)
    if stop_reason():
        return None, {}
    series, not_run = _run_engines(scene, run, engines, progress, stop_reason)
    metrics: dict = {
        "duration_s": duration,
        "sites": _sites(run),
        "validation_solver": dataclasses.asdict(solver),
        "scene_solver": dataclasses.asdict(built.scene.solver),
        "engines": {},
    }
    if "exudyn" in series:
        metrics["exudyn_settings"] = exudyn_settings_for(run).__dict__.copy()
    if not_run:
        metrics["engines_not_run"] = not_run
    for s in series.values():  # no ideal motion without a platform-pose drive: the statistic is then None
        s.ee_ideal = ideal_positions(run, s.t) if prescribes_end_effector(run) else None
    lagrange = series["lagrange"]
    window_end = lagrange.first_onset  # inf for the ideal mechanism: whole run
    stats_ref = CMP.statistics(lagrange, duration)
    for name in series:
        if not name.endswith("@lagrange"):
            metrics["engines"][name] = _engine_metrics(name, series, duration, stats_ref, window_end)
    metrics["first_impact_s"] = None if not math.isfinite(window_end) else window_end
    return metrics, series


def _run_engines(scene: str, run, engines, progress, stop_reason: Callable[[], str | None]) -> tuple[dict, list[str]]:
    """The engines' series, the Lagrange model first, and the engines not run because a stop was asked for.

    The engines after the Lagrange model are compared with its records, so it
    always runs; each other engine starts only if no stop is pending.
    """
    solver, duration = run.scene.solver, run.scene.duration
    progress(f"[{scene}] Lagrange ({duration} s, {solver.method} rtol {solver.rtol:g} atol {solver.atol:g} max_step {solver.max_step:g} s)")
    lagrange = lagrange_series(run)
    series = {"lagrange": lagrange}
    others = [name for name in ENGINES[1:] if name in engines]
    for index, name in enumerate(others):
        if stop_reason():
            return series, others[index:]
        if name == "newton_euler":
            progress(f"[{scene}] Newton-Euler")
            series["newton_euler"], series["newton_euler@lagrange"] = newton_euler_series(run, lagrange.t)
        else:
            settings = exudyn_settings_for(run)
            progress(f"[{scene}] Exudyn (h = {settings.step_size} s)")
            series["exudyn"] = exudyn_series(run, settings)
    return series, []


def _engine_metrics(name: str, series: dict, duration: float, stats_ref: dict, window_end: float) -> dict:
    """One engine's entry of ``metrics["engines"]``: its outcome, cost, statistics and deviations from the Lagrange model."""
    s, lagrange = series[name], series["lagrange"]
    entry = {
        "success": s.success,
        "message": s.message,
        "t_last_record_s": float(s.t[-1]) if len(s.t) else 0.0,
        "solver": s.solver,
        "wall_time_s": s.wall_time,
        "integration_wall_time_s": s.integration_time,
        "n_records": int(len(s.t)),
        "statistics": CMP.statistics(s, duration),
    }
    if name == "lagrange":
        return entry
    entry["statistics_relative_to_lagrange"] = CMP.compare_statistics(entry["statistics"], stats_ref)
    if name == "newton_euler":
        sampled = series["newton_euler@lagrange"]
        entry["pointwise_before_first_impact"] = CMP.pointwise_on_reference_times(sampled, lagrange, window_end)
        entry["pointwise_whole_run"] = CMP.pointwise_on_reference_times(sampled, lagrange, math.inf)
        entry["separation_time_1um_s"] = CMP.separation_time(sampled, lagrange, same_times=True)
    else:
        entry["pointwise_before_first_impact"] = CMP.pointwise_interpolated(s, lagrange, window_end)
        entry["separation_time_1um_s"] = CMP.separation_time(s, lagrange, same_times=False)
    return entry


def summary_table(results: dict) -> str:
    """A plain-text table of the main numbers."""
    lines = []
    for scene, m in results["scenes"].items():
        vs = m.get("validation_solver", {})
        solver = f", {vs['method']} rtol {vs['rtol']:g} atol {vs['atol']:g} max_step {vs['max_step']:g} s" if vs else ""
        lines.append(f"{scene} ({m['duration_s']} s, first impact {m['first_impact_s']}{solver})")
        for name, e in m["engines"].items():
            pw = e.get("pointwise_before_first_impact", {})
            st = e["statistics"]
            peaks = ", ".join(f"{k} peak {v['peak_N']:.1f} N mean {v['mean_N']:.2f} N rms {v['rms_N']:.2f} N" for k, v in st["contact"].items())
            line = f"  {name:13s} wall {e['wall_time_s']:7.1f} s" + (_pointwise_text(pw) if pw else "")
            line += f"  impacts {st['n_impacts']}  {peaks}"
            if st.get("rms_ee_deviation_from_ideal_m") is not None:
                line += f"  EE rms dev {st['rms_ee_deviation_from_ideal_m']:.3g} m"
            if e.get("separation_time_1um_s") is not None:
                line += f"  separates (1 um) at {e['separation_time_1um_s']:.4f} s"
            if not e["success"]:
                line += f"  FAILED: {e['message']}"
            lines.append(line)
        if m.get("engines_not_run"):
            lines.append(f"  not run: {', '.join(m['engines_not_run'])}")
    return "\n".join(lines)


def _pointwise_text(pw: dict) -> str:
    """The table's largest deviations from the Lagrange model: driving forces (dF), end effector (dEE), body origins (dBodies).

    A quantity that was not compared (no actuator, nothing in the window) is left out.
    """
    text = ""
    if pw.get("driving_force_max_abs_N") is not None:
        text += f"  dF {pw['driving_force_max_abs_N']:.3g} N ({pw['driving_force_max_rel']:.2g})"
    if pw.get("ee_position_max_m") is not None:
        text += f"  dEE {pw['ee_position_max_m']:.3g} m"
    if pw.get("body_position_max_m") is not None:
        text += f"  dBodies {pw['body_position_max_m']:.3g} m"
    return text


def failure_report(results: dict, path: Path) -> str:
    """What went wrong, for the console: each failed engine run with its time and cause, and a stop with what it skipped.

    Empty when the study succeeded. The comparison table above it is then of
    partial runs, so the report says so and where the partial results are.
    """
    if results.get("success", True):
        return ""
    failed, stop = results.get("failed_runs", []), results.get("interrupted")
    problems = ([f"{len(failed)} engine run(s) failed"] if failed else []) + ([f"stopped by {stop['cause']}"] if stop else [])
    figures = " and the figures" if any(m.get("figures") for m in results["scenes"].values()) else ""
    lines = [f"validation incomplete: {', '.join(problems)}; what was computed is in {path}{figures}"]
    for run in failed:
        duration = results["scenes"][run["scene"]]["duration_s"]
        lines.append(
            f"  {run['scene']}: the {run['engine']} run failed ({duration:g} s asked, last record at t = {run['t_last_record_s']:.6g} s): {run['message']}"
        )
    if stop:
        skipped = "; ".join(f"{scene}: {', '.join(engines)}" for scene, engines in stop["not_run"].items())
        lines.append(f"  {stop['cause']}: not run: {skipped}" if skipped else f"  {stop['cause']} came during the last run (stopped there, or finished if it was Exudyn's): no run was skipped")
    return "\n".join(lines)


def parse_args(argv=None) -> argparse.Namespace:
    parser = argparse.ArgumentParser(description="Cross-check the Lagrange model against Newton-Euler and Exudyn.")
    add_arguments(parser)
    return parser.parse_args(argv)


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """The study's options (``clearance validate``, :mod:`robot.cli.validate`)."""
    parser.add_argument("--out", default="results/validation", help="output directory (default results/validation)")
    parser.add_argument("--scenes", nargs="+", default=list(DEFAULT_SCENES), help=f"scenes (default {' '.join(DEFAULT_SCENES)})")
    parser.add_argument(
        "--duration", nargs="*", default=[], metavar="SCENE=T",
        help="simulated time of a scene (s); default: the study's horizons for its default scenes "
        f"({', '.join(f'{k} {v:g} s' for k, v in DEFAULT_DURATIONS.items())}), every other scene its own duration",
    )
    parser.add_argument("--engines", nargs="+", default=list(ENGINES[1:]), choices=ENGINES[1:], help="engines besides the Lagrange model")
    parser.add_argument("--exudyn-step", type=float, default=None, help="Exudyn step size with clearance joints (default 1e-5 s)")
    v = VALIDATION_SOLVER
    group = parser.add_argument_group(
        "validation solver",
        "integrator of the Lagrange and the Newton-Euler runs, the same for both; the scenes' [solver] tables are not used "
        f"(default: robot.validation.settings.VALIDATION_SOLVER = {v.method}, rtol {v.rtol:g}, atol {v.atol:g}, max_step {v.max_step:g} s)",
    )
    group.add_argument("--method", choices=list(METHODS), default=None, help=f"integrator (default {v.method}; with newton_euler: RK45, RK23 or DOP853)")
    group.add_argument("--rtol", type=float, default=None, help=f"relative tolerance (default {v.rtol:g})")
    group.add_argument("--atol", type=float, default=None, help=f"absolute tolerance (default {v.atol:g})")
    group.add_argument("--max-step", type=float, default=None, help=f"largest step, s (default {v.max_step:g}; also the largest spacing of the compared records)")
    group.add_argument("--first-step", type=float, default=None, help="first step, s (the step size of fixed-step methods)")
    parser.add_argument("--no-figures", action="store_true", help="write validation.json only")


def main(argv=None) -> int:
    """Run the study of ``argv`` (``clearance validate`` is the command line); 0 if every run succeeded, else 1."""
    args = parse_args(argv)
    try:
        solver_from_options(args)
        check_scenes(args)
    except ValueError as exc:  # UnsupportedFeatureError is one too
        raise SystemExit(f"validate: {exc}") from None
    return 0 if run_validation(args, checked=True)["success"] else 1


def solver_from_options(args: argparse.Namespace) -> SolverOptions:
    """The validation solver with ``--method/--rtol/--atol/--max-step/--first-step`` applied, checked before any run.

    The options get the ranges of a scene's ``[solver]`` table (checked by the
    scene loader's own code, so the two cannot drift apart), ``--first-step`` may
    not exceed the largest step, and the method must suit the engines
    (:func:`robot.validation.settings.check_solver`). ``ValueError`` names the
    option, its value and the valid range.
    """
    given = {name: getattr(args, name) for name in SOLVER_OPTIONS if getattr(args, name) is not None}
    try:
        scene_solver_table(given, "validation solver")
    except SceneError as exc:
        raise ValueError(_option_message(exc)) from None
    max_step = given.get("max_step", VALIDATION_SOLVER.max_step)
    first_step = given.get("first_step")
    if first_step is not None and first_step > max_step:
        raise ValueError(f"--first-step={first_step!r} is out of range (0, {max_step:g}]: the first step cannot exceed the largest step (--max-step {max_step:g} s)")
    return validation_solver(**given, newton_euler="newton_euler" in args.engines)


def _option_message(exc: SceneError) -> str:
    """The scene loader's message about a ``[solver]`` key, worded for the command-line option of that name."""
    key = str(exc.key)
    option = "--" + key.replace("_", "-")
    detail = str(exc).split(": ", 1)[-1]  # the loader prefixes where the key is
    if not detail.startswith(f"{key}="):
        return f"{option}: {detail}"
    scene_range = f" (the range of a scene's [solver] {key})" if "out of range" in detail else ""
    return f"{option}{detail[len(key):]}{scene_range}"


def scene_durations(args: argparse.Namespace) -> dict[str, float]:
    """Each scene's simulated time: ``--duration SCENE=T``; else :data:`DEFAULT_DURATIONS` (the default study's scenes); else the scene's own ``duration``."""
    durations = dict(DEFAULT_DURATIONS)
    for item in args.duration:
        scene, _, value = item.partition("=")
        try:
            durations[scene] = float(value)
        except ValueError:
            raise SystemExit(f"--duration {item!r}: expected SCENE=SECONDS") from None
    return {scene: durations[scene] if scene in durations else load_scene(scene).duration for scene in args.scenes}


def check_scenes(args: argparse.Namespace) -> None:
    """Build every scene of ``args`` and check that each engine of ``args.engines`` models it; nothing is run.

    ``UnsupportedFeatureError`` (exit status 2 on the command line) naming the
    scene, the engine, the feature and what the engine supports.
    """
    durations = scene_durations(args)
    solver = solver_from_options(args)
    for scene in args.scenes:
        run = build_run(scene, duration=durations[scene])
        try:  # the validation solver's steps against the scene's own limits (limits.min_step), as a scene's are
            check_steps(solver, run.scene.limits, f"--scenes {scene}")
        except SceneError as exc:
            raise ValueError(f"{_option_message(exc)} (scene {scene}'s limits)") from None
        check_engines(scene, run, args.engines)


def check_engines(scene: str, run: Run, engines: Sequence[str]) -> None:
    """``UnsupportedFeatureError`` if an engine of ``engines`` does not model the built ``run`` of ``scene`` (see :func:`check_scenes`)."""
    checks = {"newton_euler": NE.check_supported, "exudyn": EX.check_supported}
    for name in engines:
        if name not in checks:
            continue
        try:
            checks[name](run)
        except UnsupportedFeatureError as exc:
            raise UnsupportedFeatureError(f"--scenes {scene}: the {name} engine does not model this scene: {exc}", key="scenes", value=scene) from None


def run_validation(args: argparse.Namespace, stop_reason: Callable[[], str | None] = _no_stop, *, checked: bool = False) -> dict:
    """Run the study of ``args`` (options checked: :func:`solver_from_options`); returns what validation.json holds.

    First, unless ``checked`` (the caller ran it), :func:`check_scenes`: a scene
    an engine does not model raises ``UnsupportedFeatureError`` before any run
    and before anything is written.

    Nothing computed is lost: after every scene, validation.json is rewritten
    (atomically) and the scene's figures drawn, failed runs included (their
    records up to the failure). A failed engine run does not stop the study: the
    other engines and scenes still say something. ``stop_reason()`` (the command
    line's signal handling) stops it before the next engine run; the runs skipped
    are listed under ``interrupted``. ``results["success"]``: every run reached
    its end and nothing was skipped.
    """
    if not checked:
        check_scenes(args)
    durations = scene_durations(args)
    if args.exudyn_step is not None:
        EXUDYN_SETTINGS["clearance"] = dataclasses.replace(EXUDYN_SETTINGS["clearance"], step_size=args.exudyn_step)
    solver = solver_from_options(args)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    results = {
        "description": "Lagrange model (robot.dynamics.equations) against Newton-Euler (robot.validation.newton_euler) and Exudyn (robot.validation.exudyn_model); see docs/validation.md",
        "validation_solver": dataclasses.asdict(solver),
        "scenes": {},
    }
    not_run: dict[str, list[str]] = {}
    started = time.perf_counter()
    for scene in args.scenes:
        metrics, series = (None, {}) if stop_reason() else compare_scene(
            scene, durations[scene], ("lagrange", *args.engines), solver=solver, stop_reason=stop_reason
        )
        if metrics is None:
            not_run[scene] = ["lagrange", *args.engines]
            continue
        results["scenes"][scene] = metrics
        if metrics.get("engines_not_run"):
            not_run[scene] = list(metrics["engines_not_run"])
        if not args.no_figures:
            from robot.validation.figures import scene_figures

            metrics["figures"] = [p.name for p in scene_figures(scene, series, metrics, out)]
        write_results(results, out, not_run, stop_reason())
    results["total_wall_time_s"] = time.perf_counter() - started
    if not results["scenes"]:  # stopped before the first run: no file to write (an older one stays as it was)
        return study_outcome(results, not_run, stop_reason())
    path = write_results(results, out, not_run, stop_reason())
    print(summary_table(results))
    report = failure_report(results, path)
    print(report or f"wrote {path}")
    return results


def study_outcome(results: dict, not_run: dict[str, list[str]], stop: str | None) -> dict:
    """Record in ``results`` whether the study succeeded, which engine runs failed and what a stop skipped."""
    results["failed_runs"] = [
        {"scene": scene, "engine": name, "t_last_record_s": entry["t_last_record_s"], "message": entry["message"]}
        for scene, metrics in results["scenes"].items()
        for name, entry in metrics["engines"].items()
        if not entry["success"]
    ]
    results["interrupted"] = {"cause": stop, "not_run": not_run} if stop else None
    results["success"] = not results["failed_runs"] and not stop and not not_run
    return results


def write_results(results: dict, out: Path, not_run: dict[str, list[str]], stop: str | None) -> Path:
    """Write OUT/validation.json atomically (a reader never sees half a file; a stop mid-write keeps the last one)."""
    study_outcome(results, not_run, stop)
    return atomic_write_text(out / "validation.json", json.dumps(_clean(results), indent=2))


def _clean(value):
    """JSON-ready copy: numpy scalars and arrays to Python, non-finite floats to null."""
    if isinstance(value, dict):
        return {str(k): _clean(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_clean(v) for v in value]
    if isinstance(value, np.ndarray):
        return _clean(value.tolist())
    if isinstance(value, (np.floating, np.integer, np.bool_)):
        value = value.item()
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value
