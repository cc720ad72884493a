"""The counterweight: evaluating one, the optimum over the balance fraction (exact, the peak
force is convex in it), the family of counterweights on the optimal curve, and the brute-force
grid the optimum is checked against."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from modal.errors import ParameterError

from .forces import _check_objective, _objective_value, _refined_max
from ..._checks import bounded
from .model import (
    PAPER_RULES,
    Objective,
    SliderCrank,
    _angles,
    _counterweight_moment,
    _factors,
    _force_xy,
    _require_reciprocating,
    _speed_rad_s,
    counterweight_moment,
)

__all__ = [
    "CounterweightEvaluation",
    "OptimalCurve",
    "OptimalCounterweight",
    "Counterweight",
    "GridSearchResult",
    "evaluate_counterweight",
    "evaluate_balance_fraction",
    "optimal_counterweight",
    "counterweight_on_curve",
    "grid_search_counterweight",
]


# --------------------------------------------------------------------------- evaluation
@dataclass(frozen=True)
class CounterweightEvaluation:
    """One counterweight (or none) evaluated over a revolution.

    Attributes
    ----------
    balance_fraction : float
        ``alpha``.
    counterweight_moment_kg_m : float
        ``m_c r_c`` [kg m].
    max_force_n : float
        Peak resultant [N].
    max_force_angle_rad : float
        Crank angle of the peak in ``[0, pi]`` [rad] (``|F|`` is even).
    rms_force_n : float
        RMS resultant over a revolution [N].
    force_x_range_n, force_y_range_n : tuple of float
        (min, max) of each component [N].
    force_x_span_n, force_y_span_n : float
        Peak-to-peak spans [N].
    reduction : float
        ``1 - max_force_n / (peak without counterweight)``.
    """

    balance_fraction: float
    counterweight_moment_kg_m: float
    max_force_n: float
    max_force_angle_rad: float
    rms_force_n: float
    force_x_range_n: tuple[float, float]
    force_y_range_n: tuple[float, float]
    force_x_span_n: float
    force_y_span_n: float
    reduction: float


def _evaluate_moment(mech: SliderCrank, omega: float, moment: float) -> CounterweightEvaluation:
    peak, angles, _ = _refined_max(lambda t: np.hypot(*_force_xy(mech, omega, moment, t)))
    x_max = abs(mech.rotating_mass_kg * mech.crank_radius_m - moment) * omega ** 2
    y_max = _refined_max(lambda t: _force_xy(mech, omega, moment, t)[1])[0]
    y_min = -_refined_max(lambda t: -_force_xy(mech, omega, moment, t)[1])[0]
    unbalanced = _objective_value(mech, omega, 0.0, "max")
    alpha = (moment / mech.crank_radius_m - mech.rotating_mass_kg) / mech.reciprocating_mass_kg
    return CounterweightEvaluation(
        balance_fraction=float(alpha), counterweight_moment_kg_m=moment, max_force_n=peak,
        max_force_angle_rad=float(angles[0]),
        rms_force_n=_objective_value(mech, omega, moment, "rms"),
        force_x_range_n=(-x_max, x_max), force_y_range_n=(y_min, y_max),
        force_x_span_n=2.0 * x_max, force_y_span_n=y_max - y_min,
        reduction=1.0 - peak / unbalanced if unbalanced > 0 else 0.0)


def evaluate_counterweight(mech: SliderCrank, speed_rpm: float, counterweight_mass_kg: float = 0.0,
                           counterweight_radius_m: float = 0.0) -> CounterweightEvaluation:
    """Peak, RMS, component ranges and peak-to-peak spans for a given counterweight.

    Parameters
    ----------
    mech : SliderCrank
        Needs ``reciprocating_mass_kg > 0`` (the result reports ``alpha``).
    speed_rpm : float
        Crank speed [rev/min], > 0.
    counterweight_mass_kg : float
        ``m_c`` [kg], >= 0.
    counterweight_radius_m : float
        ``r_c`` [m], in ``[0, r]``.

    Returns
    -------
    CounterweightEvaluation
    """
    _require_reciprocating(mech)
    omega = _speed_rad_s(speed_rpm)
    moment = _counterweight_moment(mech, counterweight_mass_kg, counterweight_radius_m)
    return _evaluate_moment(mech, omega, moment)


def evaluate_balance_fraction(mech: SliderCrank, speed_rpm: float,
                              balance_fraction_value: float | str) -> CounterweightEvaluation:
    """Evaluate a balance fraction, or one of the papers' rules by name.

    Parameters
    ----------
    mech : SliderCrank
    speed_rpm : float
        Crank speed [rev/min], > 0.
    balance_fraction_value : float or str
        ``alpha``, or a key of :data:`PAPER_RULES` (``"rotating"``:
        ``m_dt r = m_tq R``; ``"rotating_plus_half_reciprocating"``:
        ``m_dt r = R (m_tq + 0.5 m_ct)``).

    Returns
    -------
    CounterweightEvaluation
    """
    if isinstance(balance_fraction_value, str):
        if balance_fraction_value not in PAPER_RULES:
            raise ParameterError(
                f"balance_fraction_value = {balance_fraction_value!r}: expected a number or one "
                f"of {tuple(PAPER_RULES)}")
        balance_fraction_value = PAPER_RULES[balance_fraction_value]
    _require_reciprocating(mech)
    omega = _speed_rad_s(speed_rpm)
    return _evaluate_moment(mech, omega, counterweight_moment(mech, balance_fraction_value))


# --------------------------------------------------------------------------- optimum
@dataclass(frozen=True)
class OptimalCurve:
    """All counterweights ``(k, r_c)`` with the optimal moment, ``m_c = m_rot + k m_rec``.

    Attributes
    ----------
    k : ndarray
        The papers' fraction ``k`` in ``[max(alpha*, 0), 1]``.
    counterweight_mass_kg : ndarray
        ``m_c`` [kg].
    counterweight_radius_m : ndarray
        ``r_c = m_c* r_c* / m_c`` [m], <= ``r``.
    radius_ratio : ndarray
        ``r_c / r``.
    """

    k: np.ndarray
    counterweight_mass_kg: np.ndarray
    counterweight_radius_m: np.ndarray
    radius_ratio: np.ndarray

    def archive_units(self) -> dict[str, str]:
        """Units of the fields whose names do not say them (for :mod:`modal.archive`)."""
        return {"k": "1"}


@dataclass(frozen=True)
class OptimalCounterweight:
    """Exact optimum of the counterweight over the papers' feasible box.

    Attributes
    ----------
    balance_fraction : float
        Optimal ``alpha*`` (speed-independent).
    max_force_n : float
        Peak resultant force at the optimum [N].
    objective : str
        Objective minimised (``"max"``, ``"rms"``, ``"max_x"``, ``"max_y"``).
    objective_value_n : float
        Its value at the optimum [N].
    counterweight_moment_kg_m : float
        ``m_c r_c`` at the optimum [kg m].
    peak_angles_rad : ndarray
        Crank angles in ``[0, pi]`` of the active peaks at the optimum [rad]
        (two equal peaks when the optimum is an equal-peak point).
    peak_forces_n : ndarray
        Resultant at those angles [N].
    unbalanced_max_force_n : float
        Peak resultant without counterweight [N].
    reduction : float
        ``1 - max_force_n / unbalanced_max_force_n``.
    speed_rpm : float
        Speed the forces refer to [rev/min] (forces scale with its square).
    method : str
        ``"equal-peak root"`` or ``"bounded Brent"``.
    curve : OptimalCurve
        The whole family of optimal ``(k, r_c)``.
    """

    balance_fraction: float
    max_force_n: float
    objective: str
    objective_value_n: float
    counterweight_moment_kg_m: float
    peak_angles_rad: np.ndarray
    peak_forces_n: np.ndarray
    unbalanced_max_force_n: float
    reduction: float
    speed_rpm: float
    method: str
    curve: OptimalCurve


def _local_peak(mech: SliderCrank, omega: float, moment: float, angle: float,
                half_width: float) -> tuple[float, float]:
    """Refined local maximum of |F| within ``angle +- half_width``: (angle, value)."""
    lo, hi = max(0.0, angle - half_width), min(np.pi, angle + half_width)
    _, angles, peaks = _refined_max(lambda t: np.hypot(*_force_xy(mech, omega, moment, t)),
                                    lo, hi, n_grid=41)
    return float(angles[0]), float(peaks[0])


def _optimal_curve(mech: SliderCrank, alpha: float, moment: float, n_points: int) -> OptimalCurve:
    k = np.linspace(max(alpha, 0.0), 1.0, n_points)
    mass = mech.rotating_mass_kg + k * mech.reciprocating_mass_kg
    with np.errstate(divide="ignore"):
        radius = np.where(mass > 0, moment / np.where(mass > 0, mass, 1.0), 0.0)
    radius = np.minimum(radius, mech.crank_radius_m)
    return OptimalCurve(k, mass, radius, radius / mech.crank_radius_m)


def optimal_counterweight(mech: SliderCrank, speed_rpm: float, objective: Objective = "max",
                          n_curve_points: int = 101) -> OptimalCounterweight:
    """Exact optimal counterweight: minimise the objective over ``alpha``.

    The feasible box of the papers (``0 <= k <= 1``, ``0 <= r_c <= r``) is
    ``-m_rot/m_rec <= alpha <= 1``.  The convex objective is minimised by
    bounded Brent (inner maxima refined to 1e-10 rad); for ``"max"`` the
    result is then polished by solving the equal-peak condition with
    Brent's root finder when two peaks are active (:func:`scipy.optimize.brentq`).

    Parameters
    ----------
    mech : SliderCrank
        Needs ``reciprocating_mass_kg > 0``.
    speed_rpm : float
        Crank speed [rev/min], > 0 (the optimal ``alpha`` does not depend on it).
    objective : {"max", "rms", "max_x", "max_y"}
        See :func:`shaking_objective`.
    n_curve_points : int
        Points on the optimal ``(k, r_c)`` curve, >= 2.

    Returns
    -------
    OptimalCounterweight
    """
    _check_objective(objective)
    _require_reciprocating(mech)
    omega = _speed_rad_s(speed_rpm)
    n_points = int(bounded("n_curve_points", n_curve_points, minimum=2.0))
    m_rot, m_rec, r = mech.rotating_mass_kg, mech.reciprocating_mass_kg, mech.crank_radius_m
    lower, upper = -m_rot / m_rec, 1.0

    def phi(alpha: float) -> float:
        return _objective_value(mech, omega, (m_rot + alpha * m_rec) * r, objective)

    from scipy.optimize import minimize_scalar  # imported when used: a plotting process unpickles these results

    # For "max" a coarse bracket suffices: the equal-peak root polishes it.
    found = minimize_scalar(phi, bounds=(lower, upper), method="bounded",
                            options={"xatol": 1e-7 if objective == "max" else 1e-10, "maxiter": 500})
    alpha, method = float(found.x), "bounded Brent"
    # Compare with the bounds: the bounded method never evaluates them.
    for bound in (lower, upper):
        if phi(bound) < phi(alpha):
            alpha = bound
    if objective == "max":
        polished, how = _polish_equal_peak(mech, omega, alpha, lower, upper, method)
        # keep the root only if it is at least as good (it is the optimum when
        # the two peaks move in opposite directions with alpha, as they must
        # when both are active at the minimum of a convex maximum)
        if phi(polished) <= phi(alpha) * (1.0 + 1e-14):
            alpha, method = polished, how
    moment = (m_rot + alpha * m_rec) * r
    _, angles, peaks = _refined_max(lambda t: np.hypot(*_force_xy(mech, omega, moment, t)))
    active = peaks >= peaks[0] * (1.0 - 1e-7)
    unbalanced = _objective_value(mech, omega, 0.0, "max")
    peak = float(peaks[0])
    return OptimalCounterweight(
        balance_fraction=alpha, max_force_n=peak, objective=objective,
        objective_value_n=_objective_value(mech, omega, moment, objective),
        counterweight_moment_kg_m=moment, peak_angles_rad=np.sort(angles[active]),
        peak_forces_n=peaks[active][np.argsort(angles[active])],
        unbalanced_max_force_n=unbalanced, reduction=1.0 - peak / unbalanced if unbalanced > 0 else 0.0,
        speed_rpm=float(speed_rpm), method=method,
        curve=_optimal_curve(mech, alpha, moment, n_points))


def _polish_equal_peak(mech: SliderCrank, omega: float, alpha: float, lower: float, upper: float,
                       method: str) -> tuple[float, str]:
    """Solve P_a(alpha) = P_b(alpha) for the two largest distinct peaks."""
    m_rot, m_rec, r = mech.rotating_mass_kg, mech.reciprocating_mass_kg, mech.crank_radius_m
    moment = (m_rot + alpha * m_rec) * r
    _, angles, peaks = _refined_max(lambda t: np.hypot(*_force_xy(mech, omega, moment, t)))
    if peaks.size < 2 or peaks[1] < peaks[0] * (1.0 - 1e-5):
        return alpha, method
    angle_a, angle_b = angles[0], angles[1]
    half_width = 0.25 * abs(angle_a - angle_b)

    def gap(a: float) -> float:
        u = (m_rot + a * m_rec) * r
        return _local_peak(mech, omega, u, angle_a, half_width)[1] - _local_peak(
            mech, omega, u, angle_b, half_width)[1]

    step = 1e-6
    for _ in range(20):
        lo, hi = max(lower, alpha - step), min(upper, alpha + step)
        g_lo, g_hi = gap(lo), gap(hi)
        if g_lo * g_hi < 0:
            from scipy.optimize import brentq

            return brentq(gap, lo, hi, xtol=1e-15, rtol=4 * np.finfo(float).eps), "equal-peak root"
        step *= 4.0
    return alpha, method


@dataclass(frozen=True)
class Counterweight:
    """One counterweight on the optimal curve.

    Attributes
    ----------
    k : float
        ``(m_c - m_rot) / m_rec``.
    mass_kg : float
        ``m_c`` [kg].
    radius_m : float
        ``r_c`` [m].
    radius_ratio : float
        ``r_c / r``.
    rule : str
        How it was picked.
    """

    k: float
    mass_kg: float
    radius_m: float
    radius_ratio: float

    def archive_units(self) -> dict[str, str]:
        """Units of the fields whose names do not say them (for :mod:`modal.archive`)."""
        return {"k": "1"}
    rule: str


def counterweight_on_curve(mech: SliderCrank, optimum: OptimalCounterweight, *,
                           k: float | None = None,
                           radius_m: float | None = None) -> Counterweight:
    """Pick one optimal counterweight: the lightest (``r_c = r``), a given ``k`` or a given ``r_c``.

    The lightest counterweight and ``r_c = r`` are the same point, since
    ``m_c r_c`` is fixed on the curve.

    Parameters
    ----------
    mech : SliderCrank
    optimum : OptimalCounterweight
    k : float, optional
        Given ``k`` in ``[max(alpha*, 0), 1]``.
    radius_m : float, optional
        Given ``r_c`` [m] in ``(0, r]``.

    Returns
    -------
    Counterweight
    """
    if k is not None and radius_m is not None:
        raise ParameterError("give k or radius_m, not both")
    moment = optimum.counterweight_moment_kg_m
    m_rot, m_rec, r = mech.rotating_mass_kg, mech.reciprocating_mass_kg, mech.crank_radius_m
    if radius_m is not None:
        radius = bounded("radius_m", radius_m, minimum=0.0, strict=True, maximum=r)
        mass, rule = moment / radius, "given radius"
        kk = (mass - m_rot) / m_rec
        if kk > 1.0 + 1e-12:
            raise ParameterError(
                f"radius_m = {radius!r}: needs k = {kk:.6g} > 1; expected radius_m >= "
                f"{moment / (m_rot + m_rec)!r}")
        return Counterweight(kk, mass, radius, radius / r, rule)
    k_low = max(optimum.balance_fraction, 0.0)
    if k is None:
        kk, rule = k_low, "lightest (r_c = r)"
    else:
        kk = bounded("k", k, minimum=k_low - 1e-12, maximum=1.0)
        rule = "given k"
    mass = m_rot + kk * m_rec
    radius = min(moment / mass, r) if mass > 0 else 0.0
    return Counterweight(kk, mass, radius, radius / r, rule)


# --------------------------------------------------------------------------- brute force
@dataclass(frozen=True)
class GridSearchResult:
    """Best point of an exhaustive ``(k, r_c)`` search (the papers' method).

    Attributes
    ----------
    k : float
    counterweight_radius_m : float
        [m]
    max_force_n : float
        Peak resultant on the angle grid [N].
    n_evaluations : int
        ``(k, r_c)`` pairs times angles evaluated.
    """

    k: float
    counterweight_radius_m: float
    max_force_n: float
    n_evaluations: int

    def archive_units(self) -> dict[str, str]:
        """Units of the fields whose names do not say them (for :mod:`modal.archive`)."""
        return {"k": "1"}


def grid_search_counterweight(mech: SliderCrank, speed_rpm: float, k_values, radius_values_m,
                              crank_angles_rad, chunk_size: int = 200_000) -> GridSearchResult:
    """Exhaustive search over ``(k, r_c)`` with the force maximised on an angle grid.

    Kept as the papers' reference method and for benchmarks; use
    :func:`optimal_counterweight` for answers.

    Parameters
    ----------
    mech : SliderCrank
    speed_rpm : float
        Crank speed [rev/min], > 0.
    k_values : array_like
        ``k`` values.
    radius_values_m : array_like
        ``r_c`` values [m], in ``[0, r]``.
    crank_angles_rad : array_like
        Angle grid [rad].
    chunk_size : int
        Approximate number of force evaluations per vectorised block.

    Returns
    -------
    GridSearchResult
    """
    omega = _speed_rad_s(speed_rpm)
    theta = _angles(crank_angles_rad)
    ks = _angles(k_values, "k_values", "units of m_rec")
    radii = _angles(radius_values_m, "radius_values_m", "m")
    if radii.min() < 0 or radii.max() > mech.crank_radius_m * (1 + 1e-12):
        raise ParameterError(
            f"radius_values_m spans [{radii.min()!r}, {radii.max()!r}]: expected values in "
            f"[0, crank_radius_m = {mech.crank_radius_m!r}]")
    kk, rr = np.meshgrid(ks, radii, indexing="ij")
    k_flat, r_flat = kk.ravel(), rr.ravel()
    moments = (mech.rotating_mass_kg + k_flat * mech.reciprocating_mass_kg) * r_flat
    accel, _ = _factors(mech, theta)
    w2, r = omega ** 2, mech.crank_radius_m
    s, c = np.sin(theta), np.cos(theta)
    rec = mech.reciprocating_mass_kg * r * w2 * accel
    rows = max(1, int(chunk_size) // theta.size)
    best = np.empty(moments.size)
    for start in range(0, moments.size, rows):
        unbalance = (mech.rotating_mass_kg * r - moments[start:start + rows, None]) * w2
        best[start:start + rows] = np.max(np.hypot(unbalance * s, unbalance * c + rec), axis=1)
    index = int(np.argmin(best))
    return GridSearchResult(float(k_flat[index]), float(r_flat[index]), float(best[index]),
                            int(moments.size * theta.size))
