"""Synthetic time records with an exactly known FRF: impact-hammer and random excitation.

A structure is a :class:`DigitalModes`: modes (natural frequency, damping ratio,
receptance modal constants per output) sampled at one rate, or the modes of an
``M, C, K`` model (:meth:`DigitalModes.from_matrices`). Each mode becomes a
digital resonator by impulse invariance: its discrete impulse response is the
continuous one sampled, T·g(nT) (half the first sample, where g jumps, so that
the digital response is the aliased sum of the continuous one), plus the direct
term of velocity and acceleration. The digital poles are exactly e^{pT}
(p = −ζωn ± iωd) and the digital system's frequency response at any line is known
in closed form (:meth:`DigitalModes.frf`). A record made by filtering a force
through it therefore has a known FRF with no model error: an estimate from it
differs from :meth:`SyntheticRecord.frf` only by noise, leakage and the windows.

:func:`impact_record` makes hammer records (half-sine pulses with amplitude and
width varying between hits, rebounds, noise, clipping at a full scale);
:func:`random_record` makes stationary random-excitation records. Both return a
:class:`SyntheticRecord` whose ``record`` is a :class:`~modal.io.timedata.TimeRecord`
(force first, in N; responses in SI), ready for :func:`modal.estimate_frf` or
:func:`modal.io.timewrite.write_time`.

Modal constants follow :func:`modal.synthetic.modal_frf`: the receptance of mode r
at output o is A/((s − p)(s − p̄)) for a real A (proportional damping). A complex A
(from :meth:`DigitalModes.from_matrices` with non-proportional damping) is the
residue form R/(s − p) + R̄/(s − p̄) with R = A/(2iωd), which agrees with
``modal_frf`` near the resonance.
"""
from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from .errors import ParameterError
from .frf import KIND_POWER
from .io.timedata import TimeRecord
from .units import TWO_PI

__all__ = ["DigitalModes", "SyntheticRecord", "impact_record", "random_record", "hammer_force",
           "RESPONSE_UNITS"]

#: samples a response is computed in at a time (buffers of a few hundred kB, which stay in cache)
_STRETCH = 1 << 14
#: what a response channel measures → its power of s relative to displacement
_QUANTITY_POWER = {"displacement": 0, "velocity": 1, "acceleration": 2}
_KIND_OF_QUANTITY = {"displacement": "receptance", "velocity": "mobility", "acceleration": "accelerance"}
#: SI unit of each response quantity (and of the force)
RESPONSE_UNITS = {"displacement": "m", "velocity": "m/s", "acceleration": "m/s^2", "force": "N"}


def _quantity(value: str) -> str:
    if value not in _QUANTITY_POWER:
        raise ParameterError(f"'response_quantity' is {value!r}; expected one of {', '.join(_QUANTITY_POWER)}")
    return value


@dataclass(frozen=True)
class DigitalModes:
    """Modes sampled at one rate, as a digital system with an exactly known frequency response.

    Parameters
    ----------
    natural_frequency_hz : array_like, shape (n_modes,)
        Undamped natural frequencies, Hz; each below the Nyquist frequency.
    damping_ratio : array_like, shape (n_modes,)
        Viscous damping ratios, 0 <= ζ < 1.
    modal_constant : array_like, shape (n_outputs, n_modes) or (n_modes,)
        Receptance modal constants, 1/kg (real for proportional damping; see the module).
    sample_rate_hz : float
        Samples per second, Hz.
    """

    natural_frequency_hz: np.ndarray
    damping_ratio: np.ndarray
    modal_constant: np.ndarray
    sample_rate_hz: float

    def __post_init__(self) -> None:
        fs = float(self.sample_rate_hz)
        if not (np.isfinite(fs) and fs > 0):
            raise ParameterError(f"'sample_rate_hz' is {self.sample_rate_hz!r}; expected a positive rate in Hz")
        fn = np.atleast_1d(np.asarray(self.natural_frequency_hz, dtype=float))
        zeta = np.atleast_1d(np.asarray(self.damping_ratio, dtype=float))
        const = np.atleast_2d(np.asarray(self.modal_constant))
        const = const.astype(float) if not np.iscomplexobj(const) else const.astype(complex)
        if fn.ndim != 1 or not np.all(np.isfinite(fn)) or np.any(fn <= 0) or np.any(fn >= fs / 2):
            raise ParameterError(f"'natural_frequency_hz' is {self.natural_frequency_hz!r}; expected finite "
                                 f"frequencies between 0 and the Nyquist frequency {fs / 2:g} Hz")
        if zeta.shape != fn.shape or not np.all(np.isfinite(zeta)) or np.any(zeta < 0) or np.any(zeta >= 1):
            raise ParameterError(f"'damping_ratio' is {self.damping_ratio!r}; expected one ratio 0 <= ζ < 1 per mode")
        if const.ndim != 2 or const.shape[1] != fn.size or not np.all(np.isfinite(const)):
            raise ParameterError(f"'modal_constant' has shape {np.shape(self.modal_constant)}; expected finite "
                                 f"values shaped (n_outputs, {fn.size})")
        for name, value in (("natural_frequency_hz", fn), ("damping_ratio", zeta), ("modal_constant", const)):
            value.setflags(write=False)
            object.__setattr__(self, name, value)
        object.__setattr__(self, "sample_rate_hz", fs)

    @classmethod
    def from_matrices(cls, mass, damping, stiffness, sample_rate_hz: float, response_dofs=None,
                      reference_dof: int = 0) -> "DigitalModes":
        """The modes of ``M ẍ + C ẋ + K x = f``, force at ``reference_dof``, outputs at ``response_dofs``.

        Parameters
        ----------
        mass, damping, stiffness : array_like, shape (n_dof, n_dof)
            M (kg), C (N s/m), K (N/m).
        sample_rate_hz : float
        response_dofs : sequence of int, optional
            Degrees of freedom observed (default: all).
        reference_dof : int
            Degree of freedom driven by the force.

        Raises
        ------
        ParameterError
            A mode is not underdamped (a real pole), or the matrices are not square and finite.
        """
        M, C, K = (np.atleast_2d(np.asarray(a, dtype=float)) for a in (mass, damping, stiffness))
        n = M.shape[0]
        for name, a in (("mass", M), ("damping", C), ("stiffness", K)):
            if a.shape != (n, n) or not np.all(np.isfinite(a)):
                raise ParameterError(f"'{name}' must be a finite ({n}, {n}) matrix, got shape {a.shape}")
        if not 0 <= int(reference_dof) < n:
            raise ParameterError(f"'reference_dof' is {reference_dof}; expected 0 to {n - 1}")
        dofs = list(range(n)) if response_dofs is None else [int(d) for d in response_dofs]
        if any(not 0 <= d < n for d in dofs):
            raise ParameterError(f"'response_dofs' is {dofs}; expected degrees of freedom 0 to {n - 1}")
        try:
            minv = np.linalg.inv(M)
        except np.linalg.LinAlgError:
            raise ParameterError("'mass' is singular; expected a positive definite mass matrix") from None
        state = np.block([[np.zeros((n, n)), np.eye(n)], [-minv @ K, -minv @ C]])
        lam, vec = np.linalg.eig(state)
        upper = lam.imag > 0
        if upper.sum() != n:
            raise ParameterError(f"the model has {n - int(upper.sum())} mode(s) that are not underdamped (real "
                                 "poles); expected n_dof oscillating modes")
        left = np.linalg.inv(vec)
        b = np.concatenate([np.zeros(n), minv[:, int(reference_dof)]])
        residue = vec[dofs][:, upper] * (left[upper] @ b)[None, :]  # (n_outputs, n_modes)
        poles = lam[upper]
        order = np.argsort(np.abs(poles))
        poles, residue = poles[order], residue[:, order]
        wn = np.abs(poles)
        return cls(wn / TWO_PI, -poles.real / wn, residue * 2j * poles.imag, sample_rate_hz)

    @property
    def n_outputs(self) -> int:
        return self.modal_constant.shape[0]

    def poles(self) -> np.ndarray:
        """Continuous poles p = −ζωn + iωd, rad/s, one per mode."""
        wn = TWO_PI * self.natural_frequency_hz
        z = self.damping_ratio
        return -z * wn + 1j * wn * np.sqrt(1 - z**2)

    def _sections(self, power: int) -> tuple[np.ndarray, np.ndarray]:
        """Second-order sections: numerators b (n_outputs, n_modes, 3), denominators a (n_modes, 3)."""
        T = 1.0 / self.sample_rate_hz
        p = self.poles()
        residue = self.modal_constant / (2j * p.imag)[None, :]  # A/((s-p)(s-p̄)) = R/(s-p) + R̄/(s-p̄)
        zp = np.exp(p * T)
        # s^q R/(s − p) = (polynomial in s) + R p^q/(s − p): the proper part's residue, and the direct term
        rc = residue * p[None, :] ** power
        direct = {0: 0.0, 1: 2 * residue.real, 2: 2 * (residue * p[None, :]).real}[power]
        # T Σ_n g(nT) q^n with g(0) halved (g jumps there) is T[Rc/(1 − zp q) + c.c.] − T Re(Rc); plus the
        # direct term
        constant = direct - T * rc.real
        a = np.stack([np.ones_like(zp.real), -2 * zp.real, np.abs(zp) ** 2], axis=-1)
        b = np.zeros(rc.shape + (3,))
        b[..., 0] = 2 * T * rc.real
        b[..., 1] = -2 * T * (rc * zp.conj()[None, :]).real
        b += constant[..., None] * a[None, :, :]
        return b, a

    def respond(self, force, quantity: str = "displacement") -> np.ndarray:
        """Response of every output to a force record (N), from rest.

        Parameters
        ----------
        force : array_like, shape (n_samples,)
            Force, N, at the system's sample rate.
        quantity : {"displacement", "velocity", "acceleration"}
            What the outputs measure (m, m/s, m/s²).

        Returns
        -------
        ndarray, shape (n_outputs, n_samples)
        """
        from scipy.signal import lfilter  # scipy.signal loads scipy's solvers: only when a record is made

        power = _QUANTITY_POWER[_quantity(quantity)]
        force = np.asarray(force, dtype=float)
        b, a = self._sections(power)
        out = np.zeros((self.n_outputs, force.size))
        # the numerators applied a stretch of samples at a time through buffers that stay in cache: one
        # (outputs × 3)(3 × samples) product over a whole long record made fresh arrays of hundreds of MB per
        # mode, whose page faults cost more than the product (2²² samples, 4 outputs: 3.2 s against 0.2)
        # stretches of equal length (to a sample): none of one sample, which BLAS would take as a matrix-vector
        # product and round otherwise
        edges = np.linspace(0, force.size, -(-force.size // _STRETCH) + 1).round().astype(int)
        longest = int(np.diff(edges).max()) if force.size else 0
        delayed = np.zeros((3, longest))
        product = np.empty((self.n_outputs, longest))
        for r in range(a.shape[0]):
            u = lfilter([1.0], a[r], force)  # the pole part, shared by every output
            numerator = np.ascontiguousarray(b[:, r, :])
            for first, stop in zip(edges[:-1], edges[1:]):
                n = stop - first
                for lag in range(3):  # row lag holds u delayed by lag samples (zero before the record)
                    zeros = min(max(lag - first, 0), n)
                    delayed[lag, :zeros] = 0.0
                    delayed[lag, zeros:n] = u[first + zeros - lag:stop - lag]
                np.matmul(numerator, delayed[:, :n], out=product[:, :n])
                out[:, first:stop] += product[:, :n]
        return out

    def frf(self, frequency_hz, kind: str = "receptance") -> np.ndarray:
        """The digital system's exact frequency response at ``frequency_hz``.

        Parameters
        ----------
        frequency_hz : array_like, shape (n_lines,)
        kind : {"receptance", "mobility", "accelerance"}
            Displacement, velocity or acceleration over force.

        Returns
        -------
        ndarray, shape (n_outputs, n_lines), complex
        """
        if kind not in KIND_POWER:
            raise ParameterError(f"'kind' is {kind!r}; expected one of {', '.join(KIND_POWER)}")
        b, a = self._sections(KIND_POWER[kind])
        q = np.exp(-1j * TWO_PI * np.asarray(frequency_hz, dtype=float) / self.sample_rate_hz)
        powers = np.stack([np.ones_like(q), q, q * q])  # (3, n_lines)
        return np.sum((b @ powers) / (a @ powers)[None, :, :], axis=1)

    def continuous_frf(self, frequency_hz, kind: str = "receptance") -> np.ndarray:
        """The continuous system's frequency response, Σ (iω)^p [R/(iω − p) + R̄/(iω − p̄)].

        Equal to :func:`modal.synthetic.modal_frf` for real modal constants; :meth:`frf`
        is its aliased sum (the difference grows towards the Nyquist frequency).

        Returns
        -------
        ndarray, shape (n_outputs, n_lines), complex
        """
        if kind not in KIND_POWER:
            raise ParameterError(f"'kind' is {kind!r}; expected one of {', '.join(KIND_POWER)}")
        p = self.poles()
        residue = self.modal_constant / (2j * p.imag)[None, :]
        s = 1j * TWO_PI * np.asarray(frequency_hz, dtype=float)
        modes = (residue[:, :, None] / (s[None, None, :] - p[None, :, None])
                 + residue.conj()[:, :, None] / (s[None, None, :] - p.conj()[None, :, None]))
        return s ** KIND_POWER[kind] * modes.sum(axis=1)


@dataclass(frozen=True)
class SyntheticRecord:
    """A synthetic time record and the truth it was made from.

    Attributes
    ----------
    record : TimeRecord
        Channel 0 is the force (N); the others are the responses (SI units).
    system : DigitalModes
    response_quantity : str
        ``"displacement"``, ``"velocity"`` or ``"acceleration"``.
    hit_times_s : tuple of float
        Start of each hammer pulse, s (empty for random excitation).
    rebound_times_s : tuple of float
        Start of each rebound pulse, s.
    clipped_samples : tuple of int
        Per channel, samples the full scale clipped.
    """

    record: TimeRecord
    system: DigitalModes
    response_quantity: str
    hit_times_s: tuple = ()
    rebound_times_s: tuple = ()
    clipped_samples: tuple = field(default=())

    @property
    def kind(self) -> str:
        """The FRF kind the responses give over the force."""
        return _KIND_OF_QUANTITY[self.response_quantity]

    def frf(self, frequency_hz) -> np.ndarray:
        """Exact response-over-force FRF of the record's channels, shape (n_outputs, n_lines)."""
        return self.system.frf(frequency_hz, self.kind)


def hammer_force(n_samples: int, sample_rate_hz: float, pulse_times_s, width_s=0.002, amplitude_n=100.0) -> np.ndarray:
    """Half-sine force pulses, N, sampled at ``sample_rate_hz``.

    Parameters
    ----------
    n_samples : int
    sample_rate_hz : float
    pulse_times_s : sequence of float
        Start of each pulse, s.
    width_s, amplitude_n : float or sequence of float
        Each pulse's duration (s) and peak (N): one value for all, or one per pulse.
    """
    times = np.atleast_1d(np.asarray(pulse_times_s, dtype=float))
    widths = np.broadcast_to(np.asarray(width_s, dtype=float), times.shape)
    peaks = np.broadcast_to(np.asarray(amplitude_n, dtype=float), times.shape)
    force = np.zeros(int(n_samples))
    fs = float(sample_rate_hz)
    for t0, width, peak in zip(times, widths, peaks):
        if not (np.isfinite(width) and width > 0):
            raise ParameterError(f"pulse width {width!r} s; expected a positive duration")
        first = max(0, int(np.floor(t0 * fs)) - 1)
        last = min(force.size, int(np.ceil((t0 + width) * fs)) + 1)
        t = np.arange(first, last) / fs
        inside = (t >= t0) & (t < t0 + width)  # the samples of [t0, t0 + width), as the times compare
        force[first:last][inside] += peak * np.sin(np.pi * (t[inside] - t0) / width)
    return force


def _per_channel(value, n_channels: int, name: str):
    """A value per channel (None where not given) from a scalar, None or a sequence."""
    if value is None:
        return [None] * n_channels
    if np.ndim(value) == 0:
        return [float(value)] * n_channels
    values = [None if v is None else float(v) for v in value]
    if len(values) != n_channels:
        raise ParameterError(f"'{name}' has {len(values)} values; expected one per channel ({n_channels}, force first)")
    return values


def _finish(system: DigitalModes, force: np.ndarray, response: np.ndarray, quantity: str, *, rng,
            force_noise: float, response_noise: float, noise_reference: str, full_scale, declare_full_scale: bool,
            names, source: str) -> tuple[TimeRecord, tuple[int, ...]]:
    """Add noise, clip at the full scale and wrap the channels in a TimeRecord."""
    clean = np.vstack([force[None, :], response])
    n_channels = clean.shape[0]
    for name, level in (("force_noise", force_noise), ("response_noise", response_noise)):
        if not (np.isfinite(level) and level >= 0):
            raise ParameterError(f"'{name}' is {level!r}; expected a fraction >= 0")
    reference = (np.max(np.abs(clean), axis=1) if noise_reference == "peak"
                 else np.sqrt(np.mean(clean**2, axis=1)))
    level = np.array([force_noise] + [response_noise] * (n_channels - 1)) * reference
    measured = clean + level[:, None] * rng.standard_normal(clean.shape)
    scale = _per_channel(full_scale, n_channels, "full_scale")
    clipped = []
    for k, fs_k in enumerate(scale):
        if fs_k is None:
            clipped.append(0)
            continue
        if not (np.isfinite(fs_k) and fs_k > 0):
            raise ParameterError(f"'full_scale' of channel {k + 1} is {fs_k!r}; expected a positive level")
        over = np.abs(measured[k]) > fs_k
        clipped.append(int(over.sum()))
        measured[k] = np.clip(measured[k], -fs_k, fs_k)  # the converter saturates: flat tops at ±full scale
    names = (["force"] + [f"response {k}" for k in range(1, n_channels)]) if names is None else [str(n) for n in names]
    if len(names) != n_channels:
        raise ParameterError(f"'names' has {len(names)} names; expected one per channel ({n_channels}, force first)")
    declared = tuple(scale) if declare_full_scale and any(v is not None for v in scale) else None
    record = TimeRecord(measured, system.sample_rate_hz, tuple(names), ("force",) + (quantity,) * (n_channels - 1),
                        (RESPONSE_UNITS["force"],) + (RESPONSE_UNITS[quantity],) * (n_channels - 1), source, declared)
    return record, tuple(clipped)


def _varied(rng, nominal: float, variation: float, count: int, name: str) -> np.ndarray:
    """``count`` values scattered log-normally around ``nominal`` with relative spread ``variation``."""
    if not (np.isfinite(nominal) and nominal > 0):
        raise ParameterError(f"'{name}' is {nominal!r}; expected a positive value")
    if not (np.isfinite(variation) and variation >= 0):
        raise ParameterError(f"'{name}' variation is {variation!r}; expected a fraction >= 0")
    return nominal * np.exp(variation * rng.standard_normal(count))


def impact_record(system: DigitalModes, hit_times_s: Sequence[float], duration_s: float, *,
                  pulse_width_s: float = 0.002, amplitude_n: float = 100.0, amplitude_variation: float = 0.0,
                  width_variation: float = 0.0, rebound_delay_s=None, rebound_fraction: float = 0.3,
                  force_noise: float = 0.0, response_noise: float = 0.0, full_scale=None,
                  declare_full_scale: bool = True, response_quantity: str = "acceleration", names=None,
                  seed: int | np.random.Generator | None = 0, source: str = "<synthetic impact>") -> SyntheticRecord:
    """An impact-hammer record: half-sine hits on the structure, its responses, noise and clipping.

    Parameters
    ----------
    system : DigitalModes
        The structure (its sample rate is the record's).
    hit_times_s : sequence of float
        Start of each hit, s.
    duration_s : float
        Length of the record, s.
    pulse_width_s : float
        Nominal duration of a hammer pulse, s (a half sine; its spectrum is flat to about 1/width).
    amplitude_n : float
        Nominal peak force, N.
    amplitude_variation, width_variation : float
        Relative scatter between hits (log-normal, standard deviation of the logarithm).
    rebound_delay_s : float or sequence of (float or None), optional
        A second, smaller pulse this long after the start of a hit, s: one delay for
        every hit or one per hit (None for no rebound).
    rebound_fraction : float
        Peak of a rebound relative to its hit's.
    force_noise, response_noise : float
        Standard deviation of white measurement noise as a fraction of each clean
        channel's largest |value|.
    full_scale : float or sequence of (float or None), optional
        Converter full scale per channel (force first), in N and the response unit:
        the measured values are clipped to ±full scale (flat tops).
    declare_full_scale : bool
        Record the full scale in ``record.full_scale`` (as a file declaring it would).
    response_quantity : {"displacement", "velocity", "acceleration"}
    names : sequence of str, optional
        Channel names, force first (default ``"force"``, ``"response 1"``, ...).
    seed : int or Generator
        Seed of the scatter and the noise.
    source : str
        The record's name in messages.

    Returns
    -------
    SyntheticRecord
    """
    quantity = _quantity(response_quantity)
    rng = np.random.default_rng(seed)
    fs = system.sample_rate_hz
    if not (np.isfinite(duration_s) and duration_s > 0):
        raise ParameterError(f"'duration_s' is {duration_s!r}; expected a positive duration in s")
    n = int(round(duration_s * fs))
    times = np.atleast_1d(np.asarray(hit_times_s, dtype=float))
    if times.size == 0 or not np.all(np.isfinite(times)) or np.any(times < 0) or np.any(times >= duration_s):
        raise ParameterError(f"'hit_times_s' is {hit_times_s!r}; expected times within the record "
                             f"(0 to {duration_s} s)")
    peaks = _varied(rng, amplitude_n, amplitude_variation, times.size, "amplitude_n")
    widths = _varied(rng, pulse_width_s, width_variation, times.size, "pulse_width_s")
    if rebound_delay_s is None:
        delays = [None] * times.size
    elif np.ndim(rebound_delay_s) == 0:
        delays = [float(rebound_delay_s)] * times.size
    else:
        delays = [None if d is None else float(d) for d in rebound_delay_s]
        if len(delays) != times.size:
            raise ParameterError(f"'rebound_delay_s' has {len(delays)} values; expected one per hit ({times.size})")
    if not (np.isfinite(rebound_fraction) and rebound_fraction > 0):
        raise ParameterError(f"'rebound_fraction' is {rebound_fraction!r}; expected a positive fraction")
    rebound = [(t + d, w, rebound_fraction * p) for t, d, w, p in zip(times, delays, widths, peaks) if d is not None]
    if any(not (np.isfinite(r[0]) and r[0] > 0) for r in rebound):
        raise ParameterError(f"'rebound_delay_s' is {rebound_delay_s!r}; expected positive delays in s")
    pulse_times = np.concatenate([times, [r[0] for r in rebound]])
    force = hammer_force(n, fs, pulse_times, np.concatenate([widths, [r[1] for r in rebound]]),
                         np.concatenate([peaks, [r[2] for r in rebound]]))
    response = system.respond(force, quantity)
    record, clipped = _finish(system, force, response, quantity, rng=rng, force_noise=force_noise,
                              response_noise=response_noise, noise_reference="peak", full_scale=full_scale,
                              declare_full_scale=declare_full_scale, names=names, source=source)
    return SyntheticRecord(record, system, quantity, tuple(float(t) for t in times),
                           tuple(float(r[0]) for r in rebound), clipped)


def random_record(system: DigitalModes, duration_s: float, *, force_rms_n: float = 1.0, band_hz=None,
                  force_noise: float = 0.0, response_noise: float = 0.0, full_scale=None,
                  declare_full_scale: bool = True, response_quantity: str = "acceleration", names=None,
                  seed: int | np.random.Generator | None = 0, source: str = "<synthetic random>") -> SyntheticRecord:
    """A stationary random-excitation record (shaker): Gaussian force, responses, noise and clipping.

    The structure is driven for five decay times of its slowest mode before the
    record starts (by the record's force repeated), so the record holds no start-up
    transient; the force's spectrum over the record is zero outside ``band_hz``.

    Parameters
    ----------
    system : DigitalModes
    duration_s : float
        Length of the record, s.
    force_rms_n : float
        RMS of the force, N.
    band_hz : (float, float), optional
        Limit the force's spectrum to this band, Hz (default: white up to the Nyquist frequency).
    force_noise, response_noise : float
        Standard deviation of white measurement noise as a fraction of each clean channel's RMS.
    full_scale, declare_full_scale, response_quantity, names, seed, source
        As in :func:`impact_record`.

    Returns
    -------
    SyntheticRecord
    """
    quantity = _quantity(response_quantity)
    rng = np.random.default_rng(seed)
    fs = system.sample_rate_hz
    if not (np.isfinite(duration_s) and duration_s > 0):
        raise ParameterError(f"'duration_s' is {duration_s!r}; expected a positive duration in s")
    if not (np.isfinite(force_rms_n) and force_rms_n > 0):
        raise ParameterError(f"'force_rms_n' is {force_rms_n!r}; expected a positive RMS in N")
    n = int(round(duration_s * fs))
    decay_s = 1.0 / np.min(system.damping_ratio * TWO_PI * system.natural_frequency_hz) \
        if np.all(system.damping_ratio > 0) else 0.0
    warmup = int(np.ceil(5 * decay_s * fs))
    force = rng.standard_normal(n)
    if band_hz is not None:
        low, high = (float(v) for v in band_hz)
        if not (0 <= low < high <= fs / 2):
            raise ParameterError(f"'band_hz' is {band_hz!r}; expected 0 <= low < high <= {fs / 2:g} Hz")
        spectrum = np.fft.rfft(force)
        f = np.fft.rfftfreq(n, 1.0 / fs)
        spectrum[(f < low) | (f > high)] = 0.0
        force = np.fft.irfft(spectrum, n)
    force *= force_rms_n / np.sqrt(np.mean(force**2))
    # the warm-up repeats the record's force (taken as periodic), so the record's spectrum is the band's alone
    force = force[np.arange(-warmup, n) % n]
    response = system.respond(force, quantity)[:, warmup:]
    record, clipped = _finish(system, force[warmup:], response, quantity, rng=rng, force_noise=force_noise,
                              response_noise=response_noise, noise_reference="rms", full_scale=full_scale,
                              declare_full_scale=declare_full_scale, names=names, source=source)
    return SyntheticRecord(record, system, quantity, (), (), clipped)
