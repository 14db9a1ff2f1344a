"""Peak contact forces are located (``RECORD_FORCE_PEAK``), not sampled at the penetration maximum.

With Lankarani-Nikravesh damping the normal force peaks while the penetration
still grows, so the force at the penetration maximum (``RECORD_PEAK``)
underestimates the impact's peak force. Checked on the first impact of the
``spherical`` scene (onset ~9.8 ms, penetration maximum ~10.04 ms).
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from scipy.integrate import RK45, solve_ivp

from robot.dynamics import equations as D
from robot.io.results import make_result
from robot.run import build_run
from robot.integration.simulation import SolverOptions, RECORD_FORCE_PEAK, RECORD_ONSET, RECORD_PEAK, RECORD_START, RECORD_STEP, integrate

T_END = 0.0105  # past the first impact's penetration maximum
# an explicit Runge-Kutta method (its earlier steps are replayed exactly): the tests check the
# located maxima against the run's own trajectory, whatever the scene's default integrator is
SOLVER = SolverOptions("RK45", rtol=1e-7, atol=1e-9, max_step=1e-3)


@pytest.fixture(scope="module")
def spherical():
    return build_run("spherical")


def _first(trajectory, kind: str):
    return next(e for e in trajectory.events if e[2] == kind and e[1] == 0)


def _force(dynamics, workspace, y, onset) -> float:
    """S1's normal force at state y (the full equations of motion, independent of the simulation's helper)."""
    nq, nv = dynamics.nq, dynamics.nv
    q = D.normalise_quaternions(dynamics.mechanism, y[:nq])
    return float(D.evaluate(dynamics, workspace, 0.0, q, y[nq : nq + nv], onset).contacts[0].normal_force[0])


def test_force_peak_is_the_maximum_of_the_dense_output_and_precedes_the_penetration_maximum(spherical):
    run = spherical
    trajectory = integrate(run.dynamics, run.y0, (0.0, T_END), SOLVER)
    assert trajectory.success, trajectory.message
    onset, peak, force_peak = _first(trajectory, "onset"), _first(trajectory, "peak"), _first(trajectory, "force_peak")
    assert onset[0] < force_peak[0] < peak[0]  # damping: the force peaks while the penetration still grows
    # the result file holds it, and it is the largest force of the run (the max readers take)
    result = make_result("spherical", run.dynamics, trajectory, {})
    force = result["S1_normal_force"][:, 0]
    kind = result["record_kind"]
    assert np.count_nonzero(kind == RECORD_FORCE_PEAK) == 1
    assert force[kind == RECORD_FORCE_PEAK][0] == pytest.approx(force_peak[3], rel=1e-12)
    assert force.max() == pytest.approx(force_peak[3], rel=1e-12)
    at_penetration_maximum = force[(kind == RECORD_PEAK)][0]
    assert force_peak[3] > at_penetration_maximum * (1 + 1e-3)
    assert list(result["event_kind"]) == [RECORD_ONSET, RECORD_PEAK, RECORD_FORCE_PEAK]
    # 2000 points of the run's own dense output over the impact: each RK45 step replayed from its
    # recorded start state with its own size (an explicit RK step depends on nothing else)
    workspace = D.make_workspace(run.dynamics)
    boundary = np.flatnonzero(np.isin(trajectory.kind, [RECORD_STEP, RECORD_ONSET, RECORD_START]))
    order = boundary[np.argsort(trajectory.t[boundary], kind="stable")]
    options = SOLVER
    sampled = []
    for i_a, i_b in zip(order[:-1], order[1:]):
        t_a, t_b = trajectory.t[i_a], trajectory.t[i_b]
        if t_b <= onset[0] or t_a >= peak[0]:
            continue
        rates = trajectory.onset_rates[i_a]
        solver = RK45(
            lambda t, y: D.state_derivative(run.dynamics, workspace, t, y, rates),
            t_a, trajectory.y[i_a], t_b, rtol=options.rtol, atol=options.atol, first_step=t_b - t_a,
        )
        solver.step()
        assert solver.t == pytest.approx(t_b, abs=1e-15)
        dense = solver.dense_output()
        for t in np.linspace(max(t_a, onset[0]), min(t_b, peak[0]), 2000 // 8):
            sampled.append(_force(run.dynamics, workspace, dense(t), rates))
    assert len(sampled) >= 1500
    assert force_peak[3] >= max(sampled) * (1 - 1e-9)


def test_force_peak_agrees_with_a_tight_independent_run(spherical):
    """A tight run's located peak (DOP853, rtol 1e-10) against solve_ivp (rtol 1e-12) sampled finely.

    The run itself must be tight for this: at the scene's rtol 1e-7 the first
    impact's onset rate, hence its peak force, is only good to ~1e-4 (two such
    runs with another end time differ by that much).
    """
    run = spherical
    options = dataclasses.replace(SOLVER, method="DOP853", rtol=1e-10, atol=1e-12)
    trajectory = integrate(run.dynamics, run.y0, (0.0, T_END), options)
    assert trajectory.success, trajectory.message
    located, onset, peak = _first(trajectory, "force_peak"), _first(trajectory, "onset"), _first(trajectory, "peak")
    # independent: from the last state before the onset, the onset rate of the first impact set
    before = int(np.flatnonzero(trajectory.t < onset[0] - 1e-6)[-1])
    workspace = D.make_workspace(run.dynamics)
    rates = trajectory.onset_rates[before].copy()
    rates[0] = onset[3]
    solution = solve_ivp(
        lambda t, y: D.state_derivative(run.dynamics, workspace, t, y, rates),
        (trajectory.t[before], T_END), trajectory.y[before], method="DOP853", rtol=1e-12, atol=1e-14, dense_output=True,
    )
    assert solution.success
    grid = np.linspace(onset[0] + 1e-9, peak[0], 2001)
    forces = np.array([_force(run.dynamics, workspace, solution.sol(t), rates) for t in grid])
    i = int(np.argmax(forces))
    assert 0 < i < len(grid) - 1
    fine = np.linspace(grid[i - 1], grid[i + 1], 401)
    fine_forces = [_force(run.dynamics, workspace, solution.sol(t), rates) for t in fine]
    reference = max(fine_forces)
    assert located[3] == pytest.approx(reference, rel=1e-6)
    # the time of a flat maximum: within a tenth of the coarse grid's spacing of the fine grid's argmax
    assert located[0] == pytest.approx(fine[int(np.argmax(fine_forces))], abs=0.1 * (grid[1] - grid[0]))
    sampled = _force(run.dynamics, workspace, solution.sol(peak[0]), rates)
    assert abs(sampled / reference - 1) > 1e-3  # what the penetration maximum alone gave: 0.8 % low


def test_undamped_force_peaks_at_the_penetration_maximum(tmp_path):
    path = tmp_path / "elastic.toml"
    path.write_text(
        'extends = "spherical"\nname = "elastic"\nduration = 0.0105\n'
        '[[clearance]]\njoint = "S1"\ntype = "spherical"\nmaterial = "steel"\n'
        "ball_radius = 0.015\nclearance = 1.0e-4\nrestitution = 1.0\n",
        encoding="utf-8",
    )
    run = build_run(str(path))
    trajectory = integrate(run.dynamics, run.y0, (0.0, T_END), SOLVER)
    assert trajectory.success, trajectory.message
    peak, force_peak = _first(trajectory, "peak"), _first(trajectory, "force_peak")
    # the same instant, to the search's tolerance: a flat maximum's time is found to ~1e-4 of the
    # searched step (~1e-5 s here), its value to ~1e-8
    assert abs(force_peak[0] - peak[0]) < 1e-8
    i = np.flatnonzero((trajectory.t == peak[0]) & (trajectory.kind == RECORD_PEAK))[0]
    at_penetration_maximum = _force(run.dynamics, D.make_workspace(run.dynamics), trajectory.y[i], trajectory.onset_rates[i])
    assert force_peak[3] == pytest.approx(at_penetration_maximum, rel=1e-8)
