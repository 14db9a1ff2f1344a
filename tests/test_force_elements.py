"""Force elements (robot.dynamics.forces): energy balance, generalized force = -grad V, analytic
oscillations, tabulated = linear, both right-hand sides and the reference composition, bad input."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

import robot
from robot.analysis.studies.speed import reference_state_derivative
from robot.dynamics import equations as D
from robot.dynamics import state_jacobian as SJ
from robot.errors import SceneError
from robot.run import build_run, run_scene
from robot.scene.loader import load_scene

ROOT = Path(__file__).resolve().parents[1]
ARM = (ROOT / "urdf" / "two_link_arm.urdf").as_posix()
SLIDER = (ROOT / "tests" / "data" / "slider_rotor.urdf").as_posix()
SLIDER_MASS = 2.3

# the free two-link arm: elbow spring (c = 0), tip spring to the world (c = 0), harmonic shoulder torque, gravity
ARM_SCENE = f"""
name = "arm"
mechanism = "{ARM}"
end_effector = "tip"
duration = 1.5

{{actuators}}

[[force]]
name = "elbow_spring"
type = "joint_spring_damper"
joint = "elbow"
stiffness = 7.3
rest_position = -0.6
damping = {{elbow_damping}}

[[force]]
name = "tip_spring"
type = "spring_damper"
link_a = "forearm"
xyz_a = [0.02, 0.0, -0.35]
link_b = "world"
xyz_b = [0.45, 0.0, -0.5]
stiffness = 55.0
free_length = 0.15
damping = {{tip_damping}}

{{extra}}

[solver]
method = "DOP853"
rtol = 1e-11
atol = 1e-13
max_step = 1e-2
"""
SHOULDER_ACTUATOR = '[actuators]\nshoulder = { mode = "force", function = "harmonic", amplitude = 2.1, frequency = 1.3, phase = 0.4, offset = 0.2 }'
SHOULDER_ELEMENT = '[[force]]\nname = "shoulder_torque"\ntype = "joint_torque"\njoint = "shoulder"\nfunction = "harmonic"\namplitude = 2.1\nfrequency = 1.3\nphase = 0.4\noffset = 0.2'


def write(tmp_path: Path, text: str, name: str = "scene.toml") -> Path:
    path = tmp_path / name
    path.write_text(text)
    return path


def arm_scene(tmp_path, *, elbow_damping=0.0, tip_damping=0.0, torque_as="actuator", extra=""):
    actuators = SHOULDER_ACTUATOR if torque_as == "actuator" else ""
    extra = (SHOULDER_ELEMENT if torque_as == "element" else "") + "\n" + extra
    text = ARM_SCENE.format(actuators=actuators, elbow_damping=elbow_damping, tip_damping=tip_damping, extra=extra)
    return write(tmp_path, text, f"arm_{torque_as}_{elbow_damping}_{tip_damping}.toml")


@pytest.fixture(scope="module")
def conservative_arm(tmp_path_factory):
    return robot.simulate(str(arm_scene(tmp_path_factory.mktemp("arm"))))


def test_energy_balance_closes_for_a_torque_driven_free_arm_with_springs(conservative_arm):
    """kinetic + gravity + spring energy - work of the shoulder torque is constant (DOP853 rtol 1e-11)."""
    r = conservative_arm
    assert r.success, r.message
    assert r["driving_force"].shape[1] == 0  # no motion-driven actuator
    energy = r["kinetic_energy"] + r["potential_energy"] + r["force_energy"]
    balance = energy - r["actuator_work"]
    scale = np.ptp(r["kinetic_energy"]) + np.ptp(r["potential_energy"]) + np.ptp(r["force_energy"])
    assert scale > 1.0  # the run moves: springs, gravity and the torque all exchange energy
    assert np.ptp(balance) < 1e-8 * scale
    # the springs are conservative (c = 0): their integrated work is minus their energy change
    np.testing.assert_allclose(r["force_work"], -(r["force_energy"] - r["force_energy"][0]), atol=1e-8 * scale)
    # the actuator work is the integral of the applied torque times the shoulder rate
    torque = 0.2 + 2.1 * np.sin(2 * np.pi * 1.3 * r.t + 0.4)
    np.testing.assert_allclose(r["force_shoulder"], torque, rtol=0, atol=1e-12)
    np.testing.assert_allclose(r["actuator_power"], torque * r.v[:, 0], rtol=0, atol=1e-12)


def test_a_torque_element_equals_the_force_driven_actuator_and_dampers_dissipate(tmp_path, conservative_arm):
    """The same torque as a joint_torque element: the same motion, its work in force_work instead of actuator_work.
    With dampers: kinetic + gravity - actuator work - force work is constant, and the dampers' work
    (force work + change of spring energy) never increases."""
    element = robot.simulate(str(arm_scene(tmp_path, torque_as="element")))
    # the two runs take different steps (the accumulators enter the error norm): compare at the end
    assert element.t[-1] == conservative_arm.t[-1]
    np.testing.assert_allclose(element.q[-1], conservative_arm.q[-1], rtol=0, atol=1e-8)
    assert element["force_work"][-1] == pytest.approx(conservative_arm["force_work"][-1] + conservative_arm["actuator_work"][-1], abs=1e-8)
    assert np.all(element["actuator_work"] == 0.0)
    damped = robot.simulate(str(arm_scene(tmp_path, elbow_damping=0.08, tip_damping=0.9)))
    balance = damped["kinetic_energy"] + damped["potential_energy"] - damped["actuator_work"] - damped["force_work"]
    assert np.ptp(balance) < 1e-8 * np.ptp(damped["kinetic_energy"])
    damper_work = damped["force_work"] + damped["force_energy"] - damped["force_energy"][0]
    assert np.all(np.diff(damper_work) <= 1e-12)
    assert damper_work[-1] < -0.05 * np.ptp(damped["kinetic_energy"])


def test_generalized_force_of_the_springs_is_minus_the_gradient_of_their_energy(tmp_path):
    """Q(q, v = 0) = -dV/dq by central differences, at poses the scene does not start from (c = 0)."""
    run = build_run(str(arm_scene(tmp_path, torque_as="none")))
    dynamics = run.dynamics
    model = dynamics.mechanism.model
    workspace = D.make_workspace(dynamics)
    forces, data = workspace.forces, workspace.data
    rng = np.random.default_rng(3)

    def energy(q):
        pin.computeJointJacobians(model, data, q)
        return forces.potential_energy(q)

    for _ in range(5):
        q = rng.uniform(-2.5, 2.5, model.nq)
        pin.computeJointJacobians(model, data, q)
        force = forces.evaluate(0.0, q, np.zeros(model.nv)).copy()
        h = 1e-6
        gradient = np.array([(energy(q + h * e) - energy(q - h * e)) / (2 * h) for e in np.eye(model.nq)])
        np.testing.assert_allclose(force, -gradient, rtol=1e-7, atol=1e-7 * np.max(np.abs(force)))


def test_compiled_and_python_right_hand_sides_and_the_reference_agree(tmp_path):
    """Damped springs, a body force, a body torque and the actuator torque: the same dy/dt three ways."""
    extra = """
[[force]]
name = "push"
type = "body_force"
link = "upper_arm"
xyz = [0.01, 0.0, -0.3]
direction = [1.0, 0.0, 0.4]
function = "polynomial"
coefficients = [0.5, -1.2, 0.3]

[[force]]
name = "twist"
type = "body_torque"
link = "forearm"
axis = [0.0, 1.0, 0.0]
function = "constant"
value = -0.35
"""
    run = build_run(str(arm_scene(tmp_path, elbow_damping=0.08, tip_damping=0.9, extra=extra)))
    dynamics = run.dynamics
    compiled, python = D.make_workspace(dynamics), D.make_workspace(dynamics)
    assert compiled.compiled is not None
    python.compiled = None
    data = dynamics.mechanism.model.createData()
    rng = np.random.default_rng(8)
    for t in (0.0, 0.31, 1.27):
        y = np.concatenate([rng.uniform(-2, 2, 2), rng.uniform(-3, 3, 2), np.zeros(3)])
        expected = reference_state_derivative(dynamics, data, t, y, np.zeros(0))
        for workspace in (compiled, python):
            np.testing.assert_allclose(D.state_derivative(dynamics, workspace, t, y, np.zeros(0)), expected, rtol=1e-12, atol=1e-12)
        assert expected[-1] != 0.0 and expected[-3] != 0.0  # force work and actuator work both move


def test_implicit_methods_difference_the_right_hand_side_when_springs_are_present(tmp_path):
    """Springs: no structured Jacobian (documented fallback); Radau still reaches the DOP853 motion."""
    run = build_run(str(arm_scene(tmp_path)), duration=0.3)
    assert SJ.for_workspace(run.dynamics, D.make_workspace(run.dynamics)) is None
    reference = run_scene(run)
    radau = robot.simulate(run.scene, {"solver.method": "Radau", "solver.rtol": 1e-9, "solver.atol": 1e-11})
    assert radau.success
    np.testing.assert_allclose(radau.q[-1], reference.q[-1], atol=2e-6)


PUSH = '[[force]]\nname = "push"\ntype = "body_force"\nlink = "forearm"\nxyz = [0, 0, -0.2]\ndirection = [1, 0, 0]\nfunction = "constant"\nvalue = 1.7'


@pytest.mark.parametrize("extra", ["", PUSH], ids=["joint_torque", "joint_torque+body_force"])
def test_structured_jacobian_with_time_only_loads_matches_finite_differences(tmp_path, extra):
    """Only time-dependent loads (no springs): the structured Jacobian applies, exact for a tree (no constraints),
    power rows included; a body force's Q varies with q through its point Jacobian, a left-out geometric term
    (state_jacobian docstring): then the q columns of qdd and of the force power are not compared."""
    text = ARM_SCENE.format(actuators=SHOULDER_ACTUATOR, elbow_damping=0, tip_damping=0, extra="")
    text = text.split('[[force]]\nname = "elbow_spring"')[0] + extra + '\n[solver]\nmethod = "BDF"\n'
    run = build_run(str(write(tmp_path, text)))
    workspace = D.make_workspace(run.dynamics)
    jacobian = SJ.for_workspace(run.dynamics, workspace)
    assert jacobian is not None
    n = run.dynamics.state_size
    rows = [0, 1, 4, 5] if extra else list(range(n))
    for t, y in ((0.2, [0.3, -0.7, 0.5, 1.1, 0, 0, 0]), (0.9, [-1.2, 0.4, -2.0, 0.3, 0, 0, 0])):
        y = np.array(y, dtype=float)
        structured = jacobian(t, y, np.zeros(0), np.empty((n, n)))
        reference = SJ.finite_difference_jacobian(lambda tt, yy: D.state_derivative(run.dynamics, workspace, tt, yy, np.zeros(0)), t, y)
        np.testing.assert_allclose(structured[:, 2:], reference[:, 2:], atol=1e-6)
        np.testing.assert_allclose(structured[rows, :], reference[rows, :], atol=1e-6)
        assert np.abs(structured[4, 2]) > 0.1  # the actuator power row sees the torque


SLIDER_SCENE = f"""
name = "slider"
mechanism = "{SLIDER}"
end_effector = "slider"
duration = {{duration}}

[[force]]
name = "spring"
type = "spring_damper"
link_a = "slider"
link_b = "world"
xyz_b = {{anchor}}
{{law}}

[solver]
method = "DOP853"
rtol = 1e-11
atol = 1e-14
max_step = 2e-3
"""


def slider_run(tmp_path, anchor, law, duration, name):
    return robot.simulate(str(write(tmp_path, SLIDER_SCENE.format(anchor=anchor, law=law, duration=duration), name)))


def test_collinear_spring_oscillates_at_sqrt_k_over_m(tmp_path):
    """Spring along the slide from a world point: x(t) = x_eq + (x0 - x_eq) cos(sqrt(k/m) t), exactly."""
    k, free_length, anchor = 310.0, 0.37, -0.55
    r = slider_run(tmp_path, f"[{anchor}, 0.0, 0.0]", f"stiffness = {k}\nfree_length = {free_length}", 1.0, "collinear.toml")
    omega = math.sqrt(k / SLIDER_MASS)
    x_eq = anchor + free_length
    np.testing.assert_allclose(r.q[:, 0], x_eq + (0.0 - x_eq) * np.cos(omega * r.t), rtol=0, atol=1e-9)
    np.testing.assert_allclose(r["force_spring"], k * (r.q[:, 0] - anchor - free_length), rtol=0, atol=1e-9)
    assert np.all(r.q[:, 1] == 0.0)  # the rotor feels nothing


def test_inclined_spring_small_oscillation_frequency(tmp_path):
    """Anchor at height h above the slide: omega^2 = k (1 - L0/h) / m for small motion. Amplitude 1e-3 h: the cubic
    term shifts the frequency by 3.5e-6, i.e. 4.4e-5 of the amplitude over two periods; a 1e-3 error in omega would
    show as 1.3e-2 of it."""
    k, free_length, h, amplitude = 310.0, 0.3, 0.4, 4e-4
    omega = math.sqrt(k * (1.0 - free_length / h) / SLIDER_MASS)
    duration = 2 * 2 * math.pi / omega
    r = slider_run(tmp_path, f"[{-amplitude}, 0.0, {h}]", f"stiffness = {k}\nfree_length = {free_length}", duration, "inclined.toml")
    expected = -amplitude + amplitude * np.cos(omega * r.t)
    assert np.max(np.abs(r.q[:, 0] - expected)) < 1e-4 * amplitude
    detuned = -amplitude + amplitude * np.cos(1.001 * omega * r.t)
    assert np.max(np.abs(r.q[:, 0] - detuned)) > 1e-2 * amplitude


def test_tabulated_force_length_equal_to_the_linear_law_gives_the_same_motion(tmp_path):
    k, free_length = 310.0, 0.3
    lengths = np.linspace(0.2, 0.9, 9)
    law = f"length = {lengths.tolist()}\nforce = {(k * (lengths - free_length)).tolist()}"
    linear = slider_run(tmp_path, "[-0.05, 0.0, 0.4]", f"stiffness = {k}\nfree_length = {free_length}", 0.5, "linear.toml")
    table = slider_run(tmp_path, "[-0.05, 0.0, 0.4]", law, 0.5, "table.toml")
    assert linear.t.shape == table.t.shape
    np.testing.assert_allclose(table.q, linear.q, rtol=0, atol=1e-13)
    np.testing.assert_allclose(table["force_spring"], linear["force_spring"], rtol=0, atol=1e-10)
    # the table's energy is measured from its first length: it differs from the linear one by a constant
    offset = linear["force_energy"] - table["force_energy"]
    np.testing.assert_allclose(offset, 0.5 * k * (0.2 - free_length) ** 2, rtol=1e-12)


def test_tabulated_spring_continues_along_its_end_tangent(tmp_path):
    """Beyond the table the force grows with the end slope and the energy is its integral."""
    path = write(tmp_path, SLIDER_SCENE.format(anchor="[-0.5, 0, 0]", law="length = [0.1, 0.2, 0.4]\nforce = [0.0, 5.0, 30.0]", duration=0.1))
    curve = load_scene(path).forces[0].parameters["curve"]
    value, slope, _ = curve.evaluate(0.4)
    assert curve.evaluate(0.5)[:2] == pytest.approx((value + 0.1 * slope, slope))
    assert curve.integral(0.5) == pytest.approx(curve.integral(0.4) + 0.1 * value + 0.5 * slope * 0.01)


# bad input: each a SceneError naming the key and the value


def test_a_spring_on_an_unknown_link_is_refused(tmp_path):
    text = SLIDER_SCENE.format(anchor="[0, 0, 0]", law="stiffness = 1.0\nfree_length = 0.1", duration=0.1).replace('link_a = "slider"', 'link_a = "slidr"')
    with pytest.raises(SceneError, match="link_a='slidr' is not a link") as error:
        build_run(str(write(tmp_path, text)))
    assert error.value.key == "link_a" and error.value.value == "slidr"


def test_a_torque_on_a_prismatic_joint_is_refused(tmp_path):
    text = SLIDER_SCENE.format(anchor="[0, 0, 0]", law="stiffness = 1.0\nfree_length = 0.1", duration=0.1)
    text += '\n[[force]]\nname = "bad"\ntype = "joint_torque"\njoint = "slide"\nfunction = "constant"\nvalue = 1.0\n'
    with pytest.raises(SceneError, match="'slide' is a prismatic joint; type='joint_torque' acts on revolute or continuous joints \\(use type = 'joint_force'\\)") as error:
        build_run(str(write(tmp_path, text)))
    assert error.value.key == "joint" and error.value.value == "slide"


def test_an_unknown_force_type_is_refused(tmp_path):
    text = SLIDER_SCENE.format(anchor="[0, 0, 0]", law="stiffness = 1.0\nfree_length = 0.1", duration=0.1).replace('"spring_damper"', '"bungee"')
    with pytest.raises(SceneError, match="type='bungee' is not a force element type; types: .*spring_damper") as error:
        load_scene(write(tmp_path, text))
    assert error.value.key == "type" and error.value.value == "bungee"


@pytest.mark.parametrize(
    "law, key, value",
    [
        ("stiffness = -1.0\nfree_length = 0.1", "stiffness", -1.0),
        ("stiffness = 1.0", "free_length", None),
        ("length = [0.1, 0.3, 0.2]\nforce = [0, 1, 2]", "length", [0.1, 0.3, 0.2]),
        ("stiffness = 1.0\nfree_length = 0.1\nlength = [0.1, 0.2]\nforce = [0, 1]", "stiffness", 1.0),
        ("stiffness = 1.0\nfree_length = 0.1\nstifness = 2.0", "stifness", 2.0),
    ],
)
def test_bad_spring_parameters_are_refused(tmp_path, law, key, value):
    with pytest.raises(SceneError, match=key) as error:
        load_scene(write(tmp_path, SLIDER_SCENE.format(anchor="[0, 0, 0]", law=law, duration=0.1)))
    assert error.value.key == key and error.value.value == value


def test_force_element_parameters_can_be_overridden_by_name(tmp_path):
    scene = load_scene(write(tmp_path, SLIDER_SCENE.format(anchor="[0, 0, 0]", law="stiffness = 1.0\nfree_length = 0.1", duration=0.1)))
    assert scene.with_changes({"force.spring.stiffness": 42.0}).forces[0].parameters["stiffness"] == 42.0


def test_shipped_free_two_link_spring_scene_runs(tmp_path):
    """The example scene on a short horizon: it moves, and kinetic + gravity - actuator work - force work holds."""
    r = robot.simulate("free_two_link_spring", t_end=0.3)
    assert r.success, r.message
    assert {"force_elbow_spring", "force_tip_spring", "force_shoulder", "force_work", "force_energy"} <= set(r.keys())
    balance = r["kinetic_energy"] + r["potential_energy"] - r["actuator_work"] - r["force_work"]
    assert np.ptp(r["kinetic_energy"]) > 0.1
    assert np.ptp(balance) < 1e-6 * np.ptp(r["kinetic_energy"])  # the scene's own tolerance, rtol 1e-9
