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
element ``F = lambda_t``, ``M = lambda_x (z_a x x_b) + lambda_y (z_a x y_b)``
about its origin (the generalized force ``-Phi_q^T lambda`` restricted to
frame b's twist). ``tests/test_resting_state.py`` checks it against the
contact law: the simulation starting there stays at the static penetration.

**The solve.** Newton's method on the residual with a finite-difference
Jacobian (columns scaled to unit norm); directions in which no candidate is in
contact yet (zero stiffness) are stepped along the residual's force, up to a
fraction of the smallest clearance per iteration, so the element crosses the
gap and lands in contact; then Newton converges quadratically.
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
    out = {}
    for rows in centred.closures:
        if rows.closure.name not in names:
            continue
        r = rows.row
        force = multipliers[r : r + 3]
        moment = np.zeros(3)
        if rows.closure.kind == "revolute":
            z_a = data.oMf[rows.closure.frame_a].rotation[:, 2]
            rotation_b = C._frame_b_rotation(data, rows)
            moment = multipliers[r + 3] * np.cross(z_a, rotation_b[:, 0]) + multipliers[r + 4] * np.cross(z_a, rotation_b[:, 1])
        out[rows.closure.name] = np.concatenate([force, moment])
    return out


def _tilt_rotation(tilt: np.ndarray) -> np.ndarray:
    return pin.exp3(np.array([tilt[0], tilt[1], 0.0])) if tilt.size else np.eye(3)


def resting_pose(law, kind: str, outer: pin.SE3, inner: pin.SE3, load: np.ndarray, tilt_free: bool) -> RestingPose:
    """Solve ``wrench_inner = load`` for the inner element's displacement (and tilt) from ``inner`` (module docstring).

    ``outer``/``inner``: the element frames' placements in the centred state;
    ``kind``: the ideal joint (``"spherical"``: 3 force equations;
    ``"revolute"``: also the 2 moments normal to the axis when ``tilt_free``).
    """
    twist, onset = np.zeros(6), np.zeros(law.n_candidates)
    n_tilt = 2 if kind == "revolute" and tilt_free else 0
    inner_axes = inner.rotation
    rows = [0, 1, 2]
    target = np.asarray(load, dtype=float)
    magnitude = float(np.linalg.norm(target[:3]))
    if magnitude < NEGLIGIBLE_LOAD:
        return RestingPose(np.zeros(3), np.zeros(2), law.penetration(outer.rotation, outer.translation, inner.rotation, inner.translation), target, 0)

    def residual(x: np.ndarray) -> np.ndarray:
        rotation = inner.rotation @ _tilt_rotation(x[3:])
        contact = law.evaluate(outer.rotation, outer.translation, twist, rotation, inner.translation + x[:3], twist, onset)
        force = contact.wrench_inner[:3] - target[:3]
        if not n_tilt:
            return force
        moment = contact.wrench_inner[3:] - target[3:]
        return np.concatenate([force, [moment @ inner_axes[:, 0], moment @ inner_axes[:, 1]]])

    x = np.zeros(3 + n_tilt)
    gap_step = 0.25 * float(np.min(law.candidate_clearances()))
    scale = np.concatenate([np.full(3, magnitude), np.full(n_tilt, magnitude * gap_step * 1e2)])
    for iteration in range(MAX_ITERATIONS):
        r = residual(x)
        if np.max(np.abs(r[:3])) <= TOLERANCE * magnitude and (not n_tilt or np.max(np.abs(r[3:])) <= TOLERANCE * scale[3]):
            d_world = x[:3]
            return RestingPose(outer.rotation.T @ d_world, np.pad(x[3:], (0, 2 - n_tilt)), _penetration(law, outer, inner, x), target, iteration)
        x = x + _step(residual, x, r, gap_step)
    raise InitialStateError(
        f"[initial] clearance_state = 'resting': no resting pose found for a load {np.round(target, 3).tolist()} "
        f"(residual {np.round(residual(x), 6).tolist()} after {MAX_ITERATIONS} iterations)"
    )


def _penetration(law, outer: pin.SE3, inner: pin.SE3, x: np.ndarray) -> np.ndarray:
    rotation = inner.rotation @ _tilt_rotation(x[3:])
    return law.penetration(outer.rotation, outer.translation, rotation, inner.translation + x[:3])


def _step(residual, x: np.ndarray, r: np.ndarray, gap_step: float) -> np.ndarray:
    """Newton step where the contact is stiff, a gap-closing step along the force residual elsewhere."""
    n = x.size
    increments = np.concatenate([np.full(3, 1e-3 * gap_step), np.full(n - 3, TILT_INCREMENT)])
    jacobian = np.empty((n, n))
    for k in range(n):
        h = np.zeros(n)
        h[k] = increments[k]
        jacobian[:, k] = (residual(x + h) - residual(x - h)) / (2.0 * increments[k])
    norms = np.linalg.norm(jacobian, axis=0)
    stiff = norms > 1e-12 * max(float(np.max(norms)), 1e-300)
    step = np.zeros(n)
    if np.any(stiff):
        scaled = jacobian[:, stiff] / norms[stiff]
        solution, *_ = np.linalg.lstsq(scaled, -r, rcond=1e-12)
        step[stiff] = solution / norms[stiff]
    # translations without stiffness: move along the force residual (the contact force on the inner element
    # opposes its displacement, so the load it must carry, -r, is reached by moving along r)
    free = ~stiff[:3]
    if np.any(free):
        direction = np.where(free, r[:3], 0.0)
        length = float(np.linalg.norm(direction))
        if length > 0.0:
            step[:3] += gap_step * direction / length
    limit = 4.0 * gap_step
    norm = float(np.linalg.norm(step[:3]))
    if norm > limit:
        step *= limit / norm
    return step
