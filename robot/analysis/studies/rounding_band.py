"""How far a run's summary moves under perturbations at the level of rounding: the yardstick of "unchanged".

A change of the code that alters floating-point operations (another but equally
exact factorisation, a compiled replacement of a library call, a different
summation order) perturbs the trajectory at the level of rounding, ~1e-16
relative. In a mechanism with impacts that perturbation is amplified at every
contact onset (the onset time moves, the step sequence after it changes), so
two runs that are both correct to rounding differ in their peak forces and
impulses by far more than 1e-16. This module measures that spread for a scene:
the same run repeated with

* one coordinate of the initial state moved by one unit in the last place of
  its block's scale, ``numpy.spacing(max(1, largest |value| among the
  positions, or among the velocities))``: rounding acts on every value the
  step computes, not on the coordinate alone, and one ulp of a coordinate that
  is zero or nearly zero (~1e-300, or 1e-20 for a mechanism starting near its
  zero configuration) would be far below it; the floor of 1 makes it at least
  the rounding of a unit-size value (2.2e-16, in SI units);
* the relative and the absolute tolerance multiplied by ``1 + 1e-12`` (the
  step-size controller's decisions move at rounding level);

and, per summary quantity (peak normal force and normal-force impulse per
clearance joint, as :func:`robot.analysis.studies.common.simulate` defines them,
and the number of accepted steps), the largest relative change against the
unperturbed run: the **rounding band**. It is the largest of a handful of
samples, so an estimate from below of how far rounding can move a quantity, not
a bound; the report says how many variants moved anything at all. A code change whose summary differs
from the old code's by less than the band is indistinguishable from rounding;
one that stays bit for bit identical differs by zero. The band also answers
whether a criterion is meaningful at all: on ``compound_misaligned`` (2 s,
CVODE_BDF rtol 1e-6) it is a few 1e-5 for the peak forces and a few 1e-6 for the
impulses, so "peaks within 1e-6 of today's run" cannot be guaranteed short of
bit identity (``docs/performance.md``).
"""

from __future__ import annotations

import dataclasses
from typing import Callable

import numpy as np

from robot.analysis.errors import AnalysisError
from robot.analysis.studies.common import Outcome, simulate
from robot.integration.simulation import SolverOptions
from robot.run import Run

#: the tolerances' relative nudge (the step-size controller's decisions move at rounding level)
TOLERANCE_NUDGE = 1e-12


def summary(outcome: Outcome) -> dict[str, float]:
    """The quantities the band is measured on: ``peak J`` and ``impulse J`` per clearance joint, ``steps``."""
    values = {f"peak {joint}": value for joint, value in outcome.peaks.items()}
    values.update({f"impulse {joint}": value for joint, value in outcome.impulses.items()})
    values["steps"] = float(outcome.n_steps)
    return values


def relative_changes(reference: dict[str, float], other: dict[str, float]) -> dict[str, float]:
    """|other / reference - 1| per quantity (0 where both are 0, inf where only the reference is)."""
    changes = {}
    for name, value in reference.items():
        if value == 0.0:
            changes[name] = 0.0 if other[name] == 0.0 else float("inf")
        else:
            changes[name] = abs(other[name] / value - 1.0)
    return changes


def perturbations(run: Run, options: SolverOptions, coordinates: tuple[int, ...] | None = None) -> dict[str, tuple[Run, SolverOptions]]:
    """The perturbed variants of a run (module docstring), by name.

    ``coordinates``: indices of the initial state to nudge (default: the first and
    the middle position coordinate, the first and the middle velocity coordinate);
    each moves by one ulp of its block's scale (module docstring). Indices of the
    integrator's extra states (the works) are skipped.
    """
    nq, nv = run.mechanism.model.nq, run.mechanism.model.nv
    if coordinates is None:
        coordinates = tuple(sorted({0, nq // 2, nq, nq + nv // 2}))
    blocks = (slice(0, nq), slice(nq, nq + nv))
    variants = {}
    for index in coordinates:
        if not 0 <= index < run.y0.shape[0]:
            raise AnalysisError(f"coordinates: index {index} is outside the state (0 ... {run.y0.shape[0] - 1})")
        block = next((b for b in blocks if b.start <= index < b.stop), None)
        if block is None:  # an accumulator (the works), not a coordinate
            continue
        nudge = float(np.spacing(max(1.0, float(np.max(np.abs(run.y0[block]))))))
        y0 = run.y0.copy()
        y0[index] += nudge
        variants[f"y0[{index}] + {nudge:.1e}"] = (dataclasses.replace(run, y0=y0), options)
    factor = 1.0 + TOLERANCE_NUDGE
    variants[f"rtol x (1 + {TOLERANCE_NUDGE:g})"] = (run, dataclasses.replace(options, rtol=options.rtol * factor))
    variants[f"atol x (1 + {TOLERANCE_NUDGE:g})"] = (run, dataclasses.replace(options, atol=options.atol * factor))
    return variants


def rounding_band(
    run: Run,
    t_end: float | None = None,
    options: SolverOptions | None = None,
    coordinates: tuple[int, ...] | None = None,
    progress: Callable[[str], None] | None = None,
) -> dict:
    """The rounding band of a run (module docstring): reference summary, each variant's changes, the band.

    ``moved``: how many variants changed any quantity at all. Raises
    :class:`robot.analysis.errors.AnalysisError` if the reference or a variant does
    not reach ``t_end`` (a band of a failed run means nothing).
    """
    options = options or run.scene.solver
    t_end = run.t_span[1] if t_end is None else t_end

    def summarised(variant_run: Run, variant_options: SolverOptions, label: str) -> dict[str, float]:
        outcome = simulate(variant_run, variant_options, t_end, label=label)
        if not outcome.success:
            raise AnalysisError(f"rounding band of {run.scene.name!r}: the {label} run stopped at t={outcome.t_reached!r} ({outcome.message})")
        return summary(outcome)

    reference = summarised(run, options, "reference")
    variants = {}
    for name, (variant_run, variant_options) in perturbations(run, options, coordinates).items():
        variants[name] = relative_changes(reference, summarised(variant_run, variant_options, name))
        if progress is not None:
            progress(f"{name}: " + ", ".join(f"{key} {value:.1e}" for key, value in variants[name].items()))
    band = {name: max(changes[name] for changes in variants.values()) for name in reference}
    moved = sum(1 for changes in variants.values() if any(value != 0.0 for value in changes.values()))
    return {"scene": run.scene.name, "t_end": t_end, "reference": reference, "variants": variants, "band": band, "moved": moved}
