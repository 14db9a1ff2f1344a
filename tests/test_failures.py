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
