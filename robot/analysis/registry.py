"""The analysis registry: named analyses with declared inputs, parameters and fixed-shape outputs.

An :class:`Analysis` wraps a pure function of arrays (numpy/scipy) and declares

* ``inputs``: the arrays it reads (:class:`Field`: name, dimension names, unit),
  e.g. ``t`` ``("time",)`` in s, ``signal`` ``("time",)``;
* its parameters: the function's keyword-only arguments with their defaults
  (:attr:`Analysis.parameters`), e.g. the drive ``period``;
* ``outputs``: the named scalars and arrays it returns (:class:`Field`), whose
  dimensions are either input dimensions (``time``) or fixed by the parameters
  (``point`` = ``max_points``, ``frequency`` = ``segment_length // 2 + 1``, ...):
  ``sizes(parameters)`` gives the latter, so a sweep can allocate an xarray
  Dataset (one variable per output, dims ``(*sweep_dims, *field.dims)``)
  before any run; variable-length results (Poincare points) are NaN-padded.

Units: SI; ``[signal]`` stands for the unit of the analysed signal.

An analysis that needs the simulated model itself, not only its arrays (it
integrates the mechanism again: ``lyapunov_benettin``), declares
``needs_run=True``: it is called with ``run=`` the :class:`robot.run.Run` as
well, and a sweep passes each of its inputs the run's array of the same name
unless the sweep file names another.

``register(...)`` is the decorator that adds an analysis; :data:`ANALYSES`
(re-exported by :mod:`robot.analysis`) maps names to analyses and imports the
built-in analysis modules on first use, so importing the package stays cheap.
"""

from __future__ import annotations

import importlib
import inspect
from dataclasses import dataclass
from typing import Any, Callable, Iterator, Mapping

import numpy as np

from .errors import AnalysisError, UnknownAnalysisError

#: modules of robot.analysis that register analyses (imported on the registry's first use)
BUILTIN_MODULES = ("poincare", "spectra", "statistics", "orbits", "wear", "lyapunov_rosenstein", "lyapunov_simulator")


@dataclass(frozen=True)
class Field:
    """One named array of an analysis: its dimension names (``()`` for a scalar) and unit."""

    name: str
    dims: tuple[str, ...]
    unit: str
    description: str
    optional: bool = False


@dataclass(frozen=True)
class Analysis:
    """A registered analysis (see the module docstring); call it with keyword arguments."""

    name: str
    function: Callable[..., dict[str, Any]]
    inputs: tuple[Field, ...]
    outputs: tuple[Field, ...]
    sizes: Callable[..., dict[str, int]]
    source: str
    needs_run: bool = False  # called with run= the robot.run.Run too (module docstring)

    @property
    def parameters(self) -> dict[str, Any]:
        """Keyword-only parameters of the function and their defaults (``inspect.Parameter.empty`` if required)."""
        signature = inspect.signature(self.function)
        return {p.name: p.default for p in signature.parameters.values() if p.kind is p.KEYWORD_ONLY}

    def output_shapes(self, input_sizes: Mapping[str, int], **parameters: Any) -> dict[str, tuple[int, ...]]:
        """Shape of every output for the given input dimension sizes (e.g. ``{"time": n}``) and parameters."""
        merged = {k: v for k, v in self.parameters.items() if v is not inspect.Parameter.empty}
        merged.update(parameters)
        sizes = dict(input_sizes)
        sizes.update(self.sizes(**merged))
        missing = sorted({d for f in self.outputs for d in f.dims} - sizes.keys())
        if missing:
            raise AnalysisError(f"analysis {self.name!r}: input_sizes must give the dimension(s) {missing}")
        return {f.name: tuple(sizes[d] for d in f.dims) for f in self.outputs}

    def __call__(self, **arguments: Any) -> dict[str, np.ndarray]:
        """Run on named inputs and parameters; outputs as arrays, checked against the declaration."""
        required = [f.name for f in self.inputs if not f.optional and f.name not in arguments]
        required += ["run"] if self.needs_run and "run" not in arguments else []
        if required:
            raise AnalysisError(f"analysis {self.name!r} needs the input(s) {required}")
        known = {f.name for f in self.inputs} | self.parameters.keys() | ({"run"} if self.needs_run else set())
        unknown = sorted(arguments.keys() - known)
        if unknown:
            raise AnalysisError(f"analysis {self.name!r} has no input or parameter {unknown}; known: {sorted(known)}")
        result = self.function(**arguments)
        declared = [f.name for f in self.outputs]
        if sorted(result) != sorted(declared):
            raise AnalysisError(f"analysis {self.name!r} returned {sorted(result)}, declared {sorted(declared)}")
        return {name: np.asarray(result[name]) for name in declared}


class AnalysisRegistry(Mapping[str, Analysis]):
    """Name -> :class:`Analysis`; loads :data:`BUILTIN_MODULES` on the first lookup."""

    def __init__(self, builtin_modules: tuple[str, ...]) -> None:
        self._analyses: dict[str, Analysis] = {}
        self._builtin_modules = builtin_modules
        self._loaded = False

    def _load(self) -> None:
        if not self._loaded:
            self._loaded = True
            for module in self._builtin_modules:
                importlib.import_module(f"{__package__}.{module}")

    def add(self, analysis: Analysis) -> None:
        """Register ``analysis``; AnalysisError if another function already has its name."""
        existing = self._analyses.get(analysis.name)
        if existing is not None and existing.function.__qualname__ != analysis.function.__qualname__:
            raise AnalysisError(f"an analysis named {analysis.name!r} is already registered ({existing.function.__qualname__})")
        self._analyses[analysis.name] = analysis

    def __getitem__(self, name: str) -> Analysis:
        self._load()
        try:
            return self._analyses[name]
        except KeyError:
            raise UnknownAnalysisError(f"no analysis named {name!r}; registered: {sorted(self._analyses)}") from None

    def __iter__(self) -> Iterator[str]:
        self._load()
        return iter(self._analyses)

    def __len__(self) -> int:
        self._load()
        return len(self._analyses)


ANALYSES = AnalysisRegistry(BUILTIN_MODULES)


def _no_sizes(**_: Any) -> dict[str, int]:
    return {}


def register(
    name: str,
    *,
    inputs: tuple[Field, ...],
    outputs: tuple[Field, ...],
    source: str,
    sizes: Callable[..., dict[str, int]] = _no_sizes,
    registry: AnalysisRegistry = ANALYSES,
    needs_run: bool = False,
) -> Callable[[Callable[..., dict[str, Any]]], Callable[..., dict[str, Any]]]:
    """Decorator: register the decorated function as analysis ``name`` (in ``registry``, default
    :data:`ANALYSES`) and return it unchanged; ``needs_run``: it also takes ``run`` (module docstring)."""

    def decorate(function: Callable[..., dict[str, Any]]) -> Callable[..., dict[str, Any]]:
        registry.add(Analysis(name, function, tuple(inputs), tuple(outputs), sizes, source, needs_run))
        return function

    return decorate
