"""The sweep's pictures: one PNG per ``[[figure]]`` and one interactive HTML report.

The report is a single HTML file that opens offline: plotly's JavaScript is
embedded once, inline (no CDN, no server), followed by every figure and a
summary of the runs (status counts, failures with their causes and messages).
"""

from __future__ import annotations

import html
from pathlib import Path

import numpy as np

from robot.io.atomic import atomic_write_text
from robot.sweep.figures import FIGURES


def _clearance_of(spec, figure: dict):
    """Clearance (m) of a run for the orbit figure: the swept value if its key is an axis, else the base scene's."""
    from robot.scene.overrides import document_value

    key = figure["clearance"]
    axis = next((a.name for a in spec.axes if key in a.keys), None)

    def clearance(selection: dict) -> float:
        if axis is not None and axis in selection:
            return float(selection[axis])
        return float(document_value(spec.base.document, key))

    return clearance


def plotly_figure(title: str, traces: list[dict]):
    import plotly.graph_objects as go

    figure = go.Figure()
    for trace in traces:
        kind, name = trace["type"], trace["name"]
        if kind == "line":
            figure.add_trace(go.Scatter(x=trace["x"], y=trace["y"], mode="lines+markers", name=name))
        elif kind in ("heatmap", "surface"):
            figure.add_trace(go.Heatmap(x=trace["x"], y=trace["y"], z=trace["z"], colorbar={"title": name}, name=name))
        elif kind == "scatter_map":
            figure.add_trace(go.Scatter(x=trace["x"], y=trace["y"], mode="markers", marker={"color": trace["z"], "colorbar": {"title": name}, "showscale": True}, name=name))
        elif kind == "points":
            figure.add_trace(go.Scattergl(x=trace["x"], y=trace["y"], mode="markers", marker={"size": 3, "color": "black"}, name=name))
        elif kind == "orbit":
            figure.add_trace(go.Scatter(x=trace["x"], y=trace["y"], mode="lines", name=name))
        elif kind == "bar":
            figure.add_trace(go.Bar(x=trace["x"], y=trace["y"], name=name))
    if any(t["type"] == "orbit" for t in traces):
        angle = np.linspace(0, 2 * np.pi, 200)
        figure.add_trace(go.Scatter(x=np.cos(angle), y=np.sin(angle), mode="lines", line={"dash": "dash", "color": "gray"}, name="clearance"))
        figure.update_yaxes(scaleanchor="x")
    figure.update_layout(title=title, height=480)
    return figure


def _summary(dataset) -> str:
    damage = dataset.attrs.get("damaged", [])
    damaged = f"<p style='color:#b00'>damaged store: these values cannot be read and are shown as missing: {html.escape('; '.join(damage))}</p>" if damage else ""
    return damaged + _runs_summary(dataset)


def _runs_summary(dataset) -> str:
    status = dataset["status"].values.ravel()
    causes = dataset["cause"].values.ravel()
    messages = dataset["message"].values.ravel()
    rows = "".join(
        f"<tr><td>{i}</td><td>{html.escape(str(causes[i]))}</td><td>{html.escape(str(messages[i]))}</td></tr>" for i in np.flatnonzero(status == -1)[:200]
    )
    table = f"<table><tr><th>run</th><th>cause</th><th>message</th></tr>{rows}</table>" if rows else ""
    return (
        f"<p>{status.size} runs: {int(np.sum(status == 0))} reached the end, {int(np.sum(status == -1))} failed, "
        f"{int(np.sum(status == -2))} not run.</p>{table}"
    )


def draw_all(spec, store: Path, out: Path) -> list[Path]:
    """Draw every figure of ``spec`` (PNG in ``out/figures``) and ``out/report.html``; returns the paths."""
    return draw_report(spec, store, out)[0]


def draw_report(spec, store: Path, out: Path) -> tuple[list[Path], list[str]]:
    """:func:`draw_all`, and the store's values that could not be read (a damaged store: drawn as missing
    values and listed in the report, "ARRAY at run(s) ..."; empty for a sound store)."""
    from robot.analysis.figures import save_png
    from robot.sweep.store import load_dataset

    dataset = load_dataset(store)
    out = Path(out)
    written, sections, first = [], [], True
    for i, figure in enumerate(spec.figures):
        kind = FIGURES[figure["kind"]]
        extra = (_clearance_of(spec, figure),) if figure["kind"] == "orbit" else ()
        plot, traces = kind.draw(dataset, figure, out, *extra)
        title = figure.get("title", f"{figure['kind']}: {figure.get('value') or figure.get('points') or figure.get('amplitude') or figure.get('array') or ', '.join(figure.get('values', []))}")
        plot.suptitle(title, fontsize=9)
        written.append(save_png(plot, out / "figures" / f"{i:02d}_{figure['kind']}.png"))
        sections.append(plotly_figure(title, traces).to_html(full_html=False, include_plotlyjs="inline" if first else False))
        first = False
    axes = ", ".join(f"{a.name} ({', '.join(a.keys)})" for a in spec.axes)
    page = (
        f"<!DOCTYPE html><html><head><meta charset='utf-8'><title>sweep {html.escape(spec.name)}</title>"
        "<style>body{font-family:sans-serif;margin:2em} table{border-collapse:collapse} td,th{border:1px solid #ccc;padding:2px 6px;font-size:12px}</style>"
        f"</head><body><h1>Sweep {html.escape(spec.name)}</h1><p>scene {html.escape(spec.base.name)}, t_end {spec.t_end:g} s, "
        f"{spec.design.kind} design over {html.escape(axes)}; store {html.escape(str(store))}</p>{_summary(dataset)}{''.join(sections)}</body></html>"
    )
    written.append(atomic_write_text(out / "report.html", page))
    return written, list(dataset.attrs.get("damaged", []))
