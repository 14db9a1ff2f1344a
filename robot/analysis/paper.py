"""The seed paper's study: ideal vs compound clearance, aligned vs misaligned.

Runs ``ideal``, ``compound`` and ``compound_misaligned`` (two trajectory
periods by default) and writes figures corresponding to the paper's

* Figure 7: centre trajectories and time histories in the spherical joint and in
  the revolute joint (top and bottom ring), aligned and misaligned;
* Figure 8: contact forces (spherical, revolute) and driving forces (aligned,
  misaligned);
* Figure 9: end-effector displacement, velocity and acceleration (the paper's
  X and Y), ideal against clearance;
* Figure 10: end-effector X and Y displacement of the aligned clearance case,
  Newton-Euler (:mod:`robot.validation.newton_euler`, absolute coordinates)
  against Lagrange multipliers (:mod:`robot.run`), over its own horizon
  (``figure10_t_end``: the Newton-Euler engine costs ~1 min of CPU per 0.5 s);

and ``summary.json``: peak contact force per joint, peak driving forces, the
duration of the initial transient, the RMS deviation of the end-effector
acceleration from the ideal case, and the paper's five claims measured with
their verdicts (``claims``, also written as ``claims.md``:
:mod:`robot.analysis.claims`).

**Axes.** The paper's figures use its fixed frame: the RPS limb moves in its
X-Y plane and the R1 axis is its Z ("in the case of initial alignment, the
spherical joint does not move in the Z direction"). Ours (``robot/model/ups_rps_design.py``):
world z up, the R1 axis along world y, the limb in the x-z plane. So the
paper's X, Y, Z are our x, z, -y (:data:`PAPER_AXES`, right-handed).

**Initial transient** (our definition, the paper gives none): the last time at
which the normal force of a clearance joint exceeds ``TRANSIENT_FACTOR`` times
its maximum over the last trajectory period (the settled regime). Where the
run is shorter than two periods it is reported as ``null``.
"""

from __future__ import annotations

import json
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path
from typing import Callable

import numpy as np

from robot.analysis.claims import claims_json, claims_report, evaluate_claims
from robot.io.atomic import atomic_write_png, atomic_write_text
from robot.io.results import SimulationResult, load_result, save_result

SCENES = ("ideal", "compound", "compound_misaligned")
TRANSIENT_FACTOR = 1.5
#: the paper's fixed-frame axes as (name, world column, sign): X = x, Y = z (up), Z = -y (the R1 axis)
PAPER_AXES = (("X", 0, 1.0), ("Y", 2, 1.0), ("Z", 1, -1.0))
#: figure 10: the scene compared and its default horizon (s)
FIGURE10_SCENE = "compound"
FIGURE10_T_END = 0.25


def simulate_scene(args: tuple[str, float | None, str]) -> str:
    """Run one scene and save it (a top-level function so it can run in a worker process)."""
    from robot.run import build_run, compile_kernels, run_scene

    name, duration, out = args
    run = build_run(name, duration=duration)
    compile_time = compile_kernels(run)  # first-call compilation, reported apart from the run's cpu_time
    result = run_scene(run)
    result.counts["compile_cpu_time"] = compile_time
    return str(save_result(result, Path(out) / f"{name}.npz", run.scene.output))


def run_study(
    out: Path,
    duration: float | None,
    workers: int = 2,
    log: Callable[[str], None] = print,
    worker_setup: Callable[[], None] | None = None,
) -> dict[str, SimulationResult]:
    """Simulate the three scenes (in parallel processes, each started with ``worker_setup``) and load their results."""
    jobs = [(name, duration, str(out)) for name in SCENES]
    if workers > 1:
        with ProcessPoolExecutor(max_workers=workers, initializer=worker_setup) as pool:
            paths = list(pool.map(simulate_scene, jobs))
    else:
        paths = [simulate_scene(job) for job in jobs]
    results = {}
    for name, path in zip(SCENES, paths):
        result = load_result(path)
        compiled = result.counts.get("compile_cpu_time")
        compiled = f" + {compiled:.1f} s compiling" if compiled is not None else ""
        log(f"{name}: {result.message} ({result.counts['n_steps']} steps, {result.counts['cpu_time']:.1f} s cpu{compiled})")
        results[name] = result
    return results


def transient_duration(result: SimulationResult, joint: str, period: float) -> float | None:
    """Last time the joint's total normal force exceeds TRANSIENT_FACTOR x its last-period maximum."""
    t = result["t"]
    if t[-1] < 2 * period:
        return None
    force = result[f"{joint}_normal_force"].sum(axis=1)
    settled = force[t >= t[-1] - period].max()
    above = np.flatnonzero(force > TRANSIENT_FACTOR * max(settled, 1e-9))
    return float(t[above[-1]]) if above.size else 0.0


def acceleration_rms_deviation(result: SimulationResult, ideal: SimulationResult, t_from: float = 0.0) -> float:
    """RMS over time of |a_ee - a_ee_ideal| (ideal interpolated on the clearance run's records)."""
    t = result["t"]
    mask = t >= t_from
    t = t[mask]
    if t.size < 2:
        return float("nan")
    ideal_acc = np.column_stack([np.interp(t, ideal["t"], ideal["ee_acceleration"][:, k]) for k in range(3)])
    deviation = np.linalg.norm(result["ee_acceleration"][mask] - ideal_acc, axis=1)
    return float(np.sqrt(np.trapezoid(deviation**2, t) / (t[-1] - t[0])))


def summary(results: dict[str, SimulationResult], period: float = 1.0) -> dict:
    """The numbers of ``summary.json``."""
    ideal = results["ideal"]
    out: dict = {"period_s": period, "transient_definition": f"last time a joint's normal force exceeds {TRANSIENT_FACTOR} x its maximum over the last period"}
    for name, result in results.items():
        entry = {
            "status": result.status,
            "message": result.message,
            "t_end": result.t_end,
            "counts": result.counts,
            "peak_driving_force_N": np.abs(result["driving_force"]).max(axis=0).round(3).tolist(),
            "max_constraint_residual": float(result["constraint_residual"].max()),
        }
        if result.clearance_joints:
            entry["peak_contact_force_N"] = {j: float(result[f"{j}_normal_force"].sum(axis=1).max()) for j in result.clearance_joints}
            entry["max_penetration_m"] = {j: float(result[f"{j}_penetration"].max()) for j in result.clearance_joints}
            transients = {j: transient_duration(result, j, period) for j in result.clearance_joints}
            entry["initial_transient_s"] = transients
            entry["ee_acceleration_rms_deviation_from_ideal"] = acceleration_rms_deviation(result, ideal)
            settled = [v for v in transients.values() if v is not None]
            if settled:
                entry["ee_acceleration_rms_deviation_after_transient"] = acceleration_rms_deviation(result, ideal, max(settled))
            ideal_pos = np.column_stack([np.interp(result["t"], ideal["t"], ideal["ee_position"][:, k]) for k in range(3)])
            entry["max_ee_position_deviation_m"] = float(np.linalg.norm(result["ee_position"] - ideal_pos, axis=1).max())
        out[name] = entry
    return out


def _figure(rows: int, cols: int, size=(11, 7)):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(rows, cols, figsize=size, squeeze=False)
    return fig, axes


def _save(fig, path: Path) -> Path:
    fig.tight_layout()
    return atomic_write_png(fig, path, dpi=120, close=True)


UM = 1e6


def figure_7(results: dict[str, SimulationResult], path: Path) -> Path:
    """Centre trajectories and time histories in the clearance joints (paper Figure 7)."""
    aligned, misaligned = results["compound"], results["compound_misaligned"]
    fig, axes = _figure(3, 2, (12, 12))
    for result, label in ((aligned, "aligned"), (misaligned, "misaligned")):
        ecc = result["S1_eccentricity"] * UM
        axes[0, 0].plot(ecc[:, 0], ecc[:, 1], lw=0.7, label=label)
        for k, axis in enumerate("xyz"):
            axes[0, 1].plot(result["t"], ecc[:, k], lw=0.7, label=f"{axis}, {label}")
    axes[0, 0].set(title="(a) S1: ball centre in the socket frame", xlabel="x (um)", ylabel="y (um)", aspect="equal")
    axes[0, 1].set(title="(b) S1: time history", xlabel="time (s)", ylabel="eccentricity (um)")
    for row, (result, label) in enumerate(((aligned, "aligned"), (misaligned, "misaligned")), start=1):
        ecc = result["R1_eccentricity"] * UM  # (n, 2 rings, 3)
        for ring, name in enumerate(("top", "bottom")):
            axes[row, 0].plot(ecc[:, ring, 0], ecc[:, ring, 1], lw=0.7, label=f"{name} ring")
            for k, axis in enumerate("xy"):
                axes[row, 1].plot(result["t"], ecc[:, ring, k], lw=0.7, label=f"{name} {axis}")
        axes[row, 0].set(title=f"({'c' if row == 1 else 'e'}) R1 {label}: bearing ring centres in the journal frame", xlabel="x (um)", ylabel="y (um)", aspect="equal")
        axes[row, 1].set(title=f"({'d' if row == 1 else 'f'}) R1 {label}: time history", xlabel="time (s)", ylabel="radial offset (um)")
    for ax in axes.flat:
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7)
    return _save(fig, path)


def figure_8(results: dict[str, SimulationResult], path: Path) -> Path:
    """Contact forces and driving forces (paper Figure 8)."""
    aligned, misaligned = results["compound"], results["compound_misaligned"]
    fig, axes = _figure(2, 2, (12, 8))
    for result, label in ((aligned, "aligned"), (misaligned, "misaligned")):
        axes[0, 0].plot(result["t"], result["S1_normal_force"].sum(axis=1), lw=0.7, label=label)
        axes[0, 1].plot(result["t"], result["R1_normal_force"].sum(axis=1), lw=0.7, label=label)
    axes[0, 0].set(title="(a) contact force at S1", xlabel="time (s)", ylabel="normal force (N)", yscale="symlog")
    axes[0, 1].set(title="(b) contact force at R1 (all candidates)", xlabel="time (s)", ylabel="normal force (N)", yscale="symlog")
    for ax, result, label in ((axes[1, 0], aligned, "(c) axes aligned"), (axes[1, 1], misaligned, "(d) initial misalignment")):
        for k, name in enumerate(result.metadata.get("actuated_joints", [])):
            ax.plot(result["t"], result["driving_force"][:, k], lw=0.7, label=name)
        ideal = results["ideal"]
        ax.plot(ideal["t"], ideal["driving_force"][:, -1], "k--", lw=0.8, label="P5 ideal")
        ax.set(title=f"{label}: driving forces", xlabel="time (s)", ylabel="driving force (N)")
    for ax in axes.flat:
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7)
    return _save(fig, path)


def figure_9(results: dict[str, SimulationResult], path: Path) -> Path:
    """End-effector displacement, velocity, acceleration in the paper's X and Y: ideal against clearance (paper Figure 9)."""
    fig, axes = _figure(3, 2, (12, 11))
    quantities = (("ee_position", "displacement (mm)", 1e3), ("ee_velocity", "velocity (mm/s)", 1e3), ("ee_acceleration", "acceleration (m/s^2)", 1.0))
    letters = iter("abcdef")
    for row, (key, unit, scale) in enumerate(quantities):
        for col, (axis, column, sign) in enumerate(PAPER_AXES[:2]):
            ax = axes[row, col]
            for name, style in (("compound", "-"), ("compound_misaligned", "-"), ("ideal", "k--")):
                result = results[name]
                ax.plot(result["t"], sign * result[key][:, column] * scale, style, lw=0.7 if name != "ideal" else 1.0, label=name)
            ax.set(title=f"({next(letters)}) {axis}-{key.split('_')[1]}", xlabel="time (s)", ylabel=f"{axis} {unit}")
            ax.grid(alpha=0.3)
            ax.legend(fontsize=7)
    return _save(fig, path)


def figure10_series(t_end: float = FIGURE10_T_END, scene: str = FIGURE10_SCENE) -> dict:
    """End-effector positions of one scene by the two formulations, on the Lagrange run's records.

    Both integrate the same :class:`robot.run.Run` (same initial state) with the
    validation solver (:data:`robot.validation.settings.VALIDATION_SOLVER`, an
    explicit Runge-Kutta: the Newton-Euler event loop takes no other), like for
    like; the Newton-Euler positions are its dense output at the Lagrange record times. Returns ``t``, ``lagrange`` and ``newton_euler`` (n, 3) world
    positions, and each run's status and CPU seconds.
    """
    import time

    from robot.run import run_scene
    from robot.validation import newton_euler as NE
    from robot.validation.settings import validation_run

    run = validation_run(scene, duration=t_end)
    lagrange = run_scene(run)
    t = np.asarray(lagrange["t"], dtype=float)
    started = time.process_time()
    newton_euler = NE.simulate(run, t_eval=t)
    ne_cpu = time.process_time() - started
    ne_t = np.asarray(newton_euler.eval_arrays.get("t", t), dtype=float)
    ne_position = np.asarray(newton_euler.eval_arrays["ee_position"], dtype=float)
    n = min(len(ne_t), len(t))
    return {
        "scene": scene, "t_end": t_end, "t": t[:n], "lagrange": np.asarray(lagrange["ee_position"], dtype=float)[:n], "newton_euler": ne_position[:n],
        "lagrange_status": lagrange.message, "newton_euler_status": newton_euler.run.message,
        "lagrange_cpu_s": float(lagrange.counts["cpu_time"]), "newton_euler_cpu_s": ne_cpu,
    }


def figure10_numbers(series: dict) -> dict:
    """Largest difference of the two formulations per paper axis (summary.json ``figure10``)."""
    difference = series["newton_euler"] - series["lagrange"]
    out = {key: series[key] for key in ("scene", "t_end", "lagrange_status", "newton_euler_status", "lagrange_cpu_s", "newton_euler_cpu_s")}
    for axis, column, _ in PAPER_AXES:
        out[f"max_abs_difference_{axis}_m"] = float(np.max(np.abs(difference[:, column]))) if len(difference) else float("nan")
        out[f"range_{axis}_m"] = float(np.ptp(series["lagrange"][:, column])) if len(difference) else float("nan")
    return out


def figure_10(series: dict, path: Path) -> Path:
    """End-effector X and Y displacement, Newton-Euler against Lagrange multipliers (paper Figure 10).

    Panel (c), Z, is ours: X and Y of the platform centre follow almost wholly from the five
    prescribed leg lengths (both formulations meet them to the constraint tolerance), while
    Z, out of the RPS limb's plane, is the direction the clearances free: it is where the two
    formulations' dynamics are compared.
    """
    fig, axes = _figure(1, 3, (17, 4.5))
    t = series["t"]
    for ax, (letter, (axis, column, sign)) in zip(axes[0], zip("abc", PAPER_AXES)):
        ax.plot(t, sign * series["lagrange"][:, column] * 1e3, lw=1.6, label="Lagrange multipliers")
        ax.plot(t, sign * series["newton_euler"][:, column] * 1e3, "--", lw=1.0, label="Newton-Euler")
        ax.set(title=f"({letter}) {axis}-displacement, {series['scene']}", xlabel="time (s)", ylabel=f"{axis} (mm)")
        twin = ax.twinx()
        twin.plot(t, sign * (series["newton_euler"][:, column] - series["lagrange"][:, column]) * UM, color="0.5", lw=0.6)
        twin.set_ylabel("Newton-Euler - Lagrange (um)", color="0.4")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7, loc="upper left")
    return _save(fig, path)


def write_outputs(results: dict[str, SimulationResult], out: Path, figure10: dict | None = None) -> list[Path]:
    """All figures and ``summary.json``; figure 10 when its ``figure10_series`` is given."""
    written = [
        figure_7(results, out / "figure7_clearance_joints.png"),
        figure_8(results, out / "figure8_forces.png"),
        figure_9(results, out / "figure9_end_effector.png"),
    ]
    if figure10 is not None:
        written.append(figure_10(figure10, out / "figure10_newton_euler.png"))
    numbers = summary(results)
    if figure10 is not None:
        numbers["figure10"] = figure10_numbers(figure10)
    claims = evaluate_claims(results, numbers["period_s"])
    numbers["claims"] = claims_json(claims)
    written.append(atomic_write_text(out / "claims.md", claims_report(claims)))
    written.append(atomic_write_text(out / "summary.json", json.dumps(numbers, indent=2)))
    return written
