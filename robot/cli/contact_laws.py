"""Tables of docs/contact-laws.md: rebound ratio of each dissipation model, penetration of each radial law.

Rebound: a mass m = 1 kg hits a Hertz contact F = K delta^1.5 (K = 1e10 N/m^1.5) at
v_0 = 0.5 m/s with each model's damping; the impact is integrated (DOP853, rtol 1e-12)
to separation and v_out / v_0 printed, with its deviation from the c_e asked for; each
value is checked against the exact relation ``clearance_contact.dissipation.rebound_ratio``.
Radial laws: the aligned penetration of the R1 journal (20 mm, c_r 0.1 mm, L_b 40 mm,
steel) under 100 N - 10 kN for each radial law, and its ratio to the linear law's.

Sensitivity (``--table sensitivity``): the tables of the study
robot/sweep/examples/contact_laws_sensitivity.toml from its store (run it first with
``clearance sweep``): each radial law with Lankarani-Nikravesh damping, each dissipation
model with the linear law, percent changes against the scene's laws, and the whole grid.

examples:
  clearance contact-laws                    # rebound and radial tables (Markdown)
  clearance contact-laws --table radial     # only the radial laws' penetrations
  clearance contact-laws --table sensitivity --store out/sweeps/contact_laws_sensitivity/sweep.zarr
"""

from __future__ import annotations

import argparse
import math

from scipy.integrate import solve_ivp
from scipy.optimize import brentq

from clearance_contact import STEEL
from clearance_contact.dissipation import DISSIPATION_MODELS, dissipation_factor, rebound_ratio
from clearance_contact.radial_laws import RADIAL_LAWS, radial_law
from robot.cli.common import EXIT_OK

RESTITUTIONS = (0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9, 0.95, 1.0)


def integrated_rebound(chi: float, stiffness: float = 1e10, mass: float = 1.0, speed: float = 0.5) -> float:
    def rhs(t, y):
        return [y[1], -stiffness * max(y[0], 0.0) ** 1.5 * max(1.0 + chi * y[1] / speed, 0.0) / mass]

    def separation(t, y):
        return y[0]

    separation.terminal = True
    separation.direction = -1
    sol = solve_ivp(rhs, (0.0, 1.0), [0.0, speed], method="DOP853", rtol=1e-12, atol=[1e-18, 1e-14],
                    events=separation, first_step=1e-9)
    return -sol.y_events[0][-1][1] / speed


def rebound_table() -> str:
    lines = ["| c_e | " + " | ".join(DISSIPATION_MODELS) + " |", "|---" * (len(DISSIPATION_MODELS) + 1) + "|"]
    for ce in RESTITUTIONS:
        cells = []
        for name in DISSIPATION_MODELS:
            chi = dissipation_factor(name, ce)
            measured = integrated_rebound(chi)
            assert abs(measured - rebound_ratio(chi)) < 1e-7 * max(measured, 1e-3), (name, ce)
            cells.append(f"{measured:.4f} ({100 * (measured / ce - 1):+.1f} %)")
        lines.append(f"| {ce:g} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def radial_table() -> str:
    r_j, c_r, l_b = 0.020, 1.0e-4, 0.040
    laws = {name: radial_law(name, r_j, r_j + c_r, l_b, STEEL, STEEL) for name in RADIAL_LAWS}
    forces = (100.0, 1e3, 1e4)
    lines = ["| law | " + " | ".join(f"delta at {f:g} N (um)" for f in forces) + " | ratio to linear |", "|---" * 5 + "|"]
    linear = {f: brentq(lambda d: laws["linear"].aligned_force(d) - f, 1e-15, 1e-3, xtol=1e-18) for f in forces}
    for name, law in laws.items():
        deltas = [brentq(lambda d: law.aligned_force(d) - f, 1e-15, 4e-5, xtol=1e-18) for f in forces]
        ratios = "-".join(f"{d / linear[f]:.1f}" for d, f in zip(deltas, forces))
        lines.append(f"| {name} | " + " | ".join(f"{d * 1e6:.4f}" for d in deltas) + f" | {ratios} |")
    return "\n".join(lines)


#: columns of the sensitivity tables: (dataset variable, heading, scale to the heading's unit)
SENSITIVITY_COLUMNS = (
    ("R1_force_peak", "R1 peak force (kN)", 1e-3),
    ("S1_force_peak", "S1 peak force (kN)", 1e-3),
    ("R1_penetration_maximum", "R1 deepest (um)", 1e6),
    ("S1_penetration_maximum", "S1 deepest (um)", 1e6),
    ("P5_force_peak", "P5 peak abs. driving force (kN)", 1e-3),
    ("ee_deviation_peak", "EE deviation peak (mm)", 1e3),
    ("ee_deviation_rms", "EE deviation RMS (mm)", 1e3),
)
#: the scene's laws (compound_misaligned): the reference of the percent changes
SCENE_RADIAL_LAW, SCENE_DISSIPATION = "linear", "lankarani_nikravesh"


def sensitivity_tables(store: str) -> str:
    from robot.sweep import open_sweep
    from robot.sweep.sensitivity import grid_table, sensitivity_table

    data = open_sweep(store).compute()
    by_law = sensitivity_table(data.sel(dissipation=SCENE_DISSIPATION), "radial_law", SENSITIVITY_COLUMNS, SCENE_RADIAL_LAW)
    by_model = sensitivity_table(data.sel(radial_law=SCENE_RADIAL_LAW), "dissipation", SENSITIVITY_COLUMNS, SCENE_DISSIPATION)
    grids = [f"{heading}:\n\n" + grid_table(data, variable, "dissipation", "radial_law", scale) for variable, heading, scale in SENSITIVITY_COLUMNS]
    return "\n\n".join([by_law, by_model, *grids])


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--table", choices=("all", "rebound", "radial", "sensitivity"), default="all",
        help="which table to print; all = rebound and radial (default: %(default)s)",
    )
    parser.add_argument(
        "--store", default="out/sweeps/contact_laws_sensitivity/sweep.zarr",
        help="store of the contact_laws_sensitivity sweep, for --table sensitivity (default: %(default)s)",
    )


def execute(args: argparse.Namespace) -> int:
    if args.table == "sensitivity":
        print(sensitivity_tables(args.store))
        return EXIT_OK
    tables = {"rebound": rebound_table, "radial": radial_table}
    names = tuple(tables) if args.table == "all" else (args.table,)
    print("\n\n".join(tables[name]() for name in names))
    return EXIT_OK
