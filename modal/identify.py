"""``identify``: from an FRF to every mode's ωn, ζ, modal constant and k, c, m.

The front door: it checks the arguments, fits FRFs near over- or underflow at unit
scale (:mod:`modal.scaling`), chooses the method (:func:`choose_method`) and hands
the FRF to the band-wise methods (:func:`modal.sdof.identify_bands`, on the bands of
the peaks or the caller's) or to the global one (:func:`modal.global_.identify_global`).
"""
from __future__ import annotations

import numpy as np

from .blas import one_blas_thread
from .errors import IdentificationError
from .frf import FRF
from .frf_units import withhold_physical
from .peaks import _indicator_and_peak, bands_from_hz, estimate_noise_std, find_modes
from .results import IdentificationResult
from .sdof import BANDWISE_METHODS, identify_bands
from .validate import channel_mask, one_of, per_channel
from .work_budget import checked_max_evaluations

__all__ = ["identify", "choose_method", "METHODS", "BANDWISE_METHODS"]

#: all methods: the band-wise ones (one band per mode) and the global one
METHODS = BANDWISE_METHODS + ("global",)


#: automatic choice: the global method for a poly-reference grid or at least this many peaks
AUTO_GLOBAL_PEAKS = 5


#: ... unless the peaks are more than this many per reference: the global method's default sweep (orders up to
#: :data:`modal.global_.identify.MAX_DEFAULT_ORDER` = 120, m·p poles at order p with m references; a third of it
#: here, not imported, so that ``import modal`` does not load the global method) cannot hold them.
#: A peak takes a pair of poles and the sweep needs about one pole more per peak (noise, modes outside the band):
#: a third of the ceiling's poles. Measured on the single-reference files of tests/support/manymodes.py
#: (modes evenly spread, ζ 0.005, 0.1 % noise): 37-39 peaks on 8 000-12 000 lines, every mode found by the
#: global method; 41-52 peaks on 10 000-20 000 lines, 1-7 modes found where band-wise nls finds all but one
#: (benchmarks/REPORT.md, "auto's choice on many-mode files")
AUTO_PEAKS_PER_REFERENCE = 40


def choose_method(frf: FRF, bands_hz=None, min_prominence_db: float = 6.0) -> str:
    """The method ``identify(frf, "auto")`` runs: ``"global"`` for a poly-reference test (an outputs ×
    references grid with several references) or at least :data:`AUTO_GLOBAL_PEAKS` peaks (a many-mode
    measurement, where band-wise fits each see their neighbours only as an offset), else ``"nls"``
    (one to a few well-separated modes, where it is the Cramér–Rao-efficient choice). More peaks than
    the global method's default sweep holds (:data:`AUTO_PEAKS_PER_REFERENCE` per reference) are fitted
    band-wise (``"nls"``) as well. Bands given explicitly keep the band-wise method.
    """
    return _auto_choice(frf, bands_hz, min_prominence_db)[0]


def _too_many_peaks(n_peaks: int, n_references: int) -> str | None:
    """Why the global method's default sweep cannot hold ``n_peaks`` peaks (None when it can)."""
    if n_peaks <= AUTO_PEAKS_PER_REFERENCE * n_references:
        return None
    return (f"nls: {n_peaks} peaks, more than the global method's default sweep holds ({AUTO_PEAKS_PER_REFERENCE} "
            f"per reference, {n_references} reference{'s' if n_references > 1 else ''}: orders up to "
            f"{3 * AUTO_PEAKS_PER_REFERENCE})")


def _auto_choice(frf: FRF, bands_hz, min_prominence_db: float,
                 indicator=None, noise=None) -> tuple[str, list | None]:
    """:func:`choose_method`'s choice and the peaks' bands it found (None when it did not search), so that
    identify does not search twice (``indicator``: :func:`modal.peaks._indicator_and_peak`, and ``noise``,
    the raw noise per channel, when the caller has them)."""
    if bands_hz is not None:
        return "nls", None
    from .global_ import channel_grid

    index, _, transposed = channel_grid(frf)
    references = index.shape[1]
    noise = estimate_noise_std(frf) if noise is None else noise
    try:  # the peaks identify itself would fit: the same noise-aware test (an estimate's noise per line)
        bands = find_modes(frf, min_prominence_db=min_prominence_db, noise_std=noise,
                           line_noise_std=frf.noise_std, indicator=indicator)
    except IdentificationError:
        return ("global" if references > 1 else "nls"), None
    if _too_many_peaks(len(bands), references):
        return "nls", bands
    return ("global" if references > 1 or len(bands) >= AUTO_GLOBAL_PEAKS else "nls"), bands


#: the options ``identify`` passes to the global method (:func:`modal.global_.identify_global`)
GLOBAL_OPTIONS = ("modes_hz", "order", "max_order", "band_hz", "max_evaluations")


@one_blas_thread()
def identify(frf: FRF, method: str = "auto", bands_hz=None, *, noise_std=None, driving_point=None,
             min_prominence_db: float = 6.0, max_modes: int | None = None, max_evaluations: int | None = None,
             **global_options) -> IdentificationResult:
    """Identify every mode of an FRF.

    Parameters
    ----------
    frf : FRF
        One or many channels (poles are shared by all channels).
    method : {"auto", "nls", "circle", "halfpower", "global"}
        ``"auto"`` (default): ``"global"`` for poly-reference or many-mode
        data, else ``"nls"`` (:func:`choose_method`); ``result.method`` says
        which ran.
        ``"nls"``: complex nonlinear least squares of all modes
        together, each band started from its one-mode rational fit
        (:func:`modal.sdof.rational.rational_pole`; from the better of half-power and
        circle fit where that gives no pole or a doubtful fit).
        ``"global"``: poly-reference LSCF (PolyMAX) poles with a stabilisation
        diagram, then a joint refinement of all poles, modal constants and
        residual terms over the whole band (:func:`modal.global_.identify_global`;
        its options ``modes_hz``, ``order``, ``max_order`` and ``band_hz`` pass through
        ``**global_options``; ``bands_hz`` gives the band by its extremes instead).
        ``"circle"``: Kennedy–Pancu circle fit on the mobility.
        ``"halfpower"``: half-power bandwidth with exact inversion.
    bands_hz : list of (f_low, f_high), optional
        One band per mode, Hz. Default: found from the peaks, each ±3
        half-power widths, clipped halfway to its neighbours.
    noise_std : float or array_like over channels, optional
        Known noise σ (E|n|² = σ²) in the FRF's unit; default estimated from
        each line's misfit to its neighbours (:func:`modal.peaks.neighbour_noise_std`).
    driving_point : bool, array_like of bool, int or sequence of int, optional
        Declares which channels were measured at the excitation point: ``True`` (every channel; the
        usual single-channel case), one bool per channel, or 0-based channel indices. Default: the
        point ids say (response point = reference point). k, c, m are given for driving points only;
        where neither says, for no channel (flag ``driving_point_unknown``).
    min_prominence_db : float
        Peak detection threshold when ``bands_hz`` is not given.
    max_modes : int, optional
        Keep at most this many (strongest) peaks.
    max_evaluations : int, optional
        Model evaluations the least-squares refinement may take, all its fits together (for ``"circle"`` and
        ``"halfpower"``, the refinement that checks their estimates); default scaled to the size of one
        (:func:`modal.work_budget.default_max_evaluations`), never reached by ordinary files. Where they run
        out it stops, its modes flagged ``work_capped`` with a warning. ``result.settings`` gives the budget
        and the evaluations used.

    Runs with one BLAS thread (:func:`modal.blas.one_blas_thread`): its fits are many small products, which a
    BLAS thread per core makes slower (3-6 times the CPU on a 2-core machine, benchmarks/REPORT.md).

    Returns
    -------
    IdentificationResult
        ``result.modes[i]`` has ``natural_frequency_hz``, ``damping_ratio``,
        ``modal_constant``, ``stiffness_n_per_m``, ``damping_n_s_per_m``,
        ``mass_kg``, ``std`` (standard errors under the same names) and
        ``flags``; arrays over channels for multi-channel FRFs.

    Warns
    -----
    ResolutionWarning
        An estimate is resolution-limited (fewer than 3 lines above −3 dB, a
        missing crossing); it is returned flagged.
    QualityWarning
        Any other flag (band-edge peak, poor model fit, large uncertainty).
    """
    if not isinstance(frf, FRF):
        raise TypeError(f"identify() expects a modal.FRF, got {type(frf).__name__}")
    if global_options and method not in ("global", "auto"):
        raise TypeError(f"identify() got options {', '.join(sorted(global_options))} that only method='global' takes")
    unknown = sorted(set(global_options) - set(GLOBAL_OPTIONS))
    if unknown:
        raise TypeError(f"identify() got unexpected option(s) {', '.join(unknown)}; method='global' takes "
                        f"{', '.join(GLOBAL_OPTIONS)}")
    if global_options.get("band_hz") is not None and bands_hz is not None:
        raise IdentificationError("give the global method's band once: band_hz=(f_low, f_high) or bands_hz "
                                  "(whose extremes make the band), not both")
    one_of("method", method, METHODS + ("auto",), IdentificationError)
    if max_evaluations is not None:
        max_evaluations = checked_max_evaluations(max_evaluations, IdentificationError)
    if noise_std is not None:
        noise_std = per_channel("noise_std", noise_std, frf.n_channels, IdentificationError)
    if driving_point is not None:
        driving_point = channel_mask("driving_point", driving_point, frf.n_channels, IdentificationError)
    if max_evaluations is not None:
        global_options = {**global_options, "max_evaluations": max_evaluations}
    result = _identify(frf, method, bands_hz, noise_std, driving_point, min_prominence_db, max_modes, global_options)
    _check_kind(frf, result, driving_point)
    return withhold_physical(result, frf)  # no k, c, m in SI from an FRF in a unit that is not


def _check_kind(frf: FRF, result: IdentificationResult, driving_point) -> None:
    """Warn when the data contradict the declared kind (:func:`modal.kind_check.kind_contradiction`)."""
    from .errors import QualityWarning, warn_caller
    from .kind_check import kind_contradiction

    driving = driving_point if driving_point is not None else (frf.is_driving_point() if frf.driving_point_known
                                                               else None)
    message = kind_contradiction(frf, result.modes, driving)
    if message is not None:
        warn_caller(f"{frf.source}: {message}", QualityWarning)


def _identify(frf: FRF, method: str, bands_hz, noise_std, driving_point, min_prominence_db: float,
              max_modes: int | None, global_options: dict) -> IdentificationResult:
    """:func:`identify` after its arguments are checked."""
    from .scaling import scale_exponent, scaled_frf, unscale_result

    # |H| once: the mode indicator and each channel's max |H|, and (but for the global method, which measures
    # its own) the raw noise per channel from the same read of the data
    if method == "global":
        indicator, raw = _indicator_and_peak(frf), None
    else:
        mode_indicator, channel_peak, raw = _indicator_and_peak(frf, noise=True)
        indicator = (mode_indicator, channel_peak)
    exponent = scale_exponent(frf, peak=indicator[1])
    if exponent:  # values near over- or underflow: fit 2**e H (exact) and scale the results back
        gain = 2.0**exponent
        result = _identify(scaled_frf(frf, exponent), method, bands_hz,
                           None if noise_std is None else noise_std * gain, driving_point, min_prominence_db,
                           max_modes, global_options)
        return unscale_result(result, gain)
    found = None  # peak bands the automatic choice already searched
    if method == "auto":  # chosen on the (possibly rescaled) data, so the choice never overflows
        method, found = (("global", None) if set(global_options) - {"max_evaluations"}
                         else _auto_choice(frf, bands_hz, min_prominence_db, indicator, raw))
    if method == "global":
        from .global_ import identify_global

        options = dict(global_options)
        band = options.pop("band_hz", None)
        if bands_hz is not None:
            band = (min(b[0] for b in bands_hz), max(b[1] for b in bands_hz))
        return identify_global(frf, band_hz=band, noise_std=noise_std, driving_point=driving_point, **options)
    if bands_hz is not None:
        bands = bands_from_hz(frf, bands_hz, indicator=indicator[0])
    elif found is not None and max_modes is None:  # the automatic choice's search, with the same arguments
        bands = found
    else:
        bands = find_modes(frf, min_prominence_db=min_prominence_db, max_modes=max_modes, noise_std=raw,
                           line_noise_std=frf.noise_std, indicator=indicator)
    result = identify_bands(frf, method, bands, raw_noise=raw, noise_std=noise_std, driving_point=driving_point,
                            max_evaluations=global_options.get("max_evaluations"))
    if found is not None:  # the automatic choice: where many peaks chose nls, the result says why
        from .global_ import channel_grid

        why = _too_many_peaks(len(found), channel_grid(frf)[0].shape[1])
        if why is not None:
            result.settings["method_choice"] = why
    return result

