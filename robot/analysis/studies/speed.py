"""Speed of the right-hand side, and of a whole run against the clock.

``rhs_us``: microseconds per call of :func:`robot.dynamics.equations.state_derivative`
(the integrator's right-hand side) at fixed states of the scene: out of contact,
and in contact (states taken from a short run: the revolute clearance joint in
contact, and both joints in contact), median over repeats of ``timeit``; the
same for :func:`reference_state_derivative`, the straightforward composition of
the reference functions (exact drive, ``robot.model.constraints.residual/jacobian/
gamma``, every contact law evaluated), i.e. the right-hand side as it was before
the fast path, measured in the same process so the ratio is meaningful on a
noisy machine.

``realtime``: wall time of a whole simulation over simulated time (1 means
real time), with the mean cost per right-hand-side call measured inside that run
(the real mix of contact states) and the share of the per-step checks.
"""

from __future__ import annotations

import statistics
import time
import timeit
import warnings

import numpy as np
import pinocchio as pin

from robot.model import constraints as C
from robot.model.pinocchio_arrays import frame_jacobian
from robot.dynamics import equations as D
from robot.run import Run
from robot.integration.simulation import SolverOptions, initial_onset_rates, integrate



def reference_state_derivative(
    dynamics: D.DynamicsModel, data: pin.Data, t: float, y: np.ndarray, onset: np.ndarray, minimum_norm: bool = False
) -> np.ndarray:
    """dy/dt by the reference functions (no fast path): the oracle of the fast right-hand side.

    ``minimum_norm``: solve the KKT system of paper eq. (24) as one dense least-squares
    problem on every row (:func:`_dense_kkt`) instead of Pinocchio's ``forwardDynamics``,
    for mechanisms with redundant closure rows (exact for a consistent system; independent
    of the row selection of :mod:`robot.model.redundancy`).
    """
    mechanism = dynamics.mechanism
    model = mechanism.model
    nq, nv = dynamics.nq, dynamics.nv
    q = D.normalise_quaternions(mechanism, y[:nq])
    v = y[nq : nq + nv]
    constraints = dynamics.constraints
    s, sd, sdd = dynamics.drive.drive(t)
    pin.computeAllTerms(model, data, q, v)
    pin.updateFramePlacements(model, data)
    phi = C.residual(constraints, data, q, s)
    phi_q = C.jacobian(constraints, model, data)
    phi_dot = phi_q @ v - C.velocity_rhs(constraints, sd)
    gains = dynamics.baumgarte
    rhs = C.gamma(constraints, model, data, sdd) - 2.0 * gains.alpha * phi_dot - gains.beta**2 * phi
    tau = np.zeros(nv)
    for contact in dynamics.contacts:
        site = contact.site
        result = contact.law.evaluate(*D.element_states(data, model, site), onset[contact.candidates])
        if np.any(result.in_contact):
            tau += frame_jacobian(model, data, site.outer_frame).T @ result.wrench_outer
            tau += frame_jacobian(model, data, site.inner_frame).T @ result.wrench_inner
    applied = np.zeros(nv) if dynamics.forces is None else dynamics.forces.bind(model, data).evaluate(t, q, v)
    if minimum_norm:
        qdd, multipliers = _dense_kkt(model, data, q, tau + applied, phi_q, rhs)
    else:
        qdd = pin.forwardDynamics(model, data, tau + applied, phi_q, -rhs).copy()
        multipliers = -data.lambda_c.copy()
    driving_force = -multipliers[constraints.driving_rows]
    actuator = np.zeros(nv) if dynamics.forces is None else sum((_element_force(e, model, data, t, q, v) for e in dynamics.forces.elements if e.actuator), np.zeros(nv))
    out = np.empty(dynamics.state_size)
    out[:nq] = pin.tangentMap(model, q) @ v
    out[nq : nq + nv] = qdd
    out[nq + nv] = driving_force @ v[mechanism.actuator_v_index] + actuator @ v
    out[nq + nv + 1] = tau @ v
    if dynamics.forces is not None:
        out[nq + nv + 2] = (applied - actuator) @ v
    return out


def _dense_kkt(model: pin.Model, data: pin.Data, q: np.ndarray, tau: np.ndarray, phi_q: np.ndarray, rhs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(qdd, lambda) of ``[M Phi_q^T; Phi_q 0] [qdd; lambda] = [tau - h; rhs]`` by least squares.

    Paper eq. (24) with every row, redundant ones included: for a consistent system qdd is
    unique and the multipliers are the minimum-norm ones. Needs ``computeAllTerms`` at (q, v).
    """
    mass = pin.crba(model, data, q)
    mass = np.triu(mass) + np.triu(mass, 1).T
    n, m = model.nv, phi_q.shape[0]
    matrix = np.block([[mass, phi_q.T], [phi_q, np.zeros((m, m))]])
    solution, *_ = np.linalg.lstsq(matrix, np.concatenate([tau - data.nle, rhs]), rcond=None)
    return solution[:n], solution[n:]


def _element_force(element, model: pin.Model, data: pin.Data, t: float, q: np.ndarray, v: np.ndarray) -> np.ndarray:
    """One force element's generalized force on its own (the oracle separates actuator work from element work)."""
    from robot.dynamics.forces.kinematics import PointKinematics

    out = np.zeros(model.nv)
    element.apply(PointKinematics(model, data), t, q, v, out)
    return out


def sample_states(run: Run, t_end: float = 0.02) -> dict:
    """{name: (t, y, onset)}: the initial state, and states of a short run with contacts.

    Per category ("no contact", "some joints in contact", "all joints in contact")
    the state of the run with the deepest total penetration (the first one for
    "no contact"): a state at an onset touches by ~1e-18 m and has no contact
    force to speak of.
    """
    dynamics = run.dynamics
    y0 = np.concatenate([run.y0, np.zeros(dynamics.n_work)])  # work accumulators start at zero
    states = {"initial": (0.0, y0, initial_onset_rates(dynamics))}
    if not dynamics.contacts:
        return states
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        trajectory = integrate(dynamics, y0, (0.0, t_end), SolverOptions("RK45", rtol=1e-8, atol=1e-10, max_step=1e-4))
    workspace = D.make_workspace(dynamics)
    best: dict = {}
    for t, y, onset in zip(trajectory.t, trajectory.y, trajectory.onset_rates):
        q = D.normalise_quaternions(dynamics.mechanism, y[: dynamics.nq])
        pen = D.contact_probe(dynamics, workspace, float(t), q, y[dynamics.nq : dynamics.nq + dynamics.nv], onset).penetration
        touching = tuple(bool(np.any(pen[c.candidates] > 0)) for c in dynamics.contacts)
        key = "all joints in contact" if all(touching) else ("some joints in contact" if any(touching) else "no contact")
        depth = float(np.sum(np.maximum(pen, 0.0)))
        if key not in best or depth > best[key][0]:
            best[key] = (depth, (float(t), np.array(y), np.array(onset)))
    states.update({key: state for key, (_, state) in best.items()})
    return states


def _median_us(call, number: int, repeats: int) -> dict:
    times = [t / number * 1e6 for t in timeit.repeat(call, number=number, repeat=repeats)]
    return {"median_us": statistics.median(times), "min_us": min(times), "repeats": repeats, "number": number}


def rhs_benchmark(run: Run, repeats: int = 7, number: int = 2000) -> dict:
    """Microseconds per right-hand side (fast and reference) at the sample states."""
    dynamics = run.dynamics
    workspace = D.make_workspace(dynamics)
    data = dynamics.mechanism.model.createData()
    out = {}
    for name, (t, y, onset) in sample_states(run).items():
        # vary t slightly so the drive is really evaluated (the drive caches its last call)
        ticks = iter(range(10**9))
        fast = _median_us(lambda: D.state_derivative(dynamics, workspace, t + 1e-9 * next(ticks), y, onset), number, repeats)
        slow = _median_us(lambda: reference_state_derivative(dynamics, data, t + 1e-9 * next(ticks), y, onset), max(number // 5, 50), repeats)
        difference = float(np.max(np.abs(D.state_derivative(dynamics, workspace, t, y, onset) - reference_state_derivative(dynamics, data, t, y, onset))))
        out[name] = {"t": t, "fast": fast, "reference": slow, "speedup": slow["median_us"] / fast["median_us"], "max_abs_difference": difference}
    return out


def realtime(run: Run, options: SolverOptions, t_end: float) -> dict:
    """Wall time over simulated time for one run, with the cost per right-hand side inside it."""
    spent = [0.0, 0]
    original = D.state_derivative

    def timed(*args, **kwargs):
        start = time.perf_counter()
        try:
            return original(*args, **kwargs)
        finally:
            spent[0] += time.perf_counter() - start
            spent[1] += 1

    D.state_derivative = timed
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)
            trajectory = integrate(run.dynamics, run.y0, (0.0, t_end), options, run.scene.limits)
    finally:
        D.state_derivative = original
    rhs_time = spent[0]
    return {
        "method": options.method,
        "rtol": options.rtol,
        "atol": options.atol,
        "max_step": options.max_step,
        "first_step": options.first_step,
        "jacobian": options.jacobian,
        "t_end": t_end,
        "status": trajectory.status,
        "cause": trajectory.cause,
        "t_reached": trajectory.t_end,
        "wall_time": trajectory.wall_time,
        "cpu_time": trajectory.cpu_time,
        "realtime_factor": trajectory.wall_time / trajectory.t_end if trajectory.t_end > 0 else float("inf"),
        "cpu_realtime_factor": trajectory.cpu_time / trajectory.t_end if trajectory.t_end > 0 else float("inf"),
        "steps": trajectory.n_steps,
        "rhs_calls": trajectory.n_rhs,
        "jacobians": trajectory.n_jacobians,
        "events": trajectory.n_events,
        "rhs_us_in_run": rhs_time / max(spent[1], 1) * 1e6,
        "rhs_share_of_wall_time": rhs_time / trajectory.wall_time if trajectory.wall_time else float("nan"),
    }
