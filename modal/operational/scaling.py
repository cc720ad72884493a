"""Mass-normalised shapes from two operational tests: before and after adding known masses.

Adding masses ΔM lowers each mode's frequency from ω₀ to ω₁; with both records' shapes φ₀, φ₁
(normalised alike and phase-aligned) the scale factor of the first record's shape is
(Brincker & Andersen 2003; López-Aenlle et al. 2010, the form with both shapes)::

    α² = (ω₀² − ω₁²) / (ω₁² φ₀ᵀ ΔM φ₁),    ψ = α φ₀  (ψᵀ M ψ = 1)

Per channel j, the mode then is a driving point of modal constant ψ_j² (1/kg): mass 1/ψ_j²,
stiffness ω₀²/ψ_j², damping 2ζω₀/ψ_j², as :func:`modal.identify` gives them for an impact
test's driving point. Standard errors follow to first order from those of both records'
frequencies, damping and shapes (independent records).
"""
from __future__ import annotations

import warnings

import numpy as np

from ..errors import ParameterError, QualityWarning
from ..flags import MAX_LOCATION_MISFIT, MAX_SCALE_ERROR, MIN_SHIFT_SIGMAS
from ..results import IdentificationResult
from .result import scaled_result
from .selection import shape_mac

__all__ = ["scale_by_mass_change", "PAIR_MAC", "MAX_SHIFT"]

#: a mode of the second record is the same mode when its shape has at least this MAC with the first's
PAIR_MAC = 0.8
#: the added mass lowers a mode's frequency by at most this fraction (and raises it by none beyond its errors)
MAX_SHIFT = 0.3


def _masses(added_mass_kg, result: IdentificationResult) -> np.ndarray:
    n = result.n_channels
    names = list(result.settings.get("channel_names") or [])
    if not isinstance(added_mass_kg, dict) or not added_mass_kg:
        raise ParameterError(f"'added_mass_kg' is {added_mass_kg!r}; expected a dict {{channel: kg}} with at least "
                             "one channel")
    dm = np.zeros(n)
    for key, kg in added_mass_kg.items():
        if isinstance(key, (int, np.integer)) and 0 <= int(key) < n:
            ch = int(key)
        elif str(key) in names:
            ch = names.index(str(key))
        else:
            raise ParameterError(f"'added_mass_kg' names channel {key!r}; expected a 0-based index in [0, {n}) or "
                                 f"a channel name ({', '.join(names) or 'none given'})")
        if not (np.isfinite(kg) and kg > 0):
            raise ParameterError(f"'added_mass_kg' gives {kg!r} kg at channel {key!r}; expected a positive mass")
        dm[ch] += float(kg)
    return dm


def _aligned(reference: np.ndarray, shape: np.ndarray) -> np.ndarray:
    """``shape`` turned in phase so that ``referenceᴴ shape`` is real and positive."""
    inner = np.vdot(reference, shape)
    return shape * (np.conj(inner) / abs(inner)) if abs(inner) > 0 else shape


def _pair(mode, after: IdentificationResult):
    """The mode of ``after`` that is ``mode`` with mass added: highest MAC among those not far above it."""
    best, best_mac = None, PAIR_MAC
    for other in after:
        limit = 3 * np.hypot(mode.std.natural_frequency_hz, other.std.natural_frequency_hz)
        shift = other.natural_frequency_hz / mode.natural_frequency_hz - 1
        above = other.natural_frequency_hz - mode.natural_frequency_hz
        if not (-MAX_SHIFT <= shift and above <= np.nan_to_num(limit)):
            continue
        mac = shape_mac(mode.mode_shape, other.mode_shape)
        if mac >= best_mac:
            best, best_mac = other, mac
    return best


def _same_channels(before: IdentificationResult, after: IdentificationResult) -> None:
    """Refuse records of different channels (or of the same channels in another order), by their names."""
    if before.n_channels != after.n_channels:
        raise ParameterError(f"'before' ({_source(before)}) has {before.n_channels} channels and 'after' "
                             f"({_source(after)}) {after.n_channels}; expected records of the same channels")
    names = [list(r.settings.get("channel_names") or []) for r in (before, after)]
    if all(names) and names[0] != names[1]:
        how = "in another order" if sorted(names[0]) == sorted(names[1]) else "other channels"
        raise ParameterError(f"'after' ({_source(after)}) holds {how} than 'before' ({_source(before)}): channels "
                             f"{', '.join(names[1])} against {', '.join(names[0])}; expected the same channels in the "
                             "same order (the shapes are compared entry by entry)")


def _not_swapped(before: IdentificationResult, after: IdentificationResult) -> None:
    """Refuse a pair in which every mode found in both rose (beyond its errors) with the added mass: the
    records given in swapped order."""
    rose, pairs = [], 0
    for mode in before:
        best, best_mac = None, PAIR_MAC
        for other in after:
            shift = other.natural_frequency_hz / mode.natural_frequency_hz - 1
            mac = shape_mac(mode.mode_shape, other.mode_shape)
            if abs(shift) <= MAX_SHIFT and mac >= best_mac:
                best, best_mac = other, mac
        if best is None:
            continue
        pairs += 1
        limit = MIN_SHIFT_SIGMAS * np.hypot(mode.std.natural_frequency_hz, best.std.natural_frequency_hz)
        if best.natural_frequency_hz - mode.natural_frequency_hz > np.nan_to_num(limit):
            rose.append(f"{mode.natural_frequency_hz:.4g} -> {best.natural_frequency_hz:.4g} Hz")
    if pairs and len(rose) == pairs:
        raise ParameterError(f"every mode rose from 'before' ({_source(before)}) to 'after' ({_source(after)}): "
                             f"{', '.join(rose)}; added mass lowers the frequencies: expected 'before' without the "
                             "masses and 'after' with them (are the records swapped?)")


def _channels(result: IdentificationResult, dm) -> str:
    """The channels holding masses, by name where the record names them (else by 0-based index)."""
    names = list(result.settings.get("channel_names") or [])
    held = np.flatnonzero(dm)
    if len(names) == dm.size:
        return "channel(s) " + ", ".join(str(names[i]) for i in held)
    return "channel index(es) " + ", ".join(map(str, held)) + " (0-based)"


def _source(result: IdentificationResult) -> str:
    return str(result.settings.get("source", "<array>"))


def _scale(mode, other, dm):
    """α, ψ and the Jacobian of (α², ψ) with respect to (ω₀, ω₁, φ₀, φ₁), and the input standard errors."""
    w0, w1 = 2 * np.pi * mode.natural_frequency_hz, 2 * np.pi * other.natural_frequency_hz
    phi0 = np.asarray(mode.mode_shape, complex)
    phi1 = _aligned(phi0, np.asarray(other.mode_shape, complex))
    p0, p1 = phi0.real, phi1.real  # normal-mode form (the complex part is flagged complex_shape where large)
    D = w1**2 * np.sum(dm * p0 * p1)
    N = w0**2 - w1**2
    alpha2 = N / D if D != 0 else np.nan
    n = p0.size
    grad = np.zeros(2 + 2 * n)  # d α² / d (ω0, ω1, φ0, φ1)
    grad[0] = 2 * w0 / D
    grad[1] = -2 * w1 / D - 2 * alpha2 / w1
    grad[2:2 + n] = -alpha2 * w1**2 * dm * p1 / D
    grad[2 + n:] = -alpha2 * w1**2 * dm * p0 / D
    sd = np.concatenate([[2 * np.pi * mode.std.natural_frequency_hz, 2 * np.pi * other.std.natural_frequency_hz],
                         _shape_std(mode, n), _shape_std(other, n)])
    return alpha2, p0, grad, sd


def _shape_std(mode, n):
    s = mode.std.mode_shape
    return np.zeros(n) if s is None else np.nan_to_num(np.asarray(s, float))


def _location_misfit(pairs, dm) -> float:
    """How far the modes' shape changes are from what masses ``dm`` at the channels given make them.

    To first order, masses ΔM turn mode r's shape into φ₀,r + Σₛ bᵣₛ φ₀,ₛ with
    bᵣₛ = ωᵣ² αₛ² (φ₀,ₛᵀ ΔM φ₀,ᵣ) / (ωₛ² − ωᵣ²) (αₛ² the scale of mode s from its own shift): the frequency
    shifts alone fit any channel, the shape changes only the right one. ``pairs`` holds (mode, partner, α²,
    φ₀, φ₁) of the modes scaled; returns the RMS over mode pairs of the misfit of the observed bᵣₛ (φ₁,ᵣ
    projected on the φ₀'s, its component on φ₀,ᵣ one) in its errors: the shapes' noise and 20 % of the
    prediction (the perturbation's truncation), and the part of φ₁,ᵣ outside the φ₀'s (modes not identified,
    whose changes leak into the projection). NaN with fewer than two modes, or more modes than channels.
    """
    if len(pairs) < 2 or len(pairs) > pairs[0][3].size:
        return float("nan")
    basis = np.column_stack([p0 for _, _, _, p0, _ in pairs])
    inverse = np.linalg.pinv(basis)
    w0 = np.array([2 * np.pi * mode.natural_frequency_hz for mode, *_ in pairs])
    alpha2 = np.array([a2 for _, _, a2, _, _ in pairs])
    n = basis.shape[0]
    misfits = []
    for r, (mode, other, _, p0, p1) in enumerate(pairs):
        coef = inverse @ p1
        if coef[r] == 0:
            return float("nan")
        outside = np.linalg.norm(p1 - basis @ coef) / abs(coef[r])  # the change along modes not identified
        coef = coef / coef[r]
        noise = np.hypot(_shape_std(mode, n), _shape_std(other, n))
        for s in range(len(pairs)):
            if s == r:
                continue
            predicted = w0[r] ** 2 * alpha2[s] * np.sum(dm * basis[:, s] * p0) / (w0[s] ** 2 - w0[r] ** 2)
            error = np.linalg.norm([np.linalg.norm(inverse[s] * noise), 0.2 * abs(predicted),
                                    np.linalg.norm(inverse[s]) * outside])
            misfits.append((coef[s] - predicted) / error if error > 0 else 0.0)
    return float(np.sqrt(np.mean(np.square(misfits))))


def _driving_points(psi, jac_psi, inputs_sd):
    """Standard errors of ψ and the covariance (channels, 4, 4) of (ωn, ζ, Re A, Im A) with A = ψ² per
    channel, from ψ's gradient ``jac_psi`` (channels × inputs) over independent inputs of standard errors
    ``inputs_sd``, the first the natural frequency (rad/s), the last the damping ratio."""
    sd2 = np.asarray(inputs_sd, float) ** 2
    n, n_in = jac_psi.shape
    grad = np.zeros((n, 4, n_in))
    grad[:, 0, 0] = 1.0
    grad[:, 1, -1] = 1.0
    grad[:, 2] = 2 * psi[:, None] * jac_psi  # ∂ψ²/∂inputs (Im A stays 0: a real shape)
    cov = (grad * sd2) @ np.swapaxes(grad, 1, 2)
    return np.sqrt(jac_psi**2 @ sd2), cov


def scale_by_mass_change(before: IdentificationResult, after: IdentificationResult,
                         added_mass_kg: dict) -> IdentificationResult:
    """The first record's modes with mass-normalised shapes and per-channel k, c, m.

    Parameters
    ----------
    before, after : IdentificationResult
        Operational results (:func:`modal.oma`) of the same channels without and with the added masses.
    added_mass_kg : dict
        ``{channel: kg}``: the masses added at measured channels (0-based index or channel name).

    Returns
    -------
    IdentificationResult
        ``before``'s modes with ``mode_shape`` mass-normalised (1/√kg), ``modal_constant`` ψ_j² (1/kg)
        and ``mass_kg``, ``stiffness_n_per_m``, ``damping_n_s_per_m`` per channel, with standard errors
        and their correlation; a mode without a partner in ``after`` (MAC ≥ 0.8, lower frequency), or whose
        frequency shift or scale is not determined, is flagged ``scaling_uncertain``.

    Raises
    ------
    ParameterError
        Records of different channels (by number or by name, or in another order), masses at channels not
        measured or not positive, or records in swapped order (every mode found in both higher in ``after``).
    """
    _same_channels(before, after)
    dm = _masses(added_mass_kg, before)
    _not_swapped(before, after)
    scaled, pairs = [], []
    for mode in before:
        other = _pair(mode, after)
        if other is None:
            scaled.append((None, None, None, True))
            continue
        alpha2, p0, grad, sd = _scale(mode, other, dm)
        if not (np.isfinite(alpha2) and alpha2 > 0):
            scaled.append((None, None, None, True))
            continue
        pairs.append((mode, other, alpha2, p0, _aligned(p0, np.asarray(other.mode_shape, complex)).real))
        n = p0.size
        var_alpha2 = float(np.sum((grad * sd) ** 2))
        shift_sd = np.hypot(mode.std.natural_frequency_hz, other.std.natural_frequency_hz)
        shift = mode.natural_frequency_hz - other.natural_frequency_hz
        alpha = np.sqrt(alpha2)
        # ψ_j = α φ0_j: gradient over (ω0, ω1, φ0, φ1) and the damping ratio (for c)
        jac_psi = np.outer(p0, grad / (2 * alpha))
        jac_psi[np.arange(n), 2 + np.arange(n)] += alpha
        jac_psi = np.hstack([jac_psi, np.zeros((n, 1))])
        inputs_sd = np.concatenate([sd, [mode.std.damping_ratio]])
        psi = alpha * p0
        psi_std, cov = _driving_points(psi, jac_psi, inputs_sd)
        uncertain = (not shift > MIN_SHIFT_SIGMAS * np.nan_to_num(shift_sd)
                     or not np.sqrt(var_alpha2) / alpha2 / 2 <= MAX_SCALE_ERROR)
        scaled.append((psi, psi_std, cov, uncertain))
    misfit = _location_misfit(pairs, dm)
    if misfit > MAX_LOCATION_MISFIT:
        warnings.warn(f"{_source(after)}: the modes' shape changes disagree with masses at {_channels(before, dm)} "
                      f"(misfit {misfit:.3g} of its errors, above "
                      f"{MAX_LOCATION_MISFIT:g}): were the masses added at other channels? every mode's scaling is "
                      "flagged scaling_uncertain", QualityWarning, stacklevel=2)
        scaled = [(psi, psi_std, cov, True) for psi, psi_std, cov, _ in scaled]
    settings = {**before.settings, "added_mass_kg": {str(k): float(v) for k, v in added_mass_kg.items()},
                "scaled_by": "mass_change"}
    return scaled_result(before, scaled, settings)
