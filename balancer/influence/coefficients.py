"""Influence coefficients and the correction that cancels the measured vibration.

Model: the 1x readings (several sensors, several speeds, stacked) depend linearly on
the unbalance added in the correction planes, ``v = v0 + alpha @ u``.  Trial runs
give ``alpha``; the correction is the ``u`` that makes ``v`` small:

* ``"least_squares"``: minimises ``sum |w_i v_i|^2`` (the classical method);
* ``"minmax"``: minimises ``max_i w_i |v_i|``, the worst reading.  It is a
  second-order cone problem, solved here by Kelley's cutting planes with linear
  programs (:func:`scipy.optimize.linprog`, HiGHS): each ``|v_i| <= t`` is replaced by
  the half-planes ``Re(v_i exp(-i phi)) <= t`` at directions ``phi``; after each LP, a
  cut at the direction of every residual that breaks its bound is added, until the
  true worst residual is within ``minmax_rtol`` (relative) of the LP's bound.  The LP
  bound is a lower bound of the true optimum, so the result is optimal to that
  tolerance; it is also compared with least squares and the better of the two kept,
  so min-max is never worse than least squares in its worst reading.

Phase convention and units: :mod:`balancer.influence.readings`.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from modal.errors import ParameterError, QualityWarning, warn

__all__ = [
    "CorrectionResult",
    "influence_matrix",
    "correction",
    "predict_residual",
    "CONDITION_WARNING",
    "TRIAL_EFFECT_WARNING",
]

CONDITION_WARNING = 100.0
"""Condition number of ``alpha`` above which the planes are called nearly dependent:
a relative reading error ``eps`` can then move the correction by up to ``cond * eps``
(1 % noise, 100 % correction error)."""

TRIAL_EFFECT_WARNING = 0.1
"""A trial run whose largest change is below this fraction of the largest initial
reading gives a poorly known influence coefficient (field practice asks for a change
of 20-30 % in amplitude or 20-30 deg in phase)."""

_RANK_TOLERANCE = 1e-10  # singular values below this times the largest: dependent planes


_SHAPES = {"initial": "(n_readings,)", "trial_runs": "(n_planes, n_readings)", "trial_unbalances": "(n_planes,)",
           "alpha": "(n_readings, n_planes)"}


def _complex_array(values, field: str, ndim: int) -> np.ndarray:
    try:
        array = np.asarray(values, dtype=complex)
    except (TypeError, ValueError):
        raise ParameterError(f"{field}: expected complex numbers, got {type(values).__name__}") from None
    if array.ndim != ndim:
        raise ParameterError(f"{field}: shape {array.shape}; expected {_SHAPES[field]}")
    if array.size == 0:
        raise ParameterError(f"{field}: empty; expected at least one value")
    flat = array.ravel()
    bad = np.flatnonzero(~np.isfinite(flat))
    if bad.size:
        index = np.unravel_index(int(bad[0]), array.shape)
        where = index[0] if ndim == 1 else tuple(int(i) for i in index)
        raise ParameterError(f"{field}[{where}] is {flat[bad[0]]}; expected a finite reading")
    return array


def influence_matrix(initial, trial_runs, trial_unbalances) -> np.ndarray:
    """Influence coefficients from an initial run and one trial run per plane.

    Parameters
    ----------
    initial : array_like of complex, shape (n_readings,)
        1x readings without trial mass (several sensors and speeds stacked), SI or
        any one unit (``alpha`` comes out in that unit per kg m).
    trial_runs : array_like of complex, shape (n_planes, n_readings)
        Row ``j``: the same readings with the trial mass on plane ``j`` only.
    trial_unbalances : array_like of complex, shape (n_planes,)
        Trial unbalances (kg m; angle in the complex phase).

    Returns
    -------
    ndarray of complex, shape (n_readings, n_planes)
        ``alpha[:, j] = (trial_runs[j] - initial) / trial_unbalances[j]``.

    Raises
    ------
    ParameterError
        Shapes that do not match (fewer runs than planes), non-finite readings, a
        zero trial unbalance, or a trial that changed no reading.
    """
    v0 = _complex_array(initial, "initial", 1)
    runs = np.asarray(trial_runs)
    if runs.ndim == 1 and runs.size == v0.size:
        runs = runs[None, :]
    runs = _complex_array(runs, "trial_runs", 2)
    trials = _complex_array(np.atleast_1d(np.asarray(trial_unbalances)), "trial_unbalances", 1)
    n_planes = trials.size
    if runs.shape[0] != n_planes:
        raise ParameterError(f"trial_runs: {runs.shape[0]} run(s) for {n_planes} plane(s) in trial_unbalances; "
                             "expected one trial run per plane")
    if runs.shape[1] != v0.size:
        raise ParameterError(f"trial_runs: {runs.shape[1]} readings per run but initial has {v0.size}; "
                             "expected the same readings (sensors x speeds) in every run")
    if v0.size < n_planes:
        raise ParameterError(f"initial: {v0.size} reading(s) for {n_planes} planes; expected at least one reading per plane")
    zero = np.flatnonzero(trials == 0)
    if zero.size:
        raise ParameterError(f"trial_unbalances[{int(zero[0])}] is 0; expected a non-zero trial unbalance")
    change = runs - v0[None, :]
    scale = max(float(np.max(np.abs(v0))), float(np.max(np.abs(runs))))
    for j in range(n_planes):
        largest = float(np.max(np.abs(change[j])))
        if largest <= 1e-12 * scale:
            raise ParameterError(f"trial_runs[{j}]: the trial mass on plane {j + 1} changed no reading "
                                 f"(largest change {largest:.3g}); expected a measurable effect: use a larger trial mass")
        if largest < TRIAL_EFFECT_WARNING * float(np.max(np.abs(v0))):
            warn(f"trial_runs[{j}]: the trial mass on plane {j + 1} changed the readings by at most "
                 f"{100 * largest / float(np.max(np.abs(v0))):.1f} % of the largest initial reading; its influence "
                 "coefficients are poorly known (aim for 20-30 %)", QualityWarning)
    return change.T / trials[None, :]


@dataclass(frozen=True, slots=True)
class CorrectionResult:
    """A correction and the vibration it is predicted to leave.

    Attributes
    ----------
    unbalance_kg_m : ndarray of complex, shape (n_planes,)
        Unbalance to **add** in each plane (kg m; angle against rotation from the mark).
    residual : ndarray of complex, shape (n_readings,)
        Predicted readings after the correction, ``initial + alpha @ unbalance_kg_m``
        (units of the readings).
    initial : ndarray of complex, shape (n_readings,)
        The readings before correction.
    worst_residual, rms_residual : float
        ``max |residual|`` and ``sqrt(mean |residual|^2)`` (units of the readings).
    worst_initial, rms_initial : float
        The same for the readings before correction.
    condition_number : float
        2-norm condition number of ``alpha`` (weighted rows).
    method : str
        ``"least_squares"`` or ``"minmax"``.
    objective : float
        The minimised quantity: weighted RMS (least squares) or weighted worst (min-max).
        With unequal weights, min-max's guarantee (never above least squares) holds for
        this weighted worst, not for ``worst_residual``.
    max_unbalance_kg_m : float
        Bound on each plane's correction (inf: none).
    bound_active : bool
        Whether some plane's correction is at the bound.
    minmax_gap : float
        Min-max only: relative gap between the solution's true worst residual and the
        LP's lower bound of the optimum (certificate of optimality); 0 for least squares.
    flags : tuple of str
        ``"ill_conditioned"`` (planes nearly dependent), ``"bound_active"``.
    """

    unbalance_kg_m: np.ndarray
    residual: np.ndarray
    initial: np.ndarray
    worst_residual: float
    rms_residual: float
    worst_initial: float
    rms_initial: float
    condition_number: float
    method: str
    objective: float
    max_unbalance_kg_m: float
    bound_active: bool
    minmax_gap: float
    flags: tuple[str, ...]


def predict_residual(alpha, initial, unbalance_kg_m) -> np.ndarray:
    """Predicted readings ``initial + alpha @ unbalance_kg_m`` after adding the unbalances."""
    return np.asarray(initial, dtype=complex) + np.asarray(alpha, dtype=complex) @ np.asarray(unbalance_kg_m, dtype=complex)


def _weights(weights, n: int) -> np.ndarray:
    if weights is None:
        return np.ones(n)
    w = np.asarray(weights, dtype=float)
    if w.shape != (n,):
        raise ParameterError(f"weights: shape {w.shape}; expected ({n},), one per reading")
    if not np.all(np.isfinite(w)) or np.any(w <= 0):
        raise ParameterError("weights: expected finite values > 0")
    return w


def _least_squares(a: np.ndarray, b: np.ndarray, bound: float) -> np.ndarray:
    """min ||a u + b|| subject to |u_j| <= bound (SLSQP from the clipped unconstrained answer)."""
    u = np.linalg.lstsq(a, -b, rcond=None)[0]
    if not math.isfinite(bound) or np.all(np.abs(u) <= bound):
        return u
    from scipy.optimize import minimize

    p = a.shape[1]
    ar = np.block([[a.real, -a.imag], [a.imag, a.real]])
    br = np.concatenate([b.real, b.imag])
    scale = float(np.max(np.abs(br)))
    start = np.where(np.abs(u) > bound, u / np.abs(u) * bound * (1 - 1e-9), u)
    x0 = np.concatenate([start.real, start.imag]) / bound

    def objective(x):
        r = ar @ (x * bound) + br
        return float(r @ r) / scale**2, 2 * bound * (ar.T @ r) / scale**2

    constraints = {"type": "ineq", "fun": lambda x: 1.0 - x[:p] ** 2 - x[p:] ** 2,
                   "jac": lambda x: np.hstack([np.diag(-2 * x[:p]), np.diag(-2 * x[p:])])}
    sol = minimize(objective, x0, jac=True, method="SLSQP", constraints=[constraints],
                   options={"ftol": 1e-15, "maxiter": 500})
    x = sol.x * bound
    u = x[:p] + 1j * x[p:]
    over = np.abs(u) > bound
    u[over] *= bound / np.abs(u[over])
    return u


def _minmax(a: np.ndarray, b: np.ndarray, bound: float, rtol: float, max_iterations: int) -> tuple[np.ndarray, float]:
    """min_u max_i |a_i u + b_i| (|u_j| <= bound) by cutting planes; returns (u, relative gap)."""
    # scale to order one (HiGHS's tolerances are absolute): b by its largest reading,
    # u by the unbalance that moves the largest reading by that much
    s = float(np.max(np.abs(b))) or 1.0
    c = s / float(np.max(np.abs(a)))
    u_scaled, gap = _minmax_scaled(a * (c / s), b / s, bound / c, rtol, max_iterations)
    return u_scaled * c, gap


def _minmax_scaled(a: np.ndarray, b: np.ndarray, bound: float, rtol: float, max_iterations: int) -> tuple[np.ndarray, float]:
    n, p = a.shape
    # variables x = [Re u (p), Im u (p), t]; cut at direction phi for reading i:
    # Re((a_i u + b_i) e^{-i phi}) <= t  <=>  Re(a_i e^{-i phi}) Re u - Im(a_i e^{-i phi}) Im u - t <= -Re(b_i e^{-i phi})
    rows: list[np.ndarray] = []
    rhs: list[float] = []

    def add_reading_cut(i: int, phi: float) -> None:
        rot = np.exp(-1j * phi)
        ai = a[i] * rot
        rows.append(np.concatenate([ai.real, -ai.imag, [-1.0]]))
        rhs.append(-float((b[i] * rot).real))

    def add_bound_cut(j: int, phi: float) -> None:
        row = np.zeros(2 * p + 1)
        row[j], row[p + j] = math.cos(phi), math.sin(phi)
        rows.append(row)
        rhs.append(bound)

    for phi in np.arange(8) * (2 * math.pi / 8):
        for i in range(n):
            add_reading_cut(i, phi)
        if math.isfinite(bound):
            for j in range(p):
                add_bound_cut(j, phi)
    # scipy.optimize where the min-max correction runs, not at import: it was most of the import time of
    # every `balancer influence` run, which by default solves least squares
    from scipy.optimize import linprog

    cost = np.zeros(2 * p + 1)
    cost[-1] = 1.0
    u = np.zeros(p, dtype=complex)
    gap = math.inf
    for iteration in range(max_iterations):
        sol = linprog(cost, A_ub=np.array(rows), b_ub=np.array(rhs), bounds=[(None, None)] * (2 * p + 1), method="highs",
                      options={"primal_feasibility_tolerance": 1e-10, "dual_feasibility_tolerance": 1e-10})
        if sol.status != 0:
            raise ParameterError(f"min-max correction: the linear program failed ({sol.message})")
        x = sol.x
        u = x[:p] + 1j * x[p:2 * p]
        lower = float(x[-1])
        r = a @ u + b
        worst = float(np.max(np.abs(r)))
        over_bound = math.isfinite(bound) and float(np.max(np.abs(u))) > bound * (1 + rtol)
        # relative gap; below 1e-12 of the largest initial reading (scaled to 1) the readings are cancelled
        gap = (worst - lower) / worst if worst > 1e-12 else 0.0
        if gap <= rtol and not over_bound:
            break
        for i in np.flatnonzero(np.abs(r) > lower * (1 + rtol)):
            add_reading_cut(int(i), float(np.angle(r[i])))
        if math.isfinite(bound):
            for j in np.flatnonzero(np.abs(u) > bound * (1 + rtol)):
                add_bound_cut(int(j), float(np.angle(u[j])))
    else:
        warn(f"min-max correction: not converged in {max_iterations} cutting-plane iterations "
             f"(gap {gap:.2g} > {rtol:.2g}); the result is the best found", QualityWarning)
    if math.isfinite(bound):
        over = np.abs(u) > bound
        u[over] *= bound / np.abs(u[over])
    return u, max(gap, 0.0)


def correction(alpha, initial, method: str = "least_squares", weights=None, max_unbalance_kg_m=None,
               *, minmax_rtol: float = 1e-6, max_iterations: int = 500) -> CorrectionResult:
    """The unbalance to add in each plane so that the predicted vibration is smallest.

    Parameters
    ----------
    alpha : array_like of complex, shape (n_readings, n_planes)
        Influence coefficients (readings' unit per kg m), e.g. from :func:`influence_matrix`.
    initial : array_like of complex, shape (n_readings,)
        Readings to cancel.
    method : {"least_squares", "minmax"}
        Minimise the weighted sum of squares, or the weighted worst reading (see module notes).
    weights : array_like of float, shape (n_readings,), optional
        Positive weight per reading (e.g. 1 / alarm limit of that sensor); default 1.
    max_unbalance_kg_m : float, optional
        Largest correction allowed in any plane (kg m); default none.
    minmax_rtol : float
        Min-max only: relative optimality tolerance of the cutting-plane solution.
    max_iterations : int
        Min-max only: cutting-plane iterations before giving up with a warning.

    Returns
    -------
    CorrectionResult

    Raises
    ------
    ParameterError
        Mismatched shapes, non-finite values, unknown method, or a singular ``alpha``
        (dependent planes: no unique correction).

    Warns
    -----
    QualityWarning
        When ``alpha``'s condition number exceeds :data:`CONDITION_WARNING`.
    """
    a = _complex_array(alpha, "alpha", 2)
    v0 = _complex_array(initial, "initial", 1)
    if a.shape[0] != v0.size:
        raise ParameterError(f"alpha: {a.shape[0]} rows but initial has {v0.size} readings; expected one row per reading")
    n, p = a.shape
    if n < p:
        raise ParameterError(f"alpha: {n} readings for {p} planes; expected at least as many readings as planes")
    if method not in ("least_squares", "minmax"):
        raise ParameterError(f"method = {method!r}: expected 'least_squares' or 'minmax'")
    w = _weights(weights, n)
    bound = math.inf
    if max_unbalance_kg_m is not None:
        bound = float(max_unbalance_kg_m)
        if not bound > 0 or math.isnan(bound):
            raise ParameterError(f"max_unbalance_kg_m = {max_unbalance_kg_m!r}: expected > 0")
    aw = a * w[:, None]
    bw = v0 * w
    singular = np.linalg.svd(aw, compute_uv=False)
    if singular[-1] <= _RANK_TOLERANCE * singular[0]:
        raise ParameterError(f"alpha: singular (condition number {singular[0] / max(singular[-1], 1e-300):.3g}); "
                             "two or more planes have proportional influence coefficients; remove one plane "
                             "or add readings (sensors, speeds) that tell them apart")
    cond = float(singular[0] / singular[-1])
    flags: list[str] = []
    if cond > CONDITION_WARNING:
        flags.append("ill_conditioned")
        warn(f"alpha: condition number {cond:.3g} > {CONDITION_WARNING:g}; the planes are nearly dependent, so reading "
             f"errors are amplified up to {cond:.0f}x in the correction", QualityWarning)
    u_ls = _least_squares(aw, bw, bound)
    gap = 0.0
    if method == "least_squares":
        u = u_ls
        objective = float(np.sqrt(np.mean(np.abs(aw @ u + bw) ** 2)))
    else:
        u, gap = _minmax(aw, bw, bound, minmax_rtol, max_iterations)
        if np.max(np.abs(aw @ u_ls + bw)) < np.max(np.abs(aw @ u + bw)):
            u = u_ls  # within the LP tolerance least squares can tie; never return a worse worst case
        objective = float(np.max(np.abs(aw @ u + bw)))
    residual = v0 + a @ u
    bound_active = bool(math.isfinite(bound) and np.any(np.abs(u) >= bound * (1 - 1e-6)))
    if bound_active:
        flags.append("bound_active")
    return CorrectionResult(
        unbalance_kg_m=u, residual=residual, initial=v0,
        worst_residual=float(np.max(np.abs(residual))), rms_residual=float(np.sqrt(np.mean(np.abs(residual) ** 2))),
        worst_initial=float(np.max(np.abs(v0))), rms_initial=float(np.sqrt(np.mean(np.abs(v0) ** 2))),
        condition_number=cond, method=method, objective=objective, max_unbalance_kg_m=bound,
        bound_active=bound_active, minmax_gap=float(gap), flags=tuple(flags),
    )
