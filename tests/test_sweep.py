"""Sweeps on a real dask cluster: a scheduler and two workers started here on 127.0.0.1.

Checks that the stored dataset equals the same runs made one by one through the
public API (value by value, bit for bit), that a sweep whose driver is killed
(SIGKILL) halfway and resumed gives arrays identical to an uninterrupted sweep,
and that a failing run is recorded with its cause while the sweep finishes.
Horizons are short (0.02 s of the spherical scene).
"""

from __future__ import annotations

import dataclasses
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("distributed")
import xarray as xr  # noqa: E402
import zarr  # noqa: E402

from robot import load_scene  # noqa: E402
from robot.analysis import ANALYSES  # noqa: E402
from robot.run import build_run, run_scene  # noqa: E402
from robot.sweep import load_sweep, open_sweep, run_sweep  # noqa: E402
from robot.sweep.cli import main  # noqa: E402
from tests.conftest import free_port  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
DASK = Path(sys.executable).with_name("dask")
T_END = 0.02
KEEP_SAMPLES = 21
#: measured seconds: the only values allowed to differ between two executions
TIMINGS = ("wall_time", "cpu_time", "simulate_wall_time", "integration_wall_time", "integration_cpu_time")

GRID = f"""
[sweep]
scene = "spherical"
t_end = {T_END}

[[axis]]
key = "clearance.S1.clearance"
name = "clearance"
values = [5e-5, 1e-4, 2e-4]

[[axis]]
key = "trajectory.period"
name = "period"
linear = {{ start = 0.9, stop = 1.1, num = 2 }}

[keep]
arrays = ["ee_position", "S1_normal_force:sum"]
samples = {KEEP_SAMPLES}
"""


@pytest.fixture(scope="module")
def scheduler():
    """``dask scheduler`` and two ``dask worker`` processes on localhost (stopped at the end)."""
    from distributed import Client

    port = free_port()
    address = f"tcp://127.0.0.1:{port}"
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    common = ["--no-dashboard"]
    quiet = dict(env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True)
    processes = [subprocess.Popen([str(DASK), "scheduler", "--host", "127.0.0.1", "--port", str(port), *common], **quiet)]
    try:
        for _ in range(2):
            worker = [str(DASK), "worker", address, "--host", "127.0.0.1", "--nthreads", "1", "--nworkers", "1", "--death-timeout", "60", *common]
            processes.append(subprocess.Popen(worker, **quiet))
        with Client(address, timeout="60s") as client:
            client.wait_for_workers(2, timeout=90)
        yield address
    finally:
        # each process leads its own session: stopping the group stops a nanny's worker too
        for process in reversed(processes):
            os.killpg(process.pid, signal.SIGTERM)
        for process in reversed(processes):
            try:
                process.wait(timeout=5)
            except subprocess.TimeoutExpired:
                os.killpg(process.pid, signal.SIGKILL)
                process.wait()


def _write(tmp_path: Path, text: str, name: str = "grid.toml") -> Path:
    path = tmp_path / name
    path.write_text(text)
    return path


def _one_by_one(point: dict, keep_samples: int):
    """The run of one point through the public API, with the keep grid's output step."""
    scene = load_scene("spherical").with_changes({**point, "duration": T_END})
    scene = dataclasses.replace(scene, solver=dataclasses.replace(scene.solver, output_step=T_END / (keep_samples - 1)))
    return run_scene(build_run(scene))


def _same(a: xr.Dataset, b: xr.Dataset) -> None:
    """Every variable equal bit for bit (NaN = NaN), timings excepted."""
    assert sorted(a.data_vars) == sorted(b.data_vars)
    for name in a.data_vars:
        if name in TIMINGS:
            continue
        x, y = a[name].values, b[name].values
        if x.dtype.kind == "f":
            np.testing.assert_array_equal(x, y, err_msg=name)
        else:
            assert np.array_equal(x, y), name


def test_scheduler_sweep_matches_runs_made_one_by_one(scheduler, tmp_path):
    sweep = _write(tmp_path, GRID)
    assert main([str(sweep), "--scheduler", scheduler, "--out", str(tmp_path / "out"), "--no-figures"]) == 0
    dataset = open_sweep(tmp_path / "out" / "sweep.zarr").load()
    assert dict(dataset.sizes)["clearance"] == 3 and dict(dataset.sizes)["period"] == 2
    np.testing.assert_array_equal(dataset.period.values, [0.9, 1.1])
    spec = load_sweep(sweep)
    for flat, point in enumerate(spec.design.points):
        index = dict(zip(spec.design.dims, spec.design.index(flat)))
        run = dataset.isel(index)
        result = _one_by_one(point, KEEP_SAMPLES)
        assert run.done and int(run.status) == result.status == 0 and run.cause.item() == ""
        assert run.run_key.item() == spec.run_keys[flat]
        for name in ("nfev", "nsteps", "nevents"):
            assert int(run[name]) == getattr(result, name), name
        force = result["S1_normal_force"].sum(axis=1)
        stats = ANALYSES["peak_rms"](t=result.t, signal=force)
        assert float(run.S1_force_peak) == float(stats["peak"]) and float(run.S1_force_rms) == float(stats["rms"])
        assert float(run.S1_force_peak) == force.max() > 0.0  # contact happened in every run
        on_grid = (result["record_kind"] == 4) | (result["record_kind"] == 3)
        np.testing.assert_array_equal(run.ee_position.values, result["ee_position"][on_grid])
        np.testing.assert_array_equal(run.S1_normal_force_sum.values, force[on_grid])
        np.testing.assert_allclose(result.t[on_grid], np.linspace(0.0, T_END, KEEP_SAMPLES), rtol=0, atol=1e-15)
    # the axes change the physics: the largest clearance gives the later first impact, hence other peaks
    assert len(np.unique(dataset.S1_force_peak.values)) == 6


def _done(store: Path) -> int:
    try:
        return int(np.count_nonzero(zarr.open_group(str(store), mode="r")["done"][...]))
    except Exception:  # the store is not created yet
        return 0


def test_killed_sweep_resumes_to_identical_arrays(scheduler, tmp_path):
    text = GRID.replace("linear = { start = 0.9, stop = 1.1, num = 2 }", "linear = { start = 0.8, stop = 1.2, num = 6 }")
    sweep = _write(tmp_path, text)
    killed, reference = tmp_path / "killed", tmp_path / "reference"
    command = [sys.executable, str(ROOT / "scripts" / "sweep.py"), str(sweep), "--scheduler", scheduler, "--out", str(killed), "--no-figures"]
    driver = subprocess.Popen(command, env={**os.environ, "PYTHONPATH": str(ROOT)}, start_new_session=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    deadline = time.monotonic() + 120
    while _done(killed / "sweep.zarr") < 3 and driver.poll() is None and time.monotonic() < deadline:
        time.sleep(0.01)
    os.killpg(driver.pid, signal.SIGKILL)
    driver.wait()
    done_at_kill = _done(killed / "sweep.zarr")
    assert 3 <= done_at_kill < 18, f"the driver was not killed halfway ({done_at_kill} of 18 runs done)"
    spec = load_sweep(sweep)
    resumed = run_sweep(spec, killed, scheduler=scheduler, progress=False)
    assert resumed.skipped >= 3 and resumed.skipped + resumed.ran == 18 and resumed.exit_code == 0
    whole = run_sweep(spec, reference, scheduler=scheduler, progress=False)
    assert whole.ran == 18
    _same(open_sweep(killed / "sweep.zarr").load(), open_sweep(reference / "sweep.zarr").load())
    again = run_sweep(spec, killed, scheduler=scheduler, progress=False)  # nothing left to do
    assert again.ran == 0 and again.skipped == 18


def test_failed_run_is_recorded_and_the_sweep_finishes(scheduler, tmp_path, capsys):
    text = GRID.replace('values = [5e-5, 1e-4, 2e-4]', 'values = [1e-4]').replace(
        'key = "trajectory.period"\nname = "period"\nlinear = { start = 0.9, stop = 1.1, num = 2 }',
        'key = "limits.penetration_ratio"\nname = "penetration_ratio"\nvalues = [0.5, 1e-3]',
    )
    sweep = _write(tmp_path, text)
    out = tmp_path / "out"
    assert main([str(sweep), "--scheduler", scheduler, "--out", str(out), "--progress"]) == 1
    captured = capsys.readouterr()
    assert "1 failed: 1 penetration beyond physical bound" in captured.out
    # the progress bar: runs done of the total, the failures so far, the time left
    final = captured.err.replace("\r", "\n").strip().splitlines()[-1]
    assert "sweep" in final and "2/2" in final and "failed=1" in final and "<" in final, final
    dataset = open_sweep(out / "sweep.zarr").load().isel(clearance=0)
    assert dataset.done.all()
    ok, failed = dataset.sel(penetration_ratio=0.5), dataset.sel(penetration_ratio=1e-3)
    assert int(ok.status) == 0 and np.isfinite(float(ok.S1_force_peak))
    assert int(failed.status) == -1 and failed.cause.item() == "penetration beyond physical bound"
    assert failed.message.item().startswith("t=") and 0 < float(failed.t_reached) < T_END
    assert np.isnan(float(failed.S1_force_peak))  # no statistics of a partial run
    kept = failed.ee_position.values
    assert np.all(np.isfinite(kept[0])) and np.all(np.isnan(kept[-1]))  # kept up to the stop, NaN after
    report = (out / "report.html").read_text()
    assert "penetration beyond physical bound" in report and "<script src=" not in report
