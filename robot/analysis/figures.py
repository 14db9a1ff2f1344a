"""PNG pictures of analyses: bifurcation diagram, 2-D map, spectrum waterfall, orbit plot.

Each ``*_figure`` function returns a :class:`matplotlib.figure.Figure` built
on the Agg canvas (no pyplot, no global state, no display needed), so callers
can restyle it; :func:`save_png` writes it atomically (temporary file in the
target folder, then ``os.replace``: a reader never sees a half-written PNG).
The plotted data can be read back from the artists (tested).
"""

from __future__ import annotations

from pathlib import Path
from typing import Mapping

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.patches import Circle

from robot.io.atomic import atomic_write_png
from .bifurcation import BifurcationDiagram
from .errors import AnalysisError, require_array, require_positive


def new_figure(width: float = 6.4, height: float = 4.8) -> Figure:
    """A figure of ``width`` x ``height`` inches on an Agg canvas."""
    figure = Figure(figsize=(width, height))
    FigureCanvasAgg(figure)
    return figure


def save_png(figure: Figure, path: Path | str, *, dpi: int = 100) -> Path:
    """Write ``figure`` as a PNG of (width dpi) x (height dpi) pixels to ``path``, atomically."""
    return atomic_write_png(figure, path, dpi=dpi)


def bifurcation_figure(diagram: BifurcationDiagram, *, marker_size: float = 1.0) -> Figure:
    """Poincare samples (dots) against the swept parameter."""
    figure = new_figure()
    axes = figure.add_subplot()
    mu, samples = diagram.scatter_data()
    axes.plot(mu, samples, ",k" if marker_size <= 0 else ".k", markersize=marker_size, linestyle="none")
    axes.set(xlabel=diagram.parameter_label, ylabel=diagram.coordinate_label, title="Bifurcation diagram")
    return figure


#: the axis scales the figures take
AXIS_SCALES = ("linear", "log")

#: a log axis labels every cell up to this many, then every k-th
MAX_CELL_LABELS = 12


def cell_edges(centres: np.ndarray, scale: str = "linear") -> np.ndarray:
    """Edges of the cells around sorted ``centres``: midpoints, geometric on a log axis (so the cells of a
    log-spaced axis look equal on it); the end cells are as wide as their neighbours."""
    values = np.log(centres) if scale == "log" else np.asarray(centres, dtype=float)
    if values.size == 1:  # a cell 10 % wide around the value (+-0.05 in ln on a log axis); 1 wide around 0
        half_width = 0.05 if scale == "log" else (0.05 * abs(values[0]) or 0.5)
        edges = values[0] + np.array([-half_width, half_width])
    else:
        inner = 0.5 * (values[1:] + values[:-1])
        edges = np.concatenate([[2.0 * values[0] - inner[0]], inner, [2.0 * values[-1] - inner[-1]]])
    return np.exp(edges) if scale == "log" else edges


def map_figure(
    x, y, values, *, x_label: str, y_label: str, value_label: str, log_scale: bool = False, x_scale: str = "linear", y_scale: str = "linear"
) -> Figure:
    """A scalar over two swept parameters: ``values`` (len(y), len(x)) as a pcolormesh with a colour bar.

    ``x_scale``/``y_scale``: "linear" or "log" (a log axis needs positive values; cells centred on them).
    """
    xs, ys = require_array("x", x, 1), require_array("y", y, 1)
    for name, scale, centres in (("x_scale", x_scale, xs), ("y_scale", y_scale, ys)):
        if scale not in AXIS_SCALES:
            raise AnalysisError(f"{name} must be one of {AXIS_SCALES}, got {scale!r}")
        if scale == "log" and not np.all(centres > 0):
            raise AnalysisError(f"{name}='log' needs positive values, got {centres.min():g}")
    data = np.asarray(values, dtype=float)
    if data.shape != (len(ys), len(xs)):
        raise AnalysisError(f"values must be (len(y)={len(ys)}, len(x)={len(xs)}), got shape {data.shape}")
    figure = new_figure()
    axes = figure.add_subplot()
    norm = None
    if log_scale:
        from matplotlib.colors import LogNorm

        positive = data[np.isfinite(data) & (data > 0)]
        if positive.size == 0:
            raise AnalysisError("log_scale needs positive values")
        norm = LogNorm(positive.min(), positive.max())
    x_order, y_order = np.argsort(xs), np.argsort(ys)
    ordered = np.ma.masked_invalid(data[np.ix_(y_order, x_order)])
    mesh = axes.pcolormesh(cell_edges(xs[x_order], x_scale), cell_edges(ys[y_order], y_scale), ordered, shading="flat", norm=norm)
    figure.colorbar(mesh, ax=axes, label=value_label)
    axes.set(xlabel=x_label, ylabel=y_label, xscale=x_scale, yscale=y_scale)
    _label_log_cells(axes.xaxis, xs, x_scale)
    _label_log_cells(axes.yaxis, ys, y_scale)
    if "log" in (x_scale, y_scale):
        figure.tight_layout(rect=(0.0, 0.0, 1.0, 0.95))  # room for the rotated values and the title
    return figure


def _label_log_cells(axis, centres: np.ndarray, scale: str) -> None:
    """On a log axis, ticks at the cells' values (matplotlib's minor-tick labels overlap within a decade);
    beyond :data:`MAX_CELL_LABELS` cells, every k-th, the first and last included."""
    if scale != "log":
        return
    from matplotlib.ticker import NullFormatter, NullLocator

    every = -(-len(centres) // MAX_CELL_LABELS)
    shown = np.unique(np.append(np.arange(0, len(centres), every), len(centres) - 1))
    axis.set_minor_locator(NullLocator())
    axis.set_minor_formatter(NullFormatter())
    axis.set_ticks(centres[shown], [f"{value:.3g}" for value in centres[shown]], fontsize=8, rotation=30 if axis.axis_name == "x" else 0)


def waterfall_figure(
    parameter, frequency, spectra, *, parameter_label: str, amplitude_label: str = "amplitude", frequency_label: str = "frequency (Hz)"
) -> Figure:
    """Spectra stacked along the parameter: curve j is ``parameter[j] + spacing * spectra[j] / max``."""
    mu, f = require_array("parameter", parameter, 1), require_array("frequency", frequency, 1)
    data = require_array("spectra", spectra, 2)
    if data.shape != (len(mu), len(f)):
        raise AnalysisError(f"spectra must be (len(parameter)={len(mu)}, len(frequency)={len(f)}), got shape {data.shape}")
    spacing = float(np.min(np.abs(np.diff(mu)))) * 2.0 if len(mu) > 1 else 1.0
    scale = float(np.max(np.abs(data))) or 1.0
    figure = new_figure()
    axes = figure.add_subplot()
    for j in range(len(mu)):
        axes.plot(f, mu[j] + spacing * data[j] / scale, color="C0", linewidth=0.8)
    axes.set(xlabel=frequency_label, ylabel=f"{parameter_label} (+ {amplitude_label}, scaled)")
    return figure


def orbit_figure(
    orbits: Mapping[str, np.ndarray], clearances: Mapping[str, float], *, plane: tuple[int, int] = (0, 1)
) -> Figure:
    """One panel per joint: the eccentricity in the outer frame's ``plane`` divided by the clearance, with
    the clearance circle (radius 1: contact)."""
    if not orbits:
        raise AnalysisError("orbits must name at least one joint")
    figure = new_figure(4.0 * len(orbits), 4.0)
    for index, (name, eccentricity) in enumerate(orbits.items()):
        if name not in clearances:
            raise AnalysisError(f"clearances has no entry for joint {name!r}")
        c = require_positive(f"clearances[{name!r}]", clearances[name])
        e = require_array(f"orbits[{name!r}]", eccentricity, 2)
        axes = figure.add_subplot(1, len(orbits), index + 1)
        axes.add_patch(Circle((0.0, 0.0), 1.0, fill=False, color="0.4", linestyle="--", label="clearance"))
        axes.plot(e[:, plane[0]] / c, e[:, plane[1]] / c, linewidth=0.8, label="orbit")
        axes.set(title=name, xlabel=f"e_{'xyz'[plane[0]]} / c", ylabel=f"e_{'xyz'[plane[1]]} / c", aspect="equal")
        limit = max(1.1, 1.05 * float(np.max(np.abs(e[:, list(plane)])) / c))
        axes.set(xlim=(-limit, limit), ylim=(-limit, limit))
    return figure
