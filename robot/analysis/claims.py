"""The seed paper's five qualitative claims, each measured on the main job's results.

The paper (section "Dynamics response analysis", Figures 7-9) states, for the
4-UPS/RPS with the compound clearance (S1 spherical, R1 revolute), aligned
(``compound``) against initially misaligned (``compound_misaligned``) bearing:

(a) "Considering misalignment of axis, contact force of high amplitude appears in
    the initial stage ... the peak values of the driving forces are higher than
    the case of axis alignment."  Measured: the peak total normal force of R1
    and of S1 and the peak |driving force| of the RPS limb's actuator over the
    initial stage ``[0, INITIAL_STAGE]``, misaligned against aligned. Holds when
    all three are higher with the misalignment.
(b) "The system gradually stabilizes as it enters the continuous contact state
    ... From the second cycle, the time history diagram of the two trajectories
    basically coincides."  Measured over the second period ``[T, 2T]``: the
    fraction of time each clearance joint is in contact (total normal force > 0)
    in both cases, and the RMS difference of the end-effector position between
    the two cases, set against the RMS deviation of the aligned case from the
    ideal mechanism (what clearance does at all). Holds when both joints are in
    contact at least ``CONTINUOUS_CONTACT`` of the time in both cases and the
    difference is at most ``COINCIDE_RATIO`` of the clearance-induced deviation.
(c) "In the stable stage ... the peak contact force of revolute joint is less
    than that of spherical joint."  Measured: peak total normal force of R1 over
    that of S1 over ``[T, 2T]``, each case. Holds when the ratio is below 1 in
    both cases.
(d) "In the case of initial alignment, the spherical joint does not move in the
    Z direction."  Measured (aligned case): the excursion of the S1 centre out of
    the RPS limb's plane (the plane that holds the ideal mechanism's S1 path and
    the R1 centre), peak to peak; also the range of the S1 eccentricity's third
    component in the socket frame. Holds when the out-of-plane excursion is below
    the S1 radial clearance (the ball cannot be said to move if it stays
    within its own clearance).
(e) "The compound clearance joint effect on the vibrational levels of
    displacement curves is inconspicuous. However ... the velocity and
    acceleration curves of the moving platform fluctuate significantly."
    Measured (aligned case, after the first period): RMS deviation from the ideal
    of the end-effector position, velocity and acceleration, each relative to the
    RMS of the ideal signal's variation. Holds when the displacement's relative
    deviation is below ``INCONSPICUOUS`` and the acceleration's is above
    ``SIGNIFICANT``.

The thresholds are ours (the paper gives none) and are reported with every
verdict, so a reader can apply their own.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

INITIAL_STAGE = 0.1  # s: the initial stage of claim (a)
CONTINUOUS_CONTACT = 0.99  # claim (b): fraction of time in contact
COINCIDE_RATIO = 0.1  # claim (b): case difference / clearance-induced deviation
INCONSPICUOUS = 0.01  # claim (e): relative RMS deviation of the displacement
SIGNIFICANT = 0.1  # claim (e): relative RMS deviation of the acceleration
LIMB_ACTUATOR = "P5"  # the RPS limb's actuator
ALIGNED, MISALIGNED, IDEAL = "compound", "compound_misaligned", "ideal"


@dataclass
class Claim:
    """One claim: the paper's words, what was measured, the verdict and the numbers."""

    label: str
    statement: str
    measured: str
    holds: bool | None
    numbers: dict[str, Any] = field(default_factory=dict)
    criterion: str = ""

    def verdict(self) -> str:
        return "n/a (run too short)" if self.holds is None else ("holds" if self.holds else "does not hold")


def _window(result, t0: float, t1: float) -> np.ndarray:
    t = result["t"]
    return (t >= t0) & (t <= t1)


def _peak(result, key: str, mask: np.ndarray, column: int | None = None) -> float:
    values = result[key]
    values = values.sum(axis=1) if column is None and values.ndim == 2 else values[:, column] if column is not None else values
    return float(np.max(np.abs(values[mask]))) if mask.any() else float("nan")


def _time_rms(t: np.ndarray, values: np.ndarray) -> float:
    if t.size < 2 or t[-1] <= t[0]:
        return float("nan")
    return float(np.sqrt(np.trapezoid(values**2, t) / (t[-1] - t[0])))


def _on_times(result, key: str, t: np.ndarray) -> np.ndarray:
    values = result[key]
    return np.column_stack([np.interp(t, result["t"], values[:, k]) for k in range(values.shape[1])])


def _actuator_column(result) -> int:
    names = list(result.metadata.get("actuated_joints", []))
    return names.index(LIMB_ACTUATOR) if LIMB_ACTUATOR in names else len(names) - 1


def claim_a(results: dict) -> Claim:
    aligned, misaligned = results[ALIGNED], results[MISALIGNED]
    numbers: dict[str, Any] = {"initial_stage_s": INITIAL_STAGE}
    higher = []
    for name, key, column in (("R1_peak_N", "R1_normal_force", None), ("S1_peak_N", "S1_normal_force", None), (f"{LIMB_ACTUATOR}_peak_N", "driving_force", _actuator_column(aligned))):
        a = _peak(aligned, key, _window(aligned, 0.0, INITIAL_STAGE), column)
        m = _peak(misaligned, key, _window(misaligned, 0.0, INITIAL_STAGE), column)
        numbers[name] = {"aligned": a, "misaligned": m}
        higher.append(m > a)
    return Claim(
        "a", "initial misalignment gives higher contact and driving-force peaks in the initial stage",
        f"peaks over [0, {INITIAL_STAGE} s], misaligned vs aligned", all(higher), numbers,
        "misaligned higher for R1, S1 and the limb actuator",
    )


def _second_period(results: dict, period: float) -> tuple[float, float] | None:
    t_end = min(float(r["t"][-1]) for r in results.values())
    return (period, 2.0 * period) if t_end >= 2.0 * period - 1e-9 else None


def claim_b(results: dict, period: float) -> Claim:
    window = _second_period(results, period)
    statement = "after the transient both cases are in continuous contact and coincide from the second cycle"
    if window is None:
        return Claim("b", statement, "second period", None)
    aligned, misaligned, ideal = results[ALIGNED], results[MISALIGNED], results[IDEAL]
    numbers: dict[str, Any] = {"window_s": list(window), "contact_fraction": {}}
    continuous = True
    for case, result in ((ALIGNED, aligned), (MISALIGNED, misaligned)):
        mask = _window(result, *window)
        t = result["t"][mask]
        for joint in ("R1", "S1"):
            in_contact = (result[f"{joint}_normal_force"].sum(axis=1)[mask] > 0.0).astype(float)
            fraction = float(np.trapezoid(in_contact, t) / (t[-1] - t[0]))
            numbers["contact_fraction"][f"{case}:{joint}"] = fraction
            continuous &= fraction >= CONTINUOUS_CONTACT
    t = aligned["t"][_window(aligned, *window)]
    difference = _time_rms(t, np.linalg.norm(_on_times(misaligned, "ee_position", t) - _on_times(aligned, "ee_position", t), axis=1))
    induced = _time_rms(t, np.linalg.norm(_on_times(aligned, "ee_position", t) - _on_times(ideal, "ee_position", t), axis=1))
    numbers.update(ee_rms_difference_between_cases_m=difference, ee_rms_deviation_from_ideal_m=induced)
    numbers["ee_y_rms_difference_m"] = _time_rms(t, _on_times(misaligned, "ee_position", t)[:, 1] - _on_times(aligned, "ee_position", t)[:, 1])
    coincide = difference <= COINCIDE_RATIO * induced
    return Claim(
        "b", statement, f"contact fraction and end-effector RMS difference over [{window[0]:g}, {window[1]:g}] s",
        bool(continuous and coincide), numbers,
        f"contact >= {CONTINUOUS_CONTACT:.0%} of the time, difference <= {COINCIDE_RATIO:g} x the deviation from the ideal",
    )


def claim_c(results: dict, period: float) -> Claim:
    window = _second_period(results, period)
    statement = "in the stable stage the R1 contact-force peak is below S1's"
    if window is None:
        return Claim("c", statement, "second period", None)
    numbers: dict[str, Any] = {"window_s": list(window)}
    below = True
    for case in (ALIGNED, MISALIGNED):
        result = results[case]
        mask = _window(result, *window)
        r1, s1 = _peak(result, "R1_normal_force", mask), _peak(result, "S1_normal_force", mask)
        numbers[case] = {"R1_peak_N": r1, "S1_peak_N": s1, "R1_over_S1": r1 / s1 if s1 > 0 else float("inf")}
        below &= r1 < s1
    return Claim("c", statement, f"peak normal forces over [{window[0]:g}, {window[1]:g}] s", bool(below), numbers, "R1/S1 < 1 in both cases")


def claim_d(results: dict, out_of_plane: dict[str, np.ndarray]) -> Claim:
    aligned = results[ALIGNED]
    clearance = float(aligned.metadata.get("clearance_geometry", {}).get("S1", {}).get("clearance", float("nan")))
    excursion = float(np.ptp(out_of_plane[ALIGNED])) if out_of_plane[ALIGNED].size else float("nan")
    eccentricity = aligned["S1_eccentricity"]
    numbers = {
        "S1_out_of_plane_peak_to_peak_m": excursion,
        "S1_out_of_plane_max_abs_m": float(np.max(np.abs(out_of_plane[ALIGNED]))),
        "ideal_out_of_plane_max_abs_m": float(np.max(np.abs(out_of_plane[IDEAL]))),
        "S1_eccentricity_z_range_m": float(np.ptp(eccentricity[:, 2])),
        "S1_clearance_m": clearance,
    }
    return Claim(
        "d", "with aligned axes, S1 does not move in Z",
        "S1 centre out of the RPS limb's plane (aligned case), peak to peak", bool(excursion < clearance), numbers,
        "out-of-plane excursion below the S1 clearance",
    )


def claim_e(results: dict, period: float) -> Claim:
    aligned, ideal = results[ALIGNED], results[IDEAL]
    t = aligned["t"][aligned["t"] >= min(period, float(aligned["t"][-1]) / 2)]
    numbers: dict[str, Any] = {"from_s": float(t[0])}
    for key in ("ee_position", "ee_velocity", "ee_acceleration"):
        reference = _on_times(ideal, key, t)
        deviation = _time_rms(t, np.linalg.norm(_on_times(aligned, key, t) - reference, axis=1))
        variation = _time_rms(t, np.linalg.norm(reference - reference.mean(axis=0), axis=1))
        numbers[key] = {"rms_deviation": deviation, "ideal_rms_variation": variation, "relative": deviation / variation if variation > 0 else float("inf")}
    numbers["ee_y_wander_m"] = float(np.ptp(_on_times(aligned, "ee_position", t)[:, 1] - _on_times(ideal, "ee_position", t)[:, 1]))
    holds = numbers["ee_position"]["relative"] < INCONSPICUOUS and numbers["ee_acceleration"]["relative"] > SIGNIFICANT
    return Claim(
        "e", "the displacement effect is inconspicuous; velocity and acceleration fluctuate",
        "end-effector RMS deviation from the ideal relative to the ideal's variation (aligned case)", bool(holds), numbers,
        f"displacement < {INCONSPICUOUS:g}, acceleration > {SIGNIFICANT:g} (relative)",
    )


def s1_out_of_plane(results: dict) -> dict[str, np.ndarray]:
    """Distance (m) of the S1 centre from the RPS limb's plane at every record of each case.

    The plane: through the R1 centre, spanned by the ideal mechanism's S1 path
    (least squares; its residual on the ideal run is reported with claim (d)).
    """
    positions = {name: _frame_positions(results[name], "S1") for name in (IDEAL, ALIGNED)}
    centre = _frame_positions(results[IDEAL], "R1")[0]
    relative = positions[IDEAL] - centre
    normal = np.linalg.svd(relative, full_matrices=False)[2][-1]
    return {name: (p - centre) @ normal for name, p in positions.items()}


def _frame_positions(result, site: str) -> np.ndarray:
    """World position of a site at every record: its parent-side frame, or the joint's origin (Pinocchio)."""
    import pinocchio as pin

    from robot.model.mechanism import build_mechanism

    outer_on = dict(result.metadata.get("clearance_outer_on", {}))
    mechanism = build_mechanism(Path(result.metadata["mechanism_path"]), outer_on)
    model = mechanism.model
    data = model.createData()
    if site in outer_on:
        frame_name = f"{site}_inner" if outer_on[site] == "child" else f"{site}_outer"
    else:
        frame_name = f"{site}_parent"
    out = np.empty((len(result["t"]), 3))
    for i, q in enumerate(result["q"]):
        pin.forwardKinematics(model, data, q)
        if model.existFrame(frame_name):
            out[i] = pin.updateFramePlacement(model, data, model.getFrameId(frame_name)).translation
        else:  # an ideal tree joint: its origin
            out[i] = data.oMi[model.getJointId(site)].translation
    return out


def evaluate_claims(results: dict, period: float = 1.0) -> list[Claim]:
    """The five claims measured on ``ideal``, ``compound`` and ``compound_misaligned`` results."""
    out_of_plane = s1_out_of_plane(results)
    return [claim_a(results), claim_b(results, period), claim_c(results, period), claim_d(results, out_of_plane), claim_e(results, period)]


def claims_json(claims: list[Claim]) -> list[dict]:
    return [{**asdict(c), "verdict": c.verdict()} for c in claims]


def claims_report(claims: list[Claim]) -> str:
    """A short Markdown report: one row per claim, then the numbers."""
    lines = ["# The seed paper's claims, measured", "", "| claim | the paper says | measured | verdict |", "| --- | --- | --- | --- |"]
    lines += [f"| ({c.label}) | {c.statement} | {c.measured} | **{c.verdict()}** (holds when: {c.criterion}) |" for c in claims]
    lines += ["", "Definitions, thresholds and sources: `robot/analysis/claims.py`; the reasoning: `docs/parameters.md`.", ""]
    for c in claims:
        lines.append(f"## ({c.label}) {c.statement}")
        lines += [f"- {key}: {_format(value)}" for key, value in c.numbers.items()]
        lines.append("")
    return "\n".join(lines)


def _format(value: Any) -> str:
    if isinstance(value, dict):
        return ", ".join(f"{k} {_format(v)}" for k, v in value.items())
    if isinstance(value, float):
        return f"{value:.4g}"
    return str(value)
