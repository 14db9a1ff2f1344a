"""Shared test helpers."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from robot.dynamics import equations as D


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
