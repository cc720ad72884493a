"""``modal.oma(data, ...)``: operational (output-only) modal analysis, the front door.

1. Check the record and bring it to the band (:mod:`modal.operational.inputs`).
2. Correlations of every channel with the reference channels, per block of the record
   (:mod:`modal.operational.correlations`).
3. The method's poles over a sweep of model orders (SSI-cov, :mod:`modal.operational.ssi`;
   pLSCF on half-spectra, :mod:`modal.operational.plscf`), stabilisation and clustering
   (:mod:`modal.operational.selection`), one estimate per mode with error bars
   (:mod:`modal.operational.modes`); or the FDD/EFDD quick look (:mod:`modal.operational.fdd`).
4. Machine tones told apart (:mod:`modal.operational.tones`), and the result
   (:mod:`modal.operational.result`).
"""
from __future__ import annotations

import numpy as np

from ..blas import one_blas_thread
from ..parallel import map_over_threads, run_beside, thread_count
from ..errors import IdentificationError, ParameterError
from ..results import IdentificationResult
from ..shapes import mpc
from .correlations import choose_references, correlations
from .inputs import MIN_LAGS_IN_RECORD, Prepared, prepare_unscreened
from .methods import OMA_METHODS
from .modes import error_blocks, estimates_from_clusters, resolved
from .tones import flag_mains_hum, nearly_undamped, separate_tones
from .result import oma_result
from .screen import screen_findings, screen_samples, transient_kurtosis, warn_transients, warn_unresponsive
from .selection import OMAStabilisation, stabilise

__all__ = ["oma", "OMA_METHODS"]

#: at most this many reference (projection) channels are chosen automatically
MAX_AUTO_REFERENCES = 8
#: with more outputs than references, the outputs' block rows make the Hankel matrix about this many times as
#: tall as wide. Square (1) was faster, but over 50 records of 32 sensors it left a weakly excited mode's
#: frequency errors 1.5 times too large (z SD 0.67); at 2 every mode's z SD lies in 0.86-1.20, as with 8
#: sensors (``python -m benchmarks.bench_oma --records 0 --calibration 50 --channels 32``)
HANKEL_ASPECT = 2


def _references(prepared: Prepared, reference_channels) -> tuple[int, ...]:
    n = prepared.n_channels
    if reference_channels is None:
        return choose_references(prepared.signals, min(n, MAX_AUTO_REFERENCES), mean=prepared.mean)
    refs = np.atleast_1d(np.asarray(reference_channels))
    if refs.dtype.kind not in "iu" or refs.size == 0 or np.any(refs < 0) or np.any(refs >= n) \
            or np.unique(refs).size != refs.size:
        raise ParameterError(f"{prepared.source}: 'reference_channels' is {reference_channels!r}; expected distinct "
                             f"0-based channel indices in [0, {n})")
    return tuple(int(r) for r in refs)


def _sweep_size(prepared: Prepared, n_refs: int, max_order, block_rows):
    """(max_order, block rows of the outputs, block columns of the references): the correlation lags span a
    period of the lowest frequency of interest (a tenth of the band's top, or its bottom if higher), the
    Hankel matrix has room for every order. With more outputs than references the outputs take fewer block
    rows, as many as make the Hankel matrix about :data:`HANKEL_ASPECT` times as tall as wide (and room for
    every order): its rows then cost the error bars' products little more than its columns, and the lags
    still span the period."""
    fs = prepared.sample_rate_hz
    low, high = prepared.band_hz
    if max_order is None:
        max_order = 80
    if int(max_order) < 2:
        raise ParameterError(f"{prepared.source}: 'max_order' is {max_order!r}; expected an even order >= 2")
    span = int(np.ceil(fs / max(low, high / 10)))
    rows = int(block_rows) if block_rows is not None else max(span, int(np.ceil(max_order / n_refs)) + 1)
    if rows < 2:
        raise ParameterError(f"{prepared.source}: 'block_rows' is {block_rows!r}; expected at least 2")
    cols = rows
    n_out = prepared.n_channels
    if block_rows is None and n_out > n_refs:
        rows = min(cols, max(int(np.ceil(max_order / n_out)) + 1, int(np.ceil(HANKEL_ASPECT * n_refs * cols / n_out)),
                             2))
    n_samples = prepared.n_samples
    if n_samples < MIN_LAGS_IN_RECORD * 2 * cols:
        need = MIN_LAGS_IN_RECORD * 2 * cols / fs
        raise ParameterError(f"{prepared.source}: the record lasts {n_samples / fs:.4g} s; the band from "
                             f"{max(low, high / 10):.4g} Hz and model order {max_order} need correlations over "
                             f"{2 * cols} lags and at least {need:.4g} s of record (raise the band's lower edge, "
                             "lower max_order or measure longer)")
    return int(max_order), rows, cols


def _ssi(prepared: Prepared, refs, max_order, block_rows, workers: int = 1):
    from .ssi import Perturbation, poles_at, subspace_model

    max_order, rows, cols = _sweep_size(prepared, len(refs), max_order, block_rows)
    corr = correlations(prepared.signals, prepared.sample_rate_hz, refs, rows + cols, mean=prepared.mean,
                        scale=prepared.scale, workers=workers)
    model = subspace_model(corr.mean, rows, max_order, prepared.sample_rate_hz, cols)
    orders = list(range(2, model.max_order + 1, 2))
    sets = map_over_threads(lambda n: poles_at(model, n), orders, workers)  # an eigenproblem per order
    flat, stable, clusters = stabilise(sets, *prepared.band_hz)
    perturb = None
    if clusters:
        medians = np.array([np.median(flat.pole[c.members]) for c in clusters])
        n_blocks = error_blocks(prepared.duration_s, medians, corr.blocks.shape[0])
        if n_blocks >= 2:
            perturb = Perturbation(model, *corr.grouped(n_blocks), workers=workers).at
    estimates, chosen, kept = estimates_from_clusters(flat, clusters, perturb, len(orders), prepared.scale,
                                                      workers=workers)
    settings = {"orders": [orders[0], orders[-1]], "block_rows": rows, "block_cols": cols}
    return estimates, chosen, kept, flat, stable, corr, settings


@one_blas_thread()
def oma(data, sample_rate_hz: float | None = None, *, band_hz=None, method: str = "ssi", reference_channels=None,
        rotor_speed_hz: float | None = None, max_order: int | None = None, block_rows: int | None = None,
        quantity: str | None = None, workers: int | None = None) -> IdentificationResult:
    """Identify the modes of a structure from its responses alone (operational modal analysis).

    Parameters
    ----------
    data : ndarray, shape (n_channels, n_samples), TimeRecord or path
        Response records (at least 2 channels), e.g. accelerations; or a time record read by
        :func:`modal.io.timedata.read_time` (or its path), whose sample rate and quantity are used.
    sample_rate_hz : float, optional
        Sampling rate, Hz (required for an array).
    band_hz : (float, float), optional
        Band of interest, Hz: modes outside it are not reported; the record is decimated to it.
        Default: 0 Hz to 80 % of the Nyquist frequency.
    method : {"ssi", "plscf", "fdd", "efdd"}
        ``"ssi"``: covariance-driven stochastic subspace identification (default); ``"plscf"``:
        poly-reference least-squares complex frequency-domain estimation on the output half-spectra
        (an independent estimator for cross-checks); ``"fdd"``, ``"efdd"``: the frequency-domain
        decomposition quick looks (peaks of the first singular value; enhanced: damping from the
        decay of each peak's correlation function), without error bars.
    reference_channels : sequence of int, optional
        0-based indices of the reference (projection) channels. Default: all channels up to 8, else
        the 8 that best span the correlations (column-pivoted QR).
    rotor_speed_hz : float, optional
        The machine's running speed: poles on its harmonics are machine tones (listed in
        ``harmonics_hz``) or flagged ``harmonic``. Without it, tones are recognised from the data.
    max_order : int, optional
        Highest model order (states) of the sweep (default 80).
    block_rows : int, optional
        Block rows of the Hankel matrix (default: lags over a period of the lowest frequency of interest).
    quantity : str, optional
        What an array's channels measured (``"acceleration"``, ``"velocity"``, ``"displacement"``);
        names the result's ``kind``. Default: acceleration.
    workers : int, optional
        Threads among which a long record's blocks and channels are shared (default: every core the process
        may use; 1 where the caller parallelises already, as ``modal batch`` does). The result does not
        depend on it.

    Returns
    -------
    IdentificationResult
        One :class:`~modal.results.ModeResult` per structural mode, in order of frequency:
        ``natural_frequency_hz``, ``damping_ratio``, ``mode_shape`` (complex, one entry per channel,
        the largest entry the record determines 1), ``mpc``, ``std`` (frequency, damping and shape), ``flags``; k, c, m and the
        modal constant are NaN until the modes are scaled (:func:`modal.scale_by_mass_change`).
        ``stabilisation`` holds the diagram (:class:`~modal.operational.selection.OMAStabilisation`),
        ``harmonics_hz`` the machine tones found.

    Raises
    ------
    ParameterError
        Bad input: fewer than 2 channels, a constant channel, non-finite samples, a band outside
        (0, Nyquist), a record too short for the band or order; a record (file) with a force channel or
        with channels of different quantities or units.
    IdentificationError
        No stable pole in the band.

    Warns
    -----
    QualityWarning
        A flagged mode; a dropout (a run of identical samples) or a clipped channel; a channel that
        moves in none of the modes found; a record of transients (hammer hits, shocks), its modes flagged
        ``non_stationary`` (:mod:`modal.operational.screen`).

    Notes
    -----
    Runs with one BLAS thread (:func:`modal.blas.one_blas_thread`): its many small products are faster so.
The long loops over the record's blocks (correlations, the error bars' deviations) and channels (the input
check) are shared among ``workers`` threads instead, one contiguous share each (:mod:`modal.parallel`).
    """
    if method not in OMA_METHODS:
        raise ParameterError(f"'method' is {method!r}; expected one of {', '.join(OMA_METHODS)}")
    if rotor_speed_hz is not None and not (np.isfinite(rotor_speed_hz) and rotor_speed_hz > 0):
        raise ParameterError(f"'rotor_speed_hz' is {rotor_speed_hz!r}; expected a positive frequency in Hz")
    workers = thread_count(workers)
    prepared, recorded = prepare_unscreened(data, sample_rate_hz, band_hz, quantity, workers=workers)
    # the screens for dropouts, clipping and transients (each a strided read of the record, one thread) beside the
    # choice of references (one thread's products); their warnings given here, in the order prepare gives them
    rate, names, src = prepared.original_rate_hz, prepared.names, prepared.source
    refs, (findings, transients) = run_beside(
        lambda: _references(prepared, reference_channels),
        lambda: (screen_findings(recorded, rate, names, src), transient_kurtosis(prepared)), workers)
    screen_samples(recorded, rate, names, src, findings=findings)
    record_flags = frozenset({"non_stationary"}) if warn_transients(prepared, transients) else frozenset()
    if method in ("fdd", "efdd"):
        from .fdd import fdd

        result = fdd(prepared, refs, enhanced=method == "efdd", rotor_speed_hz=rotor_speed_hz,
                     record_flags=record_flags)
        warn_unresponsive(result, prepared.source)
        return result
    if method == "ssi":
        estimates, chosen, clusters, flat, stable, corr, settings = _ssi(prepared, refs, max_order, block_rows,
                                                                         workers)
    else:
        from .plscf import plscf

        estimates, chosen, clusters, flat, stable, corr, settings = plscf(prepared, refs, max_order, workers)
    resolution_hz = corr.sample_rate_hz / corr.max_lag  # what the correlation lags tell apart
    estimates, tones, dropped, diagram = _sort_out(estimates, chosen, clusters, flat, stable, prepared,
                                                   rotor_speed_hz, method, resolution_hz, workers)
    estimates = flag_mains_hum(estimates, prepared)
    if not estimates and not tones:
        raise IdentificationError(f"{prepared.source}: no stable pole in the band {prepared.band_hz[0]:g}-"
                                  f"{prepared.band_hz[1]:g} Hz (orders {settings['orders'][0]}-"
                                  f"{settings['orders'][1]}); widen the band or raise max_order")
    settings = {**settings, "band_hz": list(prepared.band_hz), "reference_channels": list(refs),
                "sample_rate_hz": prepared.original_rate_hz, "decimation": prepared.decimation,
                "duration_s": prepared.duration_s, "rotor_speed_hz": rotor_speed_hz,
                "channel_names": list(prepared.names), "n_channels": prepared.n_channels, "source": prepared.source,
                "dropped_unresolved_hz": dropped}
    result = oma_result(estimates, method=method, quantity=prepared.quantity, band_hz=prepared.band_hz,
                        stabilisation=diagram, settings=settings, harmonics_hz=tones, source=prepared.source,
                        record_flags=record_flags)
    warn_unresponsive(result, prepared.source)
    return result


def _sort_out(estimates, chosen, clusters, flat, stable, prepared: Prepared, rotor_speed_hz, method: str,
              resolution_hz: float, workers: int = 1):
    """Modes, tones (Hz), dropped noise poles (Hz) and the stabilisation diagram from the method's estimates.

    Noise poles (frequency not determined within their bandwidth) are dropped, except poles of nearly zero
    damping, which go to the tone test first (a tone's first-order frequency error is erratic); then the
    tones are told apart, and the noise poles among what is left dropped.
    """
    keep = [resolved(e, prepared.duration_s) or nearly_undamped(e) for e in estimates]
    dropped = [e.natural_frequency_hz for e, k in zip(estimates, keep) if not k]
    estimates, clusters = ([x for x, k in zip(seq, keep) if k] for seq in (estimates, clusters))
    is_tone, estimates = separate_tones(estimates, prepared, rotor_speed_hz, resolution_hz, workers)
    keep = [t or resolved(e, prepared.duration_s) for e, t in zip(estimates, is_tone)]
    dropped = sorted(dropped + [e.natural_frequency_hz for e, k in zip(estimates, keep) if not k])
    estimates, clusters, is_tone = ([x for x, k in zip(seq, keep) if k] for seq in (estimates, clusters, is_tone))
    chosen = [m for m in chosen if any(m in c.members for c in clusters)]
    n_poles = flat.pole.size
    cluster = np.full(n_poles, -1)
    tone = np.zeros(n_poles, bool)
    modes, tones = [], []
    for estimate, members, t in zip(estimates, clusters, is_tone):
        if t:
            tone[members.members] = True
            tones.append(estimate.natural_frequency_hz)
        else:
            cluster[members.members] = len(modes)
            modes.append(estimate)
    diagram = OMAStabilisation(flat.order, flat.frequency_hz, flat.damping_ratio,
                               _pole_mpc(flat.shape), stable, cluster,
                               np.isin(np.arange(n_poles), chosen), tone, method)
    return modes, tones, dropped, diagram


def _pole_mpc(shapes: np.ndarray) -> np.ndarray:
    """The MPC of every pole's shape (columns of ``shapes``) in one pass, a non-finite entry (a channel of a setup
    that misses the pole) counting as none, as :func:`modal.operational.selection.mpc` leaves it out."""
    return mpc(np.where(np.isfinite(shapes), shapes, 0).T)
