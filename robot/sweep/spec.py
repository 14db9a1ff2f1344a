"""Sweep files: a base scene, its axes, the analyses to compute, the arrays to keep.

Schema (defaults in brackets; ``docs/sweep.md`` has the full description)::

    [sweep]
    name = "r1_clearance"          # [file stem]
    scene = "compound"             # shipped scene name, or path relative to this file
    t_end = 0.5                    # s [the scene's duration]
    design = "grid"                # ["grid"], "latin_hypercube", "sobol"
    samples = 64                   # sampled designs: number of runs (Sobol: a power of 2)
    seed = 0                       # [0] sampled designs

    [overrides]                    # scene key paths changed in every run
    "solver.rtol" = 1e-6

    [[axis]]                       # one per swept scene key
    key = "clearance.R1.radial_clearance"   # or a list of keys set to the same value
    name = "radial_clearance"      # [the key, '.' -> '_'; required for a list] dataset coordinate
    values = [1e-5, 1e-4]          # grid: a list (numbers, or strings: law names), or
    # linear = {start, stop, num} / log = {start, stop, num}
    # sampled: range = [low, high], scale = "linear" | "log"

    [statistics]                   # peak/RMS ('peak_rms') of signals; default: each
    signals = { R1_force = "R1_normal_force:sum" }   # clearance joint's summed normal force and
    t_start = 0.0                                     # deepest penetration, the end-effector
                                                      # acceleration, the driving forces
    [[analysis]]                   # any analysis of robot.analysis.ANALYSES
    name = "poincare_stroboscopic"
    label = "ee_section"           # [name] prefix of its dataset variables
    state = "ee_position"          # inputs: signal names (robot.sweep.signals); t = "t" implied
    period = "@trajectory.period"  # parameters: values, or "@KEY.PATH" of the run's scene

    [keep]                         # arrays kept on a uniform time grid (exact dense output)
    arrays = ["ee_position", "R1_normal_force:sum"]
    samples = 201

    [[figure]]                     # robot.sweep.figures.FIGURES
    kind = "map"
    value = "R1_force_peak"

Every point's scene is built and validated (``Scene.with_changes``) when the file
is loaded, so a bad key path or a value the scene refuses is reported, naming
the key and the value, before any run starts.
"""

from __future__ import annotations

import hashlib
import inspect
import json
import math
import tomllib
from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path
from typing import Any, Mapping

import numpy as np

from robot.errors import SceneError
from robot.scene.loader import Scene, load_scene
from robot.sweep.design import DESIGNS, GRID, SAMPLED, Axis, Design, grid_design, python_value, sampled_design
from robot.sweep.errors import SweepError
from robot.sweep.signals import Selector, parse_selector

_TOP = {"sweep", "overrides", "axis", "statistics", "analysis", "keep", "figure"}
_SWEEP = {"name", "scene", "t_end", "design", "samples", "seed"}
_AXIS = {"key", "name", "values", "linear", "log", "range", "scale"}
_RANGE = {"start", "stop", "num"}
_STATISTICS = {"signals", "t_start", "t_end"}
_KEEP = {"arrays", "samples"}
#: sweep-file keys of an [[analysis]] table that are not the analysis's inputs or parameters
_ANALYSIS_OWN = {"name", "label"}
#: a parameter value "@KEY.PATH" is the run's scene value at KEY.PATH
SCENE_REFERENCE = "@"


@dataclass(frozen=True)
class AnalysisSpec:
    """One analysis of every run: registry ``name``, variable prefix ``label``, inputs as signal
    selectors, parameters (values or ``"@KEY.PATH"`` references to the run's scene)."""

    name: str
    label: str
    inputs: dict[str, Selector]
    parameters: dict[str, Any]

    def canonical(self) -> dict:
        return {"name": self.name, "label": self.label, "inputs": {k: s.text for k, s in self.inputs.items()}, "parameters": self.parameters}


@dataclass(frozen=True)
class KeepSpec:
    """Arrays kept per run on the uniform grid ``k * t_end / (samples - 1)``."""

    arrays: tuple[Selector, ...]
    samples: int


@dataclass(frozen=True)
class SweepSpec:
    """A loaded, validated sweep file: the base scene, the design and one resolved scene per run."""

    name: str
    path: Path | None
    base: Scene
    t_end: float
    overrides: dict[str, Any]
    axes: tuple[Axis, ...]
    design: Design
    analyses: tuple[AnalysisSpec, ...]
    keep: KeepSpec | None
    figures: tuple[dict[str, Any], ...]
    scenes: tuple[Scene, ...] = field(repr=False)

    @cached_property
    def run_keys(self) -> tuple[str, ...]:
        """One hash per run: its fully resolved scene (mechanism file by content) and outputs."""
        fingerprints: dict[Path, str] = {}
        keys = []
        for scene in self.scenes:
            if scene.mechanism_path not in fingerprints:
                fingerprints[scene.mechanism_path] = hashlib.sha256(scene.mechanism_path.read_bytes()).hexdigest()
            keys.append(digest({"scene": scene.document, "mechanism_sha256": fingerprints[scene.mechanism_path], "outputs": self.outputs_canonical()}))
        return tuple(keys)

    def outputs_canonical(self) -> dict:
        keep = None if self.keep is None else {"arrays": [s.text for s in self.keep.arrays], "samples": self.keep.samples}
        return {"analyses": [a.canonical() for a in self.analyses], "keep": keep}

    @cached_property
    def layout_key(self) -> str:
        """Hash of what fixes the store's shape: dimensions, coordinates, outputs, and the output fields
        each analysis declares (a newer version of an analysis may add one: its old store is another layout)."""
        from robot.analysis import ANALYSES

        coords = {name: [dims, np.asarray(values).tolist()] for name, (dims, values) in self.design.coords.items()}
        fields = {a.name: [[f.name, list(f.dims)] for f in ANALYSES[a.name].outputs] for a in self.analyses}
        return digest({
            "dims": self.design.dims, "shape": self.design.shape, "coords": coords,
            "axes": [a.key if not a.linked else list(a.keys) for a in self.axes], "outputs": self.outputs_canonical(), "fields": fields,
        })  # fmt: skip


def digest(value: Any) -> str:
    """SHA-256 of the canonical JSON of ``value`` (sorted keys, exact float repr)."""
    text = json.dumps(value, sort_keys=True, separators=(",", ":"), allow_nan=False, default=python_value)
    return hashlib.sha256(text.encode()).hexdigest()


def _table(data: dict, key: str, allowed: set[str], where: str) -> dict:
    table = data.get(key, {})
    if not isinstance(table, dict):
        raise SweepError(f"{where}: [{key}] must be a table, got {table!r}", key=key, value=table)
    unknown = sorted(set(table) - allowed)
    if unknown:
        raise SweepError(f"{where} [{key}]: unknown key(s) {', '.join(unknown)}; valid keys: {', '.join(sorted(allowed))}", key=f"{key}.{unknown[0]}", value=table[unknown[0]])
    return table


def _count(value: Any, key: str, where: str, minimum: int) -> int:
    if isinstance(value, bool) or not isinstance(value, int) or value < minimum:
        raise SweepError(f"{where}: {key}={value!r} must be an integer >= {minimum}", key=key, value=value)
    return value


def _positive(value: Any, key: str, where: str) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value) or value <= 0:
        raise SweepError(f"{where}: {key}={value!r} must be a finite number > 0", key=key, value=value)
    return float(value)


def _grid_values(table: dict, key: str, where: str) -> tuple:
    given = [k for k in ("values", "linear", "log") if k in table]
    if len(given) != 1:
        raise SweepError(f"{where}: axis {key!r} needs exactly one of values, linear, log (got {given or 'none'})", key=key, value=given)
    kind = given[0]
    if kind == "values":
        values = table["values"]
        if not isinstance(values, list) or not values:
            raise SweepError(f"{where}: axis {key!r}: values={values!r} must be a non-empty list", key=key, value=values)
        return _distinct(tuple(values), kind, key, where)
    spec = table[kind]
    if not isinstance(spec, dict) or set(spec) != _RANGE:
        raise SweepError(f"{where}: axis {key!r}: {kind}={spec!r} must be a table {{start, stop, num}}", key=key, value=spec)
    num = spec["num"]
    if isinstance(num, bool) or not isinstance(num, int) or num < 1:
        raise SweepError(f"{where}: axis {key!r}: {kind}.num={num!r} must be an integer >= 1", key=key, value=num)
    start, stop = spec["start"], spec["stop"]
    for name, value in (("start", start), ("stop", stop)):
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value) or (kind == "log" and value <= 0):
            rule = "a finite number > 0 (log range)" if kind == "log" else "a finite number"
            raise SweepError(f"{where}: axis {key!r}: {kind}.{name}={value!r} must be {rule}", key=key, value=value)
    values = np.geomspace(start, stop, num) if kind == "log" else np.linspace(start, stop, num)
    return _distinct(tuple(float(v) for v in values), kind, key, where)


def _distinct(values: tuple, kind: str, key: str, where: str) -> tuple:
    """The grid axis's values, refused if one repeats: runs are deterministic, so a repeated value
    runs the same point twice, and the store's coordinate could not select it (``Dataset.sel``)."""
    for index, value in enumerate(values):
        if value in values[:index]:
            raise SweepError(
                f"{where}: axis {key!r}: the value {value!r} appears twice in {kind}; the values of a grid axis must be distinct",
                key=key,
                value=value,
            )
    return values


def _sample_range(table: dict, key: str, where: str) -> tuple[float, float, str]:
    bounds = table.get("range")
    scale = table.get("scale", "linear")
    if scale not in ("linear", "log"):
        raise SweepError(f"{where}: axis {key!r}: scale={scale!r} must be 'linear' or 'log'", key=key, value=scale)
    ok = isinstance(bounds, list) and len(bounds) == 2 and all(isinstance(b, (int, float)) and not isinstance(b, bool) and math.isfinite(b) for b in bounds)
    if not ok or not bounds[0] < bounds[1] or (scale == "log" and bounds[0] <= 0):
        rule = "0 < low < high" if scale == "log" else "low < high"
        raise SweepError(f"{where}: axis {key!r}: range={bounds!r} must be [low, high] with {rule}", key=key, value=bounds)
    return float(bounds[0]), float(bounds[1]), scale


def _axis_keys(given: Any, where: str) -> tuple[str, tuple[str, ...]]:
    """An axis's ``key``: one dotted path, or a list of paths set to the same value (linked)."""
    keys = given if isinstance(given, list) else [given]
    if not keys or not all(isinstance(k, str) and k for k in keys):
        raise SweepError(f"{where}: [[axis]] needs key = \"SCENE.KEY.PATH\" or a list of them, got {given!r}", key="axis.key", value=given)
    return keys[0], tuple(keys[1:])


def _axes(data: dict, design: str, where: str) -> tuple[Axis, ...]:
    tables = data.get("axis", [])
    if not isinstance(tables, list) or not tables:
        raise SweepError(f"{where}: a sweep needs at least one [[axis]] table", key="axis", value=tables)
    axes, names = [], set()
    for table in tables:
        if not isinstance(table, dict):
            raise SweepError(f"{where}: [[axis]] entries must be tables", key="axis", value=table)
        unknown = sorted(set(table) - _AXIS)
        key, linked = _axis_keys(table.get("key"), where)
        if unknown:
            raise SweepError(f"{where}: axis {key!r}: unknown key(s) {', '.join(unknown)}; valid keys: {', '.join(sorted(_AXIS))}", key=key, value=unknown[0])
        if linked and "name" not in table:
            raise SweepError(f"{where}: axis {[key, *linked]!r} sets several keys and needs name = \"COORDINATE\"", key=key, value=None)
        name = table.get("name", key.replace(".", "_"))
        if not isinstance(name, str) or not name.isidentifier() or name in names or name == "sample":
            raise SweepError(f"{where}: axis {key!r}: name={name!r} must be a unique identifier other than 'sample'", key=key, value=name)
        names.add(name)
        if design == GRID:
            if "range" in table or "scale" in table:
                raise SweepError(f"{where}: axis {key!r}: range/scale are for sampled designs; a grid axis takes values, linear or log", key=key, value=table.get("range"))
            axes.append(Axis(key, name, values=_grid_values(table, key, where), linked=linked))
        else:
            if any(k in table for k in ("values", "linear", "log")):
                raise SweepError(f"{where}: axis {key!r}: a {design} design samples range = [low, high]; values/linear/log are for grids", key=key, value=None)
            low, high, scale = _sample_range(table, key, where)
            axes.append(Axis(key, name, low=low, high=high, scale=scale, linked=linked))
    keys = [k for a in axes for k in a.keys]
    if len(set(keys)) != len(keys):
        raise SweepError(f"{where}: a key is swept twice: {keys}", key="axis", value=keys)
    return tuple(axes)


def default_statistics(scene: Scene) -> dict[str, str]:
    """Signals whose peak and RMS every sweep records unless ``[statistics] signals`` says otherwise."""
    signals = {}
    for joint in scene.clearance_joints:
        signals[f"{joint}_force"] = f"{joint}_normal_force:sum"
        signals[f"{joint}_penetration"] = f"{joint}_penetration:max"
    if scene.trajectory.kind == "platform" or scene.trajectory.coordinates:  # else no motion-driven joint: no driving force
        signals["driving_force"] = "driving_force:maxabs"
    signals["ee_acceleration"] = "ee_acceleration:norm"
    return signals


def _statistics(data: dict, scene: Scene, where: str) -> list[AnalysisSpec]:
    table = _table(data, "statistics", _STATISTICS, where)
    signals = table.get("signals", default_statistics(scene))
    if not isinstance(signals, dict):
        raise SweepError(f"{where} [statistics]: signals={signals!r} must be a table {{label = \"SIGNAL\"}}", key="statistics.signals", value=signals)
    window = {k: table[k] for k in ("t_start", "t_end") if k in table}
    return [_analysis({"name": "peak_rms", "label": label, "signal": signal, **window}, where) for label, signal in signals.items()]


def _analysis(table: Any, where: str) -> AnalysisSpec:
    from robot.analysis import ANALYSES, AnalysisError

    if not isinstance(table, dict):
        raise SweepError(f"{where}: [[analysis]] entries must be tables", key="analysis", value=table)
    name = table.get("name")
    try:
        analysis = ANALYSES[name]
    except (AnalysisError, TypeError):
        raise SweepError(f"{where}: analysis name={name!r} is not registered; registered: {', '.join(sorted(ANALYSES))}", key="analysis.name", value=name) from None
    label = table.get("label", name)
    if not isinstance(label, str) or not label.isidentifier():
        raise SweepError(f"{where}: analysis {name!r}: label={label!r} must be an identifier", key=f"{name}.label", value=label)
    w = f"{where} analysis {label!r}"
    input_names = {f.name for f in analysis.inputs}
    parameters = analysis.parameters
    unknown = sorted(set(table) - _ANALYSIS_OWN - input_names - set(parameters))
    if unknown:
        known = ", ".join(sorted(input_names | set(parameters)))
        raise SweepError(f"{w}: {unknown[0]}={table[unknown[0]]!r} is neither an input nor a parameter of {name!r} ({known})", key=f"{label}.{unknown[0]}", value=table[unknown[0]])
    given = {k: v for k, v in table.items() if k in input_names}
    # inputs named after the run's own arrays: t always; every input of an analysis that needs the run
    for f in analysis.inputs:
        if f.name == "t" or analysis.needs_run:
            given.setdefault(f.name, f.name)
    missing = [f.name for f in analysis.inputs if not f.optional and f.name not in given]
    missing += [p for p, default in parameters.items() if default is inspect.Parameter.empty and p not in table]
    if missing:
        raise SweepError(f"{w}: {name!r} needs {', '.join(missing)}", key=f"{label}.{missing[0]}", value=None)
    inputs = {k: parse_selector(v, f"{label}.{k}") for k, v in given.items()}
    return AnalysisSpec(name, label, inputs, {k: v for k, v in table.items() if k in parameters})


def resolve_parameters(analysis: AnalysisSpec, document: dict) -> dict[str, Any]:
    """Parameter values, with ``"@KEY.PATH"`` replaced by the scene's value there."""
    from robot.scene.overrides import document_value

    return {
        name: document_value(document, value[len(SCENE_REFERENCE):]) if isinstance(value, str) and value.startswith(SCENE_REFERENCE) else value
        for name, value in analysis.parameters.items()
    }


class _InputsReached(BaseException):
    """Raised by a :class:`_Placeholder` input (a BaseException: an analysis's ``except Exception`` lets it through)."""


class _Placeholder:
    """An input that stops an analysis the moment it is read: what the analysis raised before had
    come from its parameters alone (:func:`check_parameters`)."""

    def _reached(self, *args: Any, **kwargs: Any) -> Any:
        raise _InputsReached

    __array__ = __len__ = __iter__ = __getitem__ = __float__ = __int__ = __index__ = __bool__ = __contains__ = _reached
    __add__ = __radd__ = __sub__ = __rsub__ = __mul__ = __rmul__ = __truediv__ = __rtruediv__ = __pow__ = __neg__ = __abs__ = _reached
    __lt__ = __le__ = __gt__ = __ge__ = __eq__ = __ne__ = _reached
    __hash__ = None  # type: ignore[assignment]

    def __getattr__(self, name: str) -> Any:
        raise _InputsReached


def check_parameters(spec: AnalysisSpec, scenes: tuple[Scene, ...], where: str) -> None:
    """SweepError naming the analysis, the parameter and its value if the analysis refuses the parameters of
    any run: it is called with placeholder inputs, so what it raises before it reads one is its own check
    of the parameters alone (``require_positive`` and co., ``robot/analysis/errors.py``), which every run would fail."""
    from robot.analysis import ANALYSES

    analysis = ANALYSES[spec.name]
    inputs = {name: _Placeholder() for name in spec.inputs} | ({"run": _Placeholder()} if analysis.needs_run else {})
    checked: set[str] = set()
    for i, scene in enumerate(scenes):
        try:
            parameters = resolve_parameters(spec, scene.document)
        except SceneError as exc:
            raise SweepError(f"{where} analysis {spec.label!r} ({spec.name}): a parameter refers to no key of run {i}'s scene: {exc}", key=spec.label, value=spec.parameters) from None
        token = repr(sorted(parameters.items()))
        if token in checked:
            continue
        checked.add(token)
        try:
            analysis.function(**inputs, **parameters)
        except _InputsReached:
            continue
        except Exception as exc:  # noqa: BLE001 - whatever the parameters alone make it raise, every run would
            run = f", run {i}" if parameters != spec.parameters else ""  # a value read from the run's scene
            raise _refused(spec, parameters, exc, f"{where} analysis {spec.label!r} ({spec.name}){run}") from None


def _refused(spec: AnalysisSpec, parameters: dict[str, Any], exc: Exception, where: str) -> SweepError:
    """The SweepError of an analysis that refused its parameters: which one (its key), the value, the analysis's reason."""
    from robot.analysis import AnalysisError

    text, key = str(exc), getattr(exc, "key", None)
    name = key if key in parameters else next((p for p in parameters if text.startswith(f"{p}=")), None)
    given = "" if name is None or spec.parameters.get(name) == parameters[name] else f" ({name} = {spec.parameters[name]!r} is {parameters[name]!r} there)"
    reason = text if isinstance(exc, AnalysisError) else f"{type(exc).__name__}: {text}"
    return SweepError(
        f"{where}: {reason}{given}; change the parameter in its [[analysis]] (or [statistics]) table",
        key=f"{spec.label}.{name}" if name else spec.label,
        value=parameters.get(name) if name else parameters,
    )


def _keep(data: dict, where: str) -> KeepSpec | None:
    if "keep" not in data:
        return None
    table = _table(data, "keep", _KEEP, where)
    arrays = table.get("arrays", [])
    if not isinstance(arrays, list) or not arrays:
        raise SweepError(f"{where} [keep]: arrays={arrays!r} must be a non-empty list of signal names", key="keep.arrays", value=arrays)
    selectors = tuple(parse_selector(a, "keep.arrays") for a in arrays)
    if len({s.name for s in selectors}) != len(selectors):
        raise SweepError(f"{where} [keep]: an array is listed twice: {arrays}", key="keep.arrays", value=arrays)
    return KeepSpec(selectors, _count(table.get("samples", 201), "keep.samples", where, 2))


def _scene_with(scene: Scene, changes: Mapping[str, Any], what: str, key: str, value: Any) -> Scene:
    try:
        return scene.with_changes(changes)
    except SceneError as exc:
        raise SweepError(f"{what}: {key} = {value!r} is refused by the scene: {exc}", key=key, value=value) from None


def _resolve_scenes(base: Scene, axes: tuple[Axis, ...], design: Design) -> tuple[Scene, ...]:
    """Validate every axis value alone (errors name the axis), then every point."""
    if design.kind == GRID:
        for axis in axes:
            for key in axis.keys:
                for value in axis.values:
                    _scene_with(base, {key: value}, f"axis {key!r}", key, value)
    scenes = []
    for i, point in enumerate(design.points):
        try:
            scenes.append(base.with_changes(point))
        except SceneError as exc:
            key = next((k for k in point if exc.key and k.endswith(str(exc.key))), next(iter(point)))
            raise SweepError(f"run {i} ({point}): {key} = {point[key]!r} is refused by the scene: {exc}", key=key, value=point[key]) from None
    return tuple(scenes)


def _base_scene(data: dict, sweep: dict, path: Path | None, where: str) -> tuple[Scene, float, dict]:
    name = sweep.get("scene")
    if not isinstance(name, str) or not name:
        raise SweepError(f"{where} [sweep]: scene={name!r} must name a shipped scene or a scene file", key="sweep.scene", value=name)
    located = path.parent / name if path is not None and name.endswith(".toml") else name
    try:
        scene = load_scene(located)
    except SceneError as exc:
        raise SweepError(f"{where} [sweep]: scene={name!r}: {exc}", key="sweep.scene", value=name) from None
    t_end = _positive(sweep["t_end"], "sweep.t_end", where) if "t_end" in sweep else scene.duration
    overrides = data.get("overrides", {})
    if not isinstance(overrides, dict):
        raise SweepError(f"{where}: [overrides] must be a table of key paths", key="overrides", value=overrides)
    for key, value in overrides.items():
        _scene_with(scene, {key: value}, "[overrides]", key, value)
    return _scene_with(scene, {**overrides, "duration": t_end}, "[overrides]", "duration", t_end), t_end, overrides


def _design(sweep: dict, axes_data: dict, where: str) -> tuple[tuple[Axis, ...], Design]:
    kind = sweep.get("design", GRID)
    if kind not in DESIGNS:
        raise SweepError(f"{where} [sweep]: design={kind!r} must be one of {', '.join(DESIGNS)}", key="sweep.design", value=kind)
    axes = _axes(axes_data, kind, where)
    if kind == GRID:
        if "samples" in sweep or "seed" in sweep:
            raise SweepError(f"{where} [sweep]: samples/seed are for sampled designs ({', '.join(SAMPLED)})", key="sweep.samples", value=sweep.get("samples"))
        return axes, grid_design(axes)
    if "samples" not in sweep:
        raise SweepError(f"{where} [sweep]: a {kind} design needs samples = N", key="sweep.samples", value=None)
    count = _count(sweep["samples"], "sweep.samples", where, 1)
    if kind == "sobol" and count & (count - 1):
        raise SweepError(f"{where}: sweep.samples={count} must be a power of 2 for a Sobol design", key="sweep.samples", value=count)
    seed = _count(sweep.get("seed", 0), "sweep.seed", where, 0)
    return axes, sampled_design(kind, axes, count, seed)


def load_sweep(source: str | Path | Mapping[str, Any], *, base_dir: str | Path | None = None) -> SweepSpec:
    """Read and validate a sweep (a TOML file, or its document as a mapping); every run's scene
    is validated here. SweepError (exit code 2 of the command) names the key and the value."""
    from robot.sweep.figures import check_figures

    if isinstance(source, Mapping):
        data, path = dict(source), (Path(base_dir) / "sweep.toml" if base_dir is not None else None)
    else:
        path = Path(source)
        if not path.is_file():
            raise SweepError(f"sweep file {str(path)!r} does not exist", key="sweep", value=str(path))
        try:
            data = tomllib.loads(path.read_text(encoding="utf-8"))
        except tomllib.TOMLDecodeError as exc:
            raise SweepError(f"sweep file {str(path)!r} is not valid TOML: {exc}", key="sweep", value=str(path)) from None
    where = f"sweep {path.name}" if path is not None else "sweep"
    unknown = sorted(set(data) - _TOP)
    if unknown:
        raise SweepError(f"{where}: unknown table(s) {', '.join(unknown)}; valid: {', '.join(sorted(_TOP))}", key=unknown[0], value=data[unknown[0]])
    sweep = _table(data, "sweep", _SWEEP, where)
    base, t_end, overrides = _base_scene(data, sweep, path, where)
    axes, design = _design(sweep, data, where)
    analyses = [*_statistics(data, base, where)]
    extra = data.get("analysis", [])
    if not isinstance(extra, list):
        raise SweepError(f"{where}: analyses are [[analysis]] tables", key="analysis", value=extra)
    analyses += [_analysis(table, where) for table in extra]
    labels = [a.label for a in analyses]
    if len(set(labels)) != len(labels):
        raise SweepError(f"{where}: two analyses share a label: {labels}", key="analysis.label", value=labels)
    figures = data.get("figure", [])
    name = sweep.get("name", path.stem if path is not None else "sweep")
    if not isinstance(name, str) or not name:
        raise SweepError(f"{where} [sweep]: name={name!r} must be a non-empty string", key="sweep.name", value=name)
    spec = SweepSpec(name, path, base, t_end, dict(overrides), axes, design, tuple(analyses), _keep(data, where), tuple(figures), _resolve_scenes(base, axes, design))
    for analysis in spec.analyses:
        check_parameters(analysis, spec.scenes, where)
    check_figures(spec)
    return spec
