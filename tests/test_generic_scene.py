"""The engine is not tied to the 4-UPS/RPS: a slider-crank with a revolute clearance joint, crank at constant speed."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from robot.run import build_run, run_scene

DATA = Path(__file__).resolve().parent / "data"

SCENE = """
name = "slider_crank_clearance"
description = "Flores-type slider-crank: revolute clearance joint K between rod and slider"
mechanism = "{urdf}"
end_effector = "slider"
duration = 0.05

[trajectory]
type = "joints"
crank = {{ offset = 0.0, rate = 20.0 }}

[solver]
rtol = 1e-8
atol = 1e-10
max_step = 1e-3

[materials.steel]
youngs_modulus = 2.07e11
poisson_ratio = 0.3

[[clearance]]
joint = "K"
type = "revolute"
material = "steel"
journal_radius = 0.005
radial_clearance = 2.5e-4
bearing_outer_radius = 0.008
bearing_length = 0.01
axial_clearance = 1.0e-4
restitution = 0.9
"""


@pytest.fixture(scope="module")
def slider_crank(tmp_path_factory):
    path = tmp_path_factory.mktemp("scene") / "slider_crank.toml"
    path.write_text(SCENE.format(urdf=(DATA / "slider_crank.urdf").as_posix()))
    run = build_run(str(path))
    return run, run_scene(run)


def test_clearance_on_a_closure_of_another_mechanism_builds_only_what_it_needs(slider_crank):
    run, _ = slider_crank
    assert run.mechanism.model.nv == 3  # crank, rod, slider: the revolute closure K is gone
    assert run.mechanism.n_closure_equations == 0
    assert run.dynamics.n_candidates == 4


def test_crank_turns_at_the_prescribed_constant_speed(slider_crank):
    run, result = slider_crank
    assert result.success, result.message
    crank = run.mechanism.actuator_v_index[0]
    np.testing.assert_allclose(result["v"][:, crank], 20.0, atol=1e-8)
    np.testing.assert_allclose(result["q"][:, run.mechanism.actuator_q_index[0]], 20.0 * result["t"], atol=1e-9)


def test_journal_hits_the_bearing_and_energy_balances(slider_crank):
    _, result = slider_crank
    assert result["K_normal_force"].max() > 10.0
    assert result["K_penetration"].max() < 0.1 * 2.5e-4
    energy = result["kinetic_energy"] + result["potential_energy"]
    balance = energy - energy[0] - result["actuator_work"] - result["contact_work"]
    assert np.abs(balance).max() < 1e-6 * np.abs(result["actuator_work"]).max()
