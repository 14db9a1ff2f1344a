"""Compiled contact kernels (numba): same results as the plain-Python run of the same source.

* ``kernel`` vs ``kernel.py_func`` (numba keeps the Python function) on random states,
  in and out of contact, tilted journals, C- and Fortran-ordered rotations;
* the flat output layout (offsets on the classes) against ``evaluate``;
* status codes (NaN input, journal turned by 90 deg) and their ``ContactError``;
* a user-defined friction law (not compiled): the kernel leaves the slip, ``evaluate``
  applies the law, equal to the equivalent built-in law;
* the whole contact test suite with ``CLEARANCE_CONTACT_JIT=0``, and the compiled
  outputs against that plain-Python run (subprocesses);
* ``clearance_contact`` imports and works without numba;
* numba's caches are dropped when a source file of the package changes.
"""

from __future__ import annotations

import json
import math
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from clearance_contact import (
    STEEL,
    BrownMcPheeFriction,
    ContactError,
    CoulombFriction,
    NoFriction,
    RevoluteClearanceJoint,
    SphericalClearanceJoint,
)
from clearance_contact.compiled import (
    JIT_ENABLED,
    STATUS_AXIS_TILT,
    STATUS_EXTERNAL_FRICTION,
    STATUS_NONFINITE_INPUT,
    STATUS_OK,
)

ROOT = Path(__file__).resolve().parents[1]
requires_jit = pytest.mark.skipif(not JIT_ENABLED, reason="numba JIT disabled or not installed")

BM = BrownMcPheeFriction(0.08, 0.05, 1e-3, viscous_coefficient=2.0, reference_force=5.0)
FRICTIONS = {
    "brown_mcphee": BM,
    "coulomb_sign": CoulombFriction(0.1),
    "coulomb_smooth": CoulombFriction(0.1, 1e-3),
    "none": NoFriction(),
}
# journal 10 mm in a 10.1 mm bore, end faces out to 16 mm, bearing 20 mm, flanges 20.4 mm apart
R_J, R_B1, R_B2, L_J, L_B = 0.010, 0.0101, 0.016, 0.0204, 0.020
C_R, C_A = R_B1 - R_J, L_J - L_B
R_BALL, R_SOCKET = 0.015, 0.0151


def revolute(friction=BM, axial_exponent: float = 1.0) -> RevoluteClearanceJoint:
    return RevoluteClearanceJoint(
        R_J,
        R_B1,
        R_B2,
        L_J,
        L_B,
        STEEL,
        STEEL,
        restitution=0.8,
        friction=friction,
        axial_exponent=axial_exponent,
        axial_stiffness=None if axial_exponent == 1.0 else 3e9,
    )


def spherical(friction=BM) -> SphericalClearanceJoint:
    return SphericalClearanceJoint(R_BALL, R_SOCKET, STEEL, STEEL, restitution=0.8, friction=friction)


def rot(axis, angle: float) -> np.ndarray:
    """Rotation matrix about an axis (Rodrigues)."""
    k = np.asarray(axis, dtype=float)
    k = k / np.linalg.norm(k)
    kx = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + math.sin(angle) * kx + (1 - math.cos(angle)) * kx @ kx


def random_state(rng: np.random.Generator, joint, order: str = "CC") -> tuple:
    """A random state near / in contact (tilted journals for the revolute joint)."""
    ro = rot(rng.normal(size=3), rng.uniform(0.0, math.pi))
    po = rng.uniform(-0.5, 0.5, size=3)
    if isinstance(joint, RevoluteClearanceJoint):
        tilt = rng.choice([0.0, 1e-5, 3e-3, 1.2e-2]) * rng.uniform()
        ri = ro @ rot([math.cos(a := rng.uniform(0, 2 * math.pi)), math.sin(a), 0.0], tilt) @ rot([0, 0, 1], rng.uniform(-3, 3))
        ecc = rng.uniform(0.0, C_R + 2e-5)
        angle = rng.uniform(0, 2 * math.pi)
        shift = rng.uniform(-(C_A / 2 + 2e-5), C_A / 2 + 2e-5)
        pi = po + ro @ [ecc * math.cos(angle), ecc * math.sin(angle), shift]
    else:
        ri = rot(rng.normal(size=3), rng.uniform(0.0, math.pi))
        direction = rng.normal(size=3)
        pi = po + rng.uniform(0.5 * (R_SOCKET - R_BALL), (R_SOCKET - R_BALL) + 2e-5) * direction / np.linalg.norm(direction)
    to = np.concatenate([rng.uniform(-0.5, 0.5, 3), rng.uniform(-5, 5, 3)])
    ti = np.concatenate([rng.uniform(-0.5, 0.5, 3), rng.uniform(-5, 5, 3)])
    onset = rng.uniform(0.0, 1.0, joint.N_CANDIDATES)
    layout = {"C": np.ascontiguousarray, "F": np.asfortranarray}
    return layout[order[0]](ro), po, to, layout[order[1]](ri), pi, ti, onset


def run_kernel(kernel, joint, state) -> tuple[int, np.ndarray]:
    out = np.full(joint.output_size, np.nan)
    status = kernel(joint.kernel_parameters, *state, out)
    return status, out


def assert_same(a: np.ndarray, b: np.ndarray, joint) -> None:
    """Agreement to 1e-12 relative to each field's scale (and 1e-15 absolute)."""
    sizes = [joint.N_CANDIDATES] * 3 + [3 * joint.N_CANDIDATES] * 4 + [3 * joint.N_ECCENTRICITY, 6, 6]
    start = 0
    for size in sizes + [a.size - start - sum(sizes)]:
        x, y = a[start : start + size], b[start : start + size]
        scale = max(float(np.max(np.abs(y), initial=0.0)), 1e-15)
        np.testing.assert_allclose(x, y, rtol=0.0, atol=1e-12 * scale + 1e-15, err_msg=f"offset {start}")
        start += size


# --- compiled vs Python ------------------------------------------------------------------------
@requires_jit
@settings(max_examples=60, deadline=None)
@given(
    seed=st.integers(0, 2**32 - 1),
    law=st.sampled_from(["revolute", "revolute_n13", "spherical"]),
    friction=st.sampled_from(sorted(FRICTIONS)),
    order=st.sampled_from(["CC", "FF", "CF", "FC"]),
)
def test_kernel_matches_its_python_version(seed: int, law: str, friction: str, order: str) -> None:
    joint = {
        "revolute": lambda: revolute(FRICTIONS[friction]),
        "revolute_n13": lambda: revolute(FRICTIONS[friction], axial_exponent=1.3),
        "spherical": lambda: spherical(FRICTIONS[friction]),
    }[law]()
    rng = np.random.default_rng(seed)
    for _ in range(20):
        state = random_state(rng, joint, order)
        status, out = run_kernel(type(joint).kernel, joint, state)
        status_py, out_py = run_kernel(type(joint).kernel.py_func, joint, state)
        assert status == status_py == STATUS_OK
        assert_same(out, out_py, joint)
        # the layout (C or Fortran) does not change the result
        c_state = tuple(np.ascontiguousarray(x) for x in state)
        np.testing.assert_array_equal(run_kernel(type(joint).kernel, joint, c_state)[1], out)
        pen = np.full(joint.N_CANDIDATES, np.nan)
        assert type(joint).penetration_kernel(joint.kernel_parameters, state[0], state[1], state[3], state[4], pen) == 0
        pen_py = np.full(joint.N_CANDIDATES, np.nan)
        joint.penetration_kernel.py_func(joint.kernel_parameters, state[0], state[1], state[3], state[4], pen_py)
        np.testing.assert_allclose(pen, pen_py, rtol=0.0, atol=1e-12 * max(np.max(np.abs(pen_py)), 1e-15))
        np.testing.assert_array_equal(pen, out[: joint.N_CANDIDATES])


def test_contact_and_tilt_are_sampled() -> None:
    """The random states of the comparison cover contact and out of contact, every candidate."""
    rng = np.random.default_rng(0)
    for joint in (revolute(), spherical()):
        hits = np.zeros(joint.N_CANDIDATES)
        misses = np.zeros(joint.N_CANDIDATES)
        for _ in range(200):
            result = joint.evaluate(*random_state(rng, joint))
            hits += result.normal_force > 0
            misses += result.penetration <= 0
        assert hits.min() > 10 and misses.min() > 10, (hits, misses)


# --- layout --------------------------------------------------------------------------------------
@pytest.mark.parametrize("make", [revolute, spherical])
def test_layout_matches_evaluate(make) -> None:
    joint = make()
    cls = type(joint)
    k = cls.N_CANDIDATES
    assert cls.n_candidates == k
    assert (cls.PENETRATION, cls.PENETRATION_RATE, cls.NORMAL_FORCE, cls.NORMAL) == (0, k, 2 * k, 3 * k)
    assert (cls.POINT_OUTER, cls.POINT_INNER, cls.FRICTION_FORCE, cls.ECCENTRICITY) == (6 * k, 9 * k, 12 * k, 15 * k)
    assert cls.WRENCH_OUTER == 15 * k + 3 * cls.N_ECCENTRICITY
    assert (cls.WRENCH_INNER, cls.KIND) == (cls.WRENCH_OUTER + 6, cls.WRENCH_OUTER + 12)
    assert cls.output_size >= cls.KIND + k
    params = joint.kernel_parameters
    assert params.dtype == np.float64 and params.ndim == 1 and params.flags.c_contiguous
    rng = np.random.default_rng(1)
    for _ in range(50):
        state = random_state(rng, joint)
        result = joint.evaluate(*state)
        status, out = run_kernel(joint.kernel, joint, state)
        assert status == STATUS_OK
        fields = {
            "penetration": (cls.PENETRATION, (k,)),
            "penetration_rate": (cls.PENETRATION_RATE, (k,)),
            "normal_force": (cls.NORMAL_FORCE, (k,)),
            "normal": (cls.NORMAL, (k, 3)),
            "point_outer": (cls.POINT_OUTER, (k, 3)),
            "point_inner": (cls.POINT_INNER, (k, 3)),
            "friction_force": (cls.FRICTION_FORCE, (k, 3)),
            "eccentricity": (cls.ECCENTRICITY, (cls.N_ECCENTRICITY, 3)),
            "wrench_outer": (cls.WRENCH_OUTER, (6,)),
            "wrench_inner": (cls.WRENCH_INNER, (6,)),
            "kind": (cls.KIND, (k,)),
        }
        for name, (offset, shape) in fields.items():
            value = getattr(result, name)
            assert value.shape == shape, name
            np.testing.assert_array_equal(out[offset : offset + value.size].reshape(shape), value, err_msg=name)
        assert result.kind.dtype.kind == "i"
        # evaluate's arrays are views of one fresh array
        assert result.wrench_inner.base is result.penetration.base is not None
        np.testing.assert_array_equal(joint.penetration(state[0], state[1], state[3], state[4]), result.penetration)


# --- status codes ----------------------------------------------------------------------------------
@pytest.mark.parametrize("make", [revolute, spherical])
@pytest.mark.parametrize("argument", range(7))
def test_nan_input_status(make, argument: int) -> None:
    joint = make()
    state = list(random_state(np.random.default_rng(2), joint))
    state[argument] = state[argument].copy()
    state[argument].flat[0] = np.nan if argument != 2 else np.inf
    for kernel in (joint.kernel, getattr(joint.kernel, "py_func", joint.kernel)):
        assert run_kernel(kernel, joint, state)[0] == STATUS_NONFINITE_INPUT
    with pytest.raises(ContactError, match="non-finite"):
        joint.evaluate(*state)


def test_journal_turned_by_90_deg() -> None:
    joint = revolute()
    for angle in (0.5 * math.pi, 0.75 * math.pi, math.pi):
        state = list(random_state(np.random.default_rng(3), joint))
        state[3] = state[0] @ rot([1, 0, 0], angle)
        for kernel in (joint.kernel, getattr(joint.kernel, "py_func", joint.kernel)):
            assert run_kernel(kernel, joint, state)[0] == STATUS_AXIS_TILT
        out = np.zeros(4)
        assert joint.penetration_kernel(joint.kernel_parameters, state[0], state[1], state[3], state[4], out) == STATUS_AXIS_TILT
        with pytest.raises(ContactError, match="90 deg"):
            joint.evaluate(*state)
        with pytest.raises(ContactError, match="90 deg"):
            joint.penetration(state[0], state[1], state[3], state[4])
    # NaN in a rotation: the penetration kernel reports it as non-finite input
    state = list(random_state(np.random.default_rng(4), joint))
    state[3] = state[3] * np.nan
    out = np.zeros(4)
    assert joint.penetration_kernel(joint.kernel_parameters, state[0], state[1], state[3], state[4], out) == STATUS_NONFINITE_INPUT
    with pytest.raises(ContactError, match="non-finite"):
        joint.penetration(state[0], state[1], state[3], state[4])


# --- user-defined friction law ---------------------------------------------------------------------
class VectorOnlyLaw:
    """A FrictionLaw with ``force`` only (no scalar fast path): regularised Coulomb, as a vector."""

    def __init__(self, mu: float, v_r: float) -> None:
        self.mu, self.v_r = mu, v_r

    def coefficient(self, slip_speed: float) -> float:
        return self.mu * math.tanh(slip_speed / self.v_r)

    def force(self, normal_force: float, slip_velocity) -> np.ndarray:
        v = np.asarray(slip_velocity, dtype=float)
        speed = float(np.linalg.norm(v))
        if normal_force <= 0.0 or speed == 0.0:
            return np.zeros(3)
        return -self.mu * normal_force * math.tanh(speed / self.v_r) / speed * v


class ScalarLaw(VectorOnlyLaw):
    """The same law with a user-defined scalar ``force_over_speed`` (still not compiled)."""

    def force_over_speed(self, normal_force: float, slip_speed: float) -> float:
        if normal_force <= 0.0:
            return 0.0
        x = slip_speed / self.v_r
        return self.mu * normal_force * (math.tanh(x) / x if x > 1e-4 else 1.0 - x * x / 3.0) / self.v_r


@pytest.mark.parametrize("make", [revolute, spherical])
@pytest.mark.parametrize("user_law", [VectorOnlyLaw, ScalarLaw])
def test_user_defined_friction_law(make, user_law) -> None:
    mu, v_r = 0.1, 1e-3
    user = make(friction=user_law(mu, v_r))
    builtin = make(friction=CoulombFriction(mu, v_r))
    assert not user.friction_in_kernel and builtin.friction_in_kernel
    assert user.kernel is None  # compiled callers must use evaluate for this law
    assert builtin.kernel is type(builtin).kernel is not None
    rng = np.random.default_rng(5)
    in_contact = 0
    for _ in range(100):
        state = random_state(rng, user)
        got = user.evaluate(*state)
        want = builtin.evaluate(*state)
        in_contact += int(np.any(want.normal_force > 0))
        for name in ("friction_force", "wrench_outer", "wrench_inner", "normal_force", "penetration"):
            w = getattr(want, name)
            np.testing.assert_allclose(getattr(got, name), w, rtol=0, atol=1e-12 * max(np.max(np.abs(w)), 1e-12), err_msg=name)
        # the kernel itself stops before friction
        status, out = run_kernel(type(user).kernel, user, state)
        assert status == STATUS_EXTERNAL_FRICTION
        np.testing.assert_array_equal(out[: user.FRICTION_FORCE], run_kernel(builtin.kernel, builtin, state)[1][: user.FRICTION_FORCE])
    assert in_contact > 20


# --- plain Python (CLEARANCE_CONTACT_JIT=0) and no numba --------------------------------------------
def _run(code_or_args: list, env_jit: str | None, extra_env: dict | None = None, timeout: float = 120.0):
    env = dict(os.environ)
    env.pop("CLEARANCE_CONTACT_JIT", None)
    if env_jit is not None:
        env["CLEARANCE_CONTACT_JIT"] = env_jit
    env["PYTHONPATH"] = str(ROOT) + os.pathsep + env.get("PYTHONPATH", "")
    env.update(extra_env or {})
    return subprocess.run(
        [sys.executable, *code_or_args], cwd=ROOT, env=env, capture_output=True, text=True, timeout=timeout
    )


CONTACT_TESTS = [
    "tests/test_contact_laws.py",
    "tests/test_revolute_clearance.py",
    "tests/test_spherical_clearance.py",
    "tests/test_friction.py",
]


def test_contact_suite_passes_without_jit() -> None:
    """The whole contact test suite, run as plain Python (CLEARANCE_CONTACT_JIT=0)."""
    proc = _run(["-m", "pytest", "-q", "-x", "-p", "no:cacheprovider", *CONTACT_TESTS], "0", timeout=240.0)
    assert proc.returncode == 0, proc.stdout[-4000:] + proc.stderr[-4000:]


_DUMP = """
import json, sys
import numpy as np
sys.path.insert(0, "tests")
from test_contact_kernels import seeded_cases
from clearance_contact.compiled import JIT_ENABLED
result = {"jit": JIT_ENABLED, "cases": [[law, friction, status, out.tolist()] for law, friction, status, out, _ in seeded_cases()]}
print(json.dumps(result))
"""


def seeded_cases():
    """(law name, friction name, status, out, joint) of both kernels on fixed-seed random states."""
    for make in (revolute, spherical):
        for name in sorted(FRICTIONS):
            joint = make(FRICTIONS[name])
            rng = np.random.default_rng(7)
            for _ in range(40):
                status, out = run_kernel(joint.kernel, joint, random_state(rng, joint))
                yield make.__name__, name, status, out, joint


@requires_jit
def test_compiled_matches_plain_python_run() -> None:
    """Compiled kernels (this process) vs a CLEARANCE_CONTACT_JIT=0 process: same source, same numbers."""
    proc = _run(["-c", _DUMP], "0")
    assert proc.returncode == 0, proc.stderr[-4000:]
    plain = json.loads(proc.stdout)
    assert plain["jit"] is False
    cases = list(seeded_cases())
    assert len(cases) == len(plain["cases"])
    for (law, friction, status, out, joint), (law_py, friction_py, status_py, out_py) in zip(cases, plain["cases"]):
        assert (law, friction, status) == (law_py, friction_py, status_py)
        assert_same(out, np.array(out_py), joint)


def test_imports_and_works_without_numba(tmp_path: Path) -> None:
    """numba unavailable (sys.modules['numba'] = None via sitecustomize) and no kernel library:
    plain Python, same API. (With a library and no numba: tests/test_kernel_library.py.)"""
    (tmp_path / "sitecustomize.py").write_text("import sys\nsys.modules['numba'] = None\n")
    code = """
import numpy as np
import clearance_contact as cc
from clearance_contact.compiled import JIT_ENABLED, jit
assert not JIT_ENABLED
assert jit(len) is len
joint = cc.SphericalClearanceJoint(0.015, 0.0151, cc.STEEL, cc.STEEL, friction=cc.CoulombFriction(0.1, 1e-3))
s = np.array([0.0, 0.0, 0.0]); b = np.array([0.0, 0.0, 1.05e-4])
res = joint.evaluate(np.eye(3), s, np.zeros(6), np.eye(3), b, np.array([0.1, 0, 0, 0, 0, 0]), np.zeros(1))
assert res.normal_force[0] > 0 and res.friction_force[0, 0] < 0
out = np.empty(joint.output_size)
assert joint.kernel(joint.kernel_parameters, np.eye(3), s, np.zeros(6), np.eye(3), b, np.zeros(6), np.zeros(1), out) == 0
rev = cc.RevoluteClearanceJoint(0.01, 0.0101, 0.016, 0.0204, 0.02, cc.STEEL, cc.STEEL)
res = rev.evaluate(np.eye(3), s, np.zeros(6), np.eye(3), np.array([1.05e-4, 0, 0]), np.zeros(6), np.zeros(4))
assert res.kind.tolist() == [2, 0, 2, 0]
print("ok")
"""
    proc = _run(["-c", code], None, {"PYTHONPATH": f"{tmp_path}{os.pathsep}{ROOT}", "CLEARANCE_KERNEL_DIR": str(tmp_path / "no library")})
    assert proc.returncode == 0 and proc.stdout.strip() == "ok", proc.stderr[-4000:]


# --- lengths as CPython computes them -------------------------------------------------------------
finite = st.floats(allow_nan=False, allow_infinity=False, min_value=-1e300, max_value=1e300)


@settings(max_examples=500, deadline=None)
@given(x=finite, y=finite, z=finite)
def test_norms_are_cpython_hypot(x: float, y: float, z: float) -> None:
    """norm3 / norm2 reproduce math.hypot bit for bit (compiled and Python), also at 0 and inf."""
    from clearance_contact.compiled import norm2, norm3

    for f3, f2 in ((norm3, norm2), (getattr(norm3, "py_func", norm3), getattr(norm2, "py_func", norm2))):
        assert f3(x, y, z) == math.hypot(x, y, z)
        assert f2(x, y) == math.hypot(x, y)
    assert norm3(math.inf, 0.0, 1.0) == math.inf and math.isnan(norm3(math.nan, 0.0, 1.0))
    assert norm3(0.0, -0.0, 0.0) == 0.0


def test_numba_caches_are_dropped_when_a_source_changes(tmp_path):
    """A cached function calling a kernel of another file would keep stale code: the digest drops it."""
    from clearance_contact.compiled import drop_stale_caches

    sources = [tmp_path / "law.py", tmp_path / "caller.py"]
    for source in sources:
        source.write_text("x = 1\n")
    cache = tmp_path / "__pycache__"
    cache.mkdir()
    cached = [cache / "caller.f-1.py311.nbi", cache / "caller.f-1.py311.1.nbc", cache / "caller.cpython-311.pyc"]
    for path in cached:
        path.write_bytes(b"compiled")
    assert drop_stale_caches(sources, cache)  # no digest yet: numba's files go, Python's stay
    assert [p.exists() for p in cached] == [False, False, True]
    for path in cached[:2]:
        path.write_bytes(b"compiled")
    assert not drop_stale_caches(sources, cache)  # nothing changed
    assert all(p.exists() for p in cached)
    sources[0].write_text("x = 2\n")  # the callee's file changes
    assert drop_stale_caches(sources, cache)
    assert [p.exists() for p in cached] == [False, False, True]
