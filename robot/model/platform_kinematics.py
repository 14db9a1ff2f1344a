"""Inverse kinematics of a platform driven by U-P-S and R-P-S limbs (the 4-UPS/RPS).

The layout is read from the mechanism: each actuated prismatic joint ``P`` is
the last joint of a limb whose chain from the base is either ``[U_x, U_y, P]``
(universal joint as revolute about base x then about the cross's y, prismatic
along the rod's z) or ``[R, P]`` (revolute, then prismatic along z); the limb tip
is the closure that joins the piston to the platform (a spherical joint). The
actuator coordinate is the hinge-to-hinge length ``L = |P_tip - B|``.

Pose of the platform (5 DOF): ``x, z`` (the two translations of the R limb's
tip in the plane normal to the R axis) and roll, pitch, yaw (Z-Y-X Euler angles,
``R = Rz(yaw) Ry(pitch) Rx(roll)``). The third translation follows from the R
limb: its tip stays in the plane through the R joint centre normal to its axis.

Leg kinematics (exact, used for the prescribed actuator histories):
``d = p + R r - B``, ``L = |d|``, ``u = d / L``,
``Ld = u . v_tip``, ``Ldd = u . a_tip + (|v_tip|^2 - Ld^2) / L``,
``v_tip = v + w x (R r)``, ``a_tip = a + alpha x (R r) + w x (w x (R r))``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property

import numpy as np
import pinocchio as pin

from robot.errors import SingularConfigurationError, StrokeLimitError, UnreachablePoseError
from robot.model.mechanism import Mechanism

#: above this condition number of the (length-scaled) actuation Jacobian a pose is called singular
SINGULAR_CONDITION = 1.0e6


@dataclass(frozen=True)
class Limb:
    """One actuated limb: chain joint ids (base to prismatic) and the hinge points."""

    actuator: str
    kind: str  # "UPS" or "RPS"
    joint_ids: tuple[int, ...]
    base_point: np.ndarray  # world
    platform_point: np.ndarray  # platform frame
    revolute_axis: np.ndarray | None  # RPS: world axis of R


@dataclass(frozen=True, eq=False)
class PlatformLayout:
    """Geometry of a UPS/RPS platform read from a :class:`Mechanism`."""

    mechanism: Mechanism
    platform_joint: int
    limbs: tuple[Limb, ...]
    plane_limb: int  # index of the RPS limb fixing the plane of motion
    characteristic_length: float

    # constants of the exact drive, made once (it is evaluated ~500 times a 2 s run by the drive table)
    @cached_property
    def platform_points(self) -> np.ndarray:
        """The limbs' tip points in the platform frame (rows; read-only)."""
        return _read_only(np.array([limb.platform_point for limb in self.limbs]))

    @cached_property
    def base_points(self) -> np.ndarray:
        """The limbs' base hinge points, world (rows; read-only)."""
        return _read_only(np.array([limb.base_point for limb in self.limbs]))

    @cached_property
    def plane_normal(self) -> np.ndarray:
        """Unit axis of the R-P-S limb's revolute: the normal of the plane its tip stays in (read-only).

        UnreachablePoseError unless it is (close to) the world y axis: the pose's x and z coordinates
        then parametrise that plane.
        """
        axis = self.limbs[self.plane_limb].revolute_axis
        normal = axis / np.linalg.norm(axis)
        if abs(normal @ np.array([0.0, 1.0, 0.0])) < 0.5:
            raise UnreachablePoseError("the R-P-S axis must be (close to) the world y axis for the x-z pose coordinates")
        return _read_only(normal)

    @classmethod
    def from_mechanism(cls, mechanism: Mechanism, platform_link: str = "platform") -> "PlatformLayout":
        model = mechanism.model
        description = mechanism.description
        if not model.existFrame(platform_link, pin.FrameType.BODY):
            raise UnreachablePoseError(f"mechanism {mechanism.name!r} has no link {platform_link!r}: not a UPS/RPS platform")
        platform_joint = model.frames[model.getFrameId(platform_link, pin.FrameType.BODY)].parentJoint
        if model.joints[platform_joint].shortname() != "JointModelFreeFlyer":
            raise UnreachablePoseError(f"platform link {platform_link!r} must hang on a floating joint")
        tips = {c.parent.link: c for c in description.closures if c.child.link == platform_link}
        limbs = []
        for actuator in mechanism.actuated_joints:
            joint_id = model.getJointId(actuator)
            chain = []
            j = joint_id
            while j != 0:
                chain.append(j)
                j = model.parents[j]
            chain.reverse()
            child_link = description.joints[actuator].child
            closure = tips.get(child_link)
            if closure is None:
                raise UnreachablePoseError(f"limb of {actuator!r}: no closure joins {child_link!r} to {platform_link!r}")
            kinds = [model.joints[j].shortname() for j in chain]
            base_point = np.array(model.jointPlacements[chain[0]].translation)
            axis = None
            if len(chain) == 3 and kinds[:2] == ["JointModelRX", "JointModelRY"]:
                kind = "UPS"
            elif len(chain) == 2 and kinds[0].startswith("JointModelR"):
                kind = "RPS"
                axis = model.jointPlacements[chain[0]].rotation @ np.array(description.joints[model.names[chain[0]]].axis)
            elif len(chain) == 2 and kinds[0] == "JointModelFreeFlyer":
                kind = "RPS"  # R replaced by a clearance free-flyer: geometry as the ideal joint
                axis = model.jointPlacements[chain[0]].rotation @ np.array(description.joints[model.names[chain[0]]].axis)
            else:
                raise UnreachablePoseError(f"limb of {actuator!r}: chain {kinds} is neither U-P-S nor R-P-S")
            if max(abs(x) for x in closure.parent.xyz) > 0:
                raise UnreachablePoseError(f"limb of {actuator!r}: the spherical centre must be the piston frame origin")
            # read-only: the layout's constants (platform_points, ...) are made from them once
            limbs.append(Limb(actuator, kind, tuple(chain), _read_only(base_point), _read_only(np.array(closure.child.xyz)), _read_only(axis)))
        plane = [k for k, limb in enumerate(limbs) if limb.kind == "RPS"]
        if len(plane) != 1:
            raise UnreachablePoseError(f"expected exactly one R-P-S limb, found {len(plane)}")
        radius = max(float(np.linalg.norm(limb.platform_point)) for limb in limbs)
        return cls(mechanism, platform_joint, tuple(limbs), plane[0], radius)


def _read_only(array: np.ndarray | None) -> np.ndarray | None:
    """``array`` made read-only in place (None passes through)."""
    if array is not None:
        array.setflags(write=False)
    return array


def cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``a x b`` over the last axis (3-vectors or stacks of them, broadcast).

    The same as ``np.cross``, whose axis handling costs ~10 us a call: the exact
    drive calls it 8 times, and the drive table evaluates the drive ~500 times
    for a 2 s run. Two 3-vectors go through Python floats (~1 us against ~5 us
    for a dozen small numpy operations), the same IEEE products and differences
    as numpy's element-wise ones, so the same bits (but not numpy's
    floating-point error states: ``np.errstate(over="raise")`` does not apply).
    """
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    if a.shape == b.shape == (3,):
        ax, ay, az = a.tolist()
        bx, by, bz = b.tolist()
        return np.array([ay * bz - az * by, az * bx - ax * bz, ax * by - ay * bx])
    # np.broadcast's shape: ~0.4 us against ~1.5 us for np.broadcast_shapes
    out = np.empty(np.broadcast(a, b).shape)
    out[..., 0] = a[..., 1] * b[..., 2] - a[..., 2] * b[..., 1]
    out[..., 1] = a[..., 2] * b[..., 0] - a[..., 0] * b[..., 2]
    out[..., 2] = a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]
    return out


def euler_zyx(roll: float, pitch: float, yaw: float) -> np.ndarray:
    """R = Rz(yaw) Ry(pitch) Rx(roll)."""
    return pin.rpy.rpyToMatrix(roll, pitch, yaw)


@dataclass(frozen=True)
class PlatformState:
    """Platform origin position, rotation, twist and acceleration (world axes)."""

    position: np.ndarray
    rotation: np.ndarray
    velocity: np.ndarray
    angular_velocity: np.ndarray
    acceleration: np.ndarray
    angular_acceleration: np.ndarray


def platform_state(layout: PlatformLayout, pose: np.ndarray, rate: np.ndarray | None = None, accel: np.ndarray | None = None) -> PlatformState:
    """Full platform state from the 5 pose coordinates ``[x, z, roll, pitch, yaw]`` and their derivatives."""
    rate = np.zeros(5) if rate is None else rate
    accel = np.zeros(5) if accel is None else accel
    x, z, roll, pitch, yaw = pose
    rotation = euler_zyx(roll, pitch, yaw)
    limb = layout.limbs[layout.plane_limb]
    normal = layout.plane_normal  # UnreachablePoseError unless (close to) the world y axis
    # tip of the R limb in the plane normal to its axis through its base point
    lever = rotation @ limb.platform_point  # platform origin to the R limb's tip, world
    y = (normal @ limb.base_point - normal[0] * (x + lever[0]) - normal[2] * (z + lever[2])) / normal[1] - lever[1]
    position = np.array([x, y, z])
    # angular velocity and acceleration of Z-Y-X Euler angles (world axes)
    cz, sz, cy, sy = math.cos(yaw), math.sin(yaw), math.cos(pitch), math.sin(pitch)
    axis_yaw = np.array([0.0, 0.0, 1.0])
    axis_pitch = np.array([-sz, cz, 0.0])
    axis_roll = np.array([cz * cy, sz * cy, -sy])
    d_roll, d_pitch, d_yaw = rate[2], rate[3], rate[4]
    omega = d_yaw * axis_yaw + d_pitch * axis_pitch + d_roll * axis_roll
    axis_pitch_dot = cross(d_yaw * axis_yaw, axis_pitch)
    axis_roll_dot = cross(d_yaw * axis_yaw + d_pitch * axis_pitch, axis_roll)
    alpha = accel[4] * axis_yaw + accel[3] * axis_pitch + d_pitch * axis_pitch_dot + accel[2] * axis_roll + d_roll * axis_roll_dot
    # the y translation keeps the R limb tip in its plane: differentiate that condition
    v_lever = cross(omega, lever)
    a_lever = cross(alpha, lever) + cross(omega, v_lever)
    vy = -(normal[0] * (rate[0] + v_lever[0]) + normal[2] * (rate[1] + v_lever[2])) / normal[1] - v_lever[1]
    ay = -(normal[0] * (accel[0] + a_lever[0]) + normal[2] * (accel[1] + a_lever[2])) / normal[1] - a_lever[1]
    return PlatformState(
        position, rotation, np.array([rate[0], vy, rate[1]]), omega, np.array([accel[0], ay, accel[1]]), alpha
    )


@dataclass(frozen=True)
class LegSolution:
    """Actuator lengths, their rates and accelerations, unit leg vectors (rows)."""

    lengths: np.ndarray
    rates: np.ndarray
    accelerations: np.ndarray
    directions: np.ndarray
    levers: np.ndarray  # R r_k, platform origin to tip, world


def leg_kinematics(layout: PlatformLayout, state: PlatformState) -> LegSolution:
    """Exact actuator lengths and their first and second time derivatives."""
    levers = layout.platform_points @ state.rotation.T
    d = state.position + levers - layout.base_points
    lengths = np.linalg.norm(d, axis=1)
    u = d / lengths[:, None]
    v_tip = state.velocity + cross(state.angular_velocity, levers)
    a_tip = state.acceleration + cross(state.angular_acceleration, levers) + cross(state.angular_velocity, v_tip - state.velocity)
    rates = np.einsum("ij,ij->i", u, v_tip)
    accelerations = np.einsum("ij,ij->i", u, a_tip) + (np.einsum("ij,ij->i", v_tip, v_tip) - rates**2) / lengths
    return LegSolution(lengths, rates, accelerations, u, levers)


def actuation_jacobian(layout: PlatformLayout, legs: LegSolution) -> np.ndarray:
    """J (5x5) with ``Ld = J [xd, zd, w_x L_c, w_y L_c, w_z L_c]``, rotations scaled by L_c.

    ``Ld_k = u_k . (v + w x r_k) = u_k . v + (r_k x u_k) . w``; the in-plane
    velocity has two components (x, z) once the R limb fixes y (for the
    reference layout the R axis is world y and the tip lies on it, so vy = 0 to
    first order when w is zero; the y coupling is kept through the lever terms).
    Rotational columns are divided by the characteristic length (the platform
    radius) so the condition number does not depend on units.
    """
    u, r = legs.directions, legs.levers
    moment = cross(r, u) / layout.characteristic_length
    return np.column_stack([u[:, 0], u[:, 2], moment])


def condition_number(layout: PlatformLayout, legs: LegSolution) -> float:
    return float(np.linalg.cond(actuation_jacobian(layout, legs)))


def _axis_angle(axis: np.ndarray, u: np.ndarray) -> float:
    """Angle about ``axis`` taking e_z onto ``u`` (u normal to the axis)."""
    e_z = np.array([0.0, 0.0, 1.0])
    return math.atan2(float(cross(e_z, u) @ axis), float(e_z @ u))


def inverse_kinematics(layout: PlatformLayout, pose: np.ndarray, *, check: bool = True) -> tuple[np.ndarray, LegSolution]:
    """Joint configuration q (ideal mechanism coordinates) and leg solution for a platform pose.

    Raises :class:`StrokeLimitError` if an actuator length leaves its stroke,
    :class:`UnreachablePoseError` if a limb cannot reach, and
    :class:`SingularConfigurationError` if the actuation Jacobian is singular.
    """
    mechanism = layout.mechanism
    model = mechanism.model
    pose = np.asarray(pose, dtype=float)
    if pose.shape != (5,) or not np.all(np.isfinite(pose)):
        raise UnreachablePoseError(f"pose must be 5 finite numbers [x, z, roll, pitch, yaw], got {pose!r}")
    state = platform_state(layout, pose)
    legs = leg_kinematics(layout, state)
    q = pin.neutral(model)
    frame = pin.SE3(state.rotation, state.position)
    idx = model.idx_qs[layout.platform_joint]
    q[idx : idx + 7] = pin.SE3ToXYZQUAT(model.jointPlacements[layout.platform_joint].actInv(frame))
    for k, limb in enumerate(layout.limbs):
        u = legs.directions[k]
        if limb.kind == "UPS":
            if abs(u[0]) >= 1.0 - 1e-9:
                raise UnreachablePoseError(f"limb {limb.actuator}: leg lies along the universal joint's first axis")
            angles = (math.atan2(-u[1], u[2]), math.asin(u[0]))
            for joint_id, angle in zip(limb.joint_ids[:2], angles):
                q[model.idx_qs[joint_id]] = angle
        else:
            axis = limb.revolute_axis
            if abs(u @ axis) > 1e-9:
                raise UnreachablePoseError(f"limb {limb.actuator}: tip leaves the plane of its revolute joint")
            angle = _axis_angle(axis, u)
            first = limb.joint_ids[0]
            if model.joints[first].shortname() == "JointModelFreeFlyer":
                # the free-flyer's q is the placement relative to the joint origin (as for the
                # ideal revolute joint): a rotation about the axis expressed in the joint frame
                local_axis = model.jointPlacements[first].rotation.T @ axis
                placement = pin.SE3(pin.exp3(local_axis * angle), np.zeros(3))
                q[model.idx_qs[first] : model.idx_qs[first] + 7] = pin.SE3ToXYZQUAT(placement)
            else:
                q[model.idx_qs[first]] = angle
        q[model.idx_qs[limb.joint_ids[-1]]] = legs.lengths[k]
    if check:
        order = [mechanism.actuated_joints.index(limb.actuator) for limb in layout.limbs]
        lengths = np.empty(len(order))
        lengths[order] = legs.lengths
        for name, value, lower, upper in zip(mechanism.actuated_joints, lengths, mechanism.stroke_lower, mechanism.stroke_upper):
            if not lower <= value <= upper:
                raise StrokeLimitError(
                    f"pose {np.round(pose, 6).tolist()}: actuator {name} length {value:.6f} m is outside its stroke "
                    f"[{lower}, {upper}] m; the pose is outside the workspace"
                )
        cond = condition_number(layout, legs)
        if not cond < SINGULAR_CONDITION:
            raise SingularConfigurationError(
                f"pose {np.round(pose, 6).tolist()}: actuation Jacobian condition number {cond:.3e} "
                f"exceeds {SINGULAR_CONDITION:.0e}; the pose is (near) singular"
            )
    return q, legs
