"""Stability verdicts of the balanced state without eigenvalues.

The balanced state's linearisation ``det(s^2 M0 + s C0 + K0)`` (nondimensional, see
:func:`~balancer.adb.stability.linearised_matrices`) factors in closed form for any
number of balls ``n >= 2``.  The ball block of ``s^2 M0 + s C0 + K0`` is
``s (s + beta) I_n``; its Schur complement is the 2x2 matrix
``alpha I + gamma J + delta R`` with ``J = [[0, -1], [1, 0]]``,
``R = [[C2, S2], [S2, -C2]]``, ``C2 + i S2 = sum_i exp(2 i phi_i)`` and::

    alpha = s (s + beta) (s^2 + 2 zeta s + 1 - Omega^2) - (mu n / 2) ((s^2 - Omega^2)^2 - 4 Omega^2 s^2)
    gamma = 2 Omega s (s + beta) (s + zeta) - 2 mu n Omega s (s^2 - Omega^2)
    delta = (mu / 2) (s^2 + Omega^2)^2

so that ``det = (s (s + beta))^(n - 2) P8(s)`` with ``P8 = alpha^2 + gamma^2 - rho^2 delta^2``,
``rho = |sum_i exp(2 i phi_i)|``.  The ``n - 2`` roots at 0 are the balanced family's
(dropped by the eigenvalue path too), the ``n - 2`` roots at ``-beta`` are stable for
``beta > 0``; the verdict rests on the degree-8 ``P8``.

The verdict needs no root: ``P8(z - tau)`` Hurwitz means every growth rate is below
``-tau`` (stable), ``P8(z + tau)`` not Hurwitz means one is above ``+tau`` (unstable).
A plain Routh pass on ``P8`` says which of the two to certify; the certifying pass is a
vectorised Routh array with a first-order running bound of its rounding error (from a
bound of the coefficients' own rounding).  Where a first-column entry is not clearly
above its bound, or the growth rate may lie within ``tau`` of zero, the point is
*unresolved* and the caller falls back to the eigenvalue path
(:func:`~balancer.adb.linear.eigen_analysis_nondimensional`), which keeps its honest
marginal class there.  ``tau`` is ``2 x 10 cap eps N`` with ``N`` an upper bound of the
Frobenius norm of the scaled first-order matrix: outside that band the screened
eigenvalue path (condition cap ``cap``) classifies by the sign of the growth rate alone,
so the two paths give the same verdict wherever the Routh path resolves a point.

Cost: about 0.5 us per point against about 7 us for the eigenvalues of one 8x8 matrix
(``python -m benchmarks.bench_speed``).
"""
from __future__ import annotations

import numpy as np

from .linear import STABLE, UNSTABLE

__all__ = ["balanced_polynomial", "balanced_verdicts", "routh_verdicts", "UNRESOLVED"]

#: verdict code of a point the Routh test leaves to the eigenvalue path
UNRESOLVED = 0
_EPS = np.finfo(float).eps
#: rounding-error multiple assumed for each formed coefficient (a few dozen flops each)
_COEFFICIENT_FLOPS = 64.0
#: a first-column entry counts only when it exceeds this multiple of its error bound
_SAFETY = 100.0


def _square(c: list, sign: float = 1.0) -> list:
    """Coefficients of ``sign * c(z)^2`` (lists of arrays, lowest power first; None is zero)."""
    out = [None] * (2 * len(c) - 1)
    for i, x in enumerate(c):
        if x is None:
            continue
        for j in range(i, len(c)):
            y = c[j]
            if y is None:
                continue
            term = x * y if i == j else 2.0 * x * y
            out[i + j] = sign * term if out[i + j] is None else out[i + j] + sign * term
    return out


def balanced_polynomial(mu, zeta, beta, speed_ratio, rho2, n, *, magnitude: bool = False) -> np.ndarray:
    """Coefficients of ``P8`` (lowest power first) for a batch of balanced states.

    Parameters
    ----------
    mu, zeta, beta : array_like
        Ball mass ratio, support damping ratio and ball drag ratio (-).
    speed_ratio : array_like
        ``Omega = omega / omega_n`` (-).
    rho2 : array_like
        ``|sum_i exp(2 i phi_i)|^2`` of the balanced ball angles (-).
    n : int
        Ball count.
    magnitude : bool
        Return instead the same sums with every term taken in absolute value: the size of
        what was summed, whose product with a few dozen ``eps`` bounds the rounding error.

    Returns
    -------
    ndarray, shape (9, ...)
        Coefficients of ``s^0 .. s^8`` (broadcast shape of the inputs); with
        ``det(s^2 M0 + s C0 + K0) = (s (s + beta))^(n - 2) P8(s)``.
    """
    mu, zeta, beta, Om, rho2 = np.broadcast_arrays(*(np.asarray(x, dtype=float) for x in (
        mu, zeta, beta, speed_ratio, rho2)))
    sign = 1.0 if magnitude else -1.0
    h = 0.5 * mu * n
    Om2 = Om * Om
    Om4 = Om2 * Om2
    one = np.ones_like(Om)
    # alpha = (1-h) s^4 + (2 zeta + beta) s^3 + (1 - Om^2 + 2 zeta beta + 6 h Om^2) s^2
    #         + beta (1 - Om^2) s - h Om^4
    alpha = [sign * h * Om4, beta * (1 + sign * Om2), 1 + sign * Om2 + 2 * zeta * beta + 6 * h * Om2,
             2 * zeta + beta, 1 + sign * h]
    # gamma = 2 Om ((1 - 2h) s^3 + (zeta + beta) s^2 + (beta zeta + 2 h Om^2) s)
    gamma = [None, 2 * Om * (beta * zeta + 2 * h * Om2), 2 * Om * (zeta + beta), 2 * Om * (1 + sign * 2 * h)]
    # delta = (mu / 2) (s^2 + Om^2)^2
    delta = [0.5 * mu * Om4, None, mu * Om2, None, 0.5 * mu * one]
    out = _square(alpha)
    for k, term in enumerate(_square(gamma)):
        if term is not None:
            out[k] = out[k] + term
    for k, term in enumerate(_square(delta, sign)):
        if term is not None:
            out[k] = out[k] + rho2 * term
    return np.stack(out)


def _taylor_shift(coefficients: list, sigma: np.ndarray) -> list:
    """Coefficients of ``c(z + sigma)`` from those of ``c(s)`` (lists of arrays, lowest first)."""
    out = list(coefficients)
    degree = len(out) - 1
    for i in range(degree):
        for j in range(degree - 1, i - 1, -1):
            out[j] = out[j] + sigma * out[j + 1]
    return out


def _plain_routh_stable(high: list) -> np.ndarray:
    """Whether the Routh array of ``high`` (highest power first) has a positive first column.

    No error bound: a cheap first pass that says which side of the boundary to certify.
    """
    rows = [high[0::2], high[1::2]]
    positive = (rows[0][0] > 0) & (rows[1][0] > 0)
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        for _ in range(len(high) - 2):
            upper, lower = rows[-2], rows[-1]
            ratio = upper[0] / lower[0]
            new = [upper[j + 1] - ratio * lower[j + 1] if j + 1 < len(lower) else upper[j + 1]
                   for j in range(len(upper) - 1)]
            rows.append(new)
            positive &= new[0] > 0
    return positive


def routh_verdicts(coefficients: list, errors: list) -> tuple[np.ndarray, np.ndarray]:
    """Vectorised Routh test with a first-order running bound of the rounding error.

    Parameters
    ----------
    coefficients : list of ndarray
        Polynomial coefficients, lowest power first (leading one last, positive).
    errors : list of ndarray
        Absolute error bounds of the coefficients.

    Returns
    -------
    hurwitz, not_hurwitz : ndarray of bool
        Certified Hurwitz (every first-column entry clearly positive) and certified not
        Hurwitz (a clearly negative first-column entry, or coefficient, before any entry
        that is not clear).  Neither where the rounding bound leaves the answer open.
    """
    high = coefficients[::-1]
    err = errors[::-1]
    degree = len(high) - 1
    rows = [high[0::2], high[1::2]]
    bounds = [err[0::2], err[1::2]]
    clear = np.ones(high[0].shape, dtype=bool)  # every entry so far above its bound
    negative = np.zeros(high[0].shape, dtype=bool)  # a clear negative entry found while clear
    # a clearly negative coefficient (leading one positive) already rules out Hurwitz
    for value, bound in zip(high, err):
        negative |= value < -_SAFETY * bound
    for row, bound in zip(rows, bounds):
        first_clear = np.abs(row[0]) > _SAFETY * bound[0]
        negative |= clear & first_clear & (row[0] < 0)
        clear &= first_clear
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        for _ in range(degree - 1):
            upper, lower = rows[-2], rows[-1]
            e_upper, e_lower = bounds[-2], bounds[-1]
            ratio = upper[0] / lower[0]
            size = np.abs(ratio)
            e_ratio = size * (e_upper[0] / np.abs(upper[0]) + e_lower[0] / np.abs(lower[0]) + _EPS)
            new, e_new = [], []
            for j in range(len(upper) - 1):
                lj = lower[j + 1] if j + 1 < len(lower) else 0.0
                e_lj = e_lower[j + 1] if j + 1 < len(lower) else 0.0
                term = ratio * lj
                value = upper[j + 1] - term
                new.append(value)
                e_new.append(e_upper[j + 1] + size * e_lj + e_ratio * np.abs(lj)
                             + _EPS * (np.abs(upper[j + 1]) + 2 * np.abs(term)))
            rows.append(new)
            bounds.append(e_new)
            first_clear = np.abs(new[0]) > _SAFETY * e_new[0]
            negative |= clear & first_clear & (new[0] < 0)
            clear &= first_clear
    positive = np.ones(high[0].shape, dtype=bool)
    for row in rows:
        positive &= row[0] > 0
    return clear & positive, negative


def _norm_bound(mu, zeta, beta, Om, rho, n) -> np.ndarray:
    """Upper bound of the Frobenius norm of ``[[0, I], [-M0^-1 K0, -M0^-1 C0]]``.

    ``M0 = diag(I, mu^-1/2) [[I, X^T], [X, I]] diag(I, mu^1/2)`` with ``X = sqrt(mu) P``,
    ``P^T P = n/2 I - R/2``: ``||M0^-1|| <= 1 / (sqrt(mu) (1 - sqrt(mu (n + rho) / 2)))``;
    the Frobenius norms of ``K0`` and ``C0`` are sums of their squared entries.
    """
    Om2 = Om * Om
    k2 = 2 * (1 - Om2) ** 2 + 8 * (zeta * Om) ** 2 + n * Om2 * Om2 * (mu * mu + 1)
    c2 = 8 * zeta * zeta + 8 * Om2 + 4 * n * Om2 * (mu * mu + 1) + n * beta * beta
    with np.errstate(divide="ignore", invalid="ignore"):
        gap = 1.0 - np.sqrt(mu * (n + rho) / 2.0)
        inverse = np.where(gap > 0, 1.0 / (np.sqrt(mu) * gap), np.inf)
    return np.sqrt(2 * (n + 2) + inverse * inverse * (k2 + c2))


def balanced_verdicts(mu, zeta, beta, speed_ratio, rho2, n, condition_cap: float, *, norm=None) -> np.ndarray:
    """STABLE, UNSTABLE or UNRESOLVED for each balanced state of a batch, without eigenvalues.

    Parameters
    ----------
    mu, zeta, beta, speed_ratio, rho2 : ndarray, shape (B,)
        As in :func:`balanced_polynomial`.
    n : int
        Ball count (>= 2).
    condition_cap : float
        The eigenvalue path's screening cap; sets the band ``|growth| < tau`` left to it.
    norm : ndarray, shape (B,), optional
        Frobenius norm of each scaled first-order matrix, when the caller has it; default
        an upper bound from the parameters (up to ~1/sqrt(mu) times larger, so a wider band).

    Returns
    -------
    ndarray of int, shape (B,)
        ``STABLE`` (1) where every growth rate is certified below ``-tau``, ``UNSTABLE``
        (-1) where one is certified above ``+tau``, ``UNRESOLVED`` (0) elsewhere.
    """
    arrays = np.broadcast_arrays(*(np.asarray(x, dtype=float) for x in (mu, zeta, beta, speed_ratio, rho2)))
    shape = arrays[0].shape
    mu, zeta, beta, Om, rho2 = (np.ravel(x) for x in arrays)
    norm = _norm_bound(mu, zeta, beta, Om, np.sqrt(rho2), n) if norm is None else np.ravel(norm)
    tau = 2.0 * 10.0 * float(condition_cap) * _EPS * norm
    values = list(balanced_polynomial(mu, zeta, beta, Om, rho2, n))
    magnitude = balanced_polynomial(mu, zeta, beta, Om, rho2, n, magnitude=True)
    # which side to certify: P8(z - tau) Hurwitz (stable) or P8(z + tau) not Hurwitz (unstable)
    side_stable = _plain_routh_stable(values[::-1])
    sigma = np.where(side_stable, -tau, tau)
    coefficients = _taylor_shift(values, sigma)
    # rounding of the coefficients (a few dozen flops each) and of the shift (two per term)
    errors = _taylor_shift([_COEFFICIENT_FLOPS * _EPS * m + 2 * 8 * _EPS * np.abs(v)
                            for m, v in zip(magnitude, values)], np.abs(sigma))
    hurwitz, not_hurwitz = routh_verdicts(coefficients, errors)
    finite = np.isfinite(tau)
    stable = side_stable & hurwitz & finite
    if n > 2:  # the n - 2 roots at -beta
        stable &= beta > tau
    unstable = ~side_stable & not_hurwitz & finite
    codes = np.full(Om.shape[0], UNRESOLVED, dtype=int)
    codes[stable] = STABLE
    codes[unstable] = UNSTABLE
    return codes.reshape(shape)
