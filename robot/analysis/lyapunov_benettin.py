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
That statistical error is estimated by the method of batch means
(:func:`batch_means_standard_error`): the K interval rates ln(d_k / d_0) / tau are
correlated (on the Lorenz attractor negatively: a long stretch is followed by a
shorter one), so their plain standard error is wrong in either direction, and the
spread of the running estimate misses slow drift.

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

import math
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


def batch_means_standard_error(samples) -> float:
    """Standard error of the mean of a correlated, stationary series by the method of batch means.

    The K samples are cut into b = round(sqrt(K)) consecutive batches of m = K // b
    (the earliest K - b m dropped: they are the closest to the transient); the batch
    means are nearly independent once m exceeds the correlation length, and

        SE = std(batch means, ddof=1) / sqrt(b).

    Conway, Management Science 10 (1963) 47-61; Law & Kelton, *Simulation Modeling
    and Analysis* (3rd ed. 2000), Sec. 9.5.3; b ~ sqrt(K): Flegal & Jones, Ann.
    Statist. 38 (2010) 1034-1070. NaN for K < 4 (fewer than two batches of two).
    """
    values = np.asarray(samples, dtype=float).ravel()
    if values.size < 4:
        return math.nan
    n_batches = max(2, int(round(math.sqrt(values.size))))
    size = values.size // n_batches
    means = values[values.size - n_batches * size :].reshape(n_batches, size).mean(axis=1)
    return float(np.std(means, ddof=1) / math.sqrt(n_batches))


@dataclass(frozen=True)
class BenettinResult:
    """``exponent`` (1/[time]); ``times`` (K,) ends of the averaged intervals; ``log_stretch`` (K,)
    ln(d_k / d_0); ``running`` (K,) the estimate after each interval; ``final_state`` of the reference;
    ``standard_error`` of the exponent by batch means (:func:`batch_means_standard_error`)."""

    exponent: float
    times: np.ndarray
    log_stretch: np.ndarray
    running: np.ndarray
    final_state: np.ndarray
    standard_error: float


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
    standard_error = batch_means_standard_error(logs / tau)
    return BenettinResult(float(running[-1]), t - tau * n_intervals + elapsed, logs, running, x, standard_error)
