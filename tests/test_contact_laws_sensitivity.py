"""The contact-law sensitivity study (robot/sweep/examples/contact_laws_sensitivity.toml).

* The shipped sweep file loads and validates: every registered radial law x every registered
  dissipation model, the dissipation axis setting S1 and R1 together (a linked axis).
* Linked axes and string (law name) axis values: bad input is refused naming the key.
* A 2-run, 0.01 s version of the study goes through the sweep's own per-run pipeline
  (``robot.sweep.task.execute``, what a dask worker runs, here in-process) and the physics
  holds: over the same first R1 impact, the softer radial law (``hertz_point``) penetrates
  deeper and peaks lower than the seed paper's linear law; the stored statistics equal the
  ones computed from ``robot.simulate`` directly, and ``P5_force`` is the P5 actuator's column.
* The percent changes of :mod:`robot.sweep.sensitivity` and the ``sensitivity`` figure.
"""

from __future__ import annotations

import tomllib
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from clearance_contact import DISSIPATION_MODELS, RADIAL_LAWS
from robot import simulate
from robot.sweep import SweepError, load_sweep, open_sweep
from robot.sweep.engine import make_tasks, plan_layout, store_attrs
from robot.sweep.report import draw_all
from robot.sweep.sensitivity import relative_change, sensitivity_table
from robot.sweep.store import create_store
from robot.sweep.task import execute, probe

ROOT = Path(__file__).resolve().parents[1]
STUDY = ROOT / "robot" / "sweep" / "examples" / "contact_laws_sensitivity.toml"


def test_shipped_study_covers_every_law_and_links_the_dissipation_of_both_joints():
    spec = load_sweep(STUDY)
    assert spec.base.name == "compound_misaligned" and spec.t_end == 2.0
    radial, dissipation = spec.axes
    assert set(radial.values) == set(RADIAL_LAWS) and set(dissipation.values) == set(DISSIPATION_MODELS)
    assert spec.design.shape == (len(RADIAL_LAWS), len(DISSIPATION_MODELS))
    for point, scene in zip(spec.design.points, spec.scenes):
        joints = {entry["joint"]: entry for entry in scene.document["clearance"]}
        assert joints["S1"]["dissipation"] == joints["R1"]["dissipation"] == point["clearance.S1.dissipation"]
        assert joints["R1"]["radial_law"] == point["clearance.R1.radial_law"]
    assert len(set(spec.run_keys)) == spec.design.size
    # its control: the scene's laws with c_e of both joints moved by +-0.01
    control = load_sweep(STUDY.with_name("contact_laws_sensitivity_control.toml"))
    for point, scene in zip(control.design.points, control.scenes):
        assert {e["joint"]: e["restitution"] for e in scene.document["clearance"]} == {"S1": point["clearance.S1.restitution"], "R1": point["clearance.R1.restitution"]}


AXIS = """
[sweep]
scene = "compound"
t_end = 0.01

[[axis]]
{axis}
"""


@pytest.mark.parametrize(
    "axis, key, value",
    [
        ('key = ["clearance.S1.dissipation", "clearance.R1.dissipation"]\nvalues = ["flores"]', "clearance.S1.dissipation", None),  # no name
        ('key = ["clearance.S1.restitution", "clearance.R1.restitution"]\nname = "e"\nvalues = [0.5, 1.5]', "clearance.S1.restitution", 1.5),
        ('key = "clearance.R1.radial_law"\nvalues = ["linear", "hertz"]', "clearance.R1.radial_law", "hertz"),  # unknown law
        ('key = ["clearance.R1.dissipation", "clearance.R1.dissipation"]\nname = "d"\nvalues = ["flores"]', "axis", None),  # twice
        ('key = []\nname = "d"\nvalues = ["flores"]', "axis.key", []),
    ],
)
def test_bad_linked_or_named_axes_are_refused_naming_the_key(tmp_path, axis, key, value):
    path = tmp_path / "s.toml"
    path.write_text(AXIS.format(axis=axis))
    with pytest.raises(SweepError) as caught:
        load_sweep(path)
    assert caught.value.key == key
    if value is not None:
        assert caught.value.value == value


def _short_study(tmp_path: Path, laws: list[str]):
    document = tomllib.loads(STUDY.read_text())
    document["sweep"]["t_end"] = 0.01
    document["axis"][0]["values"] = laws
    document["axis"][1]["values"] = ["lankarani_nikravesh"]
    return load_sweep(document, base_dir=STUDY.parent)


def test_softer_radial_law_penetrates_deeper_and_peaks_lower_through_the_sweep_pipeline(tmp_path):
    spec = _short_study(tmp_path, ["linear", "hertz_point"])
    tasks = make_tasks(spec)
    layout = plan_layout(spec, tmp_path / "sweep.zarr", probe(tasks[0])["shapes"])
    create_store(layout, spec.design.coords, store_attrs(spec))
    for task in tasks:
        execute(task, layout)
    data = open_sweep(tmp_path / "sweep.zarr").isel(dissipation=0).compute()
    assert list(data.status.values) == [0, 0]
    linear, hertz = (data.sel(radial_law=law) for law in ("linear", "hertz_point"))
    # both runs hold the first R1 impact (~4.6 ms); the softer law goes deeper with a lower peak
    assert 0.0 < linear.R1_force_time_of_peak < 0.01 and 0.0 < hertz.R1_force_time_of_peak < 0.01
    assert hertz.R1_penetration_maximum > 1.3 * linear.R1_penetration_maximum > 0.0
    assert hertz.R1_force_peak < 0.85 * linear.R1_force_peak

    # the sweep's statistics are those of the public API's arrays; P5_force is P5's column
    pinned = tomllib.loads(STUDY.read_text())["overrides"]  # the study's configuration (a centred start)
    result = simulate("compound_misaligned", overrides={**pinned, "clearance.R1.radial_law": "hertz_point"}, t_end=0.01)
    assert float(hertz.R1_force_peak) == result.joint("R1").normal_force.sum(axis=1).max()
    assert float(hertz.R1_penetration_maximum) == result.joint("R1").penetration.max()
    p5 = result.metadata["actuated_joints"].index("P5")
    assert float(hertz.P5_force_peak) == np.abs(result["driving_force"][:, p5]).max()

    # the study's own figures (law names selected exactly) are drawn from this store, small
    written = draw_all(spec, tmp_path / "sweep.zarr", tmp_path)
    pngs = [path for path in written if path.suffix == ".png"]
    assert len(pngs) == len(spec.figures) and all(0 < path.stat().st_size < 300_000 for path in pngs)


def _dataset(values: list[float], status: list[int]) -> xr.Dataset:
    laws = ["linear", "johnson", "pereira"]
    return xr.Dataset(
        {
            "force_peak": ("radial_law", np.array(values)),
            "status": ("radial_law", np.array(status)),
            "cause": ("radial_law", np.array(["" if s == 0 else "step size collapse" for s in status])),
            "cpu_time": ("radial_law", np.array([1.0, 2.0, 3.0])),
        },
        coords={"radial_law": laws},
    )


def test_relative_change_and_table_show_failed_runs_as_failed():
    data = _dataset([200.0, 150.0, np.nan], [0, 0, -1])
    np.testing.assert_allclose(relative_change(data, "force_peak", "radial_law"), [0.0, -25.0, np.nan])
    np.testing.assert_allclose(relative_change(data, "force_peak", "radial_law", "johnson"), [100.0 / 3.0, 0.0, np.nan])
    table = sensitivity_table(data, "radial_law", [("force_peak", "peak force (kN)", 1e-3)])
    rows = table.splitlines()
    assert rows[2].startswith("| `linear` | 0.2 | ok |")
    assert "0.15 (-25.0 %)" in rows[3]
    assert "| failed | -1: step size collapse |" in rows[4]
    with pytest.raises(SweepError, match="hertz"):
        relative_change(data, "force_peak", "radial_law", "hertz")
    with pytest.raises(SweepError, match="non-zero reference"):
        relative_change(_dataset([np.nan, 1.0, 2.0], [-1, 0, 0]), "force_peak", "radial_law")


def test_sensitivity_figure_draws_the_changes_as_bars(tmp_path):
    from robot.sweep.figures import FIGURES

    data = _dataset([200.0, 150.0, 260.0], [0, 0, 0])
    plot, traces = FIGURES["sensitivity"].draw(data, {"kind": "sensitivity", "x": "radial_law", "values": ["force_peak"]}, tmp_path)
    heights = [patch.get_height() for patch in plot.axes[0].patches]
    np.testing.assert_allclose(heights, [0.0, -25.0, 30.0])
    assert traces[0]["x"] == ["linear", "johnson", "pereira"]
