"""Contact force models chosen in a scene (issue 14), and energy conservation of R1 in a run."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from clearance_contact import STEEL, Material, NoFriction, RevoluteClearanceJoint, joint_type
from clearance_contact.dissipation import dissipation_factor
from robot.errors import SceneError
from robot.run import build_run, run_scene
from robot.scene import load_scene

ELASTIC = """
extends = "compound_misaligned"
name = "compound_misaligned_elastic"
duration = {duration}
[initial]
clearance_state = "centred"   # closed R1 impact episodes (a resting start stays in contact)
[solver]
method = "DOP853"
rtol = 1e-11
atol = 1e-13
max_step = 1e-3

[[clearance]]
joint = "S1"
type = "spherical"
material = "steel"
ball_radius = 0.015
clearance = 1.0e-4
restitution = 1.0

[[clearance]]
joint = "R1"
type = "revolute"
material = "steel"
journal_radius = 0.02
radial_clearance = 1.0e-4
bearing_outer_radius = 0.035
bearing_length = 0.04
axial_clearance = 1.0e-4
restitution = 1.0
{extra}
"""


def _scene(tmp_path, duration: float = 0.15, extra: str = "") -> str:
    path = tmp_path / "elastic.toml"
    path.write_text(ELASTIC.format(duration=duration, extra=extra))
    return str(path)


def test_elastic_r1_episodes_return_their_work(tmp_path) -> None:
    """Restitution 1, no friction, compound_misaligned over 0.15 s: every closed R1 contact
    episode (first onset of any R1 candidate until all four are out) returns the contact
    work to zero within 1e-8 J, after removing the elastic energy S1 holds at the two ends
    (U_S1 = K delta^2.5 / 2.5)."""
    run = build_run(_scene(tmp_path))
    result = run_scene(run)
    assert result.success, result.message
    t, work = result["t"], result["contact_work"]
    r1 = result["R1_penetration"]
    s1_law = next(c.law for c in run.scene.clearances if c.joint == "S1")
    s1_depth = np.maximum(result["S1_penetration"][:, 0], 0.0)
    stored_s1 = s1_law.stiffness * s1_depth**2.5 / 2.5
    in_contact = (r1 > 0).any(axis=1)
    episodes = []
    i = 0
    while i < len(t):
        if in_contact[i]:
            start = i - 1  # the record before the onset record (all out of contact or the onset itself)
            while start > 0 and in_contact[start]:
                start -= 1
            end = i
            while end < len(t) and in_contact[end]:
                end += 1
            if end < len(t) and start >= 0:
                episodes.append((start, end))
            i = end + 1
        else:
            i += 1
    assert len(episodes) >= 3, f"the test needs closed R1 episodes, found {len(episodes)}"
    worst = 0.0
    stored = 0.0
    for start, end in episodes:
        balance = (work[end] + stored_s1[end]) - (work[start] + stored_s1[start])
        worst = max(worst, abs(balance))
        stored = max(stored, np.abs(work[start:end] - work[start]).max())
    assert worst < 1e-8, (worst, stored, len(episodes))
    assert stored > 1e-6  # the episodes do store energy (the check is not vacuous)


def test_scene_chooses_the_models(tmp_path) -> None:
    scene = load_scene(_scene(tmp_path, extra='dissipation = "flores"\nradial_law = "johnson"'))
    r1 = next(c.law for c in scene.clearances if c.joint == "R1")
    s1 = next(c.law for c in scene.clearances if c.joint == "S1")
    assert r1.dissipation == "flores" and r1.radial_law.name == "johnson" and r1.radial_stiffness is None
    assert s1.dissipation == "lankarani_nikravesh"  # default
    # the shipped scenes keep today's behaviour
    for name in ("compound", "compound_misaligned", "revolute", "spherical"):
        for clearance in load_scene(name).clearances:
            assert clearance.law.dissipation == "lankarani_nikravesh"
            if clearance.kind == "revolute":
                assert clearance.law.radial_law.name == "linear"
    assert dissipation_factor("flores", 1.0) == 0.0


def test_every_shipped_scene_names_its_contact_models() -> None:
    """Issue 14: the shipped scenes say which models they use (and why, in their comments): every
    clearance joint names its dissipation model, every revolute one its radial law, in the file itself."""
    import tomllib

    from robot.scene.loader import SCENE_DIR

    checked = 0
    for path in sorted(Path(SCENE_DIR).glob("*.toml")):
        for clearance in tomllib.loads(path.read_text()).get("clearance", []):
            assert "dissipation" in clearance, f"{path.name}: clearance {clearance['joint']!r} does not name its dissipation model"
            if clearance["type"] == "revolute":
                assert "radial_law" in clearance, f"{path.name}: clearance {clearance['joint']!r} does not name its radial law"
            checked += 1
    assert checked >= 7


@pytest.mark.parametrize(
    ("extra", "message", "key", "value"),
    [
        ('dissipation = "kelvin_voigt"', r"clearance 'R1'.*dissipation='kelvin_voigt' is not known; valid: lankarani_nikravesh", "dissipation", "kelvin_voigt"),
        ('radial_law = "hertz"', r"clearance 'R1'.*radial_law='hertz' is not known; valid: linear, johnson", "radial_law", "hertz"),
        ("radial_law = 1.5", r"clearance 'R1'.*radial_law=1.5 must be a name", "radial_law", 1.5),
        ('dissipation = ""', r"clearance 'R1'.*dissipation='' must be a name", "dissipation", ""),
        ('radial_law = "pereira"\nradial_stiffness = 1e9', r"radial_law='pereira' sets its own stiffness", None, None),
    ],
)
def test_bad_model_names_give_scene_errors(tmp_path, extra, message, key, value) -> None:
    with pytest.raises(SceneError, match=message) as caught:
        load_scene(_scene(tmp_path, extra=extra))
    assert (caught.value.key, caught.value.value) == (key, value)


def test_model_names_are_recorded_with_the_scene_parameters(tmp_path) -> None:
    """The names are scene keys of the types (NAME_KEYS): recorded as given, else the law's own name."""
    scene = load_scene(_scene(tmp_path, extra='dissipation = "hunt_crossley"\nradial_law = "pereira"'))
    laws = {c.joint: c.law for c in scene.clearances}
    r1, s1 = laws["R1"].scene_parameters, laws["S1"].scene_parameters
    assert (r1["radial_law"], r1["dissipation"], r1["radial_clearance"]) == ("pereira", "hunt_crossley", 1.0e-4)
    assert s1["dissipation"] == "lankarani_nikravesh"  # not given: the joint's default, by name
    direct = RevoluteClearanceJoint(0.01, 0.0101, 0.02, 0.0301, 0.03, STEEL, STEEL, radial_law="johnson")
    assert direct.scene_parameters["radial_law"] == "johnson" and "radial_stiffness" not in direct.scene_parameters
    json.dumps(r1), json.dumps(direct.scene_parameters)  # result metadata: plain numbers and names


@pytest.mark.parametrize("law", ["linear", "johnson", "pereira", "hertz_point"])
@pytest.mark.parametrize("dissipation", ["lankarani_nikravesh", "gonthier"])
def test_joint_rebuilds_from_its_scene_parameters(law, dissipation) -> None:
    """What a result records (scene_parameters) rebuilds the same law (the animation does so)."""
    material = Material(youngs_modulus=7.0e10, poisson_ratio=0.33)
    given = {
        "journal_radius": 0.012, "radial_clearance": 2.0e-4, "bearing_outer_radius": 0.02, "bearing_length": 0.025,
        "axial_clearance": 3.0e-4, "radial_law": law, "dissipation": dissipation,
    }  # fmt: skip
    revolute = joint_type("revolute")
    first = revolute.from_scene(given, material, STEEL, 0.7, NoFriction())
    direct = RevoluteClearanceJoint(0.012, 0.0122, 0.02, 0.0253, 0.025, STEEL, material, 0.7, radial_law=law, dissipation=dissipation)
    for joint in (first, direct):
        again = revolute.from_scene(joint.scene_parameters, material, STEEL, 0.7, NoFriction())
        np.testing.assert_allclose(again.kernel_parameters, first.kernel_parameters, rtol=1e-12)
        assert again.scene_parameters["radial_law"] == law and again.dissipation == dissipation
