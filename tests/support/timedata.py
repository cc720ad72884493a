"""Synthetic time data with an exactly known FRF, for the estimator tests.

Each mode is a digital resonator made by impulse invariance: its discrete
impulse response samples the continuous one, T·2·Re(R e^{p n T}), so the
digital system's poles are exactly e^{pT} (the continuous poles p = −ζωn ± iωd),
and its frequency response at any line is known in closed form
(:func:`DigitalModes.frf`). Filtering a force with :func:`scipy.signal.lfilter`
gives the response; comparing an estimate with :meth:`DigitalModes.frf` has no
model error at all.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import signal


@dataclass(frozen=True)
class DigitalModes:
    """Modes (Hz, ζ) and receptance modal constants (1/kg) per output, sampled at ``fs`` Hz."""

    natural_frequency_hz: np.ndarray
    damping_ratio: np.ndarray
    modal_constant: np.ndarray  # (n_outputs, n_modes), real (proportional damping)
    fs: float

    def poles(self) -> np.ndarray:
        wn = 2 * np.pi * np.asarray(self.natural_frequency_hz)
        z = np.asarray(self.damping_ratio)
        return -z * wn + 1j * wn * np.sqrt(1 - z**2)

    def _sections(self, output: int):
        T = 1.0 / self.fs
        out = []
        for p, A in zip(self.poles(), np.atleast_2d(self.modal_constant)[output]):
            R = A / (2j * p.imag)  # receptance A/((s−p)(s−p*)) = R/(s−p) + R*/(s−p*)
            zp = np.exp(p * T)
            # T [R/(1 − zp q) + R*/(1 − zp* q)] over the common denominator, q = z^-1
            b = T * np.array([2 * R.real, -2 * (R * zp.conj()).real])
            a = np.array([1.0, -2 * zp.real, abs(zp) ** 2])
            out.append((b, a))
        return out

    def respond(self, force: np.ndarray) -> np.ndarray:
        """Displacement of every output for a force record (N), m; shape (n_outputs, n_samples)."""
        n_out = np.atleast_2d(self.modal_constant).shape[0]
        return np.array([sum(signal.lfilter(b, a, force) for b, a in self._sections(o)) for o in range(n_out)])

    def frf(self, frequency_hz: np.ndarray) -> np.ndarray:
        """The digital system's exact receptance at ``frequency_hz``; shape (n_outputs, n_lines)."""
        n_out = np.atleast_2d(self.modal_constant).shape[0]
        w = 2 * np.pi * np.asarray(frequency_hz) / self.fs
        return np.array([sum(signal.freqz(b, a, worN=w)[1] for b, a in self._sections(o)) for o in range(n_out)])


def hammer_force(n: int, fs: float, hit_times_s, width_s: float = 0.002, amplitude: float = 100.0) -> np.ndarray:
    """Half-sine force pulses (N) of ``width_s`` starting at ``hit_times_s``."""
    force = np.zeros(n)
    t = np.arange(n) / fs
    for t0 in hit_times_s:
        inside = (t >= t0) & (t < t0 + width_s)
        force[inside] += amplitude * np.sin(np.pi * (t[inside] - t0) / width_s)
    return force
