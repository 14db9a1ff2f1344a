"""Sweep files: bad input is refused before any run (exit code 2, key and value named); designs.

No cluster is started here: every check happens when the file is loaded.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from robot.sweep import SweepError, load_sweep
from robot.sweep.cli import main

BASE = """
[sweep]
scene = "spherical"
t_end = 0.01
{sweep_extra}

[[axis]]
key = "{key}"
{axis}
"""


def _file(tmp_path: Path, key="clearance.S1.clearance", axis="values = [5e-5, 1e-4]", sweep_extra="", extra="") -> Path:
    path = tmp_path / "s.toml"
    path.write_text(BASE.format(key=key, axis=axis, sweep_extra=sweep_extra) + extra)
    return path


@pytest.mark.parametrize(
    "arguments, key, value",
    [
        ({"key": "clearance.S1.clearence"}, "clearance.S1.clearence", "5e-05"),  # unknown key path
        ({"key": "clearance.R7.radial_clearance"}, "clearance.R7.radial_clearance", "5e-05"),  # no such joint
        ({"axis": "values = []"}, "clearance.S1.clearance", "[]"),  # empty axis
        ({"axis": "linear = { start = 1e-5, stop = 1e-4, num = 0 }"}, "clearance.S1.clearance", "0"),
        ({"axis": "range = [1e-5, 1e-4]", "sweep_extra": 'design = "latin_hypercube"\nsamples = -3'}, "sweep.samples", "-3"),
        ({"axis": "range = [1e-5, 1e-4]", "sweep_extra": 'design = "sobol"\nsamples = 6'}, "sweep.samples", "6"),
        ({"key": "clearance.S1.restitution", "axis": "values = [0.5, 1.5]"}, "clearance.S1.restitution", "1.5"),  # refused by the scene
        ({"key": "clearance.S1.clearance", "axis": "values = [1e-4, -2e-5]"}, "clearance.S1.clearance", "-2e-05"),
        ({"key": "trajectory.period", "axis": "log = { start = 0.0, stop = 2.0, num = 3 }"}, "trajectory.period", "0.0"),
        ({"axis": "values = [5e-5, 1e-4, 5e-5]"}, "clearance.S1.clearance", "5e-05"),  # a repeated value
        ({"key": "clearance.S1.dissipation", "axis": 'values = ["flores", "hunt_crossley", "flores"]'}, "clearance.S1.dissipation", "flores"),
        ({"axis": "linear = { start = 1e-4, stop = 1e-4, num = 3 }"}, "clearance.S1.clearance", "0.0001"),
    ],
)
def test_bad_sweep_file_exits_2_naming_key_and_value_before_any_run(tmp_path, capsys, arguments, key, value):
    path = _file(tmp_path, **arguments)
    out = tmp_path / "out"
    assert main([str(path), "--out", str(out)]) == 2
    message = capsys.readouterr().err
    assert message.startswith("error: ") and key in message and value in message, message
    assert not out.exists()  # nothing ran, nothing was written
    with pytest.raises(SweepError) as caught:
        load_sweep(path)
    assert caught.value.key == key


def test_a_log_scale_needs_an_axis_of_positive_numbers(tmp_path):
    names = 'values = ["lankarani_nikravesh", "flores"]'
    figure = '\n[[figure]]\nkind = "lines"\nx = "clearance_S1_dissipation"\nvalues = ["status"]\nx_scale = "log"\n'
    with pytest.raises(SweepError, match="x_scale='log' needs an axis x of positive numbers") as caught:
        load_sweep(_file(tmp_path, key="clearance.S1.dissipation", axis=names, extra=figure))
    assert caught.value.key == "figure.x_scale"
    figure = '\n[[figure]]\nkind = "lines"\nx = "clearance_S1_clearance"\nvalues = ["status"]\nx_scale = "log"\n'
    assert load_sweep(_file(tmp_path, axis="values = [5e-5, 1e-4]", extra=figure)).figures[0]["x_scale"] == "log"


def test_map_options_reach_the_drawn_figure(tmp_path):
    """x_scale, the axis titles and the colour bar's title of a sweep file's map are those of the PNG."""
    import xarray as xr

    from robot.sweep.figures import draw_map

    clearance, speed = np.geomspace(2e-5, 5e-4, 5), np.array([10.0, 20.0, 30.0])
    dataset = xr.Dataset(
        {"peak": (("clearance", "speed"), np.arange(15.0).reshape(5, 3))},
        coords={"clearance": clearance, "speed": speed},
        attrs={"coordinates": ["clearance", "speed"]},
    )
    figure = {"kind": "map", "x": "clearance", "y": "speed", "value": "peak", "x_scale": "log",
              "x_label": "clearance (m)", "y_label": "speed (rad/s)", "value_label": "peak (N)"}  # fmt: skip
    plot, traces = draw_map(dataset, figure, tmp_path)
    axes, colour_bar = plot.axes
    assert axes.get_xscale() == "log" and axes.get_xlabel() == "clearance (m)" and axes.get_ylabel() == "speed (rad/s)"
    assert colour_bar.get_ylabel() == "peak (N)"
    np.testing.assert_allclose(axes.get_xticks(), clearance)  # one tick per cell on the log axis
    np.testing.assert_array_equal(traces[0]["z"], dataset["peak"].transpose("speed", "clearance").values)


@pytest.mark.parametrize(
    "extra, key",
    [
        ('\n[[analysis]]\nname = "no_such_analysis"\n', "analysis.name"),
        ('\n[[analysis]]\nname = "amplitude_spectrum"\nsignal = "S1_normal_force:avg"\n', "signal"),
        ('\n[[analysis]]\nname = "poincare_stroboscopic"\nstate = "ee_position"\n', "period"),  # a required parameter
        ('\n[[analysis]]\nname = "peak_rms"\nsignal = "t"\nwindow = 3\n', "window"),
        ('\n[[figure]]\nkind = "map"\nx = "clearance_S1_clearance"\ny = "nope"\nvalue = "S1_force_peak"\n', "figure.y"),
        ('\n[[figure]]\nkind = "lines"\nx = "clearance_S1_clearance"\nvalues = ["S1_force_pk"]\n', "figure.values"),
        ('\n[[figure]]\nkind = "map"\nx = "clearance_S1_clearance"\ny = "clearance_S1_clearance"\nvalue = "status"\nx_scale = "logarithmic"\n', "figure.x_scale"),
        ('\n[keep]\narrays = ["ee_position", "ee_position"]\n', "keep.arrays"),
        ("\n[bogus]\n", "bogus"),
    ],
)
def test_bad_outputs_are_refused_when_loading(tmp_path, extra, key):
    with pytest.raises(SweepError) as caught:
        load_sweep(_file(tmp_path, extra=extra))
    assert key in str(caught.value.key)


def test_sampled_designs_are_seeded_in_range_and_stratified(tmp_path):
    axes = '[[axis]]\nkey = "trajectory.period"\nname = "period"\nrange = [0.8, 1.25]\n'
    path = _file(tmp_path, axis='range = [1e-5, 5e-4]\nscale = "log"', sweep_extra='design = "latin_hypercube"\nsamples = 16\nseed = 7', extra="\n" + axes)
    first, again = load_sweep(path), load_sweep(path)
    c = first.design.coords["clearance_S1_clearance"][1]
    period = first.design.coords["period"][1]
    assert first.design.dims == ("sample",) and len(first.scenes) == 16
    np.testing.assert_array_equal(c, again.design.coords["clearance_S1_clearance"][1])  # seeded: bit for bit
    assert first.run_keys == again.run_keys and len(set(first.run_keys)) == 16
    assert np.all((c >= 1e-5) & (c <= 5e-4)) and np.all((period >= 0.8) & (period <= 1.25))
    # Latin hypercube: exactly one sample in each of the 16 equal strata of every axis (log10 for the log axis)
    strata = np.floor(16 * (np.log10(c) - np.log10(1e-5)) / (np.log10(5e-4) - np.log10(1e-5))).astype(int)
    assert sorted(strata) == list(range(16))
    assert sorted(np.floor(16 * (period - 0.8) / 0.45).astype(int)) == list(range(16))
    # each run's scene carries its sampled values
    for scene, value in zip(first.scenes, c):
        assert scene.clearances[0].law.clearance == pytest.approx(value, rel=1e-12)
    other = load_sweep(path.write_text(path.read_text().replace("seed = 7", "seed = 8")) and path)
    assert not np.array_equal(c, other.design.coords["clearance_S1_clearance"][1])


def test_grid_keys_follow_the_resolved_scene(tmp_path):
    spec = load_sweep(_file(tmp_path, axis="log = { start = 1e-5, stop = 1e-3, num = 3 }"))
    np.testing.assert_allclose(spec.design.coords["clearance_S1_clearance"][1], [1e-5, 1e-4, 1e-3], rtol=1e-15)
    assert [s.duration for s in spec.scenes] == [0.01] * 3
    # the same resolved scene has the same key whatever the file that produced it
    same = load_sweep(_file(tmp_path, axis="values = [1e-5, 1e-4, 1e-3]"))
    assert spec.run_keys[1:] == same.run_keys[1:] or spec.run_keys == same.run_keys
    changed = load_sweep(_file(tmp_path, axis="values = [1e-5, 1e-4, 1e-3]", extra='\n[overrides]\n"solver.rtol" = 1e-6\n'))
    assert set(changed.run_keys).isdisjoint(spec.run_keys)


@pytest.mark.parametrize("path", sorted((Path(__file__).resolve().parents[1] / "robot" / "sweep" / "examples").glob("*.toml")), ids=lambda p: p.stem)
def test_every_shipped_sweep_file_loads(path):
    """The shipped studies stay valid as the scene schema, the analyses and the figures evolve:
    every axis value is accepted by the scene, every figure names known axes and variables."""
    spec = load_sweep(path)
    assert len(spec.scenes) == len(spec.run_keys) == len(set(spec.run_keys)) > 0


def test_a_store_of_an_older_analysis_version_is_another_layout(tmp_path, monkeypatch):
    """An analysis that gains an output (as lyapunov_benettin gained standard_error) makes the old
    store another layout: resuming into it would ask for a variable it lacks. Same file, same scenes."""
    import dataclasses

    from robot.analysis import ANALYSES
    from robot.analysis.registry import Field

    extra = '\n[[analysis]]\nname = "peak_rms"\nsignal = "S1_normal_force:sum"\n'
    path = _file(tmp_path, extra=extra)
    before = load_sweep(path)
    before_key = before.layout_key  # (computed on first access)
    newer = dataclasses.replace(ANALYSES["peak_rms"], outputs=(*ANALYSES["peak_rms"].outputs, Field("kurtosis", (), "1", "a new output")))
    monkeypatch.setitem(ANALYSES._analyses, "peak_rms", newer)
    after = load_sweep(path)
    assert after.run_keys == before.run_keys  # the runs are the same ...
    assert after.layout_key != before_key  # ... the store's variables are not
