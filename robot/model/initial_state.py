"""Consistent initial positions and velocities from the kinematic analysis.

**Clearance joints** start in one of :data:`CLEARANCE_STATES` (scene key
``[initial] clearance_state``). ``"resting"``: each inner element in contact
under the ideal joint's load at t = 0, at the static penetration
(:mod:`robot.model.resting_state`), the mechanism assembled around it.
``"centred"`` (the default): the
free bodies of clearance joints start **centred**: the
ball centre on the socket centre, the journal axis on the bearing axis with the
journal midpoint on the bearing midpoint, moving with the velocities the ideal
joint would give them. An optional misalignment rotates the bearing about its
local x axis (for the R1 joint of the 4-UPS/RPS: the limb's x6 axis) before
assembly: the rest of the mechanism assembles around it (seed paper, second
case: "the bearing rotated 0.035 deg clockwise around coordinate axis x6").
This is done by imposing, for the initial analysis only, the equations of the
ideal joints the clearance joints replace (``constraint_set(...,
centre_clearance=True)``).

**Given coordinates** (scene ``[initial] positions`` and ``velocities``, by
1-DOF joint name). Positions: the given values replace the guess's; a given
coordinate is **held** (an extra equation ``q_j = value`` in the Newton
iteration of :func:`robot.model.kinematics.assemble`) when its unit row is
independent of the constraint rows and of the coordinates held before it (file
order; rank test at the guess, relative tolerance
:data:`robot.model.kinematics.RANK_TOLERANCE`); the others are only a guess and
the assembly corrects them (an :class:`~robot.errors.InitialStateWarning` names
each one that moved). If the assembly with the held values fails, an
:class:`~robot.errors.InitialStateError` names the key and the values.
Velocities: ``v_target`` holds the given rates (0 elsewhere); the initial
velocity is its minimum-norm correction onto the constraints' tangent space,
``v = v_target + A^+ (b - A v_target)`` with ``A v = b`` the velocity
constraints ``Phi_q v = -Phi_t`` plus ``v_j = value`` for the given rates that
are independent (same rule as the positions). Actuated joints are set by the
trajectory: a given value must agree with it at t = 0.
"""

from __future__ import annotations

import warnings
from typing import Mapping

import numpy as np
import pinocchio as pin

from robot.scene.loader import CLEARANCE_STATES  # the scene schema's choices
from robot.errors import InitialStateError, InitialStateWarning, UnreachablePoseError
from robot.model import constraints as C
from robot.model.kinematics import HeldCoordinates, assemble, numerical_rank, update_kinematics, velocity_analysis
from robot.model.mechanism import Mechanism
from robot.model.resting_state import ideal_reactions, resting_pose

#: a given coordinate that the assembly moves by more than this (relative, floor 1) is reported
MOVED_TOLERANCE = 1e-9
#: the initial states of the clearance joints (module docstring)


def initial_state(
    mechanism: Mechanism,
    q_guess: np.ndarray,
    drive: tuple[np.ndarray, np.ndarray, np.ndarray],
    misalignment: dict[str, np.ndarray] | None = None,
    positions: dict[str, float] | None = None,
    velocities: dict[str, float] | None = None,
    clearance_state: str = "centred",
    laws: Mapping[str, object] | None = None,
) -> np.ndarray:
    """``y0 = [q0, v0]`` consistent with the closures and the drive at the initial time (module docstring).

    ``clearance_state = "resting"`` needs the contact ``laws`` by site name.
    """
    if clearance_state not in CLEARANCE_STATES:
        raise InitialStateError(f"[initial] clearance_state={clearance_state!r} must be one of {', '.join(CLEARANCE_STATES)}")
    constraints = C.constraint_set(mechanism, driven=True, centre_clearance=True, misalignment=misalignment)
    y0 = _assembled(constraints, q_guess, drive, positions, velocities)
    if clearance_state == "centred" or not mechanism.clearance_sites:
        return y0
    nq = mechanism.model.nq
    offsets, rotations = resting_offsets(constraints, y0[:nq], y0[nq:], drive[2], laws or {}, misalignment or {})
    resting = C.constraint_set(mechanism, driven=True, centre_clearance=True, misalignment=rotations, offsets=offsets)
    return _assembled(resting, y0[:nq], drive, positions, velocities)


def resting_offsets(
    centred: C.ConstraintSet,
    q: np.ndarray,
    v: np.ndarray,
    drive_acceleration: np.ndarray,
    laws: Mapping[str, object],
    misalignment: dict[str, np.ndarray],
) -> tuple[dict[str, np.ndarray], dict[str, np.ndarray]]:
    """Per clearance site: the resting translation offset (outer frame axes) and rotation offset of the centring rows."""
    mechanism = centred.mechanism
    model = mechanism.model
    data = model.createData()
    update_kinematics(model, data, q)
    loads = ideal_reactions(centred, q, v, drive_acceleration)
    offsets, rotations = {}, {}
    for site in mechanism.clearance_sites:
        if site.name not in laws:
            raise InitialStateError(f"[initial] clearance_state = 'resting': no contact law for clearance joint {site.name!r}")
        pose = resting_pose(laws[site.name], site.kind, data.oMf[site.outer_frame], data.oMf[site.inner_frame], loads[site.name], site.name not in misalignment)
        offsets[site.name] = pose.translation
        held = misalignment.get(site.name, np.eye(3))
        rotations[site.name] = pin.exp3(np.array([pose.tilt[0], pose.tilt[1], 0.0])).T @ held
    return offsets, rotations


def _assembled(
    constraints: C.ConstraintSet,
    q_guess: np.ndarray,
    drive: tuple[np.ndarray, np.ndarray, np.ndarray],
    positions: dict[str, float] | None,
    velocities: dict[str, float] | None,
) -> np.ndarray:
    """``[q0, v0]`` of one constraint set (centring or resting rows) with the given coordinates."""
    mechanism = constraints.mechanism
    s, sd, _ = drive
    given_q = given_coordinates(mechanism, positions or {}, "positions", s)
    given_v = given_coordinates(mechanism, velocities or {}, "velocities", sd)
    guess = np.array(q_guess, dtype=float)
    guess[given_q.q_index] = given_q.values
    held = _independent(constraints, guess, given_q)
    try:
        q0 = assemble(constraints, guess, s, held=held).q
    except UnreachablePoseError as exc:
        if not given_q.names:
            raise
        values = ", ".join(f"{n} = {v:g}" for n, v in zip(given_q.names, given_q.values))
        holding = ", ".join(held.names) or "none (they are only a guess)"
        raise InitialStateError(
            f"[initial] positions {{{values}}}: the closures cannot be assembled (held exactly: {holding}): {exc}; "
            f"give values inside the mechanism's reach{_revolute_closure_hint(mechanism)}"
        ) from None
    _report_moved(given_q, q0[given_q.q_index], "positions")
    if not given_v.names:
        return np.concatenate([q0, velocity_analysis(constraints, q0, sd)])
    v0 = _project_velocities(constraints, q0, sd, given_v)
    _report_moved(given_v, v0[given_v.v_index], "velocities")
    return np.concatenate([q0, v0])


def given_coordinates(mechanism: Mechanism, values: dict[str, float], key: str, drive: np.ndarray) -> HeldCoordinates:
    """The coordinates of ``values`` (1-DOF joint name -> value) but the actuated ones, which must agree with ``drive``."""
    model = mechanism.model
    names, q_index, v_index, numbers = [], [], [], []
    for name, value in values.items():
        if not model.existJointName(name):
            joints = [n for j, n in enumerate(model.names) if j > 0 and model.nqs[j] == 1]
            raise InitialStateError(f"[initial] {key}: {name!r} is not a joint of {mechanism.name!r}; 1-DOF joints: {', '.join(joints)}")
        joint = model.getJointId(name)
        if model.nqs[joint] != 1 or model.nvs[joint] != 1:
            raise InitialStateError(
                f"[initial] {key}: joint {name!r} has nq = {model.nqs[joint]}, nv = {model.nvs[joint]}; only 1-DOF joints "
                "(revolute, prismatic) can be given"
            )
        if name in mechanism.actuated_joints:
            prescribed = float(drive[mechanism.actuated_joints.index(name)])
            if abs(value - prescribed) > MOVED_TOLERANCE * max(1.0, abs(prescribed)):
                raise InitialStateError(
                    f"[initial] {key}: {name} = {value!r} but {name} is actuated and its trajectory gives {prescribed!r} at "
                    "t = 0; remove it from [initial] or change the trajectory"
                )
            continue
        names.append(name)
        q_index.append(model.idx_qs[joint])
        v_index.append(model.idx_vs[joint])
        numbers.append(float(value))
    return HeldCoordinates(tuple(names), np.array(q_index, dtype=int), np.array(v_index, dtype=int), np.array(numbers))


def _independent(constraints: C.ConstraintSet, q: np.ndarray, given: HeldCoordinates) -> HeldCoordinates:
    """The given coordinates whose unit rows add to the rank of Phi_q(q) and of those kept before them."""
    model = constraints.mechanism.model
    data = model.createData()
    update_kinematics(model, data, q)
    rows = C.jacobian(constraints, model, data)
    keep = []
    for k, v_index in enumerate(given.v_index):
        unit = np.zeros((1, model.nv))
        unit[0, v_index] = 1.0
        trial = np.vstack([rows, unit])
        if numerical_rank(trial) > numerical_rank(rows):
            rows = trial
            keep.append(k)
    return HeldCoordinates(tuple(given.names[k] for k in keep), given.q_index[keep], given.v_index[keep], given.values[keep])


def _project_velocities(constraints: C.ConstraintSet, q: np.ndarray, drive_rate: np.ndarray, given: HeldCoordinates) -> np.ndarray:
    """Minimum-norm correction of the given rates onto the velocity constraints (module docstring)."""
    model = constraints.mechanism.model
    held = _independent(constraints, q, given)
    data = model.createData()
    update_kinematics(model, data, q)
    unit_rows = np.zeros((held.v_index.size, model.nv))
    unit_rows[np.arange(held.v_index.size), held.v_index] = 1.0
    matrix = np.vstack([C.jacobian(constraints, model, data), unit_rows])
    rhs = np.concatenate([C.velocity_rhs(constraints, drive_rate), held.values])
    target = np.zeros(model.nv)
    target[given.v_index] = given.values
    correction, *_ = np.linalg.lstsq(matrix, rhs - matrix @ target, rcond=None)
    velocity = target + correction
    error = float(np.max(np.abs(matrix @ velocity - rhs), initial=0.0))
    if error > 1e-9 * max(1.0, float(np.max(np.abs(velocity)))):
        raise InitialStateError(f"[initial] velocities: the velocity constraints cannot be met (residual {error:.3e}); the configuration is singular")
    return velocity


def _report_moved(given: HeldCoordinates, result: np.ndarray, key: str) -> None:
    moved = [
        f"{name}: {value:.9g} -> {got:.9g}"
        for name, value, got in zip(given.names, given.values, result)
        if abs(got - value) > MOVED_TOLERANCE * max(1.0, abs(value))
    ]
    if moved:
        warnings.warn(
            f"[initial] {key}: not independent of the constraints and the values before them, corrected to satisfy the "
            f"constraints: {'; '.join(moved)}",
            InitialStateWarning,
            stacklevel=3,
        )


def _revolute_closure_hint(mechanism) -> str:
    """For mechanisms with revolute closures: where their child-side axis comes from (a cause of closures that never meet)."""
    names = [c.name for c in mechanism.description.closures if c.kind == "revolute"]
    if not names:
        return ""
    return (
        f"; revolute closure(s) {', '.join(names)} take their child-side axis from the parent's at the neutral "
        "configuration (docs/kinematics.md, section 2): if the axes are not parallel at q = 0, no position assembles them"
    )
