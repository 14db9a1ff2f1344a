"""Newton-Euler formulation (robot.validation) against the Lagrange model: short horizons, asserted tolerances.

Both engines run with the validation's pinned solver (``robot.validation.settings.VALIDATION_SOLVER``:
RK45, rtol 1e-7, atol 1e-9, max_step 1e-3 s), never with the scene's ``[solver]``: the thresholds
below are calibrated to it.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pinocchio as pin
import pytest

from robot.run import build_run, run_scene
from robot.scene.loader import load_scene
from robot.validation import comparison as CMP
from robot.validation import newton_euler as NE
from robot.validation import study
from robot.validation.absolute_constraints import skew
from robot.validation.event_loop import integrate_with_events
from robot.validation.settings import VALIDATION_SOLVER, validation_run, validation_solver
from tests.conftest import calibrated_scene, calibrated_scene_file

#: the comparison thresholds before the first impact (calibrated to VALIDATION_SOLVER)
ONSET_TOL_S = 1e-8
FORCE_REL_TOL = 1e-6
EE_TOL_M = 1e-9
PEAK_REL_TOL = 0.01


def _moved(model: NE.NewtonEulerModel, y: np.ndarray, dr: np.ndarray, dpi: np.ndarray, eps: float) -> np.ndarray:
    """State with every body translated by eps dr (world) and rotated by eps dpi (body axes)."""
    r, p, v, w = model.split(np.array(y))
    r = r + eps * dr
    out = []
    for k in range(model.n):
        half = 0.5 * eps * dpi[k]
        angle = np.linalg.norm(half)
        dq = np.concatenate([[np.cos(angle)], np.sinc(angle / np.pi) * half])
        e0, e = p[k, 0], p[k, 1:]
        out.append(np.concatenate([[e0 * dq[0] - e @ dq[1:]], e0 * dq[1:] + dq[0] * e + np.cross(e, dq[1:])]))
    return np.concatenate([r.ravel(), np.array(out).ravel(), v.ravel(), w.ravel()])


@pytest.fixture(scope="module")
def compound_model():
    run = build_run(calibrated_scene("compound", duration=0.01))
    model = NE.build_model(run)
    return run, model, NE.initial_state(model, run)


def test_initial_state_satisfies_the_absolute_constraints(compound_model):
    run, model, y0 = compound_model
    states = model.states(y0)
    rows = model.constraints.evaluate(states, model.drive.drive(0.0))
    velocity = np.hstack([states.v[: model.n], states.w[: model.n]])
    assert np.max(np.abs(rows.phi)) < 1e-12
    assert np.max(np.abs(model.constraints.times(rows.jacobian, velocity) + rows.phi_t)) < 1e-12
    # the end effector is the Pinocchio platform frame
    pmodel = run.mechanism.model
    data = pmodel.createData()
    pin.framesForwardKinematics(pmodel, data, run.y0[: pmodel.nq])
    ee = NE.evaluate(model, 0.0, y0, np.full(model.n_candidates, 1e-3)).ee_position
    assert np.allclose(ee, data.oMf[run.dynamics.end_effector_frame].translation, atol=1e-14)


def test_constraint_jacobian_and_gamma_match_finite_differences(compound_model):
    """Phi_q against central differences of Phi; gamma against d/dt (Phi_q v) along a motion with zero acceleration."""
    _, model, y0 = compound_model
    rng = np.random.default_rng(7)
    n = model.n
    cs = model.constraints
    dr, dpi = rng.normal(size=(n, 3)), rng.normal(size=(n, 3))
    eps = 1e-6
    drive = model.drive.drive(0.0)
    plus = cs.evaluate(model.states(_moved(model, y0, dr, dpi, eps)), drive).phi
    minus = cs.evaluate(model.states(_moved(model, y0, dr, dpi, -eps)), drive).phi
    rows = cs.evaluate(model.states(y0), drive)
    predicted = cs.times(rows.jacobian, np.hstack([dr, dpi]))
    assert np.max(np.abs((plus - minus) / (2 * eps) - predicted)) < 1e-8
    # dense form agrees with the compact one
    assert np.allclose(cs.dense(rows.jacobian) @ np.hstack([dr, dpi]).ravel(), predicted, atol=1e-14)
    # gamma (with s'' = 0) = -(d/dt Phi_q) v for constant v and body angular velocity
    r, p, v, w = model.split(y0)
    still = (drive[0], drive[1], np.zeros_like(drive[2]))

    def rate(h):
        y = _moved(model, y0, v, w, h)
        st = model.states(y)
        rr = cs.evaluate(st, still)
        return cs.times(rr.jacobian, np.hstack([st.v[:n], st.w[:n]]))

    d_rate = (rate(eps) - rate(-eps)) / (2 * eps)
    gamma = cs.evaluate(model.states(y0), still).gamma
    assert np.max(np.abs(d_rate + gamma)) < 1e-6 * max(1.0, np.max(np.abs(gamma)))


def test_range_space_solution_equals_the_augmented_system(compound_model):
    """The Schur-complement solve equals a dense solve of [M Phi_q^T; Phi_q 0]."""
    _, model, y0 = compound_model
    n = model.n
    onset = np.full(model.n_candidates, 1e-3)
    y = np.array(y0)
    y[7 * n : 13 * n] += 1e-3 * np.random.default_rng(1).normal(size=6 * n)  # off the manifold: Baumgarte terms active
    ev = NE.evaluate(model, 0.003, y, onset)
    st = model.states(y)
    rows = model.constraints.evaluate(st, model.drive.drive(0.003))
    J = model.constraints.dense(rows.jacobian)
    M = np.zeros((6 * n, 6 * n))
    for k in range(n):
        M[6 * k : 6 * k + 3, 6 * k : 6 * k + 3] = model.mass[k] * np.eye(3)
        M[6 * k + 3 : 6 * k + 6, 6 * k + 3 : 6 * k + 6] = model.inertia[k]
    w = st.w[:n]
    Q = np.hstack([model.mass[:, None] * NE.GRAVITY, -np.cross(w, np.einsum("kij,kj->ki", model.inertia, w))]).ravel()
    phi_dot = J @ np.hstack([st.v[:n], w]).ravel() + rows.phi_t
    rhs = rows.gamma - 2 * model.alpha * phi_dot - model.beta**2 * rows.phi
    m = J.shape[0]
    kkt = np.block([[M, J.T], [J, np.zeros((m, m))]])
    solution = np.linalg.solve(kkt, np.concatenate([Q, rhs]))  # no contact at this state
    acc = solution[: 6 * n].reshape(n, 6)
    assert not any(np.any(c.in_contact) for c in ev.contacts)
    assert np.allclose(ev.multipliers, solution[6 * n :], rtol=1e-9, atol=1e-9)
    assert np.allclose(ev.ydot[7 * n : 10 * n], acc[:, :3].ravel(), atol=1e-9)
    assert np.allclose(ev.ydot[10 * n :], acc[:, 3:].ravel(), atol=1e-9)
    assert skew(np.array([[1.0, 2.0, 3.0]]))[0] @ np.array([4.0, 5.0, 6.0]) == pytest.approx(np.cross([1, 2, 3], [4, 5, 6]))


def _series_pair(scene: str, duration: float):
    run = validation_run(calibrated_scene(scene, duration=duration) if scene.startswith("compound") else load_scene(scene).with_changes({"duration": duration}))
    assert run.scene.solver == VALIDATION_SOLVER
    lagrange = run_scene(run)
    assert lagrange.success, lagrange.message
    result = NE.simulate(run, t_eval=lagrange["t"])
    assert result.success, result.run.message
    return run, lagrange, result


def test_ideal_mechanism_agrees_with_the_lagrange_model():
    """Same integrator and tolerances: driving forces within 1e-6 relative, end effector within 1 nm, over 0.15 s."""
    _, lagrange, result = _series_pair("ideal", 0.15)
    e = result.eval_arrays
    scale = np.max(np.abs(lagrange["driving_force"]))
    assert np.max(np.abs(e["driving_force"] - lagrange["driving_force"])) <= 1e-6 * scale
    assert np.max(np.abs(e["ee_position"] - lagrange["ee_position"])) <= 1e-9
    assert np.max(result.arrays["constraint_residual"]) < 1e-9


def test_compound_clearance_agrees_before_and_at_the_first_impact():
    """Before the first contact onset: integration tolerance; the first onset time and peak force agree."""
    _, lagrange, result = _series_pair("compound", 0.006)
    onsets = lagrange["event_t"][lagrange["event_is_onset"]]
    first = onsets.min()
    ne_onsets = np.array([t for t, _, kind in result.run.events if kind == "onset"])
    assert abs(ne_onsets.min() - first) < ONSET_TOL_S
    before = lagrange["t"] < first
    e = result.eval_arrays
    scale = np.max(np.abs(lagrange["driving_force"][before]))
    assert np.max(np.abs(e["driving_force"][before] - lagrange["driving_force"][before])) <= FORCE_REL_TOL * scale
    assert np.max(np.abs(e["ee_position"][before] - lagrange["ee_position"][before])) <= EE_TOL_M
    for site in ("S1", "R1"):
        peak_lagrange = np.max(lagrange[f"{site}_normal_force"])
        peak_ne = np.max(result.arrays[f"{site}_normal_force"])
        assert peak_lagrange > 100.0  # an impact happened
        assert abs(peak_ne - peak_lagrange) <= PEAK_REL_TOL * peak_lagrange


LSODA_SCENE = """
extends = "compound_calibrated.toml"
name = "compound_lsoda"
[solver]
method = "LSODA"
rtol = 1e-6
atol = 1e-8
max_step = 5e-3
"""


@pytest.fixture
def lsoda_scene(tmp_path):
    """A scene whose [solver] asks for LSODA (a method the Newton-Euler event loop does not offer)."""
    calibrated_scene_file(tmp_path, "compound")
    path = tmp_path / "compound_lsoda.toml"
    path.write_text(LSODA_SCENE, encoding="utf-8")
    return path


def test_validation_uses_its_pinned_solver_not_the_scenes(lsoda_scene):
    """The study (scripts/validate.py's path) runs both engines with VALIDATION_SOLVER and meets its thresholds."""
    assert load_scene(lsoda_scene).solver.method == "LSODA"
    metrics, series = study.compare_scene(str(lsoda_scene), 0.006, engines=("lagrange", "newton_euler"), progress=lambda _: None)
    pinned = dataclasses.asdict(VALIDATION_SOLVER)
    assert metrics["validation_solver"] == pinned
    assert metrics["scene_solver"]["method"] == "LSODA" and metrics["scene_solver"]["rtol"] == 1e-6
    for engine in ("lagrange", "newton_euler"):  # what each engine actually ran with
        entry = metrics["engines"][engine]
        assert entry["success"], entry["message"]
        assert {k: entry["solver"][k] for k in ("method", "rtol", "atol", "max_step")} == {k: pinned[k] for k in ("method", "rtol", "atol", "max_step")}
    # the thresholds of the pinned validation hold
    ne = metrics["engines"]["newton_euler"]
    assert metrics["first_impact_s"] is not None
    assert abs(ne["statistics_relative_to_lagrange"]["first_onset_s"]) < ONSET_TOL_S
    before = ne["pointwise_before_first_impact"]
    assert before["n_points"] > 3
    assert before["driving_force_max_rel"] <= FORCE_REL_TOL
    assert before["ee_position_max_m"] <= EE_TOL_M
    for site in ("S1", "R1"):
        assert metrics["engines"]["lagrange"]["statistics"]["contact"][site]["peak_N"] > 100.0
        assert abs(ne["statistics_relative_to_lagrange"][site]["peak_N"]) <= PEAK_REL_TOL
    # the Lagrange records are the pinned run's: spacing bounded by its max_step, not the scene's 5e-3 s
    assert np.max(np.diff(series["lagrange"].t)) <= VALIDATION_SOLVER.max_step * (1 + 1e-9)


def test_unsupported_methods_are_refused_clearly(lsoda_scene):
    """Unpinned, the LSODA scene cannot run Newton-Euler: the error names the parameter, value and supported set."""
    unpinned = build_run(lsoda_scene, duration=1e-3)
    with pytest.raises(ValueError, match=r"method='LSODA' is not supported; supported methods: RK45, RK23, DOP853"):
        NE.simulate(unpinned)
    with pytest.raises(ValueError, match=r"rtol=0\.0 must be a positive number"):
        integrate_with_events(lambda t, y, o: -y, lambda t, y, o: (np.zeros(0), np.zeros(0)), np.ones(1), (0.0, 1.0), 0, rtol=0.0)
    with pytest.raises(ValueError, match=r"method='BDF' is not supported: .* supports RK45, RK23, DOP853"):
        validation_solver(method="BDF")
    assert validation_solver(method="BDF", newton_euler=False).method == "BDF"  # Lagrange against Exudyn only
    assert validation_solver(rtol=1e-8) == dataclasses.replace(VALIDATION_SOLVER, rtol=1e-8)
    with pytest.raises(SystemExit, match=r"method='LSODA' is not supported"):
        study.main(["--method", "LSODA", "--scenes", "compound", "--no-figures", "--out", str(lsoda_scene.parent / "out")])
    assert not (lsoda_scene.parent / "out").exists()  # refused before anything ran


def test_statistics_are_time_weighted():
    series = CMP.EngineSeries(
        "x", np.array([0.0, 0.5, 0.6, 1.0]), np.zeros((4, 1)), np.zeros((4, 3)), {"S1": np.array([0.0, 0.0, 10.0, 0.0])}, np.array([0.55])
    )
    stats = CMP.statistics(series, 1.0)
    assert stats["contact"]["S1"]["peak_N"] == 10.0
    assert stats["contact"]["S1"]["mean_N"] == pytest.approx(0.5 * 0.1 * 10 + 0.5 * 0.4 * 10)
