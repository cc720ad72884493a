"""From what a method found to :class:`~modal.results.ModeResult`: one place for every method.

A method (band-wise half-power, circle or NLS in :mod:`modal.sdof`, the global
pLSCF in :mod:`modal.global_`, an output-only estimator) describes each mode as a
:class:`ModeEstimate`: its pole, modal constants and their covariance, the flags
only it can raise. :func:`assemble_modes` then applies the rules that hold for
every method, in one order:

1. the flags of the rules in :mod:`modal.flags`: ``high_uncertainty`` (relative
   error of ζ), ``close_modes`` (modal overlap with any other mode),
   ``driving_point_unknown``;
2. the exponential window's damping taken out of the pole
   (:func:`modal.window_damping.remove_window_damping`);
3. k, c, m of the driving points with their covariance, and the flags on the
   way (``complex_mode``, ``non_positive_constant``, ``not_driving_point``), and none on a driving
   point whose constants change sign between modes (``driving_point_contradicted``);
4. one :class:`~modal.results.ModeResult` per mode, and a warning per flagged mode
   that names every flag and why (:data:`modal.flags.FLAG_TEXT`).
"""
from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import Sequence

import numpy as np

from .errors import IdentificationError, QualityWarning, ResolutionWarning, warn_caller
from .flags import (COMPLEX_PHASE_DEG, FLAG_TEXT, OVERLAP_LIMIT, REL_STD_LIMIT, RESOLUTION_FLAGS, SIGN_SIGMAS, overlap,
                    serious_flags)
from .results import ModeResult, ModeStd, correlation_of, physical_covariance, physical_parameters
from .units import TWO_PI
from .validate import channel_mask
from .window_damping import remove_window_damping, window_constant_factor

__all__ = ["ModeEstimate", "assemble_modes", "driving_points"]


@dataclass
class ModeEstimate:
    """One mode as a method found it, before the shared rules are applied.

    Attributes
    ----------
    omega_n : float
        Natural frequency, rad/s (as measured: an exponential window's damping still in it).
    damping_ratio : float
    modal_constant : ndarray of complex, shape (n_channels,), or None
        Receptance modal constant per channel, 1/kg (NaN where the method gives none); None: the
        method scales no constants (an output-only method's shapes go in ``mode_shape``).
    covariance : ndarray, shape (n_channels, 4, 4), or None
        Covariance of (ωn [rad/s], ζ, Re A, Im A [1/kg]) per channel; None: not known (NaN).
    std_omega_n, std_damping_ratio : float
        Standard errors of the pole, rad/s and 1; they may exceed ``covariance``'s (a bias folded in).
    band_hz : (float, float)
        Band the mode was fitted on, Hz.
    n_lines : int
        Lines in that band.
    lines_per_bandwidth : float
        Lines per half-power bandwidth 2ζfn.
    flags : set of str
        The flags only the method can raise (it adds them here).
    details : dict of str
        Text to append to a flag's reason in the warning (``{"missing_mode": " (near 12.3 Hz, ...)"}``).
    chi2, quality : float
        As in :class:`~modal.results.ModeResult`.
    reference : tuple or None
        ``(ωn, ζ, constants, covariance)`` of the refinement a biased estimate (flag ``method_bias``)
        was measured against, with the covariance before the bias was folded in: k, c, m take the
        bias exactly (see :func:`physical_with_flags`).
    mode_shape, participation, mpc
        As in :class:`~modal.results.ModeResult` (methods that give them).
    std_mode_shape : ndarray, shape (n_channels,), or None
        Standard error of each entry of ``mode_shape``, sqrt(var Re + var Im) (methods that give it:
        the output-only ones).
    """

    omega_n: float
    damping_ratio: float
    modal_constant: np.ndarray | None
    covariance: np.ndarray | None
    std_omega_n: float
    std_damping_ratio: float
    band_hz: tuple[float, float]
    n_lines: int
    lines_per_bandwidth: float
    flags: set[str] = field(default_factory=set)
    details: dict[str, str] = field(default_factory=dict)
    chi2: float = float("nan")
    quality: float = float("nan")
    reference: tuple | None = None
    mode_shape: np.ndarray | None = None
    participation: np.ndarray | None = None
    mpc: float = float("nan")
    std_mode_shape: np.ndarray | None = None


def driving_points(frf, driving_point=None) -> tuple[np.ndarray, bool]:
    """Which channels are driving points (bool per channel), and whether that is known at all.

    The one rule of the toolkit: k, c, m exist only for a channel known to be a driving point, from
    the point ids (response point = reference point, :meth:`modal.frf.FRF.is_driving_point`) or
    declared by the caller. ``driving_point``: the declaration (a bool for every channel, one bool per
    channel, or 0-based channel indices; the channels not named are then not driving points). Without
    it and without point ids nothing says where the response was measured: no channel is a driving
    point and the second value is False (flag ``driving_point_unknown``).
    """
    if driving_point is not None:
        return channel_mask("driving_point", driving_point, frf.n_channels, IdentificationError), True
    return frf.is_driving_point(), frf.driving_point_known


def physical_with_flags(wn, zeta, const, cov, driving, flags: set[str], reference=None, phase_check: bool = True,
                        driving_known: bool = True):
    """k, c, m, their standard errors and covariance (n_ch, 3, 3) of a mode; flags on the way.

    NaN on transfer channels (flag ``not_driving_point``), on every channel when ``driving_known`` is
    False (flag ``driving_point_unknown``), and where the driving point's constant has no positive real part.
    ``reference`` (ωn, ζ, constants, covariance before the fold) of a biased estimate
    (flag ``method_bias``): the difference of k, c, m from those of the reference is
    folded into their covariance (exactly, not to first order: a rotated constant
    changes |A| only to second order). ``phase_check``: raise ``complex_mode`` for a driving
    point's constant far from real (methods that judge complexity otherwise pass False).
    """
    (k, c, m), _ = physical_parameters(wn, zeta, const)
    cov_kcm = physical_covariance(wn, zeta, const, cov if reference is None else reference[3])
    if reference is not None:
        (k_r, c_r, m_r), _ = physical_parameters(*reference[:3])
        diff = np.nan_to_num(np.stack([k - k_r, c - c_r, m - m_r], axis=-1))
        cov_kcm = cov_kcm + diff[..., :, None] * diff[..., None, :]
    const = np.asarray(const)
    if driving.any():
        dp_phase = np.abs(np.angle(const[driving]))
        if phase_check and np.any(dp_phase > np.deg2rad(COMPLEX_PHASE_DEG)) and np.all(const[driving].real > 0):
            flags.add("complex_mode")
        if np.any(const[driving].real <= 0):
            flags.add("non_positive_constant")
    undefined = ~driving | (const.real <= 0)
    for arr in (k, c, m):
        arr[undefined] = np.nan
    cov_kcm[undefined] = np.nan
    sk, sc, sm = (np.sqrt(np.maximum(cov_kcm[..., i, i], 0.0)) for i in range(3))
    for arr in (sk, sc, sm):
        arr[undefined] = np.nan
    if not driving_known:
        flags.add("driving_point_unknown")
    elif (~driving).any():
        flags.add("not_driving_point")
    return (k, c, m), (sk, sc, sm), cov_kcm


def assemble_modes(estimates: Sequence[ModeEstimate], *, method: str, source: str, single: bool,
                   driving: np.ndarray | None, driving_known: bool = True, window_decay_s: float | None = None,
                   phase_check: bool = True, window_power: int = 0) -> tuple[ModeResult, ...]:
    """The :class:`~modal.results.ModeResult` of every mode, with the flags every method shares, and a
    warning per flagged mode.

    Parameters
    ----------
    estimates : sequence of ModeEstimate
        Every mode the method found (the overlap of each with all the others is measured).
    method : str
        Name in the results and the warnings.
    source : str
        The FRF's source (file name), for the warnings.
    single : bool
        One channel: the per-channel fields are scalars.
    driving : ndarray of bool, shape (n_channels,), or None
        Driving-point channels (k, c, m defined); see :func:`driving_points`. None: no channel has
        an input (output-only data): no k, c, m and no driving-point flags.
    driving_known : bool
        False: neither point ids nor the caller say which channel is a driving point: no k, c, m
        (flag ``driving_point_unknown``).
    window_decay_s : float, optional
        τ of an exponential window whose damping is taken out of every pole.
    window_power : int
        The power of iω of the FRF's kind (1 mobility, 2 accelerance), taken as what the windowed records
        measured: the window turned the modal constants by (p/p')^power, taken back out
        (:func:`modal.window_damping.window_constant_factor`).
    phase_check : bool
        Raise ``complex_mode`` from a driving point's phase (see :func:`physical_with_flags`).

    Warns
    -----
    ResolutionWarning
        A mode carries one of :data:`modal.flags.RESOLUTION_FLAGS`.
    QualityWarning
        A mode carries any other flag but the informational ones.
    """
    omega_n = np.array([e.omega_n for e in estimates], float)
    damping_ratio = np.array([e.damping_ratio for e in estimates], float)
    overlaps = [overlap(omega_n, damping_ratio, index) for index in range(len(estimates))]
    modes, details, below_zero = [], [], []
    for estimate, mode_overlap in zip(estimates, overlaps):
        flags = set(estimate.flags)
        wn, zeta = estimate.omega_n, estimate.damping_ratio
        s_wn, s_z = estimate.std_omega_n, estimate.std_damping_ratio
        if estimate.modal_constant is None:
            channels = 1 if estimate.mode_shape is None else np.size(estimate.mode_shape)
            const = np.full(channels, np.nan, complex)
        else:
            const = np.asarray(estimate.modal_constant, complex)
        cov = estimate.covariance
        if cov is None:
            cov = np.full((const.size, 4, 4), np.nan)
        reference = estimate.reference
        if np.isfinite(s_z) and np.isfinite(zeta) and zeta > 0 and s_z / zeta > REL_STD_LIMIT:
            flags.add("high_uncertainty")
        if mode_overlap > OVERLAP_LIMIT:
            flags.add("close_modes")
        window_zeta = 0.0
        if window_decay_s is not None:
            # the exponential window's damping out again (exact pole shift by 1/τ)
            wn_measured, zeta_measured = wn, zeta
            wn, zeta, cov, s_wn, s_z, window_zeta, valid = remove_window_damping(wn, zeta, cov, s_wn, s_z,
                                                                                 window_decay_s)
            if reference is not None:  # the same exact shift of the reference pole
                reference = (reference[0] + wn - wn_measured, reference[1] + zeta - zeta_measured, *reference[2:])
            if not valid:
                flags.add("window_damping_dominates")
            elif window_power:  # the windowed record was a velocity or an acceleration: its constants turned
                factor = window_constant_factor(wn_measured, zeta_measured, wn, zeta, window_power)
                const = const * factor
                turn = np.eye(4)
                turn[2:, 2:] = [[factor.real, -factor.imag], [factor.imag, factor.real]]
                cov = turn @ cov @ turn.T
                if reference is not None:
                    reference = (*reference[:2], np.asarray(reference[2]) * factor, *reference[3:])
        if driving is None:  # output-only: nothing scales the shapes to k, c, m
            k = c = m = sk = sc = sm = np.full(const.shape, np.nan)
            cov_kcm, inputs = None, np.zeros(const.shape, bool)
        else:
            (k, c, m), (sk, sc, sm), cov_kcm = physical_with_flags(wn, zeta, const, cov, driving, flags, reference,
                                                                   phase_check, driving_known)
            inputs = driving
        s_const = np.sqrt(np.maximum(cov[:, 2, 2] + cov[:, 3, 3], 0))
        sq = (lambda a: a.reshape(-1)[0].item()) if single else (lambda a: np.asarray(a))
        std = ModeStd(s_wn / TWO_PI, s_z, sq(s_const), sq(sk), sq(sc), sq(sm), mode_shape=estimate.std_mode_shape)
        flags_t = tuple(sorted(flags))
        modes.append(ModeResult(
            natural_frequency_hz=float(wn / TWO_PI), damping_ratio=float(zeta), modal_constant=sq(const),
            stiffness_n_per_m=sq(k), damping_n_s_per_m=sq(c), mass_kg=sq(m), std=std, flags=flags_t,
            method=method, band_hz=estimate.band_hz, n_lines=int(estimate.n_lines),
            lines_per_bandwidth=float(estimate.lines_per_bandwidth), chi2=estimate.chi2, driving_point=sq(inputs),
            quality=estimate.quality, window_damping_ratio=window_zeta,
            mode_shape=estimate.mode_shape, participation=estimate.participation, mpc=estimate.mpc,
            kcm_correlation=None if cov_kcm is None else correlation_of(cov_kcm[0] if single else cov_kcm)))
        details.append(estimate.details)
        below_zero.append(np.nan_to_num(const.real + SIGN_SIGMAS * np.sqrt(np.maximum(cov[:, 2, 2], 0)), nan=1.0) < 0)
    if driving is not None and modes:
        contradicted = np.asarray(driving, bool) & np.any(below_zero, axis=0)
        if contradicted.any():
            modes = [_contradicted(mode, contradicted, single) for mode in modes]
        inverted = np.asarray(driving, bool) & np.all(below_zero, axis=0)
        if inverted.any():
            # every mode below zero is what a sign error gives, not a transfer FRF (whose constants change sign)
            said = (" (here every mode's constant lies below zero: the force and the response point opposite ways, "
                    "a sensor mounted the other way round, a negative sensitivity or point ids whose directions "
                    "disagree; with one channel's sign turned, k, c, m follow)")
            details = [{**(detail or {}), "driving_point_contradicted": said} for detail in details]
    for mode, detail in zip(modes, details):
        serious = serious_flags(mode.flags)
        if serious:
            category = ResolutionWarning if serious & RESOLUTION_FLAGS else QualityWarning
            reasons = "; ".join(f"{f}: {FLAG_TEXT[f]}{detail.get(f, '')}" for f in sorted(serious))
            warn_caller(f"{source}: {method} mode near {mode.natural_frequency_hz:.6g} Hz is flagged ({reasons})",
                        category)
    return tuple(modes)


def _contradicted(mode: ModeResult, channels: np.ndarray, single: bool) -> ModeResult:
    """``mode`` without k, c, m on ``channels`` (driving points whose constants change sign between modes, so
    none: flag ``driving_point_contradicted``)."""
    def cleared(value):
        if value is None:
            return None
        if single:
            return float("nan")
        out = np.array(value, dtype=float)
        out[channels] = np.nan
        return out

    std = replace(mode.std, stiffness_n_per_m=cleared(mode.std.stiffness_n_per_m),
                  damping_n_s_per_m=cleared(mode.std.damping_n_s_per_m), mass_kg=cleared(mode.std.mass_kg))
    correlation = mode.kcm_correlation
    if correlation is not None:
        correlation = np.array(correlation, dtype=float)
        if single:
            correlation[...] = np.nan
        else:
            correlation[channels] = np.nan
    return replace(mode, stiffness_n_per_m=cleared(mode.stiffness_n_per_m),
                   damping_n_s_per_m=cleared(mode.damping_n_s_per_m), mass_kg=cleared(mode.mass_kg), std=std,
                   kcm_correlation=correlation, flags=tuple(sorted({*mode.flags, "driving_point_contradicted"})))
