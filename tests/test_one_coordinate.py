"""Mechanisms with one velocity coordinate (nv = 1): Pinocchio's one-column matrices, and a Hertz drop test.

eigenpy returns a 6 x 1 Jacobian as a 1-D array (``robot.model.pinocchio_arrays``); a scene with one
coordinate and a closure used to stop with a broadcasting error at the initial assembly.
"""

from __future__ import annotations

import math
import warnings
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
from scipy.optimize import brentq

from clearance_contact.kernel_mode import KernelSwitchWarning
from robot.integration.records import RECORD_FORCE_PEAK, RECORD_PEAK
from robot.model.pinocchio_arrays import frame_jacobian, joint_jacobian, tangent_map_product
from robot.run import build_run, run_scene

DATA = Path(__file__).resolve().parent / "data"
MASS, GRAVITY, BALL_RADIUS, CLEARANCE, YOUNG, POISSON = 2.0, 9.81, 0.02, 2.0e-4, 2.1e11, 0.29

SCENE = f"""
name = "ball_drop"
mechanism = "{DATA / 'ball_on_slide.urdf'}"
end_effector = "ball"
duration = 0.012
gravity = [0.0, 0.0, -{GRAVITY}]
[solver]
method = "DOP853"
rtol = 1e-10
atol = 1e-14
max_step = 1e-5
[materials.steel]
youngs_modulus = {YOUNG}
poisson_ratio = {POISSON}
[[clearance]]
joint = "S"
type = "spherical"
outer_on = "parent"
material = "steel"
ball_radius = {BALL_RADIUS}
clearance = {CLEARANCE}
restitution = 1.0
friction = {{ law = "none" }}
[output]
precision = "float64"
step = 0
"""


def test_pinocchio_arrays_keep_their_shape_at_one_coordinate():
    model = pin.buildModelFromUrdf(str(DATA / "ball_on_slide.urdf"))
    data = model.createData()
    q, v = np.array([0.3]), np.array([-1.5])
    pin.computeJointJacobians(model, data, q)
    pin.updateFramePlacements(model, data)
    assert pin.getFrameJacobian(model, data, 1, pin.LOCAL_WORLD_ALIGNED).shape == (6,)  # what eigenpy returns
    frame = model.getFrameId("ball")
    assert frame_jacobian(model, data, frame).shape == (6, 1)
    np.testing.assert_array_equal(frame_jacobian(model, data, frame)[:, 0], [0, 0, 1, 0, 0, 0])  # a vertical slide
    assert joint_jacobian(model, data, 1).shape == (6, 1)
    np.testing.assert_array_equal(joint_jacobian(model, data, 1)[:, 0], [0, 0, 1, 0, 0, 0])
    assert tangent_map_product(model, q, v).shape == (1,) and tangent_map_product(model, q, v)[0] == -1.5


def test_hertz_drop_of_a_ball_on_one_coordinate(tmp_path):
    """The ball falls across the clearance and hits the socket: onset at sqrt(2 c / g), the deepest
    penetration and the force from energy with gravity during the impact, elastic rebound (c_e = 1)."""
    path = tmp_path / "drop.toml"
    path.write_text(SCENE)
    with warnings.catch_warnings():
        warnings.simplefilter("error", KernelSwitchWarning)  # the kernels take the nv = 1 arrays
        result = run_scene(build_run(str(path)))
    assert result.success, result.message
    e_star = YOUNG / (2 * (1 - POISSON**2))
    socket = BALL_RADIUS + CLEARANCE
    stiffness = 4 / 3 * e_star * math.sqrt(BALL_RADIUS * socket / CLEARANCE)  # internal Hertz contact
    onset = math.sqrt(2 * CLEARANCE / GRAVITY)
    speed = GRAVITY * onset
    deepest = brentq(lambda d: 0.4 * stiffness * d**2.5 - 0.5 * MASS * speed**2 - MASS * GRAVITY * d, 1e-9, 1e-4, xtol=1e-20)
    first_onset = result["event_t"][result["event_is_onset"]][0]
    assert first_onset == pytest.approx(onset, rel=1e-6)
    kinds, values = result["event_kind"], result["event_value"]
    assert values[kinds == RECORD_PEAK][0] == pytest.approx(deepest, rel=1e-6)
    assert values[kinds == RECORD_FORCE_PEAK][0] == pytest.approx(stiffness * deepest**1.5, rel=1e-6)
    # elastic, frictionless: after the impact (t_end, separated) the mechanical energy is what it was
    energy = result["kinetic_energy"] + result["potential_energy"]
    assert abs(energy[-1] - energy[0]) < 1e-8 * 0.5 * MASS * speed**2
    assert result["v"][-1, 0] > 0  # moving up again
