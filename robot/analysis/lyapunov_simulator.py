"""``lyapunov_benettin``: the largest Lyapunov exponent of a run, by Benettin's method through the simulator.

The registered, per-run form of
:func:`robot.analysis.lyapunov_benettin.benettin_exponent` on
:class:`robot.analysis.simulator_flow.SimulatorFlow` (definitions, state
scaling, projection on the closures and the contact state: those modules'
docstrings). The pair of trajectories starts from a state of the run: its
final record (default), or the first record at or after ``t_start``; from
there, ``transient_time`` more seconds are simulated alone, then
``n_alignment`` discarded and ``n_intervals`` averaged intervals of
``renormalisation_time`` (for a driven mechanism: the drive period, or a
multiple) with a companion at scaled distance ``separation``.

``separation`` must lie well above the solver's error (it is refused below
:data:`MIN_SEPARATION_OVER_RTOL` x the scene's ``rtol``: the two trajectories'
integration errors would be measured instead of their divergence) and well
below the attractor's size over one interval (``d0 e^{lambda tau} << 1``).
Needs the run (``needs_run``): it integrates the mechanism again, costing
about ``2 (n_alignment + n_intervals) renormalisation_time`` of simulated time.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from .errors import AnalysisError, require_count, require_non_negative, require_positive
from .registry import Field, register

if TYPE_CHECKING:  # pragma: no cover
    from robot.run import Run

#: ``separation`` must be at least this multiple of the scene's relative tolerance
MIN_SEPARATION_OVER_RTOL = 10.0


def start_index(t: np.ndarray, t_start: float | None) -> int:
    """The record the pair starts from: the last one (None), else the first with ``t >= t_start``."""
    t = np.asarray(t, dtype=float)
    if t_start is None:
        return len(t) - 1
    after = np.flatnonzero(t >= t_start)
    if after.size == 0:
        raise AnalysisError(f"t_start={t_start!r} is after the run's last record (t = {t[-1]:g} s); valid range [{t[0]:g}, {t[-1]:g}]")
    return int(after[0])


@register(
    "lyapunov_benettin",
    inputs=(
        Field("t", ("time",), "s", "record times of the run"),
        Field("q", ("time", "q_coordinate"), "[q]", "configuration per record (the run's q)"),
        Field("v", ("time", "v_coordinate"), "[v]", "velocity per record (the run's v)"),
        Field("onset_rates", ("time", "candidate"), "m/s", "contact state per record (the run's onset_rates)", optional=True),
    ),
    outputs=(
        Field("exponent", (), "1/s", "largest Lyapunov exponent estimate"),
        Field("standard_error", (), "1/s", "standard error of the exponent by batch means (NaN below 4 intervals)"),
        Field("running", ("interval",), "1/s", "estimate after each averaged interval"),
        Field("log_stretch", ("interval",), "1", "ln(d_k / d0) of each averaged interval"),
        Field("t_start", (), "s", "time of the record the pair started from"),
        Field("length_scale", (), "m", "length scale L of the distance"),
        Field("time_scale", (), "s", "time scale T of the distance"),
    ),
    sizes=lambda *, n_intervals=50, **_: {"interval": n_intervals},
    source="Benettin, Galgani, Giorgilli & Strelcyn, Meccanica 15 (1980) 9-20; through the simulator (simulator_flow)",
    needs_run=True,
)
def lyapunov_benettin(
    run: "Run",
    t,
    q,
    v,
    onset_rates=None,
    *,
    renormalisation_time: float,
    n_intervals: int = 50,
    separation: float = 1e-6,
    n_alignment: int = 5,
    t_start: float | None = None,
    transient_time: float = 0.0,
    seed: int = 0,
    length_scale: float | None = None,
    time_scale: float | None = None,
) -> dict[str, np.ndarray]:
    """Benettin's exponent of ``run`` from one of its records (module docstring)."""
    from robot.analysis.lyapunov_benettin import benettin_exponent
    from robot.analysis.simulator_flow import SimulatorFlow

    tau = require_positive("renormalisation_time", renormalisation_time)
    n_intervals = require_count("n_intervals", n_intervals)
    d0 = require_positive("separation", separation)
    rtol = run.scene.solver.rtol
    if d0 < MIN_SEPARATION_OVER_RTOL * rtol:
        raise AnalysisError(
            f"separation={separation!r} is below {MIN_SEPARATION_OVER_RTOL:g} x the solver's rtol = {rtol:g}: the integration "
            f"error would be measured, not the divergence; valid range [{MIN_SEPARATION_OVER_RTOL * rtol:g}, 1)"
        )
    flow = SimulatorFlow(run, length_scale=length_scale, time_scale=time_scale)
    index = start_index(t, None if t_start is None else require_non_negative("t_start", t_start))
    state = flow.from_result(t, q, v, onset_rates, index)
    t0 = float(np.asarray(t)[index])
    result = benettin_exponent(
        flow, state, renormalisation_time=tau, n_intervals=n_intervals, separation=d0, t0=t0,
        transient_time=transient_time, n_alignment=n_alignment, seed=seed,
    )
    return {
        "exponent": result.exponent,
        "standard_error": result.standard_error,
        "running": result.running,
        "log_stretch": result.log_stretch,
        "t_start": t0,
        "length_scale": flow.length_scale,
        "time_scale": flow.time_scale,
    }
