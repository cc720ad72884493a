"""Tail probabilities and quantiles of the gamma, chi-square and F distributions.

The few that identification's checks need, written here so that a fitting process does not import
``scipy.special`` (about 0.4 CPU-s per process with scipy 1.17, whose array-API layer loads
numpy.f2py and numpy.testing).

* Regularised incomplete gamma functions ``P(a, x)`` and ``Q(a, x) = 1 - P(a, x)``: the power series
  of ``P`` below ``x = a + 1``, Legendre's continued fraction of ``Q`` above (Numerical Recipes 6.2).
* Regularised incomplete beta function ``I_x(a, b)`` and its complement: the continued fraction of
  Numerical Recipes 6.4, on ``x`` or on ``1 - x`` (with the parameters swapped), whichever converges.
* The factor in front of both, ``x^a e^-x / Γ(a)`` and ``x^a (1-x)^b / B(a, b)``, is taken through
  Stirling's series when a parameter is large, as ``a (log(1 + u) - u)`` with ``u`` the relative
  distance from the mode, so that it keeps its relative precision where ``a log x`` and
  ``log Γ(a)`` would cancel (degrees of freedom in the thousands and more).
* Each smaller tail is computed directly, never as one minus the larger, so tails of 1e-300 keep
  their digits; quantiles are found by Newton's method on the logarithm of the smaller tail, over
  ``log x`` (gamma) or the logit of ``x`` (beta), bracketed and bisected when a step leaves the bracket.

Relative precision about 1e-13 over the parameters the library uses (``tests/modal/test_quantiles.py``
compares with scipy.special).
"""
from __future__ import annotations

import math

import numpy as np

__all__ = ["gamma_lower", "gamma_upper", "gamma_lower_inverse", "gamma_upper_inverse", "beta_lower",
           "beta_upper", "chi2_upper_quantile", "f_survival", "f_upper_quantile"]

_EPS = 2.0**-53
_TINY = 1e-300
_HALF_LOG_2PI = 0.5 * math.log(2.0 * math.pi)
#: parameters from which log Γ is taken as Stirling's series (its correction then exact to 1e-17)
_STIRLING_FROM = 10.0
#: coefficients of Stirling's series of log Γ(z) - ((z - 1/2) log z - z + log √(2π)) in odd powers of 1/z
_STIRLING = (1 / 12, -1 / 360, 1 / 1260, -1 / 1680, 1 / 1188, -691 / 360360, 1 / 156)


def _stirling_correction(z: float) -> float:
    """``log Γ(z) - ((z - 1/2) log z - z + log √(2π))`` for ``z >= 10`` (error below 1e-17)."""
    w = 1.0 / (z * z)
    total = 0.0
    for c in reversed(_STIRLING):
        total = total * w + c
    return total / z


def _log1p_minus(ratio, u):
    """``log(ratio) - u`` with ``ratio = 1 + u`` (both given: each precise where the other is not),
    to full relative precision also for small ``|u|`` (a series there)."""
    ratio, u = np.asarray(ratio, float), np.asarray(u, float)
    with np.errstate(divide="ignore", invalid="ignore"):
        direct = np.log(ratio) - u
    small = np.abs(u) < 0.25
    if not np.any(small):
        return direct
    v = np.where(small, u, 0.0)
    series = np.zeros_like(v)
    for k in range(40, 1, -1):  # -u²/2 + u³/3 - ...: 0.25^40 is far below one ulp
        series = (-1.0) ** (k + 1) / k + v * series
    return np.where(small, v * v * series, direct)


# --- incomplete gamma ----------------------------------------------------------------------------

def _log_gamma_kernel(a: float, x: float) -> float:
    """``log(x^a e^-x / Γ(a))``."""
    if a < _STIRLING_FROM:
        return a * math.log(x) - x - math.lgamma(a)
    return (a * float(_log1p_minus(x / a, (x - a) / a)) + 0.5 * math.log(a) - _HALF_LOG_2PI
            - _stirling_correction(a))


def _max_terms(*parameters: float) -> int:
    # the series and continued fractions take O(√max) terms where x is near the distribution's bulk
    return int(200 + 20 * math.sqrt(max(parameters)))


def _gamma_tails(a: float, x: float) -> tuple[float, float]:
    """``(P(a, x), Q(a, x))``, the smaller of the two computed directly."""
    if not (a > 0 and math.isfinite(a)) or math.isnan(x) or x < 0:
        raise ValueError(f"incomplete gamma: expected a > 0 finite and x >= 0, got a={a!r}, x={x!r}")
    if x == 0:
        return 0.0, 1.0
    if math.isinf(x):
        return 1.0, 0.0
    front = math.exp(_log_gamma_kernel(a, x))
    if x < a + 1:
        term = total = 1.0 / a
        for n in range(1, _max_terms(a, x)):
            term *= x / (a + n)
            total += term
            if abs(term) < abs(total) * _EPS:
                break
        p = front * total
        return p, 1.0 - p
    # Legendre's continued fraction of Q, evaluated by the modified Lentz method
    b = x + 1.0 - a
    c = 1.0 / _TINY
    d = 1.0 / b
    h = d
    for i in range(1, _max_terms(a, x)):
        an = -i * (i - a)
        b += 2.0
        d = an * d + b
        d = d if abs(d) > _TINY else _TINY
        c = b + an / c
        c = c if abs(c) > _TINY else _TINY
        d = 1.0 / d
        delta = d * c
        h *= delta
        if abs(delta - 1.0) <= 2 * _EPS:
            break
    q = front * h
    return 1.0 - q, q


def gamma_lower(a: float, x: float) -> float:
    """Regularised lower incomplete gamma function ``P(a, x)``, the Gamma(a, 1) distribution function."""
    return _gamma_tails(float(a), float(x))[0]


def gamma_upper(a: float, x: float) -> float:
    """Regularised upper incomplete gamma function ``Q(a, x) = 1 - P(a, x)``, to full relative precision
    in the far tail."""
    return _gamma_tails(float(a), float(x))[1]


def _normal_deviate(lower: float, upper: float) -> float:
    """Rough ``z`` with ``P(Z < z) = lower``, ``P(Z > z) = upper`` for a standard normal ``Z`` (error
    ~3e-3: a starting point), from the smaller of the two."""
    t = math.sqrt(-2.0 * math.log(min(lower, upper)))
    z = t - (2.30753 + 0.27061 * t) / (1.0 + t * (0.99229 + 0.04481 * t))
    return z if upper < lower else -z


def _solve(log_tail_and_slope, start: float, increasing: bool, target: float) -> float:
    """Root of ``log tail(t) = log target`` for a monotonic tail: Newton's method, kept inside the
    bracket the signs have shown so far (bisected, or widened geometrically, when a step leaves it)."""
    log_target = math.log(target)
    lo, hi = -math.inf, math.inf
    t = start
    for _ in range(400):
        log_tail, slope = log_tail_and_slope(t)
        g = log_tail - log_target
        if g == 0.0:
            return t
        if (g > 0) == increasing:
            hi = t
        else:
            lo = t
        new = t - g / slope if slope != 0 and math.isfinite(slope) and math.isfinite(g) else math.nan
        if abs(new - t) <= 4 * _EPS * max(1.0, abs(t)):
            return new  # converged (a step below the last digits may not leave t)
        if not lo < new < hi:
            if math.isinf(lo):
                new = hi - max(1.0, abs(hi))
            elif math.isinf(hi):
                new = lo + max(1.0, abs(lo))
            else:
                new = 0.5 * (lo + hi)
        if new in (lo, hi):
            return new  # the bracket closed to adjacent floats
        t = new
    raise ArithmeticError("quantile: Newton's method did not converge")  # pragma: no cover - a bug


def _gamma_quantile(a: float, lower: float, upper: float) -> float:
    """``x`` with ``P(a, x) = lower`` and ``Q(a, x) = upper`` (``lower + upper = 1``; the smaller one
    is the one used)."""
    if not (a > 0 and math.isfinite(a)):
        raise ValueError(f"incomplete gamma inverse: expected a > 0 finite, got a={a!r}")
    if not (0 <= lower <= 1 and 0 <= upper <= 1):
        raise ValueError(f"incomplete gamma inverse: expected a probability in [0, 1], got {min(lower, upper)!r}")
    if lower == 0:
        return 0.0
    if upper == 0:
        return math.inf
    use_lower = lower <= upper
    target = lower if use_lower else upper
    # start (Numerical Recipes' gammpinv): Wilson-Hilferty above a = 1, the leading terms of the tails below
    if a > 1:
        z = _normal_deviate(lower, upper)
        x0 = a * max(1e-3, 1.0 - 1.0 / (9 * a) + z / (3 * math.sqrt(a))) ** 3
    else:
        t = 1.0 - a * (0.253 + a * 0.12)
        x0 = (lower / t) ** (1 / a) if lower < t else 1.0 - math.log(upper / (1.0 - t))
    start = math.log(x0) if x0 > 0 else math.log(_TINY) / max(a, 1.0)

    def log_tail_and_slope(s):
        x = math.exp(s)
        p, q = _gamma_tails(a, x)
        tail = p if use_lower else q
        if tail <= 0:
            return -math.inf, math.nan
        # d tail / d log x = ± x^a e^-x / Γ(a)
        kernel = math.exp(_log_gamma_kernel(a, x))
        return math.log(tail), (kernel if use_lower else -kernel) / tail

    return math.exp(_solve(log_tail_and_slope, start, use_lower, target))


def gamma_lower_inverse(a: float, p: float) -> float:
    """``x`` with ``P(a, x) = p``: the ``p`` quantile of the Gamma(a, 1) distribution."""
    p = float(p)
    return _gamma_quantile(float(a), p, 1.0 - p)


def gamma_upper_inverse(a: float, q: float) -> float:
    """``x`` with ``Q(a, x) = q``: the upper ``q`` quantile of the Gamma(a, 1) distribution, to full
    relative precision for tiny ``q``."""
    q = float(q)
    return _gamma_quantile(float(a), 1.0 - q, q)


def chi2_upper_quantile(dof: float, tail: float) -> float:
    """Value a chi-square variable of ``dof`` degrees of freedom exceeds with probability ``tail``."""
    return 2.0 * gamma_upper_inverse(0.5 * float(dof), tail)


# --- incomplete beta -----------------------------------------------------------------------------

def _log_beta_front(a: float, b: float, x, y):
    """``log(x^a y^b / B(a, b))`` with ``y = 1 - x`` given (both to full relative precision)."""
    with np.errstate(divide="ignore", invalid="ignore"):
        if a >= _STIRLING_FROM and b >= _STIRLING_FROM:
            u = x * b - y * a  # x (a + b) - a = b - y (a + b): the distance from the mode
            return (a * _log1p_minus(x * (a + b) / a, u / a) + b * _log1p_minus(y * (a + b) / b, -u / b)
                    + 0.5 * math.log(a * b / (a + b))
                    - _HALF_LOG_2PI + _stirling_correction(a + b) - _stirling_correction(a) - _stirling_correction(b))
        if a >= _STIRLING_FROM and b < _STIRLING_FROM:
            return _log_beta_front(b, a, y, x)
        # log x and log y each from the smaller of x and y (log1p(-y) keeps log x's digits where x is near 1)
        log_x = np.where(x < 0.5, np.log(x), np.log1p(-y))
        log_y = np.where(y < 0.5, np.log(y), np.log1p(-x))
        if b >= _STIRLING_FROM:  # log Γ(a + b) - log Γ(b) through Stirling's series, a small
            return (a * (log_x + math.log(b)) + b * log_y - math.lgamma(a) + (a + b - 0.5) * math.log1p(a / b) - a
                    + _stirling_correction(a + b) - _stirling_correction(b))
        return a * log_x + b * log_y - (math.lgamma(a) + math.lgamma(b) - math.lgamma(a + b))


def _beta_fraction(a, b, x, y, terms: int):
    """Numerical Recipes' continued fraction of ``I_x(a, b) a B(a, b) / (x^a y^b)``, ``y = 1 - x`` (elementwise,
    by the modified Lentz method; each element leaves the iteration once its fraction has converged)."""
    a, b, x, y = (np.array(v, float).ravel() for v in np.broadcast_arrays(a, b, x, y))
    if x.size == 1:  # a quantile's search: the same fraction in floats, ten times quicker than in arrays
        return np.array([_beta_fraction_scalar(float(a[0]), float(b[0]), float(x[0]), float(y[0]), terms)])
    qab, qap, qam = a + b, a + 1.0, a - 1.0
    c = np.ones_like(x)
    # its first denominator 1 - (a + b) x / (a + 1), from y where x is near 1 (it cancels there)
    d = np.where(y < 0.5, (1.0 - b + qab * y) / qap, 1.0 - qab * x / qap)
    d = 1.0 / np.where(np.abs(d) < _TINY, _TINY, d)
    h = d.copy()
    out = np.empty_like(x)
    live = np.arange(x.size)  # elements still iterating
    for m in range(1, terms):
        m2 = 2 * m
        for aa in (m * (b - m) * x / ((qam + m2) * (a + m2)), -(a + m) * (qab + m) * x / ((a + m2) * (qap + m2))):
            d = 1.0 + aa * d
            d = 1.0 / np.where(np.abs(d) < _TINY, _TINY, d)
            c = 1.0 + aa / c
            c = np.where(np.abs(c) < _TINY, _TINY, c)
            delta = d * c
            h = h * delta
        done = np.abs(delta - 1.0) <= 2 * _EPS
        if done.any():
            out[live[done]] = h[done]
            keep = ~done
            live, a, b, x, qab, qap, qam, c, d, h = (v[keep] for v in (live, a, b, x, qab, qap, qam, c, d, h))
            if live.size == 0:
                return out
    out[live] = h  # pragma: no cover - the fraction converges in O(√max(a, b)) terms
    return out


def _beta_fraction_scalar(a: float, b: float, x: float, y: float, terms: int) -> float:
    """:func:`_beta_fraction` of one ``x``."""
    qab, qap, qam = a + b, a + 1.0, a - 1.0
    c = 1.0
    d = (1.0 - b + qab * y) / qap if y < 0.5 else 1.0 - qab * x / qap
    d = 1.0 / (d if abs(d) >= _TINY else _TINY)
    h = d
    for m in range(1, terms):
        m2 = 2 * m
        for aa in (m * (b - m) * x / ((qam + m2) * (a + m2)), -(a + m) * (qab + m) * x / ((a + m2) * (qap + m2))):
            d = 1.0 + aa * d
            d = 1.0 / (d if abs(d) >= _TINY else _TINY)
            c = 1.0 + aa / c
            c = c if abs(c) >= _TINY else _TINY
            delta = d * c
            h *= delta
        if abs(delta - 1.0) <= 2 * _EPS:
            break
    return h


def _beta_tails(a: float, b: float, x, y):
    """``(I_x(a, b), 1 - I_x(a, b))`` elementwise for ``x`` and ``y = 1 - x`` given, each to full relative
    precision where it is the smaller."""
    if not (a > 0 and b > 0 and math.isfinite(a) and math.isfinite(b)):
        raise ValueError(f"incomplete beta: expected a, b > 0 finite, got a={a!r}, b={b!r}")
    x, y = np.broadcast_arrays(np.asarray(x, float), np.asarray(y, float))
    swap = x >= (a + 1.0) / (a + b + 2.0)  # there the fraction converges on 1 - x, with a and b swapped
    xs, ys, aa, bb = np.where(swap, y, x), np.where(swap, x, y), np.where(swap, b, a), np.where(swap, a, b)
    front = np.where(swap, _log_beta_front(b, a, y, x), _log_beta_front(a, b, x, y))
    direct = np.exp(front) * _beta_fraction(aa, bb, xs, ys, _max_terms(a, b)).reshape(xs.shape) / aa
    lower = np.where(swap, 1.0 - direct, direct)
    upper = np.where(swap, direct, 1.0 - direct)
    return lower, upper


def beta_lower(a: float, b: float, x):
    """Regularised incomplete beta function ``I_x(a, b)``, the Beta(a, b) distribution function (any
    array of ``x`` in [0, 1])."""
    x = np.asarray(x, float)
    return _beta_tails(float(a), float(b), x, 1.0 - x)[0]


def beta_upper(a: float, b: float, x):
    """``1 - I_x(a, b)``, computed directly where it is small."""
    x = np.asarray(x, float)
    return _beta_tails(float(a), float(b), x, 1.0 - x)[1]


def f_survival(dfn: float, dfd: float, f):
    """Probability that an F(dfn, dfd) variable exceeds ``f`` (elementwise; ``f >= 0``), to full relative
    precision also in the far tail."""
    dfn, dfd = float(dfn), float(dfd)
    f = np.asarray(f, float)
    if np.any(f < 0):
        raise ValueError("F survival: expected f >= 0")
    finite = np.isfinite(f)
    fx = np.where(finite, f, 0.0)
    scale = dfd + dfn * fx
    x, y = dfd / scale, dfn * fx / scale  # P(F > f) = I_x(dfd/2, dfn/2), x = dfd / (dfd + dfn f)
    upper = _beta_tails(0.5 * dfd, 0.5 * dfn, x, y)[0]
    return np.where(finite, upper, np.where(np.isnan(f), np.nan, 0.0))


def _logistic(t: float) -> float:
    """``1 / (1 + e^-t)``, without overflow."""
    return 1.0 / (1.0 + math.exp(-t)) if t > -700 else math.exp(t)


def f_upper_quantile(dfn: float, dfd: float, tail: float) -> float:
    """Value an F(dfn, dfd) variable exceeds with probability ``tail``."""
    dfn, dfd, tail = float(dfn), float(dfd), float(tail)
    if not (dfn > 0 and dfd > 0 and math.isfinite(dfn) and math.isfinite(dfd)):
        raise ValueError(f"F quantile: expected degrees of freedom > 0 finite, got {dfn!r}, {dfd!r}")
    if not 0 <= tail <= 1:
        raise ValueError(f"F quantile: expected a probability in [0, 1], got {tail!r}")
    if tail == 0:
        return math.inf
    if tail == 1:
        return 0.0
    # tail = I_x(a, b), a = dfd/2, b = dfn/2, x = dfd / (dfd + dfn F): solved over t = log(x / (1 - x)),
    # so that F = (dfd / dfn) e^-t keeps its precision at both ends
    a, b = 0.5 * dfd, 0.5 * dfn
    lower, upper = tail, 1.0 - tail
    use_lower = lower <= upper
    target = lower if use_lower else upper
    # start (Numerical Recipes' invbetai)
    if a >= 1 and b >= 1:
        z = -_normal_deviate(lower, upper)  # the deviate whose upper tail is `lower`, as invbetai takes it
        al = (z * z - 3.0) / 6.0
        h = 2.0 / (1.0 / (2 * a - 1) + 1.0 / (2 * b - 1))
        w = z * math.sqrt(al + h) / h - (1.0 / (2 * b - 1) - 1.0 / (2 * a - 1)) * (al + 5.0 / 6.0 - 2.0 / (3.0 * h))
        start = math.log(a / b) - 2.0 * w  # x = a / (a + b e^2w)
    else:
        lna, lnb = math.log(a / (a + b)), math.log(b / (a + b))
        ta, tb = math.exp(a * lna) / a, math.exp(b * lnb) / b
        w = ta + tb
        if lower < ta / w:
            log_x = math.log(a * w * lower) / a
            start = log_x - math.log(-math.expm1(log_x)) if log_x < 0 else 0.0
        else:
            log_y = math.log(b * w * upper) / b
            start = math.log(-math.expm1(log_y)) - log_y if log_y < 0 else 0.0

    def log_tail_and_slope(t):
        x, y = _logistic(t), _logistic(-t)
        lo, up = _beta_tails(a, b, x, y)
        value = float(lo if use_lower else up)
        if value <= 0:
            return -math.inf, math.nan
        # d I / d t = x^a y^b / B(a, b)
        front = math.exp(float(_log_beta_front(a, b, x, y)))
        return math.log(value), (front if use_lower else -front) / value

    t = _solve(log_tail_and_slope, start, use_lower, target)
    return (dfd / dfn) * math.exp(-t) if -t < 709.0 else math.inf  # beyond the largest float
