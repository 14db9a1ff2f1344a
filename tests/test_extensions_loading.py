"""The user's extensions reach the commands: ``CLEARANCE_EXTENSIONS`` names modules imported before anything is looked up.

An integrator defined outside the project (explicit Euler, in a module of a
temporary folder) is named by a scene file and run by ``clearance run`` in a
fresh process: the command imports the module, the scene validates, the run
is first order in the step like any explicit Euler. A module that is missing or
fails while it is imported stops the command with exit 2 and a one-line message
naming it (no traceback).
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from robot import extensions
from robot.cli.main import main
from robot.extensions import ExtensionError, extension_names, load_extensions

ROOT = Path(__file__).resolve().parents[1]

#: a user's module: explicit Euler (the class of tests/test_integrator_registry.py), registered under its own name
EULER_MODULE = """
from robot.integration import methods
from test_integrator_registry import ExplicitEuler

methods.register(methods.IntegratorTraits("UserEuler", ExplicitEuler, fixed_step=True, explicit=True, stages=1, replayable=True))
"""


def _scene(folder: Path, step: float) -> Path:
    path = folder / f"euler_{step:g}.toml"
    path.write_text(
        f'extends = "ideal"\nname = "euler_{step:g}"\nduration = 0.02\n[solver]\nmethod = "UserEuler"\nfirst_step = {step!r}\n'
        '[output]\nprecision = "float64"\n'
    )
    return path


def _clearance(folder: Path, *args: str, modules: str) -> subprocess.CompletedProcess:
    env = dict(os.environ, CLEARANCE_EXTENSIONS=modules, PYTHONPATH=os.pathsep.join([str(folder), str(ROOT / "tests"), str(ROOT)]))
    return subprocess.run([sys.executable, "-m", "robot.cli", *args], cwd=folder, env=env, capture_output=True, text=True, timeout=600)


def test_names_are_split_on_commas_in_order_without_duplicates():
    assert extension_names(" a.b , c,,a.b ,d ") == ["a.b", "c", "d"]
    assert extension_names("") == []


def test_a_scene_runs_a_user_integrator_named_in_the_environment(tmp_path):
    """Two steps of a first-order method: halving the step halves the error against RK45 (the ideal mechanism)."""
    (tmp_path / "user_euler.py").write_text(EULER_MODULE)
    final = {}
    for step in (2e-5, 1e-5):
        done = _clearance(tmp_path, "run", "--scene", str(_scene(tmp_path, step)), "--out", str(tmp_path / "out"), modules="user_euler")
        assert done.returncode == 0, done.stderr[-2000:]
        with np.load(tmp_path / "out" / f"euler_{step:g}.npz") as result:
            final[step] = result["q"][-1]
    reference = tmp_path / "rk45.toml"
    reference.write_text('extends = "ideal"\nname = "rk45"\nduration = 0.02\n[solver]\nmethod = "RK45"\nrtol = 1e-11\natol = 1e-13\n[output]\nprecision = "float64"\n')
    done = _clearance(tmp_path, "run", "--scene", str(reference), "--out", str(tmp_path / "out"), modules="")
    assert done.returncode == 0, done.stderr[-2000:]
    with np.load(tmp_path / "out" / "rk45.npz") as result:
        exact = result["q"][-1]
    ratio = np.linalg.norm(final[2e-5] - exact) / np.linalg.norm(final[1e-5] - exact)
    assert 1.8 < ratio < 2.2, ratio


def test_a_sweep_s_workers_load_the_extensions_too(tmp_path):
    """The scene is validated again in each worker process (a LocalCluster of its own processes): they import the
    modules named in the environment they inherit."""
    (tmp_path / "user_euler.py").write_text(EULER_MODULE)
    sweep = tmp_path / "sweep.toml"
    sweep.write_text(
        f'[sweep]\nscene = "{_scene(tmp_path, 2e-5).as_posix()}"\nt_end = 0.004\n\n'
        '[[axis]]\nkey = "solver.first_step"\nvalues = [2e-5, 1e-5]\n'
    )
    done = _clearance(tmp_path, "sweep", str(sweep), "--out", str(tmp_path / "sw"), "--workers", "1", "--no-figures", "--no-progress", modules="user_euler")
    assert done.returncode == 0, done.stderr[-3000:]
    from robot.sweep import open_sweep

    store = open_sweep(tmp_path / "sw" / "sweep.zarr")
    assert (store["status"].values == 0).all() and store["status"].size == 2


def test_without_the_variable_the_scene_names_an_unknown_method(tmp_path):
    (tmp_path / "user_euler.py").write_text(EULER_MODULE)
    done = _clearance(tmp_path, "run", "--scene", str(_scene(tmp_path, 1e-5)), "--check", modules="")
    assert done.returncode == 2 and "UserEuler" in done.stderr and "Traceback" not in done.stderr


def test_a_missing_module_stops_the_command_with_exit_2(monkeypatch, capsys):
    monkeypatch.setenv(extensions.VARIABLE, "no_such_extension_module")
    assert main(["describe"]) == 2
    err = capsys.readouterr().err
    assert "CLEARANCE_EXTENSIONS: module 'no_such_extension_module' not found" in err and "Traceback" not in err


def test_a_module_failing_at_import_is_named_with_the_line(tmp_path, monkeypatch):
    (tmp_path / "broken_extension.py").write_text("import math\n\nVALUE = 1 / 0\n")
    (tmp_path / "needs_missing.py").write_text("import no_such_dependency_module\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    with pytest.raises(ExtensionError, match=r"importing 'broken_extension' failed: ZeroDivisionError: division by zero \(.*broken_extension\.py:3\)"):
        load_extensions("broken_extension")
    # a dependency of the module missing is the module failing, not the module missing
    with pytest.raises(ExtensionError, match=r"importing 'needs_missing' failed: ModuleNotFoundError: No module named 'no_such_dependency_module'"):
        load_extensions("needs_missing")


def test_each_module_is_imported_once(tmp_path, monkeypatch):
    (tmp_path / "counting_extension.py").write_text("import builtins\nbuiltins.extension_imports = getattr(builtins, 'extension_imports', 0) + 1\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    import builtins

    assert load_extensions("counting_extension") == ["counting_extension"]
    assert load_extensions("counting_extension, counting_extension") == ["counting_extension"]
    assert builtins.extension_imports == 1
    del builtins.extension_imports
