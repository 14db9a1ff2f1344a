"""Where methods fail: failure boundaries, each failure reported with its cause.

Three maps (``clearance work-precision`` runs them, ``docs/work-precision.md``
reports them):

1. **step size against contact stiffness** (fixed-step methods, and the mean
   step an explicit variable-step method is held to): every contact stiffness
   of the scene is scaled by the same factor, the Young's modulus of every
   material (each stiffness a contact law derives from its materials is
   proportional to E*) and every stiffness a ``[[clearance]]`` table gives
   explicitly (``stiffness``, ``radial_stiffness``, ...); checked on the laws'
   parameters, and a scene whose stiffness does not follow them is refused
   before any run (:func:`scaled_stiffness`);
2. **Baumgarte gains** (alpha, beta grid): max constraint drift, cost and
   blow-up, for adaptive and for fixed-step methods;
3. **hidden contact onsets**: variable-step methods at loose tolerances, with
   and without the guard that scans each step for a contact starting and ending
   inside it (``SolverOptions.hidden_contacts``): contact onsets found, onsets
   found only by the guard, how deep a step ran into contact before being cut
   back to the onset (relative to the clearance), failures.

A cell of maps 1 and 2 says what a user needs to know of the run (``result``):

* the failure cause, if it failed (penetration beyond the physical bound,
  non-finite state, Newton divergence, constraint drift, ...);
* ``inaccurate`` (:data:`INACCURATE`): it finished, but a measure of
  :data:`THRESHOLDS` is beyond its threshold against a tight reference run of
  the same scene over the same horizon (``inaccurate_by`` names them; the
  measures are in ``errors``);
* ``accurate`` (:data:`OK`): it finished and every measure is within its threshold;
* ``no reference`` (:data:`UNCHECKED`): it finished, but the reference run
  failed, so its accuracy is unknown.

Every cell also has ``finished``: True when the run ended without a failure cause
(``result`` was ``"ok"`` for it before the classification split that into
``accurate`` and ``inaccurate``). A cell of the hidden-contact map is ``"ok"``
(:data:`FINISHED`) or the failure cause, and has ``finished`` too.

The reference (:func:`robot.analysis.studies.work_precision.reference`) is
DOP853 at rtol 1e-11 checked against rtol 1e-10: pointwise measures are taken
on the output grid (:data:`OUTPUT_STEP`) of the window where the two agree to
1e-8 m. The measures are :func:`robot.analysis.studies.work_precision.errors`. The
stiffness map's ``boundary`` is the largest step that finished (as before the
classification), ``boundary_accurate`` the largest accurate one.

Every run goes through :func:`robot.integration.simulation.integrate`, which never raises on
divergence: the maps record ``result`` and ``message``. A map stopped by the user
(Ctrl-C, or ``stop()`` true between runs) raises
:class:`robot.analysis.studies.common.StudyStopped` carrying the map
filled so far.
"""

from __future__ import annotations

import dataclasses
import math
from functools import partial
from pathlib import Path
from typing import Callable

import numpy as np

from clearance_contact import ContactError, joint_type
from robot.dynamics.equations import Baumgarte
from robot.errors import SceneError
from robot.run import Run, build_run
from robot.scene.loader import Scene, load_scene
from robot.integration.simulation import SolverOptions
from robot.analysis.studies import work_precision as wp
from robot.analysis.studies.common import INTERRUPTED, Outcome, StudyStopped, run_or_stop, save_png, simulate

#: a run that finished with every measure of THRESHOLDS within its threshold
OK = ACCURATE = "accurate"
#: a run that finished without a failure cause, with a measure beyond its threshold
INACCURATE = "inaccurate"
#: a run that finished, but whose reference run failed: its accuracy is unknown
UNCHECKED = "no reference"
#: a run of the hidden-contact map that finished (that map measures the peak forces only), and a finished
#: cell of a stiffness or gain map written before the classification
FINISHED = "ok"
#: results that are not failures
NOT_FAILED = (OK, INACCURATE, UNCHECKED, FINISHED)


def _cause(outcome) -> str:
    return FINISHED if outcome.success else (outcome.cause or "failed")


def finished(cell: dict) -> bool:
    """Whether a map cell's run ended without a failure cause (its ``finished``; a map written before it had
    the flag: from its ``result``)."""
    return bool(cell["finished"]) if "finished" in cell else cell.get("result") in NOT_FAILED


# --------------------------------------------------------------------------------------
# classification of a finished run against a tight reference
# --------------------------------------------------------------------------------------

#: the thresholds a finished map cell is checked against (docs/work-precision.md, "Where methods fail"):
#: the engineering accuracy of the work-precision study (end effector, peak contact forces, drift) and,
#: since a map cell must say whether its forces can be used, the driving forces and the energy balance
THRESHOLDS = {
    "ee": wp.EE_TARGET,  # m: max |p_ee - p_ee,ref| on the output grid of the comparable window
    "driving": 1e-2,  # max |F - F_ref| / max |F_ref| over the actuators, same grid and window
    "peak_force": wp.PEAK_TARGET,  # max over clearance joints of |peak - peak_ref| / peak_ref over [0, T]
    # the run's max |Delta(T + V) - W| (J) over the reference's max |W_act| (without actuator work: over its
    # max(max T, max V - min V), work_precision.Reference.energy_scale), [0, T]
    "energy_relative": 1e-2,
    "drift": wp.DRIFT_TARGET,  # m: the run's own max |Phi| over [0, T]
}
#: what each measure is called in messages and figures (and its one-letter code in the stiffness figure)
MEASURES = {
    "ee": ("end-effector position", "x"),
    "driving": ("driving forces", "F"),
    "peak_force": ("peak contact force", "P"),
    "energy_relative": ("energy balance", "E"),
    "drift": ("constraint drift", "d"),
}
#: the common output grid of the runs and their reference (s; the work-precision study's default)
OUTPUT_STEP = 1e-4


def beyond_thresholds(errors: dict) -> list[str]:
    """The measures of :data:`THRESHOLDS` beyond (>) their threshold (NaN counts as beyond; None, or a measure
    missing from ``errors``: not applicable)."""
    return wp.beyond(errors, THRESHOLDS)


def classify(outcome: Outcome, ref: wp.Reference | None) -> dict:
    """``result`` (:data:`OK`, :data:`INACCURATE`, :data:`UNCHECKED` or the failure cause), ``finished``
    (no failure cause), ``errors`` (:func:`robot.analysis.studies.work_precision.errors`), ``inaccurate_by``."""
    if not outcome.success:
        return {"result": outcome.cause or "failed", "finished": False, "errors": None, "inaccurate_by": []}
    if ref is None:
        return {"result": UNCHECKED, "finished": True, "errors": None, "inaccurate_by": []}
    errors = wp.errors(outcome, ref)
    beyond = beyond_thresholds(errors)
    return {"result": INACCURATE if beyond else OK, "finished": True, "errors": errors, "inaccurate_by": beyond}


def describe(cell: dict) -> str:
    """One line for a classified cell: ``accurate``, ``inaccurate: driving forces 77 %, ...`` or the cause."""
    if cell["result"] != INACCURATE:
        return cell["result"]
    parts = []
    for key in cell["inaccurate_by"]:
        value = cell["errors"].get(key)
        parts.append(f"{MEASURES[key][0]} {_amount(key, value)} (> {_amount(key, THRESHOLDS[key])})")
    return f"{INACCURATE}: " + ", ".join(parts)


def _amount(key: str, value: float | None) -> str:
    """A measure's value with its unit: m for lengths, % for the relative ones."""
    if value is None or not math.isfinite(value):
        return "not measured" if value is None or math.isnan(value) else str(value)
    return f"{value:.2g} m" if key in ("ee", "drift") else f"{100 * value:.3g} %"


def _reference(run: Run, t_end: float, label: str, finished: dict, stop) -> tuple[wp.Reference | None, dict]:
    """The tight reference of ``run`` over [0, t_end] and its summary (None and why, if the reference run failed).

    A stop of the user while it runs stops the map (:class:`StudyStopped` carrying ``finished``).
    """
    try:
        ref = wp.reference(run, t_end, OUTPUT_STEP, stop=stop)
    except StudyStopped as stopped:
        if stopped.reason == INTERRUPTED:
            raise StudyStopped(f"{label}: {stopped}", finished, stopped.stopped_run) from None
        return None, {"failed": str(stopped), "runs": stopped.finished}
    summary = {
        "method": wp.REFERENCE.method,
        "rtol": wp.REFERENCE.rtol,
        "check_rtol": wp.CHECK.rtol,
        "comparable_window_s": ref.window,
        "steps": ref.outcome.n_steps,
        "cpu_time": ref.outcome.cpu_time + ref.check.cpu_time,
        "peak_force": ref.outcome.peaks,
        "driving_force_max": float(np.max(np.abs(ref.outcome.grid_force))) if ref.outcome.grid_force.size else None,
        "actuator_work_max": ref.outcome.actuator_work_scale,
        "energy_scale": ref.energy_scale,
    }
    return ref, summary


# --------------------------------------------------------------------------------------
# 1. step size against contact stiffness
# --------------------------------------------------------------------------------------


def stiffness_map(
    scene: str,
    scales=(0.1, 1.0, 10.0, 100.0, 1000.0),
    steps=(1e-3, 3e-4, 1e-4, 3e-5, 1e-5, 3e-6, 1e-6),
    methods=("RK4", "GenAlpha"),
    t_end: float = 0.03,
    adaptive: str = "RK45",
    adaptive_rtol: float = 1e-6,
    folder: Path | None = None,
    progress=None,
    stop: Callable[[], bool] | None = None,
) -> dict:
    """Outcome of every (method, h, stiffness scale) run, classified, and the adaptive method's mean step per scale.

    Per scale: the scene with every contact stiffness scaled (:func:`scaled_stiffness`), a tight
    reference of it over [0, t_end] (``reference``), then the cells, each classified against it
    (:func:`classify`). ``boundary``: per method and scale the largest step that finished (accurate
    or not, its meaning before the classification); ``boundary_accurate``: the largest that is
    accurate. ``folder`` (where the variants' scene files went) is accepted for earlier callers and not
    used: the variants are the scene with ``overrides``, recorded in ``scaled``. SceneError before any run if the scene's contact stiffness cannot be scaled.
    """
    base = load_scene(scene)
    scaled = scaled_stiffness(base)  # refuses a scene whose stiffness the map cannot scale
    out = {
        "scene": scene, "t_end": t_end, "scales": list(scales), "steps": list(steps), "methods": {}, "adaptive": {},
        "scaled": scaled, "output_step": OUTPUT_STEP, "thresholds": dict(THRESHOLDS), "reference": {},
    }  # fmt: skip
    try:
        for scale in scales:
            variant = base.with_changes({**stiffness_overrides(scaled, scale), "name": f"{base.name}_stiffness_x{scale:g}"})
            run = build_run(variant)
            ref, out["reference"][repr(scale)] = _reference(run, t_end, f"stiffness x{scale:g} reference", out, stop)
            if progress:
                what = out["reference"][repr(scale)]
                progress(f"stiffness x{scale:g} reference: " + (f"failed ({what['failed']})" if ref is None else f"comparable window {ref.window:.3g} s"))
            _fixed_step_runs(out, run, ref, scale, methods, steps, t_end, progress, stop)
            _adaptive_run(out, run, ref, scale, adaptive, adaptive_rtol, t_end, progress, stop)
    finally:  # a stopped map keeps the boundaries of what it ran
        out["boundary"] = {
            method: {repr(scale): _largest(rows, scale, finished) for scale in scales} for method, rows in out["methods"].items()
        }
        out["boundary_accurate"] = {
            method: {repr(scale): _largest(rows, scale, lambda row: row["result"] == OK) for scale in scales}
            for method, rows in out["methods"].items()
        }
    return out


def _fixed_step_runs(out: dict, run: Run, ref, scale: float, methods, steps, t_end: float, progress, stop) -> None:
    for method in methods:
        rows = out["methods"].setdefault(method, [])
        for h in steps:
            label = f"stiffness x{scale:g} {method} h={h:g}"
            options = SolverOptions(method, rtol=1e-8, atol=1e-10, first_step=h, output_step=OUTPUT_STEP)
            outcome = run_or_stop(partial(simulate, run, options, t_end, label=label), label, out, stop)
            cell = classify(outcome, ref)
            rows.append({"scale": scale, "h": h, **cell, "message": outcome.message, "cpu_time": outcome.cpu_time, "steps": outcome.n_steps})
            if progress:
                progress(f"{label}: {describe(cell)}")


def _adaptive_run(out: dict, run: Run, ref, scale: float, adaptive: str, adaptive_rtol: float, t_end: float, progress, stop) -> None:
    options = SolverOptions(adaptive, rtol=adaptive_rtol, atol=adaptive_rtol * 1e-2, max_step=1e-3, output_step=OUTPUT_STEP)
    label = f"stiffness x{scale:g} {adaptive}"
    outcome = run_or_stop(partial(simulate, run, options, t_end, label=label), label, out, stop)
    cell = classify(outcome, ref)
    out["adaptive"][repr(scale)] = {
        "method": adaptive,
        "rtol": adaptive_rtol,
        **cell,
        "steps": outcome.n_steps,
        "mean_step": outcome.t_reached / max(outcome.n_steps, 1),
        "cpu_time": outcome.cpu_time,
    }
    if progress:
        progress(f"{label}: {outcome.n_steps} steps, {describe(cell)}")


def _largest(rows, scale: float, keep: Callable[[dict], bool]) -> float | None:
    """Largest step size at ``scale`` of a row that ``keep`` accepts (None if none is)."""
    hs = [r["h"] for r in rows if r["scale"] == scale and keep(r)]
    return max(hs) if hs else None


def scaled_stiffness(scene: Scene) -> dict:
    """What the stiffness map scales in ``scene``, with the nominal values.

    ``materials``: the Young's modulus of every material of the scene (every stiffness a
    contact law derives from its materials is proportional to E*: Hertz, line and
    flat-punch stiffness, the Johnson and Pereira laws, a translational joint's rounded
    corners); ``keys``: per clearance joint, every stiffness its ``[[clearance]]`` table
    gives explicitly (its type's scene keys ending in ``stiffness``: ``stiffness``,
    ``radial_stiffness``, ``axial_stiffness``, ``point_stiffness``), which the laws use
    instead of the materials'. Checked on the laws themselves (:func:`_probe_forces`):
    with all of these doubled, every elastic normal force of every joint at a set of
    penetrating poses must double; else :class:`SceneError` naming the joint and its keys
    (e.g. a registered joint type whose stiffness follows a key of another name).
    """
    document = scene.document
    if not document.get("clearance"):
        raise SceneError(f"scene {scene.name!r} has no clearance joint: the stiffness map has no contact stiffness to scale", key="clearance", value=None)
    materials = {name: float(table["youngs_modulus"]) for name, table in (document.get("materials") or {}).items()}
    keys: dict[str, dict[str, float]] = {}
    for entry in document["clearance"]:
        kind = joint_type(entry["type"])
        keys[entry["joint"]] = {k: float(entry[k]) for k in kind.SCENE_KEYS if k.endswith("stiffness") and k in entry}
    scaled = {"materials": materials, "keys": keys}
    doubled = scene.with_changes(stiffness_overrides(scaled, 2.0))
    nominal = {c.joint: c for c in scene.clearances}
    for spec in doubled.clearances:
        problem = _scaling_problem(_probe_forces(nominal[spec.joint].law), _probe_forces(spec.law))
        if problem:
            entry = next(e for e in document["clearance"] if e["joint"] == spec.joint)
            kind = joint_type(spec.kind)
            others = [k for k in kind.SCENE_KEYS if k in entry and k not in keys[spec.joint] and k not in kind.GEOMETRY_KEYS and k not in kind.NAME_KEYS]
            raise SceneError(
                f"scene {scene.name!r}: the stiffness map cannot scale the contact stiffness of clearance joint {spec.joint!r} "
                f"(type {spec.kind!r}): with the Young's moduli ({', '.join(materials) or 'none'}) and its keys ending in "
                f"'stiffness' ({', '.join(keys[spec.joint]) or 'none given'}) doubled, {problem}; its other numeric keys: "
                f"{', '.join(f'{k} = {entry[k]!r}' for k in others) or 'none'}. Map a scene whose contact stiffness follows "
                "the materials or a '*stiffness' key",
                key=f"clearance.{spec.joint}", value=spec.kind,
            )  # fmt: skip
    return scaled


def _probe_forces(law) -> np.ndarray:
    """Elastic normal forces of ``law`` at penetrating poses: the inner element moved by 1.01 x each candidate
    clearance along each axis of the outer element (both ways), at rest (no damping, no friction); NaN where
    the law refuses the pose."""
    rotation, origin, at_rest = np.eye(3), np.zeros(3), np.zeros(6)
    rates = np.zeros(law.N_CANDIDATES)
    forces = []
    for clearance in sorted(set(np.asarray(law.candidate_clearances(), float).tolist())):
        for axis in range(3):
            for sign in (1.0, -1.0):
                position = np.zeros(3)
                position[axis] = sign * 1.01 * clearance
                try:
                    forces.append(np.array(law.evaluate(rotation, origin, at_rest, rotation, position, at_rest, rates).normal_force, float))
                except ContactError:
                    forces.append(np.full(law.N_CANDIDATES, np.nan))
    return np.concatenate(forces) if forces else np.zeros(0)


def _scaling_problem(nominal: np.ndarray, doubled: np.ndarray) -> str | None:
    """Why the probe forces of a law with its stiffness doubled are not twice the nominal ones (None if they are)."""
    touching = np.isfinite(nominal) & (nominal > 0)
    if not touching.any():
        return "no probe pose put it in contact, so the map cannot check that its forces scale"
    ratio = doubled[touching] / nominal[touching]
    if not np.allclose(ratio, 2.0, rtol=1e-9, atol=0.0):
        return f"its contact forces at fixed penetrations changed by a factor {np.nanmin(ratio):.6g} to {np.nanmax(ratio):.6g}, not 2"
    return None


def stiffness_overrides(scaled: dict, scale: float) -> dict:
    """Scene overrides (key paths) that scale every contact stiffness of :func:`scaled_stiffness` by ``scale``."""
    overrides = {f"materials.{name}.youngs_modulus": modulus * scale for name, modulus in scaled["materials"].items()}
    for joint, keys in scaled["keys"].items():
        overrides |= {f"clearance.{joint}.{key}": value * scale for key, value in keys.items()}
    return overrides


# --------------------------------------------------------------------------------------
# 2. Baumgarte gains
# --------------------------------------------------------------------------------------


def baumgarte_map(
    scene: str = "ideal",
    alphas=(0.0, 1.0, 5.0, 20.0, 100.0, 1000.0),
    betas=(0.0, 1.0, 5.0, 20.0, 100.0, 1000.0),
    cases=(("RK45", 1e-6, None), ("RK45", 1e-3, None), ("RK4", None, 2e-3), ("GenAlpha", 1e-8, 2e-3)),
    t_end: float = 1.0,
    max_residual: float = 1e-4,
    max_wall_time: float = 20.0,
    progress=None,
    stop: Callable[[], bool] | None = None,
) -> dict:
    """Max drift, cost and class (:func:`classify`) for every (alpha, beta) and solver case (a case's grid fills as it runs).

    The reference is a tight run of the scene with its own gains (``reference``): the exact
    motion, and the exact driving forces, do not depend on the gains (the stabilisation
    terms vanish with the constraint error), so one reference serves every cell.
    """
    run = build_run(scene)
    limits = dataclasses.replace(run.scene.limits, max_residual=max_residual, max_wall_time=max_wall_time)
    out = {
        "scene": scene, "t_end": t_end, "alphas": list(alphas), "betas": list(betas), "max_residual_limit": max_residual,
        "output_step": OUTPUT_STEP, "thresholds": dict(THRESHOLDS), "cases": [],
    }  # fmt: skip
    ref, out["reference"] = _reference(run, t_end, "baumgarte reference", out, stop)
    for method, rtol, h in cases:
        options = SolverOptions(method, rtol=rtol or 1e-8, atol=(rtol or 1e-8) * 1e-2, max_step=1e-2, first_step=h, output_step=OUTPUT_STEP)
        grid: list[dict] = []
        out["cases"].append({"method": method, "rtol": rtol, "h": h, "grid": grid})
        for alpha in alphas:
            for beta in betas:
                dynamics = dataclasses.replace(run.dynamics, baumgarte=Baumgarte(alpha, beta))
                label = f"baumgarte {method} rtol={rtol} h={h} alpha={alpha:g} beta={beta:g}"
                outcome = run_or_stop(partial(simulate, run, options, t_end, label=label, dynamics=dynamics, limits=limits), label, out, stop)
                cell = classify(outcome, ref)
                drift = outcome.max_residual
                grid.append(
                    {
                        "alpha": alpha,
                        "beta": beta,
                        **cell,
                        "message": outcome.message,
                        "max_residual": drift,
                        "steps": outcome.n_steps,
                        "rhs_calls": outcome.n_rhs,
                        "cpu_time": outcome.cpu_time,
                        "t_reached": outcome.t_reached,
                    }
                )
                if progress:
                    progress(f"{label}: {describe(cell)}, drift {drift:.2e}")
    return out


# --------------------------------------------------------------------------------------
# 3. hidden contact onsets
# --------------------------------------------------------------------------------------


def hidden_contact_map(
    run: Run,
    methods=("RK23", "RK45", "DOP853", "LSODA", "BDF"),
    tolerances=(1e-2, 1e-3, 1e-4, 1e-5, 1e-6),
    t_end: float = 0.1,
    max_step: float = 1e-2,
    reference_peaks: dict | None = None,
    reference_onsets: int | None = None,
    progress=None,
    stop: Callable[[], bool] | None = None,
) -> dict:
    """Onsets, guard detections, overshoot and outcome per (method, tolerance, guard).

    ``result``: :data:`FINISHED` (``"ok"``) or the failure cause; ``finished``: no failure cause.
    With ``reference_peaks`` (a tight run's
    peak normal force per joint over the same horizon) a finished run also gets
    ``peak_force_error`` and, beyond the peak-force threshold of :data:`THRESHOLDS`,
    ``inaccurate_by = ["peak_force"]`` (this map measures no other error).
    """
    clearance = min(_clearances(run))
    out = {"scene": run.scene.name, "t_end": t_end, "max_step": max_step, "clearance": clearance, "reference_onsets": reference_onsets, "runs": []}
    for method in methods:
        for tol in tolerances:
            for guard in (True, False):
                options = SolverOptions(method, rtol=tol, atol=tol * 1e-2, max_step=max_step, hidden_contacts=guard)
                label = f"hidden {method} rtol={tol:g} guard={guard}"
                outcome = run_or_stop(partial(simulate, run, options, t_end, outputs=reference_peaks is not None), label, out, stop)
                row = {
                    "method": method,
                    "rtol": tol,
                    "guard": guard,
                    "result": _cause(outcome),
                    "finished": outcome.success,
                    "message": outcome.message,
                    "onsets": outcome.n_events,
                    "hidden_found": outcome.n_hidden_contacts,
                    "overshoot_over_clearance": outcome.max_onset_overshoot / clearance,
                    "steps": outcome.n_steps,
                    "cpu_time": outcome.cpu_time,
                }
                if reference_peaks and outcome.success:
                    row["peak_force_error"] = max(wp.relative_error(outcome.peaks.get(j, math.nan), p) for j, p in reference_peaks.items())
                    row["inaccurate_by"] = beyond_thresholds({"peak_force": row["peak_force_error"]})
                out["runs"].append(row)
                if progress:
                    progress(
                        f"{label}: {row['result']}, onsets {row['onsets']}, "
                        f"guard found {row['hidden_found']}, overshoot {row['overshoot_over_clearance']:.2g} c"
                    )
    return out


def _clearances(run: Run) -> list[float]:
    return [float(c) for contact in run.dynamics.contacts for c in contact.law.candidate_clearances()]


# --------------------------------------------------------------------------------------
# charts
# --------------------------------------------------------------------------------------

COLOURS = {
    OK: "#4caf50",
    INACCURATE: "#ffe082",
    UNCHECKED: "#ffffff",
    FINISHED: "#ffffff",  # "ok": hidden-contact map, or a map written before the classification: accuracy not checked
    "penetration beyond physical bound": "#e53935",
    "non-finite state": "#8e24aa",
    "unphysical pose": "#f06292",
    "Newton divergence": "#fb8c00",
    "constraint drift": "#1e88e5",
    "step size collapse": "#6d4c41",
    "event chattering": "#00acc1",
    "wall time": "#757575",
    "solver error": "#000000",
}
#: the hatch that marks a finished run with a measure beyond its threshold
INACCURATE_HATCH = "////"


def _legend_label(result: str) -> str:
    if result == OK:
        return "accurate: finished, every measure within its threshold"
    if result == INACCURATE:
        return "inaccurate: finished, letters = measures beyond their thresholds"
    if result in (UNCHECKED, FINISHED):
        return "finished, accuracy not checked" + (" (reference run failed)" if result == UNCHECKED else "")
    return f"failed: {result}"


def _codes(row: dict) -> str:
    return "".join(MEASURES[key][1] for key in row.get("inaccurate_by") or () if key in MEASURES)


def _thresholds_note(data: dict) -> str:
    """The thresholds a classified map checked its cells against ("" for a map written before the classification)."""
    t = data.get("thresholds")
    if not t:
        return ""
    return (
        f"against DOP853 rtol 1e-11 over the same horizon: x end effector > {t['ee']:g} m, F driving forces > {100 * t['driving']:g} %, "
        f"P peak contact force > {100 * t['peak_force']:g} %, E energy balance > {100 * t['energy_relative']:g} % of the actuator work (none: of the mechanical energy), "
        f"d drift > {t['drift']:g} m"
    )


def _class_handles(results) -> list:
    from matplotlib.patches import Patch

    order = [OK, INACCURATE, UNCHECKED, FINISHED]
    ordered = [r for r in order if r in results] + sorted(r for r in results if r not in order)
    handles, seen = [], set()
    for result in ordered:
        label = _legend_label(result)
        if label in seen:
            continue
        seen.add(label)
        hatch = INACCURATE_HATCH if result == INACCURATE else None
        handles.append(Patch(facecolor=COLOURS.get(result, "#000000"), edgecolor="k", hatch=hatch, linewidth=0.4, label=label))
    return handles


def plot_stiffness(data: dict, path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.lines import Line2D

    methods = list(data["methods"])
    fig, axes = plt.subplots(1, len(methods) + 1, figsize=(5.2 * (len(methods) + 1), 5.2))
    scales = data["scales"]
    results = set()
    for ax, method in zip(axes, methods):
        for row in data["methods"][method]:
            result = row["result"]
            results.add(result)
            hatch = INACCURATE_HATCH if result == INACCURATE else None
            ax.scatter(row["scale"], row["h"], s=170, marker="s", color=COLOURS.get(result, "#000000"), hatch=hatch, edgecolors="k", linewidths=0.4)
            if result == INACCURATE:
                ax.annotate(_codes(row), (row["scale"], row["h"]), xytext=(8, -3), textcoords="offset points", fontsize=7)
        for key, style in (("boundary_accurate", "k-"), ("boundary", "k--")):
            limits = (data.get(key) or {}).get(method, {})
            line = [(s, limits[repr(s)]) for s in scales if limits.get(repr(s))]
            if line:
                ax.plot(*zip(*line), style, lw=1)
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.margins(x=0.15, y=0.1)
        ax.set_xlabel("contact stiffness / nominal")
        ax.set_ylabel("fixed step h (s)")
        ax.set_title(f"{method} over [0, {data['t_end']:g}] s", fontsize=10)
        ax.grid(True, which="both", alpha=0.3)
    ax = axes[-1]
    adaptive = data["adaptive"]
    if adaptive:
        xs = [float(k) for k in adaptive]
        ax.loglog(xs, [adaptive[k]["mean_step"] for k in adaptive], "-", color="0.4", label=f"{next(iter(adaptive.values()))['method']} mean step")
        for k, entry in adaptive.items():
            result = entry.get("result", FINISHED)
            results.add(result)
            hatch = INACCURATE_HATCH if result == INACCURATE else None
            ax.scatter(float(k), entry["mean_step"], s=90, marker="o", color=COLOURS.get(result, "#000000"), hatch=hatch, edgecolors="k", linewidths=0.4, zorder=3)
            if result == INACCURATE:
                ax.annotate(_codes(entry), (float(k), entry["mean_step"]), xytext=(7, -3), textcoords="offset points", fontsize=7)
        if len(xs) > 1:
            x0, y0 = xs[0], next(iter(adaptive.values()))["mean_step"]
            ax.loglog(xs, [y0 * (x / x0) ** -0.5 for x in xs], "k:", label="slope -1/2 (h ~ 1/omega of a linear contact)")
    ax.set_xlabel("contact stiffness / nominal")
    ax.set_ylabel("mean accepted step (s)")
    what = next(iter(adaptive.values()), {})
    ax.set_title(f"explicit adaptive method ({what.get('method', '')} rtol {what.get('rtol', math.nan):g}): mean accepted step", fontsize=10)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    classified = "boundary_accurate" in data  # else a map written before the classification: no accuracy claimed
    lines = [Line2D([], [], color="k", lw=1, label="largest accurate step")] if classified else []
    handles = _class_handles(results) + lines + [Line2D([], [], color="k", lw=1, ls="--", label="largest step that finished")]
    fig.legend(handles=handles, loc="lower center", ncol=3, fontsize=8)
    if classified:
        title = "failed (cause), finished but inaccurate, or accurate\n" + _thresholds_note(data)
    else:
        title = "failed (cause) or finished (accuracy not checked: a map written before the classification)"
    fig.suptitle(f"Step size against contact stiffness ({data['scene']}; Young's moduli and explicit stiffness keys scaled): " + title, fontsize=9)
    fig.tight_layout(rect=(0, 0.13, 1, 0.93))
    save_png(fig, path)


def plot_baumgarte(data: dict, path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.patches import Rectangle

    cases = data["cases"]
    alphas, betas = data["alphas"], data["betas"]
    fig, axes = plt.subplots(1, len(cases), figsize=(4.4 * len(cases), 4.9), squeeze=False)
    results = set()
    for ax, case in zip(axes[0], cases):
        for row in case["grid"]:
            i, j = alphas.index(row["alpha"]), betas.index(row["beta"])
            result = row["result"]
            results.add(result)
            hatch = INACCURATE_HATCH if result == INACCURATE else None
            ax.add_patch(Rectangle((j - 0.5, i - 0.5), 1, 1, facecolor=COLOURS.get(result, "#000000"), edgecolor="k", hatch=hatch, linewidth=0.4))
            if result in NOT_FAILED:
                text = f"{_codes(row)}\n{row['steps']}" if result == INACCURATE else f"{row['steps']}"
                colour = "k"
            else:
                text, colour = _short(result), "w"
            ax.text(j, i, text, ha="center", va="center", color=colour, fontsize=6.5, fontweight="bold" if result == INACCURATE else "normal",
                    bbox=dict(facecolor="w", edgecolor="none", pad=0.5, alpha=0.8) if result == INACCURATE else None)  # fmt: skip
        ax.set_xlim(-0.5, len(betas) - 0.5)
        ax.set_ylim(-0.5, len(alphas) - 0.5)
        ax.set_xticks(range(len(betas)), [f"{b:g}" for b in betas])
        ax.set_yticks(range(len(alphas)), [f"{a:g}" for a in alphas])
        ax.set_xlabel("beta (1/s)")
        ax.set_ylabel("alpha (1/s)")
        what = f"rtol {case['rtol']:g}" if case["h"] is None else f"h = {case['h']:g} s"
        ax.set_title(f"{case['method']} {what}", fontsize=10)
    fig.legend(handles=_class_handles(results), loc="lower center", ncol=3, fontsize=8)
    fig.suptitle(
        f"Baumgarte gains ({data['scene']}, [0, {data['t_end']:g}] s): numbers: steps; labels: failure cause "
        f"(drift limit {data['max_residual_limit']:g} m)"
        + (" or, hatched, the measures beyond their thresholds\n" + _thresholds_note(data) if data.get("thresholds") else ""),
        fontsize=9,
    )
    fig.tight_layout(rect=(0, 0.1, 1, 0.9))
    save_png(fig, path)


def _short(cause: str) -> str:
    return {
        "constraint drift": "drift",
        "non-finite state": "NaN",
        "step size collapse": "h->0",
        "wall time": "slow",
        "Newton divergence": "Newton",
        "penetration beyond physical bound": "pen.",
        "unphysical pose": "pose",
    }.get(cause, cause[:6])


def plot_hidden(data: dict, path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    runs = data["runs"]
    methods = []
    for r in runs:
        if r["method"] not in methods:
            methods.append(r["method"])
    fig, axes = plt.subplots(1, 3, figsize=(16, 4.6))
    cmap = plt.get_cmap("tab10")
    for i, method in enumerate(methods):
        for guard, style in ((True, "-"), (False, "--")):
            rows = sorted((r for r in runs if r["method"] == method and r["guard"] == guard), key=lambda r: r["rtol"])
            tol = [r["rtol"] for r in rows]
            label = f"{method} {'guard' if guard else 'no guard'}"
            axes[0].semilogx(tol, [r["onsets"] for r in rows], style, marker="o", color=cmap(i), label=label)
            axes[1].loglog(tol, [max(r["overshoot_over_clearance"], 1e-6) for r in rows], style, marker="o", color=cmap(i))
            errors = [(r["rtol"], r.get("peak_force_error")) for r in rows if r.get("peak_force_error") is not None]
            if errors:
                axes[2].loglog(*zip(*errors), style, marker="o", color=cmap(i))
            for r in rows:
                if r["result"] not in NOT_FAILED:
                    axes[0].plot([r["rtol"]], [r["onsets"]], "x", color="k", markersize=9)
    if axes[2].lines:
        axes[2].axhline(THRESHOLDS["peak_force"], color="k", lw=0.8, ls=":")
    if data.get("reference_onsets"):
        axes[0].axhline(data["reference_onsets"], color="k", lw=0.8, ls=":", label="reference")
    axes[0].set_ylabel("contact onsets found")
    axes[1].set_ylabel("deepest step end past an onset / clearance")
    axes[2].set_ylabel(f"peak contact force error (relative; dotted: {100 * THRESHOLDS['peak_force']:g} % threshold)")
    for ax in axes:
        ax.set_xlabel("rtol (atol = rtol/100)")
        ax.grid(True, which="both", alpha=0.3)
    axes[0].legend(fontsize=7, ncol=2)
    fig.suptitle(
        f"Variable-step methods jumping over contact onsets ({data['scene']}, [0, {data['t_end']:g}] s, max_step {data['max_step']:g} s); "
        "x: failed run",
        fontsize=10,
    )
    fig.tight_layout(rect=(0, 0, 1, 0.94))
    save_png(fig, path)
