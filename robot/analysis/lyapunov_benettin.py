"""Largest Lyapunov exponent of a flow: two nearby trajectories, periodically renormalised.

Benettin, Galgani, Giorgilli & Strelcyn, "Lyapunov characteristic exponents
for smooth dynamical systems and for Hamiltonian systems; a method for
computing all of them", Meccanica 15 (1980) 9-20 (Part 1, Sec. 3), in the
two-trajectory form of Wolf, Swift, Swinney & Vastano, "Determining Lyapunov
exponents from a time series", Physica D 16 (1985) 285-317, Sec. 3):
a reference trajectory x(t) and a perturbed one y(t), |y(t_0) - x(t_0)| = d_0,
are advanced over intervals tau; after each interval the separation d_k is
measured and the perturbed state is reset to distance d_0 along the current
separation direction (which aligns with the most expanding direction), and

    lambda_1 = lim (1 / (K tau)) sum_{k=1..K} ln(d_k / d_0).

d_0 must be small enough for the separation to stay in the linear regime over
tau (d_0 e^{lambda tau} << attractor size) and large against the integration
error (d_0 >> rtol |x|): with ``solve_ivp`` at rtol = 1e-10, d_0 = 1e-7 relative
to the state's size is a safe choice. The first ``n_alignment`` intervals only
align the separation and are not averaged; the running estimate is returned
so its convergence can be inspected (an error ~ 1 / (K tau) from the bounded
fluctuations of ln d, plus the statistical fluctuation on chaotic attractors).

The flow is anything with :class:`Flow`'s methods: ``advance(state, t0, t1)``
(non-autonomous allowed), and the separation geometry ``separation(reference,
other)`` (a tangent vector at ``reference``), ``distance`` and ``perturb(state,
direction, size)``. :class:`EuclideanFlow` implements the geometry for states in
R^n; a state with unit quaternions (the simulator's free-flyer or spherical
joints) overrides them with the tangent-space difference (log map of the
relative rotation) and the exponential map, so the separation is measured on
the configuration manifold, not across the quaternion's normalisation.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable, Protocol, runtime_checkable

import numpy as np
from scipy.integrate import solve_ivp

from .errors import AnalysisError, require_count, require_finite, require_non_negative, require_positive


@runtime_checkable
class Flow(Protocol):
    """What :func:`benettin_exponent` needs of a dynamical system."""

    def advance(self, state: np.ndarray, t0: float, t1: float) -> np.ndarray:
        """The state at ``t1`` of the trajectory through ``state`` at ``t0``."""

    def separation(self, reference: np.ndarray, other: np.ndarray) -> np.ndarray:
        """Tangent vector at ``reference`` pointing to ``other`` (its norm is the distance)."""

    def distance(self, reference: np.ndarray, other: np.ndarray) -> float:
        """Distance between two states."""

    def perturb(self, state: np.ndarray, direction: np.ndarray, size: float) -> np.ndarray:
        """The state at distance ``size`` from ``state`` along the tangent ``direction``."""


class EuclideanFlow:
    """Separation geometry of states in R^n: y - x, |y - x|, x + size d / |d|. Subclasses define ``advance``."""

    def separation(self, reference: np.ndarray, other: np.ndarray) -> np.ndarray:
        return np.asarray(other, dtype=float) - np.asarray(reference, dtype=float)

    def distance(self, reference: np.ndarray, other: np.ndarray) -> float:
        return float(np.linalg.norm(self.separation(reference, other)))

    def perturb(self, state: np.ndarray, direction: np.ndarray, size: float) -> np.ndarray:
        norm = np.linalg.norm(direction)
        if not norm > 0.0:
            raise AnalysisError("perturbation direction must be non-zero")
        return np.asarray(state, dtype=float) + size * np.asarray(direction, dtype=float) / norm


class OdeFlow(EuclideanFlow):
    """The flow of dx/dt = rhs(t, x) by ``scipy.integrate.solve_ivp`` (default DOP853, rtol 1e-10, atol 1e-12)."""

    def __init__(
        self, rhs: Callable[[float, np.ndarray], np.ndarray], *, method: str = "DOP853", rtol: float = 1e-10, atol: float = 1e-12
    ) -> None:
        self.rhs, self.method = rhs, method
        self.rtol, self.atol = require_positive("rtol", rtol), require_positive("atol", atol)

    def advance(self, state: np.ndarray, t0: float, t1: float) -> np.ndarray:
        solution = solve_ivp(self.rhs, (t0, t1), state, method=self.method, rtol=self.rtol, atol=self.atol)
        if not solution.success:
            raise AnalysisError(f"integration from t={t0:g} to t={t1:g} failed: {solution.message}")
        return solution.y[:, -1]


@dataclass(frozen=True)
class BenettinResult:
    """``exponent`` (1/[time]); ``times`` (K,) ends of the averaged intervals; ``log_stretch`` (K,)
    ln(d_k / d_0); ``running`` (K,) the estimate after each interval; ``final_state`` of the reference."""

    exponent: float
    times: np.ndarray
    log_stretch: np.ndarray
    running: np.ndarray
    final_state: np.ndarray


def benettin_exponent(
    flow: Flow,
    state,
    *,
    renormalisation_time: float,
    n_intervals: int,
    separation: float,
    t0: float = 0.0,
    transient_time: float = 0.0,
    n_alignment: int = 10,
    seed: int = 0,
) -> BenettinResult:
    """Largest Lyapunov exponent by Benettin's method (module docstring).

    ``state`` is advanced alone over ``transient_time`` (onto the attractor),
    then ``n_alignment + n_intervals`` intervals of ``renormalisation_time`` are
    run with a companion at distance ``separation`` (random initial direction
    from ``seed``); the last ``n_intervals`` are averaged.
    """
    if not isinstance(flow, Flow):
        raise AnalysisError(f"flow must provide advance, separation, distance and perturb; got {type(flow).__name__}")
    tau = require_positive("renormalisation_time", renormalisation_time)
    n_intervals = require_count("n_intervals", n_intervals)
    d0 = require_positive("separation", separation)
    n_alignment = require_count("n_alignment", n_alignment, minimum=0)
    t = require_finite("t0", t0)
    x = np.asarray(state, dtype=float).copy()
    transient = require_non_negative("transient_time", transient_time)
    if transient > 0.0:
        x = flow.advance(x, t, t + transient)
        t += transient
    direction = np.random.default_rng(seed).standard_normal(flow.separation(x, x).shape)
    y = flow.perturb(x, direction, d0)
    logs = np.empty(n_intervals)
    for k in range(n_alignment + n_intervals):
        x, y = flow.advance(x, t, t + tau), flow.advance(y, t, t + tau)
        t += tau
        distance = flow.distance(x, y)
        if not (np.isfinite(distance) and distance > 0.0):
            raise AnalysisError(f"separation became {distance!r} at t={t:g}: increase separation or tighten the flow's tolerance")
        if k >= n_alignment:
            logs[k - n_alignment] = np.log(distance / d0)
        y = flow.perturb(x, flow.separation(x, y), d0)
    elapsed = tau * np.arange(1, n_intervals + 1)
    running = np.cumsum(logs) / elapsed
    return BenettinResult(float(running[-1]), t - tau * n_intervals + elapsed, logs, running, x)
