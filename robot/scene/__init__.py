"""Scenes: TOML files and run configuration (no Pinocchio).

:func:`load_scene` reads, merges (``extends``), overrides (key paths) and
validates a scene into a :class:`Scene`; nothing here imports Pinocchio.
"""

from robot.scene.loader import Scene, load_scene, resolve_scene_path, shipped_scenes
from robot.scene.overrides import apply_overrides

__all__ = ["Scene", "load_scene", "resolve_scene_path", "shipped_scenes", "apply_overrides"]
