"""Overconstrained mechanisms: redundant closure equations are detected and the dynamics stay exact.

Closed forms: a one-degree-of-freedom planar mechanism driven at constant crank
speed ``omega`` needs the crank torque (Lagrange's equation)

    tau = d/dt(dT/dtheta') - dT/dtheta + dV/dtheta = 1/2 m'(theta) omega^2 + dV/dtheta,
    T = 1/2 m(theta) theta'^2,   m = sum_i (m_i |G_i'|^2 + I_i psi_i'^2),
    1/2 m' = sum_i (m_i G_i' . G_i'' + I_i psi_i' psi_i''),   dV/dtheta = -sum_i m_i g . G_i'

(``'`` = d/dtheta, ``G_i`` the centre of mass and ``psi_i`` the angle of body i, ``I_i``
its inertia about the axis through ``G_i``), with the exact kinematics of the
slider-crank (sin phi = -r sin theta / l) and of the four-bar (circle
intersection; the angle rates from the differentiated loop equation, a 2 x 2
linear system), and the masses, centres of mass and inertias read from the URDF.
"""

from __future__ import annotations

import math
import warnings
import xml.etree.ElementTree as ET
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pinocchio as pin
import pytest

from robot.dynamics import equations as D
from robot.model import redundancy as R
from robot.errors import RedundantConstraintWarning, SingularConfigurationError
from robot.model import constraints as C
from robot.model import kinematics as K
from robot.model.description import parse_mechanism
from robot.model.mechanism import build_mechanism
from robot.model.summary import summarize
from robot.run import build_run, run_scene

DATA = Path(__file__).resolve().parent / "data"
SLIDER_CRANK = DATA / "slider_crank.urdf"
FOUR_BAR = DATA / "four_bar.urdf"
RSSR = DATA / "rssr.urdf"
OMEGA = 20.0  # rad/s, crank speed
THETA0 = math.pi / 3  # the crank joint origin's angle in both files
DURATION = 0.2


# --------------------------------------------------------------------------- closed forms


def _links(path: Path) -> dict[str, tuple[float, np.ndarray, float]]:
    """mass, planar centre of mass (link frame) and I_zz about it, of every link with an inertial."""
    out = {}
    for link in ET.parse(path).getroot().findall("link"):
        inertial = link.find("inertial")
        if inertial is None:
            continue
        com = np.array([float(x) for x in inertial.find("origin").get("xyz").split()])[:2]
        out[link.get("name")] = (float(inertial.find("mass").get("value")), com, float(inertial.find("inertia").get("izz")))
    return out


def _rotate(angle, vector):
    """R(angle) vector for arrays of angles (k,) and a 2-vector: (k, 2)."""
    c, s = np.cos(angle), np.sin(angle)
    return np.stack([c * vector[0] - s * vector[1], s * vector[0] + c * vector[1]], axis=-1)


def _unit(angle):
    return np.stack([np.cos(angle), np.sin(angle)], axis=-1)


def _normal(angle):
    return np.stack([-np.sin(angle), np.cos(angle)], axis=-1)


def _body_terms(mass, com, izz, pivot_d1, pivot_d2, angle, angle_d1, angle_d2, gravity):
    """(m G'.G'' + I psi' psi'', -m g.G') of one body: pivot P(theta) (its link origin), angle psi(theta)."""
    arm = _rotate(angle, com)
    turned = np.stack([-arm[:, 1], arm[:, 0]], axis=-1)
    g1 = pivot_d1 + angle_d1[:, None] * turned
    g2 = pivot_d2 + angle_d2[:, None] * turned - (angle_d1**2)[:, None] * arm
    return mass * np.einsum("ki,ki->k", g1, g2) + izz * angle_d1 * angle_d2, -mass * g1 @ gravity


def _torque(terms, omega):
    inertial = sum(t[0] for t in terms)
    potential = sum(t[1] for t in terms)
    return inertial * omega**2 + potential


def slider_crank_torque(theta, omega, gravity):
    """Crank torque of tests/data/slider_crank.urdf (crank r, rod l, slider on the x axis), theta' = omega."""
    links = _links(SLIDER_CRANK)
    r, l = 0.05, 0.12
    k = r / l
    s, c = np.sin(theta), np.cos(theta)
    root = np.sqrt(1.0 - k * k * s * s)  # cos(phi)
    phi = np.arctan2(-k * s, root)
    phi_d1 = -k * c / root
    phi_d2 = k * s / root - k**3 * s * c * c / root**3
    zero = np.zeros_like(theta)
    ones = np.ones_like(theta)
    crank_tip_d1, crank_tip_d2 = r * _normal(theta), -r * _unit(theta)
    x_d1 = -r * s - l * np.sin(phi) * phi_d1
    x_d2 = -r * c - l * np.cos(phi) * phi_d1**2 - l * np.sin(phi) * phi_d2
    terms = [
        _body_terms(*links["crank"], np.zeros((theta.size, 2)), np.zeros((theta.size, 2)), theta, ones, zero, gravity),
        _body_terms(*links["rod"], crank_tip_d1, crank_tip_d2, phi, phi_d1, phi_d2, gravity),
        _body_terms(*links["slider"], np.stack([x_d1, zero], -1), np.stack([x_d2, zero], -1), zero, zero, zero, gravity),
    ]
    return _torque(terms, omega)


FOUR_BAR_LENGTHS = (0.06, 0.18, 0.14, 0.16)  # crank, coupler, rocker, ground


def four_bar_angles(theta):
    """Coupler and rocker angles (open branch, B above the line A-D) and their first two theta-derivatives."""
    a, b, c, d = FOUR_BAR_LENGTHS
    A = a * _unit(theta)
    e = np.array([d, 0.0]) - A
    L = np.linalg.norm(e, axis=1)
    u = e / L[:, None]
    x = (b * b - c * c + L * L) / (2 * L)
    B = A + x[:, None] * u + np.sqrt(b * b - x * x)[:, None] * np.stack([-u[:, 1], u[:, 0]], -1)
    beta = np.arctan2(B[:, 1] - A[:, 1], B[:, 0] - A[:, 0])
    gamma = np.arctan2(B[:, 1], B[:, 0] - d)
    # a u'(theta) + b beta' u'(beta) = c gamma' u'(gamma), u' the unit normal; and its derivative
    matrix = np.stack([b * _normal(beta), -c * _normal(gamma)], axis=-1)  # (k, 2, 2)
    first = np.linalg.solve(matrix, (-a * _normal(theta))[..., None])[..., 0]
    beta_d1, gamma_d1 = first[:, 0], first[:, 1]
    rhs = a * _unit(theta) + b * (beta_d1**2)[:, None] * _unit(beta) - c * (gamma_d1**2)[:, None] * _unit(gamma)
    second = np.linalg.solve(matrix, rhs[..., None])[..., 0]
    return beta, gamma, beta_d1, gamma_d1, second[:, 0], second[:, 1]


def four_bar_torque(theta, omega, gravity, path=FOUR_BAR):
    links = _links(path)
    a = FOUR_BAR_LENGTHS[0]
    beta, gamma, beta_d1, gamma_d1, beta_d2, gamma_d2 = four_bar_angles(theta)
    zero, ones, still = np.zeros_like(theta), np.ones_like(theta), np.zeros((theta.size, 2))
    terms = [
        _body_terms(*links["crank"], still, still, theta, ones, zero, gravity),
        _body_terms(*links["coupler"], a * _normal(theta), -a * _unit(theta), beta, beta_d1, beta_d2, gravity),
        _body_terms(*links["rocker"], still, still, gamma, gamma_d1, gamma_d2, gravity),
    ]
    return _torque(terms, omega)


# --------------------------------------------------------------------------- scenes


def _scene(tmp_path: Path, urdf: Path, gravity=(0.0, -9.81, 0.0), name="redundant", extra: str = "") -> Path:
    path = tmp_path / f"{name}.toml"
    path.write_text(
        f"""
name = "{name}"
mechanism = "{urdf.as_posix()}"
end_effector = "crank"
duration = {DURATION}
gravity = [{', '.join(repr(float(g)) for g in gravity)}]

[trajectory]
type = "joints"
crank = {{ offset = 0.0, rate = {OMEGA} }}

[solver]
rtol = 1e-10
atol = 1e-12
max_step = 1e-3
{extra}
"""
    )
    return path


def _run(scene: Path):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RedundantConstraintWarning)
        run = build_run(str(scene))
        return run, run_scene(run)


def _torque_error(run, result, closed_form):
    theta = THETA0 + result["q"][:, run.mechanism.actuator_q_index[0]]
    expected = closed_form(theta)
    error = np.abs(result["driving_force"][:, 0] - expected)
    return error.max() / np.abs(expected).max(), expected


@pytest.mark.parametrize("mechanism", ["slider_crank", "four_bar"])
def test_driven_crank_torque_matches_lagrange_closed_form(tmp_path, mechanism):
    """Ideal mechanism with a revolute closure (3 redundant rows), gravity in its plane: the
    simulated driving torque equals Lagrange's closed form at every record of a 0.2 s run."""
    urdf, closed_form = {
        "slider_crank": (SLIDER_CRANK, lambda th: slider_crank_torque(th, OMEGA, np.array([0.0, -9.81]))),
        "four_bar": (FOUR_BAR, lambda th: four_bar_torque(th, OMEGA, np.array([0.0, -9.81]))),
    }[mechanism]
    run, result = _run(_scene(tmp_path, urdf))
    assert result.success, result.message
    assert len(result["t"]) > 150
    crank = run.mechanism.actuator_v_index[0]
    np.testing.assert_allclose(result["v"][:, crank], OMEGA, rtol=1e-9)
    relative, expected = _torque_error(run, result, closed_form)
    assert np.ptp(expected) > 0.1 * np.abs(expected).max()  # the torque does vary over the run
    assert relative < 1e-6, relative


# --------------------------------------------------------------------------- detection


def bennett_urdf(theta1: float = 1.0, a: float = 0.1, alpha_deg: float = 30.0, beta_deg: float = 60.0, baked: bool = True) -> str:
    """A Bennett linkage: four revolutes, opposite links equal (a, alpha) and (b, beta), a / sin(alpha) = b / sin(beta).

    Denavit-Hartenberg chain ``T_i = Rz(theta_i) Tx(a_i) Rx(alpha_i)``; joints 1-3 are tree joints whose
    origins carry the assembled angles at crank angle ``theta1`` (theta3 = -theta1,
    tan(theta1/2) tan(theta2/2) = sin((beta+alpha)/2) / sin((beta-alpha)/2)), joint 4 a revolute closure.
    Spatial and overconstrained: 6 x 3 - 15 - 5 = -2, yet it moves with one degree of freedom.
    """
    alpha, beta = math.radians(alpha_deg), math.radians(beta_deg)
    b = a * math.sin(beta) / math.sin(alpha)
    theta2 = 2.0 * math.atan(math.sin((beta + alpha) / 2) / math.sin((beta - alpha) / 2) / math.tan(theta1 / 2))
    theta3 = -theta1
    if not baked:  # joint origins without the assembled angles: at q = 0 the closure's axes are not parallel
        theta1 = theta2 = theta3 = 0.0

    def origin(length, twist, angle):
        rpy = [float(x) for x in pin.rpy.matrixToRpy(pin.utils.rotate("x", twist) @ pin.utils.rotate("z", angle))]
        return f'<origin xyz="{length!r} 0 0" rpy="{rpy[0]!r} {rpy[1]!r} {rpy[2]!r}"/>'

    def link(name, length):
        return (
            f'<link name="{name}"><inertial><origin xyz="{length / 2!r} 0.01 0.005" rpy="0 0 0"/><mass value="0.3"/>'
            f'<inertia ixx="0.00002" ixy="0" ixz="0" iyy="0.0003" iyz="0" izz="0.0003"/></inertial></link>'
        )

    joints = [("j1", "ground", "l1", origin(0.0, 0.0, theta1)), ("j2", "l1", "l2", origin(a, alpha, theta2)), ("j3", "l2", "l3", origin(b, beta, theta3))]
    body = "".join(
        f'<joint name="{n}" type="revolute"><parent link="{p}"/><child link="{c}"/>{o}<axis xyz="0 0 1"/>'
        f'<limit lower="-1000" upper="1000" effort="100" velocity="1000"/></joint>'
        for n, p, c, o in joints
    )
    return (
        f'<robot name="bennett"><link name="ground"/>{link("l1", a)}{link("l2", b)}{link("l3", a)}{body}'
        '<transmission name="t"><joint name="j1"/></transmission>'
        f'<closures><closure name="J4" type="revolute"><parent link="l3" xyz="{a!r} 0 0" rpy="{alpha!r} 0 0"/>'
        f'<child link="ground" xyz="{-b!r} 0 0" rpy="{-beta!r} 0 0"/><axis xyz="0 0 1"/></closure></closures></robot>'
    )


def _planar_in_3d(path: Path, closure_type: str) -> str:
    """The four-bar's text with its revolute closure replaced by a spherical one."""
    text = path.read_text()
    assert text.count('<closure name="B" type="revolute">') == 1
    return text.replace('<closure name="B" type="revolute">', f'<closure name="B" type="{closure_type}">').replace(
        '<child link="rocker" xyz="0.14 0 0" rpy="0 0 0"/>\n      <axis xyz="0 0 1"/>', '<child link="rocker" xyz="0.14 0 0" rpy="0 0 0"/>'
    )


def _rotated_base(path: Path, rpy: str) -> str:
    """The same mechanism on a base link rotated by ``rpy`` (a fixed joint from a new root link)."""
    text = path.read_text()
    root = '<link name="world"/><joint name="base" type="fixed"><parent link="world"/><child link="ground"/>' f'<origin xyz="0 0 0" rpy="{rpy}"/></joint>'
    return text.replace('<link name="ground"/>', '<link name="ground"/>' + root, 1)


MECHANISMS = {
    "slider_crank": lambda: build_mechanism(SLIDER_CRANK),
    "four_bar": lambda: build_mechanism(FOUR_BAR),
    "four_bar_spherical": lambda: build_mechanism(parse_mechanism(_planar_in_3d(FOUR_BAR, "spherical"), is_text=True)),
    "rssr": lambda: build_mechanism(RSSR),
    "bennett": lambda: build_mechanism(parse_mechanism(bennett_urdf(), is_text=True)),
    "slider_crank_rotated_base": lambda: build_mechanism(parse_mechanism(_rotated_base(SLIDER_CRANK, "1.5707963267948966 0 0"), is_text=True)),
}


@pytest.mark.parametrize(
    ("name", "grubler", "mobility", "redundant"),
    [
        ("slider_crank", -2, 1, ("K:z", "K:rot_x", "K:rot_y")),
        ("four_bar", -2, 1, ("B:z", "B:rot_x", "B:rot_y")),
        ("four_bar_spherical", 0, 1, ("B:z",)),
        ("rssr", 2, 2, ()),
        ("bennett", -2, 1, 3),
        ("slider_crank_rotated_base", -2, 1, ("K:y", "K:rot_x", "K:rot_y")),
    ],
)
def test_redundant_equations_are_detected_and_named(name, grubler, mobility, redundant):
    """Grubler-Kutzbach + redundant equations = numerical mobility, and the redundant rows are named.

    The planar mechanisms' redundant rows are the out-of-plane translation and the two axis rows
    (identically zero); the Bennett linkage's are genuinely dependent, non-zero rows (which three are
    left out is the pivoting's choice: only their number is fixed). The slider-crank on a base rotated
    by 90 deg about x moves in the x-z plane: its out-of-plane row is world y, with 4e-17 entries."""
    mechanism = MECHANISMS[name]()
    summary = summarize(mechanism)
    assert summary.assembly_residual < 1e-12
    assert (summary.grubler_free, summary.mobility_free) == (grubler, mobility)
    n_redundant = redundant if isinstance(redundant, int) else len(redundant)
    assert len(summary.redundant_equations) == n_redundant == mobility - grubler
    if not isinstance(redundant, int):
        assert summary.redundant_equations == redundant
    assert ("Redundant closure equations" in summary.text()) and (", ".join(summary.redundant_equations) or "none") in summary.text()
    if name == "bennett":  # not zero rows: every closure row has entries of the order of its scale
        constraints = C.constraint_set(mechanism, driven=False)
        data = mechanism.model.createData()
        q = K.assemble(C.constraint_set(mechanism, driven=False), pin.neutral(mechanism.model)).q
        K.update_kinematics(mechanism.model, data, q)
        phi_q = C.jacobian(constraints, mechanism.model, data)
        scales = R.row_scales(constraints, mechanism.model, data, phi_q)
        assert np.min(np.linalg.norm(phi_q, axis=1) / scales) > 0.05


def test_bennett_linkage_moves_with_one_degree_of_freedom():
    """The Bennett linkage generated above assembles over a crank range (the closure holds: a real overconstrained linkage)."""
    mechanism = MECHANISMS["bennett"]()
    constraints = C.constraint_set(mechanism)
    q = pin.neutral(mechanism.model)
    for angle in np.linspace(0.0, 1.2, 7):
        assembly = K.assemble(constraints, q, np.array([angle]), tolerance=1e-13)
        q = assembly.q
        assert assembly.residual_norm < 1e-13
        assert K.mobility(C.constraint_set(mechanism, driven=False), q) == 1


def _bennett_scene(tmp_path: Path, actuation: str, extra: str = "") -> Path:
    """A Bennett linkage of other proportions (a = 0.12 m, twists 40 and 70 deg) with gravity, integrated by RK45:
    its trial stages leave the closure manifold by up to ~1e-5 of a row's scale."""
    urdf = tmp_path / "bennett.urdf"
    urdf.write_text(bennett_urdf(theta1=1.0, a=0.12, alpha_deg=40.0, beta_deg=70.0))
    path = tmp_path / "bennett.toml"
    path.write_text(
        f'name = "bennett"\nmechanism = "{urdf.as_posix()}"\nend_effector = "l2"\nduration = 0.1\ngravity = [0.0, 0.0, -9.81]\n'
        f"{actuation}\n[solver]\nmethod = \"RK45\"\nrtol = 1e-9\natol = 1e-11\nmax_step = 1e-3\n"
        f'[output]\nprecision = "float64"\n{extra}'
    )
    return path


def _bennett_angles_error(result) -> float:
    """Largest deviation of the joint angles from Bennett's closed form (theta3 = -theta1, the theta2 relation)."""
    alpha, beta = math.radians(40.0), math.radians(70.0)
    ratio = math.sin((beta + alpha) / 2) / math.sin((beta - alpha) / 2)
    q = result["q"]  # offsets from the assembled angles at theta1 = 1
    theta1 = 1.0 + q[:, 0]
    theta2_at_1 = 2.0 * math.atan(ratio / math.tan(0.5))
    theta2 = 2.0 * np.arctan(ratio / np.tan(theta1 / 2))
    return float(max(np.abs(q[:, 2] + q[:, 0]).max(), np.abs(q[:, 1] - (theta2 - theta2_at_1)).max()))


@pytest.mark.parametrize(
    "actuation",
    ['[trajectory]\ntype = "joints"\nj1 = { function = "constant_rate", offset = 0.0, rate = 10.0 }\n', '[actuators]\nj1 = { mode = "none" }\n[initial]\nvelocities = { j1 = 15.0 }\n'],
    ids=["driven_10_rad_s", "passive_15_rad_s"],
)
def test_a_fast_bennett_linkage_keeps_its_dependent_rows_out_off_the_manifold(tmp_path, actuation):
    """Off the manifold (RK45's trial stages) the third closure row of a Bennett linkage looked independent (pivots
    1e-10 to 1e-5), and the re-detection kept it: three closure rows and the driver on three velocities, a singular
    system, the crank off its drive and the run stalled at 1e-4 s; the passive linkage lost energy. Now the closure
    rows kept never outnumber nv less the drivers and a dropped row comes back only beyond 1e-3 (redundancy.closure_rank):
    the motion is Bennett's closed form, the closure holds and the energy balance closes."""
    run, result = _run(_bennett_scene(tmp_path, actuation))
    assert result.success, result.message
    assert result.counts["n_steps"] < 200  # 100 and 101 (max_step 1e-3 over 0.1 s); a stalled run took 40,000 for 1e-4 s
    assert np.abs(result["constraint_residual"]).max() < 1e-11  # measured 4.7e-14 (driven), 7.5e-14 (passive)
    assert _bennett_angles_error(result) < 1e-11  # measured 6.9e-14, 7.7e-14
    energy = result["kinetic_energy"] + result["potential_energy"]
    balance = energy - energy[0] - result["actuator_work"]
    assert np.abs(balance).max() < 1e-11 * np.abs(energy).max()  # measured 3.6e-14, 2.1e-14 relative


def test_actuators_that_over_constrain_the_mechanism_are_refused():
    """A four-bar with crank and rocker both driven: closure rank 2 + 2 drivers on 3 velocities. The cap of the kept
    closure rows (never more than nv less the drivers) must not hide it by dropping an independent closure row."""
    text = FOUR_BAR.read_text()
    second = '<transmission name="rocker_transmission"><joint name="rocker"/><actuator name="M2"/></transmission>'
    assert text.count("</robot>") == 1
    mechanism = build_mechanism(parse_mechanism(text.replace("</robot>", second + "</robot>"), is_text=True))
    q = K.assemble(C.constraint_set(mechanism, driven=False), pin.neutral(mechanism.model)).q  # a closed pose
    data = mechanism.model.createData()
    K.update_kinematics(mechanism.model, data, q)
    driven = C.constraint_set(mechanism, driven=True)
    with pytest.raises(SingularConfigurationError, match=r"2 driving constraints \(crank, rocker\) and closure equations of rank 2 on 3 velocity coordinates: the actuators over-constrain"):
        R.detect(driven, mechanism.model, data, C.jacobian(driven, mechanism.model, data), warn=False)


def test_a_dropped_row_comes_back_only_when_it_is_clearly_independent():
    """closure_rank: the tolerance's rank, capped by nv less the drivers, and above a previous selection's count only
    for pivots beyond RANK_GROWTH_TOLERANCE (a mechanism leaving a singular configuration)."""
    pivots = np.array([1.0, 0.47, 3e-6])
    previous = SimpleNamespace(n_closure_kept=2)
    assert R.closure_rank(pivots, 1e-9, n_velocities=3, n_driving=0, previous=None) == 3
    assert R.closure_rank(pivots, 1e-9, n_velocities=3, n_driving=1, previous=None) == 2  # no more than nv rows
    assert R.closure_rank(pivots, 1e-9, n_velocities=3, n_driving=0, previous=previous) == 2  # drift, not a new row
    assert R.closure_rank(np.array([1.0, 0.47, 0.02]), 1e-9, n_velocities=3, n_driving=0, previous=previous) == 3
    assert R.closure_rank(np.array([1.0, 1e-12]), 1e-9, n_velocities=3, n_driving=0, previous=previous) == 1  # rank lost


def test_a_revolute_closures_ignored_child_orientation_is_reported():
    """The child-side axis of a revolute closure is the parent's at q = 0 (docs/kinematics.md): a declared child rpy
    that disagrees is named in a warning, and the assembly's failure says where the axis comes from; a declared rpy
    that agrees (the Bennett linkage assembled at q = 0) says nothing."""
    import robot.errors as E

    with warnings.catch_warnings():
        warnings.simplefilter("error", E.ClosureDeclarationWarning)
        build_mechanism(parse_mechanism(bennett_urdf(), is_text=True))
    with pytest.warns(E.ClosureDeclarationWarning, match=r"closure 'J4': the child frame's rpy .* is not used"):
        mechanism = build_mechanism(parse_mechanism(bennett_urdf(alpha_deg=40.0, beta_deg=70.0, baked=False), is_text=True))
    with pytest.raises(E.UnreachablePoseError, match="cannot be met from the initial guess"):
        K.assemble(C.constraint_set(mechanism, driven=False), pin.neutral(mechanism.model))
    from robot.model.initial_state import _revolute_closure_hint

    assert "J4 take their child-side axis from the parent's at the neutral configuration" in _revolute_closure_hint(mechanism)


# --------------------------------------------------------------------------- exact dynamics at a state


def _state(mechanism, drive=(0.3, 4.0, -7.0)):
    """An assembled, driven state (crank angle, rate and acceleration ``drive``)."""
    constraints = C.constraint_set(mechanism)
    s, sd, sdd = (np.array([x]) for x in drive)
    q = K.assemble(constraints, pin.neutral(mechanism.model), s).q
    v = K.velocity_analysis(constraints, q, sd)
    return q, v, K.acceleration_analysis(constraints, q, v, sdd), (s, sd, sdd)


class _Fixed:
    """A drive that returns the same (s, sd, sdd) at every time."""

    def __init__(self, values):
        self.values = values

    def drive(self, t):
        return self.values


@pytest.mark.parametrize("name", ["slider_crank", "four_bar", "four_bar_spherical", "bennett", "slider_crank_rotated_base"])
def test_accelerations_and_driving_force_are_those_of_the_mechanism(name):
    """Driven with no remaining freedom, the KKT accelerations must equal the kinematic acceleration
    analysis; the driving force equals the closed-loop inverse dynamics (least squares, exact for a
    consistent system); the multipliers reproduce the constraint force and are the minimum-norm ones."""
    mechanism = MECHANISMS[name]()
    q, v, qdd_kinematic, drive = _state(mechanism)
    dynamics = D.make_dynamics_model(mechanism, {}, _Fixed(drive), end_effector_frame=mechanism.model.frames[1].name)
    workspace = D.make_workspace(dynamics)
    with pytest.warns(RedundantConstraintWarning, match=r"closure equations are redundant .*: [A-Z0-9]+:(x|y|z|rot_x|rot_y)"):
        evaluation = D.evaluate(dynamics, workspace, 0.0, q, v, np.zeros(0))
    scale = np.abs(qdd_kinematic).max()
    np.testing.assert_allclose(evaluation.qdd, qdd_kinematic, atol=1e-9 * scale)
    force = evaluation.driving_force(dynamics.constraints)
    expected = D.inverse_dynamics_driving_forces(dynamics, workspace, q, v, qdd_kinematic)
    np.testing.assert_allclose(force, expected, rtol=1e-9)
    model, data = mechanism.model, workspace.data
    pin.computeJointJacobians(model, data, q)
    pin.updateFramePlacements(model, data)
    phi_q = C.jacobian(dynamics.constraints, model, data)
    generalized = pin.rnea(model, model.createData(), q, v, evaluation.qdd)  # M qdd + h = -Phi_q^T lambda
    np.testing.assert_allclose(-phi_q.T @ evaluation.multipliers, generalized, atol=1e-9 * np.abs(generalized).max())
    # minimum norm: orthogonal to the null space of Phi_q^T
    u, singular, _ = np.linalg.svd(phi_q)
    rank = int(np.sum(singular > 1e-9 * singular[0]))
    assert np.abs(u[:, rank:].T @ evaluation.multipliers).max() < 1e-9 * np.abs(evaluation.multipliers).max()
    assert np.abs(evaluation.multipliers).max() < 1e3  # no 1e15 multiplier from a 4e-17 row
    if name in ("slider_crank", "four_bar", "slider_crank_rotated_base"):  # identically satisfied rows carry nothing
        redundant = [dynamics.constraints.row_labels.index(label) for label in workspace.rows.labels]
        assert np.abs(evaluation.multipliers[redundant]).max() < 1e-12 * np.abs(evaluation.multipliers).max()


def test_compiled_right_hand_side_uses_the_reduced_rows():
    """Spherical closures take the compiled right-hand side; with a redundant row (a planar four-bar
    closed by a spherical joint) it must give the same state derivative as the Python path."""
    mechanism = MECHANISMS["four_bar_spherical"]()
    q, v, qdd_kinematic, drive = _state(mechanism)
    dynamics = D.make_dynamics_model(mechanism, {}, _Fixed(drive), end_effector_frame="crank")
    compiled = D.make_workspace(dynamics)
    python = D.make_workspace(dynamics)
    python.compiled = None
    assert compiled.compiled is not None
    y = np.concatenate([q, v])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RedundantConstraintWarning)
        fast = D.state_derivative(dynamics, compiled, 0.0, y, np.zeros(0))
        slow = D.state_derivative(dynamics, python, 0.0, y, np.zeros(0))
    nq, nv = mechanism.model.nq, mechanism.model.nv
    np.testing.assert_allclose(fast, slow, rtol=1e-12, atol=1e-12 * np.abs(slow).max())
    np.testing.assert_allclose(fast[nq : nq + nv], qdd_kinematic, atol=1e-9 * np.abs(qdd_kinematic).max())
    assert compiled.rows.labels == ("B:z",)
    # actuator power = driving force x crank rate
    force = D.inverse_dynamics_driving_forces(dynamics, python, q, v, qdd_kinematic)
    assert fast[nq + nv] == pytest.approx(force[0] * drive[1][0], rel=1e-9)


def test_a_dropped_row_that_becomes_independent_is_detected_again():
    """The selection made at one state is checked at every solve: forced onto a state where the
    slider-crank's kept rows are the wrong ones (a selection from the Bennett-like fake below), the
    check fails, the rows are detected again and the accelerations stay exact."""
    mechanism = MECHANISMS["slider_crank"]()
    q, v, qdd_kinematic, drive = _state(mechanism)
    dynamics = D.make_dynamics_model(mechanism, {}, _Fixed(drive), end_effector_frame="crank")
    workspace = D.make_workspace(dynamics)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RedundantConstraintWarning)
        D.evaluate(dynamics, workspace, 0.0, q, v, np.zeros(0))
        good = workspace.rows
        # keep the zero rows z, rot_x and drop x, y: a wrong selection
        wrong = R.RowSelection(np.array([2, 3, 5]), np.array([0, 1, 4]), 2, good.scales, ("K:x", "K:y", "K:rot_y"))
        workspace.rows = wrong
        evaluation = D.evaluate(dynamics, workspace, 0.0, q, v, np.zeros(0))
    assert workspace.rank_checks == 1
    assert workspace.rows.same_rows(good)
    np.testing.assert_allclose(evaluation.qdd, qdd_kinematic, atol=1e-9 * np.abs(qdd_kinematic).max())


# --------------------------------------------------------------------------- gravity


def _redrawn_in_xz(path: Path) -> str:
    """The slider-crank drawn in the x-z plane: the x-y drawing turned by +90 deg about x (y -> z,
    so its gravity -y becomes -z); joint axes z -> -y, the crank's and rod's origin angles about -y."""
    text = path.read_text()
    for old, new in (('rpy="0 0 1.0471975511965976"', 'rpy="0 -1.0471975511965976 0"'), ('rpy="0 0 -1.4"', 'rpy="0 1.4 0"')):
        assert text.count(old) == 1
        text = text.replace(old, new)
    assert text.count('<axis xyz="0 0 1"/>') == 3
    return text.replace('<axis xyz="0 0 1"/>', '<axis xyz="0 -1 0"/>')


def test_gravity_in_the_plane_of_a_mechanism_drawn_in_x_y_or_x_z(tmp_path):
    """Three formulations of one physical run: drawn in x-y with gravity -y; redrawn in x-z with
    gravity -z; the x-y drawing on a base link rotated by 90 deg about x with gravity -z (4e-17
    entries in the constraint rows). Same driving torque at every record, and equal to the closed form."""
    xz = tmp_path / "xz.urdf"
    xz.write_text(_redrawn_in_xz(SLIDER_CRANK))
    rotated = tmp_path / "rotated.urdf"
    rotated.write_text(_rotated_base(SLIDER_CRANK, "1.5707963267948966 0 0"))
    runs = {
        "xy": _run(_scene(tmp_path, SLIDER_CRANK, (0.0, -9.81, 0.0), "xy")),
        "xz": _run(_scene(tmp_path, xz, (0.0, 0.0, -9.81), "xz")),
        "rotated": _run(_scene(tmp_path, rotated, (0.0, 0.0, -9.81), "rotated")),
    }
    reference = runs["xy"][1]
    scale = np.abs(reference["driving_force"]).max()
    for name, (run, result) in runs.items():
        assert result.success, (name, result.message)
        np.testing.assert_allclose(result["t"], reference["t"], rtol=0, atol=1e-12)
        np.testing.assert_allclose(result["driving_force"], reference["driving_force"], rtol=0, atol=1e-8 * scale)
        relative, _ = _torque_error(run, result, lambda th: slider_crank_torque(th, OMEGA, np.array([0.0, -9.81])))
        assert relative < 1e-6, (name, relative)
    # gravity along the crank axis does no work: the torque is the inertial part only
    run, result = _run(_scene(tmp_path, SLIDER_CRANK, (0.0, 0.0, -9.81), "vertical"))
    relative, _ = _torque_error(run, result, lambda th: slider_crank_torque(th, OMEGA, np.zeros(2)))
    assert relative < 1e-6


@pytest.mark.parametrize("value", ["[0.0, -9.81]", "[0.0, nan, -9.81]", '"down"', "[0.0, 0.0, inf]", '[0.0, 0.0, "-9.81"]', "[true, 0.0, 0.0]"])
def test_bad_gravity_is_a_scene_error_naming_the_key(tmp_path, value):
    from robot.errors import SceneError
    from robot.scene.loader import load_scene

    path = _scene(tmp_path, SLIDER_CRANK)
    path.write_text(path.read_text().replace("gravity = [0.0, -9.81, 0.0]", f"gravity = {value}"))
    with pytest.raises(SceneError, match=r"gravity=.* must be three finite numbers \[gx, gy, gz\]") as error:
        load_scene(path)
    shown = str(error.value).split("gravity=")[1]
    assert shown.startswith(("[", "'down'")), shown


def test_gravity_reaches_the_pinocchio_model(tmp_path):
    from robot.errors import MechanismFileError

    run = build_run(str(_scene(tmp_path, RSSR, (1.0, -2.0, 3.0))))
    np.testing.assert_array_equal(run.mechanism.model.gravity.linear, [1.0, -2.0, 3.0])
    np.testing.assert_array_equal(run.mechanism.model.gravity.angular, 0.0)
    np.testing.assert_array_equal(build_mechanism(RSSR).model.gravity.linear, [0.0, 0.0, -9.81])
    with pytest.raises(MechanismFileError, match=r"gravity=\(0, 1\) must be three finite numbers"):
        build_mechanism(RSSR, gravity=(0, 1))
