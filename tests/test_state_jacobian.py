"""The structured Jacobian of the state derivative (``robot.dynamics.state_jacobian``).

* its stiff blocks (accelerations and powers against positions and velocities,
  in contact) equal a central-difference Jacobian of the right-hand side;
* what it leaves out is not stiff: the Newton iterations it steers contract as
  fast as with the exact matrix at every step size an implicit method uses;
* it is invariant to the scale of a quaternion, as the right-hand side is;
* it applies only where it can (compiled path, shipped laws), and a run with it
  follows the same trajectory as one with the solver's own differences, with far
  fewer right-hand sides; a bad choice is refused by name.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pinocchio as pin
import pytest

from clearance_contact import ContactError
from robot.dynamics import equations as D
from robot.dynamics import state_jacobian as SJ
from robot.integration import options as OPT
from robot.errors import SceneError
from robot.run import build_run
from robot.scene.loader import load_scene
from robot.integration.simulation import SolverOptions, integrate
from robot.analysis.studies.speed import sample_states
from tests.conftest import calibrated_scene

from conftest import assert_passes_as_plain_python


@pytest.fixture(scope="module")
def misaligned():
    return build_run(calibrated_scene("compound_misaligned"))


@pytest.fixture(scope="module")
def states(misaligned):
    return sample_states(misaligned)


def _jacobians(run, t, y, onset):
    dynamics = run.dynamics
    n = dynamics.nq + dynamics.nv + 2
    structured = SJ.for_workspace(dynamics, D.make_workspace(dynamics))(t, y, onset, np.empty((n, n)))
    workspace = D.make_workspace(dynamics)
    # small steps: a candidate may have just touched (penetration ~1e-9 m)
    differenced = SJ.finite_difference_jacobian(lambda tt, yy: D.state_derivative(dynamics, workspace, tt, yy, onset), t, y, relative_step=1e-9)
    return structured, differenced


@pytest.fixture(scope="module")
def scene_states(scene_runs):
    """``get(name)``: (run, sample_states(run)) of a scene of conftest's ``scene_runs``, built once."""
    cache = {}

    def get(name):
        if name not in cache:
            run = scene_runs(name)
            cache[name] = run, sample_states(run)
        return cache[name]

    return get


#: (scene, state) of the stiff-block checks: the 4-UPS/RPS, revolute closures with a revolute
#: clearance joint (the slider-crank's rod, the four-bar's rocker floating on it: the closure's axis rows
#: are not identically zero)
STIFF_CASES = [
    ("compound_misaligned", "some joints in contact"),
    ("compound_misaligned", "all joints in contact"),
    ("slider_crank_rod_clearance", "all joints in contact"),
    ("four_bar_rocker_clearance", "all joints in contact"),
    # a translational clearance joint (slider in its guide, corners of a planar slider-crank)
    ("slider_crank_translational", "all joints in contact"),
]


@pytest.mark.parametrize("scene, state", STIFF_CASES)
def test_stiff_blocks_equal_central_differences_in_contact(scene_states, scene, state):
    """Each block on its own (positions and velocities differ by ~1e5 in scale)."""
    run, states = scene_states(scene)
    dynamics = run.dynamics
    nq, nv = dynamics.nq, dynamics.nv
    structured, differenced = _jacobians(run, *states[state])
    rows = {"accelerations": slice(nq, nq + nv), "powers": slice(nq + nv, nq + nv + 2)}
    columns = {"positions": slice(0, nq), "velocities": slice(nq, nq + nv)}
    for row_name, row in rows.items():
        for column_name, column in columns.items():
            exact = differenced[row, column]
            error = np.linalg.norm(structured[row, column] - exact) / np.linalg.norm(exact)
            assert error < 2e-3, f"{state}: d {row_name} / d {column_name}: relative error {error:.2e}"
    # the contact makes these blocks stiff and damped: ~1e8 1/s^2 and ~1e3 1/s, against ~1e2 and
    # ~1e1 out of contact
    assert np.linalg.norm(differenced[rows["accelerations"], columns["positions"]]) > 1e7
    assert np.linalg.norm(differenced[rows["accelerations"], columns["velocities"]]) > 5e2


@pytest.mark.filterwarnings("ignore::robot.errors.RedundantConstraintWarning")
@pytest.mark.parametrize(
    "scene, gain", [("compound_misaligned", 1e3), ("slider_crank_rod_clearance", 1e4), ("four_bar", 1e4), ("mixed", 1e4)]
)
def test_stiff_stabilisation_blocks_equal_central_differences(scene_states, scene, gain):
    """Large Baumgarte gains make the stabilisation terms (-beta^2 X Phi_q, -2 alpha X Phi_q) stiff;
    with revolute closures their axis rows take part (four_bar, mixed: with redundant rows left out).
    The left-out terms grow with the gains too, the kept ones faster: the matrix's error falls as
    1/gain (slider-crank: 3.8e-2 at 1e3, 3.8e-3 at 1e4); the light links of the tests/data
    mechanisms (1e-5 kg m^2) need 1e4 where the 4-UPS/RPS needs 1e3."""
    original, states = scene_states(scene)
    dynamics = dataclasses.replace(original.dynamics, baumgarte=D.Baumgarte(gain, gain))
    run = dataclasses.replace(original, dynamics=dynamics)
    nq, nv = dynamics.nq, dynamics.nv
    structured, differenced = _jacobians(run, *states["initial"])
    for row in (slice(nq, nq + nv), slice(nq + nv, nq + nv + 2)):
        for column in (slice(0, nq), slice(nq, nq + nv)):
            exact = differenced[row, column]
            assert np.linalg.norm(structured[row, column] - exact) < 5e-3 * np.linalg.norm(exact)
    assert np.linalg.norm(differenced[nq : nq + nv, :nq]) > gain**2  # beta^2


def test_compiled_kernels_run_as_plain_python():
    """``CLEARANCE_CONTACT_JIT=0``: ``robot.dynamics.jacobian_kernels`` run as Python, same checks pass."""
    assert_passes_as_plain_python(__file__, "stiff_blocks_equal or quaternion_scale", len(STIFF_CASES) + 1)


@pytest.mark.parametrize("state", ["initial", "some joints in contact", "all joints in contact"])
def test_newton_iterations_contract_as_with_the_exact_matrix(misaligned, states, state):
    """Spectral radius of the Newton error map ``I - (I - g J)^-1 (I - g J~)`` at step-size factors g."""
    structured, differenced = _jacobians(misaligned, *states[state])
    identity = np.eye(structured.shape[0])
    for gamma in (1e-5, 1e-4, 1e-3):
        error_map = identity - np.linalg.solve(identity - gamma * differenced, identity - gamma * structured)
        radius = np.max(np.abs(np.linalg.eigvals(error_map)))
        assert radius < 1e-2, f"{state}, gamma={gamma}: contraction {radius:.2e}"


def test_quaternion_scale_direction_is_annihilated(misaligned, states):
    """f depends on the normalised quaternions only: the Jacobian along each quaternion itself is zero."""
    dynamics = misaligned.dynamics
    model = dynamics.mechanism.model
    t, y, onset = states["all joints in contact"]
    structured, _ = _jacobians(misaligned, t, y, onset)
    quaternions = [slice(model.idx_qs[j] + 3, model.idx_qs[j] + 7) for j in range(1, model.njoints) if model.nqs[j] == 7]
    assert len(quaternions) == 2
    for block in quaternions:
        along = structured[:, block] @ y[block]
        assert np.max(np.abs(along)) < 1e-9 * np.max(np.abs(structured[:, block]))


def test_applies_only_to_the_compiled_path_with_shipped_laws(misaligned, with_python_laws):
    dynamics = misaligned.dynamics
    assert SJ.for_workspace(dynamics, D.make_workspace(dynamics)) is not None
    wrapped = with_python_laws(dynamics)
    assert SJ.for_workspace(wrapped, D.make_workspace(wrapped)) is None
    with pytest.raises(ValueError, match="compiled laws"):
        SJ.StateJacobian(wrapped, D.make_workspace(wrapped))


@pytest.mark.parametrize("method, rtol", [("CVODE_BDF", 1e-6), ("BDF", 1e-6)])
def test_a_run_with_it_follows_the_differenced_run(misaligned, method, rtol):
    """Same trajectory to the tolerance's order, through the first impacts; far fewer right-hand sides."""
    runs = {}
    for jacobian in OPT.JACOBIAN_CHOICES:
        options = SolverOptions(method, rtol=rtol, atol=rtol * 1e-2, max_step=1e-3, jacobian=jacobian)
        runs[jacobian] = integrate(misaligned.dynamics, misaligned.y0, (0.0, 0.02), options, misaligned.scene.limits)
    structured, differenced = runs[OPT.STRUCTURED], runs[OPT.FINITE_DIFFERENCE]
    assert structured.success and differenced.success
    assert any(e[2] == "onset" for e in structured.events)
    nq = misaligned.dynamics.nq
    assert np.max(np.abs(structured.y[-1, :nq] - differenced.y[-1, :nq])) < 1e-6
    assert structured.n_jacobians > 0 and differenced.n_jacobians > 0
    assert structured.n_rhs < 0.75 * differenced.n_rhs, (structured.n_rhs, differenced.n_rhs)


def test_an_unknown_choice_is_refused_by_name(tmp_path):
    with pytest.raises(ValueError, match="jacobian='analytic'.*structured, finite-difference"):
        SolverOptions("CVODE_BDF", jacobian="analytic")
    scene = tmp_path / "scene.toml"
    scene.write_text('extends = "compound_misaligned"\n[solver]\nmethod = "CVODE_BDF"\njacobian = "exact"\n')
    with pytest.raises(SceneError, match=r"\[solver\]: jacobian='exact' is not on offer"):
        load_scene(str(scene))
    scene.write_text('extends = "compound_misaligned"\n[solver]\nmethod = "CVODE_BDF"\njacobian = "finite-difference"\n')
    assert load_scene(str(scene)).solver.jacobian == OPT.FINITE_DIFFERENCE


def test_a_refused_perturbation_falls_back_to_differences(misaligned, monkeypatch):
    """A contact law refusing a perturbed input: that Jacobian is differenced instead, the run goes on."""
    refusals, fallbacks = [], []

    def refuse(self, t, onset_rates):
        refusals.append(t)
        raise ContactError("refused for the test")

    differenced = SJ.finite_difference_jacobian

    def spy(fun, t, y, relative_step=1e-7, base=None):
        matrix = differenced(fun, t, y, relative_step, base)
        fallbacks.append((t, y.copy(), matrix))
        return matrix

    monkeypatch.setattr(SJ.StateJacobian, "contact_stiffness", refuse)
    monkeypatch.setattr(SJ, "finite_difference_jacobian", spy)
    options = SolverOptions("CVODE_BDF", rtol=1e-6, atol=1e-8, max_step=1e-3)
    trajectory = integrate(misaligned.dynamics, misaligned.y0, (0.0, 0.01), options, misaligned.scene.limits)
    assert trajectory.success, trajectory.message
    assert len(refusals) == len(fallbacks) == trajectory.n_jacobians > 0
    n = misaligned.dynamics.nq + misaligned.dynamics.nv + 2
    # forward differences from the base value: n + 1 right-hand sides per Jacobian
    assert trajectory.n_rhs >= (n + 1) * trajectory.n_jacobians
    # the fallback is the Jacobian of the right-hand side: d(dq/dt)/dv is the tangent map
    t, y, matrix = fallbacks[-1]
    nq, nv = misaligned.dynamics.nq, misaligned.dynamics.nv
    tangent = pin.tangentMap(misaligned.dynamics.mechanism.model, D.normalise_quaternions(misaligned.dynamics.mechanism, y[:nq]))
    np.testing.assert_allclose(matrix[:nq, nq : nq + nv], tangent, atol=1e-6)
