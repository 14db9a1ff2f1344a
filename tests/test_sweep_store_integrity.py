"""A sweep store describes exactly the runs it holds, and is never lost or misread.

* a store is resumed only by the sweep its attributes describe: a changed ``t_end``, override or
  scene is refused (exit 2) naming what differs, unless ``--overwrite``;
* ``--overwrite`` deletes the old store only once the new sweep's probe run succeeded;
* analysis parameters an analysis refuses are refused when the sweep file is loaded (exit 2, no
  run, no store), naming the analysis, parameter, value and range; an analysis failing in one run
  keeps the other analyses' values of that run;
* a damaged store (an array missing, a chunk that cannot be read) is reported as such (exit 2),
  naming the array and the runs, and the report draws what can be read.

Tiny sweeps (2 runs of the slider-crank, 2 ms) on one in-process dask worker.
"""

from __future__ import annotations

import contextlib
import shutil
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("distributed")
import zarr  # noqa: E402

from robot.sweep import SweepError, engine, load_sweep, open_sweep, run_sweep  # noqa: E402
from robot.sweep.cli import main  # noqa: E402
from robot.sweep.report import draw_report  # noqa: E402

T_END = 0.002

SWEEP = """
[sweep]
name = "integrity"
scene = "slider_crank_revolute"
t_end = {t_end}
{overrides}
[[axis]]
key = "clearance.K.restitution"
name = "restitution"
values = [0.8, 0.9]

[[analysis]]
name = "poincare_stroboscopic"
label = "section"
state = "ee_position:0,1"
period = {period}
max_points = 4
{extra}
[[figure]]
kind = "lines"
x = "restitution"
values = ["K_force_peak"]
"""


def _file(folder: Path, name: str = "sweep.toml", *, t_end: float = T_END, overrides: str = "", period: str = "0.0005", extra: str = "") -> Path:
    path = folder / name
    path.write_text(SWEEP.format(t_end=t_end, overrides=overrides, period=period, extra=extra))
    return path


@pytest.fixture(scope="module")
def scheduler():
    """One in-process worker (no process to start, the kernels compiled once in this process)."""
    from distributed import LocalCluster

    with LocalCluster(n_workers=1, threads_per_worker=1, processes=False, dashboard_address=None) as cluster:
        yield cluster.scheduler_address


@pytest.fixture(scope="module")
def finished(scheduler, tmp_path_factory) -> Path:
    """A finished store of :data:`SWEEP` (copied by each test that damages it)."""
    folder = tmp_path_factory.mktemp("finished")
    outcome = run_sweep(load_sweep(_file(folder)), folder / "out", scheduler=scheduler, progress=False)
    assert outcome.failed == 0 and outcome.ran == 2
    return folder


def _copy(finished: Path, tmp_path: Path) -> Path:
    shutil.copytree(finished / "out", tmp_path / "out")
    return tmp_path / "out"


def _attrs(out: Path) -> dict:
    return dict(zarr.open_group(str(out / "sweep.zarr"), mode="r").attrs)


def _cli(capsys, sweep: Path, out: Path, scheduler: str, *extra: str) -> tuple[int, str]:
    code = main([str(sweep), "--out", str(out), "--scheduler", scheduler, "--no-progress", *extra])
    return code, capsys.readouterr().err


# --- 1. a store is resumed only by the sweep its attributes describe ------------------------------


def test_a_changed_t_end_or_override_is_refused_naming_what_differs(finished, tmp_path, scheduler, capsys):
    out = _copy(finished, tmp_path)
    before = _attrs(out)
    code, err = _cli(capsys, _file(tmp_path, t_end=0.003), out, scheduler, "--no-figures")
    assert code == 2 and "Traceback" not in err
    assert "t_end: stored 0.002, this sweep 0.003" in err and "--overwrite" in err and "another --out" in err
    with pytest.raises(SweepError, match=r'overrides: stored \{\}, this sweep \{"solver.rtol": 1e-07\}'):
        run_sweep(load_sweep(_file(tmp_path, overrides='[overrides]\n"solver.rtol" = 1e-7\n')), out, scheduler=scheduler, progress=False)
    assert _attrs(out) == before  # nothing was touched


def test_overwrite_rewrites_the_attributes_with_the_runs(finished, tmp_path, scheduler):
    out = _copy(finished, tmp_path)
    outcome = run_sweep(load_sweep(_file(tmp_path, t_end=0.003)), out, scheduler=scheduler, progress=False, overwrite=True)
    assert outcome.ran == 2 and outcome.failed == 0
    assert _attrs(out)["t_end"] == 0.003
    assert np.all(open_sweep(out / "sweep.zarr").t_reached.values == 0.003)


def test_the_same_sweep_from_a_renamed_file_resumes_and_names_its_file(finished, tmp_path, scheduler):
    out = _copy(finished, tmp_path)
    renamed = _file(tmp_path, "renamed.toml")
    outcome = run_sweep(load_sweep(renamed), out, scheduler=scheduler, progress=False)
    assert outcome.skipped == 2 and outcome.ran == 0
    attrs = _attrs(out)
    assert attrs["sweep_file"] == str(renamed) and attrs["sweep"] == "integrity"


# --- 2. --overwrite deletes nothing before the probe succeeded ------------------------------------


class _BrokenProbe:
    def run(self, function, *args):
        raise RuntimeError("the worker could not build the model")


def test_overwrite_keeps_the_old_store_when_the_probe_fails(finished, tmp_path, monkeypatch):
    out = _copy(finished, tmp_path)
    before = _attrs(out)
    monkeypatch.setattr(engine, "dask_client", lambda scheduler, workers: contextlib.nullcontext(_BrokenProbe()))
    with pytest.raises(SweepError, match="probe run of the first point failed"):
        run_sweep(load_sweep(_file(tmp_path, t_end=0.003)), out, progress=False, overwrite=True)
    assert _attrs(out) == before
    assert np.all(open_sweep(out / "sweep.zarr").done.values)


# --- 3. analysis parameters ------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("period", "extra", "words"),
    [
        ("-0.01", "", ["analysis 'section' (poincare_stroboscopic)", "period=-0.01", "valid range (0, inf)"]),
        (
            "0.0005",
            '[[analysis]]\nname = "amplitude_spectrum"\nlabel = "spectrum"\nsignal = "ee_acceleration:x"\nn_samples = -5\n',
            ["analysis 'spectrum' (amplitude_spectrum)", "n_samples=-5", "valid range [4, inf)"],
        ),
    ],
    ids=["poincare-period", "spectrum-n_samples"],
)
def test_analysis_parameters_are_refused_before_any_run_and_any_store(tmp_path, capsys, period, extra, words):
    sweep = _file(tmp_path, period=period, extra=extra)
    code = main([str(sweep), "--out", str(tmp_path / "out"), "--scheduler", "tcp://127.0.0.1:1", "--no-progress"])
    err = capsys.readouterr().err
    assert code == 2 and "Traceback" not in err and err.count("\n") == 1
    assert all(w in err for w in words), err
    assert not (tmp_path / "out").exists()  # refused when loaded: no scheduler asked, no store


def test_a_parameter_read_from_the_scene_is_checked_in_every_run(tmp_path):
    """``transient = "@trajectory.crank.offset"`` swept over -0.5 and 0.5: the first run's value is refused."""
    late = '[[analysis]]\nname = "poincare_stroboscopic"\nlabel = "late"\nstate = "ee_position:0,1"\nperiod = 0.001\ntransient = "@trajectory.crank.offset"\n'
    text = _file(tmp_path, extra=late).read_text().replace('key = "clearance.K.restitution"\nname = "restitution"\nvalues = [0.8, 0.9]', 'key = "trajectory.crank.offset"\nname = "restitution"\nvalues = [-0.5, 0.5]')
    (tmp_path / "offset.toml").write_text(text)
    pattern = r"analysis 'late' \(poincare_stroboscopic\), run 0: transient=-0\.5 must be non-negative \(valid range \[0, inf\)\) \(transient = '@trajectory.crank.offset' is -0\.5 there\)"
    with pytest.raises(SweepError, match=pattern) as refused:
        load_sweep(tmp_path / "offset.toml")
    assert refused.value.key == "late.transient" and refused.value.value == -0.5


def test_one_failing_analysis_keeps_the_others_values_and_is_named(tmp_path, scheduler):
    """A transient longer than the run is a fine parameter (its check needs the record): this run's
    analysis fails, recorded naming it, while the statistics of the same run are kept."""
    sweep = _file(tmp_path, extra='[[analysis]]\nname = "poincare_stroboscopic"\nlabel = "late"\nstate = "ee_position:0,1"\nperiod = 0.001\ntransient = 1.0\n')
    outcome = run_sweep(load_sweep(sweep), tmp_path / "out", scheduler=scheduler, progress=False)
    assert outcome.causes == {"analysis error": 2}
    data = open_sweep(tmp_path / "out" / "sweep.zarr").load()
    assert all("analysis 'late' (poincare_stroboscopic): AnalysisError: transient=1.0" in str(m) for m in data.message.values)
    assert np.all(np.isfinite(data.K_force_peak.values)) and np.all(data.section_count.values >= 1)
    assert np.all(np.isnan(data.late_count.values)) and np.all(np.isnan(data.late_points.values))


# --- 4. damaged stores -----------------------------------------------------------------------------


def _truncate(path: Path) -> None:
    path.write_bytes(path.read_bytes()[:5])


@pytest.mark.parametrize(
    ("damage", "words"),
    [
        (lambda store: (store / "status" / "zarr.json").unlink(), ["array 'status' is missing"]),
        (lambda store: _truncate(store / "done" / "c" / "1"), ["array 'done' cannot be read at run(s) (1,)"]),
        (lambda store: _truncate(store / "statistics" / "c" / "0" / "0"), ["array 'statistics' cannot be read at run(s) (0,)"]),
        (lambda store: _truncate(store / "zarr.json"), ["root metadata (zarr.json) cannot be read"]),
    ],
    ids=["status-metadata", "done-chunk", "statistics-chunk", "root"],
)
def test_a_damaged_store_is_refused_naming_the_array_and_overwrite_replaces_it(finished, tmp_path, scheduler, capsys, damage, words):
    out = _copy(finished, tmp_path)
    damage(out / "sweep.zarr")
    code, err = _cli(capsys, finished / "sweep.toml", out, scheduler, "--no-figures")
    assert code == 2 and "Traceback" not in err
    assert f"the sweep store at {str(out / 'sweep.zarr')!r} is damaged" in err and "--overwrite" in err and "delete it" in err
    assert all(w in err for w in words), err
    code, err = _cli(capsys, finished / "sweep.toml", out, scheduler, "--no-figures", "--overwrite")
    assert code == 0, err
    assert np.all(open_sweep(out / "sweep.zarr").done.values)


def test_the_report_draws_a_damaged_store_and_lists_what_cannot_be_read(finished, tmp_path):
    out = _copy(finished, tmp_path)
    _truncate(out / "sweep.zarr" / "statistics" / "c" / "1" / "0")
    written, damage = draw_report(load_sweep(finished / "sweep.toml"), out / "sweep.zarr", out)
    assert damage == ["statistics at run(s) (1,)"]
    assert {p.name for p in written} == {"00_lines.png", "report.html"}
    assert "damaged store" in (out / "report.html").read_text()
