"""Where methods fail: failure boundaries, each failure reported with its cause.

Three maps (``scripts/work_precision.py`` runs them, ``docs/work-precision.md``
reports them):

1. **step size against contact stiffness** (fixed-step methods, and the mean
   step an explicit variable-step method is held to): the contact stiffness of
   every clearance joint is scaled through the material's Young's modulus (every
   stiffness of the contact layer is proportional to E*); each (h, scale) run
   ends ``ok`` or with its cause (penetration beyond the physical bound,
   non-finite state, Newton divergence, ...);
2. **Baumgarte gains** (alpha, beta grid): max constraint drift, cost and
   blow-up, for an adaptive method and for fixed-step methods;
3. **hidden contact onsets**: variable-step methods at loose tolerances, with
   and without the guard that scans each step for a contact starting and ending
   inside it (``SolverOptions.hidden_contacts``): contact onsets found, onsets
   found only by the guard, how deep a step ran into contact before being cut
   back to the onset (relative to the clearance), failures.

Every run goes through :func:`robot.integration.simulation.integrate`, which never raises on
divergence: the maps record ``status`` and ``cause``. A map stopped by the user
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

from robot.dynamics.equations import Baumgarte
from robot.run import Run, build_run
from robot.integration.simulation import SolverOptions
from robot.analysis.studies.common import run_or_stop, save_png, scene_variant, simulate

OK = "ok"


def _cause(outcome) -> str:
    return OK if outcome.success else (outcome.cause or "failed")


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
    """Outcome of every (method, h, stiffness scale) run, and the adaptive method's mean step per scale."""
    base = build_run(scene)
    # the shipped scenes' clearance joints are all of [materials.steel]: scale its Young's modulus
    modulus = _steel_modulus(base)
    out = {"scene": scene, "t_end": t_end, "scales": list(scales), "steps": list(steps), "methods": {}, "adaptive": {}}
    try:
        for scale in scales:
            run = scene_variant(
                scene,
                f"[materials.steel]\nyoungs_modulus = {modulus * scale!r}\npoisson_ratio = {_steel_poisson(base)!r}\n",
                folder,
                name=f"{scene}_stiffness_{scale:g}",
            )
            _fixed_step_runs(out, run, scale, methods, steps, t_end, progress, stop)
            _adaptive_run(out, run, scale, adaptive, adaptive_rtol, t_end, progress, stop)
    finally:  # a stopped map keeps the boundaries of what it ran
        out["boundary"] = {
            method: {repr(scale): _largest_ok([r for r in rows if r["scale"] == scale]) for scale in scales} for method, rows in out["methods"].items()
        }
    return out


def _fixed_step_runs(out: dict, run: Run, scale: float, methods, steps, t_end: float, progress, stop) -> None:
    for method in methods:
        rows = out["methods"].setdefault(method, [])
        for h in steps:
            label = f"stiffness x{scale:g} {method} h={h:g}"
            options = SolverOptions(method, rtol=1e-8, atol=1e-10, first_step=h)
            outcome = run_or_stop(partial(simulate, run, options, t_end, outputs=False), label, out, stop)
            rows.append({"scale": scale, "h": h, "result": _cause(outcome), "message": outcome.message, "cpu_time": outcome.cpu_time, "steps": outcome.n_steps})
            if progress:
                progress(f"{label}: {_cause(outcome)}")


def _adaptive_run(out: dict, run: Run, scale: float, adaptive: str, adaptive_rtol: float, t_end: float, progress, stop) -> None:
    options = SolverOptions(adaptive, rtol=adaptive_rtol, atol=adaptive_rtol * 1e-2, max_step=1e-3)
    outcome = run_or_stop(partial(simulate, run, options, t_end, outputs=False), f"stiffness x{scale:g} {adaptive}", out, stop)
    out["adaptive"][repr(scale)] = {
        "method": adaptive,
        "rtol": adaptive_rtol,
        "result": _cause(outcome),
        "steps": outcome.n_steps,
        "mean_step": outcome.t_reached / max(outcome.n_steps, 1),
        "cpu_time": outcome.cpu_time,
    }
    if progress:
        progress(f"stiffness x{scale:g} {adaptive}: {outcome.n_steps} steps")


def _largest_ok(rows) -> float | None:
    """Largest step size that succeeded (None if none did)."""
    ok = [r["h"] for r in rows if r["result"] == OK]
    return max(ok) if ok else None


def _steel_modulus(run: Run) -> float:
    law = run.dynamics.contacts[0].law
    material = getattr(law, "ball_material", None) or getattr(law, "journal_material")
    return float(material.youngs_modulus)


def _steel_poisson(run: Run) -> float:
    law = run.dynamics.contacts[0].law
    material = getattr(law, "ball_material", None) or getattr(law, "journal_material")
    return float(material.poisson_ratio)


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
    """Max drift, cost and outcome for every (alpha, beta) and solver case (a case's grid fills as it runs)."""
    run = build_run(scene)
    limits = dataclasses.replace(run.scene.limits, max_residual=max_residual, max_wall_time=max_wall_time)
    out = {"scene": scene, "t_end": t_end, "alphas": list(alphas), "betas": list(betas), "max_residual_limit": max_residual, "cases": []}
    for method, rtol, h in cases:
        options = SolverOptions(method, rtol=rtol or 1e-8, atol=(rtol or 1e-8) * 1e-2, max_step=1e-2, first_step=h)
        grid: list[dict] = []
        out["cases"].append({"method": method, "rtol": rtol, "h": h, "grid": grid})
        for alpha in alphas:
            for beta in betas:
                dynamics = dataclasses.replace(run.dynamics, baumgarte=Baumgarte(alpha, beta))
                label = f"baumgarte {method} rtol={rtol} h={h} alpha={alpha:g} beta={beta:g}"
                outcome = run_or_stop(partial(simulate, run, options, t_end, dynamics=dynamics, limits=limits), label, out, stop)
                drift = outcome.max_residual
                grid.append(
                    {
                        "alpha": alpha,
                        "beta": beta,
                        "result": _cause(outcome),
                        "message": outcome.message,
                        "max_residual": drift,
                        "steps": outcome.n_steps,
                        "rhs_calls": outcome.n_rhs,
                        "cpu_time": outcome.cpu_time,
                        "t_reached": outcome.t_reached,
                    }
                )
                if progress:
                    progress(f"{label}: {_cause(outcome)} drift {drift:.2e}")
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
    """Onsets, guard detections, overshoot and outcome per (method, tolerance, guard)."""
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
                    "message": outcome.message,
                    "onsets": outcome.n_events,
                    "hidden_found": outcome.n_hidden_contacts,
                    "overshoot_over_clearance": outcome.max_onset_overshoot / clearance,
                    "steps": outcome.n_steps,
                    "cpu_time": outcome.cpu_time,
                }
                if reference_peaks and outcome.success:
                    row["peak_force_error"] = max(abs(outcome.peaks[j] - p) / p for j, p in reference_peaks.items())
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
    "penetration beyond physical bound": "#e53935",
    "non-finite state": "#8e24aa",
    "Newton divergence": "#fb8c00",
    "constraint drift": "#1e88e5",
    "step size collapse": "#6d4c41",
    "event chattering": "#fdd835",
    "wall time": "#757575",
    "solver error": "#000000",
}


def plot_stiffness(data: dict, path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    methods = list(data["methods"])
    fig, axes = plt.subplots(1, len(methods) + 1, figsize=(5 * (len(methods) + 1), 4.6))
    scales = data["scales"]
    seen = set()
    for ax, method in zip(axes, methods):
        for row in data["methods"][method]:
            colour = COLOURS.get(row["result"], "#000000")
            label = row["result"] if row["result"] not in seen else None
            seen.add(row["result"])
            ax.scatter(row["scale"], row["h"], s=160, marker="s", color=colour, label=label, edgecolors="k", linewidths=0.4)
        boundary = [(s, data["boundary"][method][repr(s)]) for s in scales if data["boundary"][method][repr(s)]]
        if boundary:
            ax.plot(*zip(*boundary), "k-", lw=1)
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("contact stiffness / nominal (Young's modulus scale)")
        ax.set_ylabel("fixed step h (s)")
        ax.set_title(f"{method}: outcome over [0, {data['t_end']:g}] s", fontsize=10)
        ax.grid(True, which="both", alpha=0.3)
    ax = axes[-1]
    adaptive = data["adaptive"]
    xs = [float(k) for k in adaptive]
    ax.loglog(xs, [adaptive[k]["mean_step"] for k in adaptive], "o-", label=f"{next(iter(adaptive.values()))['method']} mean step")
    if len(xs) > 1:
        x0, y0 = xs[0], adaptive[repr(xs[0]) if repr(xs[0]) in adaptive else next(iter(adaptive))]["mean_step"]
        ax.loglog(xs, [y0 * (x / x0) ** -0.5 for x in xs], "k:", label="slope -1/2 (h ~ 1/omega)")
    ax.set_xlabel("contact stiffness / nominal")
    ax.set_ylabel("mean accepted step (s)")
    ax.set_title("explicit adaptive method: step held by stiffness", fontsize=10)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    handles, labels = axes[0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="lower center", ncol=len(labels), fontsize=8)
    fig.suptitle(f"Step size against contact stiffness ({data['scene']}); line: largest step that succeeded", fontsize=10)
    fig.tight_layout(rect=(0, 0.07, 1, 0.95))
    save_png(fig, path)


def plot_baumgarte(data: dict, path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    cases = data["cases"]
    alphas, betas = data["alphas"], data["betas"]
    fig, axes = plt.subplots(1, len(cases), figsize=(4.6 * len(cases), 4.6), squeeze=False)
    for ax, case in zip(axes[0], cases):
        image = np.full((len(alphas), len(betas)), np.nan)
        for row in case["grid"]:
            i, j = alphas.index(row["alpha"]), betas.index(row["beta"])
            value = row["max_residual"]
            image[i, j] = math.log10(max(value, 1e-16)) if np.isfinite(value) else 0.0
        shown = ax.imshow(image, origin="lower", cmap="viridis", vmin=-16, vmax=0, aspect="auto")
        for row in case["grid"]:
            i, j = alphas.index(row["alpha"]), betas.index(row["beta"])
            if row["result"] != OK:
                ax.text(j, i, _short(row["result"]), ha="center", va="center", color="w", fontsize=7, fontweight="bold")
            else:
                ax.text(j, i, f"{row['steps']}", ha="center", va="center", color="w", fontsize=6)
        ax.set_xticks(range(len(betas)), [f"{b:g}" for b in betas])
        ax.set_yticks(range(len(alphas)), [f"{a:g}" for a in alphas])
        ax.set_xlabel("beta (1/s)")
        ax.set_ylabel("alpha (1/s)")
        what = f"rtol {case['rtol']:g}" if case["h"] is None else f"h = {case['h']:g} s"
        ax.set_title(f"{case['method']} {what}", fontsize=10)
    fig.colorbar(shown, ax=axes[0].tolist(), label="log10 max |Phi| (m)")
    fig.suptitle(
        f"Baumgarte gains against drift and blow-up ({data['scene']}, [0, {data['t_end']:g}] s); numbers: steps; "
        f"labels: failure cause (drift limit {data['max_residual_limit']:g} m)",
        fontsize=10,
    )
    save_png(fig, path, bbox_inches="tight")


def _short(cause: str) -> str:
    return {
        "constraint drift": "drift",
        "non-finite state": "NaN",
        "step size collapse": "h->0",
        "wall time": "slow",
        "Newton divergence": "Newton",
        "penetration beyond physical bound": "pen.",
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
                if r["result"] != OK:
                    axes[0].plot([r["rtol"]], [r["onsets"]], "x", color="k", markersize=9)
    if data.get("reference_onsets"):
        axes[0].axhline(data["reference_onsets"], color="k", lw=0.8, ls=":", label="reference")
    axes[0].set_ylabel("contact onsets found")
    axes[1].set_ylabel("deepest step end past an onset / clearance")
    axes[2].set_ylabel("peak contact force error (relative)")
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
