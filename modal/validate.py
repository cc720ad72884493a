"""Argument checks of ``modal``, in one place: each returns the checked value or raises a one-line error
that names the argument, the value given and what was expected.

:class:`~modal.errors.ParameterError` by default; a caller passes its own error class
(:class:`~modal.errors.FRFValidationError`, :class:`~modal.errors.IdentificationError`)
and ``source`` (the file) where the message should start with it.
"""
from __future__ import annotations

from typing import Sequence

import numpy as np

from .errors import ParameterError

__all__ = ["positive", "non_negative", "per_channel", "per_line", "positive_number", "one_of", "finite_samples", "channel_mask",
           "system_matrices"]


def _where(source: str | None) -> str:
    return "" if source is None else f"{source}: "


def positive(name: str, value, error: type[Exception] = ParameterError) -> np.ndarray:
    """``value`` as a float array (at least 1-D) whose every entry is finite and > 0."""
    arr = np.atleast_1d(np.asarray(value, dtype=float))
    if not np.all(np.isfinite(arr)) or np.any(arr <= 0):
        raise error(f"'{name}' must be finite and > 0, got {value!r}")
    return arr


def non_negative(name: str, value, error: type[Exception] = ParameterError) -> np.ndarray:
    """``value`` as a float array (at least 1-D) whose every entry is finite and >= 0."""
    arr = np.atleast_1d(np.asarray(value, dtype=float))
    if not np.all(np.isfinite(arr)) or np.any(arr < 0):
        raise error(f"'{name}' must be finite and >= 0, got {value!r}")
    return arr


def per_channel(name: str, value, n_channels: int, error: type[Exception] = ParameterError) -> np.ndarray:
    """``value`` (finite, >= 0: one for every channel, or one per channel) as a float array of ``n_channels``."""
    arr = non_negative(name, value, error)
    if arr.size not in (1, n_channels):
        raise error(f"'{name}' has {arr.size} values; expected one, or one per channel ({n_channels})")
    return np.broadcast_to(arr, (n_channels,)).copy()


def per_line(name: str, value, shape: tuple, error: type[Exception] = ParameterError,
             source: str | None = None) -> np.ndarray:
    """``value`` as a float array shaped like an FRF's response (``shape``), every entry finite and >= 0."""
    try:
        arr = np.array(value, dtype=float)
    except (TypeError, ValueError):
        arr = np.full(1, np.nan)
    if arr.shape != shape or not np.all(np.isfinite(arr)) or np.any(arr < 0):
        raise error(f"{_where(source)}field '{name}' must be finite, >= 0 and shaped like 'response' {shape}")
    return arr


def positive_number(name: str, value, expected: str, error: type[Exception] = ParameterError,
                    source: str | None = None) -> float:
    """``value`` as a float, finite and > 0; ``expected`` says what it is (``"time in s"``)."""
    try:
        number = float(value)
    except (TypeError, ValueError):
        number = float("nan")
    if not (np.isfinite(number) and number > 0):
        raise error(f"{_where(source)}field '{name}' is {value!r}; expected a positive {expected}")
    return number


def one_of(name: str, value, choices: Sequence, error: type[Exception] = ParameterError, source: str | None = None):
    """``value``, which must be one of ``choices``."""
    if value not in choices:
        raise error(f"{_where(source)}field '{name}' is {value!r}; expected one of {', '.join(map(str, choices))}")
    return value


def finite_samples(signal, name: str, source: str, block: int = 2**22) -> None:
    """Every sample of ``signal`` (channels × samples; an array, memmap or h5py dataset, read in blocks) is finite."""
    n = signal.shape[1]
    for first in range(0, n, block):
        part = np.asarray(signal[:, first:first + block], dtype=float)
        bad = ~np.isfinite(part)
        if bad.any():
            ch, i = (int(v) for v in np.argwhere(bad)[0])
            raise ParameterError(
                f"{source}: field {name!r} has a non-finite sample at channel {ch + 1}, sample {first + i}; "
                "expected finite numbers"
            )


def channel_mask(name: str, value, n_channels: int, error: type[Exception] = ParameterError) -> np.ndarray:
    """Channels chosen by ``value`` as a boolean mask of ``n_channels``.

    ``value``: a bool (every channel, or none), one bool per channel, or channel indices (0-based, an int
    or a sequence of ints); an index outside ``0..n_channels - 1`` is refused naming the valid range.
    """
    arr = np.asarray(value)
    if arr.dtype == bool:
        if arr.size not in (1, n_channels) or arr.ndim > 1:
            raise error(f"'{name}' has {arr.size} values; expected one bool, one per channel ({n_channels}) or "
                        f"channel indices 0..{n_channels - 1}")
        return np.broadcast_to(arr.reshape(-1), (n_channels,)).copy()
    if arr.ndim > 1 or arr.size == 0 or arr.dtype.kind not in "iu":
        raise error(f"'{name}' = {value!r}: expected a bool, one bool per channel ({n_channels}) or channel "
                    f"indices 0..{n_channels - 1}")
    indices = arr.reshape(-1)
    bad = indices[(indices < 0) | (indices >= n_channels)]
    if bad.size:
        raise error(f"'{name}': no channel {int(bad[0])}; expected channel indices 0..{n_channels - 1}")
    mask = np.zeros(n_channels, bool)
    mask[indices] = True
    return mask


def system_matrices(mass, damping, stiffness) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Mass, damping and stiffness matrices of a linear system, checked: finite, square, of one size,
    the mass symmetric positive definite (kg, N s/m, N/m)."""
    M, C, K = (np.atleast_2d(np.asarray(a, dtype=float)) for a in (mass, damping, stiffness))
    n = M.shape[0]
    for name, a in (("mass", M), ("damping", C), ("stiffness", K)):
        if a.shape != (n, n) or not np.all(np.isfinite(a)):
            raise ParameterError(f"'{name}' must be a finite ({n}, {n}) matrix, got shape {a.shape}")
    try:
        np.linalg.cholesky(M)
    except np.linalg.LinAlgError:
        raise ParameterError("'mass' must be symmetric positive definite") from None
    return M, C, K
