"""Time windows for FRF estimation.

Every window is a function of the sample index within one record (segment or
hit record) and returns float weights. The exponential window is special: it
multiplies the whole record by exp(−t/τ), which moves every pole of the
measured FRF left by exactly 1/τ (rad/s); the estimate carries τ so that
identification can take it back out.
"""
from __future__ import annotations

import numpy as np

from ..errors import ParameterError
from ..validate import positive_number

__all__ = ["WINDOWS", "segment_window", "force_window", "exponential_window"]

#: window names accepted by :func:`modal.estimate_frf`
WINDOWS: tuple[str, ...] = ("rect", "hann", "force", "exponential")


def segment_window(name: str, length: int) -> np.ndarray:
    """Window for a segment of a continuous (random, burst, sine) record.

    Parameters
    ----------
    name : {"rect", "hann"}
        ``"hann"`` is the periodic Hann window (the DFT-even one, as Welch uses).
    length : int
        Samples per segment.
    """
    if name == "rect":
        return np.ones(length)
    if name == "hann":
        n = np.arange(length)
        return 0.5 - 0.5 * np.cos(2.0 * np.pi * n / length)
    raise ParameterError(
        f"window {name!r} is for impact records (one record per hit, impact=True); "
        "a continuous record takes 'rect' or 'hann'"
    )


def force_window(length: int, pretrigger: int, width: int, taper: int | None = None) -> np.ndarray:
    """Force window: 1 over the hit, 0 after it, with a half-cosine taper.

    Parameters
    ----------
    length : int
        Samples per hit record.
    pretrigger : int
        Samples kept before the trigger (the window is 1 there too).
    width : int
        Samples after the trigger during which the force pulse lasts.
    taper : int, optional
        Length of the half-cosine fall after ``width``; default ``width // 4`` (at least 1).
    """
    taper = max(1, width // 4) if taper is None else max(1, int(taper))
    w = np.zeros(length)
    end = min(length, pretrigger + width)
    w[:end] = 1.0
    stop = min(length, end + taper)
    k = np.arange(stop - end)
    w[end:stop] = 0.5 + 0.5 * np.cos(np.pi * (k + 1) / (taper + 1))
    return w


def exponential_window(length: int, sample_rate_hz: float, decay_s: float, pretrigger: int = 0) -> np.ndarray:
    """exp(−(t − t_trigger)/τ) over the whole record.

    Applied to force and response alike, the measured FRF becomes
    H(iω + 1/τ): each pole's real part is more negative by 1/τ, residues are
    unchanged (values before the trigger exceed 1, which keeps that identity exact).

    Parameters
    ----------
    decay_s : float
        Time constant τ, s.
    """
    positive_number("exponential_decay_s", decay_s, "time in s")
    t = (np.arange(length) - pretrigger) / sample_rate_hz
    return np.exp(-t / decay_s)
