"""One-dimensional solvers in plain floats: a bracketed root and a bounded minimum.

The ball balancer (stability boundaries, the symmetric balanced spacing) and the
crank counterweight need three roots and one bounded minimisation per run; these
small loops do that without importing ``scipy.optimize`` (about 0.1 s, more than the
solving itself).  Both are Brent's methods (R. P. Brent, *Algorithms for Minimization
without Derivatives*, 1973: ``zero`` and ``localmin``), the algorithms behind
``scipy.optimize.brentq`` and ``minimize_scalar(method="bounded")``; their iterates
may differ from SciPy's in the last steps, so results agree within the stated
tolerances, not bit for bit.
"""
from __future__ import annotations

import math
from typing import Callable

from modal.errors import ParameterError

__all__ = ["find_root", "minimize_bounded"]

_EPS = 2.220446049250313e-16  # machine epsilon of float64
_GOLDEN = 0.5 * (3.0 - math.sqrt(5.0))  # golden-section fraction of the larger part


def _finite(value: float, what: str) -> float:
    number = float(value)
    if not math.isfinite(number):
        raise ParameterError(f"{what} = {value!r}: expected a finite number")
    return number


def find_root(f: Callable[[float], float], low: float, high: float, *, xtol: float = 2e-12,
              rtol: float = 4 * _EPS, maxiter: int = 200) -> float:
    """A root of ``f`` in the bracket ``[low, high]`` by Brent's method.

    Inverse quadratic interpolation and secant steps, with bisection whenever they do not
    shrink the bracket fast enough: never slower than bisection.

    Parameters
    ----------
    f : callable
        ``f(x) -> float``, continuous on the bracket, with ``f(low)`` and ``f(high)`` of
        opposite signs (or one of them zero).
    low, high : float
        Ends of the bracket (either order).
    xtol, rtol : float
        Tolerance: the returned ``x`` lies within ``xtol + rtol |x|`` of a sign change of
        ``f`` (a root, for continuous ``f``); ``xtol >= 0``, ``rtol >= 4 eps``.
    maxiter : int
        Largest number of iterations (evaluations of ``f`` beyond the two ends).

    Returns
    -------
    float
        The root.

    Raises
    ------
    ParameterError
        If the ends are not finite, the signs at the ends agree or are not finite, a
        tolerance is out of range, or the iterations run out.
    """
    a, b = _finite(low, "low"), _finite(high, "high")
    if not (xtol >= 0.0 and rtol >= 4 * _EPS):
        raise ParameterError(f"xtol = {xtol!r}, rtol = {rtol!r}: expected xtol >= 0 and rtol >= 4 eps ({4 * _EPS:.3g})")
    fa, fb = float(f(a)), float(f(b))
    if not (math.isfinite(fa) and math.isfinite(fb)):
        raise ParameterError(f"f(low) = {fa!r}, f(high) = {fb!r} at low = {a!r}, high = {b!r}: expected finite values")
    if fa == 0.0:
        return a
    if fb == 0.0:
        return b
    if (fa > 0.0) == (fb > 0.0):
        raise ParameterError(f"f(low) = {fa!r} and f(high) = {fb!r} at low = {a!r}, high = {b!r}: expected "
                             f"opposite signs (a bracket around the root)")
    c, fc = a, fa
    d = e = b - a
    for _ in range(int(maxiter)):
        if (fb > 0.0) == (fc > 0.0):  # keep the root between b and c
            c, fc = a, fa
            d = e = b - a
        if abs(fc) < abs(fb):  # b is the best estimate so far
            a, b, c = b, c, b
            fa, fb, fc = fb, fc, fb
        tol = 0.5 * (xtol + rtol * abs(b))
        m = 0.5 * (c - b)
        if abs(m) <= tol or fb == 0.0:
            return b
        if abs(e) < tol or abs(fa) <= abs(fb):
            d = e = m  # bisection
        else:
            s = fb / fa
            if a == c:  # secant
                p, q = 2.0 * m * s, 1.0 - s
            else:  # inverse quadratic interpolation
                q, r = fa / fc, fb / fc
                p = s * (2.0 * m * q * (q - r) - (b - a) * (r - 1.0))
                q = (q - 1.0) * (r - 1.0) * (s - 1.0)
            if p > 0.0:
                q = -q
            else:
                p = -p
            if 2.0 * p < min(3.0 * m * q - abs(tol * q), abs(e * q)):
                e, d = d, p / q  # the interpolation is accepted
            else:
                d = e = m
        a, fa = b, fb
        b += d if abs(d) > tol else math.copysign(tol, m)
        fb = float(f(b))
        if not math.isfinite(fb):
            raise ParameterError(f"f({b!r}) = {fb!r} inside the bracket: expected a finite value")
    raise ParameterError(f"no root to xtol = {xtol!r}, rtol = {rtol!r} in {maxiter} iterations "
                         f"(bracket [{min(b, c)!r}, {max(b, c)!r}]): expected a continuous function")


def minimize_bounded(f: Callable[[float], float], low: float, high: float, *, xatol: float = 1e-5,
                     maxiter: int = 500) -> float:
    """The minimiser of ``f`` on ``(low, high)`` by Brent's method (golden section and parabolas).

    For a unimodal ``f`` the result is within about ``xatol`` of the minimiser (the
    search stops when the bracket around the best point, of half-width ``2 tol`` with
    ``tol = sqrt(eps) |x| + xatol / 3``, is no wider than that); the ends themselves are
    never evaluated (compare with them if the minimum may lie there).

    Parameters
    ----------
    f : callable
        ``f(x) -> float``.
    low, high : float
        Bounds, ``low < high``.
    xatol : float
        Absolute tolerance on the minimiser (> 0).
    maxiter : int
        Largest number of evaluations of ``f``.

    Returns
    -------
    float
        The best point found.

    Raises
    ------
    ParameterError
        If the bounds are not finite and increasing, ``xatol`` is not positive, ``f`` is not
        finite at an evaluated point, or the evaluations run out.
    """
    a, b = _finite(low, "low"), _finite(high, "high")
    if not a < b:
        raise ParameterError(f"low = {a!r}, high = {b!r}: expected low < high")
    if not xatol > 0.0:
        raise ParameterError(f"xatol = {xatol!r}: expected a tolerance > 0")
    root_eps = math.sqrt(_EPS)

    def value(x: float) -> float:
        fx = float(f(x))
        if not math.isfinite(fx):
            raise ParameterError(f"f({x!r}) = {fx!r}: expected a finite value")
        return fx

    x = w = v = a + _GOLDEN * (b - a)  # best, second best, previous second best
    fx = fw = fv = value(x)
    d = e = 0.0  # last step and the one before
    for _ in range(int(maxiter)):
        middle = 0.5 * (a + b)
        tol = root_eps * abs(x) + xatol / 3.0
        tol2 = 2.0 * tol
        if abs(x - middle) <= tol2 - 0.5 * (b - a):
            return x
        golden = True
        if abs(e) > tol:  # try a parabola through x, w, v
            r = (x - w) * (fx - fv)
            q = (x - v) * (fx - fw)
            p = (x - v) * q - (x - w) * r
            q = 2.0 * (q - r)
            if q > 0.0:
                p = -p
            q = abs(q)
            previous, e = e, d
            if abs(p) < abs(0.5 * q * previous) and q * (a - x) < p < q * (b - x):
                d = p / q
                u = x + d
                if u - a < tol2 or b - u < tol2:  # not too close to the bounds
                    d = tol if middle >= x else -tol
                golden = False
        if golden:
            e = (a - x) if x >= middle else (b - x)
            d = _GOLDEN * e
        u = x + (d if abs(d) >= tol else math.copysign(tol, d) if d != 0.0 else tol)
        fu = value(u)
        if fu <= fx:
            if u >= x:
                a = x
            else:
                b = x
            v, fv, w, fw, x, fx = w, fw, x, fx, u, fu
        else:
            if u < x:
                a = u
            else:
                b = u
            if fu <= fw or w == x:
                v, fv, w, fw = w, fw, u, fu
            elif fu <= fv or v == x or v == w:
                v, fv = u, fu
    raise ParameterError(f"no minimum to xatol = {xatol!r} in {maxiter} evaluations on [{low!r}, {high!r}]")
