"""Sensitivity of a sweep's outputs to a categorical axis (a contact law, a model choice).

For an output y and the runs along axis ``x`` (the other axes fixed), the
change of run i against the reference run r (a value of ``x``, by default its
first: the scene's default law) is

    change_i = 100 (y_i - y_r) / |y_r|   (percent)

A failed run (``status`` -1) has NaN outputs, so its change is NaN: it is shown
as failed, never as "no change". :func:`sensitivity_table` writes the outputs
and their changes as a Markdown table (with each run's status, cause and CPU
time), :func:`relative_change` feeds the ``sensitivity`` figure kind
(:mod:`robot.sweep.figures`).
"""

from __future__ import annotations

from typing import Sequence

import numpy as np

from robot.sweep.errors import SweepError


#: ``status`` of a run that was not run (yet) (robot.sweep.store)
_NOT_RUN = -2


def _missing(status: int) -> str:
    """What a table shows instead of a NaN output."""
    return "not run" if status == _NOT_RUN else "failed"


def _reference_index(data, x: str, reference) -> int:
    values = [str(v) for v in data[x].values]
    chosen = values[0] if reference is None else str(reference)
    if chosen not in values:
        raise SweepError(f"reference {x}={reference!r} is not a value of axis {x!r} ({', '.join(values)})", key="reference", value=reference)
    return values.index(chosen)


def relative_change(data, variable: str, x: str, reference=None) -> np.ndarray:
    """Percent change of ``data[variable]`` along axis ``x`` against the run at ``x = reference``
    (``data`` has ``x`` as its only run dimension; NaN where a run failed)."""
    values = np.asarray(data[variable].transpose(x, ...).values, dtype=float)
    base = values[_reference_index(data, x, reference)]
    if not np.isfinite(base) or base == 0.0:
        raise SweepError(f"{variable} of the reference run {x}={reference!r} is {base!r}; a change needs a finite, non-zero reference", key=variable, value=base)
    return 100.0 * (values - base) / abs(base)


def sensitivity_table(data, x: str, columns: Sequence[tuple[str, str, float]], reference=None) -> str:
    """A Markdown table, one row per value of axis ``x``: each column ``(variable, heading, scale)``
    as ``value * scale`` and its percent change against the reference, then the status (with the
    cause of a failed run) and the CPU time (whole run, and its integration if stored)."""
    index = _reference_index(data, x, reference)
    timed = "integration_cpu_time" in data
    header = [x, *(heading for _, heading, _ in columns), "status", "CPU (s): run / integration" if timed else "CPU (s)"]
    rows = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    changes = {variable: relative_change(data, variable, x, reference) for variable, _, _ in columns}
    for i, category in enumerate(data[x].values):
        cells = [f"`{category}`"]
        status = int(data["status"].transpose(x).values[i])
        for variable, _, scale in columns:
            value = float(data[variable].transpose(x, ...).values[i]) * scale
            cells.append(_missing(status) if not np.isfinite(value) else f"{value:.4g}" if i == index else f"{value:.4g} ({changes[variable][i]:+.1f} %)")
        cause = str(data["cause"].transpose(x).values[i])
        cells.append("ok" if status == 0 else "not run" if status == _NOT_RUN else f"{status}: {cause}")
        cpu = f"{float(data['cpu_time'].transpose(x).values[i]):.1f}"
        cells.append(f"{cpu} / {float(data['integration_cpu_time'].transpose(x).values[i]):.1f}" if timed else cpu)
        rows.append("| " + " | ".join(cells) + " |")
    return "\n".join(rows)


def grid_table(data, variable: str, rows: str, columns: str, scale: float = 1.0) -> str:
    """A Markdown table of ``data[variable] * scale`` over two axes (one row per value of ``rows``),
    "failed" / "not run" where a run failed / was not run."""
    values = np.asarray(data[variable].transpose(rows, columns).values, dtype=float) * scale
    status = np.asarray(data["status"].transpose(rows, columns).values)
    lines = [f"| {rows} \\ {columns} | " + " | ".join(f"`{c}`" for c in data[columns].values) + " |", "|---" * (values.shape[1] + 1) + "|"]
    for name, row, row_status in zip(data[rows].values, values, status):
        lines.append(f"| `{name}` | " + " | ".join(_missing(s) if not np.isfinite(v) else f"{v:.4g}" for v, s in zip(row, row_status)) + " |")
    return "\n".join(lines)
