"""The resting initial state of clearance joints: each inner element in contact under the ideal joint's load.

**What it is.** In the ideal mechanism (every clearance joint replaced by the
ideal joint it models) the joint transmits a reaction wrench ``W`` at t = 0:
gravity plus the inertia of the prescribed motion at t = 0, from the ideal
mechanism's closed-loop inverse dynamics. The *resting* state places the inner
element (ball, journal) of each clearance joint where its contact law, at rest
(zero penetration rate, zero slip), transmits exactly that wrench:

    wrench_inner(d, theta) = W            (forces; for a revolute joint also the
                                           two moments normal to its axis)

``d`` is the inner element's displacement from the centred pose (outer frame
axes; its norm is the clearance *plus* the static penetration, e.g. for a
sphere ``|d| = c + (|F| / K)^(1/n)``: the element sits at the static
penetration, not exactly at the clearance, so the initial contact force equals
the load and there is no fall across the clearance and no impact at t = 0);
``theta``: for a revolute joint, its tilt about the inner frame's x and y axes
(the line contact's pressure distribution carries the ideal joint's moment).
With an initial misalignment the tilt is the scene's (held), and only the
forces are balanced. The rest of the mechanism is then assembled around these
relative poses (:func:`robot.model.constraints.constraint_set` ``offsets``), and
the velocities are the ideal ones with no relative motion in the joint.

**The ideal load.** With the centring constraints imposed (the ideal
mechanism in the clearance model's coordinates) the multipliers of
``M qdd + Phi_q^T lambda = -h`` (paper eq. (24), ``qdd`` from the acceleration
analysis) give, for a centring closure with rows ``p_a - p_b`` and
``z_a . x_b``, ``z_a . y_b`` (a: outer, b: inner), the wrench on the inner
element (:func:`robot.model.constraints.reaction_on_b`: the generalized force
``-Phi_q^T lambda`` restricted to frame b's twist). ``tests/test_resting_state.py`` checks it against the
contact law: the simulation starting there stays at the static penetration.

**The solve.** First the force with the journal untilted, then the moment by
continuation (``MOMENT_STEPS``). Each is Newton's method on the residual with a
finite-difference Jacobian (increments well inside the current penetration).
The translations are split by the eigenvectors of the symmetric contact
stiffness ``-sym(dF/dd)`` (positive semi-definite for a conservative contact at
rest): in the stiff ones Newton steps, in the free ones (no candidate touching
in that direction yet) the element moves along the force residual by a
quarter of the smallest clearance per iteration, so it crosses the gap and
lands in contact. If full steps stall (a contact switching on and off), the
iteration restarts with backtracking on the scaled residual.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from robot.errors import InitialStateError
from robot.model import constraints as C
from robot.model.kinematics import acceleration_analysis, update_kinematics

#: residual tolerance of the resting pose, relative to the load's magnitude
TOLERANCE = 1e-9
MAX_ITERATIONS = 200
#: a load below this (N) leaves the element centred: no direction to rest in
NEGLIGIBLE_LOAD = 1e-9
#: finite-difference increment of the tilt (rad): ~1e-3 of a 0.1 mm clearance over a 0.1 m bearing
TILT_INCREMENT = 1e-6
#: continuation in the ideal joint's moment (fractions applied in turn)
MOMENT_STEPS = (0.25, 0.5, 0.75, 1.0)
#: a translation (tilt) whose stiffness is below this fraction of the stiffest one is free: the gap is open
STIFF_FRACTION = 1e-5
#: the moment residual is measured against |F| times this lever (m)
MOMENT_ARM = 0.01


@dataclass(frozen=True)
class RestingPose:
    """The inner element's pose relative to the centred one, and the contact state there."""

    translation: np.ndarray  # inner origin - outer origin, outer frame axes (m)
    tilt: np.ndarray  # rotation of the inner element about its own x and y axes (rad)
    penetration: np.ndarray  # (k,) of the law's candidates at the resting pose (m)
    load: np.ndarray  # the ideal joint's wrench on the inner element, world axes [F, M about its origin]
    iterations: int


def ideal_reactions(centred: C.ConstraintSet, q: np.ndarray, v: np.ndarray, drive_acceleration: np.ndarray) -> dict[str, np.ndarray]:
    """The ideal joints' wrenches on the inner elements at (q, v) (module docstring), world axes, by site name."""
    mechanism = centred.mechanism
    model = mechanism.model
    data = model.createData()
    qdd = acceleration_analysis(centred, q, v, drive_acceleration, data)
    tau = pin.rnea(model, data, q, v, qdd)  # M qdd + h (gravity included)
    update_kinematics(model, data, q)
    phi_q = C.jacobian(centred, model, data)
    multipliers, *_ = np.linalg.lstsq(phi_q.T, -tau, rcond=None)
    misfit = float(np.max(np.abs(phi_q.T @ multipliers + tau)))
    if misfit > 1e-8 * max(1.0, float(np.max(np.abs(tau)))):
        raise InitialStateError(f"[initial] clearance_state = 'resting': the ideal mechanism's reactions are not in equilibrium (residual {misfit:.3e})")
    if np.linalg.matrix_rank(phi_q) < phi_q.shape[0]:
        raise InitialStateError(
            "[initial] clearance_state = 'resting': the ideal mechanism is over-constrained at t = 0, its joint reactions "
            "are not unique; use clearance_state = 'centred'"
        )
    names = set(mechanism.clearance_names)
    return {rows.closure.name: C.reaction_on_b(data, rows, multipliers) for rows in centred.closures if rows.closure.name in names}


def _tilt_rotation(tilt: np.ndarray) -> np.ndarray:
    return pin.exp3(np.array([tilt[0], tilt[1], 0.0])) if tilt.size else np.eye(3)


def resting_pose(law, kind: str, outer: pin.SE3, inner: pin.SE3, load: np.ndarray, tilt_free: bool) -> RestingPose:
    """Solve ``wrench_inner = load`` for the inner element's displacement (and tilt) from ``inner`` (module docstring).

    ``outer``/``inner``: the element frames' placements in the centred state;
    ``kind``: the ideal joint (``"spherical"``: 3 force equations;
    ``"revolute"``: also the 2 moments normal to the axis when ``tilt_free``).
    The force is balanced first with the journal untilted, then the moment is
    applied in steps (continuation: a tilting journal switches its contacts
    between the rings' edges and the flanges, and each step starts close).
    """
    target = np.asarray(load, dtype=float)
    magnitude = float(np.linalg.norm(target[:3]))
    if magnitude < NEGLIGIBLE_LOAD:
        return RestingPose(np.zeros(3), np.zeros(2), _penetration(law, outer, inner, np.zeros(3)), target, 0)
    gap_step = 0.25 * float(np.min(law.candidate_clearances()))
    x, iterations = _damped_newton(law, outer, inner, target, 0.0, np.zeros(3), gap_step)
    if kind == "revolute" and tilt_free:
        x = np.concatenate([x, np.zeros(2)])
        for fraction in MOMENT_STEPS:
            x, used = _damped_newton(law, outer, inner, target, fraction, x, gap_step)
            iterations += used
    return RestingPose(outer.rotation.T @ x[:3], np.pad(x[3:], (0, 5 - x.size)), _penetration(law, outer, inner, x), target, iterations)


def _residual(law, outer: pin.SE3, inner: pin.SE3, target: np.ndarray, moment_fraction: float, x: np.ndarray) -> np.ndarray:
    """Contact wrench on the inner element minus the load: 3 forces (+ 2 moments normal to the axis when x has a tilt)."""
    twist = np.zeros(6)
    rotation = inner.rotation @ _tilt_rotation(x[3:])
    contact = law.evaluate(outer.rotation, outer.translation, twist, rotation, inner.translation + x[:3], twist, np.zeros(law.n_candidates))
    force = contact.wrench_inner[:3] - target[:3]
    if x.size == 3:
        return force
    moment = contact.wrench_inner[3:] - moment_fraction * target[3:]
    return np.concatenate([force, inner.rotation[:, :2].T @ moment])


def _damped_newton(law, outer, inner, target, moment_fraction, x, gap_step) -> tuple[np.ndarray, int]:
    """Newton's method from ``x``: full steps first (fast where the contact set settles at once);
    if that stalls, again from ``x`` with backtracking on the scaled residual. InitialStateError if both stall."""
    value = float("nan")
    for backtracking in (False, True):
        try:
            return _newton(law, outer, inner, target, moment_fraction, x, gap_step, backtracking)
        except _Stalled as stalled:
            value = stalled.value
    raise InitialStateError(
        f"[initial] clearance_state = 'resting': no resting pose found for a load {np.round(target, 3).tolist()} "
        f"(scaled residual {value:.3e} at moment fraction {moment_fraction:g}); use clearance_state = 'centred'"
    )


class _Stalled(Exception):
    def __init__(self, value: float):
        self.value = value


def _newton(law, outer, inner, target, moment_fraction, x, gap_step, backtracking: bool) -> tuple[np.ndarray, int]:
    magnitude = float(np.linalg.norm(target[:3]))
    scale = np.concatenate([np.full(3, magnitude), np.full(x.size - 3, magnitude * MOMENT_ARM)])

    def residual(point: np.ndarray) -> np.ndarray:
        return _residual(law, outer, inner, target, moment_fraction, point)

    r = residual(x)
    value = float(np.linalg.norm(r / scale))
    for iteration in range(MAX_ITERATIONS):
        if value <= TOLERANCE:
            return x, iteration
        depth = float(np.max(_penetration(law, outer, inner, x), initial=0.0))
        step, closing = _step(residual, x, r, gap_step, depth)
        for _ in range(40 if backtracking else 1):
            trial_r = residual(x + step)
            trial = float(np.linalg.norm(trial_r / scale))
            # crossing the gap the residual stays at the load (no contact yet): not worse is progress there
            if not backtracking or trial < value or (closing and trial <= value):
                break
            step = 0.5 * step
        else:
            raise _Stalled(value)
        x, r, value = x + step, trial_r, trial
    raise _Stalled(value)


def _penetration(law, outer: pin.SE3, inner: pin.SE3, x: np.ndarray) -> np.ndarray:
    rotation = inner.rotation @ _tilt_rotation(x[3:])
    return law.penetration(outer.rotation, outer.translation, rotation, inner.translation + x[:3])


def _step(residual, x: np.ndarray, r: np.ndarray, gap_step: float, depth: float = 0.0) -> tuple[np.ndarray, bool]:
    """Newton step in the stiff translations and the tilts, a gap-closing step along the force
    residual in the free translations (and whether there was one).

    The translational stiffness ``K = -sym(dF/dd)`` of a conservative contact at rest is positive
    semi-definite: its eigenvectors with (relatively) zero eigenvalue are the directions in which
    no candidate touches yet; finite-difference noise is far below STIFF_FRACTION of the largest.
    ``depth``: the deepest penetration at x (m); the increments stay well inside it, so the
    differences do not straddle the onset of the contact they measure.
    """
    n = x.size
    translation = 1e-3 * gap_step if depth <= 0.0 else min(1e-3 * gap_step, 1e-2 * depth)
    tilt = TILT_INCREMENT if depth <= 0.0 else min(TILT_INCREMENT, 1e-2 * depth / gap_step)
    increments = np.concatenate([np.full(3, translation), np.full(n - 3, tilt)])
    jacobian = np.empty((n, n))
    for k in range(n):
        h = np.zeros(n)
        h[k] = increments[k]
        jacobian[:, k] = (residual(x + h) - residual(x - h)) / (2.0 * increments[k])
    stiffness = -0.5 * (jacobian[:3, :3] + jacobian[:3, :3].T)
    eigenvalues, vectors = np.linalg.eigh(stiffness)
    stiff = eigenvalues > STIFF_FRACTION * max(float(eigenvalues[-1]), 0.0)
    basis = np.hstack([jacobian[:, :3] @ vectors[:, stiff], jacobian[:, 3:]])
    step = np.zeros(n)
    if basis.shape[1] and np.any(basis):
        norms = np.linalg.norm(basis, axis=0)
        norms[norms == 0.0] = 1.0
        solution, *_ = np.linalg.lstsq(basis / norms, -r, rcond=1e-12)
        solution /= norms
        n_stiff = int(np.sum(stiff))
        step[:3] = vectors[:, stiff] @ solution[:n_stiff]
        step[3:] = solution[n_stiff:]
    # free translations: move along the force residual (the contact force on the inner element
    # opposes its displacement, so the load it must carry, -r, is reached by moving along r)
    free = vectors[:, ~stiff]
    direction = free @ (free.T @ r[:3])
    length = float(np.linalg.norm(direction))
    closing = length > 1e-12 * max(float(np.linalg.norm(r[:3])), 1e-300)
    if closing:
        step[:3] += gap_step * direction / length
    limit = 4.0 * gap_step
    norm = float(np.linalg.norm(step[:3]))
    if norm > limit:
        step *= limit / norm
    return step, closing
