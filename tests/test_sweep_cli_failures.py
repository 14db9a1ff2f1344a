"""``clearance sweep``, ``clearance bench-sweep`` and the claims study on bad input and on Ctrl-C.

Bad options exit 2 with a message naming the option and its value, before any
run; an interrupted sweep keeps its finished runs and says how to resume (exit
1), or exits 130 when nothing was finished; an interrupted claims study does not
save the run it stopped as if it were finished.
"""

from __future__ import annotations

import os
from pathlib import Path
import signal
import subprocess
import sys
import time
from types import SimpleNamespace

import numpy as np
import pytest

pytest.importorskip("distributed")
import zarr  # noqa: E402

from robot.cli.common import EXIT_BAD_INPUT, EXIT_INTERRUPTED, EXIT_RUN_FAILED  # noqa: E402
from robot.cli.main import main  # noqa: E402
from tests.conftest import free_port  # noqa: E402
from robot.sweep import claims_study, engine  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]

SMALL = """
[sweep]
scene = "spherical"
t_end = 0.01

[[axis]]
key = "clearance.S1.clearance"
values = [5e-5, 1e-4]
"""

#: the first run is short, the second one long enough (~10 s) to be in flight when the signal comes
SHORT_THEN_LONG = """
[sweep]
scene = "spherical"
t_end = 0.01

[[axis]]
key = "duration"
values = [0.01, 30.0]
"""


def _file(folder: Path, text: str, name: str = "sweep.toml") -> str:
    path = folder / name
    path.write_text(text)
    return str(path)


def _cli(capsys, *argv) -> tuple[int, str]:
    code = main([str(a) for a in argv])
    return code, capsys.readouterr().err


# --- bad options: exit 2 before any run ----------------------------------------------------


def test_sweep_out_that_is_a_file_is_refused(capsys, tmp_path):
    blocker = tmp_path / "file"
    blocker.write_text("x")
    code, err = _cli(capsys, "sweep", _file(tmp_path, SMALL), "--out", blocker, "--no-progress", "--no-figures")
    assert code == EXIT_BAD_INPUT and "Traceback" not in err
    assert f"--out={str(blocker)!r}" in err and "is a file" in err


def test_sweep_scheduler_that_is_no_address_is_refused(capsys, tmp_path):
    code, err = _cli(capsys, "sweep", _file(tmp_path, SMALL), "--scheduler", "garbage", "--out", tmp_path / "out", "--no-figures")
    assert code == EXIT_BAD_INPUT and "Traceback" not in err
    assert "--scheduler='garbage'" in err and "not a dask scheduler address" in err
    assert not (tmp_path / "out" / "sweep.zarr").exists()


def test_sweep_scheduler_that_cannot_be_reached_is_refused(capsys, tmp_path, monkeypatch):
    import distributed

    monkeypatch.setattr(engine, "CONNECT_TIMEOUT_S", 1.0)
    timeouts = []

    def client(address, timeout=None, **kwargs):  # the real client, its timeout recorded
        timeouts.append(timeout)
        return real_client(address, timeout=timeout, **kwargs)

    real_client = distributed.Client
    monkeypatch.setattr(distributed, "Client", client)
    address = f"tcp://127.0.0.1:{free_port()}"  # nothing listens there
    code, err = _cli(capsys, "sweep", _file(tmp_path, SMALL), "--scheduler", address, "--out", tmp_path / "out", "--no-figures")
    assert code == EXIT_BAD_INPUT and "Traceback" not in err
    assert f"--scheduler={address!r}" in err and "could be reached at that address" in err
    assert timeouts == [1.0]  # the connection gives up after CONNECT_TIMEOUT_S


@pytest.mark.parametrize("target", ["folder", "/proc/nope/x.json"])
def test_bench_sweep_out_is_checked_before_the_benchmark(capsys, tmp_path, monkeypatch, target):
    import distributed

    def no_cluster(*args, **kwargs):
        raise AssertionError("a cluster was started before --out was checked")

    monkeypatch.setattr(distributed, "LocalCluster", no_cluster)
    out = tmp_path if target == "folder" else target
    code, err = _cli(capsys, "bench-sweep", "--runs", "1", "--t-end", "0.001", "--out", out)
    assert code == EXIT_BAD_INPUT and "Traceback" not in err and "--out" in err and str(Path(out).parent if target != "folder" else out) in err


def test_claims_study_of_a_missing_sweep_file_is_one_line(capsys, tmp_path):
    missing = tmp_path / "nonexist.toml"
    assert claims_study.main([str(missing), "--out", str(tmp_path / "cs")]) == 2
    err = capsys.readouterr().err
    assert err.strip().splitlines() == [f"error: sweep file {str(missing)!r} does not exist"]


def test_claims_study_out_that_is_a_file_is_refused_before_any_run(capsys, tmp_path):
    blocker = tmp_path / "file"
    blocker.write_text("x")
    sweep = _file(tmp_path, SMALL.replace('"spherical"', '"compound"').replace("S1.clearance", "R1.radial_clearance"))
    assert claims_study.main([sweep, "--out", str(blocker)]) == 2
    err = capsys.readouterr().err
    assert f"--out={str(blocker)!r} cannot be written" in err and "Traceback" not in err


# --- interrupts ----------------------------------------------------------------------------


def _done(store: Path) -> int:
    try:
        return int(np.count_nonzero(zarr.open_group(str(store), mode="r")["done"][...]))
    except Exception:  # not created yet
        return 0


def test_a_stop_after_a_finished_run_keeps_it_and_drops_the_run_in_flight(tmp_path, kernel_library_dir, monkeypatch):
    """What Ctrl-C asks of the engine (robot.cli.sweep passes clean_stops' request as ``stop``), without a
    signal's timing: stop as soon as the store holds the short run, while the 30 s run is in flight."""
    from robot.sweep.spec import load_sweep

    monkeypatch.setenv("CLEARANCE_KERNEL_DIR", str(kernel_library_dir.parent))
    out = tmp_path / "out"
    store = out / "sweep.zarr"
    outcome = engine.run_sweep(load_sweep(_file(tmp_path, SHORT_THEN_LONG)), out, workers=1, progress=False, stop=lambda: _done(store) >= 1)
    assert outcome.interrupted and outcome.finished == 1 and _done(store) == 1  # the long run: dropped, not failed
    from robot.cli.sweep import interrupted_exit

    assert interrupted_exit(outcome, ["SIGINT"]) == EXIT_RUN_FAILED


def test_ctrl_c_to_the_process_group_prints_the_sweep_message_and_no_worker_traceback(tmp_path, kernel_library_dir):
    """A terminal's Ctrl-C reaches the local workers too (one process group): they leave it to the sweep process.

    Before robot/sweep/worker_setup.py, each worker printed dask's KeyboardInterrupt traceback.
    """
    env = {**os.environ, "PYTHONPATH": str(ROOT), "CLEARANCE_KERNEL_DIR": str(kernel_library_dir.parent)}
    out = tmp_path / "out"
    command = [sys.executable, str(ROOT / "scripts" / "sweep.py"), _file(tmp_path, SHORT_THEN_LONG), "--out", str(out), "--workers", "2", "--no-figures"]
    driver = subprocess.Popen(command, env=env, start_new_session=True, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    try:
        deadline = time.monotonic() + 120
        while _done(out / "sweep.zarr") < 1 and driver.poll() is None and time.monotonic() < deadline:
            time.sleep(0.02)
        os.killpg(driver.pid, signal.SIGINT)  # what the terminal does
        _, err = driver.communicate(timeout=60)
    finally:
        if driver.poll() is None:
            os.killpg(driver.pid, signal.SIGKILL)
            driver.wait()
    assert driver.returncode == EXIT_RUN_FAILED, err
    assert "Traceback" not in err and "KeyboardInterrupt" not in err, err
    assert "SIGINT: the sweep stopped with 1 of 2 runs finished" in err and "same command again to resume" in err, err


def _outcome(finished: int, failed: int = 0):
    return SimpleNamespace(finished=finished, total=4, failed=failed, store=Path("/tmp/sw/sweep.zarr"))


def test_an_interrupted_sweep_without_finished_runs_exits_130(capsys):
    from robot.cli.sweep import interrupted_exit

    assert interrupted_exit(_outcome(0), ["SIGINT"]) == EXIT_INTERRUPTED
    assert "before any run finished" in capsys.readouterr().err


def test_an_interrupted_sweep_with_finished_runs_exits_1_naming_the_store(capsys):
    from robot.cli.sweep import interrupted_exit

    assert interrupted_exit(_outcome(2, failed=1), ["SIGTERM"]) == EXIT_RUN_FAILED
    err = capsys.readouterr().err
    assert err.startswith("SIGTERM: ") and "2 of 4 runs finished, 1 of them failed" in err
    assert "/tmp/sw/sweep.zarr" in err and "same command again to resume" in err


def test_claims_study_does_not_save_an_interrupted_run(tmp_path, monkeypatch):
    import robot.run

    monkeypatch.setattr(robot.run, "simulate", lambda *args, **kwargs: SimpleNamespace(cause="interrupted"))
    with pytest.raises(KeyboardInterrupt):
        claims_study._simulate(("compound", {}, 0.01, str(tmp_path / "runs" / "run.npz")))
    assert not (tmp_path / "runs").exists()


def test_sigterm_stops_a_claims_study_like_ctrl_c(capsys, tmp_path, monkeypatch):
    """SIGTERM during the runs: the study stops cleanly (exit 130, nothing saved yet) and the handler is restored."""
    import os
    import signal
    import time

    sweep = str(ROOT / "robot" / "sweep" / "examples" / "claims_initial_state.toml")

    def terminated(*args, **kwargs):
        os.kill(os.getpid(), signal.SIGTERM)
        time.sleep(5)  # the handler interrupts the sleep
        raise AssertionError("SIGTERM did not stop the study")

    monkeypatch.setattr(claims_study, "run_study", terminated)
    before = signal.getsignal(signal.SIGTERM)
    assert claims_study.main([sweep, "--out", str(tmp_path / "cs")]) == 130
    assert "interrupted before any run was saved" in capsys.readouterr().err
    assert signal.getsignal(signal.SIGTERM) is before


@pytest.mark.parametrize("saved, code", [(0, EXIT_INTERRUPTED), (2, EXIT_RUN_FAILED)])
def test_an_interrupted_claims_study_says_what_is_saved(capsys, tmp_path, saved, code):
    for i in range(saved):
        (tmp_path / f"run{i}.npz").write_bytes(b"")
    (tmp_path / ".run9.npz.k2j4x.npz").write_bytes(b"")  # the temporary file of a write killed by SIGKILL
    assert claims_study.interrupted_exit(tmp_path) == code
    err = capsys.readouterr().err
    assert (f"({saved}) are saved in {tmp_path}" in err) == bool(saved)
