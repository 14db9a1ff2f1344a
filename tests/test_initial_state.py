"""Initial state of any mechanism: ``[initial] positions`` and ``velocities`` by joint name.

Given coordinates independent of the constraints are held exactly; the others are
corrected onto the constraint manifold (positions: Newton, velocities: minimum-norm
projection) with a warning; impossible values give an error naming the key.
"""

from __future__ import annotations

import math
import re
import warnings
from pathlib import Path

import numpy as np
import pytest

from robot.errors import InitialStateError, InitialStateWarning, RedundantConstraintWarning, SceneError
from robot.model import constraints as C
from robot.model import kinematics as K
from robot.run import build_run, run_scene

DATA = Path(__file__).resolve().parent / "data"
SLIDER_CRANK = DATA / "slider_crank.urdf"
FOUR_BAR = DATA / "four_bar.urdf"
CRANK, ROD, SLIDER_ORIGIN = 0.05, 0.12, 0.14


def _scene(tmp_path: Path, urdf: Path, initial: str, trajectory: str = "crank = { offset = 0.3, rate = 20.0 }", gravity: str = "[0.0, -9.81, 0.0]") -> Path:
    path = tmp_path / "scene.toml"
    path.write_text(
        f"""
name = "initial"
mechanism = "{urdf.as_posix()}"
end_effector = "crank"
duration = 0.1
gravity = {gravity}
[trajectory]
type = "joints"
{trajectory}
[solver]
rtol = 1e-10
atol = 1e-12
[initial]
{initial}
"""
    )
    return path


def _free_slider_crank(tmp_path: Path) -> Path:
    """The slider-crank without its transmission: no actuator, one degree of freedom."""
    path = tmp_path / "free_slider_crank.urdf"
    text, count = re.subn(r"<transmission.*?</transmission>", "", SLIDER_CRANK.read_text(), flags=re.S)
    assert count == 1
    path.write_text(text)
    return path


def _build(scene: Path):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RedundantConstraintWarning)
        return build_run(str(scene))


def _constraint_errors(run, t: float = 0.0):
    """max |Phi| and max |Phi_q v + Phi_t| of the run's initial state."""
    mechanism = run.mechanism
    model, nq = mechanism.model, mechanism.model.nq
    q, v = run.y0[:nq], run.y0[nq:]
    s, sd, _ = run.dynamics.drive.drive(t)
    constraints = C.constraint_set(mechanism)
    data = model.createData()
    K.update_kinematics(model, data, q)
    return np.abs(C.residual(constraints, data, q, s)).max(), np.abs(C.jacobian(constraints, model, data) @ v - C.velocity_rhs(constraints, sd)).max()


def _index(run, joint: str) -> tuple[int, int]:
    model = run.mechanism.model
    j = model.getJointId(joint)
    return model.idx_qs[j], model.nq + model.idx_vs[j]


def test_inconsistent_positions_and_velocities_are_assembled_and_projected(tmp_path):
    """Driven slider-crank (no freedom left): the given rod angle and slider position are only a
    guess; they are corrected onto the closure (closed form x = r cos th + sqrt(l^2 - r^2 sin^2 th))
    and the given slider rate is projected onto the velocity constraints (x' = dx/dth omega)."""
    scene = _scene(tmp_path, SLIDER_CRANK, "positions = { crank_rod = -0.45, slider = 0.02 }\nvelocities = { slider = 1.0 }")
    with pytest.warns(InitialStateWarning) as caught:
        run = _build(scene)
    messages = " | ".join(str(w.message) for w in caught)
    assert re.search(r"\[initial\] positions: .*crank_rod: -0.45 -> .*slider: 0.02 -> ", messages), messages
    assert re.search(r"\[initial\] velocities: .*slider: 1 -> ", messages), messages
    position_error, velocity_error = _constraint_errors(run)
    assert position_error < 1e-10 and velocity_error < 1e-10
    theta = math.pi / 3 + 0.3
    s, c = math.sin(theta), math.cos(theta)
    root = math.sqrt(ROD**2 - CRANK**2 * s**2)
    slider_q, slider_v = _index(run, "slider")
    assert SLIDER_ORIGIN + run.y0[slider_q] == pytest.approx(CRANK * c + root, abs=1e-12)
    assert run.y0[slider_v] == pytest.approx((-CRANK * s - CRANK**2 * s * c / root) * 20.0, abs=1e-10)


def test_independent_coordinates_are_held_exactly(tmp_path):
    """A slider-crank without actuator: the slider position and rate are independent and held exactly;
    the crank follows (x = 0.12 m: two crank angles +-th, the guess decides); the run conserves energy."""
    scene = _scene(tmp_path, _free_slider_crank(tmp_path), "positions = { slider = -0.02 }\nvelocities = { slider = 0.5 }", trajectory="")
    with warnings.catch_warnings():
        warnings.simplefilter("error", InitialStateWarning)  # nothing given is corrected
        run = _build(scene)
    slider_q, slider_v = _index(run, "slider")
    assert run.y0[slider_q] == -0.02 and run.y0[slider_v] == 0.5
    position_error, velocity_error = _constraint_errors(run)
    assert position_error < 1e-12 and velocity_error < 1e-12
    crank_q, crank_v = _index(run, "crank")
    theta = math.pi / 3 + run.y0[crank_q]
    assert CRANK * math.cos(theta) + math.sqrt(ROD**2 - CRANK**2 * math.sin(theta) ** 2) == pytest.approx(0.12, abs=1e-12)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RedundantConstraintWarning)
        result = run_scene(run)
    assert result.success, result.message
    energy = result["kinetic_energy"] + result["potential_energy"]
    assert np.ptp(result["kinetic_energy"]) > 1e-3 * energy[0]  # gravity does work: a real motion
    assert np.abs(energy - energy[0]).max() < 1e-8 * abs(energy[0])


def test_given_rocker_angle_is_a_guess_for_a_driven_four_bar(tmp_path):
    """Driven four-bar: the rocker is not independent; a wrong value is corrected to the exact
    closed-form angle (circle intersection, open branch)."""
    from test_redundant_constraints import four_bar_angles

    scene = _scene(tmp_path, FOUR_BAR, "positions = { rocker = 0.2 }")
    with pytest.warns(InitialStateWarning, match=r"\[initial\] positions: .*rocker: 0.2 -> "):
        run = _build(scene)
    rocker_q, _ = _index(run, "rocker")
    gamma = four_bar_angles(np.array([math.pi / 3 + 0.3]))[1][0]
    assert 1.365 + run.y0[rocker_q] == pytest.approx(gamma, abs=1e-12)


def test_unreachable_position_is_an_error_naming_the_key(tmp_path):
    """The slider of the free slider-crank reaches [l - r, l + r] = [0.07, 0.17] m from the crank pivot,
    i.e. q in [-0.07, 0.03]: 0.1 cannot be assembled."""
    scene = _scene(tmp_path, _free_slider_crank(tmp_path), "positions = { slider = 0.1 }", trajectory="")
    with pytest.raises(InitialStateError, match=r"\[initial\] positions \{slider = 0.1\}: the closures cannot be assembled \(held exactly: slider\)"):
        _build(scene)


@pytest.mark.parametrize(
    ("initial", "error", "message"),
    [
        ("positions = { crank = 0.5 }", InitialStateError, r"\[initial\] positions: crank = 0.5 but crank is actuated and its trajectory gives 0.3"),
        ("velocities = { crank = 3.0 }", InitialStateError, r"\[initial\] velocities: crank = 3.0 but crank is actuated and its trajectory gives 20.0"),
        ("positions = { piston = 0.5 }", InitialStateError, r"\[initial\] positions: 'piston' is not a joint of 'slider_crank'; 1-DOF joints: crank, crank_rod, slider"),
        ('positions = { slider = "far" }', SceneError, r"\[initial\] positions: slider='far' must be a finite number"),
        ("velocities = [1.0]", SceneError, r"\[initial\]: velocities=\[1.0\] must be a table"),
    ],
)
def test_bad_initial_values_name_the_key(tmp_path, initial, error, message):
    with pytest.raises(error, match=message):
        _build(_scene(tmp_path, SLIDER_CRANK, initial))
