"""Scene tables of force elements (``[[force]]``) and actuator modes (``[actuators]``), validated (no Pinocchio).

Each ``[[force]]`` table is parsed by its registered element type
(:data:`robot.dynamics.forces.FORCE_TYPES`, whose modules import no Pinocchio)
into a :class:`ForceSpec`; ``[actuators]`` entries become :class:`ActuatorSpec`
(``robot.model.actuation`` says what each mode means). The schema is in
:mod:`robot.scene.loader`'s docstring.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

from robot.dynamics.forces import FORCE_TYPES
from robot.errors import SceneError
from robot.scene.loader import TrajectorySpec, _unknown
from robot.scene.values import FUNCTION_KEYS, check_covers, time_function


@dataclass(frozen=True)
class ForceSpec:
    """A ``[[force]]`` table: its element type (``robot.dynamics.forces.FORCE_TYPES``) and validated parameters."""

    name: str
    kind: str
    parameters: dict[str, Any]
    where: str


@dataclass(frozen=True)
class ActuatorSpec:
    """How an actuated joint is driven: ``motion`` (trajectory), ``force`` (``function`` of t) or ``none``."""

    joint: str
    mode: str
    function: Any = None


def force_specs(data: dict, where: str, base_dir: Path) -> tuple[ForceSpec, ...]:
    """``[[force]]`` tables, each parsed by its registered element type (``robot.dynamics.forces``)."""
    tables = data.get("force", [])
    if not isinstance(tables, list):
        raise SceneError(f"{where}: force must be an array of tables [[force]]", key="force", value=tables)
    if not tables:
        return ()
    specs, names = [], set()
    for index, table in enumerate(tables):
        w = f"{where} [[force]] #{index + 1}"
        if not isinstance(table, dict):
            raise SceneError(f"{w} must be a table", value=table)
        kind = table.get("type")
        if kind not in FORCE_TYPES:
            raise SceneError(f"{w}: type={kind!r} is not a force element type; types: {', '.join(sorted(FORCE_TYPES))}", key="type", value=kind)
        name = table.get("name", f"{kind}_{index + 1}")
        if not isinstance(name, str) or not name.replace("_", "").isalnum() or name in names | {"work", "energy"}:
            raise SceneError(f"{w}: name={name!r} must be a unique identifier (letters, digits, _; not 'work' or 'energy', the totals' names)", key="name", value=name)
        names.add(name)
        w = f"{where} force {name!r} ({kind})"
        element = FORCE_TYPES[kind]
        function_keys = _function_keys(table)
        if function_keys is not None:  # else the element's parse names the unknown function
            _unknown(table, element.KEYS | {"name", "type"} | function_keys, w)
        specs.append(ForceSpec(name, kind, element.parse(table, w, base_dir), w))
    return tuple(specs)


def _function_keys(table: dict) -> set[str] | None:
    """The keys of the time function a table names; None for an unknown function."""
    if "function" not in table:
        return set()
    kind = table["function"]
    return FUNCTION_KEYS[kind] | {"function"} if isinstance(kind, str) and kind in FUNCTION_KEYS else None


def actuator_specs(table: dict, where: str, base_dir: Path | None) -> dict[str, ActuatorSpec]:
    """``[actuators]``: per joint ``{mode = "motion" | "force" | "none", function ... (force)}``."""
    out = {}
    for joint, entry in table.items():
        w = f"{where} [actuators] {joint}"
        if not isinstance(entry, dict):
            raise SceneError(f"{w} must be a table {{mode = 'motion' | 'force' | 'none', ...}}", key=joint, value=entry)
        mode = entry.get("mode")
        if mode not in ("motion", "force", "none"):
            raise SceneError(f"{w}: mode={mode!r} must be 'motion', 'force' or 'none'", key="mode", value=mode)
        if mode == "force":
            function = time_function({k: v for k, v in entry.items() if k != "mode"}, w, base_dir)
            out[joint] = ActuatorSpec(joint, mode, function)
        else:
            _unknown(entry, {"mode"}, w)
            out[joint] = ActuatorSpec(joint, mode)
    return out


def check_time_tables(trajectory: TrajectorySpec, actuators: dict[str, ActuatorSpec], forces: tuple[ForceSpec, ...], duration: float, where: str) -> None:
    """Every time table covers the run [0, duration]."""
    for joint, function in trajectory.functions.items():
        check_covers(function, 0.0, duration, "file", f"{where} [trajectory] {joint}")
    for joint, actuator in actuators.items():
        check_covers(actuator.function, 0.0, duration, "time", f"{where} [actuators] {joint}")
    for spec in forces:
        check_covers(spec.parameters.get("function"), 0.0, duration, "time", spec.where)
