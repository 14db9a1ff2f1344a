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
        merged = {**self.parameter_defaults, **parameters}
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
        if not isinstance(result, Mapping):
            raise AnalysisError(f"analysis {self.name!r} returned a {type(result).__name__}; it must return a dict of its outputs {[f.name for f in self.outputs]}")
        declared = [f.name for f in self.outputs]
        if sorted(result) != sorted(declared):
            raise AnalysisError(f"analysis {self.name!r} returned {sorted(result)}, declared {sorted(declared)}")
        outputs = {name: np.asarray(result[name]) for name in declared}
        self.check_output_shapes(outputs, arguments)
        return outputs

    def check_output_shapes(self, outputs: Mapping[str, np.ndarray], arguments: Mapping[str, Any]) -> None:
        """AnalysisError naming the output whose shape is not the declared one for these inputs and parameters.

        Input dimensions are sized by the arrays given (an axis whose size is
        known from no input is not checked), the others by ``sizes``.
        """
        input_sizes: dict[str, int] = {}
        for field in self.inputs:
            shape = np.shape(arguments[field.name]) if field.name in arguments and field.dims else ()
            if len(shape) == len(field.dims):
                input_sizes.update((dim, size) for dim, size in zip(field.dims, shape) if dim not in input_sizes)
        parameters = {k: v for k, v in arguments.items() if k in self.parameters}
        sizes = {**input_sizes, **self.sizes(**{**self.parameter_defaults, **parameters})}
        for field in self.outputs:
            shape = outputs[field.name].shape
            expected = tuple(sizes.get(dim) for dim in field.dims)
            if len(shape) != len(expected) or any(size is not None and size != n for size, n in zip(expected, shape)):
                shown = tuple("?" if size is None else size for size in expected)
                raise AnalysisError(
                    f"analysis {self.name!r}: output {field.name!r} has shape {shape}, declared {shown} (dims {field.dims}): "
                    "return arrays of the declared shape (NaN-padded for fewer values) or fix the declaration's sizes",
                    key=field.name,
                    value=shape,
                )

    @property
    def parameter_defaults(self) -> dict[str, Any]:
        """The keyword-only parameters that have a default, with it."""
        return {k: v for k, v in self.parameters.items() if v is not inspect.Parameter.empty}


class AnalysisRegistry(Mapping[str, Analysis]):
    """Name -> :class:`Analysis`; loads :data:`BUILTIN_MODULES` on the first lookup."""

    def __init__(self, builtin_modules: tuple[str, ...]) -> None:
        self._analyses: dict[str, Analysis] = {}
        self._builtin_modules = builtin_modules
        self._loaded = False
        self._loading = False

    def _load(self) -> None:
        """Import the built-in modules once (their registrations re-enter here and return at once).

        ``_loaded`` is set only when every import succeeded: after a failed one the
        next lookup tries again (and raises the same error) rather than answering
        with half the built-ins.
        """
        if self._loaded or self._loading:
            return
        self._loading = True
        try:
            for module in self._builtin_modules:
                importlib.import_module(f"{__package__}.{module}")
            self._loaded = True
        finally:
            self._loading = False

    def add(self, analysis: Analysis) -> None:
        """Register ``analysis`` (built-ins loaded first); AnalysisError if another function already has its name
        or the declaration breaks the contract (:func:`check_declaration`).

        The same function registered again (the same object, or the same module and
        name: a module reloaded) replaces the old registration.
        """
        self._load()
        existing = self._analyses.get(analysis.name)
        if existing is not None and _origin(existing.function) != _origin(analysis.function):
            raise AnalysisError(
                f"an analysis named {analysis.name!r} is already registered ({'.'.join(_origin(existing.function))}); "
                f"register {'.'.join(_origin(analysis.function))} under another name",
                key="name",
                value=analysis.name,
            )
        check_declaration(analysis)
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


def _origin(function: Callable[..., Any]) -> tuple[str, str]:
    """Where a function is defined: its module and qualified name (equal for a reloaded module's function)."""
    return getattr(function, "__module__", None) or "?", getattr(function, "__qualname__", None) or repr(function)


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


def check_declaration(analysis: Analysis) -> None:
    """AnalysisError naming the analysis and the first part of its declaration that breaks the contract.

    The contract (``docs/analyses.md``, "Adding an analysis"): a name, a function
    taking every input by name and its parameters as keyword-only arguments,
    ``inputs`` and ``outputs`` tuples of :class:`Field` with distinct names and
    string dimension names, a callable ``sizes`` giving every output dimension
    that is no input dimension.
    """
    where = f"analysis {analysis.name!r}"
    if not isinstance(analysis.name, str) or not analysis.name.isidentifier():
        raise AnalysisError(f"analysis name {analysis.name!r} must be an identifier (letters, digits, _)", key="name", value=analysis.name)
    for role in ("inputs", "outputs"):
        _check_fields(where, role, getattr(analysis, role))
    if not callable(analysis.function):
        raise AnalysisError(f"{where}: register() decorates a function, got {analysis.function!r}", key="function", value=analysis.function)
    if not callable(analysis.sizes):
        raise AnalysisError(f"{where}: sizes={analysis.sizes!r} must be a function of the parameters returning {{dim: size}}", key="sizes", value=analysis.sizes)
    _check_signature(where, analysis)
    _check_output_dims(where, analysis)


def _check_fields(where: str, role: str, fields: tuple) -> None:
    """Every entry a :class:`Field` with string dimension names, the names distinct."""
    for field in fields:
        if not isinstance(field, Field):
            raise AnalysisError(f"{where}: {role} must be Field(name, dims, unit, description) entries, got {field!r}", key=role, value=field)
        if not (isinstance(field.name, str) and isinstance(field.dims, tuple) and all(isinstance(d, str) for d in field.dims)):
            raise AnalysisError(f"{where}: {role} field {field.name!r} needs a string name and a tuple of dimension names, got dims={field.dims!r}", key=role, value=field)
    names = [field.name for field in fields]
    if len(set(names)) != len(names):
        raise AnalysisError(f"{where}: {role} names {names} are not distinct", key=role, value=names)


def _check_signature(where: str, analysis: Analysis) -> None:
    """The function takes every input (and ``run``) by name; its other arguments are keyword-only."""
    try:
        parameters = inspect.signature(analysis.function).parameters
    except (TypeError, ValueError):  # not introspectable: not checked
        return
    takes_any = any(p.kind is p.VAR_KEYWORD for p in parameters.values())
    named = {f.name for f in analysis.inputs} | ({"run"} if analysis.needs_run else set())
    missing = sorted(n for n in named if n not in parameters and not takes_any)
    if missing:
        raise AnalysisError(f"{where}: the function does not take the input(s) {missing}", key="inputs", value=missing)
    positional = [p.name for p in parameters.values() if p.name not in named and p.kind in (p.POSITIONAL_ONLY, p.POSITIONAL_OR_KEYWORD)]
    if positional:
        raise AnalysisError(
            f"{where}: the function's argument(s) {positional} are neither inputs nor keyword-only parameters: "
            "declare them as inputs or put them after a '*' (parameters are keyword-only)",
            key="function",
            value=positional,
        )


def _check_output_dims(where: str, analysis: Analysis) -> None:
    """Every output dimension is an input dimension or given by ``sizes`` at the default parameters (when all have one)."""
    if len(analysis.parameter_defaults) != len(analysis.parameters):
        return  # a required parameter: sizes can only be asked at run time
    try:
        sized = analysis.sizes(**analysis.parameter_defaults)
    except Exception as exc:  # noqa: BLE001 - the user's sizes function: report what it raised
        raise AnalysisError(f"{where}: sizes(**defaults) raised {type(exc).__name__}: {exc}", key="sizes", value=analysis.sizes) from exc
    if not isinstance(sized, Mapping):
        raise AnalysisError(f"{where}: sizes(**defaults) returned {sized!r}, not a dict {{dim: size}}", key="sizes", value=sized)
    known = {d for f in analysis.inputs for d in f.dims} | set(sized)
    unsized = sorted({d for f in analysis.outputs for d in f.dims} - known)
    if unsized:
        raise AnalysisError(
            f"{where}: output dimension(s) {unsized} are no input dimension and not given by sizes: "
            "pass sizes=lambda *, <parameters>: {dim: size} to register()",
            key="sizes",
            value=unsized,
        )
