"""docs/scenes.md stays the reference of the scene format.

* every key the loader accepts (collected from the code's key sets: the loader's
  tables, the time functions, the force element types' ``KEYS``, every registered
  clearance type's ``SCENE_KEYS``, the common clearance keys, friction) and every
  name a key may take (solver methods, dissipation models, radial laws, force types)
  appears in it, as `code`;
* every ``toml`` example loads (``load_scene`` on the block written to a file) and its
  run builds, and the ``python`` examples run.
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from clearance_contact import joint_type, joint_types
from clearance_contact.dissipation import DISSIPATION_MODELS
from clearance_contact.friction import friction_law_type
from clearance_contact.radial_laws import RADIAL_LAWS
from clearance_contact.registry import COMMON_SCENE_KEYS
from robot.dynamics.forces import FORCE_TYPES
from robot.integration.options import JACOBIAN_CHOICES
from robot.integration.solvers import METHODS
from robot.model.trajectory import POSE_COORDINATES
from robot.scene import loader as L
from robot.run import build_run
from robot.scene.loader import load_scene
from robot.scene.overrides import ARRAY_ENTRY_KEYS
from robot.scene.values import FUNCTION_KEYS

DOC = Path(__file__).resolve().parents[1] / "docs" / "scenes.md"
TEXT = DOC.read_text(encoding="utf-8")


def _blocks(language: str) -> list[str]:
    return re.findall(rf"```{language}\n(.*?)```", TEXT, flags=re.S)


def _shipped_joint_types() -> list[str]:
    """The registered clearance types the packages ship (tests register their own, e.g. point_on_plane)."""
    return [name for name in joint_types() if joint_type(name).__module__.split(".")[0] in ("clearance_contact", "robot")]


def _accepted_keys() -> dict[str, set[str]]:
    """Where -> the keys the code accepts there (its own key sets, not a copy of them)."""
    keys = {
        "top level": L._TOP_KEYS,
        "[trajectory]": L._TRAJECTORY_KEYS | set(POSE_COORDINATES) | L._COORDINATE_KEYS | {"function"},
        "[solver]": L._SOLVER_KEYS,
        "[baumgarte]": L._BAUMGARTE_KEYS,
        "[limits]": L._LIMIT_KEYS,
        "[materials]": L._MATERIAL_KEYS,
        "[initial]": L._INITIAL_KEYS,
        "[output]": L._OUTPUT_KEYS,
        "[actuators]": {"mode"},
        # the shipped friction laws' keys (a registered law's own keys are its FrictionKey s)
        "friction": {"law"}.union(*({key.name for key in friction_law_type(name).keys} for name in ("none", "brown_mcphee", "coulomb"))),
        "[[clearance]]": set(COMMON_SCENE_KEYS),
        "[[force]]": {"name", "type"},
        "override arrays": set(ARRAY_ENTRY_KEYS.values()),
    }
    for function, function_keys in FUNCTION_KEYS.items():
        keys[f"time function {function}"] = set(function_keys)
    for name in _shipped_joint_types():
        keys[f"clearance type {name}"] = set(joint_type(name).SCENE_KEYS)
    for name, element in FORCE_TYPES.items():
        keys[f"force {name}"] = set(element.KEYS)
    return keys


def _accepted_names() -> dict[str, set[str]]:
    """Where -> the names a key may take."""
    return {
        "solver.method": set(METHODS),
        "solver.jacobian": set(JACOBIAN_CHOICES),
        "output.precision": set(L.PRECISIONS),
        "time functions": set(FUNCTION_KEYS),
        "force types": set(FORCE_TYPES),
        "clearance types": set(_shipped_joint_types()),
        "dissipation": set(DISSIPATION_MODELS),
        "radial_law": set(RADIAL_LAWS),
        "friction law": {"brown_mcphee", "coulomb", "none"},
        "actuator mode": {"motion", "force", "none"},
    }


@pytest.mark.parametrize("kind", ["keys", "names"])
def test_every_accepted_key_and_name_is_documented(kind):
    assert {"spherical", "revolute"} <= set(_shipped_joint_types())
    collected = _accepted_keys() if kind == "keys" else _accepted_names()
    quoted = set(re.findall(r"`([^`\n]+)`", TEXT))
    # a key is documented as `key`, `key = ...`, a list `a`/`b`, or a name as `"name"`
    words = {word.strip('"') for span in quoted for word in re.split(r"[\s,=/\[\]{}().]+", span) if word}
    missing = {where: sorted(names - words) for where, names in collected.items() if names - words}
    assert not missing, f"docs/scenes.md does not mention: {missing}"
    assert sum(len(v) for v in collected.values()) > (80 if kind == "keys" else 30)  # the collection did find the key sets


@pytest.mark.filterwarnings("error")
def test_every_toml_example_loads_and_builds(tmp_path):
    """Each example is a valid scene, and its run builds (mechanism, drive, initial state) without a warning."""
    blocks = _blocks("toml")
    assert len(blocks) >= 12
    names = set()
    for index, block in enumerate(blocks):
        path = tmp_path / f"example_{index}.toml"
        path.write_text(block, encoding="utf-8")
        scene = load_scene(path)
        names.add(scene.name)
        build_run(scene)
    assert len(names) == len(blocks)  # each example is its own scene


def test_python_examples_run():
    blocks = _blocks("python")
    assert blocks
    namespace: dict = {}
    for block in blocks:
        exec(compile(block, str(DOC), "exec"), namespace)


def test_examples_reach_the_documented_values(tmp_path):
    """The examples are not only accepted: the values end up in the scene (a key typo would be refused,
    a key silently ignored would not)."""
    by_name = {}
    for index, block in enumerate(_blocks("toml")):
        path = tmp_path / f"example_{index}.toml"
        path.write_text(block, encoding="utf-8")
        scene = load_scene(path)
        by_name[scene.name] = scene
    assert by_name["ideal_short"].gravity == (0.0, 0.0, -1.62)
    assert by_name["implicit"].solver.jacobian == "finite-difference"
    assert by_name["guarded"].limits.max_wall_time == 600.0
    assert by_name["tilted_start"].misalignment_deg == {"R1": -0.035}
    assert by_name["arm_start"].initial_positions == {"shoulder": 0.3, "elbow": 0.8}
    assert by_name["small_file"].output.precision == "float32"
    clearances = {c.joint: c for c in by_name["both_clearance_types"].clearances}
    assert clearances["R1"].law.dissipation == "hunt_crossley" and clearances["R1"].outer_on == "parent"
    assert {spec.kind for spec in by_name["every_force_element"].forces} == set(FORCE_TYPES) - {"joint_force"}
    assert by_name["arm_driven_differently"].actuators["elbow"].mode == "none"
