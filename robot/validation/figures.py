"""Comparison figures of the validation study (PNG; every axis labelled with its unit).

Per scene:

* ``validation_<scene>.png``: end-effector x and y displacement (seed paper
  Figure 10: X- and Y-displacement, Newton-Euler against Lagrange), the
  end-effector deviation from the ideal (prescribed) motion, the driving forces
  and the contact normal forces, one line style per engine (a panel says so
  when the drive prescribes no end-effector motion, i.e. is not a platform
  pose, or when there is no prescribed-motion actuator);
* ``deviation_<scene>.png``: the largest driving-force deviation and the
  end-effector deviation of Newton-Euler and Exudyn from the Lagrange model
  against time (log scale), the first impact marked.
"""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from robot.io.atomic import atomic_write_png  # noqa: E402
from robot.validation import comparison as CMP  # noqa: E402

STYLE = {
    "lagrange": dict(color="black", linestyle="-", linewidth=1.4, label="Lagrange (Pinocchio)"),
    "newton_euler": dict(color="tab:red", linestyle="--", linewidth=1.1, label="Newton-Euler"),
    "exudyn": dict(color="tab:blue", linestyle=":", linewidth=1.3, label="Exudyn"),
}
ACTUATOR_COLORS = ["tab:blue", "tab:orange", "tab:green", "tab:red", "tab:purple"]


def _engines(series: dict) -> list[str]:
    return [name for name in ("lagrange", "newton_euler", "exudyn") if name in series]


def file_label(scene: str) -> str:
    """The part of a figure's file name that names the scene: a shipped scene's name, a scene file's stem.

    A scene given as a path (``/tmp/x/pendulum.toml``) would otherwise put its
    folders into the figure's name (``OUT/validation_/tmp/x/...``).
    """
    return Path(scene).stem if scene.endswith(".toml") or "/" in scene else scene


def scene_figures(scene: str, series: dict, metrics: dict, out: Path) -> list[Path]:
    """``validation_<scene>.png`` and, with more than one engine, ``deviation_<scene>.png`` in ``out`` (:func:`file_label`)."""
    paths = [_overview(scene, series, metrics, out)]
    if len(_engines(series)) > 1:
        paths.append(_deviations(scene, series, metrics, out))
    return paths


def _overview(scene: str, series: dict, metrics: dict, out: Path) -> Path:
    fig, axes = plt.subplots(2, 2, figsize=(13, 8.5), constrained_layout=True)
    engines = _engines(series)
    ax = axes[0, 0]
    for name in engines:
        s = series[name]
        style = dict(STYLE[name])
        label = style.pop("label")
        ax.plot(s.t, 1e3 * s.ee_position[:, 0], label=f"x, {label}", **style)
        ax.plot(s.t, 1e3 * s.ee_position[:, 1], alpha=0.6, **style)
    ax.set(xlabel="time t [s]", ylabel="end-effector displacement [mm]", title="end-effector x (and y, faint)")
    ax.legend(fontsize=8)
    _ideal_deviation_panel(axes[0, 1], series, engines)
    _driving_force_panel(axes[1, 0], series, engines)
    ax = axes[1, 1]
    sites = metrics.get("sites", [])
    if sites:
        for name in engines:
            s = series[name]
            style = dict(STYLE[name])
            label = style.pop("label")
            for j, site in enumerate(sites):
                ax.plot(s.t, s.contact_force[site], label=f"{site}, {label}", alpha=1.0 if j == 0 else 0.7, **style)
        ax.set_yscale("symlog", linthresh=10.0)
        ax.set(xlabel="time t [s]", ylabel="contact normal force [N]", title="clearance-joint normal force (R1: sum of candidates)")
        ax.legend(fontsize=8)
    else:
        ax.axis("off")
        ax.text(0.02, 0.5, _summary_text(metrics), family="monospace", fontsize=9, va="center")
    fig.suptitle(f"Validation, scene '{scene}' ({metrics['duration_s']} s)")
    return _save(fig, out / f"validation_{file_label(scene)}.png")


def _note(ax, text: str) -> None:
    """An empty panel that says why it is empty."""
    ax.axis("off")
    ax.text(0.5, 0.5, text, ha="center", va="center", fontsize=10, wrap=True)


def _ideal_deviation_panel(ax, series: dict, engines: list[str]) -> None:
    """End-effector deviation from the prescribed motion (platform-pose drives only: other drives prescribe no end-effector motion)."""
    if series[engines[0]].ee_ideal is None:
        _note(ax, "no prescribed end-effector motion\n(the drive is not a platform pose):\nno deviation from an ideal motion")
        return
    for name in engines:
        s = series[name]
        style = dict(STYLE[name])
        label = style.pop("label")
        dev = 1e6 * (s.ee_position - s.ee_ideal)
        ax.plot(s.t, dev[:, 0], label=f"x, {label}", **style)
        ax.plot(s.t, dev[:, 1], alpha=0.5, **{**style, "linewidth": 0.8})
    ax.set(xlabel="time t [s]", ylabel="deviation from ideal motion [um]", title="end-effector deviation from the prescribed motion (x; y faint)")
    ax.legend(fontsize=8)


def _driving_force_panel(ax, series: dict, engines: list[str]) -> None:
    """Every actuator's driving force, one colour per actuator, one line style per engine."""
    if series[engines[0]].driving_force.shape[1] == 0:
        _note(ax, "no prescribed-motion actuator: no driving force")
        return
    for name in engines:
        s = series[name]
        style = dict(STYLE[name])
        style.pop("label")
        style.pop("color")
        for k in range(s.driving_force.shape[1]):
            ax.plot(s.t, s.driving_force[:, k], color=ACTUATOR_COLORS[k % 5], label=f"A{k + 1}" if name == "lagrange" else None, **style)
    ax.set(xlabel="time t [s]", ylabel="driving force [N]", title="driving forces (solid Lagrange, dashed N-E, dotted Exudyn)")
    ax.legend(fontsize=8, ncol=5)


def _save(fig, path: Path) -> Path:
    """Write ``fig`` to the PNG ``path`` atomically (a reader or a stop never meets half an image) and close it."""
    return atomic_write_png(fig, path, dpi=120, close=True)


def _summary_text(metrics: dict) -> str:
    lines = ["max deviation from the Lagrange model (whole run):"]
    for name, entry in metrics["engines"].items():
        pw = entry.get("pointwise_before_first_impact")
        if pw:
            if pw["driving_force_max_abs_N"] is not None:
                lines.append(f"{name}: driving force {pw['driving_force_max_abs_N']:.2e} N ({pw['driving_force_max_rel']:.1e} rel.),")
            for label, key in (("end effector", "ee_position_max_m"), ("bodies", "body_position_max_m")):
                if pw.get(key) is not None:
                    lines.append(f"{name}: {label} {pw[key]:.2e} m")
    return "\n".join(lines)


def _deviations(scene: str, series: dict, metrics: dict, out: Path) -> Path:
    fig, axes = plt.subplots(1, 2, figsize=(13, 4.5), constrained_layout=True)
    lagrange = series["lagrange"]
    pairs = []
    if "newton_euler@lagrange" in series:
        pairs.append(("newton_euler", CMP.deviation_history(series["newton_euler@lagrange"], lagrange, same_times=True)))
    if "exudyn" in series:
        pairs.append(("exudyn", CMP.deviation_history(series["exudyn"], lagrange, same_times=False)))
    floor = 1e-16
    for name, (t, d_force, d_ee) in pairs:
        style = dict(STYLE[name])
        label = style.pop("label")
        axes[0].semilogy(t, np.maximum(d_force, floor), label=label, **style)
        axes[1].semilogy(t, np.maximum(d_ee, floor), label=label, **style)
    first = metrics.get("first_impact_s")
    for ax in axes:
        if first is not None:
            ax.axvline(first, color="gray", linewidth=0.8)
            ax.text(first, ax.get_ylim()[1], " first impact", color="gray", fontsize=8, va="top")
        ax.set_xlabel("time t [s]")
        ax.legend(fontsize=8)
    axes[0].set(ylabel="max |driving force - Lagrange| [N]", title="driving-force deviation from the Lagrange model")
    axes[1].set(ylabel="|end-effector position - Lagrange| [m]", title="end-effector deviation from the Lagrange model")
    fig.suptitle(f"Deviation from the Lagrange model, scene '{scene}' (Exudyn: Lagrange interpolated by cubic splines)")
    return _save(fig, out / f"deviation_{file_label(scene)}.png")
