"""robot.integration.brent: the port of scipy.optimize.brentq makes scipy's iterations exactly.

Roots, iteration and function-call counts are compared for equality (not to a
tolerance) with scipy's compiled routine on functions of different kinds:
polynomials (simple and multiple roots), transcendental, near-flat (a root of
high multiplicity, where bisection dominates), steep, with a jump, and the
step loop's own use (a penetration on a cubic Hermite interpolant, xtol 1e-15).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.optimize import brentq as scipy_brentq

from robot.integration.brent import RTOL, NoSignChange, brentq
from robot.integration.dense import HermiteDense

CASES = [
    ("cubic", lambda x: x**3 - 2 * x - 5, 2.0, 3.0),
    ("quadratic double root side", lambda x: (x - 1.0) ** 2 - 1e-10, 1.0, 3.0),
    ("triple root", lambda x: (x - 0.3) ** 3, -1.0, 2.0),
    ("near-flat: ninth power", lambda x: (x - 0.123456789) ** 9, 0.0, 1.0),
    ("near-flat: exp(-1/x^2)", lambda x: math.copysign(math.exp(-1.0 / (x - 0.2) ** 2), x - 0.2) if x != 0.2 else 0.0, -0.5, 1.0),
    ("cosine fixed point", lambda x: math.cos(x) - x, 0.0, 1.0),
    ("exponential", lambda x: math.exp(x) - 10.0, 0.0, 5.0),
    ("logarithm", lambda x: math.log(x) + 3.0, 1e-6, 1.0),
    ("steep tanh", lambda x: math.tanh(1e4 * (x - 0.7)), 0.0, 1.0),
    ("jump", lambda x: -1.0 if x < math.pi / 4 else 2.0, 0.0, 1.0),
    ("decreasing sine", lambda x: math.sin(x), 3.0, 4.0),
    ("wilkinson-like", lambda x: float(np.prod(x - np.arange(1.0, 8.0))), 2.5, 3.5),
    ("tiny scale", lambda x: x - 3e-9, 0.0, 1e-8),
    ("large scale", lambda x: x * x - 2e12, 0.0, 1e7),
    ("reversed bracket", lambda x: x**3 - 2 * x - 5, 3.0, 2.0),
]
TOLERANCES = [dict(), dict(xtol=1e-15, rtol=RTOL), dict(xtol=1e-15, rtol=4 * np.finfo(float).eps, maxiter=200), dict(xtol=1e-6, rtol=1e-3)]


@pytest.mark.parametrize("tolerances", TOLERANCES, ids=lambda d: ",".join(f"{k}={v:g}" for k, v in d.items()) or "defaults")
@pytest.mark.parametrize("name, f, a, b", CASES, ids=[c[0] for c in CASES])
def test_same_root_and_counts_as_scipy(name, f, a, b, tolerances):
    # disp=False: multiple roots defeat both within 100 iterations (and must do so identically)
    root, info = brentq(f, a, b, full_output=True, disp=False, **tolerances)
    expected, reference = scipy_brentq(f, a, b, full_output=True, disp=False, **tolerances)
    assert root == expected  # bit for bit: the same iterations
    assert info.iterations == reference.iterations
    assert info.function_calls == reference.function_calls
    assert info.converged == reference.converged


def test_extra_arguments_as_scipy():
    f = lambda x, c, p: x**p - c  # noqa: E731
    assert brentq(f, 0.0, 3.0, args=(2.0, 3)) == scipy_brentq(f, 0.0, 3.0, args=(2.0, 3))


def test_root_at_an_end_is_returned_at_once():
    root, info = brentq(lambda x: x - 1.0, 1.0, 2.0, full_output=True)
    assert root == 1.0 and info.function_calls == 2 and info.converged
    root, info = brentq(lambda x: x - 2.0, 1.0, 2.0, full_output=True)
    assert root == 2.0 and info.function_calls == 2


def test_contact_onset_on_a_hermite_step():
    """The step loop's use: a penetration crossing zero on a cubic Hermite dense output, xtol 1e-15."""
    rng = np.random.default_rng(7)
    for _ in range(30):
        t_old, t_new = 0.0, float(rng.uniform(1e-6, 1e-3))
        y_old, y_new = np.array([-abs(rng.normal(1e-6))]), np.array([abs(rng.normal(1e-6))])
        dense = HermiteDense(t_old, t_new, y_old, rng.normal(size=1) * 1e-3, y_new, rng.normal(size=1) * 1e-3)
        penetration = lambda t: float(dense(t)[0])  # noqa: E731
        kwargs = dict(xtol=1e-15, rtol=4 * np.finfo(float).eps, maxiter=200, full_output=True)
        root, info = brentq(penetration, t_old, t_new, **kwargs)
        expected, reference = scipy_brentq(penetration, t_old, t_new, **kwargs)
        assert root == expected and info.iterations == reference.iterations


def test_no_sign_change_is_a_value_error_as_scipy():
    f = lambda x: x * x + 1.0  # noqa: E731
    with pytest.raises(NoSignChange) as ours:  # a ValueError subclass: callers catch just this case
        brentq(f, -1.0, 1.0)
    with pytest.raises(ValueError) as theirs:
        scipy_brentq(f, -1.0, 1.0)
    assert isinstance(ours.value, ValueError) and str(ours.value) == str(theirs.value)


@pytest.mark.parametrize("kwargs", [dict(xtol=0.0), dict(xtol=-1.0), dict(rtol=1e-17), dict(maxiter=-1)])
def test_bad_tolerances_are_value_errors_as_scipy(kwargs):
    f = lambda x: x - 0.5  # noqa: E731
    with pytest.raises(ValueError):
        scipy_brentq(f, 0.0, 1.0, **kwargs)
    with pytest.raises(ValueError, match="xtol|rtol|maxiter"):
        brentq(f, 0.0, 1.0, **kwargs)


def test_nan_value_is_a_value_error():
    f = lambda x: math.nan if x > 0.25 else -1.0  # noqa: E731
    with pytest.raises(ValueError, match="NaN") as ours:
        brentq(f, 0.0, 1.0)
    assert not isinstance(ours.value, NoSignChange)  # a NaN on the interpolant fails the run, never skips a peak
    with pytest.raises(ValueError, match="NaN"):
        scipy_brentq(f, 0.0, 1.0)


def test_not_converged_raises_or_returns_the_last_iterate_as_scipy():
    f = lambda x: math.cos(x) - x  # noqa: E731
    with pytest.raises(RuntimeError, match="Failed to converge after 3 iterations"):
        brentq(f, 0.0, 1.0, maxiter=3)
    with pytest.raises(RuntimeError, match="Failed to converge after 3 iterations"):
        scipy_brentq(f, 0.0, 1.0, maxiter=3)
    root, info = brentq(f, 0.0, 1.0, maxiter=3, full_output=True, disp=False)
    expected, reference = scipy_brentq(f, 0.0, 1.0, maxiter=3, full_output=True, disp=False)
    assert root == expected and not info.converged and not reference.converged
    assert info.iterations == reference.iterations == 3


def test_random_polynomials_as_scipy():
    """Random cubics and quintics on random brackets with a sign change: identical roots and counts."""
    rng = np.random.default_rng(2024)
    compared = 0
    while compared < 300:
        coefficients = rng.normal(size=int(rng.choice([4, 6]))) * 10.0 ** rng.uniform(-6, 6)
        a, b = np.sort(rng.uniform(-3, 3, size=2))
        f = lambda x: float(np.polyval(coefficients, x))  # noqa: E731
        if f(a) * f(b) >= 0:
            continue
        xtol = float(10.0 ** rng.uniform(-15, -3))
        root, info = brentq(f, a, b, xtol=xtol, full_output=True, disp=False)
        expected, reference = scipy_brentq(f, a, b, xtol=xtol, full_output=True, disp=False)
        assert (root, info.iterations, info.function_calls) == (expected, reference.iterations, reference.function_calls)
        compared += 1
