"""The module paths of before the pipeline subpackages, kept working as aliases.

``robot/`` was a flat folder until the pipeline subpackages (``docs/architecture.md``);
code that imports ``robot.simulation``, ``robot.results``, ... keeps working: the old
name is the new module itself (one module object, so ``isinstance`` and monkeypatching
agree), with a :class:`DeprecationWarning` naming the new path. Installed by
``robot/__init__.py``; a meta-path finder, so no file stands at the old paths. The old
``robot.scene``, ``robot.dynamics`` and ``robot.cli`` modules are packages now: their
main names are re-exported there (``robot.scene.load_scene``, ``robot.cli.exit_on_error``).
"""

from __future__ import annotations

import importlib
import importlib.abc
import importlib.util
import sys
import warnings

#: old module -> new module
MOVED = {
    "robot.atomic": "robot.io.atomic",
    "robot.constraints": "robot.model.constraints",
    "robot.description": "robot.model.description",
    "robot.initial_state": "robot.model.initial_state",
    "robot.integrators": "robot.integration.solvers",
    "robot.jacobian_kernels": "robot.dynamics.jacobian_kernels",
    "robot.kinematics": "robot.model.kinematics",
    "robot.mechanism": "robot.model.mechanism",
    "robot.paper": "robot.analysis.paper",
    "robot.platform_kinematics": "robot.model.platform_kinematics",
    "robot.results": "robot.io.results",
    "robot.rhs_kernels": "robot.dynamics.rhs_kernels",
    "robot.simulation": "robot.integration.simulation",
    "robot.state_jacobian": "robot.dynamics.state_jacobian",
    "robot.summary": "robot.model.summary",
    "robot.trajectory": "robot.model.trajectory",
    "robot.ups_rps_design": "robot.model.ups_rps_design",
    "robot.visualization": "robot.viz.animation",
    "robot.studies": "robot.analysis.studies",
    "robot.studies.common": "robot.analysis.studies.common",
    "robot.studies.speed": "robot.analysis.studies.speed",
    "robot.studies.stability": "robot.analysis.studies.stability",
    "robot.studies.work_precision": "robot.analysis.studies.work_precision",
}


class _AliasLoader(importlib.abc.Loader):
    def __init__(self, target: str):
        self.target = target

    def create_module(self, spec):
        module = importlib.import_module(self.target)  # the new module object itself
        self.original_spec = module.__spec__  # the import system sets the alias's spec on it
        return module

    def exec_module(self, module) -> None:
        module.__spec__ = self.original_spec  # already executed under its new name: keep its own spec


class MovedModuleFinder(importlib.abc.MetaPathFinder):
    """Finds the old names of :data:`MOVED` and hands out the new modules."""

    def find_spec(self, fullname, path=None, target=None):
        new = MOVED.get(fullname)
        if new is None:
            return None
        warnings.warn(f"{fullname} moved to {new}; import it from there", DeprecationWarning, stacklevel=3)
        return importlib.util.spec_from_loader(fullname, _AliasLoader(new))


def install() -> None:
    if not any(isinstance(finder, MovedModuleFinder) for finder in sys.meta_path):
        sys.meta_path.insert(0, MovedModuleFinder())  # before the path finder: a stale folder must not shadow an alias
