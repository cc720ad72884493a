"""The frequency response function (FRF) container.

An :class:`FRF` holds one or many channels of a measured or synthetic FRF on a
common, strictly increasing frequency axis in Hz, together with its kind
(receptance, mobility or accelerance), optional point ids and units.
It validates on construction and is immutable; conversions return new objects.
"""
from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import Literal

import numpy as np

from .errors import FRFValidationError, ModalWarning, warn
from .noise_model import NoiseModel
from .units import TWO_PI
from .validate import one_of, per_line, positive_number

__all__ = ["FRF", "FRF_KINDS", "KIND_POWER", "DEFAULT_UNITS", "kind_factor"]

Kind = Literal["receptance", "mobility", "accelerance"]
FRF_KINDS: tuple[str, ...] = ("receptance", "mobility", "accelerance")
#: H_kind(ω) = (iω)**p · receptance(ω): the power p of each kind.
KIND_POWER = {"receptance": 0, "mobility": 1, "accelerance": 2}
DEFAULT_UNITS = {"receptance": "m/N", "mobility": "m/s/N", "accelerance": "m/s^2/N"}


def line_spacing(omega: np.ndarray) -> float:
    """Median spacing of a frequency axis (any unit; the axis has at least two lines).

    The common case, an evenly spaced axis, is recognised from the extreme spacings without
    sorting (the median of ``numpy.diff`` costs a partition on every call of the checks).
    """
    steps = omega[1:] - omega[:-1]
    low, high = float(steps.min()), float(steps.max())
    if high - low <= 1e-9 * abs(high):
        return (low + high) / 2
    return float(np.median(steps))


def kind_factor(omega_rad_s: np.ndarray, kind: str) -> np.ndarray:
    """Factor (iω)**p that turns a receptance into an FRF of ``kind``.

    Parameters
    ----------
    omega_rad_s : ndarray
        Angular frequency, rad/s.
    kind : {"receptance", "mobility", "accelerance"}
    """
    power = KIND_POWER[kind]
    if power == 0:
        return np.ones_like(omega_rad_s, dtype=complex)
    return (1j * np.asarray(omega_rad_s)) ** power


def _as_point_ids(value, n_channels: int, name: str, source: str) -> tuple[str, ...] | None:
    if value is None:
        return None
    if isinstance(value, (str, int, np.integer)):
        value = [value] * n_channels  # one id for every channel (a common reference)
    ids = tuple(str(v) for v in value)
    if len(ids) != n_channels:
        raise FRFValidationError(
            f"{source}: field '{name}' has {len(ids)} point ids, expected one per channel ({n_channels})"
        )
    return ids


@dataclass(frozen=True, eq=False)
class FRF:
    """Frequency response function on a common frequency axis.

    Parameters
    ----------
    frequency_hz : array_like, shape (n_freq,)
        Frequency lines in Hz, finite, non-negative and distinct. Unsorted input
        is sorted (with a warning); duplicates, NaN and Inf are rejected.
    response : array_like, shape (n_freq,) or (n_channels, n_freq)
        Complex FRF values, in the unit given by ``units``.
    kind : {"receptance", "mobility", "accelerance"}
        Displacement/force (m/N), velocity/force (m/s/N) or acceleration/force
        (m/s²/N).
    response_points, reference_points : sequence of str, optional
        One id per channel (for example ``"101+Z"``). A channel whose response
        and reference points are equal is a driving point.
    units : str, optional
        Unit of ``response``; defaults to the SI unit of ``kind``.
    source : str
        Where the data came from (file name); used in error messages.
    noise_std : array_like, shape like ``response``, optional
        Standard deviation of the complex random error of each line, E|Ĥ − H|² = noise_std², in
        the unit of ``response``: an FRF estimated from time records knows it
        (:func:`modal.estimate_frf`), and :func:`modal.identify` then weights the lines by it and
        takes it as the noise. None when unknown (identification estimates it from the data).
    exponential_decay_s : float, optional
        τ of an exponential window applied to the records the FRF was estimated from, s: every
        pole's real part is more negative by 1/τ, and :func:`modal.identify` takes that damping
        back out. None without such a window.
    noise_model : NoiseModel, optional
        What an estimate from time records knows about its errors beyond ``noise_std``: the
        averages they rest on, the correlation of neighbouring lines and the lag window that
        biases the estimate (:class:`modal.noise_model.NoiseModel`); :func:`modal.identify`
        weights the lines with that correlation and takes the window's bias out. None when unknown.

    Attributes
    ----------
    n_channels, n_freq : int
    omega_rad_s : ndarray
        Angular frequency, rad/s.
    """

    frequency_hz: np.ndarray
    response: np.ndarray
    kind: Kind = "receptance"
    response_points: tuple[str, ...] | None = None
    reference_points: tuple[str, ...] | None = None
    units: str | None = None
    source: str = "<array>"
    _single: bool = field(default=False, repr=False)
    noise_std: np.ndarray | None = None
    exponential_decay_s: float | None = None
    noise_model: NoiseModel | None = None

    def __post_init__(self) -> None:
        src = self.source
        one_of("kind", self.kind, FRF_KINDS, FRFValidationError, src)
        try:
            freq = np.array(self.frequency_hz, dtype=float)
        except (TypeError, ValueError) as exc:
            raise FRFValidationError(f"{src}: field 'frequency_hz' is not numeric ({exc})") from None
        try:
            resp = np.array(self.response, dtype=complex)
        except (TypeError, ValueError) as exc:
            raise FRFValidationError(f"{src}: field 'response' is not numeric ({exc})") from None
        if freq.ndim != 1:
            raise FRFValidationError(f"{src}: field 'frequency_hz' must be 1-D, got shape {freq.shape}")
        if freq.size < 2:
            raise FRFValidationError(f"{src}: field 'frequency_hz' has {freq.size} lines, expected at least 2")
        single = resp.ndim == 1
        if single:
            resp = resp[np.newaxis, :]
        if resp.ndim != 2 or resp.shape[1] != freq.size:
            raise FRFValidationError(
                f"{src}: field 'response' has shape {np.shape(self.response)}, expected "
                f"({freq.size},) or (n_channels, {freq.size}) to match 'frequency_hz'"
            )
        if resp.shape[0] == 0:
            raise FRFValidationError(f"{src}: field 'response' has no channels")
        bad = ~np.isfinite(freq)
        if bad.any():
            i = int(np.flatnonzero(bad)[0])
            raise FRFValidationError(
                f"{src}: field 'frequency_hz' has a non-finite value ({freq[i]}) at line {i}; expected finite Hz"
            )
        if (freq < 0).any():
            i = int(np.flatnonzero(freq < 0)[0])
            raise FRFValidationError(
                f"{src}: field 'frequency_hz' has a negative value ({freq[i]}) at line {i}; expected >= 0 Hz"
            )
        bad = ~np.isfinite(resp)
        if bad.any():
            ch, i = (int(v) for v in np.argwhere(bad)[0])
            raise FRFValidationError(
                f"{src}: field 'response' has a non-finite value at channel {ch}, line {i} "
                f"({freq[i]} Hz); expected finite complex numbers"
            )
        steps = np.diff(freq)
        if (steps <= 0).any():
            order = np.argsort(freq, kind="stable")
            sorted_freq = freq[order]
            dup = np.flatnonzero(np.diff(sorted_freq) == 0)
            if dup.size:
                raise FRFValidationError(
                    f"{src}: field 'frequency_hz' has duplicate lines ({sorted_freq[dup[0]]} Hz); "
                    "expected distinct frequencies"
                )
            warn(f"{src}: frequency lines were not increasing; sorted them", ModalWarning, stacklevel=4)
            freq = sorted_freq
            resp = resp[:, order]
        else:
            order = None
        freq.setflags(write=False)
        resp.setflags(write=False)
        n_ch = resp.shape[0]
        object.__setattr__(self, "frequency_hz", freq)
        object.__setattr__(self, "response", resp[0] if single else resp)
        object.__setattr__(self, "_single", single)
        object.__setattr__(self, "response_points", _as_point_ids(self.response_points, n_ch, "response_points", src))
        object.__setattr__(self, "reference_points", _as_point_ids(self.reference_points, n_ch, "reference_points", src))
        if self.units is None:
            object.__setattr__(self, "units", DEFAULT_UNITS[self.kind])
        if self.noise_std is not None:
            noise = per_line("noise_std", self.noise_std, resp[0].shape if single else resp.shape, FRFValidationError, src)
            if order is not None:
                noise = noise[..., order]
            noise.setflags(write=False)
            object.__setattr__(self, "noise_std", noise)
        if self.noise_model is not None:
            if not isinstance(self.noise_model, NoiseModel):
                raise FRFValidationError(f"{src}: field 'noise_model' is a {type(self.noise_model).__name__}; "
                                         "expected a modal.noise_model.NoiseModel")
            corr = self.noise_model.line_correlation
            if corr is not None and corr.shape[1] != freq.size:
                raise FRFValidationError(f"{src}: field 'noise_model' has a line correlation over {corr.shape[1]} "
                                         f"lines; expected {freq.size} (one per line)")
            variance = self.noise_model.variance_model
            if variance is not None and variance.size != freq.size:
                raise FRFValidationError(f"{src}: field 'noise_model' has a variance model over {variance.size} "
                                         f"lines; expected {freq.size} (one per line)")
            influence = self.noise_model.record_influence
            if influence is not None and influence.shape[-1] != freq.size:
                raise FRFValidationError(f"{src}: field 'noise_model' has records' influences over "
                                         f"{influence.shape[-1]} lines; expected {freq.size} (one per line)")
            if order is not None and influence is not None:
                object.__setattr__(self, "noise_model", replace(self.noise_model, record_influence=influence[..., order]))
            if order is not None and corr is not None:  # the lines were reordered: neighbours are not neighbours
                object.__setattr__(self, "noise_model", replace(self.noise_model, line_correlation=None))
            if order is not None and variance is not None:
                object.__setattr__(self, "noise_model", replace(self.noise_model, variance_model=variance[order]))
            common = self.noise_model.relative_error
            if common is not None and common.n_lines != freq.size:
                raise FRFValidationError(f"{src}: field 'noise_model' has a relative error over {common.n_lines} "
                                         f"lines; expected {freq.size} (one per line)")
            if order is not None and common is not None:
                object.__setattr__(self, "noise_model", replace(self.noise_model, relative_error=common.cropped(order)))
        if self.exponential_decay_s is not None:
            object.__setattr__(self, "exponential_decay_s", positive_number(
                "exponential_decay_s", self.exponential_decay_s, "time in s", FRFValidationError, src))

    # ------------------------------------------------------------------ views
    @property
    def n_freq(self) -> int:
        """Number of frequency lines."""
        return self.frequency_hz.size

    @property
    def n_channels(self) -> int:
        """Number of channels (1 for a single FRF)."""
        return 1 if self._single else self.response.shape[0]

    @property
    def channels(self) -> np.ndarray:
        """Response as a 2-D array ``(n_channels, n_freq)`` (a view)."""
        return self.response[np.newaxis, :] if self._single else self.response

    @property
    def omega_rad_s(self) -> np.ndarray:
        """Angular frequency of each line, rad/s."""
        return self.frequency_hz * TWO_PI

    @property
    def magnitude(self) -> np.ndarray:
        """|H| in the unit of ``units``."""
        return np.abs(self.response)

    @property
    def phase_rad(self) -> np.ndarray:
        """Phase of H in radians, in (−π, π]."""
        return np.angle(self.response)

    @property
    def driving_point_known(self) -> bool:
        """Whether the point ids say which channels are driving points: both ``response_points`` and
        ``reference_points`` are given (without them nothing says where the response was measured
        relative to the excitation, and :func:`modal.identify` gives no k, c, m unless told)."""
        return self.response_points is not None and self.reference_points is not None

    def is_driving_point(self) -> np.ndarray:
        """Boolean per channel: response point equals reference point.

        All False when the point ids do not say (:attr:`driving_point_known`); a driving point is then
        declared to :func:`modal.identify` (``driving_point=``).
        """
        if not self.driving_point_known:
            return np.zeros(self.n_channels, bool)
        return np.array([r == q for r, q in zip(self.response_points, self.reference_points)])

    # ------------------------------------------------------------ transforms
    def as_kind(self, kind: Kind) -> "FRF":
        """Exact conversion to another FRF kind (multiplies by (iω)**Δp; ``noise_std`` by |ω|**Δp, the noise
        model's variance model by |ω|**(2Δp) and its records' influences by (iω)**Δp).

        Converting a line at 0 Hz to a lower kind (for example accelerance to
        receptance) divides by zero and is refused.
        """
        one_of("kind", kind, FRF_KINDS, FRFValidationError, self.source)
        delta = KIND_POWER[kind] - KIND_POWER[self.kind]
        if delta == 0:
            return self
        iw = 1j * self.omega_rad_s
        if delta < 0 and np.any(iw == 0):
            raise FRFValidationError(
                f"{self.source}: cannot convert {self.kind} to {kind}: the line at 0 Hz would divide by zero"
            )
        resp = self.response * iw ** delta
        units = DEFAULT_UNITS[kind] if self.units == DEFAULT_UNITS[self.kind] else None
        noise = None if self.noise_std is None else self.noise_std * np.abs(self.omega_rad_s) ** delta
        # the variance model scales as the variance, |iω|^(2Δp); each record's error converts as H does
        scale = iw ** delta
        model = None if self.noise_model is None else self.noise_model.scaled(np.abs(scale) ** 2, scale)
        return replace(self, response=resp, kind=kind, units=units, noise_std=noise, noise_model=model)

    def cropped(self, f_low_hz: float, f_high_hz: float) -> "FRF":
        """The lines with ``f_low_hz <= f <= f_high_hz``."""
        keep = (self.frequency_hz >= f_low_hz) & (self.frequency_hz <= f_high_hz)
        if keep.sum() < 2:
            raise FRFValidationError(
                f"{self.source}: band {f_low_hz}–{f_high_hz} Hz holds {int(keep.sum())} lines, expected at least 2"
            )
        return replace(self, frequency_hz=self.frequency_hz[keep], response=self.response[..., keep],
                       noise_std=None if self.noise_std is None else self.noise_std[..., keep],
                       noise_model=None if self.noise_model is None else self.noise_model.cropped(keep))

    def channel(self, index: int) -> "FRF":
        """A single-channel FRF of channel ``index``."""
        pts = lambda ids: None if ids is None else (ids[index],)  # noqa: E731
        return replace(
            self,
            response=self.channels[index],
            response_points=pts(self.response_points),
            reference_points=pts(self.reference_points),
            noise_std=None if self.noise_std is None else np.atleast_2d(self.noise_std)[index],
        )

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, FRF):
            return NotImplemented
        return (
            self.kind == other.kind
            and self.units == other.units
            and self.response_points == other.response_points
            and self.reference_points == other.reference_points
            and np.array_equal(self.frequency_hz, other.frequency_hz)
            and np.array_equal(self.response, other.response)
        )

    __hash__ = None  # type: ignore[assignment]
