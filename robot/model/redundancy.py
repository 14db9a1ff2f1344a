"""Redundant constraint equations: which rows of ``Phi_q`` are dependent, and an exact KKT solve without them.

**The problem.** An overconstrained mechanism has more closure equations than
independent ones: a planar slider-crank or four-bar closed by a revolute
closure has 5 closure rows of rank 2 (the out-of-plane translation and the two
axis-alignment rows are identically satisfied), a Bennett linkage 5 of rank 2
(genuinely dependent rows). ``Phi_q`` (m x nv) then has rank r < m, the KKT
matrix of paper eq. (24) is singular, and a solver that factorises
``S = Phi_q M^-1 Phi_q^T`` (Pinocchio's ``forwardDynamics``: Cholesky) divides by
rounding noise: the slider-crank gave a crank acceleration of -239 rad/s^2
where the drive prescribes 0.

**Exact solve on the independent rows.** Let ``I`` be r rows of ``Phi_q`` that
span its row space (the *independent* rows) and ``R`` the others
(``Phi_R = A Phi_I``). If the acceleration equations are consistent
(``c_R = A c_I``, ``c = gamma - 2 alpha Phid - beta^2 Phi``; exactly so for
equations that hold identically, to the order of the constraint drift
otherwise), then ``{qdd : Phi_q qdd = c} = {qdd : Phi_I qdd = c_I}`` and
``range(Phi_q^T) = range(Phi_I^T)``, so the reduced system
``[M Phi_I^T; Phi_I 0] [qdd; lambda_I] = [Q; c_I]`` (non-singular) has the same,
unique, ``qdd`` as the full one: the accelerations are those of the mechanism.
Which spanning set is chosen does not change ``qdd``.

**Detection** (:func:`detect`): rank-revealing QR with column pivoting
(Businger-Golub, LAPACK ``geqp3``) of the scaled closure rows' transpose. Each
row is divided by the norm of the relative frame Jacobian of the vector it is a
component of: ``||J_a^lin - J_b^lin||_F`` for the three translation rows of a
closure, ``||J_a^ang - J_b^ang||_F`` for the two axis rows of a revolute closure
(``LOCAL_WORLD_ALIGNED``), 1 for a driving row. These norms do not change when
the world frame is rotated, so the ``4e-17`` entries a rotated base frame
leaves in an out-of-plane row count as what they are, ``~1e-16`` of their
row's scale. A scaled row of norm below ``tolerance`` is redundant (zero); of
the others, the pivoted QR keeps rows while ``|R_kk| > tolerance |R_11|``.
``REDUNDANCY_TOLERANCE = 1e-9`` (as :data:`robot.model.kinematics.RANK_TOLERANCE`):
rounding leaves ``~1e-15``, and a row that is dependent to within ``1e-9`` is at a
singular configuration for any practical purpose. The redundancy is found among
the closure rows alone (it is a property of the mechanism); the driving rows
must then be independent of the kept closure rows, otherwise the driving forces
are not unique (an actuator at a singular configuration, or two actuators
driving the same freedom): :class:`~robot.errors.SingularConfigurationError`
naming the actuators.

**When.** :func:`detect` runs on a workspace's first evaluation (the initial
state; every integration, restart-free, builds its workspaces there) and again
whenever the check below fails. A mechanism without redundant rows pays nothing
afterwards: ``forwardDynamics`` on the full rows, as before (a full-rank set
that loses rank is a singular configuration, which the drift limit reports).
With redundant rows every solve checks the dropped equations,
``|Phi_R qdd - c_R|_i <= CHECK_TOLERANCE (s_i |qdd|_inf + |c_R,i|)`` (``s_i`` the
row's scale above; one (n_R x nv) product, ~1 us): a dropped row that becomes
independent (the rank changes at a singular configuration) fails it at once,
and the selection is detected again (~0.1 ms) and the system solved again. Off
the manifold (below) the check also fails on drift; the new detection then
often keeps other, better conditioned rows for the state (a check at 1e-3
instead, tried, let the driven Bennett linkage below keep one selection longer:
30 times fewer detections, but a closure residual of 2.4e-7 m instead of
1.4e-12 m at rtol 1e-9).

**Off the manifold.** Between the accepted states an integrator evaluates trial
states that violate the closures by up to the step's error (Baumgarte pulls them
back over time), and there a dependent row looks independent by about that
violation relative to the mechanism's size: a Bennett linkage driven at 10 rad/s
with RK45 showed pivots of 1e-10 to 1e-5 on its third closure row. Keeping such a
row makes the reduced system (nearly) singular: three closure rows and the driver
on three velocities gave garbage accelerations and a stalled run. So
(:func:`closure_rank`) the closure rows kept never outnumber ``nv`` less the
driving rows, and once a row is dropped, a later detection takes it back only if
its relative pivot exceeds ``RANK_GROWTH_TOLERANCE = 1e-3``: the failure limits
stop a run long before a drift makes that much (``max_residual`` 1e-4 m on a
mechanism of 0.1 m is 1e-3), while a mechanism that leaves a singular
configuration passes it on its way. A genuinely independent row left out for
longer shows as a failed check of the dropped rows (the accelerations then do
not meet it) and as constraint drift, which the drift limit reports.

**Multipliers.** ``lambda_I`` of the reduced system gives the generalized
constraint force ``Phi_I^T lambda_I``; over the redundant set any ``lambda``
with ``Phi_q^T lambda = Phi_I^T lambda_I`` is a solution (statically
indeterminate reactions of a rigid model). :func:`RowSelection.full_multipliers`
reports the **minimum-norm** one (Euclidean norm in SI units: N for
translation rows, N m for axis rows), which is also the limit of Pinocchio's
proximal KKT iterations started from ``lambda = 0``; rows that are identically
satisfied (zero rows) get ``lambda = 0``. The driving rows are independent of the
closures, so the null space of ``Phi_q^T`` has no driving components: the
driving forces are unique and exact. A :class:`~robot.errors.RedundantConstraintWarning`
names the redundant rows (``K:z, K:rot_x, K:rot_y``).
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from robot.errors import RedundantConstraintWarning, SingularConfigurationError
from robot.model import constraints as C
from robot.model.lapack import pivoted_qr  # scipy's dgeqp3 without scipy.linalg's 0.2 s of imports
from robot.model.pinocchio_arrays import frame_jacobian


#: relative tolerance of the rank decision (scaled rows, |R_kk| against |R_11|)
REDUNDANCY_TOLERANCE = 1e-9
#: relative tolerance of the dropped equations' check after each reduced solve
CHECK_TOLERANCE = 1e-6
#: relative pivot a dropped closure row needs before a later detection takes it back (module docstring, "Off the manifold")
RANK_GROWTH_TOLERANCE = 1e-3


@dataclass(frozen=True, eq=False)
class RowSelection:
    """Which rows of ``Phi`` a KKT solve uses: the independent closure rows, then every driving row."""

    independent: np.ndarray  # row indices into Phi, increasing (closures first, then the drivers)
    redundant: np.ndarray  # closure rows left out
    n_closure_kept: int  # independent closure rows: the driving multipliers start there in the reduced solve
    scales: np.ndarray  # per row of Phi: the reference norm of its row (see the module docstring)
    labels: tuple[str, ...]  # names of the redundant rows

    @property
    def full(self) -> bool:
        return self.redundant.size == 0

    def same_rows(self, other: "RowSelection") -> bool:
        return np.array_equal(self.independent, other.independent)

    def consistent(self, phi_q: np.ndarray, drift: np.ndarray, qdd: np.ndarray, tolerance: float = CHECK_TOLERANCE) -> bool:
        """Whether ``qdd`` satisfies the dropped rows ``Phi_R qdd = c_R`` (``drift = -c``, Pinocchio's sign;
        relative to each row's scale)."""
        rows = self.redundant
        target = drift[rows]
        error = np.abs(phi_q[rows] @ qdd + target)
        bound = tolerance * (self.scales[rows] * np.max(np.abs(qdd), initial=0.0) + np.abs(target))
        return bool(np.all(error <= bound))

    def full_multipliers(self, phi_q: np.ndarray, independent_multipliers: np.ndarray) -> np.ndarray:
        """Minimum-norm ``lambda`` (all rows) with ``Phi_q^T lambda = Phi_I^T lambda_I``."""
        out = np.zeros(phi_q.shape[0])
        out[self.independent] = independent_multipliers
        if self.full:
            return out
        # null space of Phi_q^T: the left singular directions beyond its rank (the rank is the
        # number of independent rows, not a second tolerance)
        u, _, _ = np.linalg.svd(phi_q, full_matrices=True)
        null = u[:, self.independent.size :]
        return out - null @ (null.T @ out)


def row_scales(constraints: C.ConstraintSet, model: pin.Model, data: pin.Data, phi_q: np.ndarray) -> np.ndarray:
    """Reference norm of every row of ``Phi_q`` (module docstring). Needs the joint Jacobians and placements on ``data``."""
    scales = np.ones(constraints.n_rows)
    for rows in constraints.closures:
        r = rows.row
        position = 2 if rows.closure.kind == "prismatic" else 3  # prismatic centring: 2 position rows, 3 rotation rows
        scales[r : r + position] = np.linalg.norm(phi_q[r : r + position])  # the rows are J_a^lin - J_b^lin (world axes)
        if rows.closure.kind in ("revolute", "prismatic"):
            relative = frame_jacobian(model, data, rows.closure.frame_a)[3:] - frame_jacobian(model, data, rows.closure.frame_b)[3:]
            scales[r + position : r + 5] = np.linalg.norm(relative)
    return scales


def ranked_rows(scaled: np.ndarray, tolerance: float = REDUNDANCY_TOLERANCE) -> tuple[np.ndarray, np.ndarray]:
    """Rows of ``scaled`` in the pivoted QR's order (most independent first) and their relative pivots ``|R_kk| / |R_11|``.

    Pivoted QR of ``scaled^T``; rows of norm ``<= tolerance`` are left out. At most
    ``min(rows, columns)`` rows are ranked (no more can be independent).
    """
    nonzero = np.flatnonzero(np.linalg.norm(scaled, axis=1) > tolerance) if scaled.size else np.zeros(0, dtype=int)
    if nonzero.size == 0:
        return nonzero, np.zeros(0)
    triangle, pivots = pivoted_qr(scaled[nonzero].T)
    diagonal = np.abs(np.diag(triangle))
    return nonzero[pivots[: diagonal.size]], diagonal / diagonal[0]


def independent_rows(scaled: np.ndarray, tolerance: float = REDUNDANCY_TOLERANCE) -> np.ndarray:
    """Indices (increasing) of rows of ``scaled`` spanning its row space: pivoted QR of ``scaled^T``."""
    rows, pivots = ranked_rows(scaled, tolerance)
    return np.sort(rows[: int(np.sum(pivots > tolerance))])


def closure_rank(pivots: np.ndarray, tolerance: float, n_velocities: int, n_driving: int, previous: "RowSelection | None") -> int:
    """How many closure rows to keep, from their relative pivots (module docstring, "Off the manifold").

    The rows above ``tolerance``, but never more than ``n_velocities - n_driving`` (the drivers are independent of
    the closures, and no more than ``nv`` rows can be); with a ``previous`` selection, more closure rows than it kept
    only if the extra ones are independent beyond :data:`RANK_GROWTH_TOLERANCE`.
    """
    rank = min(int(np.sum(pivots > tolerance)), max(n_velocities - n_driving, 0))
    if previous is not None and rank > previous.n_closure_kept:
        rank = max(previous.n_closure_kept, min(rank, int(np.sum(pivots > RANK_GROWTH_TOLERANCE))))
    return rank


def detect(
    constraints: C.ConstraintSet,
    model: pin.Model,
    data: pin.Data,
    phi_q: np.ndarray,
    tolerance: float = REDUNDANCY_TOLERANCE,
    warn: bool = True,
    previous: RowSelection | None = None,
) -> RowSelection:
    """The :class:`RowSelection` of ``Phi_q`` at the configuration on ``data`` (joint Jacobians and frame placements).

    ``previous``: the selection in use, when its dropped rows failed their check
    (:func:`closure_rank`). Raises :class:`SingularConfigurationError` when the driving
    rows depend on the closures; warns (:class:`RedundantConstraintWarning`) when closure
    rows are redundant.
    """
    scales = row_scales(constraints, model, data, phi_q)
    n_closure = constraints.n_closure_rows
    safe = np.where(scales > 0.0, scales, 1.0)
    scaled = phi_q / safe[:, None]
    scaled[scales == 0.0] = 0.0  # a closure between two bodies that cannot move relative to each other
    driving = np.arange(n_closure, constraints.n_rows)
    ranked, pivots = ranked_rows(scaled[:n_closure], tolerance)
    kept = np.sort(ranked[: closure_rank(pivots, tolerance, model.nv, driving.size, previous)])
    if driving.size:
        _check_drivers(constraints, scaled[kept], scaled[driving], pivots, model.nv, tolerance)
    dropped = np.ones(n_closure, dtype=bool)
    dropped[kept] = False
    redundant = np.flatnonzero(dropped)
    labels = tuple(constraints.row_labels[i] for i in redundant)
    selection = RowSelection(np.concatenate([kept, driving]).astype(int), redundant, int(kept.size), scales, labels)
    if warn and redundant.size:
        warnings.warn(
            f"mechanism {constraints.mechanism.name!r}: {redundant.size} of {n_closure} closure equations are redundant "
            f"(dependent on the others, relative tolerance {tolerance:.0e}): {', '.join(labels)}; the motion is solved on the "
            f"{kept.size} independent ones (exact), the multipliers of the redundant set are the minimum-norm ones and the "
            "driving forces are unique (docs/dynamics.md, 'Redundant constraints')",
            RedundantConstraintWarning,
            stacklevel=3,
        )
    return selection


def _check_drivers(constraints: C.ConstraintSet, closures: np.ndarray, drivers: np.ndarray, pivots: np.ndarray, nv: int, tolerance: float) -> None:
    """SingularConfigurationError unless the driving rows are independent of the kept closure rows.

    Two ways to fail: more closure rows clearly independent (relative pivot beyond
    :data:`RANK_GROWTH_TOLERANCE`) than ``nv`` less the drivers leaves room for, i.e. the
    actuators over-constrain the mechanism (the cap of :func:`closure_rank` must not hide
    that); or the stacked rows losing rank (an actuator at a singular configuration, two
    driving the same freedom). Either way the driving forces are not unique.
    """
    names = constraints.mechanism.actuated_joints
    room = nv - drivers.shape[0]
    if room < 0 or (pivots.size > room and pivots[room] > RANK_GROWTH_TOLERANCE):
        rank = int(np.sum(pivots > RANK_GROWTH_TOLERANCE))
        raise SingularConfigurationError(
            f"mechanism {constraints.mechanism.name!r}: {drivers.shape[0]} driving constraints ({', '.join(names)}) and "
            f"closure equations of rank {rank} on {nv} velocity coordinates: the actuators over-constrain the mechanism "
            "(their forces are not unique); drive fewer joints, or make some actuators force-driven"
        )
    stacked = np.vstack([closures, drivers])
    singular_values = np.linalg.svd(stacked, compute_uv=False)
    if singular_values[-1] <= tolerance * singular_values[0]:
        dependent = [names[k] for k in _dependent_drivers(closures, drivers, tolerance)]
        raise SingularConfigurationError(
            f"mechanism {constraints.mechanism.name!r}: the driving constraints of {', '.join(dependent)} depend on the "
            "closures at this configuration (smallest relative singular value "
            f"{singular_values[-1] / singular_values[0]:.1e} <= {tolerance:.0e}): the actuators are at a singular "
            "configuration or drive the same freedom, so their forces are not unique; change the trajectory or the actuation"
        )


def _dependent_drivers(closures: np.ndarray, drivers: np.ndarray, tolerance: float) -> list[int]:
    """Driving rows (indices) that add nothing to the closures and the drivers before them."""
    dependent, basis = [], closures
    for k, row in enumerate(drivers):
        trial = np.vstack([basis, row[None]])
        if independent_rows(trial, tolerance).size > basis.shape[0]:
            basis = trial
        else:
            dependent.append(k)
    return dependent
