"""Synthetic ambient (output-only) records whose modes are known exactly.

White random forces, held over each sample, drive an ``M, C, K`` model
(:func:`ambient_response`) or a modal model (:func:`ambient_modal_response`). The
sampled system is the exact zero-order-hold discretisation, so its poles are exactly
``exp(λT)`` of the continuous ones and an identification of the record has no model
error; the record starts in the stationary state. Machine tones and white
measurement noise are added per channel. :func:`chain_matrices` builds chains of
masses for mass-change tests.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .errors import ParameterError
from .units import TWO_PI
from .validate import positive, system_matrices

__all__ = ["AmbientRecord", "ambient_response", "ambient_modal_response", "chain_matrices"]


@dataclass(frozen=True)
class AmbientRecord:
    """An output-only record whose modes are known exactly.

    Attributes
    ----------
    signals : ndarray, shape (n_channels, n_samples)
        Responses (m, m/s or m/s² as ``quantity`` says), measurement noise and tones included.
    sample_rate_hz : float
    natural_frequency_hz, damping_ratio : ndarray, shape (n_modes,)
        The system's poles, sorted by frequency: the sampled system's poles are exactly
        ``exp(λ T)`` of these continuous ones.
    mode_shape : ndarray, shape (n_channels, n_modes), complex
        Observed shape of each mode (displacement shape at the output channels), its
        largest-magnitude entry scaled to 1.
    tone_frequency_hz : ndarray
        Frequencies of the sinusoids added to every channel (machine tones), Hz.
    quantity : str
        ``"displacement"``, ``"velocity"`` or ``"acceleration"``.
    """

    signals: np.ndarray
    sample_rate_hz: float
    natural_frequency_hz: np.ndarray
    damping_ratio: np.ndarray
    mode_shape: np.ndarray
    tone_frequency_hz: np.ndarray
    quantity: str


def _ambient_state_space(A, B, C, D, sample_rate_hz, n_samples, force_std, rng):
    """Outputs of ``ẋ = A x + B u, y = C x + D u`` driven by white forces held over each sample (zero-order hold),
    started from the stationary state distribution. Exact: the sampled modes evolve by ``exp(λ T)``.

    Returns ``(y, eigenvalues λ, eigenvectors V)``.
    """
    from scipy.signal import lfilter

    T = 1.0 / sample_rate_hz
    lam, V = np.linalg.eig(A)
    Vinv = np.linalg.inv(V)
    mu = np.exp(lam * T)
    with np.errstate(divide="ignore", invalid="ignore"):
        hold = np.where(np.abs(lam) > 0, (mu - 1.0) / lam, T)  # ∫₀ᵀ e^{λτ} dτ
    G = hold[:, None] * (Vinv @ B)  # modal input gains (n_state, n_inputs)
    std = np.broadcast_to(np.asarray(force_std, float), (B.shape[1],))
    # stationary covariance of the modal states, P_ij = (G Q Gᴴ)_ij / (1 − μ_i μ_j*), drawn in real coordinates
    P = (G * std**2) @ G.conj().T / (1.0 - mu[:, None] * mu.conj()[None, :])
    Px = np.real(V @ P @ V.conj().T)
    w, E = np.linalg.eigh(0.5 * (Px + Px.T))
    z0 = Vinv @ (E @ (np.sqrt(np.maximum(w, 0.0)) * rng.standard_normal(w.size)))
    u = rng.standard_normal((B.shape[1], n_samples)) * std[:, None]
    drive = G @ u  # (n_state, n_samples)
    steps = np.arange(n_samples)
    y = np.real(D @ u).astype(float)
    CV = C @ V
    for i in range(lam.size):
        if lam[i].imag < 0:
            continue  # the conjugate of a mode with Im λ > 0: its share is the conjugate, counted twice below
        # z[k+1] = μ z[k] + drive[k], z[0] = z0
        z = lfilter([0.0, 1.0], [1.0, -mu[i]], drive[i]) + z0[i] * np.exp(lam[i] * T * steps)
        y += (1.0 if lam[i].imag == 0 else 2.0) * np.real(np.outer(CV[:, i], z))
    return y, lam, V


def _measurement(y, rng, noise, tones_hz, tone_rms, sample_rate_hz):
    """Tones (each channel its own amplitude and phase) and white measurement noise on ``y``."""
    tones = np.atleast_1d(np.asarray(tones_hz if tones_hz is not None else [], float))
    if tones.size and (not np.all(np.isfinite(tones)) or np.any(tones <= 0) or np.any(tones >= sample_rate_hz / 2)):
        raise ParameterError(f"'tones_hz' must lie in (0, {sample_rate_hz / 2}) Hz, got {tones_hz!r}")
    if not np.isfinite(noise) or noise < 0:
        raise ParameterError(f"'noise' must be finite and >= 0, got {noise!r}")
    levels = np.broadcast_to(np.asarray(tone_rms, float), tones.shape)
    rms = np.sqrt(np.mean(y**2, axis=1))
    t = np.arange(y.shape[1]) / sample_rate_hz
    for f, level in zip(tones, levels):
        amplitude = np.sqrt(2.0) * level * rms * rng.uniform(0.5, 1.0, y.shape[0])
        phase = rng.uniform(0, 2 * np.pi, y.shape[0])
        y = y + amplitude[:, None] * np.sin(2 * np.pi * f * t[None, :] + phase[:, None])
    return y + noise * np.sqrt(np.mean(y**2, axis=1))[:, None] * rng.standard_normal(y.shape), tones


def _observed_shapes(S, lam, V, n_dof):
    """Displacement shapes S ψ of the modes with Im λ > 0, sorted by |λ|, largest entry 1."""
    keep = np.flatnonzero(lam.imag > 0)
    keep = keep[np.argsort(np.abs(lam[keep]))]
    shapes = S @ V[:n_dof, keep]
    lead = shapes[np.argmax(np.abs(shapes), axis=0), np.arange(keep.size)]
    return lam[keep], shapes / lead[None, :]


def _output_matrices(Minv_K, Minv_C, S, Minv_E, quantity):
    """Output matrices (C, D) of displacement, velocity or acceleration at the observed dofs S."""
    n = Minv_K.shape[0]
    zero = np.zeros((S.shape[0], n))
    no_feed = np.zeros((S.shape[0], Minv_E.shape[1]))
    if quantity == "displacement":
        return np.hstack([S, zero]), no_feed
    if quantity == "velocity":
        return np.hstack([zero, S]), no_feed
    if quantity == "acceleration":
        return -S @ np.hstack([Minv_K, Minv_C]), S @ Minv_E
    raise ParameterError(f"'quantity' must be 'displacement', 'velocity' or 'acceleration', got {quantity!r}")


def _record(A, B, Cout, D, S, n_dof, sample_rate_hz, n_samples, force_std, quantity, noise, tones_hz, tone_rms,
            seed) -> AmbientRecord:
    fs = float(positive("sample_rate_hz", sample_rate_hz)[0])
    if int(n_samples) < 2:
        raise ParameterError(f"'n_samples' must be >= 2, got {n_samples}")
    rng = np.random.default_rng(seed)
    y, lam, V = _ambient_state_space(A, B, Cout, D, fs, int(n_samples), force_std, rng)
    y, tones = _measurement(y, rng, noise, tones_hz, tone_rms, fs)
    poles, shapes = _observed_shapes(S, lam, V, n_dof)
    return AmbientRecord(y, fs, np.abs(poles) / TWO_PI, -poles.real / np.abs(poles), shapes, tones, quantity)


def ambient_response(mass, damping, stiffness, sample_rate_hz: float, n_samples: int, *, output_dofs=None,
                     force_dofs=None, force_std_n=1.0, quantity: str = "acceleration", noise: float = 0.1,
                     tones_hz=None, tone_rms=1.0, seed: int | np.random.Generator | None = 0) -> AmbientRecord:
    """Ambient response of ``M ẍ + C ẋ + K x = f`` to white random forces, sampled exactly.

    The forces are independent white Gaussian sequences held over each sample, so the sampled
    system is the exact zero-order-hold discretisation: its poles are ``exp(λ T)`` of the
    continuous poles λ, and an identification of the record has no model error. The record
    starts in the stationary state (no transient).

    Parameters
    ----------
    mass, damping, stiffness : array_like, shape (n_dof, n_dof)
        M (kg, symmetric positive definite), C (N s/m), K (N/m).
    sample_rate_hz : float
    n_samples : int
    output_dofs : sequence of int, optional
        Degrees of freedom observed, one channel each (default all).
    force_dofs : sequence of int, optional
        Degrees of freedom loaded by independent random forces (default all).
    force_std_n : float or array_like over ``force_dofs``
        Standard deviation of each force, N.
    quantity : {"displacement", "velocity", "acceleration"}
    noise : float
        Measurement noise: white, standard deviation this fraction of each channel's RMS.
    tones_hz : sequence of float, optional
        Sinusoids added to every channel (machine tones), each with RMS ``tone_rms`` times the
        channel's response RMS (times a random factor in [0.5, 1] per channel) and a random phase.
    tone_rms : float or array_like over ``tones_hz``
    seed : int or Generator

    Returns
    -------
    AmbientRecord
    """
    M, C, K = system_matrices(mass, damping, stiffness)
    n = M.shape[0]
    outs = list(range(n)) if output_dofs is None else [int(d) for d in output_dofs]
    ins = list(range(n)) if force_dofs is None else [int(d) for d in force_dofs]
    if not outs or not ins or any(not 0 <= d < n for d in outs + ins):
        raise ParameterError(f"'output_dofs' and 'force_dofs' must be non-empty and lie in [0, {n}), got {outs}, {ins}")
    S = np.eye(n)[outs]
    Minv_K, Minv_C, Minv_E = np.linalg.solve(M, K), np.linalg.solve(M, C), np.linalg.solve(M, np.eye(n)[:, ins])
    A = np.block([[np.zeros((n, n)), np.eye(n)], [-Minv_K, -Minv_C]])
    B = np.vstack([np.zeros((n, len(ins))), Minv_E])
    Cout, D = _output_matrices(Minv_K, Minv_C, S, Minv_E, quantity)
    return _record(A, B, Cout, D, S, n, sample_rate_hz, n_samples, force_std_n, quantity, noise, tones_hz, tone_rms,
                   seed)


def ambient_modal_response(natural_frequency_hz, damping_ratio, mode_shape, sample_rate_hz: float, n_samples: int,
                           *, modal_force_std=1.0, quantity: str = "acceleration", noise: float = 0.1,
                           tones_hz=None, tone_rms=1.0,
                           seed: int | np.random.Generator | None = 0) -> AmbientRecord:
    """Ambient response of a modal model: each mode an SDOF of unit modal mass driven by its own white force.

    ``q̈_r + 2 ζ_r ω_r q̇_r + ω_r² q_r = f_r``, ``y = Φ q`` (or its derivatives), sampled exactly as
    :func:`ambient_response` does. Independent modal forces of different size give weakly and
    strongly excited modes; any number of channels per mode.

    Parameters
    ----------
    natural_frequency_hz, damping_ratio : array_like, shape (n_modes,)
    mode_shape : array_like, shape (n_channels, n_modes)
        Real shapes Φ (the observed displacement per unit modal coordinate).
    sample_rate_hz : float
    n_samples : int
    modal_force_std : float or array_like over the modes
        Standard deviation of each modal force (N per unit modal mass).
    quantity, noise, tones_hz, tone_rms, seed
        As for :func:`ambient_response`.
    """
    fn = positive("natural_frequency_hz", natural_frequency_hz)
    zeta = np.atleast_1d(np.asarray(damping_ratio, float))
    if zeta.shape != fn.shape or not np.all(np.isfinite(zeta)) or np.any(zeta <= 0) or np.any(zeta >= 1):
        raise ParameterError(f"'damping_ratio' must lie in (0, 1), one per mode, got {damping_ratio!r}")
    phi = np.atleast_2d(np.asarray(mode_shape, float))
    if phi.shape[1] != fn.size or not np.all(np.isfinite(phi)):
        raise ParameterError(f"'mode_shape' must be finite, (n_channels, {fn.size}), got shape {phi.shape}")
    wn = fn * TWO_PI
    n = fn.size
    Minv_K, Minv_C = np.diag(wn**2), np.diag(2 * zeta * wn)
    A = np.block([[np.zeros((n, n)), np.eye(n)], [-Minv_K, -Minv_C]])
    B = np.vstack([np.zeros((n, n)), np.eye(n)])
    Cout, D = _output_matrices(Minv_K, Minv_C, phi, np.eye(n), quantity)
    return _record(A, B, Cout, D, phi, n, sample_rate_hz, n_samples, modal_force_std, quantity, noise, tones_hz,
                   tone_rms, seed)


def chain_matrices(masses_kg, stiffnesses_n_per_m, damping_ratio: float | None = None, *, alpha_per_s: float = 0.0,
                   beta_s: float = 0.0):
    """M, C, K of a chain of masses joined by springs, the first spring to the ground.

    Parameters
    ----------
    masses_kg : array_like, shape (n,)
    stiffnesses_n_per_m : array_like, shape (n,)
        Spring i joins mass i−1 (the ground for i = 0) to mass i.
    damping_ratio : float, optional
        Modal damping, the same ratio for every mode: C = M Φ diag(2 ζ ω) Φᵀ M with Φ the
        mass-normalised undamped shapes.
    alpha_per_s, beta_s : float
        Rayleigh damping C = α M + β K (used when ``damping_ratio`` is None).

    Returns
    -------
    (M, C, K) : ndarrays, shape (n, n)
    """
    m = positive("masses_kg", masses_kg)
    k = positive("stiffnesses_n_per_m", stiffnesses_n_per_m)
    if m.shape != k.shape:
        raise ParameterError(f"one spring per mass expected, got {m.size} masses and {k.size} springs")
    K = np.diag(k + np.append(k[1:], 0.0)) - np.diag(k[1:], 1) - np.diag(k[1:], -1)
    M = np.diag(m)
    if damping_ratio is None:
        C = alpha_per_s * M + beta_s * K
    else:
        from scipy.linalg import eigh

        w2, phi = eigh(K, M)
        C = M @ phi @ np.diag(2 * float(damping_ratio) * np.sqrt(w2)) @ phi.T @ M
    return M, C, K
