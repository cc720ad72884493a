"""Half-power bandwidth (peak picking), done exactly.

The −3 dB crossings are interpolated in dB, the peak is refined with the
exact three-point fit of ω^{2p}/|H|², which is a quadratic in ω² for one
viscous mode, and the damping ratio and natural frequency come from the exact
relations of the FRF kind (``../shared/reference/numerics.md`` §1), not the
textbook ζ ≈ Δω/2ωn (4.7 % off at ζ = 0.2 on receptance).
"""
from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np

from ..model import mode_basis

__all__ = ["HalfPowerEstimate", "half_power_curve", "invert_half_power"]


@dataclass(frozen=True)
class HalfPowerEstimate:
    """Half-power result on one channel."""

    omega_n: float
    damping_ratio: float
    std_omega_n: float
    std_damping_ratio: float
    n_above: int
    flags: tuple[str, ...]
    #: ∂(ωn, ζ)/∂|H| on every line of the band, shape (2, n): the linearisation of this
    #: estimator (its line choices held fixed), from which the errors are propagated
    jacobian: np.ndarray | None = None


def invert_half_power(w1: float, w2: float, power: int) -> tuple[float, float]:
    """Exact (ωn, ζ) from the half-power frequencies ω1 < ω2 (rad/s).

    Receptance and accelerance: q = (ω2² − ω1²)/(ω2² + ω1²),
    ζ² = ½(1 − 1/√(1+q²)); ωn² = (ω1² + ω2²)/(2(1 − 2ζ²)) for receptance,
    2(1 − 2ζ²)/(ω1⁻² + ω2⁻²) for accelerance. Mobility: ωn = √(ω1ω2),
    ζ = (ω2 − ω1)/(2√(ω1ω2)).
    """
    if power == 1:
        wn = np.sqrt(w1 * w2)
        return wn, (w2 - w1) / (2 * wn)
    q = (w2**2 - w1**2) / (w2**2 + w1**2)
    zeta = np.sqrt(0.5 * (1 - 1 / np.sqrt(1 + q**2)))
    if power == 0:
        wn = np.sqrt((w1**2 + w2**2) / (2 * (1 - 2 * zeta**2)))
    else:
        wn = np.sqrt(2 * (1 - 2 * zeta**2) / (w1**-2 + w2**-2))
    return wn, zeta


def _one_sided(u_peak, u_cross, power: int):
    """(ωn, ζ) from the refined peak and one crossing (the other is missing)."""
    if power == 1:  # r = sqrt(1+ζ²) ± ζ about the peak ωn
        wn = np.sqrt(u_peak)
        ratio = np.sqrt(u_cross / u_peak)
        zeta = np.abs(ratio - 1 / ratio) / 2
        return wn, zeta
    # receptance: u/u_peak = 1 ± q ; accelerance: u_peak/u = 1 ± q
    q = np.abs(u_cross / u_peak - 1) if power == 0 else np.abs(u_peak / u_cross - 1)
    zeta = np.sqrt(0.5 * (1 - 1 / np.sqrt(1 + q**2)))
    one_minus = np.maximum(1 - 2 * zeta**2, 1e-12)
    wn = np.sqrt(u_peak / one_minus) if power == 0 else np.sqrt(u_peak * one_minus)
    return wn, zeta


@dataclass(frozen=True)
class _Plan:
    """The discrete choices of one half-power estimate (which lines enter which step).

    With the choices held, the estimate is a smooth function of the magnitudes:
    :func:`_evaluate` computes it for a batch of magnitude vectors, which gives both
    the estimate and its linearisation (the propagated standard errors).
    """

    i: int                                 # peak line
    peak_lines: tuple[int, int] | None     # lines of the refined-peak fit, or None: the peak line itself
    left: tuple | None                     # ("linear", j_below, j_above) or ("fit", lines, guess, root) or None
    right: tuple | None


@functools.lru_cache(maxsize=64)
def _quadratic_pinv(x: bytes) -> np.ndarray:
    """Pseudo-inverse of the design of a quadratic in x (float64 values as bytes), read-only.

    A curve's estimate evaluates the same fits over the same lines many times (each model pass, the
    final estimate, the Jacobian's batch, the interpolation check): the pseudo-inverse (an SVD) was
    a fifth of the half-power method's time; cached by the values, so the numbers are the same."""
    pinv = np.linalg.pinv(np.vander(np.frombuffer(x), 3))
    pinv.setflags(write=False)
    return pinv


def _peak_fit(omega, lo, hi):
    """Design of the least-squares quadratic in ω² through lines lo..hi (pseudo-inverse, scale)."""
    u = omega[lo:hi + 1] ** 2
    scale = u[len(u) // 2]
    return _quadratic_pinv(np.ascontiguousarray(u / scale, float).tobytes()), u, scale


def _peak_values(omega, mag, plan: _Plan, power: int):
    """Refined peak (ω², |H|²) for a batch of magnitudes ``mag`` (B, n)."""
    i = plan.i
    if plan.peak_lines is None:
        return np.full(mag.shape[0], omega[i] ** 2), mag[:, i] ** 2
    lo, hi = plan.peak_lines
    pinv, u, scale = _peak_fit(omega, lo, hi)
    g = u**power / mag[:, lo:hi + 1] ** 2
    coef = g @ pinv.T
    a, b, c = coef[:, 0] / scale**2, coef[:, 1] / scale, coef[:, 2]
    with np.errstate(all="ignore"):
        if power == 0:
            u_star = -b / (2 * a)
        elif power == 1:
            u_star = np.sqrt(c / a)
        else:
            u_star = -2 * c / b
        return u_star, u_star**power / (a * u_star**2 + b * u_star + c)


def _choose_peak(omega, mag, i, power):
    """Lines of the refined-peak fit: ω^{2p}/|H|² is exactly a quadratic in ω² for one viscous mode.

    Three lines around line i fix it exactly on clean data; when more lines lie
    within 1 dB of the peak line, a least-squares fit over all of them keeps the
    noise on the highest line (which the arg-max selects for being high) from
    lifting the −3 dB level. None when the refined peak does not stand (it must
    lie between the neighbours of line i and not below line i).
    """
    if i == 0 or i == mag.size - 1:
        return None
    lo, hi = i, i
    level = mag[i] * 10 ** (-1 / 20)
    while lo > 0 and mag[lo - 1] >= level:
        lo -= 1
    while hi < mag.size - 1 and mag[hi + 1] >= level:
        hi += 1
    lo, hi = min(lo, i - 1), max(hi, i + 1)
    probe = _Plan(i, (lo, hi), None, None)
    u_star, peak2 = (float(v[0]) for v in _peak_values(omega, mag[None, :], probe, power))
    u = omega[i - 1:i + 2] ** 2
    if not (np.isfinite(u_star) and u[0] <= u_star <= u[2]):
        return None
    if not (np.isfinite(peak2) and peak2 >= mag[i] ** 2):
        return None
    return (lo, hi)


def _crossing(omega, db, level_db, j_below, j_above):
    """Frequency where the dB curve crosses ``level_db`` between two lines (linear in dB)."""
    t = (level_db - db[..., j_below]) / (db[..., j_above] - db[..., j_below])
    return omega[j_below] + t * (omega[j_above] - omega[j_below])


def _fit_design(w):
    """Pseudo-inverse of the quadratic design in x = (ω − ω0)/ptp(ω) over lines ``w``."""
    return _quadratic_pinv(np.ascontiguousarray((w - w[0]) / np.ptp(w), float).tobytes())


def _fit_roots(coef, w):
    """Both real roots (ω) of the fitted quadratic coef (B, 3) in x = (ω − w0)/ptp(w); NaN if none."""
    c2, c1, c0 = coef[:, 0], coef[:, 1], coef[:, 2]
    with np.errstate(all="ignore"):
        disc = np.sqrt(c1**2 - 4 * c2 * c0)
        roots = np.stack([(-c1 - disc) / (2 * c2), (-c1 + disc) / (2 * c2)], axis=1)
    return w[0] + roots * np.ptp(w)


def _fitted_crossing(omega, db, level_db, guess, offset, chooser=None, window_db=1.0, min_lines=7):
    """Refine a −3 dB crossing by least squares of a quadratic in ω over the lines within
    ±``window_db`` of the level on one side of the peak (``omega``, ``db`` that side, its
    first line at ``offset`` of the band). Returns the plan of this side: ("fit", lines,
    root index) or None to keep ``guess`` (too few lines, no real root, a root away from
    the guess). ``chooser``: the dB values that choose the lines (default ``db``)."""
    near = np.flatnonzero(np.abs((db if chooser is None else chooser) - level_db) <= window_db)
    if near.size < min_lines:
        return None
    w = omega[near]
    coef = (db[near] - level_db) @ _fit_design(w).T
    roots = _fit_roots(coef[None, :], w)[0]
    if not np.any(np.isfinite(roots)):
        return None
    which = int(np.nanargmin(np.abs(roots - guess)))
    crossing = roots[which]
    if abs(crossing - guess) > 0.5 * np.ptp(w):  # outside the fitted lines: not a crossing of this side
        return None
    # under heavy noise the lines near the level scatter over the whole side, and a root
    # half their span from the guess can fall past the peak or below zero (a negative ω2 at
    # 18 % noise): a crossing of this side lies within its lines
    if not omega[0] <= crossing <= omega[-1]:
        return None
    return ("fit", near + offset, which)


def _side_value(omega, db, level_db, side):
    """Crossing frequency of one side for a batch (B,) from its plan."""
    if side is None:
        return np.full(db.shape[0], np.nan)
    if side[0] == "linear":
        return _crossing(omega, db, level_db, side[1], side[2])
    lines, which = side[1], side[2]
    w = omega[lines]
    coef = (db[:, lines] - level_db[:, None]) @ _fit_design(w).T
    return _fit_roots(coef, w)[:, which]


def _evaluate(omega, mag, power, plan: _Plan):
    """(ωn, ζ), each shape (B,), for a batch of magnitudes ``mag`` (B, n) with the choices held."""
    return _evaluate_sides(omega, mag, power, plan)[:2]


def _evaluate_sides(omega, mag, power, plan: _Plan):
    """(ωn, ζ, ω1, ω2), each shape (B,): :func:`_evaluate` and the crossings it found (NaN for a side
    without one)."""
    u_peak, peak2 = _peak_values(omega, mag, plan, power)
    db = 20 * np.log10(np.maximum(mag, np.finfo(float).tiny))
    level_db = 10 * np.log10(peak2 / 2)
    w1 = _side_value(omega, db, level_db, plan.left)
    w2 = _side_value(omega, db, level_db, plan.right)
    if plan.left is not None and plan.right is not None:
        return (*invert_half_power(w1, w2, power), w1, w2)
    if plan.left is not None or plan.right is not None:
        wc = w1 if plan.left is not None else w2
        return (*_one_sided(u_peak, wc**2, power), w1, w2)
    # no crossing at all: the band holds less than the half-power width
    spacing = np.min(np.diff(omega)) if omega.size > 1 else np.nan
    wn = np.sqrt(u_peak)
    return wn, np.maximum((omega[-1] - omega[0]) / (2 * wn), spacing / (2 * wn)), w1, w2


def _jacobian(omega, mag, power, plan: _Plan, lines):
    """∂(ωn, ζ)/∂|H| (2, n) by central differences on ``lines`` (the others do not enter)."""
    jac = np.zeros((2, mag.size))
    lines = np.asarray(sorted(lines), int)
    if lines.size == 0:
        return jac
    step = 1e-6 * mag[lines]
    step[step == 0] = 1e-6 * np.max(mag)
    batch = np.repeat(mag[None, :], 2 * lines.size, axis=0)
    rows = np.arange(lines.size)
    batch[2 * rows, lines] += step
    batch[2 * rows + 1, lines] -= step
    with np.errstate(all="ignore"):
        wn, zeta = _evaluate(omega, batch, power, plan)
    jac[0, lines] = (wn[0::2] - wn[1::2]) / (2 * step)
    jac[1, lines] = (zeta[0::2] - zeta[1::2]) / (2 * step)
    return jac


def _plan_lines(plan: _Plan, n: int):
    """Every line whose magnitude enters the estimate under ``plan``."""
    lines = {plan.i}
    if plan.peak_lines is not None:
        lines.update(range(plan.peak_lines[0], plan.peak_lines[1] + 1))
    for side in (plan.left, plan.right):
        if side is not None:
            lines.update(side[1:3] if side[0] == "linear" else side[1].tolist())
    return {j for j in lines if 0 <= j < n}


def _interpolation_shift(omega, power, plan: _Plan, pole, crossings):
    """|Δ(ωn, ζ)| that interpolating the crossings linearly in dB causes on the estimated mode.

    The curve of one viscous mode with the estimated pole is interpolated between the
    same lines as the data; its crossings against its exact ones, through the exact
    inversion, give the estimator's bias from the line spacing (the curvature of the dB
    curve between two lines: 6e-4 of ωn at ζ = 0.2, 5 lines per half-power band, on
    exact data), free of the noise of the lines.
    """
    sides = (plan.left, plan.right)
    if any(side is None for side in sides) or all(side[0] != "linear" for side in sides):
        return np.zeros(2)
    if not (np.all(np.isfinite(pole)) and pole[0] > 0 and pole[1] > 0):
        return np.zeros(2)
    level = -10 * np.log10(2)
    model = _model_db(omega, power, pole)
    linear, exact = [], []
    for side, fitted in zip(sides, crossings):
        if side[0] != "linear":  # a fitted crossing: no interpolation error of this kind
            linear.append(fitted)
            exact.append(fitted)
            continue
        a, b = sorted(side[1:3])
        if not (min(model[a], model[b]) <= level <= max(model[a], model[b])):
            return np.zeros(2)
        t = (level - model[a]) / (model[b] - model[a])
        linear.append(omega[a] + t * (omega[b] - omega[a]))
        exact.append(_exact_crossing(omega[a], omega[b], power, pole, omega, level))
    return np.abs(np.array(invert_half_power(*linear, power)) - np.array(invert_half_power(*exact, power)))


#: passes of the model-chosen peak and crossing lines after the first estimate (they settle
#: in two or three: the plan repeats and the loop stops)
MODEL_PASSES = 4


def _same_plan(a: _Plan, b: _Plan) -> bool:
    """Whether two plans choose the same lines."""
    def key(side):
        return None if side is None else (side[0], tuple(np.atleast_1d(side[1]).tolist()), side[2])
    return a.peak_lines == b.peak_lines and key(a.left) == key(b.left) and key(a.right) == key(b.right)


#: samples of a model curve: its peak over a band, and each side's crossing between two lines
PEAK_SAMPLES = 4001
CROSSING_SAMPLES = 2001
#: every how many samples the coarse pass looks, before the samples that matter are computed
_STRIDE = 50


def _model_abs(fine, wn: float, zeta: float, power: int) -> np.ndarray:
    """|φ| of one viscous mode on the samples ``fine`` (rad/s)."""
    return np.abs(mode_basis(fine, wn, zeta, power)[0])


def _peak_location(power: int, wn: float, zeta: float) -> float:
    """ω (rad/s) of the peak of |φ| over ω ≥ 0 (0 or inf where |φ| is monotone there)."""
    if power == 1:
        return wn
    shrink = 1 - 2 * zeta**2
    if not shrink > 0:
        return 0.0 if power == 0 else np.inf
    return wn * np.sqrt(shrink) if power == 0 else wn / np.sqrt(shrink)


@functools.lru_cache(maxsize=16)
def _model_peak(first: float, last: float, power: int, wn: float, zeta: float) -> float:
    """Peak |φ| of one viscous mode (ωn, ζ) of kind ``power`` between two frequencies (rad/s), the
    largest of ``PEAK_SAMPLES`` samples (cached: the interpolation check asks for the same mode's peak
    once per side, after its own curve).

    |φ| has one peak over ω ≥ 0, so every ``_STRIDE``-th sample locates it and only the samples
    between the coarse maximum's neighbours are computed: elementwise, the same values as those
    of the whole grid, whose largest lies there."""
    fine = np.linspace(first, last, PEAK_SAMPLES)
    if not first >= 0:  # one peak on each side of ω = 0: the whole grid
        return float(_model_abs(fine, wn, zeta, power).max())
    coarse = np.arange(0, PEAK_SAMPLES, _STRIDE)
    k = int(np.argmax(_model_abs(fine[coarse], wn, zeta, power)))
    lo, hi = coarse[max(k - 1, 0)], coarse[min(k + 1, coarse.size - 1)]
    return float(_model_abs(fine[lo:hi + 1], wn, zeta, power).max())


def _exact_crossing(first: float, last: float, power: int, pole, reference, level: float) -> float:
    """Where the model dB curve (relative to its peak over ``reference``) crosses ``level`` between
    two lines (rad/s): linear interpolation between ``CROSSING_SAMPLES`` samples.

    Where the mode's peak lies outside the two lines the curve is monotone between them: every
    ``_STRIDE``-th sample brackets the crossing and only the samples around it are computed
    (elementwise the same values, and the same two samples enter the interpolation)."""
    fine = np.linspace(first, last, CROSSING_SAMPLES)
    window = slice(None)
    if first >= 0 and not first < _peak_location(power, *pole) < last:
        coarse = np.arange(0, CROSSING_SAMPLES, _STRIDE)
        values = _model_db(fine[coarse], power, pole, reference=reference)
        steps = np.diff(values)
        above = np.flatnonzero(values >= level)
        if (np.all(steps > 0) or np.all(steps < 0)) and 0 < above.size < coarse.size:
            # the last coarse sample below the level and the first above it, one stride wider
            # each way (a sample equal to the level is in either bracket)
            edge = above[0] if steps[0] > 0 else above[-1]
            window = slice(coarse[max(edge - 2, 0)], coarse[min(edge + 2, coarse.size - 1)] + 1)
    fine = fine[window]
    curve = _model_db(fine, power, pole, reference=reference)
    order = np.argsort(curve)
    return float(np.interp(level, curve[order], fine[order]))


def _model_db(omega, power, pole, reference=None):
    """dB of one viscous mode (ωn, ζ) of kind ``power`` on the lines, relative to its peak
    over the lines ``reference`` (default ``omega``), sampled finely."""
    wn, zeta = pole
    span = omega if reference is None else reference
    peak = _model_peak(float(span[0]), float(span[-1]), power, float(wn), float(zeta))
    return 20 * np.log10(_model_abs(omega, wn, zeta, power) / peak)


def _model_crossing(omega, curve, level_db):
    """Where a smooth (model) dB curve over one side of the peak crosses the level, or None."""
    above = curve >= level_db
    change = np.flatnonzero(above[1:] != above[:-1])
    if change.size == 0:
        return None
    j = int(change[0] if curve[0] < level_db else change[-1])
    return float(_crossing(omega, curve, level_db, j, j + 1))


def _plan(omega, mag, db, power, i, peak_lines, noise_std, model=None, peak2=None):
    """The choices of the crossings for a given peak fit; and the lines above the level.

    ``model``: a first estimate (ωn, ζ) whose curve chooses the lines of each fitted
    crossing (within ±1 dB of −3 dB on the model), so that the noise on a line does not
    decide whether it enters (selecting on the noisy dB trims the noise the fit sees).
    ``peak2``: the peak fit's |H|² on these lines, when the caller has it.
    """
    n = mag.size
    if peak2 is None:
        _, peak2 = (float(v[0]) for v in _peak_values(omega, mag[None, :], _Plan(i, peak_lines, None, None), power))
    level = np.sqrt(peak2 / 2)
    level_db = 10 * np.log10(peak2 / 2)
    lo = i
    while lo >= 0 and mag[lo] >= level:
        lo -= 1
    hi = i
    while hi < n and mag[hi] >= level:
        hi += 1
    n_above = int(np.sum(mag[max(lo, 0):min(hi, n)] >= level))
    left = ("linear", lo, lo + 1) if lo >= 0 else None
    right = ("linear", hi, hi - 1) if hi < n else None
    # many lines across a crossing: a local quadratic fit of dB against ω averages the
    # noise (the first line below the level is selected for being low, which narrows the band)
    noisy = np.isfinite(noise_std) and 6.14 * noise_std / level > 0.01  # σ in dB at the level
    chooser = db if model is None else _model_db(omega, power, model) + level_db + 10 * np.log10(2)
    if noisy and left is not None:
        guess = _model_crossing(omega[:i + 1], chooser[:i + 1], level_db) if model is not None else None
        if guess is None:
            guess = float(_crossing(omega, db, level_db, lo, lo + 1))
        left = _fitted_crossing(omega[:i + 1], db[:i + 1], level_db, guess, 0, chooser[:i + 1]) or left
    if noisy and right is not None:
        guess = _model_crossing(omega[i:], chooser[i:], level_db) if model is not None else None
        if guess is None:
            guess = float(_crossing(omega, db, level_db, hi, hi - 1))
        right = _fitted_crossing(omega[i:], db[i:], level_db, guess, i, chooser[i:]) or right
    return _Plan(i, peak_lines, left, right), n_above


def half_power_curve(omega: np.ndarray, h: np.ndarray, power: int, noise_std: float,
                     errors: bool = True) -> HalfPowerEstimate:
    """Half-power estimate of the mode with the largest peak in a band (one channel).

    Parameters
    ----------
    omega : ndarray
        Lines of the band, rad/s.
    h : ndarray of complex
        FRF on those lines.
    power : int
        Kind power (0 receptance, 1 mobility, 2 accelerance).
    noise_std : float
        σ of the complex noise on ``h`` (E|n|² = σ², white over the band; for the
        standard errors).
    errors : bool
        False: the estimate only (standard errors NaN, no ``jacobian``), for start values.

    Notes
    -----
    The standard errors are the estimator's own, propagated to first order: with its
    line choices (peak line, the lines of the peak fit and of each crossing) held, the
    estimate is a smooth function of the magnitudes, whose noise is σ/√2 per line (the
    radial part of circular noise); ``jacobian`` holds that linearisation.
    """
    mag = np.abs(h)
    n = mag.size
    i = int(np.argmax(mag))
    flags: list[str] = []
    if i == 0 or i == n - 1:
        flags.append("band_edge_peak")
    db = 20 * np.log10(np.maximum(mag, np.finfo(float).tiny))
    plan, n_above = _plan(omega, mag, db, power, i, _choose_peak(omega, mag, i, power), noise_std)
    evaluated = None  # the last plan evaluated, with its (ωn, ζ, ω1, ω2)
    for _ in range(MODEL_PASSES):
        # further passes: the peak fit on the lines within 1 dB of the last estimate's model
        # peak (|ω − ωn| ≤ ζωn/2), and the crossing fits on the lines within ±1 dB of −3 dB on
        # that model, not chosen by the noisy lines themselves: the highest line is selected
        # for being high, which lifts the level and narrows the band (ζ −0.2 to −0.3 of its
        # error low at 1 % noise, −20 errors at 5 % noise and 300 lines per band)
        if plan.left is None or plan.right is None:
            break
        with np.errstate(all="ignore"):
            values = tuple(float(v[0]) for v in _evaluate_sides(omega, mag[None, :], power, plan))
        evaluated = (plan, values)
        wn1, zeta1 = values[:2]
        if not (np.isfinite(wn1) and np.isfinite(zeta1) and zeta1 > 0):
            break
        near = np.flatnonzero(np.abs(omega - wn1) <= 0.5 * zeta1 * wn1)
        if near.size < 3 or np.any(np.diff(near) != 1):
            break
        lines = (int(near[0]), int(near[-1]))
        u_star, peak2 = (float(v[0]) for v in _peak_values(omega, mag[None, :], _Plan(i, lines, None, None), power))
        if not (np.isfinite(u_star) and omega[lines[0]] ** 2 <= u_star <= omega[lines[1]] ** 2 and peak2 > 0):
            break
        previous = plan
        plan, n_above = _plan(omega, mag, db, power, i, lines, noise_std, (wn1, zeta1), peak2)
        if _same_plan(plan, previous):
            break
    if n_above < 3:
        flags.append("resolution_limited")
    if plan.left is None or plan.right is None:
        flags.append("missing_crossing")
    if evaluated is not None and _same_plan(evaluated[0], plan):  # the same lines: the same numbers
        wn, zeta, *crossings = evaluated[1]
    else:
        wn, zeta, *crossings = (float(v[0]) for v in _evaluate_sides(omega, mag[None, :], power, plan))
    std_wn = std_zeta = np.nan
    if not errors:
        return HalfPowerEstimate(float(wn), float(zeta), std_wn, std_zeta, n_above, tuple(flags), None)
    jac = _jacobian(omega, mag, power, plan, _plan_lines(plan, n))
    if np.isfinite(noise_std) and noise_std > 0 and np.all(np.isfinite(jac)):
        # white circular noise σ: each magnitude carries σ/√2 (its radial part), independently
        var = (noise_std**2 / 2) * np.sum(jac**2, axis=1)
        std_wn, std_zeta = float(np.sqrt(var[0])), float(np.sqrt(var[1]))
    with np.errstate(all="ignore"):
        shift = _interpolation_shift(omega, power, plan, (wn, zeta), crossings)
    if np.any(shift != 0) and np.isfinite(std_wn) and np.isfinite(std_zeta):
        # a crossing interpolated linearly in dB between two lines is off by the curvature of
        # the dB curve between them: the systematic error, added to the noise-driven one
        std_wn, std_zeta = float(np.hypot(std_wn, shift[0])), float(np.hypot(std_zeta, shift[1]))
    if "resolution_limited" in flags or "missing_crossing" in flags:
        # the crossings are decided by the grid: add the quantisation of the line spacing
        spacing = float(np.min(np.diff(omega)))
        std_wn = float(np.hypot(std_wn if np.isfinite(std_wn) else 0.0, spacing / np.sqrt(12)))
        std_zeta = float(np.hypot(std_zeta if np.isfinite(std_zeta) else 0.0, spacing / (2 * wn)))
    return HalfPowerEstimate(float(wn), float(zeta), std_wn, std_zeta, n_above, tuple(flags), jac)
