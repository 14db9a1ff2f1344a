"""Design of a sweep: the points (scene key values) an axis list spans.

Two families:

* **grid**: the Cartesian product of the axes' value lists (``values``, or
  ``linear`` / ``log`` ranges: ``numpy.linspace`` / ``numpy.geomspace``); the
  dataset has one dimension per axis, its coordinate the axis values;
* **sampled**: ``latin_hypercube`` or ``sobol`` points of ``scipy.stats.qmc``
  in the unit cube, scaled to each axis's ``range`` (linearly, or linearly in
  ``log10`` for ``scale = "log"``); the dataset has one ``sample`` dimension
  and each axis is a coordinate along it. The generator is seeded
  (``seed``), so a sweep file always gives the same points, bit for bit.
  Sobol points are scrambled (Owen); their balance properties need a power-of-2
  count (Sobol', 1967; Owen, 1998), which is therefore required.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass
from typing import Any

import numpy as np

GRID = "grid"
SAMPLED = ("latin_hypercube", "sobol")
DESIGNS = (GRID, *SAMPLED)
SAMPLE_DIM = "sample"


@dataclass(frozen=True)
class Axis:
    """One swept scene key: ``key`` (dotted path), ``name`` (dataset coordinate),
    ``values`` (grid designs: numbers, strings such as law names, booleans) or
    ``low``/``high``/``scale`` (sampled designs). ``linked`` keys take the same value
    as ``key`` at every point (one dissipation model for every clearance joint)."""

    key: str
    name: str
    values: tuple[Any, ...] = ()
    low: float = float("nan")
    high: float = float("nan")
    scale: str = "linear"
    linked: tuple[str, ...] = ()

    @property
    def keys(self) -> tuple[str, ...]:
        """Every scene key this axis sets."""
        return (self.key, *self.linked)


@dataclass(frozen=True)
class Design:
    """The runs of a sweep: dataset dimensions, their sizes, coordinates, and one point per run.

    ``points[i]`` maps each axis key to its value for the run at flat index ``i``
    (C order over ``shape``); ``coords`` maps a coordinate name to ``(dims, values)``.
    """

    kind: str
    dims: tuple[str, ...]
    shape: tuple[int, ...]
    coords: dict[str, tuple[tuple[str, ...], np.ndarray]]
    points: tuple[dict[str, Any], ...]

    @property
    def size(self) -> int:
        return len(self.points)

    def index(self, flat: int) -> tuple[int, ...]:
        """The dataset index of run ``flat``."""
        return tuple(int(i) for i in np.unravel_index(flat, self.shape))


def python_value(value: Any) -> Any:
    """A numpy scalar as the Python number TOML and JSON know (other values unchanged)."""
    return value.item() if isinstance(value, np.generic) else value


def grid_design(axes: tuple[Axis, ...]) -> Design:
    coords = {a.name: ((a.name,), np.asarray(a.values)) for a in axes}
    points = tuple({k: python_value(v) for a, v in zip(axes, combo) for k in a.keys} for combo in itertools.product(*(a.values for a in axes)))
    return Design(GRID, tuple(a.name for a in axes), tuple(len(a.values) for a in axes), coords, points)


def unit_samples(kind: str, dimension: int, count: int, seed: int) -> np.ndarray:
    """``count`` points of the unit cube [0, 1)^dimension (``scipy.stats.qmc``, seeded)."""
    from scipy.stats import qmc

    rng = np.random.default_rng(seed)
    engine = qmc.LatinHypercube(d=dimension, rng=rng) if kind == "latin_hypercube" else qmc.Sobol(d=dimension, scramble=True, rng=rng)
    return engine.random(count)


def sampled_design(kind: str, axes: tuple[Axis, ...], count: int, seed: int) -> Design:
    unit = unit_samples(kind, len(axes), count, seed)
    columns = {}
    for j, axis in enumerate(axes):
        if axis.scale == "log":
            low, high = np.log10(axis.low), np.log10(axis.high)
            columns[axis.name] = 10.0 ** (low + unit[:, j] * (high - low))
        else:
            columns[axis.name] = axis.low + unit[:, j] * (axis.high - axis.low)
    coords = {SAMPLE_DIM: ((SAMPLE_DIM,), np.arange(count))}
    coords.update({a.name: ((SAMPLE_DIM,), columns[a.name]) for a in axes})
    points = tuple({k: float(columns[a.name][i]) for a in axes for k in a.keys} for i in range(count))
    return Design(kind, (SAMPLE_DIM,), (count,), coords, points)
