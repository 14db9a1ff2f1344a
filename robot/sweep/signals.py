"""Signals of a run chosen by name: ``ARRAY`` or ``ARRAY:REDUCTION``.

``ARRAY`` is any array of a :class:`robot.io.results.Result` (``t``, ``q``,
``ee_position``, ``driving_force``, ``R1_normal_force``, ... as listed in
``robot/io/results.py``) or ``ee_deviation``: the end-effector position minus
the prescribed (ideal-mechanism) platform position at the same time, (n, 3) in m,
for platform trajectories (``robot.validation.study.ideal_positions``).

``REDUCTION`` acts on each record's row (the axes after the first):

* ``sum`` (e.g. the normal forces of a joint's contact candidates), ``norm``
  (Euclidean), ``max``, ``min``, ``maxabs``;
* ``x``, ``y``, ``z``: column 0, 1, 2;
* integers ``i`` or ``i,j,...``: those columns (``q:0,1,2``).
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from typing import Any, Callable

import numpy as np

from robot.sweep.errors import SweepError

_REDUCTIONS: dict[str, Callable[[np.ndarray], np.ndarray]] = {
    "sum": lambda rows: rows.sum(axis=1),
    "norm": lambda rows: np.linalg.norm(rows, axis=1),
    "max": lambda rows: rows.max(axis=1),
    "min": lambda rows: rows.min(axis=1),
    "maxabs": lambda rows: np.abs(rows).max(axis=1),
}
_COMPONENTS = {"x": 0, "y": 1, "z": 2}
_SELECTOR = re.compile(r"^([A-Za-z_][A-Za-z0-9_]*)(?::([a-z]+|\d+(?:,\d+)*))?$")
DERIVED = ("ee_deviation",)


@dataclass(frozen=True)
class Selector:
    """A parsed signal name: the array and what to take of each record's row."""

    text: str
    array: str
    reduction: str | None

    @property
    def name(self) -> str:
        """A variable-name form: ``R1_normal_force:sum`` -> ``R1_normal_force_sum``."""
        return self.text.replace(":", "_").replace(",", "_")

    def __call__(self, arrays: Callable[[str], np.ndarray]) -> np.ndarray:
        values = np.asarray(arrays(self.array), dtype=float)
        if self.reduction is None:
            return values
        rows = values.reshape(len(values), -1)
        if self.reduction in _REDUCTIONS:
            return _REDUCTIONS[self.reduction](rows)
        columns = [_COMPONENTS[c] if c in _COMPONENTS else int(c) for c in self.reduction.split(",")]
        if max(columns) >= rows.shape[1]:
            raise SweepError(f"signal {self.text!r}: {self.array} has {rows.shape[1]} column(s)", key=self.text, value=self.reduction)
        return rows[:, columns[0]] if len(columns) == 1 else rows[:, columns]


def parse_selector(text: Any, where: str) -> Selector:
    """Check the syntax of a signal name (its array is checked against a run, by the probe)."""
    match = _SELECTOR.match(text) if isinstance(text, str) else None
    if match is None:
        raise SweepError(f"{where}: signal {text!r} must be ARRAY or ARRAY:REDUCTION (e.g. 'R1_normal_force:sum', 'ee_position:x')", key=where, value=text)
    array, reduction = match.groups()
    if reduction is not None and not (reduction in _REDUCTIONS or reduction in _COMPONENTS or reduction[0].isdigit()):
        known = ", ".join([*_REDUCTIONS, *_COMPONENTS, "i", "i,j,..."])
        raise SweepError(f"{where}: signal {text!r}: reduction {reduction!r} is not known; use one of {known}", key=where, value=text)
    return Selector(text, array, reduction)


class RunSignals:
    """The arrays of one run, for selectors: the result's arrays and the derived ``ee_deviation``."""

    def __init__(self, result, run) -> None:
        self.result = result
        self.run = run
        self._derived: dict[str, np.ndarray] = {}

    def __call__(self, name: str) -> np.ndarray:
        if name in self.result.arrays:
            return self.result.arrays[name]
        if name == "ee_deviation":
            if "ee_deviation" not in self._derived:
                self._derived[name] = self._ee_deviation()
            return self._derived[name]
        raise SweepError(
            f"signal array {name!r} is not an array of scene {self.result.scene!r}'s results; arrays: {', '.join([*self.result.keys(), *DERIVED])}",
            key=name,
            value=name,
        )

    def _ee_deviation(self) -> np.ndarray:
        if self.run.layout is None:
            raise SweepError(
                f"signal 'ee_deviation' needs a platform trajectory (the prescribed pose); scene {self.result.scene!r} drives its joints",
                key="ee_deviation",
                value=None,
            )
        from robot.validation.study import ideal_positions

        return self.result["ee_position"] - ideal_positions(self.run, self.result.t)
