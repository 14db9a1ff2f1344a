"""A diverging run stops with the time and the cause, keeping what it computed."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from robot.io.results import load_result
from robot.run import build_run, run_scene

ROOT = Path(__file__).resolve().parents[1]


def _absurd_step_scene(tmp_path) -> Path:
    path = tmp_path / "absurd.toml"
    path.write_text('extends = "spherical"\nname = "absurd"\nduration = 0.5\n[solver]\nmethod = "RK4"\nfirst_step = 2e-3\n')
    return path


def test_absurd_fixed_step_is_reported_as_failed(tmp_path):
    result = run_scene(build_run(str(_absurd_step_scene(tmp_path))))
    assert not result.success
    assert result.cause in {"penetration beyond physical bound", "non-finite state"}
    assert "t=" in result.message
    assert 0.0 < result.t_end < 0.5
    assert np.all(np.isfinite(result["q"]))  # what was kept is the good part
    assert result["t"][-1] == pytest.approx(result.t_end)


def test_simulate_script_saves_partial_results_on_failure(tmp_path):
    scene = _absurd_step_scene(tmp_path)
    completed = subprocess.run(
        [sys.executable, str(ROOT / "scripts" / "simulate.py"), "--scene", str(scene), "--out", str(tmp_path)],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert completed.returncode == 1, completed.stderr
    result = load_result(tmp_path / "absurd.npz")
    assert result.status == -1 and result.cause
    assert len(result["t"]) > 1


def test_drift_limit_detects_constraint_drift(tmp_path):
    """Without stabilisation and with a loose tolerance, drift beyond the limit is caught and named."""
    path = tmp_path / "drift.toml"
    path.write_text(
        'extends = "ideal"\nname = "drift"\nduration = 2.0\n[baumgarte]\nalpha = 0.0\nbeta = 0.0\n'
        '[solver]\nrtol = 1e-3\natol = 1e-3\nmax_step = 0.05\n[limits]\nmax_residual = 1e-7\n'
    )
    result = run_scene(build_run(str(path)))
    assert not result.success
    assert result.cause == "constraint drift"
    assert result.t_end < 2.0


def test_bad_scene_on_the_command_line_exits_2(tmp_path):
    completed = subprocess.run(
        [sys.executable, str(ROOT / "scripts" / "simulate.py"), "--scene", "no_such_scene", "--out", str(tmp_path)],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert completed.returncode == 2
    assert "shipped scenes" in completed.stderr


class _Switching:
    """y' = -sign(y): y reaches 0 at t = 1, then the right-hand side switches sign between the stages
    of every step (as constraint rows switching near a rank loss do), and an explicit method creeps on."""

    size, n_candidates = 1, 0
    penetration_bounds = np.zeros(0)
    structure = jacobian = None

    def __init__(self):
        self.rhs_calls = 0

    def derivative(self, t, y, onset):
        self.rhs_calls += 1
        return -np.sign(y)

    def probe(self, t, y, onset, residual=True):
        from robot.dynamics.probe import Probe

        return Probe(np.zeros(0), np.zeros(0), 0.0, np.zeros(0))

    def penetrations(self, t, y):
        return np.zeros(0)

    def normalise(self, y):
        return np.array(y, dtype=float)

    def replica(self):
        return _Switching()


def test_a_creeping_run_fails_as_stalled_instead_of_running_forever():
    """Steps of ~1e-8 s (far above min_step) from t = 1 on: at that pace 3 s need ~2e8 steps > max_steps."""
    from robot.integration.event_loop import EventDrivenIntegrator
    from robot.integration.options import STALL_WINDOW, FailureLimits, SolverOptions

    options = SolverOptions(method="RK45", rtol=1e-10, atol=1e-10, max_step=0.1)
    trajectory = EventDrivenIntegrator(_Switching(), np.array([1.0]), (0.0, 3.0), options).run()
    assert trajectory.status == -1 and trajectory.cause == "integration stalled"
    assert 1.0 <= trajectory.t_end < 1.01 and trajectory.n_steps <= 4 * STALL_WINDOW
    assert "max_steps" in trajectory.message and trajectory.message.startswith("t=1.")
    # with a budget its pace fits in, the same creeping run goes on through two windows to its end
    generous = FailureLimits(max_steps=1e12)
    trajectory = EventDrivenIntegrator(_Switching(), np.array([1.0]), (0.0, 1.0002), options, generous).run()
    assert trajectory.status == 0 and trajectory.t_end == pytest.approx(1.0002) and trajectory.n_steps > 2 * STALL_WINDOW


def test_max_steps_is_a_limit_of_the_scene(tmp_path):
    from robot.errors import SceneError
    from robot.scene import load_scene

    path = tmp_path / "budget.toml"
    path.write_text('extends = "spherical"\nname = "budget"\n[limits]\nmax_steps = 5e5\n')
    assert load_scene(str(path)).limits.max_steps == 5e5
    path.write_text('extends = "spherical"\nname = "budget"\n[limits]\nmax_steps = 0\n')
    with pytest.raises(SceneError, match=r"max_steps=0 is out of range \[1\.0, inf\]"):
        load_scene(str(path))
