"""Validated scene values shared by trajectories, actuators and force elements (no Pinocchio).

* :func:`time_function`: a table ``{function = ..., ...}`` -> a
  :mod:`robot.model.time_functions` object. ``function`` is one of
  ``constant`` (``value``), ``polynomial`` (``coefficients = [c0, c1, ...]``,
  ``sum c_k t^k``), ``constant_rate`` (``offset``, ``rate``), ``harmonic``
  (``amplitude``, ``frequency`` Hz, ``phase`` rad [0], ``offset`` [0]) or
  ``tabulated`` (``time = [...]`` and ``value = [...]`` inline, or ``file =
  "table.csv"``: two columns time, value, path relative to the scene file that
  writes it; every row finite, times strictly increasing; cubic spline).
* :func:`table_curve`: inline abscissae and ordinates (strictly increasing abscissae) -> a spline.
* :func:`vector3`, :func:`number_list`.

Every bad value raises :class:`robot.errors.SceneError` naming the key, its value
and what is valid.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np

from robot.errors import SceneError
from robot.model import time_functions as TF
from robot.scene.loader import _number, _unknown

FUNCTION_KEYS = {
    "constant": {"value"},
    "polynomial": {"coefficients"},
    "constant_rate": {"offset", "rate"},
    "harmonic": {"amplitude", "frequency", "phase", "offset"},
    "tabulated": {"time", "value", "file"},
}


def number_list(table: dict, key: str, where: str, *, min_length: int = 1) -> tuple[float, ...]:
    values = table.get(key)
    ok = isinstance(values, list) and len(values) >= min_length
    ok = ok and all(isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x) for x in values)
    if not ok:
        raise SceneError(f"{where}: {key}={values!r} must be a list of at least {min_length} finite numbers", key=key, value=values)
    return tuple(float(x) for x in values)


def vector3(table: dict, key: str, where: str, default: tuple[float, float, float] | None = None, *, unit: bool = False) -> np.ndarray:
    """A 3-vector ``[x, y, z]``; ``unit=True``: normalised, refused if zero."""
    if key not in table and default is not None:
        return np.array(default, dtype=float)
    values = table.get(key)
    if not (isinstance(values, list) and len(values) == 3):
        raise SceneError(f"{where}: {key}={values!r} must be three numbers [x, y, z]", key=key, value=values)
    vector = np.array(number_list(table, key, where, min_length=3))
    if unit:
        norm = float(np.linalg.norm(vector))
        if not norm > 0.0:
            raise SceneError(f"{where}: {key}={values!r} must be a non-zero direction", key=key, value=values)
        vector = vector / norm
    return vector


def table_curve(x: tuple[float, ...], y: tuple[float, ...], x_key: str, y_key: str, where: str) -> TF.Tabulated:
    """A spline through inline lists ``(x, y)``; refused with the offending entry if ``x`` is not strictly increasing."""
    if len(x) != len(y):
        raise SceneError(f"{where}: {x_key} and {y_key} must have the same length (got {len(x)} and {len(y)})", key=y_key, value=list(y))
    bad = TF.first_non_increasing(x)
    if bad is not None:
        raise SceneError(f"{where}: {x_key} must be strictly increasing; entry {bad} ({x[bad]!r}) follows {x[bad - 1]!r}", key=x_key, value=list(x))
    return TF.Tabulated(np.array(x), np.array(y))


def _tabulated(table: dict, where: str, base_dir: Path | None) -> TF.Tabulated:
    if "file" in table:
        if "time" in table or "value" in table:
            raise SceneError(f"{where}: give either file or time and value, not both", key="file", value=table["file"])
        return _file_table(table["file"], where, base_dir)
    return table_curve(number_list(table, "time", where, min_length=2), number_list(table, "value", where, min_length=2), "time", "value", where)


def _file_table(name: Any, where: str, base_dir: Path | None) -> TF.Tabulated:
    """The spline of a CSV time table ``file = name`` (relative to ``base_dir``), its columns checked first."""
    if not isinstance(name, str) or not name:
        raise SceneError(f"{where}: file={name!r} must be the path of a CSV file (time, value)", key="file", value=name)
    path = (base_dir or Path.cwd()) / name
    try:
        time, value = TF.read_table_csv(path)
    except FileNotFoundError:
        raise SceneError(f"{where}: file={name!r}: {str(path)!r} does not exist", key="file", value=name) from None
    except OSError as exc:
        raise SceneError(f"{where}: file={name!r}: {str(path)!r} cannot be read: {exc.strerror or exc}", key="file", value=name) from None
    except (ValueError, UnicodeDecodeError) as exc:
        raise SceneError(f"{where}: file={name!r} is not a two-column CSV table (time, value): {exc}", key="file", value=name) from None
    time, value = [float(t) for t in time], [float(v) for v in value]
    _check_file_columns(time, value, f"{where}: file={name!r}", f"in {str(path)!r}", name)
    return TF.Tabulated(np.array(time), np.array(value))


def _check_file_columns(time: list[float], value: list[float], where: str, source: str, name: str) -> None:
    """A time table file's columns hold finite numbers and strictly increasing times, as the inline lists must.

    scipy's spline would refuse them with a traceback. Entries count from 0 like
    those of the inline lists (header and comment lines not counted); ``source``
    says which file on disk, as a relative name may resolve anywhere.
    """
    for column, numbers in (("time", time), ("value", value)):
        bad = next((i for i, x in enumerate(numbers) if not math.isfinite(x)), None)
        if bad is not None:
            raise SceneError(
                f"{where}: the {column} column must hold finite numbers; entry {bad} (data row {time[bad]!r}, {value[bad]!r}) is {numbers[bad]!r}, {source}",
                key="file",
                value=name,
            )
    bad = TF.first_non_increasing(time)
    if bad is not None:
        raise SceneError(f"{where}: the time column must be strictly increasing; entry {bad} ({time[bad]!r}) follows {time[bad - 1]!r}, {source}", key="file", value=name)


def time_function(table: Any, where: str, base_dir: Path | None, *, extra_keys: set[str] = frozenset(), default: str | None = None):
    """The time function a table describes (module docstring); ``extra_keys`` are the caller's own keys."""
    if not isinstance(table, dict):
        raise SceneError(f"{where} must be a table {{function = ..., ...}}, got {table!r}", value=table)
    kind = table.get("function", default)
    if kind not in FUNCTION_KEYS:
        raise SceneError(f"{where}: function={kind!r} is not known; use one of {', '.join(FUNCTION_KEYS)}", key="function", value=kind)
    _unknown(table, FUNCTION_KEYS[kind] | {"function"} | set(extra_keys), where)
    if kind == "constant":
        return TF.Constant(_number(table, "value", where, required=True))
    if kind == "polynomial":
        return TF.Polynomial(number_list(table, "coefficients", where))
    if kind == "constant_rate":
        return TF.Polynomial((_number(table, "offset", where, 0.0), _number(table, "rate", where, required=True)))
    if kind == "harmonic":
        return TF.Harmonic(
            _number(table, "amplitude", where, required=True),
            _number(table, "frequency", where, required=True, low=0.0),
            _number(table, "phase", where, 0.0),
            _number(table, "offset", where, 0.0),
        )
    return _tabulated(table, where, base_dir)


def check_covers(function, start: float, end: float, key: str, where: str) -> None:
    """A time table must cover the run ``[start, end]`` (beyond it the spline's end tangent would be extrapolated)."""
    if isinstance(function, TF.Tabulated) and (function.x[0] > start or function.x[-1] < end):
        raise SceneError(
            f"{where}: the time table spans [{function.x[0]:g}, {function.x[-1]:g}] s and does not cover the run [{start:g}, {end:g}] s",
            key=key,
            value=[float(function.x[0]), float(function.x[-1])],
        )
