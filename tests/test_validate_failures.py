"""``clearance validate`` when things go wrong: bad solver options, failed and interrupted runs, atomic writes.

Commands run in-process through ``robot.cli.main.main``; runs are a few
milliseconds of the ideal scene, or 8 ms of the compound scene with tolerances
so loose that its Lagrange run fails (penetration beyond half the clearance at
t ~ 6 ms), which takes about a second.
"""

from __future__ import annotations

import json
import os
import signal
from pathlib import Path

import numpy as np
import pytest

from robot.cli.common import EXIT_BAD_INPUT, EXIT_INTERRUPTED, EXIT_RUN_FAILED
from robot.cli.main import main
from robot.io import atomic
from robot.validation import comparison as CMP
from robot.validation import figures, study

#: the compound scene's Lagrange run fails with these tolerances, quickly (robot.scene.loader still accepts them)
FAILING = ("--scenes", "compound", "--duration", "compound=0.008", "--engines", "newton_euler", "--rtol", "0.1", "--atol", "0.03")
IDEAL = ("--scenes", "ideal", "--duration", "ideal=0.01", "--engines", "newton_euler")


def run_cli(capsys, *argv) -> tuple[int, str, str]:
    code = main(["validate", *(str(a) for a in argv)])
    captured = capsys.readouterr()
    return code, captured.out, captured.err


@pytest.mark.parametrize(
    "options, named",
    [
        (("--rtol", "5"), ["--rtol=5.0", "[2.220446049250313e-14, 0.1]"]),
        (("--rtol", "1e-30"), ["--rtol=1e-30", "[2.220446049250313e-14, 0.1]"]),
        (("--atol", "1"), ["--atol=1.0", "0.1]"]),
        (("--max-step", "0"), ["--max-step=0.0", "out of range"]),
        (("--first-step", "1", "--max-step", "0.001"), ["--first-step=1.0", "(0, 0.001]", "--max-step"]),
        (("--first-step", "0.01"), ["--first-step=0.01", "(0, 0.001]"]),  # above the default max_step
        (("--max-step", "1e-14"), ["--max-step=1e-14", "limits.min_step = 1e-13 s", "scene ideal"]),  # below the scene's min_step
    ],
    ids=lambda v: " ".join(v) if isinstance(v, tuple) else None,
)
def test_solver_options_out_of_the_scene_range_exit_2_naming_option_value_and_range(capsys, tmp_path, options, named):
    out = tmp_path / "out"
    code, _, err = run_cli(capsys, *IDEAL, "--out", out, *options)
    assert code == EXIT_BAD_INPUT
    for text in named:
        assert text in err
    assert "Traceback" not in err
    assert not out.exists()  # refused before anything ran or was written


def test_a_failed_engine_run_exits_1_and_keeps_every_result(capsys, tmp_path):
    code, stdout, err = run_cli(capsys, *FAILING, "--out", tmp_path)
    assert code == EXIT_RUN_FAILED
    results = json.loads((tmp_path / "validation.json").read_text())
    assert results["success"] is False and results["interrupted"] is None
    lagrange = results["scenes"]["compound"]["engines"]["lagrange"]
    assert lagrange["success"] is False and "penetration" in lagrange["message"]
    assert {(run["scene"], run["engine"]) for run in results["failed_runs"]} >= {("compound", "lagrange")}
    assert "newton_euler" in results["scenes"]["compound"]["engines"]  # the study went on
    assert {"validation_compound.png", "deviation_compound.png"} <= {p.name for p in tmp_path.iterdir()}
    # the console names the failed run, its time and its cause
    assert "validation incomplete" in stdout and "the lagrange run failed" in stdout
    assert lagrange["message"] in stdout and "t=" in lagrange["message"]
    assert "FAILED" in stdout  # the table marks the run too


def _interrupt_lagrange_at(monkeypatch, t_stop: float, signum: int = signal.SIGINT) -> None:
    """Make the study's Lagrange run signal this process once its integration passes ``t_stop``."""
    run_scene = study.run_scene

    def signalling_run(run, **kwargs):
        sent = []

        def progress(t):
            if t >= t_stop and not sent:
                sent.append(t)
                os.kill(os.getpid(), signum)

        return run_scene(run, progress=progress)

    monkeypatch.setattr(study, "run_scene", signalling_run)


@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM])
def test_a_signal_stops_the_study_saves_what_ran_and_exits_1(capsys, tmp_path, monkeypatch, signum):
    _interrupt_lagrange_at(monkeypatch, 0.005, signum)
    code, stdout, err = run_cli(capsys, "--scenes", "ideal", "--duration", "ideal=0.05", "--engines", "newton_euler", "--out", tmp_path)
    assert code == EXIT_RUN_FAILED
    assert "stopping the integration" in err
    results = json.loads((tmp_path / "validation.json").read_text())
    name = signal.Signals(signum).name
    assert results["success"] is False
    assert results["interrupted"] == {"cause": name, "not_run": {"ideal": ["newton_euler"]}}
    lagrange = results["scenes"]["ideal"]["engines"]["lagrange"]
    assert lagrange["success"] is False and "interrupted" in lagrange["message"]
    assert 0.005 <= lagrange["t_last_record_s"] < 0.05
    assert (tmp_path / "validation_ideal.png").is_file()
    assert "the lagrange run failed" in stdout and "interrupted" in stdout and f"{name}: not run: ideal: newton_euler" in stdout
    assert signal.getsignal(signal.SIGTERM) is signal.SIG_DFL  # handlers restored


def test_a_signal_before_any_run_exits_130_and_writes_nothing(capsys, tmp_path, monkeypatch):
    with_solver = study.with_solver

    def signalling_setup(*args, **kwargs):  # the study's own setup of its first run (the scene checks are done)
        run = with_solver(*args, **kwargs)
        os.kill(os.getpid(), signal.SIGINT)
        return run

    monkeypatch.setattr(study, "with_solver", signalling_setup)
    code, _, err = run_cli(capsys, *IDEAL, "--out", tmp_path)
    assert code == EXIT_INTERRUPTED
    assert "nothing to save" in err
    assert list(tmp_path.iterdir()) == []


def test_a_signal_while_the_scenes_are_checked_exits_130_and_creates_nothing(capsys, tmp_path, monkeypatch):
    build_run = study.build_run

    def signalling_build(*args, **kwargs):  # first called by the checks, before any run
        built = build_run(*args, **kwargs)
        os.kill(os.getpid(), signal.SIGINT)
        return built

    monkeypatch.setattr(study, "build_run", signalling_build)
    out = tmp_path / "out"
    code, _, err = run_cli(capsys, *IDEAL, "--out", out)
    assert code == EXIT_INTERRUPTED
    assert "interrupted" in err and "Traceback" not in err
    assert not out.exists()


def test_json_and_figures_are_written_atomically(capsys, tmp_path, monkeypatch):
    replaced = []
    replace = os.replace

    def spy(source, target):
        replaced.append(Path(target).name)
        return replace(source, target)

    monkeypatch.setattr(atomic.os, "replace", spy)
    code, _, _ = run_cli(capsys, *IDEAL, "--out", tmp_path)
    assert code == 0
    assert {"validation.json", "validation_ideal.png", "deviation_ideal.png"} <= set(replaced)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["deviation_ideal.png", "validation.json", "validation_ideal.png"]


def test_a_figure_that_fails_to_save_leaves_the_previous_file_whole(tmp_path, monkeypatch):
    t = np.linspace(0.0, 0.01, 11)
    series = {"lagrange": CMP.EngineSeries("lagrange", t, np.zeros((11, 5)), np.zeros((11, 3)), ee_ideal=np.zeros((11, 3)))}
    metrics = {"duration_s": 0.01, "sites": [], "engines": {}}
    (tmp_path / "validation_x.png").write_bytes(b"previous figure")

    def failing_savefig(fig, target, **kwargs):
        Path(target).write_bytes(b"half an image")
        raise OSError("disk full")

    monkeypatch.setattr(figures.plt.Figure, "savefig", failing_savefig)
    with pytest.raises(OSError, match="disk full"):
        figures.scene_figures("x", series, metrics, tmp_path)
    assert (tmp_path / "validation_x.png").read_bytes() == b"previous figure"
    assert [p.name for p in tmp_path.iterdir()] == ["validation_x.png"]  # no temporary file left
