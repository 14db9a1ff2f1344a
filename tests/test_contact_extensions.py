"""The contact layer's extension points, used as a third party would: friction laws and dissipation
models registered by name from the user's own module, the checks of what they return, the joint-type
registry's loading, and a user friction law on the kernel library.

* a friction law registered by name is named in a TOML scene, survives ``with_changes``, overrides and
  ``simulate(scene, t_end=...)``, is actually called, and the result's metadata names it; a law swapped
  in behind the document's back (``dataclasses.replace``) is refused loudly on re-validation;
* the law's scene keys are checked (unknown key, value out of range: the key, value and range named);
  taken names are refused, the built-ins included;
* a user Coulomb law written in Python gives the built-in compiled Coulomb law's forces on the three
  joint types; broken laws (negative g, NaN, raising, wrong signature, force along the slip) are refused
  with the law, the value and the valid range, never run silently;
* dissipation models: refused names, read-only ``DISSIPATION_MODELS``, chi checked (negative, NaN, inf,
  text, not callable, wrong signature) when the joint is built, exit 2 through ``clearance run``; a user
  model with the same chi as a built-in gives the same forces;
* ``register_joint_type`` loads the shipped types first; the lazy load marks itself loaded only on success;
* a user friction law runs on the kernel library without switching the process to numba's JIT.
"""

from __future__ import annotations

import dataclasses
import json
import math
import os
import subprocess
import sys
import textwrap
from types import SimpleNamespace
from pathlib import Path

import numpy as np
import pytest

import clearance_contact as cc
from clearance_contact import ContactError, ContactParameterError, CoulombFriction, FrictionKey
from clearance_contact import dissipation as D
from clearance_contact import friction as F
from clearance_contact import registry as R
from robot import simulate
from robot.errors import SceneError
from robot.scene.loader import load_scene

ROOT = Path(__file__).resolve().parents[1]


# --- user friction laws (as a third party writes them) -------------------------------------------
class ThrelfallFriction:
    """Threlfall (1978): f = mu F_N (1 - exp(-3 v / v0)); g = f / v -> 3 mu F_N / v0 at v = 0. Counts its calls."""

    calls = 0

    def __init__(self, coefficient: float, v0: float) -> None:
        self.mu, self.v0 = float(coefficient), float(v0)

    def coefficient(self, slip_speed: float) -> float:
        return self.mu * (1.0 - math.exp(-3.0 * abs(slip_speed) / self.v0))

    def force_over_speed(self, normal_force: float, slip_speed: float) -> float:
        type(self).calls += 1
        if normal_force <= 0.0:
            return 0.0
        x = 3.0 * slip_speed / self.v0
        return self.mu * normal_force * (3.0 / self.v0 if x < 1e-8 else -math.expm1(-x) / slip_speed)

    def force(self, normal_force: float, slip_velocity) -> np.ndarray:
        v = np.asarray(slip_velocity, dtype=float)
        return -self.force_over_speed(normal_force, math.hypot(*v.tolist())) * v


class PyCoulomb:
    """The regularised Coulomb law mu F_N tanh(v / v_r), in Python: the same formula as the compiled built-in."""

    def __init__(self, coefficient: float, regularisation_velocity: float) -> None:
        self.mu, self.v_r = float(coefficient), float(regularisation_velocity)

    def coefficient(self, slip_speed: float) -> float:
        return self.mu * math.tanh(slip_speed / self.v_r)

    def force_over_speed(self, normal_force: float, slip_speed: float) -> float:
        if normal_force <= 0.0:
            return 0.0
        y = slip_speed / self.v_r
        return self.mu * normal_force * (1.0 - y * y / 3.0 if y < 1e-4 else math.tanh(y) / y) / self.v_r

    def force(self, normal_force: float, slip_velocity) -> np.ndarray:
        v = np.asarray(slip_velocity, dtype=float)
        return -self.force_over_speed(normal_force, math.hypot(*v.tolist())) * v


class VectorCoulomb(PyCoulomb):
    """The same law through ``force`` only (no scalar path)."""

    force_over_speed = None

    def force(self, normal_force: float, slip_velocity) -> np.ndarray:
        v = np.asarray(slip_velocity, dtype=float)
        return -PyCoulomb.force_over_speed(self, normal_force, math.hypot(*v.tolist())) * v


THRELFALL = "threlfall_test"
if THRELFALL not in F.friction_law_names():  # this module may be imported twice (pytest, subprocesses)
    cc.register_friction_law(THRELFALL, ThrelfallFriction, (FrictionKey("coefficient"), FrictionKey("v0", low_open=True)))


@pytest.fixture(name="scratch_registries")
def scratch_registries_fixture():
    """Models and laws a test registers are removed afterwards (the registries' own dicts, restored in place)."""
    models, laws = dict(D._MODELS), dict(F._LAWS)
    yield
    for registry, saved in ((D._MODELS, models), (F._LAWS, laws)):
        registry.clear()
        registry.update(saved)


# --- joints in contact, with slip -----------------------------------------------------------------
TILT = np.array([[1.0, 0.0, 0.0], [0.0, math.cos(0.002), -math.sin(0.002)], [0.0, math.sin(0.002), math.cos(0.002)]])
OFFSET, TWIST = np.array([1.2e-4, 0.0, 0.0]), np.array([0.1, -0.2, 0.0, 0.0, 0.0, 0.1])
JOINTS = {
    "spherical": lambda friction: cc.SphericalClearanceJoint(0.015, 0.0151, cc.STEEL, cc.STEEL, friction=friction),
    "revolute": lambda friction: cc.RevoluteClearanceJoint(0.01, 0.0101, 0.016, 0.0204, 0.02, cc.STEEL, cc.STEEL, friction=friction),
    "translational": lambda friction: cc.TranslationalClearanceJoint(
        0.05, 0.02, 0.01, 0.0202, 0.0102, cc.STEEL, cc.STEEL, friction=friction, corner_radius=1.5e-3
    ),
}


def evaluate(joint):
    """The joint at a state in contact (tilted inner element, offset beyond the clearance, slipping)."""
    return joint.evaluate(np.eye(3), np.zeros(3), TWIST, TILT, OFFSET, -TWIST, np.full(joint.N_CANDIDATES, 0.1))


# --- 1. friction laws by name in scenes -------------------------------------------------------------
def _scene_file(tmp_path: Path, friction: str, dissipation: str = "lankarani_nikravesh") -> Path:
    path = tmp_path / "user_law.toml"
    path.write_text(
        textwrap.dedent(
            f"""\
            extends = "spherical"
            name = "user_law"
            duration = 0.05
            [[clearance]]
            joint = "S1"
            type = "spherical"
            ball_radius = 0.015
            clearance = 1.0e-4
            restitution = 0.9
            dissipation = "{dissipation}"
            friction = {friction}
            """
        )
    )
    return path


def test_a_user_friction_law_named_in_a_scene_survives_re_validation_and_is_called(tmp_path):
    """The TOML names the registered law; every re-validation (with_changes, overrides, t_end) keeps it, it is
    called during the run, its friction stays below mu F_N (Threlfall's coefficient < mu), and the result's
    metadata names it with its keys."""
    path = _scene_file(tmp_path, f'{{ law = "{THRELFALL}", coefficient = 0.1, v0 = 1.0e-3 }}')
    scene = load_scene(path)
    assert isinstance(scene.clearances[0].law.friction, ThrelfallFriction)
    changed = scene.with_changes({"clearance.S1.restitution": 0.8, "clearance.S1.friction.coefficient": 0.2})
    law = changed.clearances[0].law
    assert isinstance(law.friction, ThrelfallFriction) and law.friction.mu == 0.2 and law.restitution == 0.8
    overridden = load_scene(path, overrides={"clearance.S1.friction.v0": 2e-3})
    assert isinstance(overridden.clearances[0].law.friction, ThrelfallFriction) and overridden.clearances[0].law.friction.v0 == 2e-3

    ThrelfallFriction.calls = 0
    result = simulate(scene, t_end=0.03)
    assert result.status == 0 and ThrelfallFriction.calls > 0
    joint = result.joint("S1")
    loaded = joint.normal_force[:, 0] > 1.0
    assert loaded.any() and np.all(joint.friction_force[loaded, 0] <= 0.1 * joint.normal_force[loaded, 0] * (1 + 1e-9))
    recorded = result.metadata["clearance_parameters"]["S1"]["friction"]
    assert recorded == {"law": THRELFALL, "coefficient": 0.1, "v0": 1e-3}
    json.dumps(result.metadata["clearance_parameters"])  # plain names and numbers


class LateFailingFriction(ThrelfallFriction):
    """Passes the checks made when the joint is built, then returns NaN at its 200th call (mid-run), once."""

    def force_over_speed(self, normal_force: float, slip_speed: float) -> float:
        g = super().force_over_speed(normal_force, slip_speed)  # counts the call
        return math.nan if LateFailingFriction.calls == 200 else g


def test_a_user_law_failing_mid_run_stops_it_naming_the_law(tmp_path, scratch_registries):
    """Not a pose the law refuses (a trial stage would shrink the step until 'step size collapse'): the run stops at
    once with cause 'contact law error', the message naming the law and the value, the records so far kept."""
    cc.register_friction_law("late_failing_test", LateFailingFriction, (FrictionKey("coefficient"), FrictionKey("v0", low_open=True)))
    scene = load_scene(_scene_file(tmp_path, '{ law = "late_failing_test", coefficient = 0.1, v0 = 1.0e-3 }'))
    LateFailingFriction.calls = 0
    result = simulate(scene, t_end=0.03)
    assert result.status == -1 and result.cause == "contact law error", (result.cause, result.message)
    assert "LateFailingFriction" in result.message and "nan is outside the valid range [0, inf)" in result.message
    assert 0.0 < result.t_end < 0.03 and len(result.t) > 1


def test_the_built_in_laws_are_registered_and_named_in_the_metadata():
    scene = load_scene("spherical")
    assert scene.clearances[0].law.scene_parameters["friction"] == {
        "law": "brown_mcphee", "static": 0.07, "dynamic": 0.05, "transition_velocity": 5e-3, "viscous": 0.0, "reference_force": 1.0,
    }  # fmt: skip
    assert set(F.friction_law_names()) >= {"none", "brown_mcphee", "coulomb", THRELFALL}
    assert F.friction_scene_table(CoulombFriction(0.1, 1e-3)) == {"law": "coulomb", "coefficient": 0.1, "regularisation_velocity": 1e-3}
    assert F.friction_scene_table(PyCoulomb(0.1, 1e-3)) == {"class": f"{__name__}.PyCoulomb"}
    # what scene_parameters reports rebuilds the joint (its friction entry is not a type's key)
    law = scene.clearances[0].law
    again = type(law).from_scene(law.scene_parameters, law.socket_material, law.ball_material, 0.9, law.friction)
    assert np.array_equal(again.kernel_parameters, law.kernel_parameters)


@pytest.mark.parametrize(
    ("friction", "words"),
    [
        (f'{{ law = "{THRELFALL}", coefficient = 0.1, v0 = 0.0 }}', ["v0=0.0", "(0, inf)"]),
        (f'{{ law = "{THRELFALL}", coefficient = -0.1, v0 = 1e-3 }}', ["coefficient=-0.1", "[0, inf)"]),
        (f'{{ law = "{THRELFALL}", coefficient = 0.1, v0 = 1e-3, static = 0.1 }}', ["unknown key", "static", "v0"]),
        (f'{{ law = "{THRELFALL}", coefficient = 0.1 }}', ["missing required key 'v0'"]),
        ('{ law = "coulomb", coefficient = "0.1" }', ["coefficient='0.1'", "[0, inf)"]),
        ('{ law = "brown_mcphee", static = 0.03, dynamic = 0.05, transition_velocity = 1e-3 }', ["static=0.03 must be >= dynamic=0.05"]),
        ('{ law = "brown_mcphee", static = 0.07, dynamic = 0.05, transition_velocity = -1.0 }', ["transition_velocity=-1.0", "(0, inf)"]),
        ('{ law = "no_such_law" }', ["'no_such_law' is not registered", THRELFALL, "register_friction_law"]),
    ],
)
def test_bad_friction_tables_name_the_key_the_value_and_the_range(tmp_path, friction, words):
    with pytest.raises(SceneError) as caught:
        load_scene(_scene_file(tmp_path, friction))
    message = str(caught.value)
    assert "clearance 'S1' friction" in message and all(word in message for word in words), message


def test_taken_friction_law_names_are_refused(scratch_registries):
    for name in ("coulomb", "none", THRELFALL):
        with pytest.raises(ContactParameterError, match=f"friction law '{name}' is already registered"):
            cc.register_friction_law(name, PyCoulomb)
    assert F.friction_law_type("coulomb").law_class is CoulombFriction  # the built-in is still there
    # the same definition again (a module reloaded, a notebook cell run twice) may register again
    cc.register_friction_law(THRELFALL, ThrelfallFriction, (FrictionKey("coefficient"), FrictionKey("v0", low_open=True)))
    with pytest.raises(ContactParameterError, match="cannot take the keys"):
        cc.register_friction_law("mismatched_keys_test", PyCoulomb, (FrictionKey("mu"),))
    assert "mismatched_keys_test" not in F.friction_law_names()


def test_a_decorated_law_class_gets_its_keys_from_its_signature(scratch_registries):
    @cc.register_friction_law("decorated_coulomb_test")
    class Decorated(PyCoulomb):
        pass

    law, table = F.friction_law_from_scene({"law": "decorated_coulomb_test", "coefficient": 0.3, "regularisation_velocity": 1e-3})
    assert type(law) is Decorated and law.mu == 0.3 and table["law"] == "decorated_coulomb_test"
    assert F.friction_scene_table(law) == {"law": "decorated_coulomb_test"}
    with pytest.raises(ContactParameterError, match="missing required key 'regularisation_velocity'"):
        F.friction_law_from_scene({"law": "decorated_coulomb_test", "coefficient": 0.3})


def test_a_law_swapped_in_by_dataclasses_replace_is_refused_on_re_validation():
    """The document still says brown_mcphee: re-validating it would silently run that law instead of the user's."""
    scene = load_scene("spherical", duration=0.01)
    old = scene.clearances[0].law
    law = type(old).from_scene(old.scene_parameters, old.socket_material, old.ball_material, old.restitution, PyCoulomb(0.1, 1e-3))
    swapped = dataclasses.replace(scene, clearances=(dataclasses.replace(scene.clearances[0], law=law),))
    for rerun in (lambda: swapped.with_changes({"solver.rtol": 1e-6}), lambda: simulate(swapped, t_end=0.005)):
        with pytest.raises(SceneError, match="'S1' were replaced outside the scene's document"):
            rerun()
    # other fields replaced: the clearances are still the document's
    dataclasses.replace(scene, duration=0.02).with_changes({"solver.rtol": 1e-6})


# --- 3. user friction laws: same forces as the built-ins, broken ones refused ------------------------
@pytest.mark.parametrize("kind", sorted(JOINTS))
@pytest.mark.parametrize("user_law", [PyCoulomb, VectorCoulomb])
def test_a_user_coulomb_law_gives_the_built_in_forces(kind, user_law):
    user, built_in = JOINTS[kind](user_law(0.1, 1e-3)), JOINTS[kind](CoulombFriction(0.1, 1e-3))
    assert not user.friction_in_kernel and built_in.friction_in_kernel
    got, want = evaluate(user), evaluate(built_in)
    assert np.max(want.normal_force) > 0.0 and np.max(np.abs(want.friction_force)) > 0.0
    for name in ("friction_force", "wrench_outer", "wrench_inner", "normal_force"):
        w = getattr(want, name)
        np.testing.assert_allclose(getattr(got, name), w, rtol=0, atol=1e-13 * np.max(np.abs(w)), err_msg=name)


class Switchable(PyCoulomb):
    """Regularised Coulomb until ``mode`` is set: then g is negative, NaN, or the law raises."""

    mode = None

    def force_over_speed(self, normal_force, slip_speed):
        if self.mode == "negative":
            return -super().force_over_speed(normal_force, slip_speed)
        if self.mode == "nan":
            return math.nan
        if self.mode == "raises":
            raise ZeroDivisionError("oops in the user's law")
        if self.mode == "text":
            return "0.1"
        return super().force_over_speed(normal_force, slip_speed)


class AlongSlip(VectorCoulomb):
    """A force-only law whose force pushes along the slip once ``flip`` is set."""

    flip = False

    def force(self, normal_force, slip_velocity):
        return (-1.0 if self.flip else 1.0) * super().force(normal_force, slip_velocity)


@pytest.mark.parametrize("kind", sorted(JOINTS))
@pytest.mark.parametrize(
    ("mode", "words"),
    [
        ("negative", ["Switchable", "force_over_speed(normal_force=", "= -", "valid range [0, inf)"]),
        ("nan", ["Switchable", "= nan", "valid range [0, inf)"]),
        ("text", ["Switchable", "= '0.1'", "valid range [0, inf)"]),
        ("raises", ["Switchable", "raised ZeroDivisionError: oops in the user's law"]),
    ],
)
def test_a_law_that_breaks_during_a_run_gives_a_contact_error(kind, mode, words):
    """Sampled when the joint is built (fine then), broken afterwards: each call is checked (same message for
    the three joint types: one check)."""
    law = Switchable(0.1, 1e-3)
    joint = JOINTS[kind](law)
    law.mode = mode
    with pytest.raises(ContactError) as caught:
        evaluate(joint)
    message = str(caught.value)
    assert all(word in message for word in words), message


@pytest.mark.parametrize("kind", sorted(JOINTS))
def test_a_force_along_the_slip_gives_a_contact_error(kind):
    law = AlongSlip(0.1, 1e-3)
    joint = JOINTS[kind](law)
    law.flip = True
    with pytest.raises(ContactError, match=r"AlongSlip.*pushes along the slip .*valid range \(-inf, 0\]"):
        evaluate(joint)


class WrongSignature(PyCoulomb):
    def force_over_speed(self, slip_speed):
        return 0.0


class NaNAtZeroSlip(PyCoulomb):
    def force_over_speed(self, normal_force, slip_speed):
        return math.nan if slip_speed == 0.0 else super().force_over_speed(normal_force, slip_speed)


@pytest.mark.parametrize(
    ("law", "words"),
    [
        (WrongSignature(0.1, 1e-3), ["WrongSignature", "force_over_speed(normal_force, slip_speed)"]),
        (NaNAtZeroSlip(0.1, 1e-3), ["NaNAtZeroSlip", "slip_speed=0.0", "= nan", "[0, inf)", "when the joint is built"]),
        (Switchable(-0.1, 1e-3), ["Switchable", "[0, inf)"]),
    ],
)
def test_broken_laws_are_refused_when_the_joint_is_built(law, words):
    for make in JOINTS.values():
        with pytest.raises(ContactParameterError) as caught:
            make(law)
        assert all(word in str(caught.value) for word in words), str(caught.value)


# --- 2. dissipation models ------------------------------------------------------------------------
def stiff_chi(ce):
    """A user's chi written with numpy: returns a 0-d array."""
    return np.where(ce < 1.0, 3.0 * (1.0 - ce) / 4.0, 0.0)


def test_a_user_model_may_return_a_numpy_scalar_and_register_again(scratch_registries):
    cc.register_dissipation_model("lee_wang_numpy_test", stiff_chi)
    cc.register_dissipation_model("lee_wang_numpy_test", stiff_chi)  # the same definition again: allowed
    assert D.dissipation_factor("lee_wang_numpy_test", 0.8) == pytest.approx(0.15)
    assert F.user_friction_gain(SimpleNamespace(force_over_speed=lambda n, v: np.float32(2.0) * np.ones(())), 1.0, 0.1) == 2.0


def test_dissipation_model_names_cannot_be_taken_or_written(scratch_registries):
    hunt_crossley = D.DISSIPATION_MODELS["hunt_crossley"]
    with pytest.raises(ContactParameterError, match="'hunt_crossley' is already registered"):
        cc.register_dissipation_model("hunt_crossley", lambda ce: 0.0)
    with pytest.raises(ContactParameterError, match="read-only.*register_dissipation_model"):
        cc.DISSIPATION_MODELS["hunt_crossley"] = lambda ce: 0.0
    assert D.DISSIPATION_MODELS["hunt_crossley"] is hunt_crossley and D.dissipation_factor("hunt_crossley", 0.9) == pytest.approx(0.15)
    assert list(D.DISSIPATION_MODELS)[:5] == ["lankarani_nikravesh", "hunt_crossley", "gonthier", "flores", "hu_guo"]
    for chi, words in ((0.15, "must be a callable"), (lambda ce, n: 0.1, "cannot be called as chi(c_e)")):
        with pytest.raises(ContactParameterError, match=r"dissipation model 'bad_signature_test'") as caught:
            cc.register_dissipation_model("bad_signature_test", chi)
        assert words in str(caught.value)


@pytest.mark.parametrize(
    ("chi", "value"),
    [(lambda ce: -0.75 * (1 - ce) - 0.5, "chi=-0.6"), (lambda ce: math.nan, "chi=nan"), (lambda ce: math.inf, "chi=inf"), (lambda ce: "0.15", "chi='0.15'")],
)
def test_bad_chi_is_refused_when_the_joint_is_built(scratch_registries, chi, value):
    cc.register_dissipation_model("bad_chi_test", chi)
    for make in (
        lambda: cc.SphericalClearanceJoint(0.015, 0.0151, cc.STEEL, cc.STEEL, restitution=0.8, dissipation="bad_chi_test"),
        lambda: cc.RevoluteClearanceJoint(0.01, 0.0101, 0.016, 0.0204, 0.02, cc.STEEL, cc.STEEL, restitution=0.8, dissipation="bad_chi_test"),
    ):
        with pytest.raises(ContactParameterError) as caught:
            make()
        message = str(caught.value)
        assert "'bad_chi_test'" in message and value in message and "c_e=0.8" in message and "[0, inf)" in message, message


def test_a_user_model_with_a_built_in_chi_gives_its_forces(scratch_registries):
    """Lee & Wang chi = 3 (1 - c_e) / 4 at c_e = 0.8 is Hunt & Crossley's 3 (1 - c_e) / 2 at 0.9: the same force law."""
    cc.register_dissipation_model("lee_wang_test", lambda ce: 0.75 * (1.0 - ce))
    lee_wang = cc.SphericalClearanceJoint(0.015, 0.0151, cc.STEEL, cc.STEEL, restitution=0.8, dissipation="lee_wang_test")
    hunt_crossley = cc.SphericalClearanceJoint(0.015, 0.0151, cc.STEEL, cc.STEEL, restitution=0.8, dissipation="hunt_crossley")
    reference = cc.SphericalClearanceJoint(0.015, 0.0151, cc.STEEL, cc.STEEL, restitution=0.9, dissipation="hunt_crossley")
    a, b, c = evaluate(lee_wang), evaluate(hunt_crossley), evaluate(reference)
    assert a.normal_force[0] > 0.0 and a.normal_force[0] != b.normal_force[0]
    np.testing.assert_allclose(a.wrench_inner, c.wrench_inner, rtol=1e-14)


def _cli(args: list[str], env: dict, cwd: Path) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "robot.cli", *args], cwd=cwd, env=env, capture_output=True, text=True, timeout=600)


def test_a_negative_chi_model_exits_2_through_clearance_run(tmp_path, kernel_library_dir):
    """The user's module (CLEARANCE_EXTENSIONS) registers a model with a negative chi; the scene names it:
    ``clearance run`` refuses it with exit 2 and a one-line message naming the model, c_e and chi."""
    (tmp_path / "negative_chi_ext.py").write_text(
        "from clearance_contact import register_dissipation_model\n"
        "register_dissipation_model('negative_chi', lambda ce: -0.75 * (1.0 - ce) - 0.5)\n"
    )
    scene = _scene_file(tmp_path, '{ law = "none" }', dissipation="negative_chi")
    env = dict(os.environ, PYTHONPATH=f"{tmp_path}{os.pathsep}{ROOT}", CLEARANCE_EXTENSIONS="negative_chi_ext")
    done = _cli(["run", "--scene", str(scene), "--out", str(tmp_path / "out")], env, tmp_path)
    assert done.returncode == 2, done.stderr[-2000:]
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error:") and "Traceback" not in done.stderr, done.stderr
    assert "'negative_chi'" in lines[0] and "chi=-0.57" in lines[0] and "c_e=0.9" in lines[0], lines[0]


# --- 5. the joint-type registry -----------------------------------------------------------------------
_EARLY_TYPE = """
import json
from clearance_contact import ContactParameterError, register_joint_type, joint_types
import clearance_contact.spherical as sp
try:
    @register_joint_type
    class Fake(sp.SphericalClearanceJoint):
        type_name = "revolute"
    error = None
except ContactParameterError as exc:
    error = str(exc)
from robot.scene.loader import load_scene
scene = load_scene("revolute")
print(json.dumps({"error": error, "types": list(joint_types()), "law": type(scene.clearances[0].law).__name__}))
"""


def test_a_type_registered_before_the_first_look_up_cannot_take_a_shipped_name():
    done = subprocess.run([sys.executable, "-c", _EARLY_TYPE], cwd=ROOT, env=dict(os.environ, PYTHONPATH=str(ROOT)), capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr[-3000:]
    report = json.loads(done.stdout.strip().splitlines()[-1])
    assert "joint type 'revolute' is already registered by clearance_contact.revolute.RevoluteClearanceJoint" in report["error"]
    assert {"spherical", "revolute", "translational"} <= set(report["types"]) and report["law"] == "RevoluteClearanceJoint"


def test_a_failed_lazy_load_is_not_marked_loaded(monkeypatch):
    monkeypatch.setattr(R, "_builtins_loaded", False)
    monkeypatch.setattr(R, "BUILTIN_MODULES", R.BUILTIN_MODULES + ("clearance_contact.no_such_module",))
    with pytest.raises(ModuleNotFoundError):
        R.joint_types()
    assert R._builtins_loaded is False
    monkeypatch.setattr(R, "BUILTIN_MODULES", R.BUILTIN_MODULES[:-1])
    assert {"spherical", "revolute", "translational"} <= set(R.joint_types()) and R._builtins_loaded is True


# --- 4. a user friction law on the kernel library --------------------------------------------------------
_LIBRARY_SCRIPT = """
import json, sys
import numpy as np
from clearance_contact import compiled
from tests.test_contact_extensions import JOINTS, PyCoulomb, VectorCoulomb, evaluate
outputs = []
for make in JOINTS.values():
    for law in (PyCoulomb(0.1, 1e-3), VectorCoulomb(0.1, 1e-3)):
        contact = evaluate(make(law))
        outputs.append(np.concatenate([contact.normal_force.ravel(), contact.friction_force.ravel(), contact.wrench_outer, contact.wrench_inner]).tolist())
# a whole run whose scene names the user law (the site-by-site right-hand side: site_twists, add_site_wrenches)
from pathlib import Path
from robot.run import simulate
from tests.test_contact_extensions import THRELFALL, _scene_file
result = simulate(str(_scene_file(Path(sys.argv[1]), '{ law = "' + THRELFALL + '", coefficient = 0.1, v0 = 1.0e-3 }')), t_end=0.01)
outputs.append([float(result.status)] + result.joint("S1").friction_force[:, 0].tolist())
print(json.dumps({"mode": compiled.KERNEL_MODE, "switched_by": compiled.SWITCHED_BY, "numba": "numba" in sys.modules, "outputs": outputs}))
"""


def test_a_user_friction_law_runs_on_the_kernel_library(kernel_library_dir, tmp_path):
    """The three joint types with a user law (scalar and vector paths), and a whole run of a scene naming one: no
    switch to numba's JIT, numba not even imported, and numba's JIT gives the same outputs bit for bit."""
    reports = {}
    for mode in ("1", "numba"):
        env = dict(os.environ, CLEARANCE_KERNEL_DIR=str(kernel_library_dir.parent), CLEARANCE_CONTACT_JIT=mode, PYTHONPATH=str(ROOT))
        done = subprocess.run([sys.executable, "-c", _LIBRARY_SCRIPT, str(tmp_path)], cwd=ROOT, env=env, capture_output=True, text=True, timeout=600)
        assert done.returncode == 0, done.stderr[-3000:]
        assert "KernelSwitchWarning" not in done.stderr, done.stderr[-3000:]
        reports[mode] = json.loads(done.stdout.strip().splitlines()[-1])
    library = reports["1"]
    assert (library["mode"], library["switched_by"], library["numba"]) == ("library", None, False)
    assert reports["numba"]["mode"] == "numba" and library["outputs"] == reports["numba"]["outputs"]
    assert all(max(abs(x) for x in row) > 0 for row in library["outputs"])
