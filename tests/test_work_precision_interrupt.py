"""``clearance work-precision`` stopped by Ctrl-C keeps what it finished (exit 1), and its figures are written atomically.

A Ctrl-C in the middle of a study used to lose the finished runs (exit 130,
only the benchmark in ``work_precision.json``) or, in a reference run, end in a
traceback (exit 3). Now the run in progress stops, the finished runs are saved,
marked ``incomplete`` with the step, the cause and the time the stopped run
reached, and the message says where. The signal is real (this process sends
itself SIGINT from inside a run's integration, as the terminal would).
"""

from __future__ import annotations

import json
import os
import signal
from pathlib import Path

import matplotlib.figure
import pytest

from robot.analysis.studies import common, stability
from robot.analysis.studies import work_precision as wp
from robot.cli import work_precision as command
from robot.cli.common import EXIT_OK, EXIT_RUN_FAILED
from robot.cli.main import build_parser

SWEEP = ["--scene", "ideal", "--methods", "RK45,DOP853", "--tolerances", "1e-6,1e-7", "--skip-stability", "--realtime-t-end", "0", "--t-end", "0.1"]
#: the order of the runs of SWEEP: the reference and its check, then the sweep's
REFERENCE_RUN, CHECK_RUN, FIRST_SWEEP_RUN, SECOND_SWEEP_RUN = 1, 2, 3, 4


def execute(out: Path, *options: str) -> int:
    """The command in this process (its signal handling included); a KeyboardInterrupt escaping it fails the test."""
    args = build_parser("work-precision").parse_args(["work-precision", *SWEEP, *options, "--out", str(out)])
    try:
        return command.execute(args)
    except KeyboardInterrupt:
        pytest.fail("a KeyboardInterrupt escaped the command: the finished runs were not saved")


def interrupt_run(monkeypatch, number: int, t_stop: float) -> None:
    """Send this process SIGINT once the ``number``-th run of the study passes ``t_stop`` (inside its integration)."""
    integrate, calls = common.integrate, []

    def integrate_and_interrupt(*args, **kwargs):
        calls.append(1)
        if len(calls) != number:
            return integrate(*args, **kwargs)

        def progress(t):
            if t >= t_stop and not calls[-1] == "sent":
                calls[-1] = "sent"
                os.kill(os.getpid(), signal.SIGINT)

        return integrate(*args, progress=progress, **kwargs)

    monkeypatch.setattr(common, "integrate", integrate_and_interrupt)


def report(out: Path) -> dict:
    return json.loads((out / "work_precision.json").read_text())


def test_ctrl_c_in_a_sweep_run_saves_the_finished_runs_and_exits_1(tmp_path, monkeypatch, capsys):
    handler_before = signal.getsignal(signal.SIGINT)  # default_int_handler, or SIG_IGN in a background job
    interrupt_run(monkeypatch, SECOND_SWEEP_RUN, t_stop=0.02)
    assert execute(tmp_path) == EXIT_RUN_FAILED
    err = capsys.readouterr().err
    saved = report(tmp_path)
    assert [row["label"] for row in saved["runs"]] == ["RK45 rtol=1e-06"]  # the finished run, not the stopped one
    assert saved["rhs_benchmark"] and saved["reference"]["comparable_window_s"] > 0
    stop = saved["incomplete"]
    assert stop["step"] == "sweep" and stop["cause"] == "interrupted by the user (SIGINT)"
    assert stop["stopped_run"]["label"] == "RK45 rtol=1e-07" and 0.02 <= stop["stopped_run"]["t_reached"] < 0.1
    assert "interrupted by the user" in stop["message"] and stop["elapsed_s"] > 0 and stop["at"]
    assert f"saved in {tmp_path / 'work_precision.json'} (marked incomplete)" in err
    assert "Traceback" not in err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["work_precision.json", "work_precision.png"]  # no temporary file
    assert signal.getsignal(signal.SIGINT) is handler_before  # handlers restored

    monkeypatch.undo()  # the same study again, to its end: complete, no longer marked incomplete
    assert execute(tmp_path) == EXIT_OK
    saved = report(tmp_path)
    assert "incomplete" not in saved and len(saved["runs"]) == 4


def test_ctrl_c_in_a_reference_run_saves_the_benchmark_and_exits_1(tmp_path, monkeypatch, capsys):
    """Used to be exit 3 and a traceback: RuntimeError: reference runs failed: ...; interrupted by the user."""
    interrupt_run(monkeypatch, CHECK_RUN, t_stop=0.01)
    assert execute(tmp_path) == EXIT_RUN_FAILED
    err = capsys.readouterr().err
    saved = report(tmp_path)
    assert saved["rhs_benchmark"] and "runs" not in saved
    assert saved["reference"]["reference"]["status"] == 0  # the reference run that finished is kept
    stop = saved["incomplete"]
    assert stop["step"] == "sweep (its reference solutions)" and stop["stopped_run"]["label"] == "check DOP853 rtol 1e-10"
    assert "saved in" in err and "Traceback" not in err


def test_a_keyboard_interrupt_escaping_a_run_stops_the_sweep_with_the_rows_done(tmp_path, monkeypatch, capsys):
    """A KeyboardInterrupt raised outside the step loop (e.g. while summarising a run) is a stop too."""
    simulate, calls = wp.simulate, []

    def simulate_then_interrupt(*args, **kwargs):
        calls.append(kwargs.get("label"))
        if len(calls) == SECOND_SWEEP_RUN:
            raise KeyboardInterrupt
        return simulate(*args, **kwargs)

    monkeypatch.setattr(wp, "simulate", simulate_then_interrupt)
    assert execute(tmp_path) == EXIT_RUN_FAILED
    saved = report(tmp_path)
    assert [row["label"] for row in saved["runs"]] == ["RK45 rtol=1e-06"]
    assert saved["incomplete"]["message"] == "RK45 rtol=1e-07: interrupted by the user"
    assert saved["incomplete"]["stopped_run"] is None
    capsys.readouterr()


def test_a_failed_reference_run_stops_the_study_with_exit_1_not_a_traceback(tmp_path, monkeypatch, capsys):
    simulate, calls = wp.simulate, []

    def failing_check(*args, **kwargs):
        outcome = simulate(*args, **kwargs)
        calls.append(outcome.label)
        if len(calls) == CHECK_RUN:
            outcome.status, outcome.cause, outcome.message = -1, "non-finite state", "t=0.05 s: non-finite state (test)"
        return outcome

    monkeypatch.setattr(wp, "simulate", failing_check)
    assert execute(tmp_path) == EXIT_RUN_FAILED
    saved = report(tmp_path)
    stop = saved["incomplete"]
    assert stop["cause"] == "reference failed" and "t=0.05 s: non-finite state (test)" in stop["message"]
    assert set(saved["reference"]) == {"reference", "check"}
    assert "Traceback" not in capsys.readouterr().err


def test_a_stability_map_stopped_between_runs_keeps_its_filled_cells():
    runs = []
    with pytest.raises(wp.StudyStopped) as stopped:
        stability.baumgarte_map(
            alphas=(0.0, 5.0), betas=(0.0,), cases=(("RK4", None, 2e-3),), t_end=0.004, progress=runs.append, stop=lambda: len(runs) >= 1
        )
    grid = stopped.value.finished["cases"][0]["grid"]
    assert [(cell["alpha"], cell["result"]) for cell in grid] == [(0.0, stability.OK)]
    assert str(stopped.value) == "stopped before baumgarte RK4 rtol=None h=0.002 alpha=5 beta=0"


# --- figures written atomically ---------------------------------------------------------------

ROWS = [{"options": {"method": "RK45", "rtol": 1e-6, "first_step": None}, "status": 0, "cpu_time": 0.1,
         "errors": {"ee": 1e-9, "peak_force": 1e-3, "driving": 1e-4, "energy": 1e-8}}]  # fmt: skip
FIGURES = {
    "work_precision": lambda path: wp.plot(ROWS, {"comparable_window_s": 0.1, "window_tolerance_m": 1e-8}, 0.1, path, "test"),
    "stiffness": lambda path: stability.plot_stiffness(
        {"methods": {"RK4": [{"scale": 1.0, "h": 1e-5, "result": "ok"}]}, "boundary": {"RK4": {"1.0": 1e-5}}, "scales": [1.0],
         "steps": [1e-5], "adaptive": {"1.0": {"method": "RK45", "mean_step": 1e-5}}, "t_end": 0.01, "scene": "test"}, path),  # fmt: skip
    "baumgarte": lambda path: stability.plot_baumgarte(
        {"cases": [{"method": "RK4", "rtol": None, "h": 2e-3, "grid": [{"alpha": 0.0, "beta": 0.0, "result": "ok", "max_residual": 1e-12, "steps": 10}]}],
         "alphas": [0.0], "betas": [0.0], "scene": "test", "t_end": 0.1, "max_residual_limit": 1e-4}, path),  # fmt: skip
    "hidden": lambda path: stability.plot_hidden(
        {"runs": [{"method": "RK45", "guard": True, "rtol": 1e-3, "onsets": 2, "overshoot_over_clearance": 0.1, "result": "ok", "peak_force_error": 0.01}],
         "reference_onsets": 2, "scene": "test", "t_end": 0.1, "max_step": 1e-2}, path),  # fmt: skip
}


@pytest.mark.parametrize("figure", sorted(FIGURES))
def test_a_figure_write_that_fails_leaves_the_previous_png_intact(figure, tmp_path, monkeypatch):
    path = tmp_path / f"{figure}.png"
    FIGURES[figure](path)
    previous = path.read_bytes()
    assert previous.startswith(b"\x89PNG")

    def half_written(self, target, *args, **kwargs):
        Path(target).write_bytes(b"\x89PNG half")
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(matplotlib.figure.Figure, "savefig", half_written)
    with pytest.raises(OSError, match="No space left"):
        FIGURES[figure](path)
    assert path.read_bytes() == previous
    assert [p.name for p in tmp_path.iterdir()] == [path.name]  # the temporary file is gone
