"""Time records → FRFs: segmenting, windows, hit detection, H1/H2/Hv, coherence, noise.

``estimate_frf`` is the entry point; it returns an :class:`EstimatedFRF` (an
:class:`~modal.frf.FRF` with ``coherence``, ``averages``, ``rejected`` and
``noise_std``).
"""
from .core import RESPONSE_QUANTITIES, EstimatedFRF, estimate_frf
from .hits import Hits, find_hits
from .spectra import ESTIMATORS, overlap_variance_factor
from .windows import WINDOWS

__all__ = ["estimate_frf", "EstimatedFRF", "RESPONSE_QUANTITIES", "Hits", "find_hits", "ESTIMATORS", "WINDOWS",
           "overlap_variance_factor"]
