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

import numpy as np
import pinocchio as pin
import pytest

from robot.dynamics import equations as D
from robot.dynamics import redundancy as R
from robot.errors import RedundantConstraintWarning
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
