"""Ambient records with known modes for the operational-analysis tests and benchmark.

The anchor case: eight sensors on a machine frame with six modes, a close pair 1.9 % apart with
different shapes, one mode weakly excited, and machine tones at 1×, 2× and 3× the running speed;
white measurement noise of 5-20 % of each channel's RMS. Exactly discretised
(:func:`modal.synthetic.ambient_modal_response`), so the truth is exact.
"""
from __future__ import annotations

import numpy as np

from modal.synthetic import AmbientRecord, ambient_modal_response

#: the anchor case's modes (Hz, damping ratio); modes 3 and 4 are 1.9 % apart
FN = np.array([3.1, 7.4, 11.2, 11.4128, 17.5, 24.3])
ZETA = np.array([0.015, 0.010, 0.008, 0.012, 0.020, 0.015])
#: modal force standard deviations: mode 5 is excited 10 times less (in force) than the others
FORCE = np.array([1.0, 1.0, 1.0, 1.0, 0.1, 1.0])
#: running speed and its tones (1×, 2×, 3×)
ROTOR_HZ = 4.8
TONES = ROTOR_HZ * np.array([1.0, 2.0, 3.0])
N_SENSORS = 8


def anchor_shapes(n_sensors: int = N_SENSORS) -> np.ndarray:
    """Real shapes (n_sensors, 6): bending-like sines along the frame; the close pair gets a
    bending and a torsion-like (antisymmetric, alternating) shape, MAC between them near 0."""
    x = (np.arange(n_sensors) + 0.5) / n_sensors
    phi = np.column_stack([
        np.sin(np.pi * x),
        np.sin(2 * np.pi * x),
        np.sin(3 * np.pi * x),
        np.cos(np.pi * x) * np.where(np.arange(n_sensors) % 2 == 0, 1.0, -0.8),
        np.sin(4 * np.pi * x) + 0.3 * x,
        np.sin(5 * np.pi * x),
    ])
    return phi


def anchor_record(seed: int = 0, noise: float = 0.1, duration_s: float = 1000.0, sample_rate_hz: float = 100.0,
                  tones: bool = True, tone_rms: float = 0.5, n_sensors: int = N_SENSORS) -> AmbientRecord:
    """The anchor case's record (accelerations), ``duration_s`` long at ``sample_rate_hz``, on ``n_sensors``
    sensors along the frame."""
    return ambient_modal_response(FN, ZETA, anchor_shapes(n_sensors), sample_rate_hz, int(duration_s * sample_rate_hz),
                                  modal_force_std=FORCE, noise=noise, tones_hz=TONES if tones else None,
                                  tone_rms=tone_rms, seed=seed)


def machine_tone(n_samples: int, sample_rate_hz: float, frequency_hz: float, wander: float = 0.0,
                 seed: int = 0) -> np.ndarray:
    """A unit-amplitude machine tone, ``n_samples`` long: a sinusoid of random phase whose frequency wanders
    slowly (a random walk scaled to reach ±``wander`` of ``frequency_hz``, as a running machine's speed drifts),
    or is constant (``wander`` = 0)."""
    rng = np.random.default_rng(seed)
    drift = np.cumsum(rng.standard_normal(n_samples))
    drift = drift - drift.mean()
    drift /= max(np.abs(drift).max(), 1e-300)
    phase = 2 * np.pi * np.cumsum(frequency_hz * (1.0 + wander * drift)) / sample_rate_hz
    return np.sin(phase + rng.uniform(0.0, 2 * np.pi))


#: the lone-tone case: four modes on six sensors at 400 Hz, with room for a tone between modes far from any,
#: at a mains frequency and above the highest mode
LONE_FN = np.array([12.0, 31.0, 78.0, 117.0])
LONE_ZETA = np.array([0.015, 0.01, 0.012, 0.02])


def lone_tone_record(tone_hz: float, wander: float, seed: int, duration_s: float = 100.0):
    """(signals, sample rate Hz): the lone-tone case's random response (10 % noise) with a machine tone
    (:func:`machine_tone`) of RMS 0.25-0.5 of each channel's."""
    fs = 400.0
    n = int(duration_s * fs)
    x = (np.arange(6) + 0.5) / 6
    shapes = np.column_stack([np.sin(np.pi * x), np.sin(2 * np.pi * x), np.sin(3 * np.pi * x),
                              np.sin(4 * np.pi * x) + 0.2 * x])
    rec = ambient_modal_response(LONE_FN, LONE_ZETA, shapes, fs, n, noise=0.1, seed=seed)
    size = np.random.default_rng(seed).uniform(0.5, 1.0, 6) * rec.signals.std(axis=1) / np.sqrt(2)
    return rec.signals + size[:, None] * machine_tone(n, fs, tone_hz, wander, seed)[None, :], fs
