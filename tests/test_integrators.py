"""The fast right-hand side equals the reference computations; the added integrators work.

* ``ConstraintKernel`` (views, one Jacobian call, float 3-vectors) = ``residual``,
  ``jacobian``, ``gamma`` of ``robot.model.constraints``, for spherical-only, mixed and
  revolute-only constraint sets;
* ``state_derivative`` (compiled path of ``robot.dynamics.rhs_kernels``, with compiled
  or Python contact laws; table drive; tangent map) = the reference
  composition, in and out of contact;
* ``evaluate``, ``configuration_rate``, ``contact_probe`` = their reference forms;
* the drive table = the exact drive, and falls back to it where it cannot fit;
* generalized-alpha: second order, Newmark conserves the energy of an oscillator,
  Lie-group update of quaternions; CVODE through scikit-sundae.
"""

from __future__ import annotations

import dataclasses
import math
import warnings
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

from clearance_contact import ContactError
from robot.errors import DriveError, Error, RedundantConstraintWarning
from robot.model.description import CLOSURE_TYPES
from robot.model import constraints as C
from robot.dynamics import equations as D
from robot.integration import solvers as I
from robot.model.mechanism import build_mechanism
from robot.run import build_run
from robot.scene.loader import misalignment_rotation
from robot.integration.simulation import RECORD_OUTPUT, SolverOptions, integrate
from robot.analysis.studies.speed import reference_state_derivative

from conftest import CLOSURE_SCENES, assert_passes_as_plain_python

DATA = Path(__file__).resolve().parent / "data"
LWA = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED


@pytest.fixture(scope="module")
def misaligned():
    return build_run("compound_misaligned")


def _random_states(run, rng, n):
    dynamics = run.dynamics
    model = dynamics.mechanism.model
    nq, nv = dynamics.nq, dynamics.nv
    base = np.concatenate([run.y0, [0.0, 0.0]])  # work accumulators start at zero
    for _ in range(n):
        y = base.copy()
        y[:nq] = pin.integrate(model, y[:nq], 10 ** rng.uniform(-7, -3.5) * rng.standard_normal(nv))
        y[nq : nq + nv] += 0.05 * rng.standard_normal(nv)
        yield float(rng.uniform(0.0, 2.0)), y, 10 ** rng.uniform(-3, 0, dynamics.n_candidates)


def _kernel_matches_reference(constraints, q_states, rng):
    model = constraints.mechanism.model
    data, reference = model.createData(), model.createData()
    kernel = C.ConstraintKernel(constraints, data)
    n_drive = constraints.mechanism.n_actuators if constraints.driven else 0
    for q in q_states:
        v = rng.standard_normal(model.nv)
        s, sd, sdd = (rng.standard_normal(n_drive) for _ in range(3)) if n_drive else (None, None, None)
        for d in (data, reference):
            pin.computeAllTerms(model, d, q, v)
            pin.updateFramePlacements(model, d)
        phi, gam = kernel.update(q, s, sdd)
        np.testing.assert_allclose(phi, C.residual(constraints, reference, q, s), rtol=0, atol=1e-14)
        np.testing.assert_allclose(kernel.phi_q, C.jacobian(constraints, model, reference), rtol=0, atol=1e-13)
        np.testing.assert_allclose(gam, C.gamma(constraints, model, reference, sdd), rtol=1e-12, atol=1e-12)
        np.testing.assert_allclose(kernel.residual(q, s), phi, rtol=0, atol=0)
        two_alpha, beta2 = 7.0, 30.0
        expected = two_alpha * (kernel.phi_q @ v - C.velocity_rhs(constraints, sd)) + beta2 * phi - gam
        np.testing.assert_allclose(kernel.stabilised_drift(q, v, s, sd, sdd, two_alpha, beta2), expected, rtol=1e-12, atol=1e-11)


def test_constraint_kernel_spherical_closures_equal_reference(misaligned):
    rng = np.random.default_rng(0)
    model = misaligned.mechanism.model
    states = [pin.integrate(model, misaligned.y0[: model.nq], 0.05 * rng.standard_normal(model.nv)) for _ in range(5)]
    _kernel_matches_reference(misaligned.dynamics.constraints, states, rng)


def test_constraint_kernel_mixed_rows_equal_reference(misaligned):
    """Centring rows: a spherical and a revolute site (with a rotation offset) after the closures."""
    mechanism = misaligned.mechanism
    constraints = C.constraint_set(mechanism, driven=True, centre_clearance=True, misalignment={"R1": misalignment_rotation(-0.5)})
    assert any(r.closure.kind == "revolute" for r in constraints.closures)
    rng = np.random.default_rng(1)
    states = [pin.integrate(mechanism.model, misaligned.y0[: mechanism.model.nq], 0.05 * rng.standard_normal(mechanism.model.nv)) for _ in range(5)]
    _kernel_matches_reference(constraints, states, rng)


def test_constraint_kernel_revolute_closure_equal_reference():
    mechanism = build_mechanism(DATA / "slider_crank.urdf")
    constraints = C.constraint_set(mechanism, driven=True)
    rng = np.random.default_rng(2)
    states = [pin.randomConfiguration(mechanism.model, -np.ones(mechanism.model.nq), np.ones(mechanism.model.nq)) for _ in range(5)]
    _kernel_matches_reference(constraints, states, rng)


RHS_SCENES = ["compound_misaligned", *CLOSURE_SCENES]


@pytest.mark.parametrize("laws", ["compiled", "python"])
@pytest.mark.parametrize("scene", RHS_SCENES)
def test_state_derivative_equals_reference_in_and_out_of_contact(scene_runs, with_python_laws, laws, scene):
    """Three formulations of one right-hand side agree: the compiled path (with the laws' compiled
    kernels or, ``python``, through their Python API), the Python path (constraint kernel views) and
    the reference composition (``robot.model.constraints``' rows; with redundant closure rows the
    dense KKT system by least squares). Spherical, revolute and mixed closures, ideal and with
    clearance joints; in and out of contact."""
    run = scene_runs(scene)
    dynamics = run.dynamics
    evaluated = dynamics if laws == "compiled" else with_python_laws(dynamics)
    workspace, python = D.make_workspace(evaluated), D.make_workspace(evaluated)
    assert workspace.compiled is not None
    python.compiled = None
    assert all((site.law_kernel is None) == (laws == "python") for site in workspace.compiled.sites)
    data = dynamics.mechanism.model.createData()
    rng = np.random.default_rng(3)
    touched = 0
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RedundantConstraintWarning)
        for t, y, onset in _random_states(run, rng, 80):
            try:
                got = D.state_derivative(evaluated, workspace, t, y, onset)
            except ContactError:
                with pytest.raises(ContactError):
                    reference_state_derivative(dynamics, data, t, y, onset)
                continue
            expected = reference_state_derivative(dynamics, data, t, y, onset, minimum_norm=not workspace.rows.full)
            in_contact = expected[dynamics.nq + dynamics.nv + 1] != 0.0  # contact power
            touched += bool(in_contact)
            # in contact, rounding: a penetration (~1e-6 m) is a difference of positions (~0.1 m), so one
            # ulp of q moves the contact force, and f, by up to ~6e-12 of its largest entry
            atol = (5e-11 if in_contact else 1e-12) * max(1.0, np.max(np.abs(expected)))
            np.testing.assert_allclose(got, expected, rtol=1e-12, atol=atol)
            np.testing.assert_allclose(D.state_derivative(evaluated, python, t, y, onset), got, rtol=1e-12, atol=atol)
            # the rows themselves, redundant ones included: Phi_q, Pinocchio's drift, max |Phi|
            np.testing.assert_allclose(workspace.compiled.phi_q, python.kernel.phi_q, rtol=0, atol=1e-14)
            q, v = D.normalise_quaternions(dynamics.mechanism, y[: dynamics.nq]), y[dynamics.nq : dynamics.nq + dynamics.nv]
            gains = dynamics.baumgarte
            drift = python.kernel.stabilised_drift(q, v, *python.drive(t), 2.0 * gains.alpha, gains.beta**2)
            np.testing.assert_allclose(workspace.compiled.drift, drift, rtol=1e-12, atol=1e-12 * np.max(np.abs(drift)))
            if laws == "compiled":
                probe = D.contact_probe(evaluated, workspace, t, q, v, onset)
                assert probe.residual == pytest.approx(np.max(np.abs(python.kernel.residual(q, python.drive(t)[0]))), rel=1e-12, abs=1e-16)
    if dynamics.contacts:
        assert touched >= 10  # the sample has states in contact (contact power non-zero)
    # the planar loops closed by a revolute closure have 3 redundant rows (out of plane, axis rows)
    assert workspace.rows.full == (scene not in ("slider_crank", "four_bar", "mixed"))


def test_compiled_right_hand_side_covers_every_closure_type(scene_runs):
    """Every shipped scene, and mechanisms with revolute and mixed closures, run the compiled path."""
    assert set(D.COMPILED_CLOSURE_KINDS) == set(CLOSURE_TYPES)
    shipped = ("ideal", "spherical", "revolute", "compound", "compound_misaligned", "four_bar_revolute", "slider_crank_revolute")
    for name in (*shipped, *CLOSURE_SCENES):
        dynamics = scene_runs(name).dynamics
        workspace = D.make_workspace(dynamics)
        assert workspace.compiled is not None, name
        assert all(site.law_kernel is not None for site in workspace.compiled.sites), name  # laws compiled too
    kinds = [rows.closure.kind for rows in scene_runs("mixed").dynamics.constraints.closures]
    assert kinds == ["spherical", "revolute", "spherical"]


def test_placement_buffer_follows_pinocchio_data(misaligned):
    from robot.dynamics.rhs_kernels import placement_buffer

    model = misaligned.mechanism.model
    data = model.createData()
    view = placement_buffer(data.oMf)
    rng = np.random.default_rng(14)
    for _ in range(3):
        q = pin.integrate(model, misaligned.y0[: model.nq], 0.2 * rng.standard_normal(model.nv))
        pin.framesForwardKinematics(model, data, q)
        for k in range(model.nframes):
            np.testing.assert_array_equal(view[k, :9].reshape(3, 3).T, data.oMf[k].rotation)
            np.testing.assert_array_equal(view[k, 9:], data.oMf[k].translation)


def test_packed_slots_are_the_compiled_terms_arrays(misaligned):
    """Each slot of the packed buffers, read as the fused kernels read it, is the CompiledTerms array
    of that name: the same values in the same memory (what one writes the other sees)."""
    from robot.dynamics import rhs_kernels as K

    dynamics = misaligned.dynamics
    compiled = D.make_workspace(dynamics).compiled
    slots = {
        K.FRAMES_A: compiled.frames_a, K.FRAMES_B: compiled.frames_b, K.CLOSURE_ROWS: compiled.closure_rows,
        K.ACTUATOR_Q: compiled.actuator_q, K.ACTUATOR_V: compiled.actuator_v, K.CLOSURE_MASKS: compiled.closure_masks,
        K.SITE_TABLE: compiled.site_table, K.SITE_MASKS: compiled.site_masks, K.PROBE_GATHER: compiled.probe_gather,
        K.DRIFT: compiled.drift, K.TAU: compiled.tau, K.GAINS: compiled.gains, K.DRIVE: compiled.drive_values,
        K.LAW_PARAMETERS: compiled.site_parameters, K.LAW_OUTPUTS: compiled.site_outputs_buffer, K.SITE_TWISTS: compiled.site_twists,
    }  # fmt: skip
    assert sorted(slots) == list(range(K.N_SLOTS))
    for slot, array in slots.items():
        assert array.size > 0, slot  # the scene has closures, actuators and compiled laws
        buffer = compiled.indices if slot < K.DRIFT else compiled.work
        read = {1: K._flat, 2: K._matrix, 3: K._cube}[array.ndim](buffer, compiled.indices, slot)
        np.testing.assert_array_equal(read, array)
        assert np.shares_memory(read, array), slot
    gains = dynamics.baumgarte
    np.testing.assert_array_equal(compiled.gains, [2.0 * gains.alpha, gains.beta**2])
    assert compiled.drive_values.shape == (3 * 5,) and compiled.probe_gather.shape == (dynamics.n_candidates, 3)


def test_pack_keeps_empty_slots_in_place():
    """Empty slots (no closure, no site: shapes (0,), (0, 3), (0, 2, nv)) read back empty with their shapes,
    and the slots after them keep their values; a missing slot is refused."""
    from robot.dynamics import rhs_kernels as K

    nv = 7
    rng = np.random.default_rng(8)
    empty = {
        K.FRAMES_A: np.zeros(0), K.PROBE_GATHER: np.zeros((0, 3)), K.SITE_MASKS: np.zeros((0, 2, nv)), K.SITE_TWISTS: np.zeros((0, 2, 6))
    }  # fmt: skip
    arrays = {
        slot: empty.get(slot, rng.integers(-9, 9, size=(slot % 3 + 1, 2)) if slot < K.DRIFT else rng.standard_normal(slot))
        for slot in range(K.N_SLOTS)
    }
    indices, work, views = K.pack(arrays)
    assert sorted(views) == list(range(K.N_SLOTS))
    for slot, array in arrays.items():
        buffer = indices if slot < K.DRIFT else work
        assert views[slot].dtype == (np.int64 if slot < K.DRIFT else np.float64)
        assert views[slot].shape == np.shape(array)
        read = {1: K._flat, 2: K._matrix, 3: K._cube}[np.ndim(array)](buffer, indices, slot)
        assert read.shape == np.shape(array), slot
        np.testing.assert_array_equal(read, array)
    assert indices.size == 4 * K.N_SLOTS + sum(np.size(arrays[s]) for s in range(K.DRIFT))
    assert work.size == sum(np.size(arrays[s]) for s in range(K.DRIFT, K.N_SLOTS))
    with pytest.raises(ValueError, match=rf"missing slots \[{K.GAINS}\]"):
        K.pack({slot: array for slot, array in arrays.items() if slot != K.GAINS})


def test_compiled_sites_report_a_failing_law_with_its_message(misaligned):
    """A law that refuses its input inside the fused compiled call: its own ContactError, wrapped with the site's name."""
    dynamics = misaligned.dynamics
    workspace = D.make_workspace(dynamics)
    assert workspace.compiled.sites_fused
    y = np.concatenate([misaligned.y0, [0.0, 0.0]])
    y[dynamics.nq + dynamics.nv - 1] = np.nan  # a non-finite velocity reaches the contact laws
    with pytest.raises(ContactError, match="non-finite"):
        D.state_derivative(dynamics, workspace, 0.0, y, np.full(dynamics.n_candidates, 0.1))


@pytest.mark.parametrize("call", ["state_derivative", "contact_probe"])
def test_a_failing_law_names_its_site_and_time(misaligned, call):
    """NaN onset rates on the second clearance joint (R1): the error names R1, t and the law's own reason."""
    dynamics = misaligned.dynamics
    workspace = D.make_workspace(dynamics)
    assert workspace.compiled.sites_fused and [c.site.name for c in dynamics.contacts] == ["S1", "R1"]
    y = np.concatenate([misaligned.y0, [0.0, 0.0]])
    onset = np.full(dynamics.n_candidates, 0.1)
    onset[dynamics.contacts[1].candidates] = np.nan
    q, v = y[: dynamics.nq], y[dynamics.nq : dynamics.nq + dynamics.nv]
    with pytest.raises(ContactError, match=r"^contact law of 'R1' failed at t=0\.25: non-finite input onset_rates=\[nan") as caught:
        if call == "state_derivative":
            D.state_derivative(dynamics, workspace, 0.25, y, onset)
        else:
            D.contact_probe(dynamics, workspace, 0.25, q, v, onset)
    assert isinstance(caught.value.__cause__, ContactError)  # the law's own error, chained


def test_a_failing_laws_class_key_and_value_are_kept(misaligned, monkeypatch):
    """The site-naming error keeps what the law said: its class, ``key`` and ``value``; a law that does not say, the status."""
    from clearance_contact.errors import ContactParameterError

    dynamics = misaligned.dynamics
    workspace = D.make_workspace(dynamics)
    twists, onset = np.zeros((2, 6)), np.zeros(dynamics.contacts[1].law.n_candidates)

    class Refusing:
        def evaluate(self, *args):
            raise ContactParameterError("youngs_modulus=-1.0 must be positive", key="youngs_modulus", value=-1.0)

    monkeypatch.setattr(workspace.sites[1], "law", Refusing())
    with pytest.raises(ContactParameterError, match=r"^contact law of 'R1' failed at t=0\.5: youngs_modulus=-1\.0") as caught:
        D._raise_contact_error(dynamics, workspace, 1, twists, onset, 0.5, 3)
    assert (caught.value.key, caught.value.value) == ("youngs_modulus", -1.0) and isinstance(caught.value, ValueError)

    class Silent:
        def evaluate(self, *args):
            return None

    monkeypatch.setattr(workspace.sites[1], "law", Silent())
    with pytest.raises(ContactError, match=r"^contact law of 'R1' failed \(status 3\) at t=0\.5$"):
        D._raise_contact_error(dynamics, workspace, 1, twists, onset, 0.5, 3)


@pytest.mark.parametrize("scene", ["compound_misaligned", "mixed", "four_bar_rocker_clearance"])
@pytest.mark.parametrize("change", [-1, 1])
def test_a_drive_with_the_wrong_number_of_values_is_refused(scene_runs, scene, change):
    """One value too few or too many for the motion actuators (5 on the 4-UPS/RPS' platform-pose drive, 2 joint
    drives on the mixed-closure linkage, 1 on the four-bar): every dynamics model refuses the drive, made by
    ``make_dynamics_model`` or ``dataclasses.replace`` (the compiled calls would read past it); the right one passes."""
    run = scene_runs(scene)
    n_actuators = len(run.mechanism.actuator_q_index)

    class Resized:
        def drive(self, t):
            return tuple(np.resize(np.atleast_1d(a), np.size(a) + change) for a in run.dynamics.drive.drive(t))

    size = n_actuators + change
    with pytest.raises(DriveError, match=rf"returns \[{size}, {size}, {size}\] values .* has {n_actuators} motion-driven") as caught:
        dataclasses.replace(run.dynamics, drive=Resized())
    assert isinstance(caught.value, Error) and caught.value.key == "drive"
    dynamics = run.dynamics
    laws = {contact.site.name: contact.law for contact in dynamics.contacts}
    frame = dynamics.mechanism.model.frames[dynamics.end_effector_frame].name
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RedundantConstraintWarning)
        with pytest.raises(DriveError, match="motion-driven"):  # already when the model is made (the run's set-up)
            D.make_dynamics_model(dynamics.mechanism, laws, Resized(), dynamics.baumgarte, frame)
        D.make_dynamics_model(dynamics.mechanism, laws, run.dynamics.drive, dynamics.baumgarte, frame)  # the right drive passes


def test_compiled_right_hand_side_runs_as_plain_python():
    """``CLEARANCE_CONTACT_JIT=0``: the kernels of ``robot.dynamics.rhs_kernels`` run as Python, same answers
    (the right-hand side, the probe with and without its residual, an exact drive segment)."""
    selection = "state_derivative_equals_reference or placement_buffer or probe_without_residual or exact_drive_segment"
    assert_passes_as_plain_python(__file__, selection, 2 * len(RHS_SCENES) + 3)


def test_probe_without_residual_gives_the_same_contacts(misaligned):
    """``contact_probe(residual=False)``: the same penetrations, rates and normal forces bit for bit, residual NaN."""
    dynamics = misaligned.dynamics
    workspace = D.make_workspace(dynamics)
    assert workspace.compiled.sites_fused
    nq, nv = dynamics.nq, dynamics.nv
    touched = 0
    for t, y, onset in _random_states(misaligned, np.random.default_rng(21), 30):
        q, v = D.normalise_quaternions(dynamics.mechanism, y[:nq]), y[nq : nq + nv]
        try:
            full = D.contact_probe(dynamics, workspace, t, q, v, onset)
        except ContactError:
            continue
        quick = D.contact_probe(dynamics, workspace, t, q, v, onset, residual=False)
        assert math.isnan(quick.residual) and math.isfinite(full.residual) and full.residual > 0.0
        for name in ("penetration", "penetration_rate", "normal_force"):
            np.testing.assert_array_equal(getattr(quick, name), getattr(full, name), err_msg=name)
        touched += bool(np.any(full.normal_force > 0.0))
    assert touched >= 3  # states in contact, not only zero forces


def test_exact_drive_segment_reaches_the_compiled_calls_bit_for_bit(misaligned):
    """Where the drive table cannot fit the drive (a kink), the compiled right-hand side and probe
    read the drive's own values, bit for bit, and the probe's residual is computed from them."""
    from robot.dynamics import rhs_kernels as K

    class Kinked:
        """The scene's drive plus a kink of 1 mm/s slope change at t = 0.7 s on every actuator."""

        def drive(self, t):
            s, sd, sdd = misaligned.dynamics.drive.drive(t)
            return s + 1e-3 * abs(t - 0.7), sd + 1e-3 * math.copysign(1.0, t - 0.7), sdd.copy()

    dynamics = dataclasses.replace(misaligned.dynamics, drive=Kinked())
    workspace = D.make_workspace(dynamics)
    compiled, table = workspace.compiled, workspace.drive
    nq, nv = dynamics.nq, dynamics.nv
    y = np.concatenate([misaligned.y0, [0.0, 0.0]])
    q, v = D.normalise_quaternions(dynamics.mechanism, y[:nq]), y[nq : nq + nv]
    onset = np.full(dynamics.n_candidates, 0.1)
    for t in (0.7 - 0.01, 0.7 + 1e-3, 0.2):  # two times in the kinked segment, one in a smooth one
        exact = np.concatenate(dynamics.drive.drive(t))
        compiled.drive_values[:] = np.nan
        D.state_derivative(dynamics, workspace, t, y, onset)
        from_rhs = compiled.drive_values.copy()
        compiled.drive_values[:] = np.nan
        probe = D.contact_probe(dynamics, workspace, t, q, v, onset)
        np.testing.assert_array_equal(compiled.drive_values, from_rhs)
        worst = K.largest_residual(compiled.placements, compiled.frames_a, compiled.frames_b, compiled.closure_rows, q, from_rhs, compiled.actuator_q)
        assert probe.residual == worst
        if t == 0.2:  # the table's polynomial: within its tolerance, not the drive's rounding
            np.testing.assert_allclose(from_rhs, exact, rtol=0, atol=1e-12 * np.max(np.abs(exact)))
        else:
            np.testing.assert_array_equal(from_rhs, exact)
    assert table.exact_segments == 1 and table.segments[math.floor(0.7 / table.width)][1] is None


def test_state_derivative_contact_hint_does_not_change_the_result(misaligned):
    """A site flagged 'touching' from the previous call but now out of contact gets no force."""
    dynamics = misaligned.dynamics
    workspace = D.make_workspace(dynamics)
    y = np.concatenate([misaligned.y0, [0.0, 0.0]])
    onset = np.full(dynamics.n_candidates, 0.1)
    cold = D.state_derivative(dynamics, workspace, 0.0, y, onset)
    for views in workspace.sites:
        views.touching = True
    np.testing.assert_array_equal(D.state_derivative(dynamics, workspace, 0.0, y, onset), cold)


def test_evaluate_and_probe_equal_reference(misaligned):
    dynamics = misaligned.dynamics
    model = dynamics.mechanism.model
    workspace = D.make_workspace(dynamics)
    rng = np.random.default_rng(4)
    nq, nv = dynamics.nq, dynamics.nv
    for t, y, onset in _random_states(misaligned, rng, 20):
        q = D.normalise_quaternions(dynamics.mechanism, y[:nq])
        v = y[nq : nq + nv]
        try:
            evaluation = D.evaluate(dynamics, workspace, t, q, v, onset)
        except ContactError:
            continue
        data = model.createData()
        pin.computeAllTerms(model, data, q, v)
        pin.updateFramePlacements(model, data)
        s, sd, sdd = dynamics.drive.drive(t)
        np.testing.assert_allclose(evaluation.residual, C.residual(dynamics.constraints, data, q, s), atol=1e-14)
        expected_rate = C.jacobian(dynamics.constraints, model, data) @ v - C.velocity_rhs(dynamics.constraints, sd)
        np.testing.assert_allclose(evaluation.residual_rate, expected_rate, atol=1e-12)
        reference = reference_state_derivative(dynamics, model.createData(), t, y, onset)
        np.testing.assert_allclose(evaluation.qdd, reference[nq : nq + nv], rtol=1e-11, atol=1e-8)
        pen, rate, worst, force = D.contact_probe(dynamics, workspace, t, q, v, onset)
        pin.forwardKinematics(model, data, q, v)
        pin.updateFramePlacements(model, data)
        for contact in dynamics.contacts:
            result = contact.law.evaluate(*D.element_states(data, model, contact.site), onset[contact.candidates])
            np.testing.assert_allclose(pen[contact.candidates], result.penetration, atol=1e-18)
            np.testing.assert_allclose(rate[contact.candidates], result.penetration_rate, atol=1e-15)
            np.testing.assert_allclose(force[contact.candidates], result.normal_force, rtol=1e-12, atol=1e-9)
        table_s = D.make_workspace(dynamics).drive(t)[0]
        assert worst == pytest.approx(np.max(np.abs(C.residual(dynamics.constraints, data, q, table_s))), abs=1e-15)


def test_configuration_rate_is_the_quaternion_kinematics(misaligned):
    dynamics = misaligned.dynamics
    workspace = D.make_workspace(dynamics)
    rng = np.random.default_rng(5)
    model = dynamics.mechanism.model
    q = pin.integrate(model, misaligned.y0[: dynamics.nq], 0.3 * rng.standard_normal(dynamics.nv))
    v = rng.standard_normal(dynamics.nv)
    qdot = D.configuration_rate(dynamics, workspace, q, v)
    for j in range(1, model.njoints):  # joints whose configuration is their velocity (not the free-flyers)
        if model.nqs[j] == model.nvs[j]:
            iq, iv, n = model.idx_qs[j], model.idx_vs[j], model.nqs[j]
            np.testing.assert_array_equal(qdot[iq : iq + n], v[iv : iv + n])
    for iq, iv in dynamics.mechanism.free_flyers:
        x, y, z, w = q[iq + 3 : iq + 7]
        rotation = pin.Quaternion(w, x, y, z).toRotationMatrix()
        omega = v[iv + 3 : iv + 6]
        np.testing.assert_allclose(qdot[iq : iq + 3], rotation @ v[iv : iv + 3], atol=1e-14)
        np.testing.assert_allclose(qdot[iq + 3 : iq + 6], 0.5 * (w * omega + np.cross([x, y, z], omega)), atol=1e-14)
        assert qdot[iq + 6] == pytest.approx(-0.5 * np.dot([x, y, z], omega), abs=1e-14)


def test_drive_table_equals_the_exact_drive(misaligned):
    drive = misaligned.dynamics.drive
    table = D.DriveTable(drive)
    for t in np.linspace(-0.01, 2.2, 301):
        for got, exact in zip(table(t), drive.drive(t)):
            np.testing.assert_allclose(got, exact, rtol=0, atol=1e-12 * max(1.0, np.max(np.abs(exact))))
    assert table.exact_segments == 0
    assert D.drive_table(drive) is D.drive_table(drive)  # shared by the workspaces of one drive


def test_drive_table_falls_back_where_it_cannot_fit():
    class Kink:
        def drive(self, t):
            value = np.array([abs(t - 0.1)])
            return value, np.sign(value), np.zeros(1)

    kink = Kink()
    table = D.DriveTable(kink)
    assert table(0.1 + 1e-3)[0][0] == pytest.approx(1e-3, abs=1e-15)  # exact in the segment of the kink
    assert table.exact_segments == 1
    assert table(0.5)[0][0] == pytest.approx(0.4, abs=1e-13)  # smooth elsewhere: interpolated
    assert table.exact_segments == 1


def test_output_grid_records_the_dense_output(misaligned):
    options = SolverOptions("RK45", rtol=1e-7, atol=1e-9, output_step=1e-3)
    trajectory = integrate(misaligned.dynamics, misaligned.y0, (0.0, 0.01), options)
    assert trajectory.success
    grid = trajectory.t[trajectory.kind == RECORD_OUTPUT]
    np.testing.assert_allclose(grid, np.arange(1, 11) * 1e-3, atol=1e-15)


# ------------------------------------------------------------------ integrators on small problems


def _oscillator(omega=2.0):
    """q'' = -omega^2 q as y = [q, v, energy-work] with the second-order structure."""

    def fun(t, y):
        return np.array([y[1], -(omega**2) * y[0], 0.0])

    structure = I.SecondOrderStructure(1, 1, lambda q, dq: q + dq)
    return fun, structure


def _final(solver):
    while solver.status == "running":
        solver.step()
    return solver


@pytest.mark.parametrize("method", ["GenAlpha", "Newmark"])
def test_generalized_alpha_is_second_order(method):
    fun, structure = _oscillator()
    errors = []
    for h in (0.02, 0.01, 0.005):
        solver = _final(I.make_solver(method, fun, 0.0, np.array([1.0, 0.0, 0.0]), 2.0, 1e-10, 1e-12, np.inf, h, structure))
        assert solver.status == "finished"
        errors.append(abs(solver.y[0] - math.cos(4.0)))
    orders = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
    assert np.all(orders > 1.8), orders


def test_newmark_conserves_the_oscillator_energy_and_gen_alpha_damps_it():
    fun, structure = _oscillator(omega=50.0)  # h omega = 5: the high-frequency regime
    energies = {}
    for method in ("Newmark", "GenAlpha"):
        solver = _final(I.make_solver(method, fun, 0.0, np.array([1.0, 0.0, 0.0]), 2.0, 1e-12, 1e-14, np.inf, 0.1, structure))
        energies[method] = 0.5 * solver.y[1] ** 2 + 0.5 * 50.0**2 * solver.y[0] ** 2
    initial = 0.5 * 50.0**2
    assert energies["Newmark"] == pytest.approx(initial, rel=1e-8)
    assert energies["GenAlpha"] < 0.5 * initial  # rho_inf = 0.8 damps the unresolved frequency


def test_generalized_alpha_updates_quaternions_on_the_group():
    """A free body spinning at constant rate: the quaternion stays unit and matches the exact rotation."""
    model = pin.Model()
    model.addJoint(0, pin.JointModelFreeFlyer(), pin.SE3.Identity(), "free")
    omega = np.array([0.3, -1.2, 2.0])

    def fun(t, y):
        out = np.zeros(7 + 6)
        out[:7] = pin.tangentMapProduct(model, y[:7], y[7:13].reshape(-1, 1)).ravel()
        return out  # no acceleration: constant body twist

    structure = I.SecondOrderStructure(7, 6, lambda q, dq: pin.integrate(model, q, dq))
    y0 = np.concatenate([pin.neutral(model), [0.1, 0.0, 0.0], omega])
    solver = _final(I.make_solver("GenAlpha", fun, 0.0, y0, 1.0, 1e-10, 1e-12, np.inf, 0.01, structure))
    q = solver.y[:7]
    assert np.linalg.norm(q[3:7]) == pytest.approx(1.0, abs=1e-14)
    expected = pin.integrate(model, pin.neutral(model), np.concatenate([[0.1, 0.0, 0.0], omega]))
    np.testing.assert_allclose(q, expected, atol=1e-10)


def test_generalized_alpha_matches_rk45_on_the_ideal_mechanism():
    run = build_run("ideal")
    reference = integrate(run.dynamics, run.y0, (0.0, 0.2), SolverOptions("RK45", rtol=1e-10, atol=1e-12))
    gaps = []
    for h in (2e-3, 1e-3):
        trajectory = integrate(run.dynamics, run.y0, (0.0, 0.2), SolverOptions("GenAlpha", rtol=1e-10, atol=1e-12, first_step=h))
        assert trajectory.success, trajectory.message
        gaps.append(np.max(np.abs(trajectory.y[-1, : run.dynamics.nq] - reference.y[-1, : run.dynamics.nq])))
    assert gaps[1] < gaps[0] / 3.0  # second order
    assert gaps[1] < 1e-5


def test_fixed_step_methods_need_a_step():
    fun, structure = _oscillator()
    for method in ("RK4", "GenAlpha"):
        with pytest.raises(ValueError, match="first_step"):
            I.make_solver(method, fun, 0.0, np.array([1.0, 0.0, 0.0]), 1.0, 1e-6, 1e-9, np.inf, None, structure)
    with pytest.raises(ValueError, match="not on offer"):
        I.make_solver("Euler", fun, 0.0, np.array([1.0, 0.0, 0.0]), 1.0, 1e-6, 1e-9, np.inf, None)


cvode = pytest.mark.skipif("CVODE_BDF" not in I.METHODS, reason="scikit-sundae is not installed")


@cvode
@pytest.mark.parametrize("method", ["CVODE_BDF", "CVODE_Adams"])
def test_cvode_steps_interpolates_and_continues(method):
    fun, _ = _oscillator(omega=1.0)
    solver = I.make_solver(method, fun, 0.0, np.array([1.0, 0.0, 0.0]), 3.0, 1e-10, 1e-12, np.inf, None)
    times = []
    while solver.status == "running":
        solver.step()
        times.append(solver.t)
        if len(times) > 5 and solver.status == "running":
            dense = solver.dense_output()
            middle = 0.5 * (solver.t_old + solver.t)
            assert dense(middle)[0] == pytest.approx(math.cos(middle), abs=1e-7)
    assert np.all(np.diff(times) > 0)  # every step advances, also after an interpolation
    assert solver.t == 3.0
    assert solver.y[0] == pytest.approx(math.cos(3.0), abs=1e-7)


@cvode
def test_cvode_runs_a_scene_with_contact_events(misaligned):
    trajectory = integrate(misaligned.dynamics, misaligned.y0, (0.0, 0.01), SolverOptions("CVODE_BDF", rtol=1e-7, atol=1e-9))
    assert trajectory.success, trajectory.message
    assert trajectory.n_events > 0
    assert trajectory.n_rejected == -1  # CVODE does not tell
