"""Pictures of a sweep, declared in the sweep file (``[[figure]]``), drawn from its dataset.

Kinds (:data:`FIGURES`; ``x``/``y`` name axes, ``value``/``points``/... name
dataset variables, ``select = {AXIS = VALUE}`` fixes the other axes, nearest
value; unselected axes take their first value):

* ``lines``: scalar variable(s) ``values = [...]`` against axis ``x``, one
  curve per value of an optional second axis ``by``; ``x_scale``, ``y_scale``, ``x_label``, ``y_label``;
* ``map``: a scalar ``value`` over axes ``x`` and ``y`` (grid designs; sampled
  designs draw the samples as coloured points), ``log_color``, ``x_scale`` /
  ``y_scale`` ("linear" or "log": cells centred on log-spaced values look equal),
  ``x_label`` / ``y_label`` / ``value_label`` (default: the axis and variable names;
  say the units);
* ``bifurcation``: Poincare points ``points`` (an analysis's ``LABEL_points``),
  column ``component``, against axis ``x``;
* ``waterfall``: spectra ``amplitude`` over ``frequency`` stacked along ``x``;
* ``orbit``: a kept eccentricity ``array`` (columns x, y) divided by the
  clearance at the scene key ``clearance``, one panel per value of ``x``
  (at most ``panels``);
* ``sensitivity``: grouped bars, one group per value of axis ``x`` (a law
  name, any category), one bar per scalar variable of ``values``: its percent
  change against the run at ``x = reference`` (default: the first value),
  :mod:`robot.sweep.sensitivity`; a failed run is marked "failed".

Axes of strings (law names) are drawn as categories: ``map`` puts one cell per
name, ``lines`` one tick per name.

The PNGs use :mod:`robot.analysis.figures`; the same data feed the HTML report
(:mod:`robot.sweep.report`). Each drawing function returns ``(title, traces)``
where traces are plain data the report turns into plotly figures.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable

import numpy as np

from robot.sweep.errors import SweepError

_COMMON = {"kind", "title", "select"}


@dataclass(frozen=True)
class FigureKind:
    keys: frozenset[str]
    required: frozenset[str]
    draw: Callable[..., Any]
    grid_only: bool = False


def selected(dataset, figure: dict, keep: tuple[str, ...]):
    """The dataset with every run dimension other than ``keep`` fixed (``select`` or the first value)."""
    from robot.sweep.design import SAMPLE_DIM

    selection = dict(figure.get("select", {}))
    out = dataset
    for dim in dataset.attrs.get("coordinates", []):
        if dim in keep or dim not in out.dims or dim == SAMPLE_DIM:
            continue
        if dim not in selection:
            out = out.isel({dim: 0})
        elif out[dim].dtype.kind in "biuf":
            out = out.sel({dim: selection[dim]}, method="nearest")
        elif str(selection[dim]) in [str(v) for v in out[dim].values]:
            out = out.sel({dim: selection[dim]})  # names (law names) are chosen exactly
        else:
            raise SweepError(f"figure select: {dim}={selection[dim]!r} is not a value of the axis ({', '.join(map(str, out[dim].values))})", key=f"figure.select.{dim}", value=selection[dim])
    return out


def _label(value) -> str:
    """An axis value as text: numbers in %g, names as they are."""
    return f"{value:g}" if isinstance(value, (int, float, np.number)) and not isinstance(value, bool) else str(value)


def _positions(values) -> tuple[np.ndarray, list[str] | None]:
    """Plot positions of an axis's values: the values if numeric, else 0, 1, ... with the names as tick labels."""
    values = np.asarray(values)
    if values.dtype.kind in "biuf":
        return values, None
    return np.arange(len(values), dtype=float), [str(v) for v in values]


def draw_lines(dataset, figure: dict, out: Path):
    from robot.analysis.figures import new_figure

    x, by = figure["x"], figure.get("by")
    data = selected(dataset, figure, (x, by) if by else (x,))
    plot = new_figure()
    axes = plot.add_subplot()
    traces = []
    positions, names = _positions(data[x].values)
    for value in figure["values"]:
        curves = [(None, data[value])] if by is None else [(f"{by}={_label(b)}", data[value].sel({by: b})) for b in data[by].values]
        for label, curve in curves:
            name = value if label is None else f"{value}, {label}"
            axes.plot(positions, curve.transpose(x).values, marker="o", markersize=3, label=name)
            traces.append({"type": "line", "x": data[x].values, "y": curve.values, "name": name})
    axes.set(xlabel=figure.get("x_label", x), ylabel=figure.get("y_label", ""), xscale=figure.get("x_scale", "linear"), yscale=figure.get("y_scale", "linear"))
    if names is not None:
        axes.set_xticks(positions, names, rotation=20, fontsize=8)
    axes.legend(fontsize=7)
    return plot, traces


def draw_map(dataset, figure: dict, out: Path):
    from robot.analysis.figures import map_figure, new_figure

    x, y, value = figure["x"], figure["y"], figure["value"]
    log = bool(figure.get("log_color", False))
    if "sample" in dataset.dims:
        plot = new_figure()
        axes = plot.add_subplot()
        from matplotlib.colors import LogNorm

        values = dataset[value].values
        points = axes.scatter(dataset[x].values, dataset[y].values, c=values, norm=LogNorm() if log else None)
        plot.colorbar(points, ax=axes, label=figure.get("value_label", value))
        axes.set(xlabel=figure.get("x_label", x), ylabel=figure.get("y_label", y), xscale=figure.get("x_scale", "linear"), yscale=figure.get("y_scale", "linear"))
        return plot, [{"type": "scatter_map", "x": dataset[x].values, "y": dataset[y].values, "z": values, "name": value}]
    data = selected(dataset, figure, (x, y))
    z = data[value].transpose(y, x).values
    (x_positions, x_names), (y_positions, y_names) = _positions(data[x].values), _positions(data[y].values)
    plot = map_figure(
        x_positions, y_positions, z, x_label=figure.get("x_label", x), y_label=figure.get("y_label", y), value_label=figure.get("value_label", value),
        log_scale=log, x_scale=figure.get("x_scale", "linear") if x_names is None else "linear",
        y_scale=figure.get("y_scale", "linear") if y_names is None else "linear",
    )
    if x_names is not None:
        plot.axes[0].set_xticks(x_positions, x_names, rotation=20, fontsize=8)
    if y_names is not None:
        plot.axes[0].set_yticks(y_positions, y_names, fontsize=8)
    if x_names is not None or y_names is not None:
        plot.tight_layout(rect=(0.0, 0.0, 1.0, 0.95))  # room for the names and the title
    return plot, [{"type": "heatmap", "x": data[x].values, "y": data[y].values, "z": z, "name": value}]


def draw_bifurcation(dataset, figure: dict, out: Path):
    from robot.analysis.bifurcation import BifurcationDiagram
    from robot.analysis.figures import bifurcation_figure

    x, points = figure["x"], figure["points"]
    data = selected(dataset, figure, (x,))
    cloud = data[points].values[..., int(figure.get("component", 0))] if data[points].ndim == 3 else data[points].values
    diagram = BifurcationDiagram(data[x].values, cloud, parameter_label=x, coordinate_label=f"{points}[{figure.get('component', 0)}]")
    mu, samples = diagram.scatter_data()
    return bifurcation_figure(diagram, marker_size=2.0), [{"type": "points", "x": mu, "y": samples, "name": points}]


def draw_waterfall(dataset, figure: dict, out: Path):
    from robot.analysis.figures import waterfall_figure

    x = figure["x"]
    data = selected(dataset, figure, (x,))
    frequency = np.asarray(data[figure["frequency"]].values)
    frequency = frequency[0] if frequency.ndim == 2 else frequency
    spectra = data[figure["amplitude"]].transpose(x, ...).values
    plot = waterfall_figure(data[x].values, frequency, spectra, parameter_label=x)
    return plot, [{"type": "surface", "x": frequency, "y": data[x].values, "z": spectra, "name": figure["amplitude"]}]


def draw_orbit(dataset, figure: dict, out: Path, clearance_of: Callable[[dict], float]):
    from robot.analysis.figures import orbit_figure

    x, array = figure["x"], figure["array"]
    data = selected(dataset, figure, (x,))
    values = data[x].values
    chosen = np.unique(np.linspace(0, len(values) - 1, min(len(values), int(figure.get("panels", 4)))).round().astype(int))
    orbits, clearances, traces = {}, {}, []
    for j in chosen:
        name = f"{x}={values[j]:.3g}"
        e = data[array].isel({x: j}).values
        e = e[np.all(np.isfinite(e), axis=1)]
        orbits[name], clearances[name] = e, clearance_of({x: values[j]})
        traces.append({"type": "orbit", "x": e[:, 0] / clearances[name], "y": e[:, 1] / clearances[name], "name": name})
    return orbit_figure(orbits, clearances), traces


def draw_sensitivity(dataset, figure: dict, out: Path):
    from robot.analysis.figures import new_figure
    from robot.sweep.sensitivity import relative_change

    x, values = figure["x"], figure["values"]
    data = selected(dataset, figure, (x,))
    categories = [str(c) for c in data[x].values]
    reference = figure.get("reference", categories[0])
    positions = np.arange(len(categories), dtype=float)
    width = 0.8 / len(values)
    plot = new_figure(7.5, 4.2)
    axes = plot.add_subplot()
    traces = []
    for k, value in enumerate(values):
        change = relative_change(data, value, x, reference)
        axes.bar(positions + (k - (len(values) - 1) / 2) * width, np.nan_to_num(change), width, label=value)
        traces.append({"type": "bar", "x": categories, "y": change, "name": value})
    failed = [i for i, c in enumerate(categories) if int(data["status"].transpose(x).values[i]) != 0]
    for i in failed:
        axes.annotate("failed", (positions[i], 0.0), ha="center", va="bottom", color="red", fontsize=8)
    axes.axhline(0.0, color="black", linewidth=0.6)
    axes.set_xticks(positions, categories, rotation=15, fontsize=8)
    axes.set(xlabel=x, ylabel=f"change against {x} = {reference} (%)")
    axes.grid(axis="y", linewidth=0.3)
    axes.legend(fontsize=7)
    plot.tight_layout(rect=(0.0, 0.0, 1.0, 0.94))  # room for the title
    return plot, traces


FIGURES: dict[str, FigureKind] = {
    "lines": FigureKind(frozenset({"x", "values", "by", "x_scale", "y_scale", "x_label", "y_label"}), frozenset({"x", "values"}), draw_lines),
    "map": FigureKind(
        frozenset({"x", "y", "value", "log_color", "x_scale", "y_scale", "x_label", "y_label", "value_label"}), frozenset({"x", "y", "value"}), draw_map
    ),
    "bifurcation": FigureKind(frozenset({"x", "points", "component"}), frozenset({"x", "points"}), draw_bifurcation, grid_only=True),
    "waterfall": FigureKind(frozenset({"x", "frequency", "amplitude"}), frozenset({"x", "frequency", "amplitude"}), draw_waterfall, grid_only=True),
    "orbit": FigureKind(frozenset({"x", "array", "clearance", "panels"}), frozenset({"x", "array", "clearance"}), draw_orbit, grid_only=True),
    "sensitivity": FigureKind(frozenset({"x", "values", "reference"}), frozenset({"x", "values"}), draw_sensitivity, grid_only=True),
}


def output_names(spec) -> set[str]:
    """Every dataset variable a sweep will hold (figures may name them)."""
    from robot.analysis import ANALYSES
    from robot.sweep.store import COUNTS, TIMING

    names = {f"{a.label}_{f.name}" for a in spec.analyses for f in ANALYSES[a.name].outputs}
    names |= {s.name for s in spec.keep.arrays} if spec.keep else set()
    return names | set(COUNTS) | set(TIMING) | {"status", "t_reached"}


def _check_scales(spec, name: str, figure: dict) -> None:
    """``x_scale``/``y_scale``: one of the scales, and "log" only on an axis of positive numbers
    (a ``lines`` figure's y is its values, not an axis: left to the data)."""
    from robot.analysis.figures import AXIS_SCALES

    for key, axis_key in (("x_scale", "x"), ("y_scale", "y")):
        if key not in figure:
            continue
        if figure[key] not in AXIS_SCALES:
            raise SweepError(f"figure {name!r}: {key} must be one of {AXIS_SCALES}, got {figure[key]!r}", key=f"figure.{key}", value=figure[key])
        if axis_key not in figure:
            continue
        axis = next((a for a in spec.axes if a.name == figure.get(axis_key)), None)
        values = () if axis is None else (axis.values or (axis.low, axis.high))  # a sampled axis: its range
        numeric = bool(values) and all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in values)
        if figure[key] == "log" and not (numeric and min(values) > 0):
            raise SweepError(
                f"figure {name!r}: {key}='log' needs an axis {axis_key} of positive numbers; {figure.get(axis_key)!r} has "
                f"{', '.join(map(str, values)) or 'no values'}", key=f"figure.{key}", value=figure[key],
            )


def check_figures(spec) -> None:
    """Every ``[[figure]]`` table names a known kind, its keys, existing axes and variables."""
    axes = {a.name for a in spec.axes}
    variables = output_names(spec)
    for figure in spec.figures:
        kind = FIGURES.get(figure.get("kind")) if isinstance(figure, dict) else None
        if kind is None:
            raise SweepError(f"figure {figure!r}: kind must be one of {', '.join(FIGURES)}", key="figure.kind", value=figure.get("kind") if isinstance(figure, dict) else figure)
        name = figure["kind"]
        unknown = sorted(set(figure) - kind.keys - _COMMON)
        missing = sorted(kind.required - set(figure))
        if unknown or missing:
            bad = (unknown or missing)[0]
            raise SweepError(f"figure {name!r}: {'unknown key' if unknown else 'missing key'} {bad!r}; keys: {', '.join(sorted(kind.keys | _COMMON))}", key=f"figure.{bad}", value=figure.get(bad))
        if kind.grid_only and spec.design.kind != "grid":
            raise SweepError(f"figure {name!r} needs a grid design", key="figure.kind", value=name)
        for key in ("x", "y", "by"):
            if key in figure and figure[key] not in axes:
                raise SweepError(f"figure {name!r}: {key}={figure[key]!r} is not an axis name ({', '.join(sorted(axes))})", key=f"figure.{key}", value=figure[key])
        for key in ("value", "points", "frequency", "amplitude", "array"):
            if key in figure and figure[key] not in variables:
                raise SweepError(f"figure {name!r}: {key}={figure[key]!r} is not a variable of this sweep ({', '.join(sorted(variables))})", key=f"figure.{key}", value=figure[key])
        if "reference" in figure:
            axis = next(a for a in spec.axes if a.name == figure["x"])
            if figure["reference"] not in axis.values:
                raise SweepError(f"figure {name!r}: reference={figure['reference']!r} is not a value of axis {axis.name!r} ({', '.join(map(str, axis.values))})", key="figure.reference", value=figure["reference"])
        _check_scales(spec, name, figure)
        for value in figure.get("values", []):
            if value not in variables:
                raise SweepError(f"figure {name!r}: values has {value!r}, not a variable of this sweep", key="figure.values", value=value)
