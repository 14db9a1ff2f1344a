"""Locating a candidate's normal-force maximum over an impact's compression phase.

With Lankarani-Nikravesh damping the force ``K delta^n (1 + c delta_dot /
delta_dot0)`` peaks while the penetration still grows (``dF/dt = 0`` at a
positive rate), so the force at the penetration maximum underestimates the
peak. :class:`ForcePeaks` is called only for a step that contains a penetration
maximum of candidate ``k`` at ``t_peak``: the force is maximised (sampled, then
successive parabolic interpolation, :func:`parabolic_maximum`) on the step's
dense output over ``[t_old, t_new]``; if the maximum is at the step's start, it
lies in an earlier step: the force at the recorded step boundaries, walking
back from ``t_old``, brackets it (largest sampled value and its two neighbouring
steps), and those steps are replayed from their recorded start states
(methods registered ``replayable``, explicit Runge-Kutta: the very same step, so
the same dense output; other methods, e.g. multistep ones, whose step cannot be
redone alone: the cubic Hermite interpolant of the recorded end states and
their derivatives, :class:`robot.integration.dense.HermiteDense`) and searched
the same way. The search never goes back past the candidate's previous
penetration maximum (nor its onset, where the force is zero); when the force
only decreases since then, no maximum is recorded. The force is the system's
contact probe at the state (no right-hand-side call).
"""

from __future__ import annotations

import math

import numpy as np

from clearance_contact import ContactError, ContactLawError

from robot.integration import methods as registry
from robot.integration.dense import HermiteDense
from robot.integration.options import SolverOptions
from robot.integration.records import Records
from robot.integration.solvers import make_solver


def derivative_or_refused(system, onset_rates: np.ndarray, refused: float = math.inf):
    """``f(t, y)`` of ``system`` at fixed onset rates, answering ``refused`` (inf or NaN) where a contact law refuses the state.

    A trial stage of a too-large step can land in an absurd pose (e.g. a journal
    turned half round): a non-finite derivative makes the step's error estimate
    non-finite, so the solver rejects the step and shrinks it. Accepted states
    are still checked, and a real blow-up is reported. A ``ContactLawError`` (a
    user-defined law that raised or returned a value out of range) passes through:
    the run stops on it, naming the law. :func:`refused_stage_value` chooses
    ``refused`` for a method.
    """

    def fun(t: float, y: np.ndarray) -> np.ndarray:
        try:
            return system.derivative(t, y, onset_rates)
        except ContactLawError:
            raise  # a user-defined law broke its contract: no smaller step mends that
        except ContactError:
            return np.full(system.size, refused)

    return fun


def refused_stage_value(traits: registry.IntegratorTraits) -> float:
    """What a method's trial stage in a pose a contact law refuses is answered with: NaN if explicit, else inf.

    Explicit Runge-Kutta methods combine the stages with weights of which some are
    zero (RK45's ``B`` and ``E``, DOP853's ``E5``): ``inf * 0`` makes numpy print
    "RuntimeWarning: invalid value encountered in dot" on runs that go on fine,
    while NaN passes through quietly. Their error norm is NaN either way (the
    zero weights turn inf into NaN) and scipy rejects the step with the same
    step-size factor (``error_norm < 1`` is false, ``max(MIN_FACTOR, NaN)`` is
    ``MIN_FACTOR`` as is ``max(MIN_FACTOR, inf ** -k)``). The implicit methods
    keep inf: their Newton iterations and error tests (LSODA's in Fortran, CVODE's
    in C) are relied on to reject it, and a NaN fails every comparison.
    """
    return math.nan if traits.explicit else math.inf


class ForcePeaks:
    """The force-maximum search of one run (see the module docstring), over that run's :class:`Records`."""

    samples = 4  # force samples per searched interval, bracketing the maximum for the parabolic search
    # the maximum's time, relative to the searched interval: the force is flat there, so its value is
    # exact to ~1e-8 (peaks within 2e-9 of xtol 1e-6 with 6 samples on compound_misaligned, 37 % fewer evaluations)
    xtol = 1e-4
    max_walk = 1000  # step boundaries walked back at most

    def __init__(self, system, options: SolverOptions, records: Records):
        self.system, self.options, self.records = system, options, records
        self.phase_start = np.full(system.n_candidates, -math.inf)  # time of each candidate's last penetration maximum
        self.replay_system = None  # a replica of the system (its own work data) for replayed steps

    def force(self, t: float, y: np.ndarray, onset_rates: np.ndarray, k: int) -> float:
        """Normal force (N) of candidate ``k`` at (t, y); ``-inf`` in a pose the contact law refuses."""
        try:
            return float(self.system.probe(t, y, onset_rates, residual=False).normal_force[k])
        except ContactLawError:
            raise  # a user-defined law broke its contract: the run stops on it (not a missed peak)
        except ContactError:
            return -math.inf

    def _search(self, dense, a: float, b: float, onset_rates: np.ndarray, k: int) -> tuple[float, float, int]:
        """(t, F, edge) of the largest force of candidate ``k`` on ``dense`` over [a, b].

        ``edge``: -1 if the largest sample is the first one (the maximum may lie
        before ``a``), +1 if the last one (after ``b``), else 0.
        """
        times = sample_times(a, b, self.samples)
        forces = [self.force(tt, dense(tt), onset_rates, k) for tt in times]
        i = int(np.argmax(forces))
        fun = lambda s: self.force(a + s, dense(a + s), onset_rates, k)  # noqa: E731 - in the offset from a: rounding relative to the step
        bracket = None
        if 0 < i < self.samples:
            bracket = (times[i - 1] - a, times[i] - a, times[i + 1] - a, forces[i - 1], forces[i], forces[i + 1])
        else:
            # the largest sample is at an end: is the force still rising just inside it? (an
            # offset well above the force's rounding, well below the sample spacing)
            inner = times[i] + (1e-4 if i == 0 else -1e-4) * (b - a)
            f_inner = self.force(inner, dense(inner), onset_rates, k)
            if f_inner > forces[i]:
                if i == 0:
                    bracket = (0.0, inner - a, times[1] - a, forces[0], f_inner, forces[1])
                else:
                    bracket = (times[i - 1] - a, inner - a, b - a, forces[i - 1], f_inner, forces[i])
        if bracket is None:
            return float(times[i]), forces[i], (-1 if i == 0 else 1)
        s, f = parabolic_maximum(fun, *map(float, bracket), xtol=self.xtol * (b - a))
        return a + s, f, 0

    def _replay(self, i_a: int, i_b: int) -> list:
        """Dense outputs covering the step between boundary records ``i_a`` and ``i_b``, from the recorded start state."""
        options, records = self.options, self.records
        t_a, t_b = records.t[i_a], records.t[i_b]
        if self.replay_system is None:
            self.replay_system = self.system.replica()
        traits = registry.traits(options.method)
        fun = derivative_or_refused(self.replay_system, records.onset[i_a], refused_stage_value(traits))
        if not traits.replayable:
            # a step that cannot be redone alone: the cubic Hermite interpolant of its two accepted end
            # states and their derivatives (two right-hand sides), on the method's own trajectory and as
            # accurate as its steps (error ~ h^4 max|y^(4)| / 384)
            y_a, y_b = records.y[i_a], records.y[i_b]
            return [HermiteDense(t_a, t_b, y_a, fun(t_a, y_a), y_b, fun(t_b, y_b))]
        solver = make_solver(options.method, fun, t_a, records.y[i_a], t_b, options.rtol, options.atol, math.inf, t_b - t_a)
        dense = []
        for _ in range(10_000):
            if solver.status != "running":
                break
            solver.step()
            if solver.status == "failed":
                break
            dense.append(solver.dense_output())
        return dense

    def locate(self, k: int, dense, t_old: float, t_peak: float, t_new: float, onset_rates: np.ndarray):
        """(t, y, force, onset rates) of candidate ``k``'s force maximum up to just past ``t_peak``, or None.

        The step's part searched runs to its end ``t_new``: an undamped force peaks
        at the penetration maximum itself, and that maximum is then inside the
        searched interval. A force still growing at ``t_new`` (a revolute candidate's
        force also depends on the tilt) or only decreasing since the previous
        penetration maximum has no maximum in view: None.
        """
        t_lo = self.phase_start[k]
        self.phase_start[k] = t_peak
        a = max(t_old, t_lo)
        if not t_new > a:
            return None
        t_best, f_best, edge = self._search(dense, a, t_new, onset_rates, k)
        if edge > 0:
            return None
        best = (t_best, f_best, dense, onset_rates) if edge == 0 else None
        left_end = a
        if t_old > t_lo:
            # the force may have peaked (higher) in an earlier step of the same compression phase
            found = self._earlier(k, t_old, t_lo, f_best if edge < 0 else self.force(t_old, dense(t_old), onset_rates, k), edge < 0)
            if found is not None:
                left_end = found[0]
                if found[1] is not None and (best is None or found[1][1] > best[1]):
                    best = found[1]
        if best is None:
            return None
        t_best, f_best, dense_best, onset_best = best
        if t_best <= left_end or not f_best > 0:
            return None  # the force only decreases over the phase searched: no maximum in it
        return float(t_best), self.system.normalise(dense_best(t_best)), float(f_best), onset_best.copy()

    def _boundary_forces(self, k: int, t_old: float, t_lo: float, f_old: float) -> tuple[np.ndarray, np.ndarray] | None:
        """The boundary records from ``t_old`` back to the phase start (latest first), and candidate ``k``'s force at each.

        The force at ``t_old`` is ``f_old``, at the earlier records the one the step
        loop probed there (the same contact law, same state). The walk stops at
        (and includes) the previous penetration maximum, the onset (zero force),
        the run's start (the first record), or its ``max_walk``-th record; None
        when the records do not end at the step's start.
        """
        index, times, all_forces = self.records.boundaries()
        n = index.size
        if not n or times[n - 1] != t_old:
            return None  # the records do not end at the step's start: nothing to walk back over
        back = slice(n - 1, None if n <= self.max_walk else n - 1 - self.max_walk, -1)
        forces = all_forces[back, k].copy()  # the first entry is replaced
        forces[0] = f_old
        stops = (times[back] <= t_lo) | ~(forces > 0)
        end = int(np.argmax(stops)) + 1 if stops.any() else forces.size
        return index[back][:end], forces[:end]

    def _earlier(self, k: int, t_old: float, t_lo: float, f_old: float, falling: bool):
        """The compression phase's earlier steps: (left end searched, best (t, F, dense, onset) or None).

        The largest sampled local maximum of the force at the step boundaries
        (``t_old`` counts when the force is ``falling`` after it) is refined on its
        two neighbouring steps, replayed.
        """
        walked = self._boundary_forces(k, t_old, t_lo, f_old)
        if walked is None:
            return None
        chain, forces = walked
        records_t = self.records.t
        left_end = max(records_t[chain[-1]], t_lo)
        p = largest_local_maximum(forces, falling)
        if p is None:
            return left_end, None
        best = None
        intervals = [(chain[p + 1], chain[p])] + ([(chain[p], chain[p - 1])] if p >= 1 else [])
        for i_a, i_b in intervals:
            if not records_t[i_b] > records_t[i_a]:
                continue
            onset_rates = self.records.onset[i_a]
            for segment in self._replay(i_a, i_b):
                lo, hi = max(segment.t_old, t_lo, records_t[i_a]), min(segment.t, records_t[i_b])
                if not hi > lo:
                    continue
                t_found, f_found, _ = self._search(segment, lo, hi, onset_rates, k)
                if t_found <= left_end:
                    continue  # the tail of the previous phase's maximum, not a maximum of this one
                if best is None or f_found > best[1]:
                    best = (t_found, f_found, segment, onset_rates)
        return left_end, best


def largest_local_maximum(forces: np.ndarray, falling: bool) -> int | None:
    """The largest local maximum of a force walked back in time (``forces[p + 1]`` before ``forces[p]``): its index, or None.

    A local maximum is not below the force before it and above the force after it;
    ``forces[0]``, with no force after it, is one when the force is ``falling``
    after it and ``forces[-1]`` never is. Of equal maxima, the latest.
    """
    above_after = np.empty(forces.size - 1, dtype=bool)
    above_after[:1] = falling
    above_after[1:] = forces[1:-1] > forces[:-2]
    peaks = np.flatnonzero((forces[:-1] >= forces[1:]) & above_after)
    return int(peaks[np.argmax(forces[peaks])]) if peaks.size else None


def sample_times(a: float, b: float, intervals: int) -> list[float]:
    """``np.linspace(a, b, intervals + 1)`` as floats, the same numbers without its overhead (``a < b``).

    numpy's sequence is ``j * step + a`` with ``step = (b - a) / intervals``, the
    last point exactly ``b``.
    """
    step = (b - a) / intervals
    return [j * step + a for j in range(intervals)] + [b]


def parabolic_maximum(f, a: float, m: float, b: float, fa: float, fm: float, fb: float, xtol: float, maxiter: int = 60) -> tuple[float, float]:
    """Maximum of a smooth unimodal ``f`` bracketed by ``a < m < b`` (``f(m) >= f(a), f(b)``): (x, f(x)).

    Successive parabolic interpolation (the vertex of the parabola through the
    bracket's three points), with a golden-section step into the larger part of
    the bracket when the vertex falls outside it; stops when the vertex moves by
    less than ``xtol``. Near a smooth maximum it converges superlinearly: a
    handful of evaluations.
    """
    golden = 0.3819660112501051
    for _ in range(maxiter):
        p = (m - a) * (fm - fb)
        r = (m - b) * (fm - fa)
        denominator = 2.0 * (p - r)
        x = m - ((m - a) * p - (m - b) * r) / denominator if denominator != 0.0 else math.nan
        converged = abs(x - m) < xtol
        if not a < x < b:
            x = m + golden * (b - m) if b - m > m - a else m - golden * (m - a)
            converged = False
        if x == m:
            break
        fx = f(x)
        if x > m:
            if fx >= fm:
                a, fa, m, fm = m, fm, x, fx
            else:
                b, fb = x, fx
        else:
            if fx >= fm:
                b, fb, m, fm = m, fm, x, fx
            else:
                a, fa = x, fx
        if converged or b - a < xtol:
            break
    return m, fm
