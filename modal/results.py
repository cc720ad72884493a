"""Result dataclasses of identification and the physical parameters k, c, m.

One :class:`ModeResult` per mode. For a multi-channel FRF the pole
(``natural_frequency_hz``, ``damping_ratio``) is shared by all channels and is a
float; the modal constant, k, c and m are arrays over channels.
"""
from __future__ import annotations

from dataclasses import dataclass, field, fields
from typing import Any, Iterator

import numpy as np

from .flags import channel_flags, serious_flags
from .units import TWO_PI

__all__ = ["ModeStd", "ModeResult", "IdentificationResult", "physical_parameters", "physical_covariance", "correlation_of"]

@dataclass(frozen=True)
class ModeStd:
    """Standard errors (one sigma) under the same names as :class:`ModeResult`.

    ``modal_constant`` is the standard error of the complex value,
    sqrt(var Re + var Im). NaN where a quantity is not defined (then the
    result says why in its flags).
    """

    natural_frequency_hz: float
    damping_ratio: float
    modal_constant: np.ndarray | float
    stiffness_n_per_m: np.ndarray | float
    damping_n_s_per_m: np.ndarray | float
    mass_kg: np.ndarray | float
    #: operational modes: standard error of each entry of ``mode_shape``, sqrt(var Re + var Im)
    mode_shape: np.ndarray | None = None


@dataclass(frozen=True)
class ModeResult:
    """One identified mode.

    Attributes
    ----------
    natural_frequency_hz : float
        Undamped natural frequency, Hz.
    damping_ratio : float
        Viscous damping ratio ζ (dimensionless).
    modal_constant : complex or ndarray of complex
        Receptance modal constant A (1/kg) per channel, whatever the FRF kind:
        ``H_receptance ≈ A / (ωn² − ω² + 2iζωnω)``.
    stiffness_n_per_m, damping_n_s_per_m, mass_kg : float or ndarray
        k = m ωn², c = 2 ζ m ωn, m = 1/|A| for driving-point channels; NaN
        for transfer channels (flag ``not_driving_point``).
    std : ModeStd
        Standard errors of all the above.
    flags : tuple of str
        Quality flags; see :data:`modal.flags.FLAG_TEXT`. Empty when the estimate is sound.
    method : str
        ``"nls"``, ``"circle"`` or ``"halfpower"``.
    band_hz : tuple of float
        Frequency band (Hz) the mode was fitted on.
    n_lines : int
        Lines in the band.
    lines_per_bandwidth : float
        Lines per half-power bandwidth 2ζfn (resolution; < 3 is coarse).
    chi2 : float
        Residual variance over the noise variance (≈ 1 when the model explains
        the data; NaN when not computed). The noise is estimated without the
        model: each line against the straight line through its neighbours, on
        the raw data and on the residual, the smaller of the two
        (:func:`modal.sdof.checks.residual_noise_std`). The median over the channels
        (for ``"nls"`` with more than 128 channels, over a fixed random sample
        of 128: :func:`modal.peaks.channel_sample`).
    driving_point : bool or ndarray of bool
        Per channel: whether k, c, m are defined.
    quality : float
        Method-specific quality measure (circle: relative spread of the
        damping-pair estimates; NLS: chi2; half-power: lines above −3 dB).
    window_damping_ratio : float
        Damping ratio an exponential window had added to the measured FRF and
        that was removed from ``damping_ratio`` (0 without such a window).
    mode_shape : ndarray of complex or None
        Method ``"global"``: the modal constants normalised per reference (each
        channel divided by the largest-magnitude constant among the channels of
        its reference), in the order of the FRF's channels.
    participation : ndarray of complex or None
        Method ``"global"``: the modal participation vector (one entry per
        reference, unit norm) from the pLSCF denominator.
    mpc : float
        Modal phase collinearity (Pappa) of the modal constants, per reference
        and averaged: 1 for a real (normal) mode, lower for a complex one. NaN
        where not computed.
    kcm_correlation : ndarray or None
        Correlation matrix of the errors of (k, c, m) per channel, shape (3, 3)
        for a single channel, (n_channels, 3, 3) otherwise. The three share ωn,
        ζ and the modal constant and are strongly correlated: carry the whole
        covariance (:attr:`kcm_covariance`) into anything computed from more
        than one of them. NaN for transfer channels; None where not computed.
        (A correlation, not a covariance, so that it holds at any scale of the
        data: k² of an FRF near 1e-300 overflows.)
    """

    natural_frequency_hz: float
    damping_ratio: float
    modal_constant: np.ndarray | complex
    stiffness_n_per_m: np.ndarray | float
    damping_n_s_per_m: np.ndarray | float
    mass_kg: np.ndarray | float
    std: ModeStd
    flags: tuple[str, ...] = ()
    method: str = ""
    band_hz: tuple[float, float] = (float("nan"), float("nan"))
    n_lines: int = 0
    lines_per_bandwidth: float = float("nan")
    chi2: float = float("nan")
    driving_point: np.ndarray | bool = True
    quality: float = float("nan")
    window_damping_ratio: float = 0.0
    mode_shape: np.ndarray | None = None
    participation: np.ndarray | None = None
    mpc: float = float("nan")
    kcm_correlation: np.ndarray | None = None

    def archive_units(self) -> dict[str, str]:
        """Units of the fields whose names do not say them (for :mod:`modal.archive`)."""
        return {"kcm_correlation": "1"}

    @property
    def kcm_covariance(self) -> np.ndarray | None:
        """Covariance of (k [N/m], c [N s/m], m [kg]) per channel: the standard errors in
        ``std`` with :attr:`kcm_correlation`; shape (3, 3) or (n_channels, 3, 3); None where
        the correlation was not computed."""
        if self.kcm_correlation is None:
            return None
        sd = np.stack([np.asarray(self.std.stiffness_n_per_m, float), np.asarray(self.std.damping_n_s_per_m, float),
                       np.asarray(self.std.mass_kg, float)], axis=-1)
        return sd[..., :, None] * np.asarray(self.kcm_correlation, float) * sd[..., None, :]

    @property
    def omega_n_rad_s(self) -> float:
        """Natural frequency in rad/s."""
        return self.natural_frequency_hz * TWO_PI

    @property
    def ok(self) -> bool:
        """True when the estimate carries no flag other than informational ones."""
        return not serious_flags(self.flags)


@dataclass(frozen=True)
class IdentificationResult:
    """All modes identified from one FRF by one method.

    Iterating gives the :class:`ModeResult` objects in order of frequency.
    """

    modes: tuple[ModeResult, ...]
    method: str
    kind: str
    n_channels: int
    noise_std: np.ndarray = field(default_factory=lambda: np.zeros(0))
    residuals: np.ndarray | None = None
    stabilisation: Any = None
    settings: dict = field(default_factory=dict)
    #: operational analysis: frequencies (Hz) of the machine tones found, listed apart from the modes
    harmonics_hz: tuple[float, ...] = ()

    def archive_units(self) -> dict[str, str]:
        """Units of the fields whose names do not say them (for :mod:`modal.archive`)."""
        from .frf_units import result_units

        units = result_units(self.kind, self.settings)
        constant = {"modal_constant": units["modal_constant"]}
        return {"noise_std": units["noise_std"], "n_channels": "1",
                "residuals": f"{units['upper_residual']} (column 0: upper residual), {units['lower_residual']} "
                             "(column 1: lower residual)",
                "modes": {**constant, "std": constant}}  # the modes' constants are in the FRF's unit, as the result

    def synthesize(self, frequency_hz) -> "FRF":
        """The identified model (modes, plus residual terms where fitted) as an FRF on any axis.

        Parameters
        ----------
        frequency_hz : array_like
            Lines, Hz (>= 0), for example the fitted FRF's own axis with its 0 Hz line.

        Returns
        -------
        FRF
            Of this result's kind, one channel per channel of the fitted FRF. On a 0 Hz line the
            model's limit: the lower residual (mass line, ``-L/omega**2`` in receptance) of an accelerance
            tends to ``L`` there.

        Raises
        ------
        ParameterError
            A negative or non-finite line, or a 0 Hz line where the model has no finite limit: the
            mass line of a receptance or mobility grows without bound towards 0 Hz.
        """
        from .errors import ParameterError
        from .frf import FRF, KIND_POWER
        from .model import mode_basis

        freq = np.asarray(frequency_hz, float)
        if not np.all(np.isfinite(freq)) or np.any(freq < 0):
            raise ParameterError("synthesize: 'frequency_hz' holds a negative or non-finite line; expected lines "
                                 ">= 0 Hz")
        omega = freq * TWO_PI
        power = KIND_POWER[self.kind]
        total = np.zeros((self.n_channels, freq.size), complex)
        for mode in self.modes:
            phi = mode_basis(omega, mode.omega_n_rad_s, mode.damping_ratio, power)[0]
            const = np.nan_to_num(np.atleast_1d(np.asarray(mode.modal_constant, complex)))
            total += const[:, None] * phi[None, :]
        if self.residuals is not None:
            upper, lower = np.asarray(self.residuals, complex).T
            # (i omega)**p / omega**2 = i**p omega**(p - 2): for an accelerance (p = 2) the constant -1 on
            # every line, 0 Hz included; below p = 2 it has no finite value at 0 Hz
            mass_line = np.zeros(freq.size, complex)
            positive = omega > 0
            mass_line[positive] = 1j**power * omega[positive] ** (power - 2)
            if power == 2:
                mass_line[~positive] = -1.0
            elif (~positive).any() and np.any(lower != 0):
                raise ParameterError(f"synthesize: the {self.kind} model's lower residual (mass line) has no finite "
                                     "value at 0 Hz; expected lines above 0 Hz (frequency_hz[frequency_hz > 0])")
            total += upper[:, None] * ((1j * omega) ** power)[None, :] - lower[:, None] * mass_line[None, :]
        return FRF(freq, total[0] if self.n_channels == 1 else total, kind=self.kind,
                   source=f"synthesised ({self.method})")

    def mac(self) -> np.ndarray:
        """MAC matrix of the modes' modal constants over the channels, shape (n_modes, n_modes)."""
        shapes = np.array([np.atleast_1d(np.asarray(m.modal_constant, complex)) for m in self.modes])
        shapes = np.nan_to_num(shapes)
        num = np.abs(shapes.conj() @ shapes.T) ** 2
        norms = np.sum(np.abs(shapes) ** 2, axis=1)
        den = np.outer(norms, norms)
        return num / np.where(den > 0, den, np.inf)

    def __iter__(self) -> Iterator[ModeResult]:
        return iter(self.modes)

    def __len__(self) -> int:
        return len(self.modes)

    def __getitem__(self, index: int) -> ModeResult:
        return self.modes[index]

    def rows(self) -> list[dict]:
        """One plain dict per mode and channel (JSON-ready; keys as the fields)."""
        out = []
        names = ("modal_constant", "stiffness_n_per_m", "damping_n_s_per_m", "mass_kg")
        for number, mode in enumerate(self.modes, start=1):
            for ch in range(self.n_channels):
                def pick(value, ch=ch):
                    arr = np.asarray(value)
                    return arr.reshape(-1)[ch] if arr.ndim else arr[()]

                row = {
                    "mode": number,
                    "channel": ch,
                    "method": mode.method,
                    "natural_frequency_hz": float(mode.natural_frequency_hz),
                    "damping_ratio": float(mode.damping_ratio),
                }
                for name in names:
                    row[name] = complex(pick(getattr(mode, name))) if name == "modal_constant" else float(pick(getattr(mode, name)))
                row["std"] = {f.name: float(pick(getattr(mode.std, f.name))) for f in fields(ModeStd)
                              if getattr(mode.std, f.name) is not None}
                row["driving_point"] = bool(pick(mode.driving_point))
                # only those that apply here
                row["flags"] = channel_flags(mode.flags, row["driving_point"], np.isfinite(row["stiffness_n_per_m"]))
                row["band_hz"] = [float(b) for b in mode.band_hz]
                row["chi2"] = float(mode.chi2)
                row["window_damping_ratio"] = float(mode.window_damping_ratio)
                out.append(row)
        return out


def _kcm(omega_n, damping_ratio, A: np.ndarray):
    """k = m ωn², c = 2 ζ m ωn, m = 1/|A| (infinite where A = 0)."""
    with np.errstate(divide="ignore", invalid="ignore"):
        m = 1.0 / np.abs(A)
        return m * omega_n**2, 2.0 * damping_ratio * m * omega_n, m


def physical_parameters(omega_n, damping_ratio, modal_constant, cov=None):
    """k, c, m and their standard errors from (ωn, ζ, A) of a driving point.

    m = 1/|A|, k = m ωn², c = 2 ζ m ωn.

    Parameters
    ----------
    omega_n : float
        Natural frequency, rad/s.
    damping_ratio : float
    modal_constant : complex or ndarray of complex
        Receptance modal constant(s), 1/kg.
    cov : ndarray, shape (..., 4, 4), optional
        Covariance of (ωn, ζ, Re A, Im A) per channel.

    Returns
    -------
    (k, c, m), (std_k, std_c, std_m) : tuples of ndarray
    """
    A = np.asarray(modal_constant, dtype=complex)
    k, c, m = _kcm(omega_n, damping_ratio, A)
    if cov is None:
        nan = np.full(A.shape, np.nan)
        return (k, c, m), (nan, nan.copy(), nan.copy())
    cov_kcm = physical_covariance(omega_n, damping_ratio, A, cov)
    with np.errstate(invalid="ignore"):
        diag = np.sqrt(np.maximum(np.diagonal(cov_kcm, axis1=-2, axis2=-1), 0.0))
    return (k, c, m), (diag[..., 0], diag[..., 1], diag[..., 2])


def correlation_of(cov: np.ndarray) -> np.ndarray:
    """Correlation matrix (..., n, n) of covariance matrices; NaN where a variance is not positive."""
    cov = np.asarray(cov, float)
    variance = np.diagonal(cov, axis1=-2, axis2=-1)
    sd = np.sqrt(np.where(variance > 0, variance, np.nan))  # not positive: NaN, as documented, without a warning
    with np.errstate(divide="ignore", invalid="ignore"):
        out = cov / (sd[..., :, None] * sd[..., None, :])
    return np.where(np.isfinite(out), np.clip(out, -1.0, 1.0), np.nan)


def physical_covariance(omega_n, damping_ratio, modal_constant, cov):
    """Covariance of (k, c, m) from that of (ωn, ζ, Re A, Im A), to first order.

    Parameters
    ----------
    omega_n : float
        Natural frequency, rad/s.
    damping_ratio : float
    modal_constant : complex or ndarray of complex
        Receptance modal constant(s) of driving points, 1/kg.
    cov : ndarray, shape (..., 4, 4)
        Covariance of (ωn [rad/s], ζ, Re A, Im A [1/kg]) per channel.

    Returns
    -------
    ndarray, shape (..., 3, 3)
        Rows and columns k (N/m), c (N s/m), m (kg).
    """
    A = np.asarray(modal_constant, dtype=complex)
    k, c, m = _kcm(omega_n, damping_ratio, A)
    with np.errstate(divide="ignore", invalid="ignore"):
        a = np.abs(A)
        da_dre, da_dim = A.real / a, A.imag / a  # ∂|A|/∂Re A, ∂|A|/∂Im A
        # gradients of (k, c, m) with respect to (ωn, ζ, Re A, Im A): (..., 3, 4)
        grad = np.zeros(A.shape + (3, 4))
        grad[..., 0, 0] = 2 * m * omega_n
        grad[..., 1, 0] = 2 * damping_ratio * m
        grad[..., 1, 1] = 2 * m * omega_n
        for row, value in enumerate((k, c, m)):
            grad[..., row, 2] = -value * m * da_dre
            grad[..., row, 3] = -value * m * da_dim
        return grad @ np.asarray(cov, float) @ np.swapaxes(grad, -1, -2)
