"""Solver options are checked before anything runs: exit 2, one line naming the parameter, its value and the valid range.

* a scene's ``[solver] method`` that is not a string (a number, a bool, a list, a table);
* ``rtol`` in :data:`robot.scene.loader.RTOL_RANGE`, whose lower bound the integrators
  honour (scipy's replace an rtol below 100 eps, with a warning), the same range for
  ``clearance work-precision --tolerances`` and ``--candidates``;
* a fixed-step method refused as a ``--candidates`` tolerance candidate;
* ``max_step`` (and a fixed-step method's step, a first step) not below ``limits.min_step``
  (CVODE: its own smallest step, 1e-12 s), in scenes and in ``work-precision --max-step/--steps``;
* the run summary says ``rejected n/a`` for a failed run (its rejected steps are not counted).
"""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import RK45

from robot.cli import work_precision as command
from robot.cli.common import EXIT_BAD_INPUT, EXIT_RUN_FAILED
from robot.cli.main import main
from robot.cli.run import counts_line
from robot.errors import SceneError
from robot.scene.loader import RTOL_RANGE, load_scene

RANGE = f"[{RTOL_RANGE[0]:g}, {RTOL_RANGE[1]:g}]"


def run_cli(capsys, *argv) -> tuple[int, str, str]:
    code = main([str(a) for a in argv])
    captured = capsys.readouterr()
    return code, captured.out, captured.err


def one_line_error(err: str) -> str:
    """The one ``error:`` line (the kernel library's build may print its own lines first)."""
    lines = [line for line in err.splitlines() if line.startswith("error:")]
    assert len(lines) == 1 and "Traceback" not in err, err
    return lines[0]


def scene(tmp_path: Path, text: str, parent: str = "ideal") -> Path:
    path = tmp_path / "scene.toml"
    path.write_text(f'extends = "{parent}"\nname = "checked"\n{text}\n')
    return path


# --- the scene's [solver] table ---------------------------------------------------------------


@pytest.mark.parametrize("value, shown", [("4", "4"), ("4.5", "4.5"), ("true", "True"), ('["RK45"]', "['RK45']"), ("{ name = 1 }", "{'name': 1}")])
def test_a_method_that_is_not_a_string_exits_2_naming_it_and_the_methods(capsys, tmp_path, value, shown):
    path = scene(tmp_path, f"[solver]\nmethod = {value}")
    code, _, err = run_cli(capsys, "run", "--scene", path, "--check")
    assert code == EXIT_BAD_INPUT, err
    line = one_line_error(err)
    assert f"method={shown}" in line and "[solver]" in line and "RK45" in line and "CVODE_BDF" in line


def test_the_rtol_range_starts_where_the_integrators_honour_rtol(tmp_path):
    """scipy replaces an rtol below 100 eps (with a UserWarning); the scenes' lower bound is not below it, and valid."""
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        RK45(lambda t, y: -y, 0.0, np.ones(1), 1.0, rtol=RTOL_RANGE[0], atol=1e-16)
    with pytest.warns(UserWarning, match="rtol"):  # the bound is needed: below it scipy runs another rtol
        RK45(lambda t, y: -y, 0.0, np.ones(1), 1.0, rtol=1e-14, atol=1e-16)
    assert load_scene(scene(tmp_path, f"[solver]\nrtol = {RTOL_RANGE[0]!r}")).solver.rtol == RTOL_RANGE[0]


@pytest.mark.parametrize("rtol", ["1e-14", "2e-14", "1e-20"])
def test_an_rtol_the_integrators_would_replace_is_refused_when_the_scene_is_read(tmp_path, rtol):
    with pytest.raises(SceneError, match=rf"rtol={rtol} is out of range \[2.220446049250313e-14, 0.1\].*100 eps"):
        load_scene(scene(tmp_path, f"[solver]\nrtol = {rtol}"))
    assert load_scene(scene(tmp_path, "[solver]\nrtol = 5e-14")).solver.rtol == 5e-14  # honoured by scipy: valid


@pytest.mark.parametrize(
    "valid, refused, message",
    [
        ('method = "RK45"\nmax_step = 1e-13', 'method = "RK45"\nmax_step = 1e-14', r"max_step=1e-14 must be >= limits.min_step = 1e-13 s"),
        ('method = "CVODE_BDF"\nmax_step = 1e-12', 'method = "CVODE_BDF"\nmax_step = 1e-14', r"max_step=1e-14 must be >= 1e-12 s, the smallest step CVODE_BDF takes"),
        ('method = "CVODE_Adams"\nmax_step = 1e-12', 'method = "CVODE_Adams"\nmax_step = 5e-13', r"max_step=5e-13 must be >= 1e-12 s, the smallest step CVODE_Adams"),
        (
            'method = "LSODA"\nmax_step = 1e-9\n[limits]\nmin_step = 0.0',
            'method = "LSODA"\nmax_step = 1e-7\n[limits]\nmin_step = 1e-6',
            r"max_step=1e-07 must be >= limits.min_step = 1e-06 s",
        ),
        ('method = "RK45"\nfirst_step = 1e-13', 'method = "RK45"\nfirst_step = 1e-15', r"first_step=1e-15 must be >= limits.min_step = 1e-13 s"),
    ],
)
def test_a_step_below_the_smallest_step_is_refused_when_the_scene_is_read(tmp_path, valid, refused, message):
    load_scene(scene(tmp_path, f"[solver]\n{valid}"))  # at the smallest step: valid
    with pytest.raises(SceneError, match=message):
        load_scene(scene(tmp_path, f"[solver]\n{refused}"))


@pytest.mark.parametrize("solver", ['method = "RK4"\nfirst_step = 1e-7', 'method = "GenAlpha"\nfirst_step = 1e-7\nmax_step = 1e-9'])
def test_min_step_is_no_limit_of_the_fixed_step_methods(tmp_path, solver):
    """The run checks min_step for variable-step methods only (a fixed step cannot collapse): no refusal either."""
    loaded = load_scene(scene(tmp_path, f"[solver]\n{solver}\n[limits]\nmin_step = 1e-6"))
    assert loaded.solver.first_step == 1e-7


def test_a_max_step_below_min_step_exits_2_before_any_run(capsys, tmp_path):
    path = scene(tmp_path, '[solver]\nmethod = "CVODE_BDF"\nrtol = 1e-6\natol = 1e-8\nmax_step = 1e-14', parent="revolute")
    code, _, err = run_cli(capsys, "run", "--scene", path, "--out", tmp_path / "out")
    assert code == EXIT_BAD_INPUT, err
    line = one_line_error(err)
    assert "[solver]: max_step=1e-14" in line and "limits.min_step = 1e-13 s" in line
    assert not list((tmp_path / "out").glob("*.npz"))


# --- work-precision ---------------------------------------------------------------------------


@pytest.fixture
def no_study(monkeypatch):
    """The study must not start: a check that lets bad options through fails here at once."""

    def refuse(*args, **kwargs):
        raise AssertionError("the study started with options that should have been refused")

    monkeypatch.setattr(command, "_Phases", refuse)


def work_precision(capsys, tmp_path, *options) -> tuple[int, str, Path]:
    out = tmp_path / "wp"
    code, _, err = run_cli(
        capsys, "work-precision", "--scene", "ideal", "--skip-stability", "--realtime-t-end", "0", "--t-end", "0.01", "--out", out, *options
    )
    return code, err, out


@pytest.mark.parametrize("tolerances, bad", [("1e-20,0.5", "1e-20"), ("1e-6,0.5", "0.5"), ("1e-14", "1e-14")])
def test_work_precision_tolerances_outside_the_scene_rtol_range_exit_2(capsys, tmp_path, no_study, tolerances, bad):
    code, err, out = work_precision(capsys, tmp_path, "--methods", "RK45", "--tolerances", tolerances)
    assert code == EXIT_BAD_INPUT, err
    line = one_line_error(err)
    assert "--tolerances" in line and f"rtol {bad} " in line and RANGE in line
    assert not out.exists()


@pytest.mark.parametrize("candidate, bad", [("RK45:0.5", "0.5"), ("LSODA:1e-20", "1e-20"), ("CVODE_BDF:1e-14:finite-difference", "1e-14")])
def test_work_precision_candidate_rtol_outside_the_scene_rtol_range_exits_2(capsys, tmp_path, no_study, candidate, bad):
    code, err, out = work_precision(capsys, tmp_path, "--skip-sweep", "--realtime-t-end", "1", "--candidates", candidate)
    assert code == EXIT_BAD_INPUT, err
    line = one_line_error(err)
    assert f"--candidates {candidate!r}" in line and f"rtol {bad} " in line and RANGE in line
    assert not out.exists()


@pytest.mark.parametrize("method", ["RK4", "GenAlpha", "Newmark"])
def test_work_precision_refuses_a_fixed_step_method_as_a_tolerance_candidate(capsys, tmp_path, no_study, method):
    code, err, out = work_precision(capsys, tmp_path, "--skip-sweep", "--realtime-t-end", "1", "--candidates", f"RK45:1e-7,{method}:1e-6")
    assert code == EXIT_BAD_INPUT, err
    line = one_line_error(err)
    assert f"'{method}:1e-6'" in line and "fixed-step method" in line and "--steps" in line and "RK45" in line
    assert not out.exists()


@pytest.mark.parametrize("candidate", ["RK45", "RK45:1e-6:structured:extra"])
def test_work_precision_candidate_of_the_wrong_shape_exits_2(capsys, tmp_path, no_study, candidate):
    code, err, _ = work_precision(capsys, tmp_path, "--skip-sweep", "--realtime-t-end", "1", "--candidates", candidate)
    assert code == EXIT_BAD_INPUT, err
    assert "METHOD:RTOL[:JACOBIAN]" in one_line_error(err)


@pytest.mark.parametrize(
    "options, named",
    [
        (("--methods", "RK45", "--max-step", "1e-14"), ["--max-step=1e-14", "[1e-13, inf)", "limits.min_step"]),
        (("--methods", "RK45,CVODE_BDF", "--max-step", "5e-13"), ["--max-step=5e-13", "[1e-12, inf)", "CVODE_BDF"]),
    ],
)
def test_work_precision_steps_below_the_scenes_min_step_exit_2(capsys, tmp_path, no_study, options, named):
    code, err, out = work_precision(capsys, tmp_path, *options)
    assert code == EXIT_BAD_INPUT, err
    line = one_line_error(err)
    assert all(word in line for word in named), line
    assert not out.exists()


def test_work_precision_uses_the_scenes_rtol_range():
    """One definition of the range: the command's checks read the loader's."""
    with pytest.raises(command.UsageError, match=r"\[2.22045e-14, 0.1\]"):
        command._candidates("RK45:1e-14")
    assert command._candidates(f"RK45:{RTOL_RANGE[0]!r},LSODA:{RTOL_RANGE[1]!r}")[0].rtol == RTOL_RANGE[0]


# --- the run summary ----------------------------------------------------------------------------


def test_the_summary_of_a_failed_run_does_not_claim_zero_rejected_steps(capsys, tmp_path):
    path = scene(tmp_path, 'duration = 0.01\n[solver]\nmethod = "RK45"\n[limits]\nmax_residual = 1e-30')
    code, out, err = run_cli(capsys, "run", "--scene", path, "--out", tmp_path / "out")
    assert code == EXIT_RUN_FAILED, err
    assert "constraint residual" in out and "rejected n/a" in out and "rejected 0" not in out


def test_counts_line_rejected_is_counted_only_for_a_finished_run():
    counts = {"n_steps": 10, "n_rejected": 0, "n_rhs": 60, "n_events": 0, "cpu_time": 0.1}
    assert "rejected 0," in counts_line(counts)
    assert "rejected n/a," in counts_line(counts, finished=False)
    assert "steps 10," in counts_line(counts, finished=False)


def test_work_precision_refuses_a_scene_the_stiffness_map_cannot_scale_before_any_run(capsys, tmp_path, no_study, monkeypatch):
    """The map's refusal came after the sweep (up to ~16 min); now before the study starts, with exit 2."""
    from robot.analysis.studies import stability

    def cannot_scale(scene):
        raise SceneError("stiffness map: cannot scale the contact stiffness of clearance joint 'K'", key="clearance.K", value=None)

    monkeypatch.setattr(stability, "scaled_stiffness", cannot_scale)
    out = tmp_path / "wp"
    code, _, err = run_cli(capsys, "work-precision", "--scene", "slider_crank_revolute", "--realtime-t-end", "0", "--t-end", "0.01", "--out", out)
    assert code == EXIT_BAD_INPUT, err
    assert "cannot scale the contact stiffness of clearance joint 'K'" in one_line_error(err)
    assert not out.exists()
