"""Deviations and statistics between the engines' histories.

Every engine's run is reduced to an :class:`EngineSeries` (time, driving forces,
end-effector position, the positions of every body's link-frame origin, contact
normal force per clearance joint, contact onset times, wall time). Two kinds of
comparison:

* **pointwise**, where the runs must agree to integration accuracy: over the
  whole run for the ideal mechanism, and before the first contact onset for
  clearance joints (after a few impacts the penalty-contact dynamics is
  chaotic: tolerance-sized differences grow until the histories separate).
  Newton-Euler is evaluated at the Lagrange record times from its dense output
  (no interpolation); Exudyn's fixed steps are compared with the Lagrange
  histories interpolated by cubic splines on the smooth pre-impact part.
  Relative driving-force deviations are divided by the largest driving force
  of the Lagrange run in the same window. Compared: the driving forces, the
  end-effector position and the **body positions** (the largest distance
  between the two engines' positions of any body's link-frame origin,
  ``body_position_max_m``): the driving forces and the end effector alone miss
  a wrong motion of the other bodies, e.g. in a mechanism without actuators
  whose end effector does not move.
* **statistics**, which survive the separation: peak, time-averaged mean and
  RMS of the contact normal force of each clearance joint (sum over its
  candidates), time-averaged driving forces, RMS of the end-effector deviation
  from the ideal (prescribed) motion (only with a platform-pose drive, which
  prescribes the end effector's motion; ``None`` otherwise), number of
  impacts, and the first impact (onset time and peak force within
  ``FIRST_IMPACT_WINDOW`` after it).
  Time averages are trapezoidal integrals over the (non-uniform) records
  divided by the duration.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.interpolate import CubicSpline

#: the first impact's peak is searched within this time after its onset (s)
FIRST_IMPACT_WINDOW = 5e-4


@dataclass
class EngineSeries:
    """One engine's histories (rows sorted by time; NaN where a value is not defined)."""

    name: str
    t: np.ndarray
    driving_force: np.ndarray
    ee_position: np.ndarray
    contact_force: dict = field(default_factory=dict)  # site -> (n,) sum of candidate normal forces
    onsets: np.ndarray = field(default_factory=lambda: np.zeros(0))  # contact onset times (any candidate)
    wall_time: float = float("nan")
    success: bool = True
    message: str = ""
    ee_ideal: np.ndarray | None = None  # (n, 3) prescribed platform position at t; None: no platform-pose drive
    integration_time: float = float("nan")  # wall time of the time integration alone
    penetration: dict = field(default_factory=dict)  # site -> (n,) deepest penetration over the candidates
    solver: dict = field(default_factory=dict)  # integrator settings the engine actually ran with
    body_origins: np.ndarray | None = None  # (n, bodies, 3) world positions of the bodies' link-frame origins

    @property
    def first_onset(self) -> float:
        return float(self.onsets.min()) if self.onsets.size else float("inf")


def _time_average(t: np.ndarray, values: np.ndarray, duration: float) -> np.ndarray:
    ok = np.all(np.isfinite(values.reshape(len(t), -1)), axis=1)
    return np.trapezoid(values[ok], t[ok], axis=0) / duration


def statistics(series: EngineSeries, duration: float) -> dict:
    """Peak, mean and RMS of the contact forces, mean driving forces, RMS EE deviation from ideal."""
    out: dict = {
        "mean_driving_force_N": _time_average(series.t, series.driving_force, duration).tolist(),
        "n_impacts": int(series.onsets.size),
        "first_onset_s": series.first_onset if np.isfinite(series.first_onset) else None,
    }
    out["rms_ee_deviation_from_ideal_m"] = out["max_ee_deviation_from_ideal_m"] = None  # no prescribed end-effector motion
    if series.ee_ideal is not None:
        deviation = np.linalg.norm(series.ee_position - series.ee_ideal, axis=1)
        out["rms_ee_deviation_from_ideal_m"] = float(np.sqrt(_time_average(series.t, deviation**2, duration)))
        out["max_ee_deviation_from_ideal_m"] = float(np.nanmax(deviation))
    sites = {}
    for site, force in series.contact_force.items():
        entry = {
            "peak_N": float(np.nanmax(force)) if force.size else 0.0,
            "mean_N": float(_time_average(series.t, force, duration)),
            "rms_N": float(np.sqrt(_time_average(series.t, force**2, duration))),
        }
        if np.isfinite(series.first_onset):
            window = (series.t >= series.first_onset) & (series.t <= series.first_onset + FIRST_IMPACT_WINDOW)
            entry["first_impact_peak_N"] = float(np.nanmax(force[window])) if np.any(window) else 0.0
            if site in series.penetration:
                entry["first_impact_max_penetration_m"] = float(max(0.0, np.nanmax(series.penetration[site][window]))) if np.any(window) else 0.0
        sites[site] = entry
    out["contact"] = sites
    return out


def relative_difference(value: float, reference: float, floor: float = 0.0) -> float | None:
    """(value - reference) / |reference|; None when undefined or |reference| <= floor (round-off level)."""
    if value is None or reference is None or not np.isfinite(value) or not np.isfinite(reference) or abs(reference) <= floor:
        return None
    return float((value - reference) / abs(reference))


def compare_statistics(stats: dict, reference: dict) -> dict:
    """Relative differences (engine - reference) / |reference| of the statistics."""
    out = {
        "mean_driving_force": [relative_difference(a, b) for a, b in zip(stats["mean_driving_force_N"], reference["mean_driving_force_N"])],
        "n_impacts": stats["n_impacts"] - reference["n_impacts"],
    }
    if stats.get("first_onset_s") is not None and reference.get("first_onset_s") is not None:
        out["first_onset_s"] = stats["first_onset_s"] - reference["first_onset_s"]
    if stats.get("rms_ee_deviation_from_ideal_m") is not None:
        out["rms_ee_deviation_from_ideal"] = relative_difference(
            stats["rms_ee_deviation_from_ideal_m"], reference["rms_ee_deviation_from_ideal_m"], floor=1e-9
        )
    for site, entry in stats["contact"].items():
        ref = reference["contact"].get(site, {})
        out[site] = {key: relative_difference(entry[key], ref.get(key), floor=1e-12) for key in entry}
    return out


def _window(series: EngineSeries, t_end: float) -> np.ndarray:
    return (series.t > 0.0) & (series.t < t_end) & np.all(np.isfinite(series.driving_force), axis=1)


def pointwise_on_reference_times(series: EngineSeries, reference: EngineSeries, t_end: float) -> dict:
    """Maximum deviations at identical times (``series`` sampled at the reference's times), for t < t_end."""
    if len(series.t) != len(reference.t) or not np.allclose(series.t, reference.t, rtol=0, atol=1e-15):
        raise ValueError("pointwise_on_reference_times needs the series sampled at the reference's times")
    mask = _window(reference, t_end) & np.all(np.isfinite(series.driving_force), axis=1)
    scale = _scale(reference, reference.t < t_end)
    d_bodies = _body_difference(series.body_origins, reference.body_origins, mask, lambda values: values[mask])
    return _deviations(
        series.driving_force[mask] - reference.driving_force[mask], series.ee_position[mask] - reference.ee_position[mask], d_bodies, scale, t_end
    )


def pointwise_interpolated(series: EngineSeries, reference: EngineSeries, t_end: float) -> dict:
    """Maximum deviations with the reference interpolated (cubic spline) at the series' times, for t < t_end."""
    ref_mask = (reference.t < t_end) & np.all(np.isfinite(reference.driving_force), axis=1)
    t_ref, keep = np.unique(reference.t[ref_mask], return_index=True)
    mask = _window(series, min(t_end, t_ref[-1]))
    force = CubicSpline(t_ref, reference.driving_force[ref_mask][keep])(series.t[mask])
    ee = CubicSpline(t_ref, reference.ee_position[ref_mask][keep])(series.t[mask])
    d_bodies = _body_difference(
        series.body_origins, reference.body_origins, mask, lambda values: CubicSpline(t_ref, values[ref_mask][keep])(series.t[mask])
    )
    return _deviations(series.driving_force[mask] - force, series.ee_position[mask] - ee, d_bodies, _scale(reference, ref_mask), t_end)


def _body_difference(origins: np.ndarray | None, reference: np.ndarray | None, mask: np.ndarray, at_times) -> np.ndarray | None:
    """(points, bodies, 3) body-origin differences at the compared times (``at_times``: the reference there); None if not recorded.

    Every engine records the bodies of :func:`robot.validation.bodies.read_geometry`, in its order: other
    shapes are a bug of an engine, raised, not a comparison left out."""
    if origins is None or reference is None:
        return None
    if origins.shape[1:] != reference.shape[1:]:
        raise ValueError(f"body origins of shape {origins.shape[1:]} cannot be compared with the reference's {reference.shape[1:]}")
    return origins[mask] - at_times(reference)


def _scale(reference: EngineSeries, mask: np.ndarray) -> float:
    """Largest |driving force| of the reference in the window (the denominator of relative deviations)."""
    values = reference.driving_force[mask]
    values = values[np.isfinite(values)]
    return float(np.max(np.abs(values))) if values.size else float("nan")


def _deviations(d_force: np.ndarray, d_ee: np.ndarray, d_bodies: np.ndarray | None, scale: float, t_end: float) -> dict:
    """The largest deviations: driving forces (N and relative to ``scale``), end effector and body origins (m).

    ``None`` where nothing is compared (no actuator, no point in the window, no body).
    """
    d_force = np.abs(d_force)
    d_ee = np.linalg.norm(d_ee, axis=1)
    d_bodies = np.zeros((0, 0)) if d_bodies is None else np.linalg.norm(d_bodies, axis=2)
    out = {
        "window_end_s": float(t_end) if np.isfinite(t_end) else None,
        "n_points": int(len(d_ee)),
        "driving_force_max_abs_N": float(d_force.max()) if d_force.size else None,
        "driving_force_max_rel": float(d_force.max() / scale) if d_force.size else None,
        "driving_force_scale_N": scale,
        "ee_position_max_m": float(d_ee.max()) if d_ee.size else None,
        "body_position_max_m": float(d_bodies.max()) if d_bodies.size else None,
    }
    return out


def _largest_per_row(values: np.ndarray) -> np.ndarray:
    """Largest finite entry of each row; NaN for a row without one (no actuator: no driving force to compare)."""
    if values.shape[1] == 0:
        return np.full(values.shape[0], np.nan)
    return np.nanmax(values, axis=1)


def deviation_history(series: EngineSeries, reference: EngineSeries, same_times: bool) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(t, max |dF| over actuators, |dEE|) for plotting; the reference is interpolated unless ``same_times``."""
    if same_times:
        t = reference.t
        d_force = _largest_per_row(np.abs(series.driving_force - reference.driving_force))
        d_ee = np.linalg.norm(series.ee_position - reference.ee_position, axis=1)
        return t, d_force, d_ee
    ok = np.all(np.isfinite(reference.driving_force), axis=1)
    t_ref, keep = np.unique(reference.t[ok], return_index=True)
    mask = (series.t > 0) & (series.t <= t_ref[-1])
    force = CubicSpline(t_ref, reference.driving_force[ok][keep])(series.t[mask])
    ee = CubicSpline(t_ref, reference.ee_position[ok][keep])(series.t[mask])
    return series.t[mask], _largest_per_row(np.abs(series.driving_force[mask] - force)), np.linalg.norm(series.ee_position[mask] - ee, axis=1)


def separation_time(series: EngineSeries, reference: EngineSeries, same_times: bool, threshold: float = 1e-6) -> float | None:
    """First time the end-effector positions of the two runs differ by more than ``threshold`` (m); None if never."""
    t, _, d_ee = deviation_history(series, reference, same_times)
    beyond = np.flatnonzero(d_ee > threshold)
    return float(t[beyond[0]]) if beyond.size else None
