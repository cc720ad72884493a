"""The noise of a single impact record, read from the samples where the channels hold noise alone.

One hit gives one record: its FRF has no residual over records to tell its noise, line by line. Its
channels do: before the trigger (the pre-trigger) the response holds only its sensor's noise, and after
the pulse the force channel holds only its own. For white noise of variance σ² through a record window
w, each line of the record's transform carries noise of power σ² Σ w² (the transforms are unnormalised,
as in :func:`modal.estimate.spectra.accumulate`). An H1 estimate from one record, Ĥ = Y/X, then errs by
(N_y − H N_x)/X to first order, of power

    (a + b |H|²) / |X|²,   a = σ_y² Σ w_out²,  b = σ_x² Σ w_in²,

the response's noise and the force's, the latter in proportion to |H| (large at the peaks):
the shape :func:`modal.noise_model.input_noise_split` fits to the residual of several records.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["QuietNoise", "quiet_noise", "MIN_QUIET_SAMPLES"]

#: at least this many noise-only samples per channel, else the noise is not read (the variance of 16
#: samples is within ±35 % of σ², one standard error; fewer tell little)
MIN_QUIET_SAMPLES = 16
#: samples left out on either side of the pulse (its rise before the trigger, its tail after the force
#: window's nominal width), besides the pulse itself
PULSE_MARGIN = 4
#: the median absolute deviation of Gaussian noise is this fraction of its standard deviation
MAD_TO_STD = 1.4826


@dataclass(frozen=True)
class QuietNoise:
    """The noise powers of one record's lines (see the module), as |transform|² of the records (the
    channel's unit squared).

    Attributes
    ----------
    response_power : ndarray, shape (n_outputs,)
        a = σ_y² Σ w_out² per output.
    force_power : float
        b = σ_x² Σ w_in².
    """

    response_power: np.ndarray
    force_power: float


def quiet_noise(force, response, start: int, length: int, pretrigger: int, pulse_samples: int,
                input_window: np.ndarray, output_window: np.ndarray) -> QuietNoise | None:
    """The noise powers a, b of one impact record (see the module), or None where too few quiet samples.

    Parameters
    ----------
    force : ndarray, shape (n_samples,)
        The force channel.
    response : array_like, shape (n_outputs, n_samples)
        The response channels.
    start, length : int
        The record's first sample and its length, samples.
    pretrigger : int
        Samples of the record before the trigger.
    pulse_samples : int
        The force pulse's duration, samples.
    input_window, output_window : ndarray, shape (length,)
        The windows of the force and the responses.

    Returns
    -------
    QuietNoise or None
        None also where a channel's lines would carry no noise at all (b = 0 and some a = 0: noise-free
        data, whose errors the fit's residual tells). a per output from the variance of the responses' pre-trigger (less its mean: a constant offset
        enters the 0 Hz line only); b from the force after the pulse, by its median absolute deviation
        (robust to a hammer's ringing after the pulse, a few samples far from the noise).
    """
    quiet_response = max(pretrigger - PULSE_MARGIN, 0)
    after_pulse = pretrigger + 2 * pulse_samples + PULSE_MARGIN
    if quiet_response < MIN_QUIET_SAMPLES or length - after_pulse < MIN_QUIET_SAMPLES:
        return None
    pre = np.asarray(response[:, start:start + quiet_response], float)
    response_variance = np.var(pre, axis=1, ddof=1)
    tail = np.asarray(force[start + after_pulse:start + length], float)
    force_std = MAD_TO_STD * float(np.median(np.abs(tail - np.median(tail))))
    a = response_variance * float(np.dot(output_window, output_window))
    b = force_std**2 * float(np.dot(input_window, input_window))
    if not (np.all(np.isfinite(a)) and np.isfinite(b)) or (b == 0 and not np.all(a > 0)):
        return None  # no noise on some channel's lines (noise-free data): the fit's residual tells it
    return QuietNoise(a, b)
