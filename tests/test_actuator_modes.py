"""Actuator modes (motion, force, none), joint trajectory functions, free mechanisms, bad input."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

import robot
from robot.errors import SceneError
from robot.model import time_functions as TF
from robot.run import build_run
from robot.scene.loader import load_scene

ROOT = Path(__file__).resolve().parents[1]
SLIDER = (ROOT / "tests" / "data" / "slider_rotor.urdf").as_posix()
SLIDER_MASS = 2.3
ROTOR_INERTIA = 0.004 + 0.9 * (0.1**2 + 0.05**2)  # izz + m d^2 about the spin axis (the URDF's comment)

BASE = f"""
name = "modes"
mechanism = "{SLIDER}"
end_effector = "slider"
duration = {{duration}}

{{body}}

[solver]
method = "DOP853"
rtol = 1e-11
atol = 1e-13
max_step = 1e-2
"""


def write(tmp_path: Path, body: str, duration: float = 0.5, name: str = "scene.toml") -> Path:
    path = tmp_path / name
    path.write_text(BASE.format(duration=duration, body=body))
    return path


def test_a_urdf_without_transmissions_runs_free(tmp_path):
    """No transmission, `type = "joints"` and no entries (the former IndexError), and no [trajectory] at all:
    the bodies stay at rest (gravity along -z does no work on a horizontal slide and a vertical spin axis)."""
    for body in ('[trajectory]\ntype = "joints"', ""):
        r = robot.simulate(str(write(tmp_path, body)))
        assert r.success, r.message
        assert r["driving_force"].shape == (len(r.t), 0)
        assert np.all(r.q == 0.0) and np.all(r.v == 0.0)


def test_prescribed_torque_gives_the_prescribed_angular_acceleration(tmp_path):
    """tau = I alpha on the rotor: theta = alpha t^2 / 2; F = m a on the slider: x = a t^2 / 2 (exact)."""
    alpha, acceleration = 3.7, -1.9
    body = f"""
[actuators]
spin = {{ mode = "force", function = "constant", value = {ROTOR_INERTIA * alpha!r} }}
slide = {{ mode = "force", function = "constant", value = {SLIDER_MASS * acceleration!r} }}
"""
    r = robot.simulate(str(write(tmp_path, body, duration=0.8)))
    assert r.success, r.message
    np.testing.assert_allclose(r.q[:, 1], 0.5 * alpha * r.t**2, rtol=1e-10, atol=1e-13)
    np.testing.assert_allclose(r.v[:, 1], alpha * r.t, rtol=1e-10, atol=1e-13)
    np.testing.assert_allclose(r.q[:, 0], 0.5 * acceleration * r.t**2, rtol=1e-10, atol=1e-13)
    # the actuators' work is the kinetic energy they gave
    np.testing.assert_allclose(r["actuator_work"], r["kinetic_energy"], rtol=1e-9, atol=1e-13)
    assert r["force_spin"] == pytest.approx(np.full(len(r.t), ROTOR_INERTIA * alpha))


def test_harmonic_torque_drives_the_rotor_as_integrated_analytically(tmp_path):
    """tau = A sin(w t + p) on a free rotor at rest: theta = A/(I w^2) (sin p + w t cos p - sin(w t + p))."""
    amplitude, frequency, phase = 0.7, 2.3, 0.9
    body = f'[actuators]\nspin = {{ mode = "force", function = "harmonic", amplitude = {amplitude}, frequency = {frequency}, phase = {phase} }}'
    r = robot.simulate(str(write(tmp_path, body, duration=1.0)))
    w = 2 * math.pi * frequency
    theta = amplitude / (ROTOR_INERTIA * w**2) * (math.sin(phase) + w * r.t * math.cos(phase) - np.sin(w * r.t + phase))
    np.testing.assert_allclose(r.q[:, 1], theta, rtol=0, atol=1e-10 * np.max(np.abs(theta)))


CSV_SINE = (0.03, 1.7)  # amplitude (m), frequency (Hz) of the sampled motion


def sine_csv(path: Path, step: float) -> None:
    amplitude, frequency = CSV_SINE
    t = np.arange(0.0, 1.0 + step / 2, step)
    lines = ["time,value"] + [f"{float(ti)!r},{amplitude * math.sin(2 * math.pi * frequency * ti)!r}" for ti in t]
    path.write_text("\n".join(lines) + "\n")


def test_joint_trajectory_functions_against_their_analytic_derivatives(tmp_path):
    """polynomial, constant_rate, harmonic and Fourier coordinates: value, rate, acceleration exact;
    a CSV of a sampled sine: spline errors within the cubic-spline bounds (Hall and Meyer 1976)."""
    sine_csv(tmp_path / "motion.csv", 0.02)
    body = """
[trajectory]
type = "joints"
period = 0.8
slide = { function = "tabulated", file = "motion.csv" }
spin = { function = "polynomial", coefficients = [0.1, -0.4, 2.5, -1.5] }
"""
    scene = load_scene(write(tmp_path, body))
    polynomial = scene.trajectory.functions["spin"]
    for t in (0.0, 0.37, 1.9):
        expected = (0.1 - 0.4 * t + 2.5 * t**2 - 1.5 * t**3, -0.4 + 5.0 * t - 4.5 * t**2, 5.0 - 9.0 * t)
        assert polynomial.evaluate(t) == pytest.approx(expected, rel=1e-14, abs=1e-14)
    harmonic = TF.Harmonic(0.2, 1.3, 0.4, -0.1)
    w = 2 * math.pi * 1.3
    t = 0.61
    assert harmonic.evaluate(t) == pytest.approx((-0.1 + 0.2 * math.sin(w * t + 0.4), 0.2 * w * math.cos(w * t + 0.4), -0.2 * w * w * math.sin(w * t + 0.4)), rel=1e-14)
    amplitude, frequency = CSV_SINE
    w, h = 2 * math.pi * frequency, 0.02
    spline = scene.trajectory.functions["slide"]
    times = np.linspace(4 * h, 1.0 - 4 * h, 997)  # interior: the not-a-knot ends' influence decays by ~0.27 per knot
    values = np.array([spline.evaluate(t) for t in times])
    exact = np.column_stack([amplitude * np.sin(w * times), amplitude * w * np.cos(w * times), -amplitude * w * w * np.sin(w * times)])
    fourth = amplitude * w**4  # max |f''''|
    bounds = (5 / 384 * h**4 * fourth, (math.sqrt(3) / 216 + 1 / 24) * h**3 * fourth, 3 / 8 * h**2 * fourth)
    errors = np.max(np.abs(values - exact), axis=0)
    assert np.all(errors <= bounds), (errors, bounds)
    assert errors[1] > 0.01 * bounds[1]  # the bound is not vacuous: the rate error is of its order


def test_prescribed_motion_from_a_csv_on_a_joint_without_transmission(tmp_path):
    """[actuators] makes the slide motion-driven; its driving force is m times the spline's acceleration."""
    sine_csv(tmp_path / "motion.csv", 0.01)
    body = """
[actuators]
slide = { mode = "motion" }

[trajectory]
type = "joints"
slide = { function = "tabulated", file = "motion.csv" }
"""
    path = write(tmp_path, body, duration=0.6)
    r = robot.simulate(str(path))
    assert r.success, r.message
    spline = load_scene(path).trajectory.functions["slide"]
    expected = np.array([spline.evaluate(t) for t in r.t])
    np.testing.assert_allclose(r.q[:, 0], expected[:, 0], atol=1e-9)
    np.testing.assert_allclose(r["driving_force"][:, 0], SLIDER_MASS * expected[:, 2], rtol=1e-7, atol=1e-7)
    assert build_run(str(path)).mechanism.actuated_joints == ("slide",)


def test_none_mode_frees_a_transmission_joint(tmp_path):
    """A URDF transmission joint set to mode = "none": no driving constraint, no trajectory entry needed."""
    urdf = Path(SLIDER).read_text().replace(
        "</robot>",
        '<transmission name="t"><type>transmission_interface/SimpleTransmission</type><joint name="slide"/>'
        '<actuator name="m"/></transmission></robot>',
    )
    (tmp_path / "with_transmission.urdf").write_text(urdf)
    text = BASE.format(duration=0.1, body='[actuators]\nslide = { mode = "none" }').replace(SLIDER, "with_transmission.urdf")
    (tmp_path / "none.toml").write_text(text)
    run = build_run(str(tmp_path / "none.toml"))
    assert run.mechanism.actuated_joints == ()
    (tmp_path / "motion.toml").write_text(text.replace('[actuators]\nslide = { mode = "none" }', '[trajectory]\ntype = "joints"'))
    with pytest.raises(SceneError, match="missing \\['slide'\\]"):  # without it, the slide is motion-driven: it needs a trajectory
        build_run(str(tmp_path / "motion.toml"))


# bad input


def test_a_non_increasing_csv_time_column_is_refused(tmp_path):
    (tmp_path / "bad.csv").write_text("time,value\n0.0,0.0\n0.5,1.0\n0.5,2.0\n1.0,3.0\n")
    body = '[actuators]\nslide = { mode = "motion" }\n[trajectory]\ntype = "joints"\nslide = { function = "tabulated", file = "bad.csv" }'
    with pytest.raises(SceneError, match="file='bad.csv': the time column must be strictly increasing; entry 2 \\(0.5\\) follows 0.5") as error:
        load_scene(write(tmp_path, body))
    assert error.value.key == "file" and error.value.value == "bad.csv"


def test_a_missing_csv_file_names_the_key(tmp_path):
    body = '[actuators]\nslide = { mode = "motion" }\n[trajectory]\ntype = "joints"\nslide = { function = "tabulated", file = "nowhere.csv" }'
    with pytest.raises(SceneError, match="file='nowhere.csv'.*does not exist") as error:
        load_scene(write(tmp_path, body))
    assert error.value.key == "file" and error.value.value == "nowhere.csv"


def test_a_time_table_must_cover_the_run(tmp_path):
    body = '[actuators]\nspin = { mode = "force", function = "tabulated", time = [0.0, 0.2], value = [1.0, 2.0] }'
    with pytest.raises(SceneError, match="does not cover the run \\[0, 0.5\\] s"):
        load_scene(write(tmp_path, body))


@pytest.mark.parametrize(
    "body, match, key",
    [
        ('[actuators]\nspin = { mode = "torque" }', "mode='torque' must be 'motion', 'force' or 'none'", "mode"),
        ('[actuators]\nspin = { mode = "force", function = "sine", value = 1.0 }', "function='sine' is not known", "function"),
        ('[actuators]\nspin = { mode = "force", function = "harmonic", amplitude = 1.0 }', "missing required key 'frequency'", "frequency"),
        ('[actuators]\nspin = { mode = "none", value = 1.0 }', "unknown key\\(s\\) value", "value"),
    ],
)
def test_bad_actuator_tables_are_refused(tmp_path, body, match, key):
    with pytest.raises(SceneError, match=match) as error:
        load_scene(write(tmp_path, body))
    assert error.value.key == key


def test_an_actuator_on_a_fixed_or_unknown_joint_is_refused(tmp_path):
    with pytest.raises(SceneError, match="'spun' is not a joint of 'slider_rotor'; actuators drive one-coordinate joints: slide, spin") as error:
        build_run(str(write(tmp_path, '[actuators]\nspun = { mode = "none" }')))
    assert error.value.key == "spun"
