"""The pipeline's shape (docs/architecture.md): imports run one way; scenes and the public API stay light."""

from __future__ import annotations

import ast
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

#: the stages of robot/, in the order data flows (a module may import its own stage and earlier ones)
STAGES = ["errors", "data", "scene", "model", "dynamics", "integration", "io", "run", "validation", "analysis", "viz", "sweep", "cli", "compat", "__init__"]

#: declarations of later stages that the scene layer validates against: registries and plain data,
#: none of which imports Pinocchio (test_scene_parsing_imports_no_pinocchio checks that)
SCHEMA_MODULES = {
    "robot.integration.options": "SolverOptions, FailureLimits: run configuration",
    "robot.integration.solvers": "the integrator names a scene may choose",
    "robot.dynamics.baumgarte": "Baumgarte gains: run configuration",
    "robot.dynamics.forces": "the force-element types a scene may declare",
    "robot.model.description": "URDF read as XML: which joint a clearance type may replace",
    "robot.model": "time functions of prescribed motions (robot.model.time_functions)",
    "robot.io.array_names": "the result arrays a scene's [output] keep may name",
}


def _stage(module: str) -> str | None:
    parts = module.split(".")
    if parts[0] != "robot":
        return None
    return "__init__" if len(parts) == 1 else parts[1]


def _imports(path: Path) -> list[str]:
    tree = ast.parse(path.read_text(encoding="utf-8"))
    names = []
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            names.append(node.module)
        elif isinstance(node, ast.Import):
            names.extend(alias.name for alias in node.names)
    return names


def test_imports_run_one_way():
    backward = []
    for path in sorted((ROOT / "robot").rglob("*.py")):
        module = ".".join(path.relative_to(ROOT).with_suffix("").parts).removesuffix(".__init__")
        source = _stage(module)
        for name in _imports(path):
            target = _stage(name)
            if target is None or target == source or STAGES.index(target) < STAGES.index(source):
                continue
            if name in SCHEMA_MODULES and source == "scene":
                continue
            backward.append(f"{module} imports {name} (stage {target} comes after {source})")
    assert not backward, "\n".join(backward)


def test_the_stage_list_covers_every_subpackage():
    subpackages = {p.name for p in (ROOT / "robot").iterdir() if p.is_dir() and (p / "__init__.py").is_file()}
    modules = {p.stem for p in (ROOT / "robot").glob("*.py")}
    assert subpackages | modules <= set(STAGES), sorted((subpackages | modules) - set(STAGES))


def _loaded_after(statement: str) -> set[str]:
    code = f"import sys; {statement}; print(' '.join(sorted(m.split('.')[0] for m in sys.modules)))"
    done = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, timeout=120, check=True)
    return set(done.stdout.split())


def test_scene_parsing_imports_no_pinocchio():
    loaded = _loaded_after("from robot.scene import load_scene; load_scene('compound_misaligned')")
    assert "pinocchio" not in loaded and "matplotlib" not in loaded


def test_public_api_and_contact_errors_import_lazily():
    loaded = _loaded_after("import robot, robot.errors, robot.analysis; robot.Error")
    assert not loaded & {"pinocchio", "numba", "scipy", "matplotlib", "exudyn", "dask"}, loaded


def test_old_module_paths_are_aliases_of_the_new_modules():
    """Code written against the flat robot/ of before keeps working (with a DeprecationWarning)."""
    import importlib
    import warnings

    from robot.compat import MOVED

    for old, new in MOVED.items():
        with warnings.catch_warnings(record=True):
            warnings.simplefilter("always")
            alias = importlib.import_module(old)
        assert alias is importlib.import_module(new) and alias.__spec__.name == new, old
    from robot.results import load_result as old_load  # noqa: F401 (the old spelling)
    from robot.io.results import load_result

    assert old_load is load_result
