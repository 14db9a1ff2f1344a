"""What a run writes: the records (states at chosen instants), the output-time schedule and the :class:`Trajectory`.

Every record is ``(t, y, onset rates, kind)``, the onset rates being the contact
state the record's forces are evaluated with (:mod:`clearance_contact`,
Lankarani-Nikravesh ``ddelta0``). The kinds (``record_kind`` in the result file,
:mod:`robot.io.results`, ``docs/dynamics.md``):

* ``RECORD_STEP``: the end of an accepted step;
* ``RECORD_ONSET``: a contact onset, where a step was cut and the solver restarted;
* ``RECORD_PEAK``: a penetration maximum inside a step;
* ``RECORD_START``: the initial state;
* ``RECORD_OUTPUT``: a requested output time, from the step's dense output;
* ``RECORD_FORCE_PEAK``: a candidate's normal-force maximum over an impact's
  compression phase (:mod:`robot.integration.force_peaks`).

Records are kept in the order they are written (a step's inner records before
the step's end record), not sorted by time.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Callable, Iterator

import numpy as np

SUCCESS, FAILED = 0, -1

RECORD_STEP, RECORD_ONSET, RECORD_PEAK, RECORD_START, RECORD_OUTPUT = 0, 1, 2, 3, 4
#: the maximum of a candidate's normal force over an impact's compression phase (see robot.integration.force_peaks)
RECORD_FORCE_PEAK = 5
#: record kinds at which a solver step starts or ends (the others lie inside a step)
BOUNDARY_KINDS = (RECORD_STEP, RECORD_ONSET, RECORD_START)


@dataclass
class Trajectory:
    """Raw result of a run: recorded states, event log, status and counts (like ``scipy.integrate.solve_ivp``)."""

    status: int
    message: str
    cause: str | None
    t_end: float
    t: np.ndarray
    y: np.ndarray  # (n, state size); the Lagrange state is q, v, actuator work, contact work
    onset_rates: np.ndarray  # (n, n_candidates): contact state used at each record
    kind: np.ndarray  # (n,) 0 step, 1 contact onset, 2 penetration maximum, 3 start, 4 output grid, 5 force maximum
    n_steps: int = 0
    n_rejected: int = 0
    n_rhs: int = 0
    n_events: int = 0
    n_restarts: int = 0
    n_jacobians: int = 0  # Jacobians of implicit methods, as each solver counts them (LSODA: its LU factorisations)
    cpu_time: float = 0.0
    wall_time: float = 0.0
    events: list = field(default_factory=list)  # (t, candidate, kind, value): "onset" (approach rate), "peak" (depth), "force_peak" (N)
    n_hidden_contacts: int = 0  # onsets found inside a step whose ends are both out of contact
    max_onset_overshoot: float = 0.0  # deepest penetration (m) at the end of a step cut back to a contact onset

    @property
    def success(self) -> bool:
        return self.status == SUCCESS


class Records:
    """The records of one run, in the order written; ``force`` keeps the normal forces the loop probed (else None).

    A boundary record (:data:`BOUNDARY_KINDS`) always carries its forces: the
    force-peak search walks back over them (:mod:`robot.integration.force_peaks`),
    through :meth:`boundaries`.
    """

    def __init__(self, n_candidates: int) -> None:
        self.t: list[float] = []
        self.y: list[np.ndarray] = []
        self.onset: list[np.ndarray] = []
        self.kind: list[int] = []
        self.force: list[np.ndarray | None] = []
        self._boundary_rows: list[int] = []  # indices of the boundary records
        # their index, time and forces as arrays, filled in their first `_converted` rows by `boundaries`
        self._boundary_index = np.empty(0, dtype=np.intp)
        self._boundary_t = np.empty(0)
        self._boundary_force = np.empty((0, n_candidates))
        self._converted = 0

    def add(self, t: float, y: np.ndarray, kind: int, onset_rates: np.ndarray, forces: np.ndarray | None = None) -> None:
        if kind in BOUNDARY_KINDS:
            if forces is None:
                raise ValueError(f"a boundary record (kind {kind}) needs the normal forces probed at its state")
            self._boundary_rows.append(len(self.t))
        self.t.append(t)
        self.y.append(np.array(y))
        self.onset.append(onset_rates.copy())
        self.kind.append(kind)
        self.force.append(forces)

    def __len__(self) -> int:
        return len(self.t)

    def boundaries(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The boundary records in the order written: (record index, t, normal forces (rows: records)), views.

        The arrays are extended by the records added since the last call (a few
        hundred calls a run: cheaper than writing array rows at every step).
        """
        rows, done = self._boundary_rows, self._converted
        total = len(rows)
        if total > done:
            if total > self._boundary_t.shape[0]:
                capacity = max(2 * self._boundary_t.shape[0], total)
                for name in ("_boundary_index", "_boundary_t", "_boundary_force"):
                    old = getattr(self, name)
                    grown = np.empty((capacity,) + old.shape[1:], dtype=old.dtype)
                    grown[:done] = old[:done]
                    setattr(self, name, grown)
            new = rows[done:]
            self._boundary_index[done:total] = new
            self._boundary_t[done:total] = [self.t[i] for i in new]
            self._boundary_force[done:total] = [self.force[i] for i in new]
            self._converted = total
        return self._boundary_index[:total], self._boundary_t[:total], self._boundary_force[:total]

    def arrays(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """(t, y, onset rates, kind) as arrays."""
        return (
            np.array(self.t),
            np.array(self.y),
            np.array(self.onset).reshape(len(self.t), self._boundary_force.shape[1]),
            np.array(self.kind, dtype=np.int8),
        )


class OutputTimes:
    """The times at which the state is also recorded (``RECORD_OUTPUT``), from the dense output of the step containing them.

    :meth:`grid`: every multiple ``k * step`` (k >= 1) of an output step, the last
    one within ``1e-12 step`` of a step end taken at that end (so the end of the
    run is on the grid despite rounding); :meth:`at`: given times (those before
    the start are skipped). ``taken`` lists the indices recorded.
    """

    def __init__(self, time_of: Callable[[int], float], count: float, tolerance: float):
        self._time_of, self._count, self._tolerance = time_of, count, tolerance
        self.index = 0
        self.taken: list[int] = []
        self._next = self._time_at_index()

    @classmethod
    def grid(cls, step: float) -> "OutputTimes":
        return cls(lambda k: (k + 1) * step, math.inf, 1e-12 * step)

    @classmethod
    def at(cls, times: np.ndarray) -> "OutputTimes":
        times = np.asarray(times, dtype=float)
        return cls(lambda k: float(times[k]), len(times), 0.0)

    def _time_at_index(self) -> float:
        """The output time at ``index``; NaN when none is left (it is never due)."""
        return self._time_of(self.index) if self.index < self._count else math.nan

    def due(self, t_to: float) -> bool:
        """Is an output time at or before ``t_to`` still to be recorded?"""
        return self._next <= t_to + self._tolerance

    def take(self, t_from: float, t_to: float) -> Iterator[float]:
        """The output times in [t_from, t_to] not yet recorded (each at most ``t_to``); earlier ones are skipped."""
        while self.due(t_to):
            t_out = min(self._next, t_to)
            if t_out >= t_from:
                self.taken.append(self.index)
                yield t_out
            self.index += 1
            self._next = self._time_at_index()
