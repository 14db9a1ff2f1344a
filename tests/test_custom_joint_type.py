"""A clearance joint type defined and registered here alone runs through the whole simulator.

The toy type ``point_on_plane``: the inner element is a point, the outer element a
plane ``gap`` below the point's assembled position (normal = the outer frame's z
axis), with the Lankarani-Nikravesh law of ``clearance_contact.normal_force``.  It
has no compiled kernel (``KERNEL_ID = None``): the simulator evaluates it through
``ClearanceJoint.evaluate``, which runs its plain-Python kernel below.

A puck hangs on a revolute joint ``P`` of a fixed ground; the scene makes ``P`` a
``point_on_plane`` clearance joint, so the puck becomes a free body that falls by
``gap`` onto the plane, bounces and comes to rest.  Checked against physics:
free fall before the impact, the first rebound against an independent 1-DOF
integration of the same law, and at rest the contact force equals the weight
with the static penetration (m g / K)^(1/n).
"""

from __future__ import annotations

import base64
import math
import re

import numpy as np
import pytest
import umsgpack
from scipy.integrate import solve_ivp

from clearance_contact import KIND_NONE, KIND_POINT, ClearanceJoint, NoFriction, Shape, register_joint_type
from clearance_contact.compiled import STATUS_NONFINITE_INPUT, STATUS_OK
from clearance_contact.errors import require_positive
from clearance_contact.normal_force import lankarani_nikravesh, validate_normal_law

from robot.errors import SceneError
from robot.run import build_run, run_scene
from robot.scene.loader import load_scene

_GAP, _STIFFNESS, _EXPONENT, _RESTITUTION = range(4)


def point_on_plane_penetration(parameters, outer_rotation, outer_position, inner_rotation, inner_position, out) -> int:
    """delta = -z . (p_i - p_o) - gap, z the plane normal (outer frame z)."""
    d = np.asarray(inner_position) - np.asarray(outer_position)
    out[0] = -(np.asarray(outer_rotation)[:, 2] @ d) - parameters[_GAP]
    return STATUS_OK


def point_on_plane_kernel(parameters, outer_rotation, outer_position, outer_twist, inner_rotation, inner_position, inner_twist, onset_rates, out) -> int:
    """The whole law in Python, into the layout of ``PointOnPlane`` (ClearanceJoint offsets)."""
    if not all(np.all(np.isfinite(a)) for a in (outer_rotation, outer_position, outer_twist, inner_position, inner_twist, onset_rates)):
        return STATUS_NONFINITE_INPUT
    law = PointOnPlane
    z = outer_rotation[:, 2]
    d = inner_position - outer_position
    delta = -(z @ d) - parameters[_GAP]
    # d(delta)/dt = -(w_o x z) . d - z . (v_i - v_o)
    rate = -(np.cross(outer_twist[3:], z) @ d) - z @ (inner_twist[:3] - outer_twist[:3])
    force = lankarani_nikravesh(delta, rate, onset_rates[0], parameters[_STIFFNESS], parameters[_EXPONENT], parameters[_RESTITUTION])
    normal = -z  # from the point toward the plane
    out[law.PENETRATION] = delta
    out[law.PENETRATION_RATE] = rate
    out[law.NORMAL_FORCE] = force
    out[law.NORMAL : law.NORMAL + 3] = normal
    out[law.POINT_OUTER : law.POINT_OUTER + 3] = inner_position + delta * z  # the point's foot on the plane
    out[law.POINT_INNER : law.POINT_INNER + 3] = inner_position
    out[law.FRICTION_FORCE : law.FRICTION_FORCE + 3] = 0.0
    out[law.ECCENTRICITY : law.ECCENTRICITY + 3] = outer_rotation.T @ d
    f_inner = force * z  # -F_N normal
    point = inner_position + 0.5 * delta * z  # half-way between the surfaces
    out[law.WRENCH_INNER : law.WRENCH_INNER + 3] = f_inner
    out[law.WRENCH_INNER + 3 : law.WRENCH_INNER + 6] = np.cross(point - inner_position, f_inner)
    out[law.WRENCH_OUTER : law.WRENCH_OUTER + 3] = -f_inner
    out[law.WRENCH_OUTER + 3 : law.WRENCH_OUTER + 6] = np.cross(point - outer_position, -f_inner)
    out[law.KIND] = KIND_POINT if delta > 0.0 else KIND_NONE
    return STATUS_OK


@register_joint_type
class PointOnPlane(ClearanceJoint):
    """A point (inner) above a frictionless plane (outer) ``gap`` below it when assembled."""

    __slots__ = ("_gap", "_stiffness", "_exponent")

    type_name = "point_on_plane"
    N_CANDIDATES = 1
    N_ECCENTRICITY = 1
    SCENE_KEYS = ("gap", "stiffness", "exponent")
    REQUIRED_KEYS = ("gap", "stiffness")
    GEOMETRY_KEYS = ("gap",)
    GAP_KEYS = ("gap",)
    DEFAULT_GEOMETRY = {"gap": 0.01}
    kernel = staticmethod(point_on_plane_kernel)
    penetration_kernel = staticmethod(point_on_plane_penetration)

    def __init__(self, gap, stiffness, exponent=1.5, restitution=0.9, outer_material=None, inner_material=None, friction=NoFriction()):
        self._gap = require_positive("gap", gap)
        self._stiffness, self._exponent, self._restitution = validate_normal_law(stiffness, exponent, restitution)
        self._wire_friction(friction)
        self.kernel_parameters = np.array([self._gap, self._stiffness, self._exponent, self._restitution])

    @property
    def gap(self) -> float:
        return self.given("gap", self._gap)

    @property
    def stiffness(self) -> float:
        return self._stiffness

    @property
    def exponent(self) -> float:
        return self._exponent

    def candidate_clearances(self) -> np.ndarray:
        return np.array([self.gap])

    @classmethod
    def drawing(cls, geometry) -> tuple[Shape, ...]:
        """A thin translucent slab whose top face is the plane, and the point as a small ball."""
        slab = 0.002
        return (
            Shape("outer", "plane", "box", size=(0.1, 0.1, slab), centre=(0.0, 0.0, -geometry["gap"] - 0.5 * slab), opacity=0.4),
            Shape("inner", "point", "sphere", radius=0.003),
        )


MASS, GAP, STIFFNESS, EXPONENT, RESTITUTION = 2.5, 0.004, 2.0e6, 1.5, 0.6

URDF = """<?xml version="1.0"?>
<robot name="puck_on_turntable">
  <link name="ground"/>
  <link name="turntable">
    <inertial><origin xyz="0 0 0" rpy="0 0 0"/><mass value="4.0"/><inertia ixx="0.02" ixy="0" ixz="0" iyy="0.02" iyz="0" izz="0.04"/></inertial>
  </link>
  <link name="puck">
    <inertial><origin xyz="0 0 0" rpy="0 0 0"/><mass value="{mass}"/><inertia ixx="0.002" ixy="0" ixz="0" iyy="0.002" iyz="0" izz="0.003"/></inertial>
  </link>
  <joint name="spin" type="revolute">
    <parent link="ground"/><child link="turntable"/>
    <origin xyz="0 0 0" rpy="0 0 0"/><axis xyz="0 0 1"/>
    <limit lower="-1000" upper="1000" effort="100" velocity="1000"/>
  </joint>
  <joint name="P" type="revolute">
    <parent link="turntable"/><child link="puck"/>
    <origin xyz="0.1 -0.2 0.3" rpy="0 0 0"/><axis xyz="0 0 1"/>
    <limit lower="-1000" upper="1000" effort="0" velocity="1000"/>
  </joint>
  <transmission name="spin_transmission">
    <type>transmission_interface/SimpleTransmission</type>
    <joint name="spin"><hardwareInterface>hardware_interface/EffortJointInterface</hardwareInterface></joint>
    <actuator name="M1"><mechanicalReduction>1</mechanicalReduction></actuator>
  </transmission>
</robot>
"""

SCENE = """
name = "puck"
mechanism = "puck.urdf"
end_effector = "puck"
duration = {duration}

[trajectory]
type = "joints"
spin = {{ offset = 0.0, rate = 3.0 }}  # the plane slides under the puck: no effect on a frictionless contact

[solver]
rtol = 1e-9
atol = 1e-11
max_step = 5e-4

[materials.steel]
youngs_modulus = 2.07e11
poisson_ratio = 0.3

[[clearance]]
joint = "P"
type = "{type}"
outer_on = "parent"
restitution = {restitution}
gap = {gap}
stiffness = {stiffness}
exponent = {exponent}
"""


def write_scene(folder, duration=0.35, kind="point_on_plane"):
    (folder / "puck.urdf").write_text(URDF.format(mass=MASS))
    path = folder / "puck.toml"
    path.write_text(SCENE.format(duration=duration, type=kind, restitution=RESTITUTION, gap=GAP, stiffness=STIFFNESS, exponent=EXPONENT))
    return path


@pytest.fixture(scope="module")
def bouncing(tmp_path_factory):
    run = build_run(write_scene(tmp_path_factory.mktemp("puck")))
    return run, run_scene(run)


def reference_first_rebound(g: float) -> tuple[float, float]:
    """Impact speed and first rebound apex height (above the plane contact level) of the 1-DOF model.

    m z'' = -m g + F_LN(delta, delta', onset), delta = -z - gap: the same law integrated
    by scipy on its own (onset rate = delta' at the contact onset), no Pinocchio.
    """
    def falling(t, y):
        return [y[1], -g]

    def touch(t, y):
        return -y[0] - GAP

    touch.terminal, touch.direction = True, 1.0
    fall = solve_ivp(falling, (0.0, 1.0), [0.0, 0.0], events=touch, rtol=1e-12, atol=1e-14)
    z, v = fall.y_events[0][0]
    onset = -v

    def contact(t, y):
        delta, rate = -y[0] - GAP, -y[1]
        return [y[1], -g + lankarani_nikravesh(delta, rate, onset, STIFFNESS, EXPONENT, RESTITUTION) / MASS]

    def leave(t, y):
        return -y[0] - GAP

    leave.terminal, leave.direction = True, -1.0
    hit = solve_ivp(contact, (0.0, 1.0), [z, v], events=leave, rtol=1e-12, atol=1e-16, max_step=1e-5)
    v_out = hit.y_events[0][0][1]
    return onset, v_out**2 / (2 * g)


def test_the_registered_type_drives_the_scene(bouncing):
    run, result = bouncing
    assert result.success, result.message
    law = run.scene.clearances[0].law
    assert type(law) is PointOnPlane and law.KERNEL_ID is None
    assert run.dynamics.n_candidates == 1 and run.mechanism.model.nv == 1 + 6  # P became a free joint
    assert run.dynamics.mechanism.clearance_sites[0].kind == "revolute"
    assert result.metadata["clearance_type"] == {"P": "point_on_plane"}
    assert result.metadata["clearance_geometry"] == {"P": {"gap": GAP}}  # as given
    assert result["P_eccentricity"].shape == (len(result["t"]), 3)


def test_free_fall_then_the_first_rebound_matches_a_1dof_integration(bouncing):
    run, result = bouncing
    g = -float(run.mechanism.model.gravity.linear[2])
    t, pen = result["t"], result["P_penetration"][:, 0]
    z_index = run.mechanism.model.idx_qs[run.mechanism.model.getJointId("P")] + 2
    height = result["q"][:, z_index] - result["q"][0, z_index]
    airborne = t < math.sqrt(2 * GAP / g) * 0.999
    np.testing.assert_allclose(height[airborne], -0.5 * g * t[airborne] ** 2, atol=1e-10)
    np.testing.assert_allclose(pen[airborne], -GAP - height[airborne], atol=1e-12)
    # the first contact phase, then the first apex in the air
    first_contact = int(np.argmax(pen > 0))
    separation = first_contact + int(np.argmax(pen[first_contact:] <= 0))
    second_contact = separation + int(np.argmax(pen[separation:] > 0))
    impact_speed, apex = reference_first_rebound(g)
    assert result["onset_rates"][separation, 0] == pytest.approx(impact_speed, rel=1e-6)
    simulated_apex = np.max(height[separation:second_contact]) + GAP
    assert simulated_apex == pytest.approx(apex, rel=2e-3)
    assert 0.1 * GAP < apex < 0.9 * GAP  # the restitution lost energy but the puck did leave the plane


def test_at_rest_the_contact_force_carries_the_weight(bouncing):
    run, result = bouncing
    g = -float(run.mechanism.model.gravity.linear[2])
    weight = MASS * g
    last = result["t"] > result["t"][-1] - 0.02
    force, pen = result["P_normal_force"][last, 0], result["P_penetration"][last, 0]
    np.testing.assert_allclose(force, weight, rtol=1e-3)
    np.testing.assert_allclose(pen, (weight / STIFFNESS) ** (1 / EXPONENT), rtol=1e-3)
    assert np.all(result["P_kind"][last, 0] == KIND_POINT)


def test_a_type_that_does_not_fit_the_joint_is_a_scene_error(tmp_path):
    text = write_scene(tmp_path).read_text()
    wrong = text[: text.index("[[clearance]]")] + '[[clearance]]\njoint = "P"\ntype = "spherical"\nball_radius = 0.01\nclearance = 1e-4\n'
    (tmp_path / "wrong.toml").write_text(wrong)
    with pytest.raises(SceneError, match=r"type='spherical' cannot replace 'P', a revolute joint .* use type = 'point_on_plane' or 'revolute'"):
        load_scene(tmp_path / "wrong.toml")
    # the type's own keys: a key of another type is unknown
    (tmp_path / "extra.toml").write_text(text.replace("exponent =", "ball_radius = 0.01\nexponent ="))
    with pytest.raises(SceneError, match=r"unknown key\(s\) ball_radius; valid keys: .*gap"):
        load_scene(tmp_path / "extra.toml")


def test_the_custom_joint_animates_with_its_own_drawing_and_contact_points(bouncing, tmp_path):
    from robot.io.results import save_result
    from robot.viz.animation import export_html

    run, result = bouncing
    path = save_result(result, tmp_path / "puck.npz")
    summary = export_html(path, tmp_path / "puck.html", urdf=run.scene.mechanism_path, speed=0.05, exaggerate=3.0)
    assert summary.sizes["P"].kind == "point_on_plane" and summary.sizes["P"].values == {"gap": GAP}
    page = (tmp_path / "puck.html").read_text()
    commands = [umsgpack.unpackb(base64.b64decode(b)) for b in re.findall(r'meshcatCommand\("([A-Za-z0-9+/=]+)"\)', page)]
    objects = {c["path"]: c["object"] for c in commands if c["type"] == "set_object"}
    base = "/meshcat/mechanism/clearance/P"
    assert objects[f"{base}/inner/point"]["geometries"][0]["radius"] == pytest.approx(0.003)
    assert objects[f"{base}/outer/plane"]["geometries"][0]["type"] == "BoxGeometry"
    (animation,) = [c for c in commands if c["type"] == "set_animation"]
    tracks = {a["path"]: {t["name"]: t for t in a["clip"]["tracks"]} for a in animation["animations"]}
    visible = [key["value"] for key in tracks[f"{base}/force0/shaft"][".visible"]["keys"]]
    assert True in visible and False in visible  # the arrow shows during contact only
