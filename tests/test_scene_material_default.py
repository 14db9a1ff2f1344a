"""A clearance joint's material: the default name "steel" is only a name (no material is built in),
so a scene that defines none is told to define [materials.steel] or to set ``material``; a key the
scene did write is named as written (robot.scene.loader)."""

from __future__ import annotations

import pytest

from robot.errors import SceneError
from robot.scene.loader import load_scene

SCENE = """mechanism = "ups_rps.urdf"
duration = 0.1
[trajectory]
preset = "reference"
{materials}
[[clearance]]
joint = "S1"
type = "spherical"
ball_radius = 0.015
clearance = 1e-4
{material_key}
"""


def scene(tmp_path, materials: str = "", material_key: str = ""):
    path = tmp_path / "scene.toml"
    path.write_text(SCENE.format(materials=materials, material_key=material_key))
    return path


def test_a_defaulted_material_is_said_to_be_the_default(tmp_path):
    with pytest.raises(SceneError) as caught:
        load_scene(scene(tmp_path))
    message = str(caught.value)
    assert "default material 'steel' is not defined" in message
    assert "[materials.steel]" in message and 'material = "NAME"' in message
    assert "outer_material" not in message  # a key the scene never wrote


def test_a_written_material_key_is_named_as_written(tmp_path):
    steel = "[materials.steel]\nyoungs_modulus = 2e11\npoisson_ratio = 0.3"
    with pytest.raises(SceneError, match=r"material='brass' is not defined; defined materials: steel") as caught:
        load_scene(scene(tmp_path, steel, 'material = "brass"'))
    assert "outer_material" not in str(caught.value)
    with pytest.raises(SceneError, match=r"inner_material='brass' is not defined"):
        load_scene(scene(tmp_path, steel, 'inner_material = "brass"'))


def test_a_defined_steel_is_used_by_default(tmp_path):
    steel = "[materials.steel]\nyoungs_modulus = 2e11\npoisson_ratio = 0.3"
    loaded = load_scene(scene(tmp_path, steel))
    assert [c.joint for c in loaded.clearances] == ["S1"]
