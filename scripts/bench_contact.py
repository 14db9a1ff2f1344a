"""Benchmark (not a test): microseconds per ``evaluate()`` call of the clearance joints.

Times the spherical joint (in contact with Brown-McPhee friction, out of contact,
and its cheap ``penetration()``) and, when importable, the revolute joint (axes
misaligned with both radial candidates in contact, and centred out of contact).
timeit, median (and min) over ``--repeats`` >= 7 repeats; writes JSON atomically.
"""

from __future__ import annotations

import argparse
import json
import platform
import statistics
import sys
import timeit
from pathlib import Path

import numpy as np

from clearance_contact import STEEL, BrownMcPheeFriction, SphericalClearanceJoint
from robot.atomic import atomic_write_text

DEFAULT_OUT = Path(__file__).resolve().parents[1] / "results" / "bench_contact.json"
FRICTION = BrownMcPheeFriction(static_coefficient=0.08, dynamic_coefficient=0.05, transition_velocity=1e-3)


def _rot_x(angle: float) -> np.ndarray:
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def _time(call, repeats: int, number: int) -> dict:
    times = [t / number * 1e6 for t in timeit.repeat(call, repeat=repeats, number=number)]
    return {"median_us": statistics.median(times), "min_us": min(times), "repeats": repeats, "number": number}


def _case(joint, args: tuple, repeats: int, number: int) -> dict:
    result = joint.evaluate(*args)
    return _time(lambda: joint.evaluate(*args), repeats, number) | {
        "in_contact": result.in_contact.tolist(),
        "kind": result.kind.tolist(),
    }


def spherical_cases(repeats: int, number: int) -> dict:
    """Ball 15 mm in a 15.1 mm socket (MODEL-NOTES 2), steel, Brown-McPhee friction."""
    joint = SphericalClearanceJoint(0.015, 0.0151, STEEL, STEEL, restitution=0.9, friction=FRICTION)
    rot_s, rot_b = np.eye(3), _rot_x(0.3)
    pos_s = np.array([0.1, -0.2, 0.5])
    twist_s = np.array([0.01, -0.02, 0.03, 0.5, -0.2, 0.1])
    twist_b = np.array([0.05, 0.12, -0.03, 2.0, 1.0, -3.0])
    onset = np.array([0.05])
    direction = np.array([2.0, -1.0, 2.0]) / 3.0
    pos_in = pos_s + (joint.clearance + 5e-6) * direction
    pos_out = pos_s + 0.5 * joint.clearance * direction
    return {
        "spherical_in_contact": _case(joint, (rot_s, pos_s, twist_s, rot_b, pos_in, twist_b, onset), repeats, number),
        "spherical_out_of_contact": _case(
            joint, (rot_s, pos_s, twist_s, rot_b, pos_out, twist_b, onset), repeats, number
        ),
        "spherical_penetration": _time(lambda: joint.penetration(rot_s, pos_s, rot_b, pos_in), repeats, number),
    }


def revolute_cases(repeats: int, number: int) -> dict:
    """Journal 10 mm / bearing 10.1-20 mm, lengths 40.2 / 40 mm, steel, Brown-McPhee.
    Misaligned: bearing tilted about x so that L_b/2 tan(tilt) = c_r + 5 um (both radial
    candidates in contact); the tilt also lifts the outer edge of each end face by
    R_b2 sin(tilt) = 105 um > c_a/2 = 100 um, so all four candidates are in contact."""
    try:
        from clearance_contact import RevoluteClearanceJoint
    except ImportError as exc:
        return {"revolute": {"skipped": f"RevoluteClearanceJoint not importable: {exc}"}}
    joint = RevoluteClearanceJoint(
        journal_radius=0.010,
        bearing_inner_radius=0.0101,
        bearing_outer_radius=0.020,
        journal_length=0.0402,
        bearing_length=0.040,
        journal_material=STEEL,
        bearing_material=STEEL,
        restitution=0.9,
        friction=FRICTION,
    )
    tilt = np.arctan((joint.radial_clearance + 5e-6) / 0.020)
    pos = np.array([0.0, 0.3, 0.2])
    twist_j = np.array([0.01, 0.02, -0.01, 0.3, -0.2, 5.0])
    twist_b = np.array([0.0, 0.0, 0.0, 0.1, 0.0, 0.0])
    onset = np.full(4, 0.05)
    common = (pos, twist_b, np.eye(3), pos, twist_j, onset)
    return {
        "revolute_misaligned_in_contact": _case(joint, (_rot_x(tilt), *common), repeats, number),
        "revolute_out_of_contact": _case(joint, (np.eye(3), *common), repeats, number),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--out", type=Path, default=DEFAULT_OUT, help="JSON file to write (default: %(default)s)")
    parser.add_argument("--repeats", type=int, default=7, help="timeit repeats, >= 7 (default: %(default)s)")
    parser.add_argument("--number", type=int, default=20000, help="calls per repeat (default: %(default)s)")
    args = parser.parse_args()
    if args.repeats < 7:
        parser.error("--repeats must be >= 7")
    cases = spherical_cases(args.repeats, args.number) | revolute_cases(args.repeats, args.number)
    report = {
        "unit": "microseconds per call",
        "statistic": "median over repeats",
        "python": sys.version.split()[0],
        "numpy": np.__version__,
        "machine": platform.machine(),
        "processor": platform.processor() or platform.machine(),
        "cases": cases,
    }
    atomic_write_text(args.out, json.dumps(report, indent=2) + "\n")
    for name, case in cases.items():
        print(f"{name:34s} {case['median_us']:8.2f} us" if "median_us" in case else f"{name:34s} {case}")
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
