"""Position, velocity and acceleration analysis of a closed-loop mechanism.

* Position analysis (assembly): Newton iteration on Phi(q, t) = 0 on the
  configuration manifold, ``q <- integrate(q, -Phi_q^+ Phi)`` (Pinocchio's
  ``integrate`` keeps quaternions unit). With more coordinates than independent
  equations (clearance joints free), ``Phi_q^+`` is the pseudo-inverse and the
  step the minimum-norm correction.
* Velocity analysis: ``Phi_q qd = -Phi_t``; acceleration analysis:
  ``Phi_q qdd = gamma`` (seed paper eq. (24) without stabilisation).
* Mobility: ``nv - rank(Phi_q)``, the numerical degrees of freedom.
* Redundant closure equations (overconstrained mechanisms, :mod:`robot.model.redundancy`):
  the Newton step is a least-squares step, exact for a consistent redundant set;
  the velocity and acceleration analyses solve on the independent rows and check
  that the redundant ones hold.
* Held coordinates (``assemble(..., held=...)``): extra equations ``q_j = value``
  for joints whose initial coordinate is given (:mod:`robot.model.initial_state`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from robot.model import constraints as C
from robot.model import redundancy as R
from robot.errors import SingularConfigurationError, StrokeLimitError, UnreachablePoseError
from robot.model.mechanism import Mechanism

RANK_TOLERANCE = 1e-9


@dataclass(frozen=True)
class HeldCoordinates:
    """Joint coordinates held at given values during an assembly (1-DOF joints: one q and one v index each)."""

    names: tuple[str, ...]
    q_index: np.ndarray
    v_index: np.ndarray
    values: np.ndarray

    @classmethod
    def none(cls) -> "HeldCoordinates":
        return cls((), np.zeros(0, dtype=int), np.zeros(0, dtype=int), np.zeros(0))


@dataclass(frozen=True)
class Assembly:
    """Result of a position analysis."""

    q: np.ndarray
    residual_norm: float
    iterations: int


def update_kinematics(model: pin.Model, data: pin.Data, q: np.ndarray) -> None:
    """Joint and frame placements and joint Jacobians at q."""
    pin.computeJointJacobians(model, data, q)
    pin.updateFramePlacements(model, data)


def check_strokes(mechanism: Mechanism, lengths: np.ndarray) -> None:
    """Raise :class:`StrokeLimitError` if an actuator coordinate is outside its limits."""
    for name, value, lower, upper in zip(mechanism.actuated_joints, lengths, mechanism.stroke_lower, mechanism.stroke_upper):
        if not lower - 1e-12 <= value <= upper + 1e-12:
            raise StrokeLimitError(
                f"actuator {name}: length {value:.6g} m is outside its stroke [{lower:.6g}, {upper:.6g}] m; "
                "choose a pose or trajectory inside the workspace"
            )


def assemble(
    constraints: C.ConstraintSet,
    q_guess: np.ndarray,
    drive: np.ndarray | None = None,
    *,
    tolerance: float = 1e-12,
    max_iterations: int = 50,
    data: pin.Data | None = None,
    held: HeldCoordinates | None = None,
) -> Assembly:
    """Solve Phi(q, t) = 0 by Newton iteration from ``q_guess`` (and ``q_j = value`` for the ``held`` coordinates).

    Raises :class:`UnreachablePoseError` when the iteration does not converge
    (the drive values or the guess are not compatible with the closures) and
    :class:`StrokeLimitError` when the drive values exceed the strokes.
    """
    mechanism = constraints.mechanism
    model = mechanism.model
    data = data or model.createData()
    if constraints.driven:
        check_strokes(mechanism, np.asarray(drive, dtype=float))
    q = pin.normalize(model, np.array(q_guess, dtype=float))
    norm = np.inf
    for iteration in range(max_iterations + 1):
        update_kinematics(model, data, q)
        phi = C.residual(constraints, data, q, drive)
        if held is not None:
            phi = np.concatenate([phi, q[held.q_index] - held.values])
        norm = float(np.max(np.abs(phi))) if phi.size else 0.0
        if not np.isfinite(norm):
            break
        if norm <= tolerance:
            return Assembly(q, norm, iteration)
        phi_q = C.jacobian(constraints, model, data)
        if held is not None:
            unit_rows = np.zeros((held.v_index.size, model.nv))
            unit_rows[np.arange(held.v_index.size), held.v_index] = 1.0
            phi_q = np.vstack([phi_q, unit_rows])
        step, *_ = np.linalg.lstsq(phi_q, -phi, rcond=None)
        q = pin.integrate(model, q, step)
    target = "the closures" if drive is None or not len(drive) else f"the actuator coordinates {np.round(drive, 6).tolist()} (m or rad)"
    raise UnreachablePoseError(
        f"assembly did not converge: constraint residual {norm:.3e} after {max_iterations} Newton iterations "
        f"(tolerance {tolerance:.1e}); {target} cannot be met from the initial guess"
    )


def _solve_full_rank(matrix: np.ndarray, rhs: np.ndarray, what: str) -> np.ndarray:
    solution, _, rank, singular_values = np.linalg.lstsq(matrix, rhs, rcond=None)
    if rank < min(matrix.shape) and matrix.shape[0] <= matrix.shape[1]:
        raise SingularConfigurationError(
            f"{what}: constraint Jacobian has rank {rank} < {matrix.shape[0]} rows "
            f"(smallest singular value {singular_values.min() if singular_values.size else 0:.3e}); "
            "the configuration is singular, move away from it"
        )
    return solution


def _solve_redundant(constraints: C.ConstraintSet, model: pin.Model, data: pin.Data, phi_q: np.ndarray, rhs: np.ndarray, what: str) -> np.ndarray:
    """Solve ``Phi_q x = rhs`` on the independent rows (:mod:`robot.model.redundancy`), check the redundant ones."""
    rows = R.detect(constraints, model, data, phi_q, warn=False)
    solution = _solve_full_rank(phi_q[rows.independent], rhs[rows.independent], what)
    error = np.abs(phi_q[rows.redundant] @ solution - rhs[rows.redundant])
    bound = 1e-8 * (rows.scales[rows.redundant] * np.max(np.abs(solution), initial=0.0) + np.abs(rhs[rows.redundant]))
    if np.any(error > bound):
        worst = int(np.argmax(error - bound))
        raise SingularConfigurationError(
            f"{what}: the dependent equation {rows.labels[worst]} is not satisfied (error {error[worst]:.3e}): the "
            "equations are inconsistent, the configuration is singular; move away from it"
        )
    return solution


def velocity_analysis(constraints: C.ConstraintSet, q: np.ndarray, drive_rate: np.ndarray | None, data: pin.Data | None = None) -> np.ndarray:
    """Joint velocities with Phi_q qd = -Phi_t (minimum-norm if the system is underdetermined)."""
    model = constraints.mechanism.model
    data = data or model.createData()
    update_kinematics(model, data, q)
    phi_q = C.jacobian(constraints, model, data)
    return _solve_redundant(constraints, model, data, phi_q, C.velocity_rhs(constraints, drive_rate), "velocity analysis")


def acceleration_analysis(
    constraints: C.ConstraintSet,
    q: np.ndarray,
    v: np.ndarray,
    drive_acceleration: np.ndarray | None,
    data: pin.Data | None = None,
) -> np.ndarray:
    """Joint accelerations with Phi_q qdd = gamma."""
    model = constraints.mechanism.model
    data = data or model.createData()
    pin.forwardKinematics(model, data, q, v, np.zeros(model.nv))
    pin.computeJointJacobians(model, data, q)
    pin.updateFramePlacements(model, data)
    phi_q = C.jacobian(constraints, model, data)
    return _solve_redundant(constraints, model, data, phi_q, C.gamma(constraints, model, data, drive_acceleration), "acceleration analysis")


def numerical_rank(matrix: np.ndarray) -> int:
    """Singular values above :data:`RANK_TOLERANCE` x max(1, the largest); 0 for an empty matrix."""
    if matrix.size == 0:
        return 0
    singular_values = np.linalg.svd(matrix, compute_uv=False)
    return int(np.sum(singular_values > RANK_TOLERANCE * max(1.0, singular_values[0])))


def mobility(constraints: C.ConstraintSet, q: np.ndarray, data: pin.Data | None = None) -> int:
    """Numerical degrees of freedom: nv - rank(Phi_q) at q (relative SVD tolerance)."""
    model = constraints.mechanism.model
    data = data or model.createData()
    update_kinematics(model, data, q)
    return model.nv - numerical_rank(C.jacobian(constraints, model, data))
