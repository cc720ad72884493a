"""Quality flags, defined once: what each means (:data:`FLAG_TEXT`), the limits that raise them,
what a user should do about it (:data:`FLAG_ACTION`), which flags belong to a channel rather than
to the mode, which combinations would contradict each other, and the rules every method applies
(:func:`model_inadequate`, :func:`overlap`). :mod:`modal.flag_table` writes them as the table of
docs/flags.md.
"""
from __future__ import annotations

import numpy as np

from .frf import line_spacing

__all__ = ["FLAG_TEXT", "FLAG_ACTION", "CHI2_LIMIT", "RELATIVE_MISFIT", "REL_STD_LIMIT", "OVERLAP_LIMIT", "BIAS_LIMIT",
           "COMPLEX_PHASE_DEG", "MPC_LIMIT", "WEAK_FRACTION", "RIGID_BODY_RATIO", "HARMONIC_TOLERANCE",
           "HARMONIC_SIGMAS", "KURTOSIS_LIMIT", "MIN_DECAYS", "MIN_SHIFT_SIGMAS", "MAX_SCALE_ERROR", "MAX_LOCATION_MISFIT", "SIGN_SIGMAS", "GRID_FLAGS", "RESOLUTION_FLAGS", "RULE_FLAGS",
           "INFORMATIONAL", "serious_flags", "DRIVING_POINT_ONLY", "TRANSFER_ONLY", "lines_near_mode", "model_inadequate", "overlap",
           "channel_flags", "contradictions", "WITHOUT_KCM"]

#: chi-square (residual variance over the noise variance) above which a model may be flagged model_inadequate
CHI2_LIMIT = 3.0
#: ... and only when the misfit near the mode is also more than this fraction of the data there (RMS over
#: the lines within ±3 half-power widths, at least ±3 lines). Calibrated on the real beam (data/real): its
#: clean modes show 0.2-2.4 % misfit at chi-square 770-4600 (a linear viscous model on measured data:
#: calibration, leakage on under-resolved peaks; the line-to-line noise there is tiny), while modes merged
#: into one peak show 4.5 % (three modes, exact data) and 5.3 % (a pair 1 Hz apart, 0.2 % noise). On noisy
#: data chi-square alone decides: a misfit of 3 noise σ there is above this fraction already.
RELATIVE_MISFIT = 0.03
#: a driving point's modal constant whose real part lies more than this many standard errors below zero shows the
#: channel is no driving point (a driving point's constants are all positive: A = φ_dp²), and its other modes'
#: positive constants give no k, c, m either (flag driving_point_contradicted); 3 σ: a right driving point's
#: weak mode with a constant near zero falls below it by noise in 0.13 % of estimates (one-sided Gaussian)
SIGN_SIGMAS = 3.0
#: relative standard error of ζ above which an estimate is flagged high_uncertainty
REL_STD_LIMIT = 0.1
#: modal overlap 2·max(ζωn)/|Δωn| with another mode above which close_modes is raised: up to 1.5 the
#: NLS errors match the scatter (SD of z 0.95 at 1.2, 1.15 at 1.5, over 100 seeds at 1.6 % noise); at 2
#: they are 2–4× optimistic (docs/stress.md)
OVERLAP_LIMIT = 1.5
#: half-power and circle fits: an estimate further than this many of its own standard errors from the
#: least-squares refinement of the same modes is flagged method_bias
BIAS_LIMIT = 3.0
#: phase of a driving point's modal constant (deg) above which complex_mode is raised
COMPLEX_PHASE_DEG = 10.0
#: MPC below which a mode's shape counts as complex (complex_shape)
MPC_LIMIT = 0.8
#: a selected pole stable (in frequency) in fewer than this fraction of the swept orders has weak evidence
WEAK_FRACTION = 0.5
#: a mode below this fraction of the next mode's frequency counts as a rigid-body / suspension mode
RIGID_BODY_RATIO = 0.1
#: operational analysis: a pole lies on a harmonic k·f₀ of the running speed when within this fraction of it
#: (the speed varies a little over a record)...
HARMONIC_TOLERANCE = 0.005
#: ... or within this many of its frequency's standard errors (flag harmonic)
HARMONIC_SIGMAS = 3.0
#: operational: kurtosis of the response band-passed around a pole's strongest line below which it holds a
#: sinusoid (a machine tone): 3 for Gaussian narrow-band response, 1.5 for a pure tone, 2.25 for two equal tones.
#: The estimate (from the band's lines, never below 1.5) has a short lower tail: for Gaussian response over
#: 64 lines (``modal.operational.tones.MIN_BANDWIDTH_TIME``) its 10⁻⁴ quantile is 2.27 with a flat spectrum and
#: 2.18 with a mode's bell spanning the band (10⁵ draws each; ``tests/modal/operational/test_tones.py`` checks
#: the margin)
KURTOSIS_LIMIT = 1.95
#: operational: a pole whose damping ratio, less three of its standard errors, gives at least this many decay
#: times ζ·2πf·T in a record of T seconds would be Gaussian random response were it a structural mode: its
#: kurtosis alone then tells a tone (flag tone_like below it). Random response of one mode (10 % noise)
#: band-passed over 64 lines around its strongest line, 1000 records per case: kurtosis below
#: :data:`KURTOSIS_LIMIT` in 16 % of them at ζωT = 2, 5 % at 4, 0.2 % at 8, none at 16 (smallest 2.05; 2.15 at
#: 32); ``tests/modal/operational/test_tones.py`` checks it at this limit
MIN_DECAYS = 16.0
#: mass-change scaling: the frequency shift must exceed this many of its standard errors...
MIN_SHIFT_SIGMAS = 3.0
#: ... and the scale factor's relative standard error stay at or below this, else scaling_uncertain
MAX_SCALE_ERROR = 0.1
#: ... and the modes' shape changes agree with masses at the channels given: the RMS over mode pairs of the
#: first-order shape change's misfit, in its errors (shape noise, and 20 % of the prediction for the
#: perturbation's truncation, and the change along modes not identified), stays at or below this. On the 4-mass
#: chain of tests/modal/operational/test_scaling.py, one mass of 50-300 g at a random channel, 12 pairs of records
#: per case: given where added, largest 1.69 (1500 s records, all 4 modes), 1.00 (300 s), 1.21 (2 modes in the
#: band); given at the next channel, median 7.3, 4.9, 4.4 (smallest 4.3, 2.0, 1.3: not every wrong channel shows)
MAX_LOCATION_MISFIT = 3.0

#: Every quality flag with the reason it is raised.
FLAG_TEXT = {
    "resolution_limited": "fewer than 3 lines above the half-power level: damping is below what the lines resolve",
    "missing_crossing": "a half-power (-3 dB) crossing is missing in the band",
    "band_edge_peak": "the peak lies at the edge of the band: the band does not contain the resonance",
    "too_few_points": "too few lines near resonance for this method",
    "damping_pair_spread": "circle fit: the damping estimates from point pairs disagree by more than 10 %",
    "model_inadequate": (f"residual is much larger than the noise (chi-square > {CHI2_LIMIT:g}) and more than "
                         f"{100 * RELATIVE_MISFIT:g} % of the data near the mode: the model does not explain the data "
                         "(close modes, missing mode, nonlinearity)"),
    "high_uncertainty": (f"standard error of the damping ratio exceeds {100 * REL_STD_LIMIT:g} % of its value, or the "
                         "errors are undetermined (the data do not determine this mode's pole apart from another's)"),
    "did_not_converge": "least-squares refinement did not converge; the start values are reported",
    "work_capped": ("identify stopped at a work budget scaled to the size of the problem: the least-squares "
                    "refinement at its budget of model evaluations (max_evaluations) before converging (the "
                    "estimates are where it stood, its checks were cut short), or the global method's "
                    "stabilisation sweep on fewer lines or orders, or its refinement on fewer modes than proposed; "
                    "modes may be missing"),
    "driving_point_unknown": ("nothing says which channel was measured at the excitation point (no point ids, none "
                              "declared): k, c, m are not given"),
    "not_driving_point": "transfer FRF (response point differs from reference): k, c, m are not defined for it",
    "units_unknown": ("the FRF's unit is neither the kind's SI unit nor one the toolkit converts (V/V: sensitivities "
                      "not applied): k, c, m in N/m, N s/m, kg are not given"),
    "complex_mode": (f"modal constant of a driving point is far from real (phase > {COMPLEX_PHASE_DEG:g} deg): "
                     "k, c, m are approximate"),
    "non_positive_constant": "driving-point modal constant has a negative real part: k, c, m not defined",
    "driving_point_contradicted": (f"the channel taken as a driving point has another mode whose modal constant's "
                                   f"real part lies more than {SIGN_SIGMAS:g} standard errors below zero, where a "
                                   "driving point's constants are all positive: the channel is a transfer FRF (or "
                                   "its point ids or declaration are wrong); k, c, m not given on it for any mode"),
    "close_modes": ("another mode lies within this mode's fitting band, or overlaps it "
                    f"(2*zeta*wn/delta_wn > {OVERLAP_LIMIT:g}): the standard errors understate the scatter"),
    "missing_mode": ("the residual holds another mode in or next to this band that peak detection missed (one more "
                     "mode reduces it significantly, F-test at 1e-6), or this mode moves by more than 3 of its errors "
                     "once that mode is in the model; the estimates are biased by it: give bands_hz for both modes "
                     "or lower min_prominence_db"),
    "window_damping_dominates": ("the exponential window's decay 1/tau is not below the mode's measured decay rate: "
                                 "all its damping may be the window's, so it was not removed; use a longer tau"),
    "weak_evidence": ("global: the pole is stable in fewer than half of the upper half of the model orders of the "
                      "stabilisation diagram (or a modes_hz hint picked a pole stable in fewer than 3); operational: "
                      "in fewer than half of the orders swept: a weakly excited mode or a noise pole; check the "
                      "diagram and the shape before using it"),
    "outside_band": ("global: the mode lies below the first resolvable lines or above the band: its parameters "
                     "are extrapolated; widen the band or treat it as a residual"),
    "rigid_body": ("global: the mode lies below a tenth of the next mode's frequency: a rigid-body or suspension "
                   "mode of a free structure, not a flexible mode"),
    "complex_shape": (f"global and operational: the modal constants (the shape) are far from collinear in phase "
                      f"(MPC < {MPC_LIMIT:g}): a complex mode, or noise/close modes; k, c, m and shape comparisons "
                      "are approximate"),
    "method_bias": (f"half-power or circle estimate lies more than {BIAS_LIMIT:g} of its standard errors from the "
                    "least-squares refinement of the same modes (the method's own bias: line spacing, noise at the "
                    "peak, a neighbouring mode); its standard errors include the difference, method 'nls' gives the "
                    "refined values"),
    # operational (output-only) analysis
    "harmonic": (f"operational: the mode lies on a harmonic k x f0 of the running speed (rotor_speed_hz, or the "
                 f"fundamental the machine tones share), within {HARMONIC_SIGMAS:g} of its standard errors or "
                 f"{100 * HARMONIC_TOLERANCE:g} %, where a machine tone may bias its frequency and damping"),
    "scaling_uncertain": (f"mass-change scaling: the mode has no partner in the record with added mass, its frequency "
                          f"shift is below {MIN_SHIFT_SIGMAS:g} of its standard errors, or the scale factor's standard "
                          f"error exceeds {100 * MAX_SCALE_ERROR:g} % of it (too little added mass, or added where "
                          "the mode barely moves), or the modes' shape changes disagree with masses at the channels "
                          f"given (misfit above {MAX_LOCATION_MISFIT:g} of its errors: added at another channel?): the "
                          "mass-normalised shape and k, c, m are poorly determined"),
    "missing_in_setup": ("merged setups: the mode was not found in every setup; the shape entries of the setups "
                         "without it are NaN"),
    "mains_hum": ("operational: the mode lies within 1 % of a multiple of the mains frequency (50 or 60 Hz) where a "
                  "channel's spectrum holds a line far above its surroundings: electrical hum; frequency, damping and "
                  "shape may be the hum's"),
    "tone_like": (f"operational: the response band-passed around the mode's strongest line is a sinusoid's "
                  f"(kurtosis below {KURTOSIS_LIMIT:g}, where random response gives 3), but its damping, less three "
                  f"standard errors, gives fewer than {MIN_DECAYS:g} decay times in the record: a machine tone or hum "
                  f"the record cannot tell from a mode this lightly damped; frequency, damping and shape may be the "
                  f"tone's"),
    "non_stationary": ("operational: the record is not stationary random response (its kurtosis lies far above a "
                       "Gaussian response's 3: hammer hits, shocks or bursts ringing down): frequency, damping and "
                       "their errors assume stationary random forces and are biased"),
}


def lines_near_mode(omega: np.ndarray, omega_n: float, damping_ratio: float) -> np.ndarray:
    """The lines (mask over ``omega``, rad/s) where :data:`RELATIVE_MISFIT` is measured for a mode at
    ``omega_n`` (rad/s): within ±3 half-power widths of it, at least ±3 line spacings."""
    spacing = line_spacing(omega) if omega.size > 1 else 0.0
    return np.abs(omega - omega_n) <= max(3 * 2 * damping_ratio * omega_n, 3 * spacing)


def model_inadequate(chi2: float, relative_misfit: float) -> bool:
    """Whether a mode's model is inadequate where a user should act: the misfit near it exceeds the noise
    (``chi2`` above :data:`CHI2_LIMIT`) and is more than :data:`RELATIVE_MISFIT` of the data there (a NaN
    relative misfit, not measured, leaves the chi-square alone to decide)."""
    return bool(np.isfinite(chi2) and chi2 > CHI2_LIMIT and not relative_misfit <= RELATIVE_MISFIT)


def overlap(omega_n: np.ndarray, damping_ratio: np.ndarray, index: int) -> float:
    """Largest modal overlap 2·max(ζωn)/|Δωn| of mode ``index`` with any other mode (modes without a finite
    pole are left out; infinite for two modes at one frequency); compared with :data:`OVERLAP_LIMIT`."""
    wn, zeta = omega_n[index], damping_ratio[index]
    worst = 0.0
    for other, (wn_o, zeta_o) in enumerate(zip(omega_n, damping_ratio)):
        if other == index or not (np.isfinite(wn_o) and np.isfinite(zeta_o)):
            continue
        gap = abs(wn_o - wn)
        width = 2 * max(zeta * wn, zeta_o * wn_o)
        worst = max(worst, width / gap if gap > 0 else np.inf)
    return worst

#: What to do when a flag is raised.
FLAG_ACTION = {
    "resolution_limited": "measure with a finer line spacing (longer record) around the mode, or trust the "
                          "nls estimate, which fits the shape of the peak rather than counting lines (not that of "
                          "an FRF estimated from time records: there take longer segments, segment_length / "
                          "--segment-length, so that the half-power band holds at least 3 lines)",
    "missing_crossing": "widen the band (--band) so that it holds both half-power points, or use method nls",
    "band_edge_peak": "give a band centred on the resonance with --band FMIN FMAX",
    "too_few_points": "widen the band or measure a finer line spacing",
    "damping_pair_spread": "use method nls; the circle is distorted (noise, a neighbouring mode or nonlinearity)",
    "model_inadequate": "look at the fit plot (--plot): add the neighbouring mode with --band, check for "
                        "nonlinearity (amplitude-dependent peaks) or a bad channel",
    "high_uncertainty": "average more measurements or improve the signal-to-noise ratio near the mode",
    "did_not_converge": "give a band around the mode with --band, or try method global",
    "work_capped": "raise the budget (identify(..., max_evaluations=N), --max-evaluations N with N above the one the "
                   "result's settings give), or fit fewer modes or lines at once: --band for the modes of interest, "
                   "a cropped band, or method nls for a file of many modes (the warning says which budget bound)",
    "driving_point_unknown": "declare the channel measured at the excitation point: --driving-point CHANNEL "
                             "(modal fit, modal batch; channels counted from 1, or a point id), driving_point = "
                             "CHANNEL under [identify] in a scene, identify(frf, driving_point=...) in Python; or "
                             "give the file point ids (response point = reference point at the driving point)",
    "not_driving_point": "nothing to do: a transfer FRF gives frequency, damping and modal constant but no k, c, m",
    "units_unknown": "give the channels in physical units (sensitivities applied) or label the FRF with a unit the "
                     "readers convert (m, mm, in; m/s, mm/s, in/s; m/s^2, mm/s^2, g, in/s^2; over N, kN or lbf)",
    "complex_mode": "check for close modes or non-proportional damping; k, c, m use |A| and are approximate",
    "non_positive_constant": "check the sign convention of the force and response channels and the driving-point "
                             "declaration; k, c, m are not reported",
    "driving_point_contradicted": ("check which channel was measured at the excitation point (--driving-point, "
                                   "driving_point=, or the file's point ids): that channel's modal constants are "
                                   "all positive; a channel whose constants change sign is a transfer FRF"),
    "close_modes": "fit the close modes together (method nls with a --band per mode, or method global)",
    "missing_mode": "give --band for both modes, or lower the peak threshold (min_prominence_db)",
    "window_damping_dominates": "measure with a longer exponential window time constant tau",
    "weak_evidence": "check the stabilisation diagram (--stabilisation-plot) and the mode shape; excite the "
                     "mode better or drop it",
    "outside_band": "widen the measured band around the mode, or treat it as a residual term",
    "rigid_body": "nothing to do for flexible modes; do not use it as a structural mode",
    "complex_shape": "check for close modes or noise; k, c, m and shape comparisons are approximate",
    "method_bias": "use the nls (or global) values, which the half-power and circle estimates start from",
    "harmonic": "check the running speed; measure at another speed to move the tone off the mode",
    "scaling_uncertain": "add more mass (a frequency shift of 2-5 %), where the mode moves most; check the "
                         "channels the masses are given at",
    "missing_in_setup": "excite the mode better in that setup, or leave its channels out of the merged shape",
    "mains_hum": "ground the sensors' cables at one point (a ground loop) or shield them, and measure again; or "
                 "leave the humming channels out",
    "tone_like": "give the running speed (--rotor-speed-hz) if the machine's; look for a line in the spectrum; "
                 "measure longer (a structural mode's amplitude then varies at random, a tone's does not)",
    "non_stationary": "for a hammer test with a force channel use modal fit --impact; otherwise cut the transients "
                      "out of the record or measure while the machine runs steadily",
}

#: Flags of an estimate the line spacing limits: its error includes the grid's quantisation
GRID_FLAGS = frozenset({"resolution_limited", "missing_crossing", "too_few_points"})
#: Flags raised with a :class:`~modal.errors.ResolutionWarning` (any other serious flag: a QualityWarning)
RESOLUTION_FLAGS = GRID_FLAGS | {"outside_band"}
#: Flags :func:`modal.assemble.assemble_modes` raises by its shared rules (a result assembled again, as by
#: mass-change scaling or merging setups, starts from the method's own flags without these).
RULE_FLAGS = frozenset({"high_uncertainty", "close_modes", "driving_point_unknown", "window_damping_dominates",
                        "complex_mode", "non_positive_constant", "not_driving_point", "driving_point_contradicted"})
#: Flags that describe the setting, not a defect (``ModeResult.ok`` ignores them). ``driving_point_assumed``
#: is no longer raised (k, c, m only where the driving point is known or declared) but archives written
#: before still carry it, and read back their modes as they were judged then.
INFORMATIONAL = frozenset({"driving_point_unknown", "not_driving_point", "driving_point_assumed"})


def serious_flags(flags) -> set[str]:
    """The flags that say something is wrong: all but the :data:`INFORMATIONAL` ones (``flags`` an iterable of
    names, or a table cell of names separated by spaces)."""
    return set(flags.split() if isinstance(flags, str) else flags) - INFORMATIONAL


#: Flags about a driving-point channel's constant (never on a transfer channel).
DRIVING_POINT_ONLY = frozenset({"complex_mode", "non_positive_constant", "units_unknown",
                                "driving_point_contradicted"})
#: Flags about a transfer channel (never on a driving-point channel).
TRANSFER_ONLY = frozenset({"not_driving_point"})


#: Flags of a driving-point channel that gives no k, c, m for the mode (its constant has no positive real part, or
#: its constants change sign between modes): on a driving-point channel that gives them they are another channel's.
WITHOUT_KCM = frozenset({"non_positive_constant", "driving_point_contradicted"})


def channel_flags(flags, driving_point: bool, gives_kcm: bool = False) -> list[str]:
    """The mode's flags that apply to one channel.

    A mode's flags are raised over all its channels; the per-channel report keeps those
    about the kind of channel it is (``not_driving_point`` only on transfer channels,
    ``complex_mode`` and the like only on driving points), and on a driving point that gives k, c, m
    (``gives_kcm``) none of :data:`WITHOUT_KCM` (raised by another driving point of the mode).
    """
    drop = TRANSFER_ONLY if driving_point else DRIVING_POINT_ONLY
    if driving_point and gives_kcm:
        drop = drop | WITHOUT_KCM
    return [f for f in flags if f not in drop]


def contradictions(row: dict) -> list[str]:
    """What contradicts itself in one row of :meth:`IdentificationResult.rows` (empty when consistent)."""
    flags = set(row["flags"])
    found = []
    if row["driving_point"]:
        found += [f"driving_point is true with flag {f}" for f in sorted(flags & TRANSFER_ONLY)]
        if np.isfinite(row["stiffness_n_per_m"]):
            found += [f"driving point reports stiffness_n_per_m with flag {f}" for f in sorted(flags & WITHOUT_KCM)]
    else:
        found += [f"driving_point is false with flag {f}" for f in sorted(flags & DRIVING_POINT_ONLY)]
        found += [f"transfer channel reports {name}" for name in ("stiffness_n_per_m", "damping_n_s_per_m", "mass_kg")
                  if np.isfinite(row[name])]
    if {"complex_mode", "non_positive_constant"} <= flags:
        found.append("complex_mode (constant with positive real part) with non_positive_constant")
    unknown = flags - set(FLAG_TEXT)
    found += [f"flag {f} is not defined in FLAG_TEXT" for f in sorted(unknown)]
    return found
