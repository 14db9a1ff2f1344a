"""The kernel library (clearance_contact.kernel_library): ahead-of-time kernels, loaded without numba.

* a library built into a temporary folder (the real build: numba.pycc and the C guards) is fresh there;
* its guards take exactly the arguments numba would type as an exported signature, checked
  against ``numba.typeof`` on a battery of arrays and scalars (layouts, strides, dtypes,
  byte order, read-only, unaligned, subclasses, ints out of range, numpy scalars);
* a call no export takes goes to numba's just-in-time kernel and gives its result (a strided
  view is not read as contiguous, a float32 array does not crash), and the process says why;
* whole runs give the same arrays bit for bit with the library and with numba's JIT, on
  mechanisms the library's signatures were not written from (planar and spatial linkages,
  redundant closures, spherical and revolute clearance joints, a law without a compiled
  kernel), and a library run imports no numba;
* staleness: another digest, a missing extension or a changed source means no library;
* ``ensure_library`` and ``clearance build-kernels``: off when the environment asks for another
  mode, fresh without a build, a failed build reported and not fatal.
"""

from __future__ import annotations

import enum
import json
import os
import shutil
import subprocess
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest

from clearance_contact import kernel_library
from tests.conftest import closure_scene

ROOT = Path(__file__).resolve().parents[1]


def _env(library: Path, mode: str = "1") -> dict:
    """A process's environment that finds ``library`` (a folder of :func:`kernel_library.library_folder`'s kind)."""
    return dict(os.environ, CLEARANCE_KERNEL_DIR=str(library.parent), CLEARANCE_CONTACT_JIT=mode, PYTHONPATH=str(ROOT))


@pytest.fixture(name="library_dir", scope="module")
def library_dir_fixture(kernel_library_dir) -> Path:
    """The library conftest builds once per session into a temporary folder (the real build)."""
    return kernel_library_dir


@pytest.fixture(scope="module")
def library(library_dir):
    loaded = kernel_library.load(library_dir)
    assert loaded is not None
    return loaded


def test_the_built_library_is_fresh_and_complete(library_dir, library):
    """Every kernel that declares exports is in the manifest with each of its signatures, and loads."""
    assert (library_dir / kernel_library.MANIFEST).is_file()
    from clearance_contact import compiled
    from robot.dynamics import kernel_build
    import importlib

    for name in kernel_build.KERNEL_MODULES:
        importlib.import_module(name)
    declared = {name: kernel.exports for name, kernel in compiled.KERNELS.items() if kernel.exports}
    exported = library.manifest["exports"]
    assert declared and set(exported) == set(declared)
    for name, signatures in declared.items():
        assert [entry["signature"] for entry in exported[name]] == list(signatures)
        for entry in exported[name]:
            assert callable(getattr(library.kernels, entry["symbol"]))
    assert kernel_library.is_fresh(library_dir)
    assert "robot/dynamics/rhs_kernels.py" in library.manifest["sources"]


# --- the guards against numba's typeof ---------------------------------------------------------------


def _arrays() -> list[tuple[str, object]]:
    """Arrays of every kind a caller might pass: the layouts and flags numba types differently."""
    base = np.arange(24.0)
    readonly = base.reshape(4, 6).copy()
    readonly.flags.writeable = False
    with warnings.catch_warnings():  # numpy's own notice that np.matrix is discouraged: that is why it is here
        warnings.simplefilter("ignore", PendingDeprecationWarning)
        matrix = np.asmatrix(np.zeros((2, 2)))
    unaligned = np.frombuffer(bytearray(b"\0" + np.arange(6.0).tobytes()), dtype=np.float64, count=6, offset=1)  # writeable
    return [
        ("f8 1-d", np.arange(5.0)),
        ("f8 1-d strided", base[::2]),
        ("f8 1-d single", np.zeros(1)),
        ("f8 1-d empty", np.zeros(0)),
        ("f8 C 2-d", base.reshape(4, 6)),
        ("f8 F 2-d", np.asfortranarray(base.reshape(4, 6))),
        ("f8 column (C and F)", np.zeros((6, 1))),
        ("f8 row (C and F)", np.zeros((1, 6))),
        ("f8 2-d strided", base.reshape(4, 6)[:, ::2]),
        ("f8 2-d transposed view", base.reshape(4, 6).T),
        ("f8 C 3-d", base.reshape(2, 3, 4)),
        ("f8 read-only", readonly),
        ("f8 unaligned", unaligned),
        ("f8 big-endian", np.arange(5.0).astype(">f8")),
        ("f4 1-d", np.arange(5.0, dtype=np.float32)),
        ("i8 1-d", np.arange(5)),
        ("i8 C 2-d", np.arange(6).reshape(2, 3)),
        ("i4 1-d", np.arange(5, dtype=np.int32)),
        ("longlong 1-d", np.arange(5, dtype=np.longlong)),
        ("bool 1-d", np.zeros(3, dtype=bool)),
        ("complex 1-d", np.zeros(3, dtype=complex)),
        ("0-d f8", np.array(1.0)),
        ("matrix subclass", matrix),
    ]


def _scalars() -> list[tuple[str, object]]:
    return [
        ("float", 1.5), ("np.float64", np.float64(1.5)), ("np.float32", np.float32(1.5)), ("int", 3),
        ("int out of int64", 2**70), ("np.int64", np.int64(3)), ("np.int32", np.int32(3)), ("True", True),
        ("np.bool_", np.bool_(True)), ("None", None), ("str", "x"), ("list", [1.0, 2.0]),
        ("np.longlong", np.longlong(3)), ("IntEnum", _Small.ONE),
    ]  # fmt: skip


class _Small(enum.IntEnum):
    ONE = 1


#: what the guards refuse though numba takes it (the call then goes to numba: slower, never wrong):
#: ndarray subclasses, unaligned data (numba types it as aligned; the library is not asked to), and
#: np.longlong scalars (int64 to numba, a type of its own to numpy's C API)
_STRICTER = {"matrix subclass", "f8 unaligned", "np.longlong"}


def _numba_takes(value, numba_type) -> bool:
    """Would numba's dispatcher type ``value`` as ``numba_type``? (An F-declared array also takes an
    array numba calls C that is F-contiguous as well: one memory layout, e.g. a column.)"""
    import numba
    from numba.core import types

    try:
        typed = numba.typeof(value)
    except Exception:  # noqa: BLE001 - numba's own errors for what it cannot type (big-endian, huge ints)
        return False
    if typed == numba_type:
        return True
    if isinstance(numba_type, types.Array) and isinstance(typed, types.Array) and numba_type.layout == "F":
        return bool(value.flags.f_contiguous) and typed.copy(layout="F") == numba_type
    return False


def _declared_types(library) -> list:
    """Every distinct argument type of the library's exported signatures (numba types and descriptions)."""
    from numba.core import sigutils, types

    seen = {}
    for entries in library.manifest["exports"].values():
        for entry in entries:
            arguments, _ = sigutils.normalize_signature(entry["signature"])
            for numba_type, description in zip(arguments, entry["arguments"]):
                if not isinstance(numba_type, types.BaseTuple):
                    seen[str(numba_type)] = (numba_type, description)
    return list(seen.values())


def test_a_guard_takes_exactly_what_numba_types_as_the_signature(library):
    """Sound (a value taken is one numba types as declared: nothing is read wrongly) and complete
    (what numba types as declared is taken: no needless fall-back), for every declared type."""
    declared = _declared_types(library)
    assert len(declared) >= 8
    for numba_type, description in declared:
        spec = kernel_library.guard_spec(description)
        checked = 0
        for label, value in _arrays() + _scalars():
            taken = library.guards.check(value, spec)
            expected = _numba_takes(value, numba_type)
            if label in _STRICTER:
                assert not taken, (numba_type, label)  # stricter than numba: such calls go to numba itself
                continue
            assert taken == expected, f"{numba_type} given {label}: guard {taken}, numba {expected}"
            checked += taken
        assert checked >= 1, numba_type  # each declared type took at least one value of the battery


def test_a_tuple_argument_is_checked_item_by_item(library):
    """``site_stiffness`` takes a tuple of four arrays: wrong length, wrong item, a list: not taken."""
    (entry,) = library.manifest["exports"]["robot.dynamics.jacobian_kernels.site_stiffness"]
    spec = kernel_library.guard_spec(next(d for d in entry["arguments"] if d["kind"] == "tuple"))
    good = (np.zeros((2, 3, 4)), np.zeros((2, 3)), np.zeros((2, 3)), np.zeros(3))
    assert library.guards.check(good, spec)
    assert not library.guards.check(good[:3], spec)
    assert not library.guards.check((good[0], np.asfortranarray(np.zeros((2, 3))), good[2], good[3]), spec)
    assert not library.guards.check(list(good), spec)


def test_the_guard_type_sends_other_calls_to_its_fallback(library):
    """Keywords, another number of arguments, other types: the fallback; the fallback can be replaced
    (switch_to_numba does); malformed descriptions are refused when the guard is made."""
    calls = []
    spec = kernel_library.guard_spec({"kind": "array", "dtype": "float64", "ndim": 1, "layout": "C", "mutable": True})
    guard = library.guards.Guard(
        (((spec, (0,)), lambda *a: calls.append(("export", len(a))) or "export"),), lambda *a, **k: calls.append(("fallback", len(a), tuple(k))) or "fallback"
    )  # fmt: skip
    vector = np.zeros(3)
    assert guard(vector, 1.0) == "export"
    assert guard(vector, x=1.0) == "fallback" and guard(vector) == "fallback" and guard(vector, 1.0, 2.0) == "fallback"
    assert guard(vector[::2], 1.0) == "fallback" and guard(vector, 1) == "fallback"
    assert calls == [("export", 2), ("fallback", 1, ("x",)), ("fallback", 1, ()), ("fallback", 3, ()), ("fallback", 2, ()), ("fallback", 2, ())]
    guard.fallback = lambda *a: "replaced"
    assert guard(vector) == "replaced"
    with pytest.raises(TypeError):
        guard.fallback = 3
    for malformed in [(), ("3",), (3, 102, 8), (3, 102, 8, 1, -1), (9,), (0, 1), (4, (3,)), (3, 102, 8, 1, 2**80)]:
        with pytest.raises((ValueError, OverflowError)):
            library.guards.Guard((((malformed,), len),), len)
        with pytest.raises((ValueError, OverflowError)):
            library.guards.check(1.0, malformed)
    with pytest.raises(ValueError):
        library.guards.Guard((("not a version",),), len)
    with pytest.raises(TypeError):
        library.guards.Guard((), "not callable")


_FALLBACK_SCRIPT = """
import sys, json, warnings, numpy as np
from clearance_contact import compiled
from robot.integration import events
before = (compiled.KERNEL_MODE, "numba" in sys.modules, hasattr(events.all_finite, "py_func"), events.all_finite.__name__)
contiguous = events.all_finite(np.array([1.0, 2.0]))
with warnings.catch_warnings(record=True) as caught:
    warnings.simplefilter("always")
    strided = events.all_finite(np.array([1.0, np.nan, 2.0, np.nan])[::2])  # [1, 2]: finite
single = events.all_finite(np.array([1.0, np.inf], dtype=np.float32))
print(json.dumps({"before": before, "results": [contiguous, strided, single], "after": compiled.KERNEL_MODE,
                  "switched_by": compiled.SWITCHED_BY, "numba": "numba" in sys.modules,
                  "warned": [(type(w.message).__name__, w.filename) for w in caught]}))
"""


def test_a_call_the_library_cannot_take_gets_numbas_result(library_dir):
    """A strided view and a float32 array: numba's answers (not a contiguous misreading, not a crash),
    after which the process runs numba and says which call made it switch."""
    done = subprocess.run([sys.executable, "-c", _FALLBACK_SCRIPT], cwd=ROOT, env=_env(library_dir), capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr[-3000:]
    report = json.loads(done.stdout.strip().splitlines()[-1])
    assert report["before"] == ["library", False, True, "all_finite"]
    assert report["results"] == [True, True, False]
    assert report["after"] == "numba" and report["numba"]
    assert report["switched_by"].startswith("robot.integration.events.all_finite(float64[1d, A]")
    assert report["warned"] == [["KernelSwitchWarning", "<string>"]]  # once, pointing at the caller


_PUBLIC_EVALUATE_SCRIPT = """
import sys, json, warnings, numpy as np
import clearance_contact as cc
from clearance_contact import compiled
from clearance_contact.kernel_mode import KernelSwitchWarning
from clearance_contact.radial_laws import RADIAL_LAWS, radial_law
warnings.simplefilter("error", KernelSwitchWarning)
laws = [
    cc.SphericalClearanceJoint(0.015, 0.0151, cc.STEEL, cc.STEEL, friction=cc.CoulombFriction(0.1, 1e-3)),
    cc.RevoluteClearanceJoint(0.01, 0.0101, 0.016, 0.0204, 0.02, cc.STEEL, cc.STEEL),
    cc.TranslationalClearanceJoint(0.05, 0.02, 0.01, 0.0202, 0.0102, cc.STEEL, cc.STEEL, corner_radius=1.5e-3),
]
tilt = np.array([[1.0, 0.0, 0.0], [0.0, np.cos(0.002), -np.sin(0.002)], [0.0, np.sin(0.002), np.cos(0.002)]])
offset, twist = np.array([1.2e-4, 0.0, 0.0]), np.array([0.1, -0.2, 0.0, 0.0, 0.0, 0.1])
orders = {"C": np.ascontiguousarray, "F": np.asfortranarray}
def read_only(array):
    array = np.array(array)
    array.setflags(write=False)
    return array
outputs, forces = [], []
for law in laws:
    onset = np.full(law.N_CANDIDATES, 0.1)
    for outer in "CF":
        for inner in "CF":
            rotations = orders[outer](np.eye(3)), orders[inner](tilt)
            result = law.evaluate(rotations[0], np.zeros(3), twist, rotations[1], offset, -twist, onset)
            outputs.append(np.concatenate([result.normal_force.ravel(), result.wrench_outer, result.wrench_inner]).tolist())
            forces.append(float(np.max(result.normal_force)))
            outputs.append(law.penetration(rotations[0], np.zeros(3), rotations[1], offset).tolist())
    # a strided rotation (a block of a transform), a read-only twist and a strided onset: copied, not a new specialisation
    transform = np.eye(4)
    transform[:3, :3] = tilt
    strided = law.evaluate(np.eye(3), np.zeros(3), read_only(twist), transform[:3, :3], offset, -twist, np.repeat(onset, 2)[::2])
    outputs.append(np.concatenate([strided.normal_force.ravel(), strided.wrench_outer, strided.wrench_inner]).tolist())
for name in RADIAL_LAWS:  # the radial laws' line loads, as clearance contact-laws tabulates them
    law = radial_law(name, 0.01, 0.0101, 0.02, cc.STEEL, cc.STEEL)
    outputs.append([law.line_density(delta) for delta in (0.0, 1e-6, 1e-5, 1e-4)])
print(json.dumps({"mode": compiled.KERNEL_MODE, "switched_by": compiled.SWITCHED_BY, "numba": "numba" in sys.modules,
                  "outputs": outputs, "forces": forces}))
"""


def test_the_public_evaluate_stays_on_the_library_with_numpys_rotations(library_dir):
    """Rotations as numpy makes them (C order) or as Pinocchio hands them over (Fortran order), in every
    combination, for the three shipped laws' forces and penetrations; strided and read-only inputs; every
    radial law's line load (``clearance contact-laws``): the library takes every call (no switch to numba, no
    numba imported), with numba's JIT's results bit for bit; every law is in contact (a positive force)."""
    reports = {}
    for mode in ("1", "numba"):
        done = subprocess.run([sys.executable, "-c", _PUBLIC_EVALUATE_SCRIPT], cwd=ROOT, env=_env(library_dir, mode), capture_output=True, text=True, timeout=600)
        assert done.returncode == 0, done.stderr[-3000:]
        reports[mode] = json.loads(done.stdout.strip().splitlines()[-1])
    library, jit = reports["1"], reports["numba"]
    assert (library["mode"], library["switched_by"], library["numba"]) == ("library", None, False)
    assert jit["mode"] == "numba"
    assert library["outputs"] == jit["outputs"]
    assert len(library["forces"]) == 12 and min(library["forces"]) > 0.0


_WITHOUT_NUMBA_SCRIPT = """
import sys, json, numpy as np
from clearance_contact import compiled
from robot.integration import events
from robot.run import build_run, run_scene
library = compiled.KERNEL_MODE
result = run_scene(build_run("compound_misaligned", duration=0.01))
steps = int(result.counts["n_steps"])
strided = events.all_finite(np.array([1.0, np.nan, 2.0, np.nan])[::2])  # no export takes it, and numba is missing
print(json.dumps({"library": library, "steps": steps, "strided": strided, "after": compiled.KERNEL_MODE}))
"""


def test_the_library_runs_without_numba_and_falls_back_to_python(library_dir, tmp_path):
    """numba not installed (blocked): the library still runs the kernels; a call it cannot take runs
    the kernel's Python source (right, slower), since there is no numba to switch to."""
    (tmp_path / "sitecustomize.py").write_text("import sys\nsys.modules['numba'] = None\n")
    env = dict(_env(library_dir), PYTHONPATH=f"{tmp_path}{os.pathsep}{ROOT}")
    done = subprocess.run([sys.executable, "-c", _WITHOUT_NUMBA_SCRIPT], cwd=ROOT, env=env, capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr[-3000:]
    report = json.loads(done.stdout.strip().splitlines()[-1])
    assert report["library"] == "library" and report["steps"] > 10
    assert report["strided"] is True and report["after"] == "python"


# --- whole runs: library against numba's JIT, bit for bit ----------------------------------------------

_RUN_SCRIPT = """
import sys, json, numpy as np
from robot.run import build_run, run_scene
arrays = {}
for index, (scene, duration) in enumerate(json.loads(sys.argv[2])):
    result = run_scene(build_run(scene, duration=duration))
    arrays.update({f"{index}:{key}": np.asarray(value) for key, value in result.arrays.items()})
np.savez(sys.argv[1], **arrays)
from clearance_contact import compiled
print(json.dumps({"mode": compiled.KERNEL_MODE, "numba": "numba" in sys.modules, "switched_by": compiled.SWITCHED_BY}))
"""


def _run(library_dir: Path, mode: str, out: Path, scenes: list) -> dict:
    done = subprocess.run(
        [sys.executable, "-c", _RUN_SCRIPT, str(out), json.dumps(scenes)], cwd=ROOT, env=_env(library_dir, mode), capture_output=True, text=True, timeout=900
    )
    assert done.returncode == 0, done.stderr[-3000:]
    return json.loads(done.stdout.strip().splitlines()[-1])


def _assert_same_arrays(first: Path, second: Path) -> int:
    a, b = np.load(first), np.load(second)
    assert sorted(a.files) == sorted(b.files)
    for key in a.files:
        assert a[key].shape == b[key].shape and a[key].tobytes() == b[key].tobytes(), key
    return len(a.files)


def test_runs_are_the_same_bit_for_bit_and_import_no_numba(library_dir, tmp_path):
    """Spatial RSSR, redundant mixed closures (revolute + spherical clearance), a slider-crank, the
    4-UPS/RPS with a misaligned revolute joint and a torque-driven free linkage (also with scipy's BDF, whose
    difference Jacobian passes strided states): every output array
    identical; the library run never imports numba."""
    bdf_scene = tmp_path / "free_bdf.toml"
    bdf_scene.write_text('extends = "free_two_link_spring"\nname = "free_bdf"\n[solver]\nmethod = "BDF"\n')
    scenes = [
        (str(closure_scene(tmp_path, "rssr_rocker_clearance")), 0.03),
        (str(closure_scene(tmp_path, "mixed_clearance")), 0.03),
        (str(closure_scene(tmp_path, "slider_crank_rod_clearance")), 0.03),
        ("compound_misaligned", 0.05),
        ("free_two_link_spring", 0.05),
        (str(bdf_scene), 0.02),  # scipy's BDF differences the right-hand side on columns of a 2-D array
    ]
    from_library = _run(library_dir, "1", tmp_path / "library.npz", scenes)
    from_numba = _run(library_dir, "numba", tmp_path / "numba.npz", scenes)
    assert from_library == {"mode": "library", "numba": False, "switched_by": None}
    assert from_numba["mode"] == "numba"
    assert _assert_same_arrays(tmp_path / "library.npz", tmp_path / "numba.npz") > 5 * 20


_PYTHON_LAW_SCRIPT = """
import sys, json, numpy as np
sys.path.insert(0, sys.argv[2])
from tests.conftest import with_python_laws
from robot.run import build_run
from robot.dynamics import equations as D
run = build_run("spherical")
dynamics = with_python_laws(run.dynamics)
workspace, rng = D.make_workspace(dynamics), np.random.default_rng(5)
nq, nv = dynamics.nq, dynamics.nv
derivatives = []
for k in range(5):  # velocities perturbed (positions stay on the closures)
    y = run.y0.copy()
    y[nq : nq + nv] += rng.normal(scale=0.2, size=nv)
    derivatives.append(D.state_derivative(dynamics, workspace, 0.01 * k, y, np.full(dynamics.n_candidates, 0.1)))
np.save(sys.argv[1], np.array(derivatives))
from clearance_contact import compiled
print(json.dumps({"mode": compiled.KERNEL_MODE, "switched_by": compiled.SWITCHED_BY}))
"""


def test_a_law_without_a_compiled_kernel_stays_on_the_library_with_numbas_result(library_dir, tmp_path):
    """The site-by-site path (a law seen only through Python, e.g. a user's friction law) calls kernels the
    library exports (site_twists, add_site_wrenches): no switch to numba, and numba's right-hand sides bit for bit."""
    outputs = {}
    for mode in ("1", "numba"):
        done = subprocess.run(
            [sys.executable, "-c", _PYTHON_LAW_SCRIPT, str(tmp_path / f"{mode}.npy"), str(ROOT)],
            cwd=ROOT, env=_env(library_dir, mode), capture_output=True, text=True, timeout=900,
        )  # fmt: skip
        assert done.returncode == 0, done.stderr[-3000:]
        outputs[mode] = json.loads(done.stdout.strip().splitlines()[-1])
    assert outputs["1"] == {"mode": "library", "switched_by": None} and outputs["numba"]["mode"] == "numba"
    assert np.load(tmp_path / "1.npy").tobytes() == np.load(tmp_path / "numba.npy").tobytes()


# --- staleness, ensure_library, the command ---------------------------------------------------------


def test_another_digest_or_a_missing_extension_means_no_library(library_dir, tmp_path):
    copy = tmp_path / "copy"
    shutil.copytree(library_dir, copy)
    assert kernel_library.load(copy) is not None
    manifest = json.loads((copy / kernel_library.MANIFEST).read_text())
    (copy / kernel_library.MANIFEST).write_text(json.dumps(dict(manifest, digest="0" * 64)))
    assert not kernel_library.is_fresh(copy) and kernel_library.load(copy) is None
    (copy / kernel_library.MANIFEST).write_text(json.dumps(manifest))
    (copy / manifest["filename"]).unlink()
    assert not kernel_library.is_fresh(copy) and kernel_library.load(copy) is None  # a fresh digest, nothing to load
    (copy / kernel_library.MANIFEST).write_text("{not json")
    assert kernel_library.load(copy) is None


def test_the_digest_follows_every_source_of_the_kernels_folders(tmp_path, monkeypatch):
    """A changed constant in any file beside a kernel's source changes the digest (compiled code reads them)."""
    (tmp_path / "pkg").mkdir()
    kernel, helper = tmp_path / "pkg" / "kernels.py", tmp_path / "pkg" / "constants.py"
    kernel.write_text("def f(): pass\n")
    helper.write_text("LIMIT = 1.0\n")
    monkeypatch.setattr(kernel_library, "ANCHOR", tmp_path)
    sources = kernel_library.source_files([kernel])
    assert sources == ["pkg/constants.py", "pkg/kernels.py"]
    first = kernel_library.digest(sources)
    helper.write_text("LIMIT = 2.0\n")
    assert kernel_library.digest(sources) != first


def test_ensure_library_respects_the_environment_and_reports_a_failed_build(library_dir, tmp_path, monkeypatch, capsys):
    from robot.dynamics.kernel_build import ensure_library

    monkeypatch.setenv("CLEARANCE_KERNEL_DIR", str(library_dir.parent))
    for mode in ("0", "numba"):
        monkeypatch.setenv("CLEARANCE_CONTACT_JIT", mode)
        assert ensure_library() == "off"
    monkeypatch.setenv("CLEARANCE_CONTACT_JIT", "1")
    assert ensure_library() == "fresh"
    blocker = tmp_path / "a file"
    blocker.write_text("")
    monkeypatch.setenv("CLEARANCE_KERNEL_DIR", str(blocker))  # its folder cannot be made: the build fails fast
    outcome = ensure_library()
    assert outcome.startswith("unavailable: ")
    assert "runs use numba's just-in-time kernels until it is" in capsys.readouterr().err


def test_a_failed_build_is_recorded_and_not_tried_at_every_command(tmp_path, monkeypatch, capsys):
    """No working C compiler: the build fails once, says why, and later commands do not try again
    until the sources or the compilers change; ``retry_failed`` (clearance build-kernels) does."""
    from robot.dynamics.kernel_build import ensure_library

    monkeypatch.setenv("CLEARANCE_KERNEL_DIR", str(tmp_path))
    monkeypatch.setenv("CLEARANCE_CONTACT_JIT", "1")
    monkeypatch.setenv("CC", "/bin/false")  # distutils' compiler: numba's compiler check fails at once
    first = ensure_library()
    assert first.startswith("unavailable: ") and "C and C++ compilers" in first, first
    assert kernel_library.failed_build() is not None
    assert "was not built" in capsys.readouterr().err
    again = ensure_library()
    assert again.startswith("unavailable: ") and "build-kernels` tries again" in capsys.readouterr().err  # from the record
    assert ensure_library(retry_failed=True).startswith("unavailable: ") and "was not built" in capsys.readouterr().err
    monkeypatch.setenv("CC", "/bin/true")  # other compilers: the record no longer applies
    assert kernel_library.failed_build() is None


def test_a_read_only_package_folder_sends_builds_to_the_user_cache(tmp_path, monkeypatch):
    """Reads look in the package's folder first (a library built at installation), then the user's cache;
    a build writes to the first that can be written."""
    monkeypatch.delenv("CLEARANCE_KERNEL_DIR", raising=False)
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    package, cache = kernel_library.library_folders()
    assert package.parent.parent.name == "__pycache__" and cache.is_relative_to(tmp_path)
    assert package.name == cache.name == kernel_library.environment_key()[:16]
    monkeypatch.setattr(kernel_library.os, "access", lambda path, mode: not Path(path).is_relative_to(package.parents[2]))
    assert kernel_library.library_folder() == cache


def test_the_build_kernels_command(library_dir, tmp_path):
    status = subprocess.run(
        [sys.executable, "-m", "robot.cli.main", "build-kernels", "--status"], cwd=ROOT, env=_env(library_dir), capture_output=True, text=True, timeout=300
    )
    assert status.returncode == 0 and "fresh" in status.stdout and "exported signatures" in status.stdout, status.stdout + status.stderr
    empty = subprocess.run(
        [sys.executable, "-m", "robot.cli.main", "build-kernels", "--status"], cwd=ROOT, env=dict(_env(library_dir), CLEARANCE_KERNEL_DIR=str(tmp_path)), capture_output=True, text=True, timeout=300
    )
    assert empty.returncode == 1 and "missing or stale" in empty.stdout
    fresh = subprocess.run(
        [sys.executable, "-m", "robot.cli.main", "build-kernels"], cwd=ROOT, env=_env(library_dir), capture_output=True, text=True, timeout=300
    )
    assert fresh.returncode == 0 and fresh.stdout.strip().endswith(": fresh"), fresh.stdout + fresh.stderr
