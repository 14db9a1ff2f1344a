"""Benchmark (not a test): microseconds per call of the clearance joints' contact laws.

Times the spherical joint (in contact with Brown-McPhee friction, out of contact,
and its cheap ``penetration()``) and the revolute joint (axes misaligned with all
four candidates in contact, centred out of contact, and a skew-tilted contact for each
radial law of :data:`clearance_contact.RADIAL_LAWS`), each through

* ``evaluate`` (the Python API: input checks, kernel, ``JointContact`` of views), and
* the raw compiled ``kernel(parameters, ..., out)`` with a preallocated ``out`` (what a
  compiled right-hand side calls, minus numba's dispatch from Python, ~0.8 us for its
  9 array arguments), and ``penetration_kernel``.

examples:
  clearance bench                       # compiled kernels, results/bench_contact.json
  clearance bench --plain --out /tmp/bench.json

``--plain`` also times the same calls as plain Python (``CLEARANCE_CONTACT_JIT=0``, in
a subprocess; ~100x slower, fewer calls).  timeit, median (and min) over ``--repeats``
>= 7 repeats; writes JSON atomically.
"""

from __future__ import annotations

import argparse
import json
import platform
import subprocess
import statistics
import sys
import timeit
from pathlib import Path

import numpy as np

from clearance_contact import STEEL, BrownMcPheeFriction, SphericalClearanceJoint
from clearance_contact import compiled
from robot.cli.common import EXIT_OK, UsageError, positive_int, writable_file
from robot.io.atomic import atomic_write_text

DEFAULT_OUT = Path("results") / "bench_contact.json"
FRICTION = BrownMcPheeFriction(static_coefficient=0.08, dynamic_coefficient=0.05, transition_velocity=1e-3)


def _rot_x(angle: float) -> np.ndarray:
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def _time(call, repeats: int, number: int) -> dict:
    times = [t / number * 1e6 for t in timeit.repeat(call, repeat=repeats, number=number)]
    return {"median_us": statistics.median(times), "min_us": min(times), "repeats": repeats, "number": number}


def _case(joint, args: tuple, repeats: int, number: int) -> dict:
    """``evaluate`` and the raw ``kernel`` (preallocated out) on one state."""
    result = joint.evaluate(*args)
    kernel, parameters = type(joint).kernel, joint.kernel_parameters
    out = np.empty(joint.output_size)
    status = kernel(parameters, *args, out)
    assert status == 0 and np.array_equal(out[joint.WRENCH_INNER : joint.WRENCH_INNER + 6], result.wrench_inner)
    return _time(lambda: joint.evaluate(*args), repeats, number) | {
        "kernel": _time(lambda: kernel(parameters, *args, out), repeats, number),
        "in_contact": result.in_contact.tolist(),
        "kind": result.kind.tolist(),
    }


def _penetration_case(joint, rotation_outer, position_outer, rotation_inner, position_inner, repeats: int, number: int) -> dict:
    out = np.empty(joint.n_candidates)
    kernel, parameters = type(joint).penetration_kernel, joint.kernel_parameters
    args = (rotation_outer, position_outer, rotation_inner, position_inner)
    return _time(lambda: joint.penetration(*args), repeats, number) | {
        "kernel": _time(lambda: kernel(parameters, *args, out), repeats, number)
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
        "spherical_penetration": _penetration_case(joint, rot_s, pos_s, rot_b, pos_in, repeats, number),
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
    from clearance_contact.radial_laws import RADIAL_LAWS

    from clearance_contact.dissipation import DISSIPATION_MODELS

    def joint_with(law: str, dissipation: str = "lankarani_nikravesh") -> RevoluteClearanceJoint:
        return RevoluteClearanceJoint(
            journal_radius=0.010,
            bearing_inner_radius=0.0101,
            bearing_outer_radius=0.020,
            journal_length=0.0402,
            bearing_length=0.040,
            journal_material=STEEL,
            bearing_material=STEEL,
            restitution=0.9,
            friction=FRICTION,
            radial_law=law,
            dissipation=dissipation,
        )

    joint = joint_with("linear")
    tilt = np.arctan((joint.radial_clearance + 5e-6) / 0.020)
    pos = np.array([0.0, 0.3, 0.2])
    twist_j = np.array([0.01, 0.02, -0.01, 0.3, -0.2, 5.0])
    twist_b = np.array([0.0, 0.0, 0.0, 0.1, 0.0, 0.0])
    onset = np.full(4, 0.05)
    common = (pos, twist_b, np.eye(3), pos, twist_j, onset)
    # skew tilt: bearing offset along x by c_r - 2 um and tilted about x by 0.9 c_r / (L_b/2)
    # (the journal axis leans sideways to the eccentricity: curved profile, both rings wet)
    skew_pos = pos + np.array([joint.radial_clearance - 2e-6, 0.0, 0.0])
    skew = (_rot_x(0.9 * joint.radial_clearance / 0.020), pos, twist_b, np.eye(3), skew_pos, twist_j, onset)
    cases = {
        "revolute_misaligned_in_contact": _case(joint, (_rot_x(tilt), *common), repeats, number),
        "revolute_out_of_contact": _case(joint, (np.eye(3), *common), repeats, number),
        "revolute_penetration": _penetration_case(joint, _rot_x(tilt), pos, np.eye(3), pos, repeats, number),
    }
    for law in RADIAL_LAWS:  # every radial law, skew-tilted contact
        cases[f"revolute_skew_in_contact_{law}"] = _case(joint_with(law), skew, repeats, number)
    for model in DISSIPATION_MODELS:  # every dissipation model, same contact, linear law
        cases[f"revolute_skew_in_contact_{model}"] = _case(joint_with("linear", model), skew, repeats, number)
    return cases


def plain_python_cases(repeats: int, number: int) -> dict:
    """The same cases with CLEARANCE_CONTACT_JIT=0 (subprocess): the plain-Python run of the same source."""
    from clearance_contact.kernel_library import child_environment

    env = child_environment("python")
    code = (
        "import json; from robot.cli import bench as b; "
        f"print(json.dumps(b.spherical_cases({repeats}, {number}) | b.revolute_cases({repeats}, {number})))"
    )
    proc = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True)
    return json.loads(proc.stdout)


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--out", type=Path, default=DEFAULT_OUT, help="JSON file to write (default: %(default)s)")
    parser.add_argument("--repeats", type=positive_int, default=7, help="timeit repeats, >= 7 (default: %(default)s)")
    parser.add_argument("--number", type=positive_int, default=20000, help="calls per repeat (default: %(default)s)")
    parser.add_argument(
        "--plain", action="store_true", help="also time plain Python (CLEARANCE_CONTACT_JIT=0), with --number / 50 calls"
    )


def execute(args: argparse.Namespace) -> int:
    if args.repeats < 7:
        raise UsageError(f"--repeats={args.repeats} must be >= 7")
    writable_file(args.out, "--out")
    if not compiled.JIT_ENABLED:  # the numbers would be plain Python's, 20-40 x the compiled ones: say so first
        print(
            "warning: the contact kernels are NOT compiled (numba missing or CLEARANCE_CONTACT_JIT=0): these are "
            "plain-Python times; install numba (pip install numba) for the compiled ones",
            file=sys.stderr,
        )
    cases = spherical_cases(args.repeats, args.number) | revolute_cases(args.repeats, args.number)
    plain = plain_python_cases(args.repeats, max(args.number // 50, 10)) if args.plain else None
    try:
        import numba

        numba_version = numba.__version__
    except ImportError:
        numba_version = None
    report = {
        "unit": "microseconds per call",
        "statistic": "median over repeats",
        "jit": compiled.JIT_ENABLED,
        "kernels": compiled.KERNEL_MODE,  # at the end: a call the library does not take switches to numba
        "python": sys.version.split()[0],
        "numpy": np.__version__,
        "numba": numba_version,
        "machine": platform.machine(),
        "processor": platform.processor() or platform.machine(),
        "cases": cases,
    }
    if plain is not None:
        report["plain_python_cases"] = plain
    atomic_write_text(args.out, json.dumps(report, indent=2) + "\n")
    print(f"{'case':46s} {'evaluate':>10s} {'kernel':>10s}" + (f" {'plain eval':>11s} {'plain kern':>11s}" if plain else ""))
    for name, case in cases.items():
        if "median_us" not in case:
            print(f"{name:46s} {case}")
            continue
        line = f"{name:46s} {case['median_us']:8.2f}us {case['kernel']['median_us']:8.2f}us"
        if plain:
            line += f" {plain[name]['median_us']:9.2f}us {plain[name]['kernel']['median_us']:9.2f}us"
        print(line)
    print(f"wrote {args.out}")
    return EXIT_OK
