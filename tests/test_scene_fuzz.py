"""Property: any invalid scene file makes ``clearance run`` exit 2 naming the key (and the value), never a traceback.

Hypothesis mutates a valid scene (the shipped ``compound_misaligned``, flattened
into one file): a number becomes a string, NaN, inf, a boolean, a list, a table
or (for keys that must be positive) a negative number; a required key goes
missing; an unknown key appears; a clearance joint gets the other joint type;
a choice gets a value not on offer. ``--check`` validates and builds the model
without running, so each example takes milliseconds.
"""

from __future__ import annotations

import copy
import json
import math
import tempfile
from pathlib import Path

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from robot.cli.common import EXIT_BAD_INPUT, EXIT_OK
from robot.cli.main import main
from robot.scene.loader import _read, resolve_scene_path


def _base_scene() -> dict:
    data = _read(resolve_scene_path("compound_misaligned"))
    data.pop("__dir__")
    data["mechanism"] = "ups_rps.urdf"  # the shipped file, found from any folder
    return data


BASE = _base_scene()

#: (path, must be > 0 or >= 0: a negative value is invalid)
NUMBERS = [
    (("duration",), True),
    (("trajectory", "period"), True),
    (("solver", "rtol"), True),
    (("solver", "atol"), True),
    (("solver", "max_step"), True),
    (("baumgarte", "alpha"), True),
    (("baumgarte", "beta"), True),
    (("materials", "steel", "youngs_modulus"), True),
    (("materials", "steel", "poisson_ratio"), False),
    (("clearance", 0, "ball_radius"), True),
    (("clearance", 0, "clearance"), True),
    (("clearance", 0, "restitution"), True),
    (("clearance", 0, "exponent"), True),
    (("clearance", 0, "friction", "static"), True),
    (("clearance", 0, "friction", "dynamic"), True),
    (("clearance", 0, "friction", "transition_velocity"), True),
    (("clearance", 1, "journal_radius"), True),
    (("clearance", 1, "radial_clearance"), True),
    (("clearance", 1, "bearing_outer_radius"), True),
    (("clearance", 1, "bearing_length"), True),
    (("clearance", 1, "axial_clearance"), True),
    (("initial", "misalignment_deg", "R1"), False),
]
REQUIRED = [
    ("mechanism",),
    ("clearance", 0, "joint"),
    ("clearance", 0, "type"),
    ("clearance", 0, "ball_radius"),
    ("clearance", 0, "clearance"),
    ("clearance", 1, "journal_radius"),
    ("clearance", 1, "radial_clearance"),
    ("clearance", 1, "bearing_outer_radius"),
    ("clearance", 1, "bearing_length"),
    ("clearance", 1, "axial_clearance"),
    ("clearance", 0, "friction", "static"),
    ("materials", "steel", "youngs_modulus"),
]
TABLES = [(), ("solver",), ("baumgarte",), ("limits",), ("trajectory",), ("materials", "steel"), ("clearance", 0), ("clearance", 1), ("clearance", 1, "friction"), ("initial",), ("output",)]
CHOICES = [
    (("solver", "method"), "RK99"),
    (("solver", "jacobian"), "magic"),
    (("trajectory", "type"), "teleport"),
    (("clearance", 0, "friction", "law"), "glue"),
    (("clearance", 0, "outer_on"), "sideways"),
    (("clearance", 0, "material"), "cheese"),
    (("end_effector",), "no_such_frame"),
    (("output", "precision"), "float16"),
]
NOT_A_NUMBER = [("abc", "'abc'"), (math.nan, "nan"), (math.inf, "inf"), (-math.inf, "-inf"), (True, "True"), ([1.0], "[1.0]"), ({"a": 1}, "{'a': 1}")]


def _toml_value(value) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float) and not math.isfinite(value):
        return "nan" if math.isnan(value) else ("inf" if value > 0 else "-inf")
    if isinstance(value, (int, float)):
        return repr(value)
    if isinstance(value, str):
        return json.dumps(value)
    if isinstance(value, list):
        return "[" + ", ".join(_toml_value(v) for v in value) + "]"
    if isinstance(value, dict):
        return "{" + ", ".join(f"{json.dumps(k)} = {_toml_value(v)}" for k, v in value.items()) + "}"
    raise TypeError(value)


def to_toml(data: dict) -> str:
    """One line per top-level key, tables inline (enough for scenes)."""
    return "".join(f"{key} = {_toml_value(value)}\n" for key, value in data.items())


def _parent(data, path):
    for part in path[:-1]:
        data = data.setdefault(part, {}) if isinstance(part, str) else data[part]
    return data


@st.composite
def mutations(draw):
    """(scene dict, words the error message must contain)."""
    data = copy.deepcopy(BASE)
    kind = draw(st.sampled_from(["not a number", "negative", "missing", "extra", "joint type", "choice"]))
    if kind == "not a number":
        path, _ = draw(st.sampled_from(NUMBERS))
        value, shown = draw(st.sampled_from(NOT_A_NUMBER))
        _parent(data, path)[path[-1]] = value
        return data, [path[-1], shown]
    if kind == "negative":
        path, _ = draw(st.sampled_from([n for n in NUMBERS if n[1]]))
        value = -draw(st.sampled_from([1e-9, 0.5, 3.0, 1e12]))
        _parent(data, path)[path[-1]] = value
        return data, [path[-1].split("_")[0], repr(value)]
    if kind == "missing":
        path = draw(st.sampled_from(REQUIRED))
        del _parent(data, path)[path[-1]]
        return data, [path[-1].split("_")[0]]
    if kind == "extra":
        path = draw(st.sampled_from(TABLES))
        key = draw(st.sampled_from(["bogus", "Duration", "rtoll", "youngs-modulus"]))
        table = data
        for part in path:
            table = table.setdefault(part, {}) if isinstance(part, str) else table[part]
        table[key] = draw(st.sampled_from([1.0, "x", True]))
        return data, [key]
    if kind == "joint type":
        index = draw(st.sampled_from([0, 1]))
        data["clearance"][index]["type"] = "revolute" if index == 0 else "spherical"
        return data, ["type"]
    path, value = draw(st.sampled_from(CHOICES))
    _parent(data, path)[path[-1]] = value
    return data, [value]


def test_the_base_scene_is_valid(capsys):
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "base.toml"
        path.write_text(to_toml(BASE))
        assert main(["run", "--scene", str(path), "--check"]) == EXIT_OK, capsys.readouterr().err


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(mutations())
def test_every_invalid_scene_exits_2_naming_the_key_and_value(capsys, mutation):
    data, words = mutation
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "mutated.toml"
        path.write_text(to_toml(data))
        code = main(["run", "--scene", str(path), "--check"])
    err = capsys.readouterr().err
    assert code == EXIT_BAD_INPUT, f"exit {code} for\n{to_toml(data)}\n{err}"
    assert "Traceback" not in err
    for word in words:
        assert word in err, f"{word!r} not named in {err!r}"
