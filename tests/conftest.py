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
