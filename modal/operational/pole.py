"""One mode as an operational method found it: its pole, shape and their errors, before it becomes a
:class:`~modal.results.ModeResult` (:mod:`modal.operational.result`)."""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..units import TWO_PI

__all__ = ["PoleEstimate"]


@dataclass(frozen=True)
class PoleEstimate:
    """A mode's pole and observed shape with their standard errors.

    Attributes
    ----------
    pole : complex
        Continuous-time pole λ, rad/s.
    shape : ndarray, shape (n_channels,), complex
        Observed shape over the channels, its largest-magnitude entry 1 among those the record determines
        (:func:`modal.operational.modes._physical_shape`).
    std_frequency_hz, std_damping_ratio : float
        Standard errors of the natural frequency (Hz) and damping ratio (NaN where the method gives none).
    std_shape : ndarray, shape (n_channels,)
        Standard error of each shape entry, sqrt(var Re + var Im) (NaN where none).
    n_orders, n_orders_swept : int
        The orders of the sweep that hold the mode stable, and all the orders swept.
    order : int
        The order the mode is reported from.
    flags : frozenset of str
        Flags the method raised itself (``harmonic``, ...).
    damping_known : bool
        False where the method measures no damping (FDD: the damping ratio is NaN).
    pole_deviation : ndarray or None
        The pole's first-order deviation per block of the record (rad/s), for methods that build on it.
    """

    pole: complex
    shape: np.ndarray
    std_frequency_hz: float
    std_damping_ratio: float
    std_shape: np.ndarray
    n_orders: int
    n_orders_swept: int
    order: int
    flags: frozenset = field(default_factory=frozenset)
    damping_known: bool = True
    pole_deviation: np.ndarray | None = field(default=None, repr=False, compare=False)

    @property
    def natural_frequency_hz(self) -> float:
        return float(abs(self.pole) / TWO_PI)

    @property
    def damping_ratio(self) -> float:
        return float(-self.pole.real / abs(self.pole)) if self.damping_known else float("nan")
