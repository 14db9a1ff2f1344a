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
    as ``value * scale`` and its percent change against the reference, then status and CPU time."""
    index = _reference_index(data, x, reference)
    header = [x, *(heading for _, heading, _ in columns), "status", "CPU (s)"]
    rows = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    changes = {variable: relative_change(data, variable, x, reference) for variable, _, _ in columns}
    for i, category in enumerate(data[x].values):
        cells = [f"`{category}`"]
        for variable, _, scale in columns:
            value = float(data[variable].transpose(x, ...).values[i]) * scale
            cells.append("failed" if not np.isfinite(value) else f"{value:.4g}" if i == index else f"{value:.4g} ({changes[variable][i]:+.1f} %)")
        status = int(data["status"].values[i])
        cause = str(data["cause"].values[i])
        cells.append("ok" if status == 0 else f"{status}: {cause}")
        cells.append(f"{float(data['cpu_time'].values[i]):.1f}")
        rows.append("| " + " | ".join(cells) + " |")
    return "\n".join(rows)
