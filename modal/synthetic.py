"""Synthetic FRFs with known truth: from modal parameters or from M, C, K.

Used by the tests, the benchmarks and the demo. Noise is seeded circular
complex Gaussian, either relative to max |H| of each channel or per line.
"""
from __future__ import annotations

import numpy as np

from .errors import ParameterError
from .frf import FRF, kind_factor
from .units import TWO_PI
from .validate import non_negative, one_of, positive, system_matrices

__all__ = ["modal_frf", "matrix_frf", "add_noise", "sdof_frf", "frequency_axis"]


def frequency_axis(f_low_hz: float, f_high_hz: float, n_lines: int) -> np.ndarray:
    """Evenly spaced frequency lines in Hz (``n_lines`` of them, both ends included)."""
    if not (np.isfinite(f_low_hz) and np.isfinite(f_high_hz) and 0 <= f_low_hz < f_high_hz):
        raise ParameterError(f"frequency range must satisfy 0 <= f_low < f_high, got {f_low_hz}, {f_high_hz}")
    if int(n_lines) < 2:
        raise ParameterError(f"'n_lines' must be >= 2, got {n_lines}")
    return np.linspace(f_low_hz, f_high_hz, int(n_lines))


def modal_frf(
    frequency_hz,
    natural_frequency_hz,
    damping_ratio,
    modal_constant,
    kind: str = "receptance",
    lower_residual=0.0,
    upper_residual=0.0,
    response_points=None,
    reference_points=None,
) -> FRF:
    """FRF of a viscously damped system from its modal parameters.

    ``H(ω) = (iω)**p [ Σ_r A_r / (ω_r² − ω² + 2iζ_r ω_r ω) + U − L/ω² ]``
    with p = 0, 1, 2 for receptance, mobility, accelerance.

    Parameters
    ----------
    frequency_hz : array_like, shape (n_freq,)
        Frequency lines, Hz.
    natural_frequency_hz, damping_ratio : array_like, shape (n_modes,)
        Undamped natural frequencies (Hz) and viscous damping ratios.
    modal_constant : array_like, shape (n_modes,) or (n_channels, n_modes)
        Receptance modal constants A_r, 1/kg (complex allowed). For a driving
        point of an SDOF system A = 1/m.
    kind : {"receptance", "mobility", "accelerance"}
    lower_residual, upper_residual : complex or array_like over channels
        Receptance residual terms: upper U (m/N, stiffness line), lower L (1/kg,
        mass line).
    response_points, reference_points : sequence of str, optional
        Point ids per channel; a channel whose two ids are equal is a driving point. Without them
        :func:`modal.identify` gives no k, c, m unless told which channel is a driving point.
    """
    freq = np.asarray(frequency_hz, dtype=float)
    fn = positive("natural_frequency_hz", natural_frequency_hz)
    zeta = np.atleast_1d(np.asarray(damping_ratio, dtype=float))
    if zeta.shape != fn.shape or np.any(zeta < 0) or not np.all(np.isfinite(zeta)):
        raise ParameterError(f"'damping_ratio' must be finite, >= 0 and one per mode, got {damping_ratio!r}")
    const = np.asarray(modal_constant, dtype=complex)
    single = const.ndim <= 1
    const = np.atleast_2d(const)
    if const.shape[1] != fn.size:
        raise ParameterError(f"'modal_constant' must have one value per mode ({fn.size}), got shape {const.shape}")
    omega = freq * TWO_PI
    wn = fn * TWO_PI
    denom = wn[:, None] ** 2 - omega[None, :] ** 2 + 2j * zeta[:, None] * wn[:, None] * omega[None, :]
    receptance = const @ (1.0 / denom)
    upper = np.atleast_1d(np.asarray(upper_residual, dtype=complex))[:, None]
    lower = np.atleast_1d(np.asarray(lower_residual, dtype=complex))[:, None]
    if np.any(lower != 0):
        with np.errstate(divide="ignore"):
            receptance = receptance - lower / omega[None, :] ** 2
    receptance = receptance + upper
    response = receptance * kind_factor(omega, kind)[None, :]
    return FRF(
        freq,
        response[0] if single else response,
        kind=kind,
        response_points=response_points,
        reference_points=reference_points,
        source="<synthetic>",
    )


def sdof_frf(frequency_hz, mass_kg: float, stiffness_n_per_m: float, damping_n_s_per_m: float,
             kind: str = "receptance") -> FRF:
    """Driving-point FRF of a single mass–spring–damper, ``1/(k − mω² + icω)`` times (iω)**p.

    Its point ids say so (response and reference point ``"1"``), so that :func:`modal.identify`
    gives k, c, m.
    """
    m = positive("mass_kg", mass_kg)[0]
    k = positive("stiffness_n_per_m", stiffness_n_per_m)[0]
    c = float(non_negative("damping_n_s_per_m", damping_n_s_per_m)[0])
    omega = np.asarray(frequency_hz, dtype=float) * TWO_PI
    h = 1.0 / (k - m * omega**2 + 1j * c * omega) * kind_factor(omega, kind)
    return FRF(frequency_hz, h, kind=kind, response_points=["1"], reference_points=["1"], source="<synthetic>")


def matrix_frf(frequency_hz, mass, damping, stiffness, response_dofs=None, reference_dof: int = 0,
               kind: str = "receptance") -> FRF:
    """FRFs of ``M ẍ + C ẋ + K x = f`` by direct solution at every line (any damping).

    Parameters
    ----------
    frequency_hz : array_like, shape (n_freq,)
    mass, damping, stiffness : array_like, shape (n_dof, n_dof)
        M (kg), C (N s/m), K (N/m). M symmetric positive definite.
    response_dofs : sequence of int, optional
        Degrees of freedom observed (default: all), one channel each.
    reference_dof : int
        Degree of freedom excited.
    kind : {"receptance", "mobility", "accelerance"}

    Returns
    -------
    FRF
        Channels in ``response_dofs`` order; point ids are the dof indices.
    """
    M, C, K = system_matrices(mass, damping, stiffness)
    n = M.shape[0]
    if not 0 <= reference_dof < n:
        raise ParameterError(f"'reference_dof' must be in [0, {n}), got {reference_dof}")
    dofs = list(range(n)) if response_dofs is None else [int(d) for d in response_dofs]
    if any(not 0 <= d < n for d in dofs):
        raise ParameterError(f"'response_dofs' must lie in [0, {n}), got {dofs}")
    omega = np.asarray(frequency_hz, dtype=float) * TWO_PI
    dyn = K[None] - omega[:, None, None] ** 2 * M[None] + 1j * omega[:, None, None] * C[None]
    rhs = np.zeros((omega.size, n, 1), dtype=complex)
    rhs[:, reference_dof, 0] = 1.0
    x = np.linalg.solve(dyn, rhs)[:, :, 0]  # (n_freq, n_dof)
    response = (x[:, dofs] * kind_factor(omega, kind)[:, None]).T
    return FRF(frequency_hz, response, kind=kind,
               response_points=[str(d) for d in dofs], reference_points=[str(reference_dof)] * len(dofs),
               source="<synthetic>")


def modal_parameters_of_matrices(mass, damping, stiffness):
    """Poles of ``M, C, K`` (rad/s): natural frequencies ``|λ|`` and damping ratios ``−Re λ/|λ|``.

    Returns the modes sorted by natural frequency, one per conjugate pair.
    """
    M, C, K = (np.atleast_2d(np.asarray(a, dtype=float)) for a in (mass, damping, stiffness))
    n = M.shape[0]
    A = np.block([[np.zeros((n, n)), np.eye(n)], [-np.linalg.solve(M, K), -np.linalg.solve(M, C)]])
    lam = np.linalg.eigvals(A)
    lam = lam[lam.imag > 0]
    lam = lam[np.argsort(np.abs(lam))]
    return np.abs(lam), -lam.real / np.abs(lam)


def add_noise(frf: FRF, level: float, seed: int | np.random.Generator | None = 0,
              relative_to: str = "max") -> FRF:
    """Add circular complex Gaussian noise.

    Parameters
    ----------
    level : float
        Standard deviation of the complex noise (E|n|² = σ²) as a fraction of
        max |H| of each channel (``relative_to="max"``) or of |H| at each line
        (``relative_to="line"``).
    seed : int or Generator
        Seed for reproducible noise.
    """
    non_negative("level", level)
    one_of("relative_to", relative_to, ("max", "line"))
    rng = np.random.default_rng(seed)
    h = frf.channels
    scale = np.abs(h).max(axis=1, keepdims=True) if relative_to == "max" else np.abs(h)
    noise = (rng.standard_normal(h.shape) + 1j * rng.standard_normal(h.shape)) * np.sqrt(0.5)
    noisy = h + level * scale * noise
    from dataclasses import replace

    return replace(frf, response=noisy[0] if frf.n_channels == 1 and frf.response.ndim == 1 else noisy)


# ------------------------------------------------------------ time records (impact and random excitation)
from .synthetic_time import (  # noqa: E402
    DigitalModes, SyntheticRecord, hammer_force, impact_record, random_record,
)

__all__ += ["DigitalModes", "SyntheticRecord", "hammer_force", "impact_record", "random_record"]

# ------------------------------------------------------------ ambient (output-only) records
from .synthetic_ambient import (  # noqa: E402
    AmbientRecord, ambient_modal_response, ambient_response, chain_matrices,
)

__all__ += ["AmbientRecord", "ambient_response", "ambient_modal_response", "chain_matrices"]
