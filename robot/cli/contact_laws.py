"""Tables of docs/contact-laws.md: rebound ratio of each dissipation model, penetration of each radial law.

Rebound: a mass m = 1 kg hits a Hertz contact F = K delta^1.5 (K = 1e10 N/m^1.5) at
v_0 = 0.5 m/s with each model's damping; the impact is integrated (DOP853, rtol 1e-12)
to separation and v_out / v_0 printed, with its deviation from the c_e asked for; each
value is checked against the exact relation ``clearance_contact.dissipation.rebound_ratio``.
Radial laws: the aligned penetration of the R1 journal (20 mm, c_r 0.1 mm, L_b 40 mm,
steel) under 100 N - 10 kN for each radial law, and its ratio to the linear law's.

examples:
  clearance contact-laws                    # both tables (Markdown)
  clearance contact-laws --table radial     # only the radial laws' penetrations
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


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--table", choices=("all", "rebound", "radial"), default="all", help="which table to print (default: %(default)s)"
    )


def execute(args: argparse.Namespace) -> int:
    tables = {"rebound": rebound_table, "radial": radial_table}
    names = tuple(tables) if args.table == "all" else (args.table,)
    print("\n\n".join(tables[name]() for name in names))
    return EXIT_OK
