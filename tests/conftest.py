"""Shared test helpers."""

from __future__ import annotations

import atexit
import os
import shutil
import subprocess
import sys
import tempfile
import warnings
from pathlib import Path

import pytest

if "CLEARANCE_KERNEL_DIR" not in os.environ:
    # the session's own kernel library folder (set before any kernel is imported): the tests never
    # write into the checkout's, the commands they start build it there once (kernel_library_dir),
    # and this process, which imports the kernels below before any library exists there, runs numba's JIT
    os.environ["CLEARANCE_KERNEL_DIR"] = tempfile.mkdtemp(prefix="clearance-kernel-library-")
    atexit.register(shutil.rmtree, os.environ["CLEARANCE_KERNEL_DIR"], True)

from robot.dynamics import equations as D  # noqa: E402 (after the kernel library's folder is set)
from robot.errors import RedundantConstraintWarning  # noqa: E402

DATA = Path(__file__).resolve().parent / "data"

#: mechanisms of tests/data with closures, ideal or with clearance joints: name -> (mechanism file,
#: motion-driven joints (constant rate), clearance joints (joint or closure, type)). Revolute closures:
#: slider_crank, four_bar (3 redundant rows each, planar), mixed_closures (spherical, revolute,
#: spherical; 3 redundant rows); rssr has spherical closures only (here with a revolute clearance joint).
CLOSURE_SCENES = {
    "slider_crank": ("slider_crank.urdf", ("crank",), ()),
    "slider_crank_rod_clearance": ("slider_crank.urdf", ("crank",), (("crank_rod", "revolute"),)),
    "four_bar": ("four_bar.urdf", ("crank",), ()),
    "four_bar_rocker_clearance": ("four_bar.urdf", ("crank",), (("rocker", "revolute"),)),
    "rssr_rocker_clearance": ("rssr.urdf", ("crank",), (("rocker", "revolute"),)),
    "mixed": ("mixed_closures.urdf", ("crank", "rs_crank"), ()),
    "mixed_clearance": ("mixed_closures.urdf", ("crank", "rs_crank"), (("crank_rod", "revolute"), ("Sb", "spherical"))),
}

_CLEARANCE_KEYS = {
    "revolute": "journal_radius = 0.005\nradial_clearance = 1.0e-4\nbearing_outer_radius = 0.008\nbearing_length = 0.01\naxial_clearance = 1.0e-4\n",
    "spherical": "ball_radius = 0.01\nclearance = 1.0e-4\n",
}


def closure_scene(directory: Path, name: str) -> Path:
    """Write the scene file of :data:`CLOSURE_SCENES` ``name`` into ``directory`` (cranks at 20 rad/s, steel)."""
    urdf, driven, clearances = CLOSURE_SCENES[name]
    text = f'name = "{name}"\nmechanism = "{(DATA / urdf).as_posix()}"\nend_effector = "crank"\nduration = 0.05\n'
    text += '\n[trajectory]\ntype = "joints"\n' + "".join(f"{joint} = {{ offset = 0.0, rate = 20.0 }}\n" for joint in driven)
    text += "\n[materials.steel]\nyoungs_modulus = 2.07e11\npoisson_ratio = 0.3\n"
    for joint, kind in clearances:
        text += f'\n[[clearance]]\njoint = "{joint}"\ntype = "{kind}"\nmaterial = "steel"\nrestitution = 0.9\n' + _CLEARANCE_KEYS[kind]
    path = directory / f"{name}.toml"
    path.write_text(text)
    return path


class PythonOnlyLaw:
    """A contact law seen only through its public Python API (no compiled kernel)."""

    def __init__(self, law):
        self._law = law
        self.n_candidates = law.n_candidates

    def evaluate(self, *args):
        return self._law.evaluate(*args)

    def penetration(self, *args):
        return self._law.penetration(*args)


def with_python_laws(dynamics: D.DynamicsModel) -> D.DynamicsModel:
    """``dynamics`` with every contact law wrapped in :class:`PythonOnlyLaw`."""
    return D.DynamicsModel(
        dynamics.mechanism,
        dynamics.constraints,
        tuple(D.ContactSite(c.site, PythonOnlyLaw(c.law), c.first_candidate) for c in dynamics.contacts),
        dynamics.drive,
        dynamics.baumgarte,
        dynamics.end_effector_frame,
    )


@pytest.fixture(name="with_python_laws")
def with_python_laws_fixture():
    return with_python_laws


def assert_passes_as_plain_python(test_file: str, selection: str, passed: int) -> None:
    """Run the tests of ``test_file`` matching ``selection`` with ``CLEARANCE_CONTACT_JIT=0`` (numba off)."""
    env = dict(os.environ, CLEARANCE_CONTACT_JIT="0")
    proc = subprocess.run(
        [sys.executable, "-m", "pytest", "-q", "-x", "-p", "no:cacheprovider", test_file, "-k", selection],
        cwd=Path(__file__).resolve().parents[1], env=env, capture_output=True, text=True, timeout=300,
    )  # fmt: skip
    assert proc.returncode == 0 and f"{passed} passed" in proc.stdout, proc.stdout[-3000:] + proc.stderr[-3000:]


@pytest.fixture(scope="module")
def scene_runs(tmp_path_factory):
    """``get(name)``: ``build_run`` of a shipped scene or of a :data:`CLOSURE_SCENES` scene, built once per module."""
    from robot.run import build_run

    runs = {}

    def get(name):
        if name not in runs:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", RedundantConstraintWarning)
                if name in CLOSURE_SCENES:
                    runs[name] = build_run(str(closure_scene(tmp_path_factory.mktemp(name), name)))
                else:  # the 4-UPS/RPS scenes as the checks were calibrated (CALIBRATED_COMPOUND)
                    runs[name] = build_run(calibrated_scene(name) if name.startswith("compound") else name)
        return runs[name]

    return get
#: The compound scenes' R1 geometry and start that the integrator, stability and validation tests were
#: calibrated on (impacts from a centred start, the 40 mm bearing). Issue 18 changed the shipped defaults
#: (docs/parameters.md); those tests test the integrators and the formulations, not the defaults.
CALIBRATED_COMPOUND = {"clearance.R1.bearing_length": 0.04, "clearance.R1.bearing_outer_radius": 0.035, "initial.clearance_state": "centred"}


def calibrated_scene(name: str, **changes):
    """The shipped scene ``name`` with :data:`CALIBRATED_COMPOUND` (and ``changes``, e.g. ``duration``)."""
    from robot.scene.loader import load_scene

    return load_scene(name).with_changes({**CALIBRATED_COMPOUND, **changes})


_CALIBRATED_CLEARANCES = """
[initial]
clearance_state = "centred"

[[clearance]]
joint = "S1"
type = "spherical"
outer_on = "child"
material = "steel"
ball_radius = 0.015
clearance = 1.0e-4
restitution = 0.9
exponent = 1.5
dissipation = "lankarani_nikravesh"
friction = { law = "brown_mcphee", static = 0.07, dynamic = 0.05, transition_velocity = 5.0e-3 }

[[clearance]]
joint = "R1"
type = "revolute"
outer_on = "child"
material = "steel"
journal_radius = 0.02
radial_clearance = 1.0e-4
bearing_outer_radius = 0.035
bearing_length = 0.04
axial_clearance = 1.0e-4
restitution = 0.9
dissipation = "lankarani_nikravesh"
radial_law = "linear"
friction = { law = "brown_mcphee", static = 0.07, dynamic = 0.05, transition_velocity = 5.0e-3 }
"""


def calibrated_scene_file(folder: Path, name: str, extra: str = "") -> Path:
    """A scene file extending the shipped ``name`` with :data:`CALIBRATED_COMPOUND` (for functions that take
    scene files); ``extra``: more top-level TOML before the tables (e.g. a [solver] table goes after)."""
    path = folder / f"{name}_calibrated.toml"
    path.write_text(f'extends = "{name}"\nname = "{name}_calibrated"\n{extra}\n{_CALIBRATED_CLEARANCES}', encoding="utf-8")
    return path


#: a torque-driven four-bar with a bronze revolute clearance at the coupler's crank pin (tests/data):
#: the journal meets the bore at t = 1.866 ms; ``{restitution}``, ``{solver}`` (the [solver] table's
#: lines) and ``{extra}`` (more tables) are the tests' own
FOUR_BAR_TORQUE_SCENE = """
name = "{name}"
mechanism = "{urdf}"
end_effector = "rocker"
duration = {duration}
gravity = [0.0, -9.81, 0.0]
[actuators]
crank = {{ mode = "force", function = "constant", value = 3.0 }}
[initial]
velocities = {{ crank = 10.0 }}
[solver]
{solver}
[materials.bronze]
youngs_modulus = 1.1e11
poisson_ratio = 0.34
[[clearance]]
joint = "coupler"
type = "revolute"
outer_on = "child"
material = "bronze"
journal_radius = 0.008
radial_clearance = 2.0e-4
bearing_outer_radius = 0.014
bearing_length = 0.015
axial_clearance = 2.0e-4
restitution = {restitution}
friction = {{ law = "none" }}
{extra}
"""


def four_bar_torque_scene(path: Path, *, name: str, duration: float, solver: str, restitution: float, extra: str = "") -> Path:
    """Write :data:`FOUR_BAR_TORQUE_SCENE` to ``path`` and return it."""
    urdf = (Path(__file__).resolve().parent / "data" / "four_bar_torque_driven.urdf").as_posix()
    path.write_text(FOUR_BAR_TORQUE_SCENE.format(name=name, urdf=urdf, duration=duration, solver=solver, restitution=restitution, extra=extra))
    return path


@pytest.fixture(scope="session")
def kernel_library_dir() -> Path:
    """The session's kernel library folder (``library_folder()`` under this session's ``CLEARANCE_KERNEL_DIR``), built
    as a command builds it (``ensure_library``) if no command built it yet (15-40 s, once a session). Processes the
    tests start find it by default; pass its parent as ``CLEARANCE_KERNEL_DIR`` to one that was given another."""
    from clearance_contact.kernel_library import is_fresh, library_folder
    from robot.dynamics.kernel_build import ensure_library

    messages: list[str] = []
    status = ensure_library(announce=messages.append, wanted=True, retry_failed=True)
    assert status in ("fresh", "built") and is_fresh(), f"{status}: {messages}"
    return library_folder()


def free_port() -> int:
    """A TCP port of localhost nothing listens on (at the time of the call)."""
    import socket

    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return sock.getsockname()[1]
