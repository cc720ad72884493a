"""Time records → FRF with coherence and a calibrated noise level per line.

:func:`estimate_frf` is the one entry point; it returns an
:class:`EstimatedFRF`, an :class:`~modal.frf.FRF` that also carries the
coherence, the number of averages, what was rejected, and ``noise_std``: the
standard deviation of the complex random error of each line, so that
:func:`modal.identify` can weight by it.

Noise model (Bendat & Piersol, *Random Data*, ch. 9): with n records and
q inputs, the least-squares FRF's error is complex Gaussian with
E|Ĥ − H|² = σ²_N [S_xx⁻¹]_ii, σ²_N estimated from the residual
Σ|Y − ĤX|² / (n − q); for one input this is |H|²(1 − γ²)/(γ²(n − 1)).
Overlapping records share noise; :func:`~modal.estimate.spectra.overlap_variance_factor`
inflates the variance by Welch's 1 + 2Σρ².
"""
from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from ..blas import one_blas_thread
from ..errors import FRFValidationError, ParameterError, QualityWarning, warn
from ..frf import FRF, FRF_KINDS, KIND_POWER
from ..noise_model import (INPUT_NOISE_LIMIT, NoiseModel, input_noise_split, lag_window, lags_carried,
                           window_line_correlation)
from ..validate import finite_samples, one_of, per_line, positive_number
from . import spectra
from .excitation_noise import EXCITATION_NOISE_LIMIT, excitation_noise_share
from .common_error import common_error_factor
from .error_correlation import LEAKAGE_LAGS, MIN_RECORDS, measured_line_correlation
from .record_influence import MAX_INFLUENCE_VALUES, channel_influence, overlapping_records, record_influence
from .hits import find_hits, pulse_train, reject_pulses_the_window_cuts
from .roles import refuse_swapped_channels, warn_impulsive_responses
from .levels import MIN_HITS, hit_spectra
from .level_warnings import (warn_change_dependence, warn_changes_within_takes, warn_level_dependence,
                             warn_take_dependence)
from .overload import find_overloads
from .periodic import repeats_every, shortest_period
from .quiet import quiet_noise
from .takes import find_hits_in_takes, hit_labels, segment_starts, take_bounds
from .takes import take_names as _take_names
from .rise import rise_tests
from .unrelated import chance_tests, warn_unrelated
from .windows import WINDOWS, exponential_window, force_window, segment_window

__all__ = ["EstimatedFRF", "estimate_frf", "RESPONSE_QUANTITIES"]

#: a continuous record averaged over fewer records is warned: with 2 records (1 degree of freedom per line) the
#: errors of fits over 15 synthetic records were 1.5–2.7 times too small (z SD of fn and ζ, bench_chain's
#: random cell on 4096-sample segments); with 3 records (bench_chain random-hann-3avg) 0.6–1.2
FEW_RECORDS = 3
#: two excitation channels more coherent than this on their median line are warned: two synthetic shakers
#: (3 records per case) gave fits whose mass and damping errors were 1.7–2.8 times their error bars (RMS z)
#: at input coherence 0–0.9, as with independent inputs, and 95 times at 0.98
INPUT_COHERENCE_LIMIT = 0.95
#: what a response channel measured, and its power of iω relative to displacement
RESPONSE_QUANTITIES = {"displacement": 0, "velocity": 1, "acceleration": 2}


@dataclass(frozen=True, eq=False)
class EstimatedFRF(FRF):
    """An FRF estimated from time records, with its coherence and noise.

    Channels are ordered output by output and, within one output, input by
    input (channel ``o * n_inputs + i``).

    Attributes
    ----------
    coherence : ndarray, shape like ``response``
        Ordinary coherence of each input–output pair (0–1).
    multiple_coherence : ndarray, shape (n_outputs, n_freq)
        Multiple coherence of each output on all inputs (equal to the ordinary
        coherence for one input).
    noise_std : ndarray, shape like ``response``, or None
        (:class:`~modal.frf.FRF`'s field) Standard deviation of the complex random error of
        each line, E|Ĥ − H|² = noise_std², in the FRF's unit. One hit (an impact estimate from one record):
        the noise its channels hold before the trigger and after the pulse gives it
        (:mod:`modal.estimate.quiet`); None with one average otherwise (undefined).
    averages : int
        Records (segments or accepted hits) averaged.
    rejected : list of dict
        Rejected hits: ``hit`` (from 1), ``time_s``, ``reason``.
    estimator : {"H1", "H2", "Hv"}
    window : str
    exponential_decay_s : float or None
        (:class:`~modal.frf.FRF`'s field) τ of the exponential window, s: every pole's real
        part is more negative by 1/τ; :func:`modal.identify` takes it back out.
    sample_rate_hz : float
    segment_length : int
        Samples per record.
    overlap : float
        Fraction of a segment shared with the next (continuous records).
    n_inputs : int
        Excitation channels.
    hit_times_s : tuple of float
        Trigger time of each accepted hit, s (impact records; empty otherwise).
    overloads : list of dict
        Channels clipped (flat tops at the recorder's extreme) or overloaded (at a declared
        full scale) anywhere in the record: ``channel``, ``how`` (``"flat tops"`` or
        ``"full scale"``), ``level`` (in the channel's unit), ``samples``, ``longest_run``.
        Impact records reject the hits they touch; continuous records warn.
    unrelated : list of dict
        Response channels unrelated to the force (a dead or unplugged sensor: their coherence no higher
        than chance, :mod:`modal.estimate.unrelated`, and for hits no rise of their power at the triggers,
        :mod:`modal.estimate.rise`), warned: ``channel``, ``mean_coherence`` (over the ``lines`` driven
        lines), ``chance`` and ``chance_se`` (its mean and standard error under no relation), ``records``
        (None where too few records or lines), ``rise`` and ``rise_log_se`` (hits: the power ratio and the
        standard error of its log under no relation; None otherwise).
    """

    coherence: np.ndarray | None = None
    multiple_coherence: np.ndarray | None = None
    averages: int = 1
    rejected: list = field(default_factory=list)
    estimator: str = "H1"
    window: str = "rect"
    sample_rate_hz: float | None = None
    segment_length: int | None = None
    overlap: float = 0.0
    n_inputs: int = 1
    hit_times_s: tuple = ()
    overloads: list = field(default_factory=list)
    unrelated: list = field(default_factory=list)

    def __post_init__(self) -> None:
        super().__post_init__()
        if self.coherence is not None:
            arr = per_line("coherence", self.coherence, np.shape(self.response), FRFValidationError, self.source)
            arr.setflags(write=False)
            object.__setattr__(self, "coherence", arr)
        if self.multiple_coherence is not None:
            arr = np.atleast_2d(np.array(self.multiple_coherence, dtype=float))
            arr.setflags(write=False)
            object.__setattr__(self, "multiple_coherence", arr)

    def _per_line(self, keep) -> dict:
        out = {}
        for name in ("coherence", "noise_std", "multiple_coherence"):
            value = getattr(self, name)
            out[name] = None if value is None else value[..., keep]
        return out

    def cropped(self, f_low_hz: float, f_high_hz: float) -> "EstimatedFRF":
        """The lines with ``f_low_hz <= f <= f_high_hz`` (coherence and noise with them)."""
        keep = (self.frequency_hz >= f_low_hz) & (self.frequency_hz <= f_high_hz)
        if keep.sum() < 2:
            raise FRFValidationError(
                f"{self.source}: band {f_low_hz}–{f_high_hz} Hz holds {int(keep.sum())} lines, expected at least 2"
            )
        return replace(self, frequency_hz=self.frequency_hz[keep], response=self.response[..., keep],
                       noise_model=None if self.noise_model is None else self.noise_model.cropped(keep),
                       **self._per_line(keep))

    def channel(self, index: int) -> "EstimatedFRF":
        """A single-channel estimate of channel ``index``."""
        pts = lambda ids: None if ids is None else (ids[index],)  # noqa: E731
        pick = lambda a: None if a is None else np.atleast_2d(a)[index]  # noqa: E731
        output = index // self.n_inputs
        model = self.noise_model
        if model is not None and model.record_influence is not None and model.record_influence.ndim == 3:
            model = replace(model, record_influence=model.record_influence[index])  # that channel's records' shares
        return replace(self, response=self.channels[index], response_points=pts(self.response_points),
                       noise_model=model, reference_points=pts(self.reference_points), coherence=pick(self.coherence),
                       noise_std=pick(self.noise_std), multiple_coherence=np.atleast_2d(
                           self.multiple_coherence)[output] if self.multiple_coherence is not None else None,
                       n_inputs=1)


def _as_signals(value, name: str, source: str):
    """(channels, samples) view of an array-like; ndarray/memmap/h5py slices stream."""
    if not hasattr(value, "shape") or not hasattr(value, "__getitem__"):
        try:
            value = np.asarray(value, dtype=float)
        except (TypeError, ValueError) as exc:
            raise ParameterError(f"{source}: field {name!r} is not numeric ({exc})") from None
    if len(value.shape) == 1:
        value = np.asarray(value, dtype=float)[np.newaxis, :]
    if len(value.shape) != 2:
        raise ParameterError(
            f"{source}: field {name!r} has shape {tuple(value.shape)}; expected (samples,) or (channels, samples)"
        )
    return value


def _noise_model(sums, output_correlation, input_window, output_window, sample_rate_hz, overlap_factor,
                 decay_s=None, frf=None, quiet=None, overlapping=0, withheld=False, excitation=None) -> NoiseModel:
    """The estimate's :class:`~modal.noise_model.NoiseModel` from its sums and windows.

    One input: the errors of lines k and k + m correlate by c_out(m) Σ conj(X_k) X_{k+m} / √(S_xx,k S_xx,k+m)
    (the response noise's window correlation times the excitation's own, over the records), and the lag window
    follows from the excitation's mean square per sample; an exponential window's decay is divided out of it
    (identification removes that damping exactly). Several inputs: the averages, the lag window and the records'
    influences.

    One input and one output with ``frf`` (H1, shape (1, 1, n_lines)) and more than one record: the
    excitation's own noise enters the estimate as −H N_x X*/S_xx, an error in proportion to H that correlates
    through the input window (c_in) and turns with H's phase. Its share of each line's error follows from the
    residual (:func:`~modal.noise_model.input_noise_split`: power a + b|H|² per record), the correlation is the
    two parts' sum, (a c_out(m) + b c_in(m) H_k H*_{k+m}) g_km / √((a + b|H_k|²)(a + b|H_{k+m}|²)), g_km the
    excitation's term above, and the model's variance per line, (a + b|H_k|²)/S_xx,k, is the noise level's
    shape (``variance_model``). A hammer test's force noise, over the force window's few dozen samples, is
    nearly the same on every line of a band: at the peaks it is most of the error. Several outputs of one input,
    more than one record: the variance model is the shape the outputs share (:func:`_shared_variance`). With
    ``excitation`` (its samples, the records' starts and length; a hammer's) the excitation noise's error H_o η
    (one η for every output) is carried as a factor of η's covariance
    (:func:`~modal.estimate.common_error.common_error_factor`): nls takes it into several channels' errors, and
    a roving join of one-output estimates keeps each point's apart from its response noise.

    Continuous records (``sums.error_products`` summed): the correlation measured over the records
    (:func:`~modal.estimate.error_correlation.measured_line_correlation`) replaces the window's model.

    Records kept one by one (``sums.record_cross``; several channels, ``sums.record_input`` and
    ``sums.record_output``): each record's share of the error
    (:func:`~modal.estimate.record_influence.record_influence`,
    :func:`~modal.estimate.record_influence.channel_influence`), ``overlapping`` the records each overlaps;
    ``withheld``: they were not kept, over the memory budget.

    One record (a single hit) has no residual over records: ``quiet`` (:func:`~modal.estimate.quiet.quiet_noise`,
    the noise read from the samples where the channels hold noise alone) gives a and b instead.
    """
    n_in = sums.sxx.shape[0]
    dof = max(sums.n_records - n_in, 0) / overlap_factor
    interval = 1.0 / sample_rate_hz
    if sums.sxx_lag is None:
        # several inputs: no line correlation; the lag window from the inputs' summed mean square per sample (each
        # input's estimate is the transform of its impulse response times its own lag window, one for all where the
        # inputs share one profile: stationary random, bursts in step)
        lags = lag_window(input_window, output_window, sums.excitation_square / sums.n_records)
        if decay_s is not None:
            lags = lags * np.exp(np.arange(lags.size) * interval / decay_s)
        influence = _channel_influence(sums, frf)
        return NoiseModel(sums.n_records, dof, None, lags, interval, record_influence=influence,
                          overlapping_records=overlapping if influence is not None else 0, influence_withheld=withheld)
    power = sums.sxx[0, 0].real
    n_lags, n_lines = sums.sxx_lag.shape
    correlation = np.zeros((n_lags, n_lines), complex)
    response_part, input_part, variance, common = np.ones(n_lines), np.zeros(n_lines, complex), None, None
    one_record = quiet is not None and sums.n_records == 1
    if frf is not None and frf.shape[:2] == (1, 1) and (sums.n_records > 1 or one_record):
        h = frf[0, 0]
        if one_record:
            a, b = float(quiet.response_power[0]), quiet.force_power
        else:
            with np.errstate(divide="ignore", invalid="ignore"):
                residual = (sums.syy[0] - np.abs(sums.syx[0, 0]) ** 2 / power) / (sums.n_records - 1)
            a, b = input_noise_split(residual, np.abs(h) ** 2)
            # where the excitation's noise is not small against the excitation (above a hammer's band, at the
            # zeros of its spectrum) H1 is biased towards zero and the model does not hold: fitted without them
            holds = b * sums.n_records < INPUT_NOISE_LIMIT * power
            a, b = input_noise_split(residual, np.abs(h) ** 2, holds)
        holds = b * sums.n_records < INPUT_NOISE_LIMIT * power
        total = a + b * np.abs(h) ** 2
        if b > 0 and np.any(holds) and np.all(total[holds] > 0):
            response_part = np.where(holds, np.sqrt(a / np.where(holds, total, 1.0)), 1.0)
            input_part = np.where(holds, np.sqrt(b / np.where(holds, total, 1.0)) * h, 0.0)
            variance = np.where(holds, total / power * overlap_factor, np.nan)
            if excitation is not None:
                common = common_error_factor(*excitation, input_window, b)
    elif frf is not None and frf.shape[1] == 1 and frf.shape[0] > 1 and sums.n_records > 1:
        variance, excitation_noise = _shared_variance(sums, frf[:, 0], power)
        variance = variance * overlap_factor
        if excitation is not None:
            common = common_error_factor(*excitation, input_window, excitation_noise)
    input_correlation = window_line_correlation(input_window)
    for m in range(1, n_lags + 1):
        with np.errstate(divide="ignore", invalid="ignore"):
            mixed = (output_correlation[m] * response_part[:-m] * response_part[m:]
                     + input_correlation[m] * input_part[:-m] * np.conj(input_part[m:]))
            value = mixed * sums.sxx_lag[m - 1, :-m] / np.sqrt(power[:-m] * power[m:])
        correlation[m - 1, :-m] = np.where(np.isfinite(value), value, 0.0)
    magnitude = np.abs(correlation)
    correlation = np.where(magnitude > 1, correlation / np.maximum(magnitude, 1e-300), correlation)
    if sums.error_products is not None and frf is not None and frf.shape[:2] == (1, 1):
        # near a resonance a continuous record's errors are mostly leakage, which the window's model does not
        # describe: the correlation measured over the records serves instead
        measured = measured_line_correlation(sums.error_products, frf[0, 0], sums.n_records)
        if measured is not None:
            correlation = measured
    lags = lag_window(input_window, output_window, sums.excitation_square / sums.n_records)
    if decay_s is not None:
        lags = lags * np.exp(np.arange(lags.size) * interval / decay_s)
    influence = None
    if sums.record_cross is not None and frf is not None and frf.shape[:2] == (1, 1):
        influence = record_influence(sums.record_cross, sums.record_power, frf[0, 0], power)
    elif frf is not None:
        influence = _channel_influence(sums, frf)
    return NoiseModel(sums.n_records, dof, correlation, lags, interval, variance, influence,
                      overlapping if influence is not None else 0, withheld, common)


def _channel_influence(sums, frf: np.ndarray | None) -> np.ndarray | None:
    """Several channels' records' influences (:func:`~modal.estimate.record_influence.channel_influence`), or
    None where the records' spectra were not kept or the estimate is not H1 (``frf`` None)."""
    if frf is None or sums.record_input is None:
        return None
    return channel_influence(sums.record_input, sums.record_output, frf, sums.sxx)


def _shared_variance(sums, frf: np.ndarray, power: np.ndarray) -> tuple[np.ndarray, float]:
    """Several outputs of one input: the part of each line's error variance whose shape every channel shares,
    a/S_xx with a the outputs' mean response-noise power, and the excitation noise's power b (their mean) (:func:`~modal.noise_model.input_noise_split` of each
    output's residual; NaN on lines where an output's excitation-noise part does not hold). The excitation's noise
    enters output o as H_o times one common error, a different shape in every channel and, over the few samples
    a force window keeps, nearly one complex gain across a mode's band, which its modal constants take up."""
    n_out = frf.shape[0]
    a, b_out = np.zeros(n_out), np.zeros(n_out)
    holds = np.ones(power.size, bool)
    with np.errstate(divide="ignore", invalid="ignore"):
        for o in range(n_out):
            residual = (sums.syy[o] - np.abs(sums.syx[o, 0]) ** 2 / power) / (sums.n_records - 1)
            h2 = np.abs(frf[o]) ** 2
            _, b = input_noise_split(residual, h2)
            a[o], b_out[o] = input_noise_split(residual, h2, b * sums.n_records < INPUT_NOISE_LIMIT * power)
            holds &= b_out[o] * sums.n_records < INPUT_NOISE_LIMIT * power
        return np.where(holds & (power > 0), np.mean(a) / power, np.nan), float(np.mean(b_out))


def _warn_periods_per_record(excitation, length: int, sample_rate_hz: float, source: str) -> None:
    """Warn when a periodic excitation repeats several times within a record: only every k-th line holds it."""
    period = shortest_period(excitation, length)
    if period < length:
        count = length // period
        warn(f"{source}: the excitation repeats every {period} samples ({period / sample_rate_hz:g} s), {count} times "
             f"in each {length}-sample record: one line in {count} holds it and the lines between hold noise alone; "
             f"make a record one period (segment_length {period}; --segment-length {period})", QualityWarning)


def _warn_correlated_inputs(sxx: np.ndarray, labels, source: str) -> None:
    """Warn when two excitation channels are nearly fully coherent (:data:`INPUT_COHERENCE_LIMIT`)."""
    power = np.einsum("iif->if", sxx).real
    powered = np.all(power >= 1e-3 * power.max(axis=1, keepdims=True), axis=0)
    if not np.any(powered):
        return
    for i in range(sxx.shape[0]):
        for j in range(i + 1, sxx.shape[0]):
            coherence = float(np.median(np.abs(sxx[i, j, powered]) ** 2 / (power[i, powered] * power[j, powered])))
            if coherence > INPUT_COHERENCE_LIMIT:
                warn(f"{source}: {labels[i]} and {labels[j]} are {100 * coherence:.1f} % coherent (median line): "
                     "MIMO H1 separates the inputs by the part they do not share, and with so little of it the FRFs "
                     "and their errors do not hold; drive the shakers with independent signals", QualityWarning)
                return


def _warn_few_records(n_records: int, length: int, sample_rate_hz: float, source: str) -> None:
    """Warn when a continuous record gives fewer than :data:`FEW_RECORDS` records to average."""
    if n_records == 1:
        what = ("one record: its coherence is 1 by construction and it tells nothing of the FRF's noise; a fit's "
                "error bars then rest on its residual alone")
    else:
        what = (f"{n_records} records: each line's noise level rests on {n_records - 1} degree(s) of freedom, so the "
                "lines' weights and a fit's error bars do not hold (measured: damping errors 2.6 times wider than "
                "their error bars with 2 records)")
    warn(f"{source}: the FRF is averaged over {what}; average at least {FEW_RECORDS} records: a longer record or "
         f"shorter segments (segment_length {length} samples = {length / sample_rate_hz:g} s now; "
         "--segment-length N)", QualityWarning)


def _warn_excitation_noise(sums, name: str, source: str) -> None:
    """Warn when the measured excitation holds content the responses do not follow: H1 is then low by that
    share whatever the averages (:mod:`modal.estimate.excitation_noise`)."""
    share = excitation_noise_share(sums.sxx[0, 0].real, sums.syx[:, 0], sums.syy, sums.n_records)
    if share is not None and share > EXCITATION_NOISE_LIMIT:
        warn(f"{source}: {name}: the responses do not follow about {100 * min(share, 1.0):.0f} % of its power "
             "(median line): H1 reads the FRF that much low and masses and stiffnesses high, whatever the averages; "
             "noise on the force channel (a force measured at the shaker's body rather than through the force cell "
             "at the stinger's tip, a cable, a gain), a delay between the channels, or leakage of a very lightly "
             "damped mode: check the force channel, or estimate with H2 (estimator='H2'; --estimator H2), or "
             "longer segments", QualityWarning)


def _default_segment_length(n_samples: int) -> int:
    """Largest power of two giving at least 16 half-overlapping segments (at least 16 samples)."""
    return 1 << max(4, int(np.floor(np.log2(max(n_samples / 8.5, 16)))))


@one_blas_thread()
def estimate_frf(excitation, response, sample_rate_hz: float, *, estimator: str = "H1",
                 kind: str = "receptance", segment_length: int | None = None, overlap: float = 0.5,
                 window: str = "hann", exponential_decay_s: float | None = None, impact: bool = False,
                 response_quantity: str | None = None, excitation_points=None, response_points=None,
                 threshold: float | None = None, pretrigger_s: float | None = None,
                 double_hit_window_s: float = 0.05, decay_fraction: float = 0.05,
                 full_scale=None, take_lengths=None, take_names: list[str] | None = None,
                 source: str = "<array>") -> EstimatedFRF:
    """Estimate FRFs, coherence and per-line noise from excitation and response records.

    Parameters
    ----------
    excitation : array_like, shape (n_samples,) or (n_inputs, n_samples)
        Force channel(s), N (or the force unit of the file).
    response : array_like, shape (n_samples,) or (n_outputs, n_samples)
        Response channels. Any array-like that slices (``np.memmap``, an h5py
        dataset) is streamed record by record.
    sample_rate_hz : float
        Samples per second, Hz.
    estimator : {"H1", "H2", "Hv"}
        ``"H1"`` (noise on the response; MIMO with several inputs), ``"H2"``
        (noise on the force), ``"Hv"`` (total least squares). H2 and Hv take one input.
    kind : {"receptance", "mobility", "accelerance"}
        Kind of the returned FRF.
    response_quantity : {"displacement", "velocity", "acceleration"}, optional
        What the response channels measured; default: what ``kind`` implies (no
        conversion). Converting to a lower kind drops the 0 Hz line.
    segment_length : int, optional
        Samples per record. Continuous records: default the largest power of two
        giving ≥ 16 half-overlapping segments. Impact: default from the hit spacing.
    overlap : float
        Fraction in [0, 1) of a segment shared with the next (continuous records only).
    window : {"rect", "hann", "force", "exponential"}
        Continuous records: ``"rect"`` or ``"hann"`` on every channel. Impact
        records: ``"rect"``; ``"force"`` (force window on the excitation);
        ``"exponential"`` (force window on the excitation and exp(−t/τ) on all
        channels; needs ``exponential_decay_s``).
    exponential_decay_s : float, optional
        τ of the exponential window, s (also allowed with ``"force"``). The FRF
        carries it and :func:`modal.identify` corrects the damping.
    impact : bool
        Find the hits in a continuous record and average one record per accepted hit.
    excitation_points, response_points : sequence of str, optional
        Point ids of the inputs and outputs (a pair with equal ids is a driving point).
    threshold, pretrigger_s, double_hit_window_s, decay_fraction
        Hit detection settings, see :func:`modal.estimate.hits.find_hits`.
    full_scale : float or sequence of (float or None), optional
        The recorder's full scale: one value for every channel or one per channel
        (inputs first, then outputs), in the channels' units. Samples at or beyond
        99.9 % of it, and flat tops at a channel's extreme (clipping), are overloads:
        impact records reject the hits they touch, continuous records warn
        (:class:`~modal.errors.QualityWarning`); both list them in ``overloads``.
    take_lengths : sequence of int, optional
        Samples of each take when the records join several takes of one test end to end (hammer
        hits saved one file per hit): no segment or hit record straddles two takes, and hits are
        found take by take (:mod:`modal.estimate.takes`). ``hit_times_s`` then count on the joined
        samples, and each rejection says its ``take`` (from 1) and ``take_name``.
    take_names : sequence of str, optional
        How messages name the takes (the files; default ``"take 1"``, …).
    source : str
        Name used in messages (the file).

    Returns
    -------
    EstimatedFRF

    Notes
    -----
    Runs with one BLAS thread (:func:`modal.blas.one_blas_thread`): its products are small or one
    vector long, and a BLAS thread per core only waits for its threads (16 channels of 10⁶ samples on a
    loaded 2-core machine: 12-20 s with OpenBLAS's default threads, 2-2.7 s with one).
    """
    estimator = {"h1": "H1", "h2": "H2", "hv": "Hv"}.get(str(estimator).lower(), estimator)
    one_of("estimator", estimator, spectra.ESTIMATORS)
    one_of("kind", kind, FRF_KINDS)
    if response_quantity is not None:
        one_of("response_quantity", response_quantity, tuple(RESPONSE_QUANTITIES))
    one_of("window", window, WINDOWS)
    fs = positive_number("sample_rate_hz", sample_rate_hz, "rate in Hz")
    if not (0.0 <= overlap < 1.0):
        raise ParameterError(f"field 'overlap' is {overlap!r}; expected a fraction in [0, 1)")
    x = _as_signals(excitation, "excitation", source)
    y = _as_signals(response, "response", source)
    if x.shape[1] != y.shape[1]:
        raise ParameterError(
            f"{source}: 'excitation' has {x.shape[1]} samples and 'response' {y.shape[1]}; expected equal lengths"
        )
    n = x.shape[1]
    finite_samples(x, "excitation", source)
    finite_samples(y, "response", source)
    bounds = take_bounds(take_lengths, n, source)
    names_of_takes = _take_names(take_names, bounds.size - 1, source)

    def ids(points, count, name):
        if points is None:
            return None
        points = [points] if isinstance(points, (str, int)) else list(points)
        if len(points) != count:
            raise ParameterError(f"{source}: field {name!r} has {len(points)} ids, expected {count}")
        return [str(p) for p in points]

    ins = ids(excitation_points, x.shape[0], "excitation_points")
    outs = ids(response_points, y.shape[0], "response_points")
    labels = ([f"force {p}" for p in ins] if ins else
              ["force"] if x.shape[0] == 1 else [f"force {i + 1}" for i in range(x.shape[0])])
    labels += [f"response {p}" for p in outs] if outs else [f"response {o + 1}" for o in range(y.shape[0])]
    n_channels = x.shape[0] + y.shape[0]
    if full_scale is not None and np.ndim(full_scale) and len(full_scale) != n_channels:
        raise ParameterError(f"{source}: field 'full_scale' has {len(full_scale)} values; expected one or one per "
                             f"channel ({n_channels}, inputs first)")

    rejected: list[dict] = []
    hit_times: tuple = ()
    if impact:
        if window == "hann":
            raise ParameterError("field 'window': 'hann' would suppress the hit; impact records take "
                                 "'rect', 'force' or 'exponential'")
        if window == "exponential" and exponential_decay_s is None:
            raise ParameterError("field 'exponential_decay_s' is required with window='exponential' (τ in s)")
        if x.shape[0] != 1:
            raise ParameterError(f"{source}: impact=True takes one force channel, got {x.shape[0]}")
        force = np.asarray(x[0], dtype=float)
        refuse_swapped_channels(force, y, fs, labels, source)
        pre = None if pretrigger_s is None else pretrigger_s

        def find(force, response, rate, **options):
            if take_lengths is None:
                return find_hits(force, response, rate, **options)
            return find_hits_in_takes(force, response, rate, bounds, names_of_takes, **options)

        probe = find(force, np.asarray(y, dtype=float), fs, threshold=threshold, pretrigger_s=pre,
                     record_length=segment_length, double_hit_window_s=double_hit_window_s,
                     decay_fraction=decay_fraction, full_scale=full_scale, channel_names=labels, source=source)
        length = probe.record_length
        pre_samples = int(probe.trigger_index[0] - probe.record_start[0])
        decay = (None if exponential_decay_s is None
                 else exponential_window(length, fs, exponential_decay_s, pre_samples))
        hits = probe if decay is None else find(
            force, np.asarray(y, dtype=float), fs, threshold=threshold, pretrigger_s=pre, record_length=length,
            double_hit_window_s=double_hit_window_s, decay_fraction=decay_fraction, decay_window=decay,
            full_scale=full_scale, channel_names=labels, source=source)
        in_w = np.ones(length)
        if window in ("force", "exponential"):
            in_w = force_window(length, pre_samples, width=max(8, 3 * hits.pulse_samples))
            hits = reject_pulses_the_window_cuts(hits, force, in_w, fs, hit_labels(
                hits, None if take_lengths is None else bounds, names_of_takes, fs))
        rejected = hits.rejected
        overloads = hits.overloads
        # the force channel's offset (a charge amplifier's, an IEPE sensor settling) is no force the structure
        # felt: under the force window it would add a rectangular pulse the width of the window, a bias at the
        # lowest modes; the median of a hammer record, quiet but for its hits, is that offset. A response's
        # offset under the exponential window is a decaying pulse of its own, a pole at -1/τ
        x = (force - np.median(force))[np.newaxis, :]
        y = np.asarray(y, dtype=float)
        y = y - np.median(y, axis=1, keepdims=True)
        hit_times = tuple(float(t) / fs for t in hits.trigger_index[hits.accepted])
        starts = hits.record_start[hits.accepted]
        if starts.size == 0:
            where = [f"{r['take_name']} " if "take" in r else "" for r in rejected]
            reasons = "; ".join(f"{at}hit {r['hit']} at {r['time_s']:.3f} s: {r['reason']}"
                                + (f" ({r['detail']})" if r.get("detail") else "") for at, r in zip(where, rejected))
            advice = ""
            if any(r["reason"] == "response not decayed within the record" for r in rejected) and decay is None:
                advice = ("; the responses still ring at the end of the hit records: an exponential window makes them "
                          "decay within them (window='exponential' with exponential_decay_s; modal fit --window "
                          "exponential --exponential-decay-s S), its damping taken back out of the modes")
            raise ParameterError(f"{source}: every hit was rejected ({reasons}){advice}")
        out_w = np.ones(length)
        if decay is not None:
            in_w = in_w * decay
            out_w = decay
        step = length
    else:
        if window not in ("rect", "hann"):
            raise ParameterError(f"field 'window': {window!r} is for impact records (impact=True); "
                                 "a continuous record takes 'rect' or 'hann'")
        if exponential_decay_s is not None:
            raise ParameterError("field 'exponential_decay_s' applies to impact records (impact=True)")
        shortest = int(np.min(np.diff(bounds)))
        length = (min(_default_segment_length(n), 1 << int(np.floor(np.log2(shortest))))
                  if segment_length is None else int(segment_length))
        if not (2 <= length <= shortest):
            what = f"{shortest} samples (the shortest take)" if bounds.size > 2 else f"{n} samples"
            raise ParameterError(f"field 'segment_length' is {segment_length!r}; expected 2 to {what}")
        step = max(1, int(round(length * (1.0 - overlap))))
        starts = segment_starts(bounds, length, step)
        in_w = out_w = segment_window(window, length)
        decay = None
        forces = [pulse_train(np.asarray(x[i], dtype=float), fs) for i in range(x.shape[0])]
        for i, train in enumerate(forces):
            if train.impulsive:
                warn(f"{source}: {labels[i]} is {train.count} short pulse(s) holding {100 * train.energy_share:.0f} % "
                     f"of its energy in {100 * train.duty:.2f} % of the record, as hammer hits are; estimated as a "
                     f"continuous record (window {window!r}), which averages them with the noise between and cuts "
                     "those that straddle segments: estimate it as an impact record (impact=True; modal fit "
                     "--impact; scene key impact = true)", QualityWarning)
        if not any(train.impulsive for train in forces) and any(train.count for train in forces):
            # an excitation with excursions far above its noise that are no train of hits (a shaker's random or
            # swept force has none: no sample above 8 robust standard deviations) may be a response's ringing
            warn_impulsive_responses(y, fs, labels, source)
        overloads = find_overloads([x[i] for i in range(x.shape[0])] + [y[o] for o in range(y.shape[0])],
                                   full_scale)
        for item in overloads:
            warn(f"{source}: {item.describe(labels[item.channel])}: the spectra are distorted where it clipped; "
                 "lower the gain or the excitation level", QualityWarning)

    if impact and starts.size >= MIN_HITS:  # the hits' spectra over the force's band, once for all three tests
        band = hit_spectra(x[0], y, starts, length, in_w, out_w)
        warn_level_dependence(x[0], y, starts, length, in_w, out_w, fs, labels, source, band)
        if bounds.size <= 2:  # one record: did its FRF change part way through?
            warn_change_dependence(x[0], y, starts, np.flatnonzero(hits.accepted) + 1, hit_times, length, in_w,
                                    out_w, fs, labels, source, band)
        else:  # several takes: do they measure one FRF, and did one's change part way through?
            take_of_hit = np.searchsorted(bounds, starts, side="right") - 1
            warn_take_dependence(x[0], y, starts, take_of_hit, length, in_w, out_w, fs, labels, names_of_takes, source,
                                  band)
            warn_changes_within_takes(x[0], y, starts, take_of_hit, hits, bounds, names_of_takes, length, in_w, out_w,
                                       fs, labels, source, band)
    output_correlation = window_line_correlation(out_w)
    window_lags = lags_carried(output_correlation, length // 2 + 1)
    # continuous records, enough of them: the errors' correlation is also measured over the records
    measured = not impact and starts.size >= MIN_RECORDS
    # ... and each record's share of it kept (of every channel), within a memory budget
    keep_records = measured and starts.size * (length // 2 + 1) * x.shape[0] * y.shape[0] <= MAX_INFLUENCE_VALUES
    sums = spectra.accumulate(x, y, starts, length, in_w, out_w, lags=window_lags,
                              error_lags=max(window_lags, LEAKAGE_LAGS) if measured else 0,
                              keep_records=keep_records)
    if not impact and sums.n_records < FEW_RECORDS:
        _warn_few_records(sums.n_records, length, fs, source)
    if not impact and estimator == "H1" and x.shape[0] == 1:
        _warn_excitation_noise(sums, labels[0], source)
    if x.shape[0] > 1:
        _warn_correlated_inputs(sums.sxx, labels, source)
    factor = spectra.overlap_variance_factor(out_w, step) if not impact else 1.0
    estimate = {"H1": spectra.h1, "H2": spectra.h2, "Hv": spectra.hv}[estimator]
    frf3, coherence3, multiple, variance3 = estimate(sums, source)
    rises = rise_tests(y, hits.trigger_index, hits.accepted, length, hits.pulse_samples, fs) if impact else []
    unrelated = warn_unrelated(chance_tests(sums, multiple, output_correlation, factor),
                               labels[x.shape[0]:], x.shape[0], impact, source, rises)
    n_out, n_in, n_lines = frf3.shape
    frequency = np.fft.rfftfreq(length, 1.0 / fs)
    response_lines = frf3.reshape(n_out * n_in, n_lines)
    coherence = coherence3.reshape(n_out * n_in, n_lines)
    noise = None
    if variance3 is not None:
        noise = np.sqrt(variance3.reshape(n_out * n_in, n_lines) * factor)
    quiet = None
    if impact and sums.n_records == 1 and estimator == "H1":
        # one hit: no residual over records; the noise is read where the channels hold noise alone
        quiet = quiet_noise(x[0], y, int(starts[0]), length, pre_samples, hits.pulse_samples, in_w, out_w)
        if quiet is not None:
            with np.errstate(divide="ignore", invalid="ignore"):
                variance = ((quiet.response_power[:, None, None] + quiet.force_power * np.abs(frf3) ** 2)
                            / sums.sxx[0, 0].real)
            if np.all(np.isfinite(variance)):
                noise = np.sqrt(variance.reshape(n_out * n_in, n_lines))
    model = _noise_model(sums, output_correlation, in_w, out_w, fs, factor, decay_s=exponential_decay_s,
                         frf=frf3 if estimator == "H1" else None, quiet=quiet,
                         overlapping=0 if impact else overlapping_records(length, step),
                         withheld=measured and not keep_records and (n_in * n_out == 1 or estimator == "H1"),
                         excitation=(x[0], starts, length) if impact and n_in == 1 else None)

    if not impact and repeats_every([x[i] for i in range(x.shape[0])], length):
        _warn_periods_per_record([x[i] for i in range(x.shape[0])], length, fs, source)
        if window == "rect" and repeats_every([y[o] for o in range(y.shape[0])], length):
            model = replace(model, lag_window=None)  # whole periods in every record: no leakage to take out
    if response_quantity is not None:
        delta = KIND_POWER[kind] - RESPONSE_QUANTITIES[response_quantity]
        if delta:
            keep = frequency > 0 if delta < 0 else np.ones(frequency.size, bool)
            frequency = frequency[keep]
            scale = (2j * np.pi * frequency) ** delta
            response_lines = response_lines[:, keep] * scale
            coherence = coherence[:, keep]
            multiple = multiple[:, keep]
            if noise is not None:
                noise = noise[:, keep] * np.abs(scale)
            model = model.cropped(keep).scaled(np.abs(scale) ** 2, scale)

    single = n_out * n_in == 1
    return EstimatedFRF(
        frequency_hz=frequency,
        response=response_lines[0] if single else response_lines,
        kind=kind,
        response_points=None if outs is None else [o for o in outs for _ in range(n_in)],
        reference_points=None if ins is None else [i for _ in range(n_out) for i in ins],
        source=source,
        coherence=coherence[0] if single else coherence,
        multiple_coherence=multiple,
        noise_std=None if noise is None else (noise[0] if single else noise),
        averages=sums.n_records,
        rejected=list(rejected),
        estimator=estimator,
        window=window,
        exponential_decay_s=None if exponential_decay_s is None else float(exponential_decay_s),
        noise_model=model,
        sample_rate_hz=fs,
        segment_length=length,
        overlap=0.0 if impact else float(overlap),
        n_inputs=n_in,
        hit_times_s=hit_times,
        overloads=[{"channel": labels[o.channel], "how": o.how, "level": o.level, "samples": o.samples,
                    "longest_run": o.longest_run} for o in overloads],
        unrelated=unrelated,
    )
