"""Brent's root finder on a bracketing interval: a line-by-line port of ``scipy.optimize.brentq``.

The step loop locates contact onsets (penetration crossing zero) and
penetration maxima (its rate crossing zero) on a step's dense output with
Brent's method (:mod:`robot.integration.events`, :mod:`robot.integration.event_loop`).
``scipy.optimize`` costs ~0.1-0.3 s to import (it pulls ``scipy.sparse``,
``scipy.linalg``, ``scipy.special``); this port makes the same iterations without it,
so the located times are the same floating-point numbers (issue 16, import time).

**Method** (Brent 1973, *Algorithms for Minimization without Derivatives*,
ch. 4; the variant of Charles Harris in scipy): the root stays bracketed by
``[xcur, xblk]`` with ``|f(xcur)| <= |f(xblk)|``; each iteration tries inverse
quadratic extrapolation through ``(xpre, xcur, xblk)`` (linear interpolation when
``xpre == xblk``), and takes the trial step ``stry`` only if
``2 |stry| < min(|spre|, 3 |sbis| - delta)`` (``sbis`` half the bracket, ``spre``
the step before last), otherwise bisects; a step is at least ``delta``. Converged
when ``f(xcur) == 0`` or ``|sbis| < delta = (xtol + rtol |xcur|) / 2``.
Superlinear on smooth functions, never slower than about bisection.

**Source**: ``scipy/optimize/Zeros/brentq.c`` (C, written by Charles Harris;
unchanged since scipy 1.10, commit 873b43c, 2022, through scipy 1.17), the wrapper
``call_solver`` of ``scipy/optimize/_zerosmodule.c`` (errors) and ``brentq`` of
``scipy/optimize/_zeros_py.py`` (argument checks, defaults ``xtol = 2e-12``,
``rtol = 4 eps``, ``maxiter = 100``; a NaN function value raises). Python floats
are IEEE doubles as C's, and the operations are the same in the same order, so
the iterates are bit for bit those of scipy (``tests/test_brent.py`` checks
roots, iteration and call counts against scipy). The errors are scipy's:
``ValueError`` when ``f(a)`` and ``f(b)`` have the same sign (the callers catch
it), for a NaN function value and bad tolerances; ``RuntimeError`` when
``maxiter`` iterations do not converge (``disp=True``).
"""

from __future__ import annotations

import math
import operator
from dataclasses import dataclass
from typing import Callable

#: scipy.optimize's defaults for brentq
XTOL = 2e-12
RTOL = 4 * 2.220446049250313e-16  # 4 machine epsilons: the smallest relative tolerance accepted
MAXITER = 100


class NoSignChange(ValueError):
    """f(a) and f(b) have the same sign: no root is bracketed (a ``ValueError``, as scipy's)."""


@dataclass(frozen=True)
class BrentResult:
    """What ``full_output=True`` returns beside the root (the fields of scipy's ``RootResults``)."""

    root: float
    iterations: int
    function_calls: int
    converged: bool

    @property
    def flag(self) -> str:
        return "converged" if self.converged else "convergence error"


def _signbit(x: float) -> bool:
    return math.copysign(1.0, x) < 0.0


def _divide(numerator: float, denominator: float) -> float:
    """IEEE division, as in C: a zero denominator gives a signed infinity or NaN (Python raises)."""
    if denominator != 0.0:
        return numerator / denominator
    if numerator == 0.0 or math.isnan(numerator):
        return math.nan
    return math.inf if _signbit(numerator) == _signbit(denominator) else -math.inf


def brentq(
    f: Callable[..., float],
    a: float,
    b: float,
    args: tuple = (),
    xtol: float = XTOL,
    rtol: float = RTOL,
    maxiter: int = MAXITER,
    full_output: bool = False,
    disp: bool = True,
) -> float | tuple[float, BrentResult]:
    """A root of ``f`` in ``[a, b]`` (``f(a)``, ``f(b)`` of opposite signs), as ``scipy.optimize.brentq``.

    Returns the root, or ``(root, BrentResult)`` with ``full_output``; with
    ``disp=False`` an unconverged search returns its last iterate (``converged``
    False) instead of raising ``RuntimeError``.
    """
    if not isinstance(args, tuple):
        args = (args,)
    maxiter = operator.index(maxiter)
    if xtol <= 0:
        raise ValueError(f"xtol too small ({xtol:g} <= 0)")
    if rtol < RTOL:
        raise ValueError(f"rtol too small ({rtol:g} < {RTOL:g})")
    if maxiter < 0:
        raise ValueError("maxiter must be >= 0")
    calls = 0

    def value(x: float) -> float:
        nonlocal calls
        fx = float(f(x, *args))
        calls += 1
        if math.isnan(fx):
            raise ValueError(f"The function value at x={x} is NaN; solver cannot continue.")
        return fx

    root, iterations, converged = _iterate(value, float(a), float(b), float(xtol), float(rtol), maxiter)
    if not converged and disp:
        raise RuntimeError(f"Failed to converge after {iterations} iterations.")
    if full_output:
        return root, BrentResult(root, iterations, calls, converged)
    return root


def _iterate(f: Callable[[float], float], xa: float, xb: float, xtol: float, rtol: float, maxiter: int) -> tuple[float, int, bool]:
    """``brentq.c``'s loop: ``(last iterate, iterations, converged)``; ValueError without a sign change."""
    xpre, xcur = xa, xb
    xblk = fblk = spre = scur = 0.0
    fpre = f(xpre)
    fcur = f(xcur)
    if fpre == 0:
        return xpre, 0, True
    if fcur == 0:
        return xcur, 0, True
    if _signbit(fpre) == _signbit(fcur):
        raise NoSignChange("f(a) and f(b) must have different signs")
    iterations = 0
    for _ in range(maxiter):
        iterations += 1
        if fpre != 0 and fcur != 0 and _signbit(fpre) != _signbit(fcur):
            xblk, fblk = xpre, fpre
            spre = scur = xcur - xpre
        if abs(fblk) < abs(fcur):
            xpre, xcur, xblk = xcur, xblk, xcur
            fpre, fcur, fblk = fcur, fblk, fcur
        delta = (xtol + rtol * abs(xcur)) / 2
        sbis = (xblk - xcur) / 2
        if fcur == 0 or abs(sbis) < delta:
            return xcur, iterations, True
        if abs(spre) > delta and abs(fcur) < abs(fpre):
            if xpre == xblk:  # interpolate
                stry = _divide(-fcur * (xcur - xpre), fcur - fpre)
            else:  # extrapolate (inverse quadratic)
                # f can repeat a value (a flat function, rounding): the C code divides by zero
                # there and bisects on the infinite or NaN trial step; so does this
                dpre = _divide(fpre - fcur, xpre - xcur)
                dblk = _divide(fblk - fcur, xblk - xcur)
                stry = _divide(-fcur * (fblk * dblk - fpre * dpre), dblk * dpre * (fblk - fpre))
            limit = 3 * abs(sbis) - delta
            if abs(spre) < limit:  # C's MIN(a, b) = a < b ? a : b (Python's min differs on NaN)
                limit = abs(spre)
            if 2 * abs(stry) < limit:  # good short step
                spre, scur = scur, stry
            else:  # bisect
                spre = scur = sbis
        else:  # bisect
            spre = scur = sbis
        xpre, fpre = xcur, fcur
        if abs(scur) > delta:
            xcur += scur
        else:
            xcur += delta if sbis > 0 else -delta
        fcur = f(xcur)
    return xcur, iterations, False
