"""PNG pictures: size, not blank, data read back from the artists; bifurcation diagram of the logistic map."""

from __future__ import annotations

import os

import numpy as np
import pytest
from matplotlib.image import imread

from robot.analysis import AnalysisError
from robot.analysis.bifurcation import BifurcationDiagram, distinct_points
from robot.analysis.figures import bifurcation_figure, map_figure, orbit_figure, save_png, waterfall_figure


def logistic_samples(r: float, transient: int = 3000, keep: int = 64) -> np.ndarray:
    x = 0.3
    for _ in range(transient):
        x = r * x * (1 - x)
    out = np.empty(keep)
    for k in range(keep):
        x = r * x * (1 - x)
        out[k] = x
    return out


def logistic_diagram(parameter) -> BifurcationDiagram:
    return BifurcationDiagram.from_samples(parameter, [logistic_samples(r) for r in parameter], parameter_label="r", coordinate_label="x")


def test_logistic_map_period_doubling():
    """x -> r x (1 - x): fixed point 1 - 1/r for 1 < r < 3, period 2 for 3 < r < 1 + sqrt(6), period 4 up to
    3.5441 (Strogatz 1994, Sec. 10.2); the 2-cycle is (r + 1 -+ sqrt((r - 3)(r + 1))) / (2 r)."""
    r = np.array([2.5, 2.9, 3.1, 3.3, 3.5])
    diagram = logistic_diagram(r)
    np.testing.assert_array_equal(diagram.distinct_counts(1e-6), [1, 1, 2, 2, 4])
    np.testing.assert_allclose(diagram.points[0], 1 - 1 / 2.5, atol=1e-12)
    for j in (2, 3):
        cycle = (r[j] + 1 + np.array([-1, 1]) * np.sqrt((r[j] - 3) * (r[j] + 1))) / (2 * r[j])
        np.testing.assert_allclose(np.unique(np.round(diagram.points[j], 9)), cycle, atol=1e-9)


def png_checks(path, width_px: int, height_px: int) -> np.ndarray:
    image = imread(path)
    assert image.shape[:2] == (height_px, width_px)
    non_white = np.any(image[:, :, :3] < 0.95, axis=2).mean()
    assert 0.01 < non_white < 0.9  # something is drawn, and the picture is not a filled block
    return image


def test_bifurcation_png(tmp_path):
    r = np.linspace(2.8, 4.0, 120)
    diagram = logistic_diagram(r)
    figure = bifurcation_figure(diagram)
    line = figure.axes[0].lines[0]
    mu, samples = diagram.scatter_data()
    np.testing.assert_array_equal(line.get_xdata(), mu)
    np.testing.assert_array_equal(line.get_ydata(), samples)
    path = save_png(figure, tmp_path / "bifurcation.png", dpi=80)
    png_checks(path, 512, 384)
    assert sorted(os.listdir(tmp_path)) == ["bifurcation.png"]  # no temporary file left


def test_map_png(tmp_path):
    x, y = np.linspace(0, 1, 30), np.linspace(-2, 2, 20)
    values = np.sin(3 * x)[None, :] * np.cos(y)[:, None]
    figure = map_figure(x, y, values, x_label="clearance (mm)", y_label="speed", value_label="peak force (N)")
    mesh = figure.axes[0].collections[0]
    np.testing.assert_allclose(np.asarray(mesh.get_array()).reshape(20, 30), values)
    assert len(figure.axes) == 2  # the colour bar
    png_checks(save_png(figure, tmp_path / "map.png", dpi=50), 320, 240)
    with pytest.raises(AnalysisError, match=r"values must be \(len\(y\)=20, len\(x\)=30\)"):
        map_figure(x, y, values.T, x_label="", y_label="", value_label="")


def test_map_on_a_log_axis_centres_equal_cells_on_the_values():
    """A log-spaced axis drawn on a log scale: every value sits in the middle (geometric) of its cell,
    all cells equally wide in log space, and unsorted axes are drawn sorted with their values."""
    x, y = np.geomspace(2e-5, 5e-4, 8), np.array([30.0, 10.0, 20.0])
    values = np.arange(24.0).reshape(3, 8)
    figure = map_figure(x, y, values, x_label="clearance (m)", y_label="speed", value_label="v", x_scale="log")
    axes = figure.axes[0]
    assert axes.get_xscale() == "log" and axes.get_yscale() == "linear"
    mesh = axes.collections[0]
    corners = mesh.get_coordinates()  # (len(y)+1, len(x)+1, 2)
    x_edges, y_edges = corners[0, :, 0], corners[:, 0, 1]
    np.testing.assert_allclose(np.sqrt(x_edges[1:] * x_edges[:-1]), x, rtol=1e-12)
    np.testing.assert_allclose(np.diff(np.log(x_edges)), np.log(x[1] / x[0]), rtol=1e-12)
    np.testing.assert_allclose(y_edges, [5.0, 15.0, 25.0, 35.0])
    np.testing.assert_allclose(np.asarray(mesh.get_array()).reshape(3, 8), values[[1, 2, 0]])  # rows sorted by y
    many = np.geomspace(1e-5, 1e-3, 30)  # more cells than readable labels: every k-th, both ends
    ticks = map_figure(many, y, np.ones((3, 30)), x_label="", y_label="", value_label="", x_scale="log").axes[0].get_xticks()
    assert len(ticks) <= 13 and ticks[0] == many[0] and ticks[-1] == many[-1] and set(ticks) <= set(many)
    with pytest.raises(AnalysisError, match="x_scale='log' needs positive values"):
        map_figure(x - 1.0, y, values, x_label="", y_label="", value_label="", x_scale="log")
    with pytest.raises(AnalysisError, match=r"y_scale must be one of \('linear', 'log'\)"):
        map_figure(x, y, values, x_label="", y_label="", value_label="", y_scale="symlog")


def test_waterfall_png(tmp_path):
    parameter = np.array([0.1, 0.2, 0.3, 0.4])
    frequency = np.linspace(0, 50, 200)
    spectra = np.array([np.exp(-((frequency - 10 * (j + 1)) ** 2)) for j in range(4)])
    figure = waterfall_figure(parameter, frequency, spectra, parameter_label="gain")
    lines = figure.axes[0].lines
    assert len(lines) == 4
    for j, line in enumerate(lines):
        peak = frequency[np.argmax(line.get_ydata())]
        assert peak == pytest.approx(10 * (j + 1), abs=0.3)
        assert np.min(line.get_ydata()) == pytest.approx(parameter[j], abs=1e-12)
    png_checks(save_png(figure, tmp_path / "sub" / "waterfall.png", dpi=60), 384, 288)


def test_orbit_png(tmp_path):
    t = np.linspace(0, 2 * np.pi, 400)
    c = 2e-5
    e = np.column_stack([0.9 * c * np.cos(t), 0.5 * c * np.sin(t), np.zeros_like(t)])
    figure = orbit_figure({"R1": e, "S1": 1.2 * e}, {"R1": c, "S1": c})
    assert [a.get_title() for a in figure.axes] == ["R1", "S1"]
    np.testing.assert_allclose(figure.axes[0].lines[0].get_xdata(), 0.9 * np.cos(t))
    assert figure.axes[0].patches[0].get_radius() == 1.0
    assert figure.axes[1].get_xlim()[1] > 1.08  # the penetrating orbit (reaches 1.08 c) stays in view
    png_checks(save_png(figure, tmp_path / "orbit.png", dpi=50), 400, 200)
    with pytest.raises(AnalysisError, match="clearances has no entry for joint 'S1'"):
        orbit_figure({"S1": e}, {"R1": c})


def test_failed_write_leaves_the_previous_file(tmp_path):
    path = tmp_path / "keep.png"
    path.write_bytes(b"previous")

    class Broken:
        def savefig(self, *args, **kwargs):
            raise RuntimeError("disk full")

    with pytest.raises(RuntimeError, match="disk full"):
        save_png(Broken(), path)
    assert path.read_bytes() == b"previous" and sorted(os.listdir(tmp_path)) == ["keep.png"]


def test_pyplot_figures_are_released_even_when_the_write_fails(tmp_path):
    """atomic_write_png(close=True), the one PNG writer of the studies, validation and paper figures."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from robot.io.atomic import atomic_write_png

    figure, _ = plt.subplots(figsize=(2.0, 1.0))
    png_checks(atomic_write_png(figure, tmp_path / "small.png", dpi=50, close=True), 100, 50)
    assert not plt.fignum_exists(figure.number)
    figure, _ = plt.subplots()
    with pytest.raises(TypeError):
        atomic_write_png(figure, tmp_path / "bad.png", dpi=50, close=True, no_such_option=1)
    assert not plt.fignum_exists(figure.number) and sorted(os.listdir(tmp_path)) == ["small.png"]


def test_distinct_points_edge_cases():
    assert distinct_points([np.nan, np.nan], 1e-3) == 0
    assert distinct_points([1.0, 1.0 + 1e-4, 2.0], 1e-3) == 2
    with pytest.raises(AnalysisError, match="tolerance=0.0 must be positive"):
        distinct_points([1.0], 0.0)
    with pytest.raises(AnalysisError, match=r"points must be \(n_parameters=2, max_points\)"):
        BifurcationDiagram(np.array([1.0, 2.0]), np.zeros((3, 4)))


def test_cell_edges_centre_each_value_in_its_cell_at_its_own_scale():
    from robot.analysis.figures import cell_edges

    # one value: a cell 10 % wide around it, whatever its size (a clearance of 0.5 mm, a speed of 60 rad/s)
    for value in (5e-4, 60.0):
        edges = cell_edges(np.array([value]))
        assert np.allclose(edges, [0.95 * value, 1.05 * value], rtol=1e-12)
        assert np.allclose(cell_edges(np.array([value]), "log"), value * np.exp([-0.05, 0.05]), rtol=1e-12)
    assert np.array_equal(cell_edges(np.array([0.0])), [-0.5, 0.5])
    # several: midpoints, geometric midpoints on a log axis, end cells as wide as their neighbours
    assert np.allclose(cell_edges(np.array([1.0, 2.0, 4.0])), [0.5, 1.5, 3.0, 5.0])
    assert np.allclose(cell_edges(np.array([1e-5, 1e-4, 1e-3]), "log"), 10.0 ** np.array([-5.5, -4.5, -3.5, -2.5]))
