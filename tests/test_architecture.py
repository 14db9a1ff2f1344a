"""The pipeline's shape (docs/architecture.md): imports run one way; scenes and the public API stay light."""

from __future__ import annotations

import ast
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]

#: the stages of robot/, in the order data flows (a module may import its own stage and earlier ones)
STAGES = ["errors", "extensions", "data", "scene", "model", "dynamics", "integration", "io", "run", "validation", "analysis", "viz", "sweep", "cli", "compat", "__init__"]

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


#: what `clearance run` does (CLI, scene build, CVODE_BDF run with contact events and the structured
#: Jacobian), then the fixed-step methods on the same model; prints the scipy modules then loaded
_RUN_WITHOUT_SCIPY = """
import dataclasses, sys
from robot.cli.main import main
status = main(["run", "--scene", "compound_misaligned", "--t-end", "0.001", "--out", sys.argv[1]])
assert status in (0, None), status
from robot.integration.simulation import integrate
from robot.run import build_run
run = build_run("compound_misaligned", duration=2e-5)
for method in ("RK4", "GenAlpha", "Newmark"):
    options = dataclasses.replace(run.scene.solver, method=method, first_step=5e-6)
    assert integrate(run.dynamics, run.y0, run.t_span, options, run.scene.limits).success, method
print("scipy modules:", *sorted(m for m in sys.modules if m == "scipy" or m.startswith("scipy.")))
print("numba imported:", "numba" in sys.modules)
"""


#: scipy's subpackages a CVODE or fixed-step run must not load (0.3-0.8 s of imports together)
_HEAVY_SCIPY = ("scipy.integrate", "scipy.optimize", "scipy.sparse", "scipy.special", "scipy.interpolate", "scipy.stats", "scipy.spatial")


@pytest.mark.parametrize("kernels", ["python", "numba", "library"], ids=["python kernels", "numba kernels", "kernel library"])
def test_a_cvode_or_fixed_step_run_imports_no_heavy_scipy(tmp_path, kernels, request):
    """scipy's integrators, root finders and sparse matrices cost 0.3-0.8 s to import (issue 16):
    CVODE and the fixed-step methods need none of them.

    Nor ``scipy.linalg`` (0.13-0.25 s, most of it numpy submodules its initialisation
    pulls in): the structured Jacobian's Cholesky solve and the redundancy check's
    pivoted QR call scipy's LAPACK module alone (``robot.model.lapack``, same bits).
    Only numba still imports it, at its start: with the kernels in plain Python
    (``CLEARANCE_CONTACT_JIT=0``) and from the kernel library, neither numba nor
    ``scipy.linalg`` is imported.
    """
    from clearance_contact.kernel_library import child_environment

    environment = child_environment(kernels)
    if kernels == "library":
        environment["CLEARANCE_KERNEL_DIR"] = str(request.getfixturevalue("kernel_library_dir").parent)
    done = subprocess.run(
        [sys.executable, "-c", _RUN_WITHOUT_SCIPY, str(tmp_path)], cwd=ROOT, env=environment, capture_output=True, text=True, timeout=600
    )
    assert done.returncode == 0, done.stderr[-3000:]
    (report,) = [line for line in done.stdout.splitlines() if line.startswith("scipy modules:")]
    loaded = [name for name in report.split()[2:] if name.startswith(_HEAVY_SCIPY)]
    assert loaded == [], f"scipy modules imported by a CVODE / fixed-step run: {loaded}"
    numba_imported = "numba imported: True" in done.stdout
    assert numba_imported == (kernels == "numba")
    if kernels != "numba":
        assert "scipy.linalg" not in report.split()[2:], report


def test_scipy_methods_are_imported_on_first_use():
    """The registry names scipy's methods as "module:attribute": their class comes when a run asks for it."""
    loaded = _loaded_after(
        "from robot.integration import methods; assert 'scipy' not in sys.modules; "
        "from robot.integration.solvers import make_solver; import numpy as np; "
        "s = make_solver('Radau', lambda t, y: -y, 0.0, np.ones(2), 1.0, 1e-6, 1e-9, np.inf, None); s.step(); "
        "assert type(s).__module__.startswith('scipy.integrate') and s.status == 'running'"
    )
    assert "scipy" in loaded
