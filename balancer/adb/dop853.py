"""A lean DOP853 (explicit Runge-Kutta 8(5,3), Dormand-Prince / Hairer) for ``t_eval`` output.

The same method, error norm, step-size control, first-step choice and 7th-degree dense
output as ``scipy.integrate.solve_ivp(method="DOP853", t_eval=...)``, in one loop: no
solver, wrapper or interpolant objects per step, and no import of ``scipy.integrate``
(whose package import also loads ``scipy.optimize``: ~0.1-0.2 s, more than a scene's
run-up takes to integrate).  The arithmetic is SciPy's, operation for operation, so the
samples agree with ``solve_ivp`` to rounding (tests/balancer/adb/test_dop853.py).

The local error per step is kept below ``atol + rtol |y|`` (RMS norm over components),
as in SciPy.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable

import numpy as np


def _coefficients():
    """Hairer's DOP853 coefficients as SciPy tabulates them (``scipy/integrate/_ivp/dop853_coefficients.py``),
    read from SciPy's installed file without importing the ``scipy.integrate`` package (whose import
    costs ~0.1-0.2 s); a SciPy that keeps the table elsewhere gets the regular import."""
    import importlib.util
    from pathlib import Path

    import scipy

    path = Path(scipy.__file__).parent / "integrate" / "_ivp" / "dop853_coefficients.py"
    if path.is_file():
        spec = importlib.util.spec_from_file_location(f"{__name__}._scipy_coefficients", path)
        module = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(module)
        return module
    from scipy.integrate._ivp import dop853_coefficients  # pragma: no cover - another SciPy layout

    return dop853_coefficients


_co = _coefficients()
__all__ = ["DOP853Result", "dop853"]

_N = _co.N_STAGES
_A = _co.A[:_N, :_N]
_B = _co.B
_C = _co.C[:_N]
_E3, _E5, _D = _co.E3, _co.E5, _co.D
_A_EXTRA = _co.A[_N + 1:]
_C_EXTRA = _co.C[_N + 1:]
_SAFETY, _MIN_FACTOR, _MAX_FACTOR = 0.9, 0.2, 10.0
_ERROR_EXPONENT = -1.0 / 8.0  # error estimator of order 7


@dataclass(frozen=True)
class DOP853Result:
    """Samples of a DOP853 run, laid out as ``solve_ivp``'s result.

    Attributes
    ----------
    t : ndarray, shape (T,)
        The requested sample times (those reached, if the run failed).
    y : ndarray, shape (n, T)
        States at ``t``.
    nfev : int
        Evaluations of the right-hand side.
    status : int
        0 on success, -1 if the step size fell below what the times can resolve.
    message : str
    """

    t: np.ndarray
    y: np.ndarray
    nfev: int
    status: int
    message: str


def _rms(x: np.ndarray) -> float:
    return float(np.linalg.norm(x) / x.size ** 0.5)


def _first_step(fun, t0: float, y0: np.ndarray, f0: np.ndarray, span: float, rtol: float, atol) -> float:
    """Hairer, Norsett & Wanner's starting step (Solving ODEs I, Sec. II.4), as SciPy's."""
    scale = atol + np.abs(y0) * rtol
    d0 = _rms(y0 / scale)
    d1 = _rms(f0 / scale)
    h0 = 1e-6 if d0 < 1e-5 or d1 < 1e-5 else 0.01 * d0 / d1
    h0 = min(h0, span)
    f1 = np.asarray(fun(t0 + h0, y0 + h0 * f0), dtype=float)
    d2 = _rms((f1 - f0) / scale) / h0
    if d1 <= 1e-15 and d2 <= 1e-15:
        h1 = max(1e-6, h0 * 1e-3)
    else:
        h1 = (0.01 / max(d1, d2)) ** (1.0 / 8.0)
    return min(100 * h0, h1, span)


def dop853(fun: Callable[[float, np.ndarray], np.ndarray], t_span: tuple[float, float], y0, t_eval, *,
           rtol: float, atol) -> DOP853Result:
    """Integrate ``y' = fun(t, y)`` forward over ``t_span`` and sample the solution at ``t_eval``.

    Parameters
    ----------
    fun : callable
        ``fun(t, y) -> ndarray`` of the shape of ``y`` (real).
    t_span : (float, float)
        Start and end time (s), ``t0 < t1``.
    y0 : array_like, shape (n,)
        State at ``t0``.
    t_eval : array_like, shape (T,)
        Increasing sample times within ``t_span``.
    rtol : float
        Relative tolerance of the local error.
    atol : float or array_like, shape (n,)
        Absolute tolerance of the local error, per component.

    Returns
    -------
    DOP853Result
        As ``solve_ivp(fun, t_span, y0, method="DOP853", t_eval=t_eval, rtol=rtol, atol=atol)``.
    """
    t, t_bound = float(t_span[0]), float(t_span[1])
    y = np.asarray(y0, dtype=float).copy()
    n = y.size
    times = np.asarray(t_eval, dtype=float)
    atol = np.asarray(atol, dtype=float)
    sqrt = math.sqrt
    # plain-float stage times (the same IEEE arithmetic as numpy scalars, cheaper in the right-hand side)
    a_rows = [(a[:s], float(c)) for s, (a, c) in enumerate(zip(_A[1:], _C[1:]), start=1)]
    a_extra = [(a[:s], float(c)) for s, (a, c) in enumerate(zip(_A_EXTRA, _C_EXTRA), start=_N + 1)]
    f = np.asarray(fun(t, y), dtype=float)
    h_abs = _first_step(fun, t, y, f, t_bound - t, rtol, atol)
    nfev = 2  # f and the first-step probe
    K = np.empty((_co.N_STAGES_EXTENDED, n))
    K_step = K[:_N + 1]
    samples_t, samples_y = [], []
    index = 0  # first sample not yet produced
    status, message = 0, "The solver successfully reached the end of the integration interval."
    while t < t_bound:
        min_step = 10 * abs(math.nextafter(t, math.inf) - t)
        h_abs = max(h_abs, min_step)
        rejected = False
        while True:
            if h_abs < min_step:
                status, message = -1, "Required step size is less than spacing between numbers."
                break
            t_new = t + h_abs
            if t_new - t_bound > 0:
                t_new = t_bound
            h = t_new - t
            h_abs = abs(h)
            # one step: the stages (as scipy.integrate._ivp.rk.rk_step)
            K[0] = f
            for s, (a, c) in enumerate(a_rows, start=1):
                K[s] = fun(t + c * h, y + np.dot(K[:s].T, a) * h)
            y_new = y + h * np.dot(K[:_N].T, _B)
            f_new = np.asarray(fun(t + h, y_new), dtype=float)
            nfev += _N
            K[_N] = f_new
            scale = atol + np.maximum(np.abs(y), np.abs(y_new)) * rtol
            err5 = np.dot(K_step.T, _E5) / scale
            err3 = np.dot(K_step.T, _E3) / scale
            err5_2 = sqrt(err5.dot(err5)) ** 2  # np.linalg.norm(x) ** 2, as SciPy, without its overhead
            err3_2 = sqrt(err3.dot(err3)) ** 2
            if err5_2 == 0 and err3_2 == 0:
                error = 0.0
            else:
                error = h_abs * err5_2 / sqrt((err5_2 + 0.01 * err3_2) * n)
            if error < 1:
                factor = _MAX_FACTOR if error == 0 else min(_MAX_FACTOR, _SAFETY * error ** _ERROR_EXPONENT)
                if rejected:
                    factor = min(1, factor)
                h_abs *= factor
                break
            h_abs *= max(_MIN_FACTOR, _SAFETY * error ** _ERROR_EXPONENT)
            rejected = True
        if status != 0:
            break
        t_old, y_old, t, y, f = t, y, t_new, y_new, f_new
        stop = int(times.searchsorted(t, side="right"))
        if stop > index:  # dense output on this step (as Dop853DenseOutput)
            for s, (a, c) in enumerate(a_extra, start=_N + 1):
                K[s] = fun(t_old + c * h, y_old + np.dot(K[:s].T, a) * h)
            nfev += len(a_extra)
            F = np.empty((_co.INTERPOLATOR_POWER, n))
            delta_y = y - y_old
            F[0] = delta_y
            F[1] = h * K[0] - delta_y
            F[2] = 2 * delta_y - h * (f + K[0])
            F[3:] = h * np.dot(_D, K)
            x = ((times[index:stop] - t_old) / h)[:, None]
            out = np.zeros((x.shape[0], n))
            for i, term in enumerate(F[::-1]):
                out += term
                if i % 2 == 0:
                    out *= x
                else:
                    out *= 1 - x
            out += y_old
            samples_t.append(times[index:stop])
            samples_y.append(out)
            index = stop
    t_out = np.concatenate(samples_t) if samples_t else np.zeros(0)
    y_out = np.concatenate(samples_y).T if samples_y else np.zeros((n, 0))
    return DOP853Result(t_out, y_out, nfev, status, message)
