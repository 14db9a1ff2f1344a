"""Archard wear around a journal bearing: depth per angular bin and total volume.

Archard's law (Archard, "Contact and rubbing of flat surfaces", J. Appl. Phys.
24 (1953) 981-988), in the local form used for clearance joints by Flores
("Modeling and simulation of wear in revolute clearance joints in multibody
systems", Mech. Mach. Theory 44 (2009) 1211-1222): a point of
the bearing surface under contact pressure p, sliding at speed v_s, wears at

    dh/dt = k_w p v_s / H,        h(theta) = (k_w / H) integral p(theta, t) v_s(t) dt,

with k_w the dimensionless wear coefficient and H the hardness (Pa) of the
worn (bearing) material. Integrating over the contact area gives Archard's
volume law dV/dt = k_w F_N v_s / H, so for any force history

    V = (k_w / H) integral F_N(t) v_s(t) dt      (= k_w F_N s / H for a constant force).

Pressure model: the contact patch is the arc of half-width b centred on the
contact-point angle theta_c(t) (measured in the bearing frame about the bearing
axis), with the mean pressure p = F_N / (2 b L) over it (L: contact length).
The half-width is an input (any model), or else the Hertz line contact of two
cylinders (Johnson, *Contact Mechanics*, 1985, Sec. 4.2, two-dimensional contact),

    b = sqrt(4 F_N R* / (pi L E*)),   R* = R_j R_b / (R_b - R_j)  (journal inside bearing),

with E* the combined modulus (``clearance_contact.materials.combined_modulus``).
Hertz assumes b << R*; in a conformal bearing with a small clearance b can
approach R_b and the Hertz patch is then only an estimate (Persson's
conformal-contact model is the usual alternative: pass its half-width).

Binning: the circumference is cut into ``n_bins`` equal bins of width
dtheta = 2 pi / n_bins (bin j covers [j dtheta, (j + 1) dtheta)). Over a
record's time weight, the patch's arc [theta_c - b/R_b, theta_c + b/R_b]
deposits the depth k_w p v_s dt / H on the part of each bin it covers, so a
bin's depth is the coverage-weighted mean over the bin. The time integral is the
trapezoid rule on the records. By construction the binned volume
sum_j h_j R_b dtheta L equals (k_w / H) trapezoid(F_N v_s) exactly, whatever the
binning, the patch widths and the angle history (tested).
"""

from __future__ import annotations

import numpy as np

from .errors import AnalysisError, require_array, require_count, require_positive
from .registry import Field, register
from .timegrid import time_series

#: records processed together (memory: chunk x n_bins floats)
_CHUNK = 2048


def hertz_line_half_width(normal_force, *, journal_radius: float, bearing_radius: float, length: float, combined_modulus: float):
    """Hertz half-width b = sqrt(4 F R* / (pi L E*)) of a journal in a bearing (module docstring)."""
    r_j = require_positive("journal_radius", journal_radius)
    r_b = require_positive("bearing_radius", bearing_radius)
    if not r_b > r_j:
        raise AnalysisError(f"bearing_radius={r_b!r} must exceed journal_radius={r_j!r} (a journal inside a bearing)")
    L = require_positive("length", length)
    e_star = require_positive("combined_modulus", combined_modulus)
    effective_radius = r_j * r_b / (r_b - r_j)
    return np.sqrt(4.0 * np.maximum(normal_force, 0.0) * effective_radius / (np.pi * L * e_star))


def trapezoid_weights(t: np.ndarray) -> np.ndarray:
    """w_i with sum_i w_i f(t_i) = trapezoid integral of f over the records."""
    dt = np.diff(t)
    weights = np.zeros_like(t)
    weights[:-1] += 0.5 * dt
    weights[1:] += 0.5 * dt
    return weights


def arc_coverage(low: np.ndarray, high: np.ndarray, n_bins: int) -> np.ndarray:
    """(m, n_bins) angle of each bin covered by the arcs [low, high] (rad, -2 pi < low <= high < 4 pi, width < 2 pi).

    An arc shorter than the circle covers each angle at most once, so its copies
    shifted by -2 pi, 0, +2 pi meet [0, 2 pi) in disjoint pieces that add up to it.
    """
    edges = np.linspace(0.0, 2 * np.pi, n_bins + 1)
    coverage = np.zeros((len(low), n_bins))
    for shift in (-2 * np.pi, 0.0, 2 * np.pi):
        lo, hi = (low + shift)[:, None], (high + shift)[:, None]
        coverage += np.clip(np.minimum(hi, edges[None, 1:]) - np.maximum(lo, edges[None, :-1]), 0.0, None)
    return coverage


def _check_histories(t, normal_force, contact_angle, sliding_speed, half_width):
    """Checked histories on the time grid with repeated times merged (:func:`.timegrid.time_series`)."""
    n = len(require_array("t", t, 1))
    names = ["normal_force", "contact_angle", "sliding_speed"] + ([] if half_width is None else ["half_width"])
    arrays = [normal_force, contact_angle, sliding_speed] + ([] if half_width is None else [half_width])
    columns = [require_array(name, value, 1, length=n) for name, value in zip(names, arrays)]
    times, histories = time_series(t, np.column_stack(columns), name="histories")
    forces, angles, speeds = histories[:, 0], histories[:, 1], np.abs(histories[:, 2])
    if np.any(forces < 0.0):
        raise AnalysisError(f"normal_force must be >= 0 (compressive magnitude); min = {forces.min():g} N")
    widths = None if half_width is None else histories[:, 3]
    if widths is not None and np.any(widths < 0.0):
        raise AnalysisError(f"half_width must be >= 0; min = {widths.min():g} m")
    return times, forces, angles, speeds, widths


@register(
    "archard_wear",
    inputs=(
        Field("t", ("time",), "s", "record times"),
        Field("normal_force", ("time",), "N", "contact normal force magnitude (0 out of contact)"),
        Field("contact_angle", ("time",), "rad", "angle of the contact point about the bearing axis, bearing frame"),
        Field("sliding_speed", ("time",), "m/s", "slip speed at the contact point"),
        Field("half_width", ("time",), "m", "contact half-width b (default: Hertz line contact)", optional=True),
    ),
    outputs=(
        Field("bin_angle", ("angle",), "rad", "bin centres (j + 1/2) 2 pi / n_bins"),
        Field("depth", ("angle",), "m", "wear depth per bin"),
        Field("volume", (), "m^3", "worn volume sum_j depth_j R_b dtheta L"),
        Field("max_depth", (), "m", "largest bin depth"),
        Field("angle_of_max_depth", (), "rad", "centre of the deepest bin"),
        Field("sliding_distance", (), "m", "integral of |v_s| while in contact"),
    ),
    sizes=lambda *, n_bins=360, **_: {"angle": n_bins},
    source="Archard, J. Appl. Phys. 24 (1953) 981-988; Flores, Mech. Mach. Theory 44 (2009) 1211-1222",
)
def archard_wear(
    t,
    normal_force,
    contact_angle,
    sliding_speed,
    half_width=None,
    *,
    wear_coefficient: float,
    hardness: float,
    bearing_radius: float,
    length: float,
    n_bins: int = 360,
    journal_radius: float | None = None,
    combined_modulus: float | None = None,
) -> dict[str, np.ndarray]:
    """Wear depth per angular bin of the bearing and worn volume (module docstring)."""
    k_w = require_positive("wear_coefficient", wear_coefficient)
    H = require_positive("hardness", hardness)
    r_b = require_positive("bearing_radius", bearing_radius)
    L = require_positive("length", length)
    n_bins = require_count("n_bins", n_bins)
    times, forces, angles, speeds, widths = _check_histories(t, normal_force, contact_angle, sliding_speed, half_width)
    if widths is None:
        if journal_radius is None or combined_modulus is None:
            raise AnalysisError("give half_width, or journal_radius and combined_modulus for the Hertz half-width")
        widths = hertz_line_half_width(
            forces, journal_radius=journal_radius, bearing_radius=r_b, length=L, combined_modulus=combined_modulus
        )
    half_angle = widths / r_b
    in_contact = (forces > 0.0) & (half_angle > 0.0)
    if np.any(half_angle[in_contact] >= np.pi):
        raise AnalysisError(f"contact half-width up to {widths.max():g} m exceeds half the bearing circumference (pi R_b)")
    # depth deposited by each record where the patch covers a bin fully: k_w p v_s w_i / H
    pressure = np.where(in_contact, forces / (2.0 * np.where(in_contact, widths, 1.0) * L), 0.0)
    deposit = k_w * pressure * speeds * trapezoid_weights(times) / H
    dtheta = 2 * np.pi / n_bins
    centre = np.mod(angles, 2 * np.pi)
    depth = np.zeros(n_bins)
    for rows in np.array_split(np.flatnonzero(in_contact), max(1, int(np.ceil(in_contact.sum() / _CHUNK)))):
        if rows.size:
            coverage = arc_coverage(centre[rows] - half_angle[rows], centre[rows] + half_angle[rows], n_bins)
            depth += deposit[rows] @ coverage / dtheta
    deepest = int(np.argmax(depth))
    bin_angle = (np.arange(n_bins) + 0.5) * dtheta
    return {
        "bin_angle": bin_angle,
        "depth": depth,
        "volume": np.float64(depth.sum() * r_b * dtheta * L),
        "max_depth": np.float64(depth[deepest]),
        "angle_of_max_depth": np.float64(bin_angle[deepest]),
        "sliding_distance": np.float64(np.trapezoid(np.where(forces > 0.0, speeds, 0.0), times)),
    }
