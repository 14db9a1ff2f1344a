"""The validation's own integrator setting, independent of the scenes' ``[solver]`` tables.

The cross-engine checks (``tests/test_validation_*.py``, :mod:`.study`,
``scripts/validate.py``) compare the Lagrange model with the Newton-Euler
formulation to integration accuracy, and their thresholds (first contact onset
within 1e-8 s, end effector within 1e-9 m and driving forces within 1e-6
relative before the first impact, ...) are calibrated to one integrator and
tolerance. The shipped scenes choose their solver for production runs (speed
against accuracy, ``docs/work-precision.md``) and may name a method the
Newton-Euler event loop does not offer (LSODA, BDF, CVODE, fixed-step schemes).
So the validation does not read the scene's ``[solver]``: it pins
:data:`VALIDATION_SOLVER` and applies it to **both** the Lagrange run and the
Newton-Euler run, so they are compared like for like.

:data:`VALIDATION_SOLVER`: RK45 (Dormand-Prince 5(4), scipy), ``rtol = 1e-7``,
``atol = 1e-9``, ``max_step = 1e-3 s`` (the setting the clearance scenes ship
with, and the one the thresholds were calibrated on). ``max_step`` also bounds
the spacing of the Lagrange records, i.e. the times at which the engines are
compared. ``scripts/validate.py --method/--rtol/--atol/--max-step/--first-step``
overrides it for a study (:func:`validation_solver`); the Newton-Euler engine
supports the methods of :data:`.event_loop.SOLVERS` only.

Everything else of the scene (mechanism, clearance joints and their laws,
trajectory, Baumgarte gains, failure limits, duration) is used as it is.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

from robot.integration.solvers import FIXED_STEP_METHODS, METHODS
from robot.run import Run, build_run
from robot.scene.loader import Scene
from robot.integration.simulation import SolverOptions
from robot.validation.event_loop import SOLVERS as EVENT_LOOP_METHODS

#: the integrator of every validation run, Lagrange and Newton-Euler alike
VALIDATION_SOLVER = SolverOptions(method="RK45", rtol=1e-7, atol=1e-9, max_step=1e-3)


def validation_solver(
    method: str | None = None,
    rtol: float | None = None,
    atol: float | None = None,
    max_step: float | None = None,
    first_step: float | None = None,
    *,
    newton_euler: bool = True,
) -> SolverOptions:
    """:data:`VALIDATION_SOLVER` with the given fields replaced, checked.

    ``newton_euler``: the Newton-Euler engine takes part, so the method must be
    one its event loop supports (:data:`.event_loop.SOLVERS`). Raises
    ``ValueError`` naming the parameter, its value and what is valid.
    """
    changes = {k: v for k, v in dict(method=method, rtol=rtol, atol=atol, max_step=max_step, first_step=first_step).items() if v is not None}
    solver = dataclasses.replace(VALIDATION_SOLVER, **changes)
    check_solver(solver, newton_euler=newton_euler)
    return solver


def check_solver(solver: SolverOptions, *, newton_euler: bool = True) -> None:
    """Raise ``ValueError`` if ``solver`` cannot run the validation (see :func:`validation_solver`)."""
    allowed = tuple(EVENT_LOOP_METHODS) if newton_euler else tuple(METHODS)
    if solver.method not in allowed:
        why = "the Newton-Euler event loop (robot.validation.event_loop) supports" if newton_euler else "choose one of"
        raise ValueError(f"validation solver method={solver.method!r} is not supported: {why} {', '.join(allowed)}")
    for name in ("rtol", "atol", "max_step"):
        value = getattr(solver, name)
        if not (isinstance(value, (int, float)) and value > 0):
            raise ValueError(f"validation solver {name}={value!r} must be a positive number")
    if solver.first_step is not None and not solver.first_step > 0:
        raise ValueError(f"validation solver first_step={solver.first_step!r} must be a positive number")
    if solver.method in FIXED_STEP_METHODS and solver.first_step is None:
        raise ValueError(f"validation solver method={solver.method!r} is a fixed-step method and needs first_step (its step size)")


def with_solver(run: Run, solver: SolverOptions = VALIDATION_SOLVER) -> Run:
    """``run`` with its scene's solver replaced by ``solver`` (nothing else changes)."""
    return dataclasses.replace(run, scene=dataclasses.replace(run.scene, solver=solver))


def validation_run(scene: Scene | str | Path, *, solver: SolverOptions = VALIDATION_SOLVER, **overrides) -> Run:
    """:func:`robot.run.build_run` with the scene's ``[solver]`` replaced by the validation solver.

    ``overrides``: top-level scene keys such as ``duration``. The returned
    ``run.scene.solver`` is ``solver``; the scene file's own ``[solver]`` is not used
    (:func:`robot.scene.loader.load_scene` still reads and validates it).
    """
    return with_solver(build_run(scene, **overrides), solver)


__all__ = ["VALIDATION_SOLVER", "validation_solver", "check_solver", "with_solver", "validation_run"]
